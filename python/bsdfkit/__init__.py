"""bsdfkit: evaluate and sample pbrt-v4 BxDFs over numpy arrays, vectorized and multi-threaded.

Conventions (pbrt-v4): directions are unit vectors in the local shading frame (z is the normal),
both pointing away from the surface; ``eval`` excludes the cosine; ``pdf`` is per unit solid angle.

>>> import numpy as np, bsdfkit as bk
>>> m = bk.Conductor.from_metal("Cu", roughness=0.3)
>>> f = m.eval(bk.direction(np.radians(40), 0.0), bk.hemisphere_grid(90, 180))   # (16200, 3)
"""
from __future__ import annotations

import numpy as np

from . import _core, io
from ._enums import BxDFFlags, ReflTrans, TransportMode
from ._models import (METALS, BxDF, Conductor, Dielectric, Diffuse, DiffuseTransmission, SampleResult,
                      ThinDielectric, conductor_fresnel, roughness_to_alpha)
from . import render  # noqa: E402  (preview renderer: bk.render.preview)
from . import filament
from ._filament_models import FilamentCloth, FilamentStandard
from .models.hair import Hair
from .models.normalized_fresnel import NormalizedFresnel
from .tradeoff import Table, knobs, simplify, tradeoff  # speed vs accuracy (bk.tradeoff is the function)
from .interop import from_mitsuba, from_pbrt, parse_pbrt_materials  # scene materials in

__version__ = "0.1.0"

__all__ = ["BxDF", "BxDFFlags", "Conductor", "Dielectric", "Diffuse", "DiffuseTransmission", "METALS",
           "ReflTrans", "SampleResult", "ThinDielectric", "TransportMode", "direction", "get_num_threads",
           "hemisphere_grid", "roughness_to_alpha", "conductor_fresnel", "set_num_threads", "MODELS"]
__all__ += ["FilamentStandard", "FilamentCloth", "filament"]
__all__ += ["Hair", "NormalizedFresnel"]
__all__ += ["tradeoff", "simplify", "knobs", "Table"]
__all__ += ["from_mitsuba", "from_pbrt", "parse_pbrt_materials", "interop"]

#: Every model class, in gallery order.
MODELS = (Diffuse, DiffuseTransmission, Conductor, Dielectric, ThinDielectric, FilamentStandard, FilamentCloth,
          NormalizedFresnel, Hair)


def set_num_threads(n: int) -> None:
    """Number of worker threads for the array kernels (default: all cores). Results do not
    depend on it: every element is computed independently and reductions use fixed blocks."""
    if isinstance(n, bool) or not isinstance(n, (int, np.integer)):
        raise TypeError(f"n: expected an integer, got {type(n).__name__}")
    _core.set_num_threads(int(n))


def get_num_threads() -> int:
    """Current number of worker threads of the array kernels."""
    return _core.get_num_threads()


def direction(theta, phi=0.0) -> np.ndarray:
    """Unit direction(s) from polar angle ``theta`` (from +z, radians) and azimuth ``phi``
    (from +x towards +y, radians); broadcasts, returns float64 (..., 3)."""
    theta = np.asarray(theta, dtype=np.float64)
    phi = np.asarray(phi, dtype=np.float64)
    st = np.sin(theta)
    return np.stack(np.broadcast_arrays(st * np.cos(phi), st * np.sin(phi), np.cos(theta)), axis=-1)


def hemisphere_grid(n_theta: int, n_phi: int, *, sphere: bool = False) -> np.ndarray:
    """Cell-centred directions on the upper hemisphere (or the whole sphere), float64
    (n_theta * n_phi, 3), theta-major: theta in (0, pi/2) (or (0, pi)), phi in (0, 2 pi)."""
    for v, name in ((n_theta, "n_theta"), (n_phi, "n_phi")):
        if isinstance(v, bool) or not isinstance(v, (int, np.integer)) or v < 1:
            raise ValueError(f"{name}: must be a positive integer, got {v!r}")
    top = np.pi if sphere else np.pi / 2
    theta = (np.arange(n_theta) + 0.5) * top / n_theta
    phi = (np.arange(n_phi) + 0.5) * 2 * np.pi / n_phi
    t, p = np.meshgrid(theta, phi, indexing="ij")
    return direction(t, p).reshape(-1, 3)
