"""Type stubs of imu_ar: the readers, Allan deviation, noise model, AR fits and the device's
recursive estimators of imu-ar."""

import os
from typing import Any, Callable, Dict, Iterable, List, NamedTuple, Optional, Sequence, Tuple, Union

import numpy as np
import numpy.typing as npt

__version__: str

PathLike = Union[str, bytes, os.PathLike[str], os.PathLike[bytes]]
ArrayLike = npt.ArrayLike

class Record(NamedTuple):
    x: npt.NDArray[np.float64]
    t: npt.NDArray[np.float64]
    t_ns: npt.NDArray[np.int64]
    columns: List[str]
    rate: Optional[float]
    timing: Optional[Dict[str, Any]]
    units: List[str]
    skipped: Optional[str]

def read(
    path: Union[PathLike, Sequence[PathLike]],
    topic: Optional[str] = ...,
    columns: Optional[Sequence[str]] = ...,
    *,
    frame_id: Optional[str] = ...,
    instance: Optional[int] = ...,
    time_column: Optional[str] = ...,
    drop_backward: bool = ...,
    unit: Optional[str] = ...,
    rate: Optional[float] = ...,
) -> Record: ...

class _AdevTuple(NamedTuple):
    taus: npt.NDArray[np.float64]
    devs: npt.NDArray[np.float64]
    errs: npt.NDArray[np.float64]
    ns: npt.NDArray[np.float64]

class Adev(_AdevTuple):
    rate: float
    def __new__(
        cls,
        taus: npt.NDArray[np.float64],
        devs: npt.NDArray[np.float64],
        errs: npt.NDArray[np.float64],
        ns: npt.NDArray[np.float64],
        rate: float,
    ) -> Adev: ...
    @property
    def m(self) -> npt.NDArray[np.float64]: ...
    @property
    def edf(self) -> npt.NDArray[np.float64]: ...
    @property
    def avar(self) -> npt.NDArray[np.float64]: ...

def adev(x: ArrayLike, rate: float = ..., taus: Union[str, Iterable[float]] = ...) -> Adev: ...

class Kalman(NamedTuple):
    phi: npt.NDArray[np.float64]
    q: npt.NDArray[np.float64]
    p0: npt.NDArray[np.float64]
    h: npt.NDArray[np.float64]
    measurement_variance: float
    states: List[str]
    filter_rate: float

class NoiseModel:
    unit: str
    rate: float
    n: int
    white_noise: Optional[float]
    quantization: Optional[float]
    random_walk: Optional[float]
    rate_ramp: Optional[float]
    bias_instability: float
    bias_instability_tau: float
    gauss_markov: List[Dict[str, float]]
    ar: Optional[Dict[str, Any]]
    budget_limited: bool
    curve_fit: bool
    explained_up_to_s: Optional[float]
    timing: Optional[Dict[str, Any]]
    intervals: Dict[str, Tuple[float, float]]
    white_noise_interval: Optional[Tuple[float, float]]
    quantization_interval: Optional[Tuple[float, float]]
    random_walk_interval: Optional[Tuple[float, float]]
    rate_ramp_interval: Optional[Tuple[float, float]]
    bias_instability_interval: Optional[Tuple[float, float]]
    allan: Dict[str, npt.NDArray[Any]]
    def __init__(
        self,
        result: Dict[str, Any],
        measurement_variance: float,
        states: List[str],
        unit: str,
        refit: Optional[Callable[[float], "NoiseModel"]] = ...,
        h: Optional[Sequence[float]] = ...,
    ) -> None: ...
    def to_dict(self) -> Dict[str, Any]: ...
    def kalman(self, filter_rate: Optional[float] = ...) -> Kalman: ...
    def plot(self, ax: Any = ..., label: Optional[str] = ...) -> Any: ...

def noise(
    x: Union[ArrayLike, PathLike, Sequence[PathLike]],
    rate: Optional[float] = ...,
    gm_states: int = ...,
    ar_order: Optional[int] = ...,
    oscillators: bool = ...,
    *,
    ramp: bool = ...,
    curve_fit: bool = ...,
    filter_rate: Optional[float] = ...,
    decimate: int = ...,
    unit: Optional[str] = ...,
    column: Optional[str] = ...,
    topic: Optional[str] = ...,
) -> NoiseModel: ...

class Characterisation:
    rate: float
    n: int
    timing: Optional[Dict[str, Any]]
    skipped: Dict[str, int]
    axes: Dict[str, NoiseModel]
    columns: Dict[str, str]
    def __init__(
        self,
        result: Dict[str, Any],
        argv: List[str],
        filters: List[Tuple[float, List[str], float, List[float]]],
    ) -> None: ...
    def to_dict(self) -> Dict[str, Any]: ...
    def write(self, dir: PathLike, formats: Sequence[str] = ...) -> List[str]: ...

def characterise(
    path: Union[PathLike, Sequence[PathLike]],
    columns: Optional[Sequence[str]] = ...,
    *,
    rate: Optional[float] = ...,
    topic: Optional[str] = ...,
    frame_id: Optional[str] = ...,
    instance: Optional[int] = ...,
    time_column: Optional[str] = ...,
    drop_backward: bool = ...,
    gyro_unit: Optional[str] = ...,
    accel_unit: Optional[str] = ...,
    gm_states: int = ...,
    oscillators: bool = ...,
    ramp: bool = ...,
    curve_fit: bool = ...,
    filter_rate: Optional[float] = ...,
    horizon: Optional[float] = ...,
    loop_rate: Optional[float] = ...,
    sysid: Optional[int] = ...,
    imu_integ_rate: Optional[float] = ...,
) -> Characterisation: ...

class ArFit:
    method: str
    scalar: str
    order: int
    n: int
    mean: float
    a: npt.NDArray[np.float64]
    noise_variance: float
    reflection: Optional[npt.NDArray[np.float64]]
    gauss_markov: Optional[Dict[str, float]]
    def __init__(self, result: Dict[str, Any]) -> None: ...
    def to_dict(self) -> Dict[str, Any]: ...

def fit_ar(
    x: Union[ArrayLike, Tuple[PathLike, str]],
    order: int,
    method: str = ...,
    *,
    rate: Optional[float] = ...,
    demean: bool = ...,
    decimate: int = ...,
    scalar: str = ...,
    lam: Optional[float] = ...,
    delta: Optional[float] = ...,
) -> ArFit: ...

class OrderCriteria(NamedTuple):
    aic: npt.NDArray[np.float64]
    aicc: npt.NDArray[np.float64]
    bic: npt.NDArray[np.float64]
    fpe: npt.NDArray[np.float64]
    selected: Dict[str, Optional[int]]
    n: int

def order_criteria(
    x: ArrayLike, max_order: int, method: str = ..., *, demean: bool = ...
) -> OrderCriteria: ...

class _Recursive:
    def __init__(
        self,
        order: int,
        lam: float = ...,
        delta: Optional[float] = ...,
        *,
        rate: Optional[float] = ...,
        scalar: Optional[str] = ...,
        demean: bool = ...,
        offset: Optional[float] = ...,
        scale: Optional[float] = ...,
    ) -> None: ...
    def update(self, x: ArrayLike, trace: bool = ...) -> Any:
        """The errors (float64, one per sample); with ``trace``, ``(errors, internals)``."""
    def model(self) -> ArFit: ...
    @property
    def n(self) -> int: ...
    def __copy__(self) -> _Recursive: ...
    def __deepcopy__(self, memo: Dict[int, Any]) -> _Recursive: ...

class Rls(_Recursive): ...
class Lattice(_Recursive): ...
class Sftf(_Recursive): ...
class FixedLattice(_Recursive): ...

def parity_input() -> npt.NDArray[np.float32]: ...
def parity_checksums() -> Tuple[int, int, int]: ...
def centre(x: ArrayLike) -> float: ...
