"""The rule every ``to_mitsuba`` follows: export exactly, or refuse naming the reason.

A model is exported only when the Mitsuba 3 plugin written is the same material. Where Mitsuba
has no exact equivalent (height-correlated Smith masking: Mitsuba's microfacet plugins use the
separable G1(wo) G1(wi); Schlick / F82 conductor Fresnel terms) ``to_mitsuba()`` raises
:class:`MitsubaExportError`; ``to_mitsuba(approximate=True)`` writes the nearest plugin and warns
with :class:`MitsubaApproximationWarning`, whose text states the difference measured between the
model and the exported material.
"""
from __future__ import annotations

import warnings

import numpy as np

__all__ = ["MitsubaExportError", "MitsubaApproximationWarning", "export_difference", "refuse_or_warn",
           "check_approximate"]


class MitsubaExportError(NotImplementedError, ValueError):
    """``to_mitsuba``: Mitsuba 3 has no plugin for exactly this material, but a nearest one that
    ``to_mitsuba(approximate=True)`` exports with a warning. A NotImplementedError
    (the rule of ``BxDF.to_mitsuba``) and a ValueError (what refusing an approximate Fresnel
    term has always raised)."""


class MitsubaApproximationWarning(UserWarning):
    """``to_mitsuba(approximate=True)`` exported a different material; the message states the
    measured difference."""


#: The reason given for a rough lobe with height-correlated masking (``.format(plugin=...)``).
MASKING_REASON = ("its masking is 'correlated' (pbrt-v4's height-correlated Smith G) and Mitsuba 3's {plugin} "
                  "has only the separable G1(wo) G1(wi) (masking='separable')")


#: Incident angles (degrees) at which the difference is measured.
_THETA_O = (0.0, 20.0, 40.0, 60.0, 70.0, 80.0, 85.0)
#: Sampled wi per incident angle (importance-sampled from the model: where its energy is).
_N_WI = 4096


def export_difference(model, exported) -> dict:
    """Relative difference of f between ``model`` and ``exported`` (the model the Mitsuba plugin
    stands for), and the absolute difference of their directional albedo, RGB, float64.

    wo at the angles of ``_THETA_O`` (phi = 0, from either side for transmissive models); wi
    importance-sampled from ``model`` (seed 0), pairs with f below 1e-4 of the largest value
    ignored. Both albedos use the same seed, so the sampling noise mostly cancels.
    Returns ``{"max_rel_f", "theta_o", "theta_i", "max_albedo", "albedo_theta_o"}`` (angles in degrees).
    """
    sides = (1.0, -1.0) if getattr(model, "transmission", False) else (1.0,)
    best = {"max_rel_f": 0.0, "theta_o": 0.0, "theta_i": 0.0, "max_albedo": 0.0, "albedo_theta_o": 0.0}
    for side in sides:
        t = np.radians(np.asarray(_THETA_O))
        wo = np.stack([np.sin(t), np.zeros_like(t), side * np.cos(t)], axis=-1)
        for i, w in enumerate(wo):
            s = model.sample(w, n=_N_WI, seed=i)
            wi = s.wi[s.valid]
            if len(wi) == 0:
                continue
            fa, fb = model.eval(w, wi), exported.eval(w, wi)
            keep = fa > 1e-4 * fa.max()
            if not keep.any():
                continue
            rel = np.where(keep, np.abs(fb - fa) / np.where(keep, fa, 1.0), 0.0).max(axis=-1)
            j = int(np.argmax(rel))
            if rel[j] > best["max_rel_f"]:
                best.update(max_rel_f=float(rel[j]), theta_o=float(_THETA_O[i]),
                            theta_i=float(np.degrees(np.arccos(min(abs(wi[j, 2]), 1.0)))))
        ra, rb = model.albedo(wo, n_samples=16384, seed=0), exported.albedo(wo, n_samples=16384, seed=0)
        d = np.abs(rb - ra).max(axis=-1)
        j = int(np.argmax(d))
        if d[j] > best["max_albedo"]:
            best.update(max_albedo=float(d[j]), albedo_theta_o=float(_THETA_O[j]))
    return best


def difference_text(model, exported, verb: str = "differs") -> str:
    """The measured difference as a clause: "f differs ... by up to ...% (...) and ..."."""
    d = export_difference(model, exported)
    parts = []
    if d["max_rel_f"] > 0:
        parts.append(f"f {verb} from this model's by up to {100 * d['max_rel_f']:.3g} % "
                     f"(at θo = {d['theta_o']:g}°, θi = {d['theta_i']:.1f}°)")
    parts.append(f"{'its' if parts else 'the'} directional albedo by up to {d['max_albedo']:.3g} "
                 f"(at θo = {d['albedo_theta_o']:g}°)" if parts else
                 f"directional albedo {verb} from this model's by up to {d['max_albedo']:.3g} "
                 f"(at θo = {d['albedo_theta_o']:g}°)")
    return (" and ".join(parts) + f", measured at θo = {', '.join(f'{a:g}' for a in _THETA_O)}° with "
            f"{_N_WI} importance-sampled wi each")


def check_approximate(approximate) -> bool:
    if not isinstance(approximate, (bool, np.bool_)):
        raise TypeError(f"approximate: expected True or False, got {approximate!r}")
    return bool(approximate)


def refuse_or_warn(model, exported_model, reasons, approximate: bool, stacklevel: int = 3) -> None:
    """Apply the rule: no ``reasons`` -> return; else raise :class:`MitsubaExportError` (unless
    ``approximate``) or warn :class:`MitsubaApproximationWarning`; both state the measured
    difference between ``model`` and ``exported_model`` (what the plugin written stands for)."""
    check_approximate(approximate)
    if not reasons:
        return
    name = type(model).__name__
    why = "; ".join(reasons)
    if not approximate:
        diff = difference_text(model, exported_model, "would differ")
        raise MitsubaExportError(
            f"{name}.to_mitsuba: Mitsuba 3 has no plugin for this material: {why}. The nearest Mitsuba "
            f"material's {diff}. Build the model with Mitsuba's choices to export it exactly, or call "
            f"to_mitsuba(approximate=True) to export the nearest Mitsuba material with a warning.")
    diff = difference_text(model, exported_model)
    warnings.warn(f"{name}.to_mitsuba(approximate=True): exported a different material: {why}; the exported "
                  f"material's {diff}",
                  MitsubaApproximationWarning, stacklevel=stacklevel)


def no_plugin(model, approximate, why: str):
    """``to_mitsuba`` of a model Mitsuba 3 has no plugin for: NotImplementedError naming ``why``
    (``approximate=True`` cannot help: there is no nearest plugin)."""
    check_approximate(approximate)
    raise NotImplementedError(f"{type(model).__name__}.to_mitsuba: {why}")
