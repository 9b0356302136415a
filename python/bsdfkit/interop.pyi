from typing import Any, Mapping

import numpy as np
import numpy.typing as npt

from ._models import BxDF

MITSUBA_IOR: dict[str, float]
PBRT_GLASS_ETA: dict[str, float]
MIRROR_ETA: float

def spectrum_to_rgb(wavelengths: npt.ArrayLike, values: npt.ArrayLike, *, d65: bool = ...,
                    bounded: bool = ...) -> np.ndarray: ...
def from_mitsuba(d: Mapping[str, Any]) -> BxDF: ...

class PbrtParam:
    type: str
    name: str
    values: tuple[Any, ...]
    line: int
    def __init__(self, type: str, name: str, values: tuple[Any, ...], line: int) -> None: ...

class PbrtMaterial:
    name: str
    type: str
    line: int
    named: bool
    params: dict[str, PbrtParam]
    shapes: int
    def __init__(self, name: str, type: str, line: int, named: bool, params: dict[str, PbrtParam],
                 shapes: int = ...) -> None: ...
    @property
    def ignored(self) -> tuple[str, ...]: ...
    def to_bxdf(self) -> BxDF: ...

def parse_pbrt_materials(text: str) -> list[PbrtMaterial]: ...
def from_pbrt(text: str, *, skip_unsupported: bool = ...) -> dict[str, BxDF]: ...
