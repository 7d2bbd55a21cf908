"""imu_ar: AR and noise models of MEMS IMU errors, from Python.

The readers, the Allan deviation, the composite noise model, the AR fits and the device's
recursive estimators of the ``imu-ar`` tool and library, with numpy arrays in and out. Every
function runs the tool's own code (the Rust crates, compiled into ``imu_ar._native``): a
result from Python is the tool's result, and the estimators are the code the firmware runs.

>>> import numpy as np, imu_ar
>>> x = np.random.default_rng(1).normal(size=100_000)
>>> taus, devs, errs, ns = imu_ar.adev(x, rate=100.0)
>>> model = imu_ar.noise(x, rate=100.0)
>>> model.white_noise                                   # doctest: +SKIP
0.0999...

Errors are Python exceptions with the tool's messages: ``ValueError`` for bad settings or data,
``FileNotFoundError`` and ``OSError`` for files, ``TypeError`` for an array that is not of real
numbers. The long calls release the GIL.
"""

from __future__ import annotations

import functools
import json
import math
import operator
import os
import tempfile
from pathlib import Path
from typing import Any, Dict, Iterable, List, NamedTuple, Optional, Sequence, Tuple, Union

import numpy as np

from . import _native

__all__ = [
    "Adev",
    "ArFit",
    "Characterisation",
    "FixedLattice",
    "Kalman",
    "Lattice",
    "NoiseModel",
    "OrderCriteria",
    "Record",
    "Rls",
    "Sftf",
    "adev",
    "centre",
    "characterise",
    "fit_ar",
    "noise",
    "order_criteria",
    "parity_checksums",
    "parity_input",
    "read",
]

__version__ = _native.__version__

PathLike = Union[str, bytes, "os.PathLike[str]", "os.PathLike[bytes]"]

# The name the tool's messages give an array passed from Python (where it names a file).
_ARRAY = "<array>"


def _samples(x: Any, name: str = "x") -> np.ndarray:
    """``x`` as a contiguous 1-D float64 array; TypeError or ValueError otherwise."""
    a = np.asarray(x)
    if a.dtype.kind not in "fiub":
        raise TypeError(f"{name}: an array of real numbers is needed, not dtype {a.dtype}")
    if a.ndim != 1:
        raise ValueError(f"{name}: a 1-D array is needed, not {a.ndim}-D of shape {a.shape}")
    return np.ascontiguousarray(a, dtype=np.float64)


def _num(v: float) -> str:
    """A number as a flag's value (shortest round trip, as the tool parses it back)."""
    return repr(float(v))


def _is_path(x: Any) -> bool:
    return isinstance(x, (str, bytes, os.PathLike))


def _path(p: Any) -> str:
    """A path as the tool takes it: bytes and names that are not UTF-8 pass through
    ``os.fsdecode`` and come back to the file system byte for byte; a name that starts with
    ``-`` is a file's (``./-``), never an option or standard input."""
    p = os.fsdecode(os.fspath(p))
    return os.path.join(".", p) if p.startswith("-") else p


# The tool's flags that take no value.
_SWITCHES = {"--oscillators", "--ramp", "--curve-fit", "--no-demean", "--drop-backward", "--json"}


def _cli(argv: List[str]) -> List[str]:
    """``argv`` with each flag joined to its value (``--column=-x``): a value that starts with
    ``-`` (a negative number, a column's name) is then never read as a flag."""
    out: List[str] = []
    i = 0
    while i < len(argv):
        a = argv[i]
        if a.startswith("--") and "=" not in a and a not in _SWITCHES and i + 1 < len(argv):
            out.append(f"{a}={argv[i + 1]}")
            i += 2
        else:
            out.append(a)
            i += 1
    return out


def _files(path: Union[PathLike, Sequence[PathLike]]) -> List[str]:
    """One file, or several read as one record, as absolute paths: a model's refit and a
    characterisation's files read them again wherever the working directory has gone."""
    if _is_path(path):
        return [os.path.abspath(_path(path))]
    files = [os.path.abspath(_path(p)) for p in path]
    if not files:
        raise ValueError("path: no files given")
    return files


def _int(name: str, v: Any, minimum: int = 0) -> int:
    """``v`` as an integer option: an ``int`` (or numpy integer) of at least ``minimum``;
    ``TypeError`` for a float or anything else, ``ValueError`` below the minimum."""
    try:
        if isinstance(v, (bool, np.bool_)):
            raise TypeError
        i = operator.index(v)
    except TypeError:
        raise TypeError(f"{name}: an integer is needed, not {type(v).__name__} {v!r}") from None
    if i < minimum:
        raise ValueError(f"{name} {i}: must be at least {minimum}")
    return i


def _names(name: str, v: Any) -> List[str]:
    """A list of names; one string is one name (not its characters)."""
    if isinstance(v, (str, bytes)):
        v = [v]
    out = [os.fsdecode(c) if isinstance(c, bytes) else str(c) for c in v]
    if not out:
        raise ValueError(f"{name}: none given")
    return out


def _input_flags(
    topic: Optional[str] = None,
    frame_id: Optional[str] = None,
    instance: Optional[int] = None,
    time_column: Optional[str] = None,
    drop_backward: bool = False,
    unit: Optional[str] = None,
) -> List[str]:
    argv: List[str] = []
    if topic is not None:
        argv += ["--topic", topic]
    if frame_id is not None:
        argv += ["--frame-id", frame_id]
    if instance is not None:
        argv += ["--instance", str(_int("instance", instance))]
    if time_column is not None:
        argv += ["--time-column", time_column]
    if drop_backward:
        argv += ["--drop-backward"]
    if unit is not None:
        argv += ["--unit", unit]
    return argv


# --- reading -------------------------------------------------------------------------------

_AXES = ["gx", "gy", "gz", "ax", "ay", "az"]
_NO_STAMP = np.iinfo(np.int64).min


class Record(NamedTuple):
    """What :func:`read` returns.

    ``x`` has one column per name of ``columns`` (shape ``(n, k)``; 1-D for one column);
    ``t_ns`` holds each sample's timestamp in ns as the record gives it (int64; the least
    int64 where a sample has none, as in a CSV file without a time column), ``t`` the same in
    s from the first (NaN where none); ``rate`` is the timestamps' rate, or the one given
    (``None`` when neither); ``timing`` is the tool's
    report of them (``imu-ar ... --json``'s ``timing``), ``units`` the unit of each column,
    ``skipped`` the tool's summary of skipped messages (or ``None``).
    """

    x: np.ndarray
    t: np.ndarray
    t_ns: np.ndarray
    columns: List[str]
    rate: Optional[float]
    timing: Optional[Dict[str, Any]]
    units: List[str]
    skipped: Optional[str]


def read(
    path: Union[PathLike, Sequence[PathLike]],
    topic: Optional[str] = None,
    columns: Optional[Sequence[str]] = None,
    *,
    frame_id: Optional[str] = None,
    instance: Optional[int] = None,
    time_column: Optional[str] = None,
    drop_backward: bool = False,
    unit: Optional[str] = None,
    rate: Optional[float] = None,
) -> Record:
    """Reads columns of a recording with the tool's readers.

    ``path`` is a CSV file (or several read as one record), a ROS 1 bag, an MCAP file, a rosbag2
    folder or database (with ``topic``), a PX4 ULog file or an ArduPilot DataFlash log.
    ``columns`` are CSV column names (with or without their unit bracket) or 0-based indices;
    for the logs ``gx, gy, gz, ax, ay, az`` [default: every CSV column but the time column, or
    the six axes]. ``unit`` converts columns of known unit (rad/s, deg/s, deg/h, m/s^2, g, mg).
    The timestamps are checked as the tool checks them; ``Record.timing`` is their report.
    With ``rate`` (Hz) they need not pass those checks (for records whose stamps the tool
    refuses: no unit, mixed rates); where they still give a rate, ``rate`` must agree with it
    within 1 %, as the tool requires, and ``timing`` is their report (else ``None``).
    """
    files = _files(path)
    if columns is None:
        if _native.kind(files[0]) == "Csv" and os.path.isfile(files[0]):
            columns = _native.csv_columns(files[0], time_column)
        else:
            columns = list(_AXES)
        if not columns:
            raise ValueError(f"{files[0]}: no columns to read")
    else:
        columns = _names("columns", columns)
    flags = _input_flags(topic, frame_id, instance, time_column, drop_backward, unit)
    if rate is not None:
        flags += ["--rate", _num(rate)]
    data = []
    units = []
    timing = None
    skipped = None
    stamps = None
    for c in columns:
        x, t_ns, t, u, s = _native.read(
            _cli(["read", *files, "--column", c, *flags]), timing is None
        )
        data.append(x)
        units.append(u)
        if t is not None and timing is None:
            timing = json.loads(t)
        if stamps is None:
            stamps = t_ns
        skipped = skipped or s
    x = data[0] if len(data) == 1 else np.column_stack(data)
    if rate is None:
        rate = timing["rate_hz"] if timing else None
    else:
        rate = float(rate)
    missing = stamps == _NO_STAMP
    seconds = np.full(len(stamps), np.nan)
    if (~missing).any():
        first = stamps[~missing][0]
        seconds[~missing] = (stamps[~missing] - first) / 1e9
    return Record(x, seconds, stamps, columns, rate, timing, units, skipped)


# --- Allan deviation -----------------------------------------------------------------------


class _AdevTuple(NamedTuple):
    taus: np.ndarray
    devs: np.ndarray
    errs: np.ndarray
    ns: np.ndarray


class Adev(_AdevTuple):
    """The overlapping Allan deviation, as ``allantools.oadev`` returns it:
    ``(taus, devs, errs, ns)``: the averaging times (s), the deviations, their errors
    ``dev / sqrt(n)`` and the number of second differences ``n`` behind each; ``rate`` is the
    sample rate (Hz), ``m`` the averaging factors, ``edf`` and ``avar`` as below."""

    rate: float

    def __new__(
        cls, taus: np.ndarray, devs: np.ndarray, errs: np.ndarray, ns: np.ndarray, rate: float
    ) -> "Adev":
        self = super().__new__(cls, taus, devs, errs, ns)
        self.rate = float(rate)
        return self

    def __getnewargs__(self) -> Tuple[Any, ...]:
        return (*self, self.rate)

    def _replace(self, **fields: Any) -> "Adev":
        return Adev(*_AdevTuple(*self)._replace(**fields), self.rate)

    @classmethod
    def _make(cls, iterable: Iterable[Any]) -> "Adev":
        """An ``Adev`` of ``(taus, devs, errs, ns, rate)``: the rate is part of it."""
        items = list(iterable)
        if len(items) != 5:
            raise TypeError(
                f"Adev._make: (taus, devs, errs, ns, rate) needed, not {len(items)} items"
            )
        return cls(*items)

    def __eq__(self, other: object) -> bool:
        return (
            isinstance(other, Adev)
            and self.rate == other.rate
            and all(np.array_equal(a, b) for a, b in zip(self, other))
        )

    def __ne__(self, other: object) -> bool:
        return not self == other

    __hash__ = None  # type: ignore[assignment]

    @property
    def m(self) -> np.ndarray:
        """The averaging factors ``tau x rate``."""
        return np.round(self.taus * self.rate)

    @property
    def edf(self) -> np.ndarray:
        """Equivalent degrees of freedom of each deviation for white frequency noise (Howe,
        Allan and Barnes, NIST SP 1065, eq. 42, ``N`` the phase points: the samples plus one),
        for chi-squared intervals of the deviations."""
        m = self.m
        n = self.ns + 2.0 * m  # the phase points, n + 1 for n rate samples
        return (3.0 * (n - 1.0) / (2.0 * m) - 2.0 * (n - 2.0) / n) * (4.0 * m * m) / (
            4.0 * m * m + 5.0
        )

    @property
    def avar(self) -> np.ndarray:
        """The Allan variances."""
        return self.devs**2


def _factors(n: int, rate: float, taus: Union[str, Iterable[float]]) -> np.ndarray:
    """The averaging factors of ``taus`` as allantools chooses them (``n`` samples)."""
    if isinstance(taus, str):
        if taus == "octave":
            maxn = int(math.floor(math.log2(n + 1)))
            m = 2.0 ** np.arange(maxn + 1)
        elif taus == "decade":
            maxn = int(math.floor(math.log10(n + 1)))
            m = np.array([f * 10.0**k for k in range(maxn + 1) for f in (1.0, 2.0, 4.0)])
        elif taus == "all":
            m = np.arange(1.0, n + 2)
        else:
            raise ValueError(f"taus {taus!r}: 'octave', 'decade', 'all' or an array of seconds")
    else:
        t = np.asarray(list(taus) if not isinstance(taus, np.ndarray) else taus, dtype=float)
        if t.ndim != 1 or not np.all(np.isfinite(t)):
            raise ValueError("taus: a 1-D array of finite averaging times in s")
        m = np.round(t * rate)
    m = m[(m > 0) & (m < n + 1)]
    m = np.unique(m)
    # At least two second differences, as allantools keeps.
    return m[n + 1 - 2 * m > 1].astype(np.int64)


def adev(x: Any, rate: float = 1.0, taus: Union[str, Iterable[float]] = "octave") -> Adev:
    """The overlapping Allan deviation of the rate samples ``x`` at ``rate`` Hz.

    The same numbers as ``allantools.oadev(x, rate=rate, data_type="freq", taus=taus)``
    (``taus`` "octave", "decade", "all" or averaging times in s), computed by the library's
    estimator, one pass per averaging factor, the factors spread over the cores; the GIL is
    released meanwhile.
    """
    x = _samples(x)
    rate = float(rate)
    if not (math.isfinite(rate) and rate > 0):
        raise ValueError(f"--rate {rate}: must be a positive number of Hz")
    if len(x) < 2:
        raise ValueError(f"{len(x)} sample(s), at least 2 needed")
    m = _factors(len(x), rate, taus)
    if len(m) == 0:
        raise ValueError(f"no averaging time leaves two second differences in {len(x)} samples")
    avar = _native.octave_avar(x, [int(v) for v in m])
    if not np.all(np.isfinite(avar)):
        tau = m[~np.isfinite(avar)][0] / rate
        raise ValueError(
            f"the Allan variance at tau = {tau:g} s overflows f64 (values of about 1e154 or "
            "more); rescale the samples"
        )
    ns = (len(x) - 2 * m + 1).astype(float)
    devs = np.sqrt(avar)
    return Adev(m / rate, devs, devs / np.sqrt(ns), ns, rate)


# --- the noise model -----------------------------------------------------------------------


class Kalman(NamedTuple):
    """The model in a Kalman filter at ``filter_rate``: the transition ``phi``, the process
    noise ``q`` and the initial covariance ``p0`` of one step, the measurement row ``h`` (a
    sample is ``h @ state + v``: 1 on each state, but 0 on an oscillator's ``dx/dt`` and -1
    on the earlier quantisation state), the variance of the white ``v`` and the states'
    names."""

    phi: np.ndarray
    q: np.ndarray
    p0: np.ndarray
    h: np.ndarray
    measurement_variance: float
    states: List[str]
    filter_rate: float


_PARAMETERS = ("white_noise", "quantization", "random_walk", "rate_ramp", "bias_instability")


class NoiseModel:
    """The composite noise model of one axis, as ``imu-ar noise`` fits it.

    Attributes: ``white_noise`` (N), ``quantization`` (Q), ``random_walk`` (K), ``rate_ramp``
    (R), ``bias_instability`` (B, at ``bias_instability_tau``), ``gauss_markov`` (a list of
    dicts: ``sigma``, ``correlation_time_s``, ``frequency_hz`` for an oscillator), ``ar`` (the
    AR part or ``None``), ``rate``, ``n``; ``intervals`` maps each parameter to its 95 %
    interval ``(low, high)`` where the library gives one (``white_noise_interval`` and so on as
    attributes too); ``allan`` is the Allan check (a dict of arrays: ``tau_s``, ``data_adev``,
    ``model_adev``, ``data_over_model``, ``tolerance``, ``agrees``). A parameter the model does
    not have is ``None``.
    """

    def __init__(
        self,
        result: Dict[str, Any],
        measurement_variance: float,
        states: List[str],
        unit: str,
        refit: Optional[Any] = None,
        h: Optional[Sequence[float]] = None,
    ) -> None:
        self._result = result
        self._measurement_variance = measurement_variance
        self._states = list(states)
        self._h = [1.0] * len(self._states) if h is None else list(h)
        self.unit = unit
        self._refit = refit
        self.rate: float = result["rate_hz"]
        self.n: int = result["n"]
        self.white_noise: Optional[float] = result["white_noise"]
        self.quantization: Optional[float] = result["quantization"]
        self.random_walk: Optional[float] = result["random_walk"]
        self.rate_ramp: Optional[float] = result["rate_ramp"]
        self.bias_instability: float = result["bias_instability"]["value"]
        self.bias_instability_tau: float = result["bias_instability"]["tau_s"]
        self.gauss_markov: List[Dict[str, float]] = result["gauss_markov"]
        self.ar: Optional[Dict[str, Any]] = result["ar"]
        self.budget_limited: bool = result["budget_limited"]
        self.curve_fit: bool = result["curve_fit"]
        self.explained_up_to_s: Optional[float] = result["explained_up_to_s"]
        self.timing: Optional[Dict[str, Any]] = result.get("timing")
        self.intervals: Dict[str, Tuple[float, float]] = {}
        iv = result.get("intervals")
        if iv:
            for key in _PARAMETERS:
                b = iv[key]
                self.intervals[key] = (b["low"], _inf(b["high"]))
            for i, t in enumerate(iv["gauss_markov"]):
                for key, b in t.items():
                    if b is not None:
                        self.intervals[f"gauss_markov[{i}].{key}"] = (b["low"], _inf(b["high"]))
        for key in _PARAMETERS:
            setattr(self, f"{key}_interval", self.intervals.get(key))
        rows = result["allan"]
        self.allan: Dict[str, np.ndarray] = {
            k: np.array([r[k] for r in rows], dtype=bool if k == "agrees" else float)
            for k in ("tau_s", "data_adev", "model_adev", "data_over_model", "tolerance", "agrees")
        }

    def to_dict(self) -> Dict[str, Any]:
        """The model as ``imu-ar noise --json`` prints it (the same keys and numbers)."""
        return json.loads(json.dumps(self._result))

    def kalman(self, filter_rate: Optional[float] = None) -> Kalman:
        """The model's filter form at ``filter_rate`` Hz [default: the model's rate]: ``phi``,
        ``q``, ``p0``, ``h`` and the measurement variance, as ``imu-ar noise --filter-rate``
        (another rate than the fit's fits the record again)."""
        r, mv, states, h = self._result, self._measurement_variance, self._states, self._h
        if filter_rate is not None and float(filter_rate) != self._filter_rate():
            if self._refit is None:
                raise ValueError(
                    "filter_rate: this model was read from the tool's output; fit it with "
                    "imu_ar.noise(..., filter_rate=...)"
                )
            other = self._refit(float(filter_rate))
            r, mv, states, h = (other._result, other._measurement_variance, other._states,
                                other._h)
        rate = float(filter_rate) if filter_rate is not None else self._filter_rate()
        # A model without states (white noise only) has 0 x 0 matrices.
        def matrix(rows: Any) -> np.ndarray:
            return np.array(rows, dtype=float).reshape(len(rows), len(rows))

        return Kalman(
            matrix(r["phi"]),
            matrix(r["q"]),
            matrix(r["p0"]),
            np.array(h, dtype=float),
            float(mv),
            list(states),
            rate,
        )

    def _filter_rate(self) -> float:
        return getattr(self, "_filter", None) or self.rate

    def plot(self, ax: Any = None, label: Optional[str] = None) -> Any:
        """The Allan deviation of the data (with the check's tolerance) and of the model, and
        the white noise and random walk asymptotes, on ``ax`` (a new figure's when ``None``).
        Needs matplotlib; returns the axes."""
        try:
            import matplotlib.pyplot as plt
        except ImportError as e:  # pragma: no cover - depends on the environment
            raise ImportError("NoiseModel.plot needs matplotlib (pip install matplotlib)") from e
        if ax is None:
            _, ax = plt.subplots(figsize=(7, 4.5))
        a = self.allan
        tau, data, model = a["tau_s"], a["data_adev"], a["model_adev"]
        tol = a["tolerance"]
        ax.fill_between(
            tau, data / (1 + tol), data * (1 + tol), color="0.85", label="data, tolerance"
        )
        ax.loglog(tau, data, "o", ms=3.5, color="black", label=label or "data")
        ax.loglog(tau, model, "-", color="tab:red", lw=1.8, label="model")
        if self.white_noise:
            ax.loglog(tau, self.white_noise / np.sqrt(tau), "--", color="tab:blue", lw=1,
                      label=f"N = {self.white_noise:.3g}")
        if self.random_walk:
            ax.loglog(tau, self.random_walk * np.sqrt(tau / 3), "--", color="tab:green", lw=1,
                      label=f"K = {self.random_walk:.3g}")
        ax.axhline(self.bias_instability * 0.664, color="tab:purple", lw=0.8, ls=":",
                   label=f"B = {self.bias_instability:.3g}")
        ax.set_xlabel("tau (s)")
        ax.set_ylabel(f"Allan deviation ({self.unit})")
        ax.grid(True, which="both", alpha=0.3)
        ax.legend(fontsize=8)
        return ax

    def __repr__(self) -> str:
        return (
            f"NoiseModel(n={self.n}, rate={self.rate}, white_noise={self.white_noise}, "
            f"random_walk={self.random_walk}, bias_instability={self.bias_instability}, "
            f"gauss_markov={len(self.gauss_markov)}, ar={'none' if not self.ar else self.ar['order']})"
        )


def _inf(v: Optional[float]) -> float:
    """An interval's end: ``null`` in the JSON is an unbounded one."""
    return math.inf if v is None else v


def noise(
    x: Any,
    rate: Optional[float] = None,
    gm_states: int = 3,
    ar_order: Optional[int] = None,
    oscillators: bool = False,
    *,
    ramp: bool = False,
    curve_fit: bool = False,
    filter_rate: Optional[float] = None,
    decimate: int = 1,
    unit: Optional[str] = None,
    column: Optional[str] = None,
    topic: Optional[str] = None,
) -> NoiseModel:
    """The composite noise model of ``x`` (rate samples at ``rate`` Hz), as ``imu-ar noise``:
    white noise, quantisation, Gauss-Markov terms (``gm_states`` Kalman states; with
    ``oscillators`` second-order ones too), random walk, a rate ramp (``ramp``) and an AR part
    (``ar_order``; default: the order 0 to 8 BIC selects, 0 for none), with the Allan check and
    the Kalman filter's form at ``filter_rate``.

    ``x`` may also be a recording's path with ``column`` (and ``topic``), read by the tool;
    ``rate`` then defaults to the timestamps'. The GIL is released during the fit.
    """
    argv = ["noise"]
    tail: List[str] = []
    if rate is not None:
        tail += ["--rate", _num(rate)]
    tail += ["--gm-states", str(_int("gm_states", gm_states))]
    if ar_order is not None:
        tail += ["--ar-order", str(_int("ar_order", ar_order))]
    if oscillators:
        tail.append("--oscillators")
    if ramp:
        tail.append("--ramp")
    if curve_fit:
        tail.append("--curve-fit")
    if filter_rate is not None:
        tail += ["--filter-rate", _num(filter_rate)]
    tail += ["--decimate", str(_int("decimate", decimate, 1))]
    if _is_path(x) or (isinstance(x, (list, tuple)) and x and all(_is_path(p) for p in x)):
        if column is None:
            raise ValueError("column: a recording's column must be named")
        argv += [*_files(x), "--column", str(column), *_input_flags(topic=topic, unit=unit)]
        samples = None
    else:
        if rate is None:
            raise ValueError("rate: the sample rate of an array must be given (Hz)")
        samples = _samples(x)
        argv += [_ARRAY, "--column", "x", *_input_flags(unit=unit)]
    out, mv, states, u, h = _native.noise(_cli([*argv, *tail, "--json"]), samples)
    # The refit reads what this fit read: the samples as they are now (a copy, not the
    # caller's buffer), the files by their absolute paths.
    again = _files(x) if samples is None else samples.copy()
    refit = functools.partial(
        _noise_at, again, rate, gm_states, ar_order, oscillators, ramp, curve_fit, decimate, unit,
        column, topic,
    )
    model = NoiseModel(json.loads(out), mv, states, u, refit, h)
    model._filter = float(filter_rate) if filter_rate is not None else None  # type: ignore[attr-defined]
    return model


def _noise_at(
    x: Any, rate: Any, gm_states: Any, ar_order: Any, oscillators: Any, ramp: Any,
    curve_fit: Any, decimate: Any, unit: Any, column: Any, topic: Any, filter_rate: float,
) -> NoiseModel:
    """:func:`noise` again at another filter rate (a module function: a model pickles)."""
    return noise(x, rate, gm_states, ar_order, oscillators, ramp=ramp, curve_fit=curve_fit,
                 filter_rate=filter_rate, decimate=decimate, unit=unit, column=column,
                 topic=topic)


# --- characterise --------------------------------------------------------------------------


def _characterised(argv: List[str]) -> "Characterisation":
    """``imu-ar characterise`` of ``argv``, its files into a folder that is then removed."""
    with tempfile.TemporaryDirectory(prefix="imu-ar-") as tmp:
        out, filters = _native.characterise(
            _cli([*argv, "--out", tmp, "--format", "state-space", "--json"])
        )
    return Characterisation(json.loads(out), argv, filters)


def _axis_at(argv: List[str], axis: str, filter_rate: float) -> "NoiseModel":
    """The recording characterised again with the filter at another rate: ``axis``'s model."""
    # Joined, a flag's value is part of its token: only the filter rate's own token goes.
    kept = [a for a in _cli(argv) if not a.startswith("--filter-rate=")]
    again = [*kept, f"--filter-rate={_num(filter_rate)}"]
    return _characterised(again).axes[axis]


class Characterisation:
    """The six axes' noise models of a recording (``imu-ar characterise``): ``axes`` maps
    ``gx .. az`` to a :class:`NoiseModel` (in SI units: rad/s, m/s^2); ``rate``, ``n``,
    ``timing`` and ``skipped`` as the tool reports them. :meth:`write` writes the parameter
    files."""

    def __init__(
        self,
        result: Dict[str, Any],
        argv: List[str],
        filters: List[Tuple[float, List[str], float, List[float]]],
    ) -> None:
        self._result = result
        self._argv = argv
        self.rate: float = result["rate_hz"]
        self.n: int = result["n"]
        self.timing: Optional[Dict[str, Any]] = result.get("timing")
        self.skipped: Dict[str, int] = result["skipped"]

        self.axes: Dict[str, NoiseModel] = {}
        for a, (mv, states, filter_rate, h) in zip(result["axes"], filters):
            refit = functools.partial(_axis_at, argv, a["axis"])
            model = NoiseModel(a["model"], mv, states, a["unit"], refit, h)
            model._filter = filter_rate  # type: ignore[attr-defined]
            self.axes[a["axis"]] = model
        self.columns: Dict[str, str] = {a["axis"]: a["column"] for a in result["axes"]}

    def to_dict(self) -> Dict[str, Any]:
        """The result as ``imu-ar characterise --json`` prints it (``files``: none written)."""
        d = json.loads(json.dumps(self._result))
        d["files"] = []
        return d

    def write(self, dir: PathLike, formats: Sequence[str] = ("all",)) -> List[str]:
        """Writes the parameter files of ``formats`` (kalibr, openvins, vins, orbslam3, px4,
        ardupilot, state-space, or all) and the plots into ``dir``, as ``imu-ar characterise
        --out DIR --format ...`` (the recording is read again); returns the files written."""
        argv = [*self._argv, "--out", _path(dir), "--format", ",".join(_names("formats", formats)),
                "--json"]
        out, _ = _native.characterise(_cli(argv))
        return list(json.loads(out)["files"])

    def __repr__(self) -> str:
        return f"Characterisation(n={self.n}, rate={self.rate}, axes={list(self.axes)})"


def characterise(
    path: Union[PathLike, Sequence[PathLike]],
    columns: Optional[Sequence[str]] = None,
    *,
    rate: Optional[float] = None,
    topic: Optional[str] = None,
    frame_id: Optional[str] = None,
    instance: Optional[int] = None,
    time_column: Optional[str] = None,
    drop_backward: bool = False,
    gyro_unit: Optional[str] = None,
    accel_unit: Optional[str] = None,
    gm_states: int = 3,
    oscillators: bool = False,
    ramp: bool = False,
    curve_fit: bool = False,
    filter_rate: Optional[float] = None,
    horizon: Optional[float] = None,
    loop_rate: Optional[float] = None,
    sysid: Optional[int] = None,
    imu_integ_rate: Optional[float] = None,
) -> Characterisation:
    """All six axes of a recording in one streaming pass, as ``imu-ar characterise``: per axis
    the noise model (with its filter form at ``filter_rate``: ``axes["gx"].kalman()``);
    ``.write(dir, formats=[...])`` writes the parameter files (``loop_rate``: the autopilot's
    loop rate, Hz, that sets EKF3's step in the ArduPilot file; ``sysid``: the vehicle's
    system id in the PX4 file; ``imu_integ_rate``: PX4's ``IMU_INTEG_RATE``, Hz, whose
    messages EKF2 steps a whole number of)."""
    argv = ["characterise", *_files(path)]
    if columns is not None:
        argv += ["--columns", ",".join(_names("columns", columns))]
    argv += _input_flags(topic, frame_id, instance, time_column, drop_backward)
    if rate is not None:
        argv += ["--rate", _num(rate)]
    if gyro_unit is not None:
        argv += ["--gyro-unit", gyro_unit]
    if accel_unit is not None:
        argv += ["--accel-unit", accel_unit]
    argv += ["--gm-states", str(_int("gm_states", gm_states))]
    for flag, on in (("--oscillators", oscillators), ("--ramp", ramp), ("--curve-fit", curve_fit)):
        if on:
            argv.append(flag)
    if filter_rate is not None:
        argv += ["--filter-rate", _num(filter_rate)]
    if horizon is not None:
        argv += ["--horizon", _num(horizon)]
    if loop_rate is not None:
        argv += ["--loop-rate", _num(loop_rate)]
    if sysid is not None:
        argv += ["--sysid", str(_int("sysid", sysid))]
    if imu_integ_rate is not None:
        argv += ["--imu-integ-rate", _num(imu_integ_rate)]
    return _characterised(argv)


# --- AR fits -------------------------------------------------------------------------------


class ArFit:
    """An AR(P) model ``x[n] = mean + sum a_k (x[n-k] - mean) + w[n]`` as ``imu-ar fit``
    reports it: ``a``, ``noise_variance``, ``mean``, ``reflection`` (or ``None``), ``order``,
    ``n``, ``method``; :meth:`to_dict` is the tool's JSON object."""

    def __init__(self, result: Dict[str, Any]) -> None:
        self._result = result
        self.method: str = result["method"]
        self.scalar: str = result["scalar"]
        self.order: int = result["order"]
        self.n: int = result["n"]
        self.mean: float = result["mean"]
        self.a: np.ndarray = np.array(result["a"], dtype=float)
        self.noise_variance: float = result["noise_variance"]
        k = result.get("reflection")
        self.reflection: Optional[np.ndarray] = None if k is None else np.array(k, dtype=float)
        self.gauss_markov: Optional[Dict[str, float]] = result.get("gauss_markov")

    def to_dict(self) -> Dict[str, Any]:
        """The model as ``imu-ar fit --json`` prints it."""
        return json.loads(json.dumps(self._result))

    def __eq__(self, other: object) -> bool:
        return isinstance(other, ArFit) and self._result == other._result

    def __repr__(self) -> str:
        return (f"ArFit(method={self.method!r}, order={self.order}, a={self.a.tolist()}, "
                f"noise_variance={self.noise_variance})")


_METHODS = {"ls": "ls", "ols": "ls", "yule-walker": "yule-walker", "yule_walker": "yule-walker",
            "yw": "yule-walker", "burg": "burg", "rls": "rls", "lattice": "lattice", "sftf": "sftf"}


def _method(method: str) -> str:
    try:
        return _METHODS[method.lower()]
    except (KeyError, AttributeError):
        raise ValueError(
            f"method {method!r}: ls, yule-walker, burg, rls, lattice or sftf"
        ) from None


def fit_ar(
    x: Any,
    order: int,
    method: str = "burg",
    *,
    rate: Optional[float] = None,
    demean: bool = True,
    decimate: int = 1,
    scalar: str = "f64",
    lam: Optional[float] = None,
    delta: Optional[float] = None,
) -> ArFit:
    """An AR(``order``) model of ``x`` as ``imu-ar fit``: ``method`` "ls" (conditional least
    squares on ``x`` less its mean, without a constant: the coefficients of statsmodels'
    ``AutoReg(x - x.mean(), lags=order, trend="n")``), "yule-walker" (biased autocovariance:
    statsmodels' ``yule_walker(x, order, method="mle")``, coefficients and variance), "burg"
    (the coefficients of statsmodels' ``burg(x, order)``; the noise variance is the Burg
    recursion's, ``x.var() * prod(1 - reflection**2)``, where statsmodels gives its own
    residual estimate), or a recursive one ("rls", "lattice", "sftf": the model after the
    last sample, in ``scalar`` f64, f32 or fixed). With ``demean=False`` nothing is
    subtracted. ``x`` may also be a path, with a ``(path, column)`` tuple."""
    argv = ["fit"]
    if isinstance(x, tuple) and len(x) == 2 and _is_path(x[0]):
        argv += [_path(x[0]), "--column", str(x[1])]
        samples = None
    else:
        samples = _samples(x)
        argv += [_ARRAY, "--column", "x"]
    argv += ["--method", _method(method), "--order", str(_int("order", order, 1)), "--scalar",
             str(scalar), "--decimate", str(_int("decimate", decimate, 1))]
    if rate is not None:
        argv += ["--rate", _num(rate)]
    if not demean:
        argv.append("--no-demean")
    if lam is not None:
        argv += ["--lambda", _num(lam)]
    if delta is not None:
        argv += ["--delta", _num(delta)]
    return ArFit(json.loads(_native.fit(_cli([*argv, "--json"]), samples)))


class OrderCriteria(NamedTuple):
    """The order criteria of orders ``0..max_order`` (``imu-ar order``): arrays ``aic``,
    ``aicc``, ``bic``, ``fpe`` (NaN where not defined) and the order each selects (``None``
    where none)."""

    aic: np.ndarray
    aicc: np.ndarray
    bic: np.ndarray
    fpe: np.ndarray
    selected: Dict[str, Optional[int]]
    n: int


def order_criteria(x: Any, max_order: int, method: str = "burg", *, demean: bool = True) -> OrderCriteria:
    """AIC, AICc, BIC and FPE of the AR fits of orders 0 to ``max_order`` by ``method`` (ls,
    yule-walker or burg), and the order each selects, as ``imu-ar order``."""
    samples = _samples(x)
    argv = ["order", _ARRAY, "--column", "x", "--max-order", str(_int("max_order", max_order)),
            "--method", _method(method)]
    if not demean:
        argv.append("--no-demean")
    r = json.loads(_native.order(_cli([*argv, "--json"]), samples))

    def arr(v: List[Optional[float]]) -> np.ndarray:
        return np.array([math.nan if c is None else c for c in v], dtype=float)

    c = r["criteria"]
    return OrderCriteria(arr(c["aic"]), arr(c["aicc"]), arr(c["bic"]), arr(c["fpe"]),
                         dict(r["selected"]), r["n"])


# --- the device's estimators ---------------------------------------------------------------


class _Recursive:
    """A recursive estimator of the library, run sample by sample on what ``update`` is given.

    ``lam`` is the forgetting factor; ``delta`` the initial regularisation [default: the tool's,
    0.1 x the variance of the finite ones among the first 1000 samples of the first update, 1
    when that is 0]; ``rate`` gives the model its time scale; ``demean`` removes the running
    mean; ``offset`` is subtracted in f64 before the samples reach the estimator [default: the tool's: 0 in f64, the first update's mean
    (:func:`centre`) in f32 and fixed point]. Replayed over a record in one ``update``, the
    defaults are the tool's and :meth:`model` is ``imu-ar fit --method ... --json``'s object.
    """

    _method = ""
    _scalar_default = "f64"

    def __init__(
        self,
        order: int,
        lam: float = 0.999,
        delta: Optional[float] = None,
        *,
        rate: Optional[float] = None,
        scalar: Optional[str] = None,
        demean: bool = True,
        offset: Optional[float] = None,
        scale: Optional[float] = None,
    ) -> None:
        self._est = _native.Estimator(
            self._method, scalar or self._scalar_default, _int("order", order, 1), float(lam),
            None if delta is None else float(delta), None if rate is None else float(rate),
            bool(demean), None if offset is None else float(offset),
            None if scale is None else float(scale),
        )

    def update(self, x: Any, trace: bool = False) -> Any:
        """Takes the samples ``x``; returns each one's a-priori prediction error
        ``x_n - xhat_n``, or NaN for a sample the estimator did not take (NaN or infinite, at
        the fixed-point format's rail, rejected by a gate: counted in the model's
        ``non_finite``, ``saturated``, ``outliers``) and for one on which it restarted (its
        state broke down or, in fixed point, saturated: counted in ``restarts``; the model
        held is the one from before). Calls from several threads take turns, each ``x`` in one
        piece. With ``trace`` (the lattices), returns
        ``(errors, internals)``: per sample ``e, f_1..f_P, kf_1..kf_P, kb_1..kb_P, F_0..F_P``
        (float64 for a float lattice; for the fixed-point lattice the numbers' bit patterns
        as int64: I5F27, I3F29 and I24F40), zeros for a rejected sample."""
        errors, internals = self._est.update(_samples(x), bool(trace))
        return (errors, internals) if trace else errors

    def model(self) -> ArFit:
        """The model after the last sample, as ``imu-ar fit --method ... --json`` reports it."""
        return ArFit(json.loads(self._est.model_json()))

    @property
    def n(self) -> int:
        """Samples taken."""
        return self._est.n

    def __copy__(self) -> "_Recursive":
        """A copy, state and all: the copy and the original go on apart."""
        other = object.__new__(type(self))
        other._est = self._est.copy()
        return other

    def __deepcopy__(self, memo: Dict[int, Any]) -> "_Recursive":
        return self.__copy__()


class Rls(_Recursive):
    """Conventional RLS (Bierman U-D), ``O(P^2)`` per sample. See :class:`_Recursive`."""

    _method = "rls"


class Lattice(_Recursive):
    """The a-priori least-squares lattice with error feedback (EF-LSL), ``O(P)`` per sample, in
    f64 or f32 (``scalar``). See :class:`_Recursive`."""

    _method = "lattice"


class Sftf(_Recursive):
    """The stabilised fast transversal filter with its divergence monitor, ``O(P)`` per
    sample. See :class:`_Recursive`."""

    _method = "sftf"


class FixedLattice(_Recursive):
    """The fixed-point lattice (32-bit state, the Cortex-M0+ path); ``scale`` is internal units
    per sensor unit [default: the tool's, 8 / max |x - offset| of the first update]. See
    :class:`_Recursive`."""

    _method = "lattice"
    _scalar_default = "fixed"


def parity_input() -> np.ndarray:
    """The input of the parity run (``imu-ar parity``, ``cargo qemu parity``): 20,000 float32
    samples of the seeded AR(2), every 997th one NaN."""
    return _native.parity_input()


def parity_checksums() -> Tuple[int, int, int]:
    """The checksums ``imu-ar parity`` prints: ``(f32, fixed, noise)``."""
    return _native.parity()


def centre(x: Any) -> float:
    """The offset ``imu-ar fit`` removes in f64 before an f32 or fixed-point fit: the mean of
    the samples f32 can hold."""
    return _native.centre(_samples(x))
