"""Filament's material models: :class:`FilamentStandard`, :class:`FilamentCloth`, the DFG table
and the individual shader terms (``dfg``)."""
from .dfg import (DFG_LUT_SAMPLES, DFG_LUT_SIZE, MIN_N_DOT_V, MIN_PERCEPTUAL_ROUGHNESS, TERMS, cache_dir, dfg_lut,
                  term)
from .materials import FilamentCloth, FilamentStandard, examples

__all__ = ["FilamentStandard", "FilamentCloth", "examples", "dfg_lut", "cache_dir", "term", "TERMS", "MIN_PERCEPTUAL_ROUGHNESS",
           "MIN_N_DOT_V", "DFG_LUT_SIZE", "DFG_LUT_SAMPLES"]
