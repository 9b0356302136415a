"""Named spectra: measured metal eta/k and glass IOR data of pbrt-v4 and Mitsuba 3.

The numbers live in ``bsdfkit/data/spectra.json`` with their source (file, array, commit):

* pbrt-v4 ``src/pbrt/util/spectrum.cpp`` names: ``metal-<X>-eta`` / ``metal-<X>-k`` for X in
  Ag, Al, Au, Cu, CuZn, MgO, TiO2; ``glass-<X>`` for BK7, BAF10, FK51A, LASF9, F5, F10, F11.
* Mitsuba 3 ``data/ior/<X>.{eta,k}.spd`` (the conductor ``material`` presets), as
  ``mitsuba-<X>-eta`` / ``mitsuba-<X>-k`` for X in Ag, Al, Au, Cu, Cr, W, Ni_palik, Mo, Ir, Rh,
  Ta, TiN, Be.
* Johnson & Christy, Phys. Rev. B 9, 5056 (1974) (tabulated in wavelength by the CC0
  refractiveindex.info database), as ``jc-<X>-eta`` / ``jc-<X>-k`` for X in Fe, Ti: neither project
  ships iron or titanium.
"""
from __future__ import annotations

import functools
import json
from importlib import resources

import numpy as np

__all__ = ["names", "data", "metal_names"]


@functools.lru_cache(maxsize=None)
def _load():
    with resources.files("bsdfkit").joinpath("data/spectra.json").open("r", encoding="utf-8") as f:
        raw = json.load(f)
    out = {}
    for name, d in raw["spectra"].items():
        lam = np.array(d["lambda"], dtype=np.float64)
        val = np.array(d["value"], dtype=np.float64)
        lam.setflags(write=False)
        val.setflags(write=False)
        out[name] = (lam, val, d["source"])
    return out


def names() -> tuple[str, ...]:
    """Every named spectrum, in file order (pbrt-v4 metals, pbrt-v4 glasses, Mitsuba metals,
    Johnson & Christy metals)."""
    return tuple(_load())


def data(name: str):
    """(wavelengths nm, values, source) of a named spectrum, read-only arrays."""
    table = _load()
    if not isinstance(name, str) or name not in table:
        raise ValueError(f"name: unknown named spectrum {name!r}; known: {', '.join(table)}")
    return table[name]


def metal_names(source: str = "pbrt") -> tuple[str, ...]:
    """Metals with eta and k spectra from ``source`` ("pbrt", "mitsuba" or "jc" = Johnson & Christy)."""
    prefix = {"pbrt": "metal-", "mitsuba": "mitsuba-", "jc": "jc-"}.get(source)
    if prefix is None:
        raise ValueError(f"source: expected 'pbrt', 'mitsuba' or 'jc', got {source!r}")
    return tuple(n[len(prefix):-4] for n in _load() if n.startswith(prefix) and n.endswith("-eta"))
