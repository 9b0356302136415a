from typing import Literal, Optional, Union

import numpy as np
import numpy.typing as npt

from ._models import BxDF

RGB = Union[float, npt.ArrayLike]
DiffuseKnob = Literal["lambert", "burley"]
MinRoughness = Union[Literal["desktop", "mobile"], float]

MIN_ROUGHNESS_FLOOR: float

class FilamentStandard(BxDF):
    base_color: np.ndarray
    metallic: float
    roughness: float
    reflectance: float
    anisotropy: float
    clear_coat: float
    clear_coat_roughness: float
    sheen_color: np.ndarray
    sheen_roughness: float
    diffuse: DiffuseKnob
    visibility: Literal["correlated", "fast"]
    f90: Literal["one", "filament"]
    energy_compensation: bool
    min_roughness: MinRoughness
    clear_coat_layering: Literal["code", "doc"]
    clear_coat_ior_change: bool
    dfg_lut_size: int
    def __init__(self, base_color: RGB = ..., metallic: float = ..., roughness: float = ..., reflectance: float = ...,
                 anisotropy: float = ..., clear_coat: float = ..., clear_coat_roughness: float = ...,
                 sheen_color: RGB = ..., sheen_roughness: float = ..., *, diffuse: DiffuseKnob = ...,
                 visibility: Literal["correlated", "fast"] = ..., f90: Literal["one", "filament"] = ...,
                 energy_compensation: bool = ..., min_roughness: MinRoughness = ...,
                 clear_coat_layering: Literal["code", "doc"] = ..., clear_coat_ior_change: bool = ...,
                 dfg_lut_size: int = ...) -> None: ...
    @property
    def min_perceptual_roughness(self) -> float: ...

class FilamentCloth(BxDF):
    base_color: np.ndarray
    sheen_color: Optional[np.ndarray]
    subsurface_color: Optional[np.ndarray]
    roughness: float
    diffuse: DiffuseKnob
    min_roughness: MinRoughness
    dfg_lut_size: int
    def __init__(self, base_color: RGB = ..., sheen_color: Optional[RGB] = ..., subsurface_color: Optional[RGB] = ...,
                 roughness: float = ..., *, diffuse: DiffuseKnob = ..., min_roughness: MinRoughness = ...,
                 dfg_lut_size: int = ...) -> None: ...
    @property
    def effective_sheen_color(self) -> np.ndarray: ...
    @property
    def min_perceptual_roughness(self) -> float: ...
