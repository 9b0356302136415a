"""bsdfkit: evaluate and sample pbrt-v4 and Filament BxDFs over numpy arrays, vectorized and multi-threaded.

Conventions (pbrt-v4): directions are unit vectors in the local shading frame (z is the normal),
both pointing away from the surface; ``eval`` excludes the cosine; ``pdf`` is per unit solid angle.

>>> import numpy as np, bsdfkit as bk
>>> m = bk.Conductor.from_metal("Cu", roughness=0.3)
>>> f = m.eval(bk.direction(np.radians(40), 0.0), bk.hemisphere_grid(90, 180))   # (16200, 3)

Subpackages, by concern:

``models``    the model classes and their registry (one module per family; ``bk.MODELS``)
``plot``      matplotlib views (polar, hemisphere, half/diff, albedo, samples, gallery, pareto, ...)
``tuning``    speed versus accuracy: knobs, errors, costs, ``tradeoff`` and ``simplify``
``fitting``   parameter gradients (``eval_grad``), least-squares fits (``fit``; ``fit_many`` on Dask; ``fit_texels`` per texel)
``interop``   scene materials in: Mitsuba 3 dictionaries, pbrt-v4 scene text, glTF 2.0 and MaterialX files
``render``    the path-traced preview renderer
``spectral``  spectra as values: named, sampled, RGB uplift; wavelength sampling, colour estimates
``measured``  writers and tabulation of measured materials (MERL tables, RGL tensor files)
``testing``   independent references (Dr.Jit float64 oracles, the Mitsuba 3 harness)
``io``        images in and out

This module only re-exports. The model classes are imported with the package; the subpackages
above and the functions re-exported from them (``bk.tradeoff``, ``bk.fit``, ``bk.from_pbrt``, ...)
are imported on first access, so ``import bsdfkit`` stays quick. The renderer and image I/O live in
the optional compiled extension ``bsdfkit._render`` (Embree, OpenImageIO), loaded on first use.
"""
import importlib as _importlib

from . import _core  # noqa: F401  (the compiled models: no Embree / OpenImageIO)
from ._enums import BxDFFlags, ReflTrans, TransportMode
from .directions import direction, hemisphere_grid
from . import models  # noqa: F401
from .models import *  # noqa: F401,F403  (every model class; a new family is re-exported by models/__init__.py)
from .models.custom import Custom
from .spectral import Spectrum, sample_wavelengths, spectrum_to_rgb
from .threads import get_num_threads, release_memory, set_num_threads

# Imported on first access (PEP 562): subpackages, and names re-exported from them.
_LAZY_MODULES = ("compensation", "filament", "fitting", "interop", "io", "measured", "plot", "render", "textures", "tuning", "testing")
_LAZY_NAMES = {
    "from_mitsuba": "interop", "from_pbrt": "interop", "from_gltf": "interop", "from_materialx": "interop",
    "parse_pbrt_materials": "interop",
    "Table": "tuning", "knobs": "tuning", "simplify": "tuning", "tradeoff": "tuning",
    "FitReport": "fitting", "fit": "fitting", "fit_many": "fitting", "fit_texels": "fitting",
    "Texture": "textures", "Textured": "models.textured",
    "albedo_table": "compensation", "AlbedoTable": "compensation",
    "__version__": "_version",
}


def __getattr__(name):
    if name in _LAZY_MODULES:
        return _importlib.import_module(f".{name}", __name__)
    if name in _LAZY_NAMES:
        value = getattr(_importlib.import_module(f".{_LAZY_NAMES[name]}", __name__), name)
        globals()[name] = value
        return value
    raise AttributeError(f"module 'bsdfkit' has no attribute {name!r}")


def __dir__():
    return sorted(set(globals()) | set(_LAZY_MODULES) | set(_LAZY_NAMES))


__all__ = models.__all__ + [
    "BxDFFlags", "ReflTrans", "TransportMode", "direction", "get_num_threads", "hemisphere_grid", "release_memory", "set_num_threads",
    "Custom", "filament", "models", "plot", "tuning", "render", "io", "tradeoff", "simplify", "knobs", "Table", "from_mitsuba",
    "from_pbrt", "from_gltf", "from_materialx", "parse_pbrt_materials", "interop", "spectral", "Spectrum", "sample_wavelengths", "spectrum_to_rgb",
    "__version__", "measured", "fitting", "fit", "fit_many", "fit_texels", "FitReport",
    "textures", "Texture", "Textured", "compensation", "albedo_table", "AlbedoTable"]
