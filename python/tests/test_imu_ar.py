"""The Python package against allantools, statsmodels and the imu-ar tool itself."""

import json
import math
import struct
import subprocess
import sys
import threading
import time

import numpy as np
import pytest

import imu_ar


# --- Allan deviation against allantools ----------------------------------------------------

allantools = pytest.importorskip("allantools")


@pytest.mark.parametrize("taus", ["octave", "decade", "all", [0.01, 0.05, 0.3, 2.0, 10.0]])
def test_adev_is_allantools_oadev(white_walk, taus):
    x = white_walk[:20_000] if taus == "all" else white_walk
    ours = imu_ar.adev(x, rate=100.0, taus=taus)
    theirs = allantools.oadev(x, rate=100.0, data_type="freq", taus=taus)
    for a, b in zip(ours, theirs):
        assert a.shape == np.asarray(b).shape
    np.testing.assert_allclose(ours.taus, theirs[0], rtol=1e-15)
    np.testing.assert_allclose(ours.devs, theirs[1], rtol=1e-12, atol=0)
    np.testing.assert_allclose(ours.errs, theirs[2], rtol=1e-12, atol=0)
    np.testing.assert_array_equal(ours.ns, theirs[3])
    assert np.all(ours.edf > 0)
    m = np.round(ours.taus * 100.0)
    np.testing.assert_allclose(ours.ns + 2 * m - 1, len(x))


def test_adev_edf_of_white_noise_at_m_1():
    n = 10_000
    r = imu_ar.adev(np.random.default_rng(0).normal(size=n), rate=1.0)
    # SP 1065 eq. 42 at m = 1: (3(N-1)/2 - 2(N-2)/N) 4/9.
    assert r.edf[0] == pytest.approx((1.5 * (n - 1) - 2 * (n - 2) / n) * 4 / 9)


def test_adev_of_a_real_record(adis):
    x = imu_ar.read(adis, columns=["gx"]).x
    ours = imu_ar.adev(x, rate=100.0)
    theirs = allantools.oadev(x, rate=100.0, data_type="freq", taus="octave")
    np.testing.assert_allclose(ours.devs, theirs[1], rtol=1e-12, atol=0)


def test_adev_is_the_tool_s(small_csv, tool):
    path, x = small_csv
    out = tool.json("adev", path, "--column", "gx", "--rate", "100")
    ours = imu_ar.adev(x, rate=100.0)
    # The tool goes on while 2m <= n; allantools (and adev here) stop at two differences.
    k = len(ours.devs)
    np.testing.assert_allclose(ours.avar, out["avar"][:k], rtol=1e-13)


# --- AR fits against statsmodels -----------------------------------------------------------


@pytest.fixture(scope="module")
def ar2():
    rng = np.random.default_rng(7)
    w = rng.normal(size=20_000)
    x = np.zeros_like(w)
    for i in range(2, len(x)):
        x[i] = 1.2 * x[i - 1] - 0.5 * x[i - 2] + w[i]
    return x + 3.0


def test_fit_ar_yule_walker_and_burg_are_statsmodels(ar2):
    lm = pytest.importorskip("statsmodels.regression.linear_model")
    for order in (1, 2, 5):
        rho, sigma = lm.yule_walker(ar2, order=order, method="mle", demean=True)
        f = imu_ar.fit_ar(ar2, order, method="yule-walker")
        np.testing.assert_allclose(f.a, rho, rtol=1e-9, atol=1e-12)
        np.testing.assert_allclose(f.noise_variance, sigma**2, rtol=1e-9)
        rho, _ = lm.burg(ar2, order=order, demean=True)
        f = imu_ar.fit_ar(ar2, order, method="burg")
        np.testing.assert_allclose(f.a, rho, rtol=1e-9, atol=1e-12)
        # statsmodels' Burg variance is its own residual estimate; the tool's is the Burg
        # recursion's, the sample variance times prod(1 - k_m^2).
        v = ar2.var() * np.prod(1 - f.reflection**2)
        np.testing.assert_allclose(f.noise_variance, v, rtol=1e-9)


def test_fit_ar_least_squares_is_autoreg(ar2):
    ar_model = pytest.importorskip("statsmodels.tsa.ar_model")
    for order in (1, 3):
        # Conditional least squares on the demeaned series, no constant.
        res = ar_model.AutoReg(ar2 - ar2.mean(), lags=order, trend="n").fit()
        f = imu_ar.fit_ar(ar2, order, method="ls")
        np.testing.assert_allclose(f.a, res.params, rtol=1e-9, atol=1e-12)


def test_fit_ar_is_the_tool_s(small_csv, tool):
    path, x = small_csv
    for method in ("ls", "yule-walker", "burg", "rls", "lattice", "sftf"):
        out = tool.json("fit", path, "--column", "gx", "--method", method, "--order", "3",
                        "--rate", "100")
        assert imu_ar.fit_ar(x, 3, method=method, rate=100.0).to_dict() == out, method
    out = tool.json("order", path, "--column", "gx", "--max-order", "6", "--method", "burg")
    c = imu_ar.order_criteria(x, 6, "burg")
    assert c.selected == out["selected"]
    np.testing.assert_array_equal(c.bic, np.array(out["criteria"]["bic"], dtype=float))


# --- the noise model against the tool ------------------------------------------------------


def _without_timing(d):
    """The tool's object without what the file's timestamps add (an array has none)."""
    return {k: v for k, v in d.items() if k != "timing"}


def test_noise_to_dict_is_the_tool_s_json_on_a_generated_record(small_csv, tool):
    path, x = small_csv
    out = tool.json("noise", path, "--column", "gx", "--rate", "100")
    model = imu_ar.noise(x, rate=100.0)
    assert model.to_dict() == _without_timing(out)
    assert imu_ar.noise(path, rate=100.0, column="gx").to_dict() == out
    assert model.white_noise == out["white_noise"]


def test_noise_to_dict_is_the_tool_s_json_on_a_real_record(adis, tool):
    out = tool.json("noise", adis, "--column", "gx", "--rate", "100")
    x = imu_ar.read(adis, columns=["gx"]).x
    assert imu_ar.noise(x, rate=100.0).to_dict() == _without_timing(out)
    assert imu_ar.noise(adis, rate=100.0, column="gx").to_dict() == out
    # From the file, with the rate from its timestamps (the timing report included).
    out = tool.json("noise", adis, "--column", "gy", "--gm-states", "2", "--ar-order", "0")
    model = imu_ar.noise(adis, column="gy", gm_states=2, ar_order=0)
    assert model.to_dict() == out
    assert model.timing["rate_hz"] == pytest.approx(100.0, rel=1e-3)


def test_noise_model_attributes_and_kalman(small_csv, tool):
    path, x = small_csv
    model = imu_ar.noise(x, rate=100.0, gm_states=2)
    d = model.to_dict()
    assert model.random_walk == d["random_walk"]
    assert model.bias_instability == d["bias_instability"]["value"]
    if d["intervals"]:
        lo, hi = model.white_noise_interval
        assert lo <= model.white_noise <= hi
    k = model.kalman()
    assert k.phi.shape == k.q.shape == k.p0.shape
    np.testing.assert_array_equal(k.phi, np.array(d["phi"]).reshape(k.phi.shape))
    assert k.measurement_variance == pytest.approx(model.white_noise**2 * 100.0, rel=1e-9)
    k50 = model.kalman(50.0)
    out = tool.json("noise", path, "--column", "gx", "--rate", "100", "--gm-states", "2",
                    "--filter-rate", "50")
    assert imu_ar.noise(x, rate=100.0, gm_states=2, filter_rate=50.0).to_dict() == (
        _without_timing(out))
    np.testing.assert_array_equal(k50.q, np.array(out["q"]).reshape(k50.q.shape))
    assert len(model.allan["tau_s"]) == len(d["allan"])


def test_plot_with_matplotlib(small_csv, tmp_path):
    matplotlib = pytest.importorskip("matplotlib")
    matplotlib.use("Agg")
    _, x = small_csv
    ax = imu_ar.noise(x, rate=100.0).plot()
    ax.figure.savefig(tmp_path / "adev.png")
    assert (tmp_path / "adev.png").stat().st_size > 1000


def test_the_package_imports_without_matplotlib():
    code = (
        "import sys; sys.modules['matplotlib'] = None; sys.modules['matplotlib.pyplot'] = None\n"
        "import imu_ar, numpy as np\n"
        "m = imu_ar.noise(np.random.default_rng(1).normal(size=5000), rate=10.0)\n"
        "try:\n    m.plot()\nexcept ImportError as e:\n    print('no matplotlib:', e)\n"
    )
    r = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True)
    assert r.returncode == 0, r.stderr
    assert "no matplotlib" in r.stdout


# --- readers and characterise --------------------------------------------------------------


def test_read_gives_samples_and_the_timing_report(small_csv, adis):
    path, x = small_csv
    rec = imu_ar.read(path)
    assert rec.columns == ["gx"]
    np.testing.assert_array_equal(rec.x, x)
    assert rec.rate == pytest.approx(100.0, rel=1e-6)
    assert rec.timing["gaps"] == 0
    np.testing.assert_allclose(rec.t, np.arange(len(x)) / 100.0, atol=1e-9)
    assert rec.t_ns.dtype == np.int64
    six = imu_ar.read(adis)
    assert six.x.shape == (500_000, 6) and six.columns == ["gx", "gy", "gz", "ax", "ay", "az"]


def test_characterise_writes_the_tool_s_files(adis, tmp_path, tool):
    c = imu_ar.characterise(adis, columns=["gx", "gy", "gz", "ax", "ay", "az"],
                            gyro_unit="deg/s", accel_unit="g")
    assert set(c.axes) == {"gx", "gy", "gz", "ax", "ay", "az"}
    out = tool.json("characterise", adis, "--columns", "gx,gy,gz,ax,ay,az", "--gyro-unit",
                    "deg/s", "--accel-unit", "g", "--out", tmp_path / "tool", "--format", "kalibr")
    for a in out["axes"]:
        assert c.axes[a["axis"]].to_dict() == a["model"]
    files = c.write(tmp_path / "py", formats=["kalibr", "px4"])
    assert any(f.endswith(".yaml") for f in files)
    assert (tmp_path / "py").is_dir()


# --- the device's estimators ---------------------------------------------------------------


@pytest.mark.parametrize(
    "cls,method,scalar",
    [
        (imu_ar.Rls, "rls", "f64"),
        (imu_ar.Rls, "rls", "f32"),
        (imu_ar.Lattice, "lattice", "f64"),
        (imu_ar.Lattice, "lattice", "f32"),
        (imu_ar.Sftf, "sftf", "f64"),
        (imu_ar.Sftf, "sftf", "f32"),
        (imu_ar.FixedLattice, "lattice", "fixed"),
    ],
)
def test_estimators_are_the_tool_s_fit(adis, tool, cls, method, scalar):
    x = imu_ar.read(adis, columns=["gy"]).x
    out = tool.json("fit", adis, "--column", "gy", "--method", method, "--order", "4",
                    "--scalar", scalar, "--rate", "100")
    est = cls(4, scalar=scalar, rate=100.0)
    e = est.update(x)
    assert e.shape == x.shape
    assert est.model().to_dict() == out
    # In chunks, with the tool's defaults given: the same model.
    est = cls(4, scalar=scalar, rate=100.0, delta=out["delta"],
              offset=None if scalar == "f64" else imu_ar.centre(x),
              scale=out.get("scale"))
    for chunk in np.array_split(x, 7):
        est.update(chunk)
    assert est.model().to_dict() == out


def _fnv(h, data):
    for b in data:
        h = ((h ^ b) * 0x100000001B3) & 0xFFFFFFFFFFFFFFFF
    return h


FNV = 0xCBF29CE484222325


def test_parity_checksums_are_the_board_s(tool):
    """The f32 and fixed-point lattices driven from Python over the parity sequence hash to
    the checksums `imu-ar parity` prints (and `cargo qemu parity` on the emulated board)."""
    line = tool("parity").split()
    want = {"f32": int(line[2], 16), "fixed": int(line[4], 16)}
    x = imu_ar.parity_input().astype(np.float64)
    assert len(x) == 20_000 and np.isnan(x).sum() == 20
    p = 4
    f32 = imu_ar.Lattice(p, lam=0.999, delta=0.1, rate=100.0, scalar="f32", offset=0.0)
    errors, rows = f32.update(x, trace=True)
    ok = ~np.isnan(errors)
    h = _fnv(FNV, rows[ok].astype("<f4").tobytes())
    m = f32.model()
    h = _fnv(h, np.append(m.a, m.noise_variance).astype("<f4").tobytes())
    assert h == want["f32"]

    fixed = imu_ar.FixedLattice(p, lam=0.999, delta=0.1, rate=100.0, offset=0.0, scale=2.0)
    errors, rows = fixed.update(x, trace=True)
    ok = ~np.isnan(errors)
    h = FNV
    for r in rows[ok]:
        h = _fnv(h, r[: 3 * p + 1].astype("<i4").tobytes())
        h = _fnv(h, r[3 * p + 1 :].astype("<i8").tobytes())
    m = fixed.model()
    h = _fnv(h, np.append(m.a, m.noise_variance).astype("<f4").tobytes())
    assert h == want["fixed"]
    assert imu_ar.parity_checksums()[:2] == (want["f32"], want["fixed"])


# --- errors --------------------------------------------------------------------------------


@pytest.mark.parametrize(
    "call,error",
    [
        (lambda: imu_ar.adev([], 100.0), ValueError),
        (lambda: imu_ar.adev([math.nan] * 100, 100.0), ValueError),
        (lambda: imu_ar.adev(np.array(["a", "b"]), 100.0), TypeError),
        (lambda: imu_ar.adev(np.ones(100), -1.0), ValueError),
        (lambda: imu_ar.noise(np.array([], dtype=float), 100.0), ValueError),
        (lambda: imu_ar.noise(np.full(1000, math.nan), 100.0), ValueError),
        (lambda: imu_ar.noise(np.ones((10, 10)), 100.0), ValueError),
        (lambda: imu_ar.noise(np.array([1 + 1j] * 100), 100.0), TypeError),
        (lambda: imu_ar.noise(np.random.default_rng(0).normal(size=1000), -5.0), ValueError),
        (lambda: imu_ar.noise(np.random.default_rng(0).normal(size=1000), 100.0, gm_states=99),
         ValueError),
        (lambda: imu_ar.fit_ar(np.random.default_rng(0).normal(size=1000), 33), ValueError),
        (lambda: imu_ar.fit_ar(np.random.default_rng(0).normal(size=1000), 2, method="x"),
         ValueError),
        (lambda: imu_ar.fit_ar(np.full(100, math.nan), 2), ValueError),
        (lambda: imu_ar.read("/nonexistent/record.csv", columns=["gx"]), FileNotFoundError),
        (lambda: imu_ar.Lattice(40), ValueError),
        (lambda: imu_ar.Lattice(4, lam=1.5), ValueError),
        (lambda: imu_ar.Rls(4, scalar="fixed"), ValueError),
        (lambda: imu_ar.Lattice(4).model(), ValueError),
    ],
)
def test_bad_input_raises(call, error):
    with pytest.raises(error):
        call()


def test_unknown_column_and_missing_file_name_them(small_csv, adis):
    path, _ = small_csv
    with pytest.raises(ValueError, match="nope"):
        imu_ar.read(path, columns=["nope"])
    with pytest.raises(ValueError, match="nope"):
        imu_ar.noise(path, column="nope")
    with pytest.raises(FileNotFoundError, match="missing.csv"):
        imu_ar.noise("missing.csv", rate=100.0, column="gx")


# --- the GIL -------------------------------------------------------------------------------


def test_long_calls_release_the_gil():
    x = np.random.default_rng(3).normal(size=4_000_000)
    ticks = []
    done = threading.Event()

    def count():
        while not done.is_set():
            ticks.append(time.perf_counter())
            time.sleep(0.001)

    for call in (lambda: imu_ar.noise(x, rate=100.0, ar_order=0),
                 lambda: imu_ar.Lattice(8).update(x)):
        ticks.clear()
        done.clear()
        t = threading.Thread(target=count)
        t.start()
        start = time.perf_counter()
        call()
        end = time.perf_counter()
        done.set()
        t.join()
        during = [s for s in ticks if start < s < end]
        # A thread holding the GIL for the whole call would let the counter tick once at most.
        assert len(during) >= 5, (len(during), end - start)


def test_a_model_without_states_has_empty_matrices():
    """White noise only: no state, so 0 x 0 matrices and the white measurement variance."""
    x = np.random.default_rng(0).normal(size=5000)
    model = imu_ar.noise(x, rate=100.0)
    assert model.to_dict()["phi"] == []
    k = model.kalman()
    assert k.phi.shape == k.q.shape == k.p0.shape == (0, 0)
    assert np.isfinite(k.measurement_variance) and k.measurement_variance > 0.0
