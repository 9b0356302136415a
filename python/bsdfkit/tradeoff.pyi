from typing import Any, Literal, Optional, Tuple, Union

import numpy as np
import numpy.typing as npt

from ._models import BxDF

Metric = Literal["max", "p99", "albedo"]
Directions = Union[None, "DirectionSet", Tuple[npt.ArrayLike, npt.ArrayLike]]

METRICS: dict[str, str]
FLOOR_FRACTION: float
ALBEDO_COS_THETA: tuple[float, ...]
COST_RESOLUTION: float
MIN_COS: float

class Knob:
    name: str
    kind: Literal["precision", "approximation", "lobe"]
    settings: tuple
    labels: tuple[str, ...]
    value: object
    reachable: bool
    note: str

class Config:
    labels: dict[str, Optional[str]]
    index: dict[str, int]
    model: BxDF
    dtype: type
    key: str
    cheapness: tuple[float, ...]
    @property
    def is_reference(self) -> bool: ...
    def changes(self) -> dict[str, str]: ...
    def describe(self) -> str: ...
    @property
    def registry_rank(self) -> tuple: ...

class DirectionSet:
    wo: np.ndarray
    wi: np.ndarray
    delta_wo: np.ndarray
    delta_uc: np.ndarray
    delta_u: np.ndarray
    albedo_wo: np.ndarray
    albedo_uc: np.ndarray
    albedo_u: np.ndarray
    seed: Optional[int]
    def __len__(self) -> int: ...

def knobs(model: BxDF) -> tuple[Knob, ...]: ...
def configurations(model: BxDF) -> list[Config]: ...
def family(model: BxDF) -> str: ...
def direction_set(model: BxDF, n: int = ..., seed: int = ..., *, n_albedo: int = ...) -> DirectionSet: ...
def relative_error(v_ref: npt.ArrayLike, v: npt.ArrayLike, floor: float) -> np.ndarray: ...
def knob_costs(path: Optional[str] = ...) -> dict[str, Any]: ...

class Table:
    model: BxDF
    reference: BxDF
    configs: list[Config]
    knobs: tuple[Knob, ...]
    floor: float
    reference_albedo: np.ndarray
    directions: DirectionSet
    family: str
    measured: bool
    seed: Optional[int]
    info: dict[str, Any]
    columns: list[str]
    def __len__(self) -> int: ...
    def __getitem__(self, i: Union[int, str]) -> Any: ...
    def to_records(self) -> list[dict[str, Any]]: ...
    def to_dict(self) -> dict[str, list]: ...
    def to_pandas(self) -> Any: ...
    def pareto_front(self, metric: Metric = ...) -> list[int]: ...
    def _repr_html_(self) -> str: ...
    def _repr_markdown_(self) -> str: ...

class SimplifyReport:
    input_model: BxDF
    model: BxDF
    dtype: type
    config: dict[str, Optional[str]]
    changes: list[tuple[str, str, str, str]]
    kept: list[tuple[str, str]]
    error: dict[str, float]
    tol: float
    metric: Metric
    expected_speedup: Optional[float]
    speedup_vs_input: Optional[float]
    ranked_by: str
    reference: BxDF
    description: str
    n_configurations: int
    n_within_tol: int
    seed: int
    floor: float
    notes: list[str]
    def summary(self) -> str: ...
    def _repr_markdown_(self) -> str: ...

def tradeoff(model: BxDF, directions: Directions = ..., n: int = ..., seed: int = ..., *, n_albedo: int = ...,
             measure: bool = ..., n_timing: int = ..., repeats: int = ..., rounds: int = ...,
             costs: Optional[dict] = ...) -> Table: ...
def simplify(model: BxDF, tol: float, metric: Metric = ..., directions: Directions = ..., seed: int = ..., *,
             n: int = ..., n_albedo: int = ..., costs: Optional[dict] = ...) -> tuple[BxDF, SimplifyReport]: ...
def pareto(table: Table, ax: Any = ..., metric: Metric = ...) -> Any: ...
