from typing import Any, ClassVar, Literal, Optional, Union

import numpy as np
import numpy.typing as npt

from ._enums import BxDFFlags, ReflTrans, TransportMode

ArrayLike = npt.ArrayLike
RGB = Union[float, npt.ArrayLike]
Masking = Literal["correlated", "separable"]
ConductorFresnel = Literal["exact", "schlick", "f82"]
ModeLike = Union[TransportMode, int, Literal["radiance", "importance", "Radiance", "Importance"]]

METALS: dict[str, tuple[tuple[float, float, float], tuple[float, float, float]]]

def roughness_to_alpha(roughness: npt.ArrayLike) -> Union[float, np.ndarray]: ...
def conductor_fresnel(cos_theta: ArrayLike, eta: RGB, k: RGB, fresnel: ConductorFresnel = ...) -> np.ndarray: ...

class SampleResult:
    wi: np.ndarray
    f: np.ndarray
    pdf: np.ndarray
    flags: np.ndarray
    eta: np.ndarray
    valid: np.ndarray
    pdf_is_proportional: np.ndarray
    @property
    def weight(self) -> np.ndarray: ...

class BxDF:
    @property
    def flags(self) -> BxDFFlags: ...
    def eval(self, wo: ArrayLike, wi: ArrayLike, mode: ModeLike = ..., out: Optional[np.ndarray] = ...) -> np.ndarray: ...
    def pdf(self, wo: ArrayLike, wi: ArrayLike, mode: ModeLike = ..., sample_flags: Union[ReflTrans, int] = ...,
            out: Optional[np.ndarray] = ...) -> np.ndarray: ...
    def sample(self, wo: ArrayLike, uc: Optional[ArrayLike] = ..., u: Optional[ArrayLike] = ..., *,
               n: Optional[int] = ..., seed: Optional[int] = ..., mode: ModeLike = ...,
               sample_flags: Union[ReflTrans, int] = ...) -> SampleResult: ...
    def albedo(self, wo: ArrayLike, n_samples: int = ..., seed: int = ..., mode: ModeLike = ...) -> np.ndarray: ...
    def __eq__(self, other: object) -> bool: ...
    def __hash__(self) -> int: ...

class Diffuse(BxDF):
    reflectance: np.ndarray
    def __init__(self, reflectance: RGB = ...) -> None: ...

class DiffuseTransmission(BxDF):
    reflectance: np.ndarray
    transmittance: np.ndarray
    def __init__(self, reflectance: RGB = ..., transmittance: RGB = ...) -> None: ...

class Conductor(BxDF):
    eta: np.ndarray
    k: np.ndarray
    alpha_x: float
    alpha_y: float
    masking: Masking
    fresnel: ConductorFresnel
    def __init__(self, eta: RGB, k: RGB, alpha: float = ..., alpha_x: Optional[float] = ...,
                 alpha_y: Optional[float] = ..., masking: Masking = ..., fresnel: ConductorFresnel = ...) -> None: ...
    @classmethod
    def from_metal(cls, name: str, roughness: Optional[float] = ..., *, alpha: Optional[float] = ...,
                   alpha_x: Optional[float] = ..., alpha_y: Optional[float] = ...,
                   masking: Masking = ..., fresnel: ConductorFresnel = ...) -> "Conductor": ...
    @classmethod
    def from_reflectance(cls, reflectance: RGB, roughness: Optional[float] = ..., *, alpha: Optional[float] = ...,
                         alpha_x: Optional[float] = ..., alpha_y: Optional[float] = ...,
                         masking: Masking = ..., fresnel: ConductorFresnel = ...) -> "Conductor": ...

class Dielectric(BxDF):
    eta: float
    alpha_x: float
    alpha_y: float
    masking: Masking
    def __init__(self, eta: float = ..., alpha: float = ..., alpha_x: Optional[float] = ...,
                 alpha_y: Optional[float] = ..., masking: Masking = ...) -> None: ...

class ThinDielectric(BxDF):
    eta: float
    def __init__(self, eta: float = ...) -> None: ...
