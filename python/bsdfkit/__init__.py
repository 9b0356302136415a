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
``fitting``   parameter gradients (``eval_grad``), least-squares fits (``fit``; ``fit_many`` on Dask)
``interop``   scene materials in: Mitsuba 3 dictionaries, pbrt-v4 scene text
``render``    the path-traced preview renderer
``spectral``  spectra as values: named, sampled, RGB uplift; wavelength sampling, colour estimates
``measured``  writers and tabulation of measured materials (MERL tables, RGL tensor files)
``testing``   independent references (Dr.Jit float64 oracles, the Mitsuba 3 harness)
``io``        images in and out

This module only re-exports.
"""
from . import _core, filament, fitting, interop, io, models, plot, render, tuning  # noqa: F401
from ._enums import BxDFFlags, ReflTrans, TransportMode
from ._version import __version__
from .directions import direction, hemisphere_grid
from .interop import from_mitsuba, from_pbrt, parse_pbrt_materials
from .models import *  # noqa: F401,F403  (every model class; a new family is re-exported by models/__init__.py)
from .models.custom import Custom
from . import measured  # noqa: E402  (writers and tabulation of measured materials: bk.measured)
from .spectral import Spectrum, sample_wavelengths, spectrum_to_rgb
from .threads import get_num_threads, release_memory, set_num_threads
from .tuning import Table, knobs, simplify, tradeoff
from .fitting import FitReport, fit, fit_many

__all__ = models.__all__ + [
    "BxDFFlags", "ReflTrans", "TransportMode", "direction", "get_num_threads", "hemisphere_grid", "release_memory", "set_num_threads",
    "Custom", "filament", "models", "plot", "tuning", "render", "io", "tradeoff", "simplify", "knobs", "Table", "from_mitsuba",
    "from_pbrt", "parse_pbrt_materials", "interop", "spectral", "Spectrum", "sample_wavelengths", "spectrum_to_rgb",
    "__version__", "measured", "fitting", "fit", "fit_many", "FitReport"]
