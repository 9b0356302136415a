"""Filament's material models: the DFG lookup table, the individual terms and the constants.

The models themselves are :class:`bsdfkit.FilamentStandard` and :class:`bsdfkit.FilamentCloth`;
everything here lives in :mod:`bsdfkit.models.filament` (this module is its public short name).
"""
from .models.filament.dfg import (DFG_LUT_SAMPLES, DFG_LUT_SIZE, MIN_N_DOT_V, MIN_PERCEPTUAL_ROUGHNESS, TERMS,
                                  _table, cache_dir, dfg_lut, term)
from .models.filament.materials import examples

__all__ = ["dfg_lut", "cache_dir", "term", "examples", "TERMS", "MIN_PERCEPTUAL_ROUGHNESS", "MIN_N_DOT_V", "DFG_LUT_SIZE",
           "DFG_LUT_SAMPLES"]
