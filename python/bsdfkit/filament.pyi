from typing import Optional

import numpy as np
import numpy.typing as npt

MIN_PERCEPTUAL_ROUGHNESS: dict[str, float]
MIN_N_DOT_V: float
DFG_LUT_SIZE: int
DFG_LUT_SAMPLES: int
TERMS: dict[str, tuple[str, ...]]

def dfg_lut(size: int = ..., samples: Optional[int] = ..., *, progress: Optional[bool] = ...) -> np.ndarray: ...
def term(name: str, *args: npt.ArrayLike, dtype: npt.DTypeLike = ...) -> np.ndarray: ...
def examples() -> dict: ...
