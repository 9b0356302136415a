"""Short human-readable names of models (legend labels and titles)."""
from __future__ import annotations

import numpy as np

from .base import BxDF
from .conductor import METALS, Conductor
from .dielectric import Dielectric, ThinDielectric
from .diffuse import Diffuse, DiffuseTransmission

__all__ = ["describe"]


def _fmt(v) -> str:
    v = np.asarray(v, dtype=np.float64)
    if v.ndim and np.allclose(v, v.flat[0]):
        v = v.flat[0]
    if v.ndim == 0:
        return f"{float(v):.3g}"
    return "(" + ", ".join(f"{x:.2g}" for x in v) + ")"


def describe(model: BxDF) -> str:
    """A short human-readable name of a model, e.g. ``"Conductor Au, α=0.2"``."""
    p = model._params
    alpha = ""
    if "alpha_x" in p:
        ax, ay = p["alpha_x"], p["alpha_y"]
        if max(ax, ay) < 1e-3:
            alpha = ", smooth"
        elif ax == ay:
            alpha = f", α={ax:.3g}"
        else:
            alpha = f", αx={ax:.3g}, αy={ay:.3g}"
    if isinstance(model, Diffuse):
        return f"Diffuse R={_fmt(p['reflectance'])}"
    if isinstance(model, DiffuseTransmission):
        return f"DiffuseTransmission R={_fmt(p['reflectance'])}, T={_fmt(p['transmittance'])}"
    if isinstance(model, Conductor):
        name = next((n for n, (eta, k) in METALS.items()
                     if np.allclose(p["eta"], eta) and np.allclose(p["k"], k)), None)
        if name is None:
            name = f"η={_fmt(p['eta'])}, k={_fmt(p['k'])}"
        return f"Conductor {name}{alpha}"
    if isinstance(model, Dielectric):
        return f"Dielectric η={p['eta']:.3g}{alpha}"
    if isinstance(model, ThinDielectric):
        return f"ThinDielectric η={p['eta']:.3g}"
    if "conductor_eta" in p:   # CoatedConductor: the metal, metal / coat alpha, whether a medium
        name = next((n for n, (eta, k) in METALS.items()
                     if np.allclose(p["conductor_eta"], eta) and np.allclose(p["conductor_k"], k)), None)
        name = name or f"η={_fmt(p['conductor_eta'])}"
        med = ", medium" if np.any(np.asarray(p["albedo"]) > 0) else ""
        return f"CoatedConductor {name}, α={p['conductor_alpha_x']:.2g}/{p['interface_alpha_x']:.2g}{med}"
    if type(model).__name__ in ("Plastic", "CoatedDiffuse"):
        a = p.get("alpha", p.get("alpha_x", 0.0))
        med = ", medium" if np.any(np.asarray(p.get("albedo", 0.0)) > 0) else ""
        return f"{type(model).__name__} R={_fmt(p['reflectance'])}, " + (f"α={a:.2g}" if a >= 1e-3 else "smooth") + med
    from .spec import to_spec

    rest = to_spec(model).split()[1:]
    return type(model).__name__ + (" " + ", ".join(rest) if rest else "")
