"""The Python package against allantools, statsmodels and the imu-ar tool itself."""

import json
import math
import os
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


def _edf(n_phase, m):
    """SP 1065 eq. 42: the overlapping Allan variance's edf for white FM, N phase points."""
    big = n_phase
    return (3 * (big - 1) / (2 * m) - 2 * (big - 2) / big) * 4 * m * m / (4 * m * m + 5)


def test_adev_edf_of_white_noise():
    n = 10_000
    r = imu_ar.adev(np.random.default_rng(0).normal(size=n), rate=4.0)
    # n rate samples are n + 1 phase points.
    np.testing.assert_allclose(r.edf, [_edf(n + 1, m) for m in 2.0 ** np.arange(len(r.taus))],
                               rtol=1e-14)
    np.testing.assert_array_equal(r.m, 2.0 ** np.arange(len(r.taus)))
    assert r.rate == 4.0


def test_adev_edf_at_a_single_tau_is_that_tau_s():
    n = 1000
    r = imu_ar.adev(np.random.default_rng(0).normal(size=n), rate=10.0, taus=[1.6])
    assert r.m.tolist() == [16.0]
    assert r.edf[0] == pytest.approx(_edf(n + 1, 16), rel=1e-14)
    # Still the four arrays allantools users unpack.
    taus, devs, errs, ns = r
    assert ns[0] == n + 1 - 2 * 16


def test_adev_refuses_an_overflowing_variance():
    x = np.random.default_rng(0).normal(size=1000) * 1e300
    with pytest.raises(ValueError, match="overflows"):
        imu_ar.adev(x, rate=1.0)


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


def test_characterise_axes_have_their_filter_form(adis, tool, tmp_path):
    c = imu_ar.characterise(adis, columns=["gx", "gy", "gz", "ax", "ay", "az"],
                            gyro_unit="deg/s", accel_unit="g", gm_states=1)
    gx = c.axes["gx"]
    k = gx.kalman()
    assert k.filter_rate == c.rate
    # The white measurement noise N^2 x rate, and a state per term of the model.
    assert k.measurement_variance == pytest.approx(gx.white_noise**2 * c.rate, rel=1e-9)
    assert len(k.states) == k.phi.shape[0] == len(gx.to_dict()["phi"])
    k50 = gx.kalman(50.0)
    out = tool.json("characterise", adis, "--columns", "gx,gy,gz,ax,ay,az", "--gyro-unit",
                    "deg/s", "--accel-unit", "g", "--gm-states", "1", "--filter-rate", "50",
                    "--out", tmp_path / "tool", "--format", "state-space")
    want = out["axes"][0]["model"]
    assert k50.filter_rate == 50.0
    np.testing.assert_array_equal(k50.q, np.array(want["q"]).reshape(k50.q.shape))
    np.testing.assert_array_equal(k50.phi, np.array(want["phi"]).reshape(k50.phi.shape))


def test_a_nan_in_the_first_samples_leaves_the_default_delta_finite():
    x = np.random.default_rng(5).normal(size=5000)
    x[[3, 10]] = [math.nan, math.inf]
    for cls in (imu_ar.Rls, imu_ar.Lattice, imu_ar.Sftf, imu_ar.FixedLattice):
        est = cls(2, rate=100.0)
        e = est.update(x)
        assert np.isnan(e[[3, 10]]).all() and np.isfinite(np.delete(e, [3, 10])).all()
        m = est.model().to_dict()
        assert m["non_finite"] == 2
        # 0.1 x the variance of the finite ones among the first 1000 samples.
        head = x[:1000][np.isfinite(x[:1000])]
        assert m["delta"] == pytest.approx(0.1 * head.var(), rel=1e-12)
        assert np.all(np.abs(m["a"]) < 0.2), m["a"]


def test_every_nan_error_is_counted(tmp_path):
    """A NaN error is a sample not taken or a restart, and the model counts each."""
    x = np.random.default_rng(1).normal(size=20_000)
    x[[100, 5000]] = math.nan
    for order in (31, 32):
        est = imu_ar.FixedLattice(order)
        e = est.update(x)
        m = est.model().to_dict()
        counted = m["restarts"] + m["non_finite"] + m["saturated"] + m["outliers"]
        assert m["restarts"] >= 1 and m["non_finite"] == 2
        assert np.isnan(e).sum() == counted, (order, m)


def test_one_estimator_from_two_threads_takes_turns():
    x = np.random.default_rng(2).normal(size=400_000)
    est = imu_ar.Lattice(4)
    errors = []

    def run(chunk):
        errors.append(est.update(chunk))

    threads = [threading.Thread(target=run, args=(c,)) for c in np.array_split(x, 4)]
    for t in threads:
        t.start()
    while any(t.is_alive() for t in threads):
        assert est.n in (0, 100_000, 200_000, 300_000, 400_000)
    for t in threads:
        t.join()
    assert len(errors) == 4 and est.n == len(x)
    assert est.model().n == len(x)


def test_paths_that_are_not_utf8_or_bytes(small_csv, tmp_path):
    path, x = small_csv
    odd = tmp_path / "caf\udce9.csv"  # the file system's bytes b"caf\xe9.csv"
    try:
        odd.write_bytes(path.read_bytes())
    except (UnicodeEncodeError, OSError):
        pytest.skip("this file system takes no such name")
    for p in (odd, str(odd), bytes(odd), [bytes(odd)]):
        rec = imu_ar.read(p)
        np.testing.assert_array_equal(rec.x, x)
    assert imu_ar.noise(bytes(odd), column="gx").n == len(x)


def test_a_binary_file_read_as_csv_raises_the_tool_s_error(tmp_path):
    path = tmp_path / "random.csv"
    path.write_bytes(bytes(range(256)) * 20)
    with pytest.raises(ValueError, match="random.csv"):
        imu_ar.read(path)


def test_a_string_is_one_name_not_its_characters(small_csv, adis, tmp_path):
    path, x = small_csv
    np.testing.assert_array_equal(imu_ar.read(path, columns="gx").x, x)
    c = imu_ar.characterise(adis, columns="gx,gy,gz,ax,ay,az", gyro_unit="deg/s",
                            accel_unit="g", gm_states=0)
    files = c.write(tmp_path / "out", formats="kalibr")
    # Kalibr's imu.yaml and the plots (a string split into characters named no format).
    assert sorted(os.path.basename(f) for f in files) == ["accel.png", "gyro.png", "imu.yaml"]


@pytest.mark.parametrize(
    "call,error,match",
    [
        (lambda: imu_ar.Rls(-1), ValueError, "order -1"),
        (lambda: imu_ar.Rls(2.7), TypeError, "integer"),
        (lambda: imu_ar.read([]), ValueError, "no files"),
        (lambda: imu_ar.fit_ar(np.ones(100), 2, None), ValueError, "method"),
        (lambda: imu_ar.fit_ar(np.ones(100), 2.5), TypeError, "integer"),
        (lambda: imu_ar.noise(np.ones(100), 10.0, gm_states=-1), ValueError, "gm_states -1"),
        (lambda: imu_ar.noise(np.ones(100), 10.0, decimate=0), ValueError, "decimate 0"),
        (lambda: imu_ar.order_criteria(np.ones(100), 3.0), TypeError, "integer"),
        (lambda: imu_ar.Lattice(2, delta=1e300), ValueError, "delta 1e300"),
        (lambda: imu_ar.Lattice(2, lam=1e300), ValueError, "1e300"),
    ],
)
def test_bad_options_raise_clear_errors(call, error, match):
    with pytest.raises(error, match=match) as e:
        call()
    assert len(str(e.value)) < 300, str(e.value)


def test_the_readme_example_prints_what_the_readme_says(adis, tmp_path, capsys):
    matplotlib = pytest.importorskip("matplotlib")
    matplotlib.use("Agg")
    from conftest import DATA, REPO

    text = (REPO / "README.md").read_text()
    section = text[text.index("## From Python"):]
    code = section[section.index("```python") + len("```python"):]
    code = code[: code.index("```")]
    printed = section[section.index("It prints `") + len("It prints `"):]
    printed = printed[: printed.index("`")]
    code = code.replace('"../shared/data/imu/', '"' + str(DATA) + "/")
    code = code.replace('"docs/plots/python-adis-gx.png"', repr(str(tmp_path / "gx.png")))
    exec(compile(code, "README.md", "exec"), {})
    assert capsys.readouterr().out.strip() == printed
    assert (tmp_path / "gx.png").stat().st_size > 1000


# --- the second red-team pass --------------------------------------------------------------


def test_read_with_a_rate_takes_stamps_the_tool_refuses(tmp_path):
    path = tmp_path / "unitless.csv"
    path.write_text("time,gx\n0,1\n0.01,2\n0.02,3\n0.03,5\n")
    with pytest.raises(ValueError, match="rate"):
        imu_ar.read(path)
    rec = imu_ar.read(path, rate=100.0)
    np.testing.assert_array_equal(rec.x, [1.0, 2.0, 3.0, 5.0])
    assert rec.rate == 100.0 and rec.timing is None


def test_kalman_carries_the_measurement_row(adis, tool, tmp_path):
    c = imu_ar.characterise(adis, columns=["gx", "gy", "gz", "ax", "ay", "az"],
                            gyro_unit="deg/s", accel_unit="g")
    tool("characterise", adis, "--columns", "gx,gy,gz,ax,ay,az", "--gyro-unit", "deg/s",
         "--accel-unit", "g", "--out", tmp_path, "--format", "state-space")
    space = json.loads((tmp_path / "state_space.json").read_text())
    # The file names the axes "gyro x" .. "accel z", in the order gx .. az.
    assert len(space["axes"]) == 6
    for model, a in zip(c.axes.values(), space["axes"]):
        k = model.kalman()
        assert k.states == a["states"]
        np.testing.assert_array_equal(k.h, a["h"])
    # Quantisation: its two states enter the sample as q_k/Dt - q_(k-1)/Dt.
    rng = np.random.default_rng(3)
    n = 400_000
    x = rng.normal(size=n) * 0.1 + 1e-5 * np.arange(n) / 100
    k = imu_ar.noise(x, rate=100.0).kalman()
    q = [i for i, s in enumerate(k.states) if s.startswith("quantization")]
    assert len(q) == 2, k.states
    assert k.h[q].tolist() == [1.0, -1.0]
    assert len(k.h) == len(k.states) == k.phi.shape[0]


def test_names_that_start_with_a_dash_are_names(tmp_path, monkeypatch):
    monkeypatch.chdir(tmp_path)
    x = np.random.default_rng(4).normal(size=3000)
    with open("-dash.csv", "w") as f:
        f.write("t_s,-x\n")
        for i, v in enumerate(x):
            f.write(f"{i / 100:.2f},{float(v)!r}\n")
    rec = imu_ar.read("-dash.csv", columns=["-x"])
    np.testing.assert_array_equal(rec.x, x)
    assert imu_ar.noise("-dash.csv", column="-x").n == len(x)
    # "-" is a file's name, not standard input.
    with pytest.raises(FileNotFoundError):
        imu_ar.read("-", columns=["gx"])
    with pytest.raises(ValueError, match="-5"):
        imu_ar.noise(x, -5.0)


def test_no_model_says_what_the_estimator_counted():
    x = np.random.default_rng(0).normal(size=50_000)
    e = imu_ar.Sftf(32, lam=1.0, scalar="f32")
    errors = e.update(x)
    # f32 at order 32 without forgetting: the recursion breaks down again and again.
    with pytest.raises(ValueError, match=f"restarts {np.isnan(errors).sum()}, non-finite 0"):
        e.model()


def test_noise_messages_name_the_cause():
    x = np.random.default_rng(0).normal(size=5000)
    x[77] = math.nan
    with pytest.raises(ValueError, match="sample 77 is NaN or infinite"):
        imu_ar.noise(x, rate=100.0)
    ramp = np.arange(5000.0) + 1e-3 * np.random.default_rng(1).normal(size=5000)
    with pytest.raises(ValueError, match="rate ramp"):
        imu_ar.noise(ramp, rate=100.0)
    assert imu_ar.noise(ramp, rate=100.0, ramp=True).rate_ramp > 0


def test_adev_replace_keeps_the_rate():
    a = imu_ar.adev(np.random.default_rng(0).normal(size=4000), rate=10.0)
    b = a._replace(devs=a.devs * 2)
    assert b.rate == 10.0 and isinstance(b, imu_ar.Adev)
    np.testing.assert_array_equal(b.edf, a.edf)
    np.testing.assert_array_equal(b.devs, 2 * a.devs)


@pytest.mark.parametrize(
    "call",
    [
        lambda x: imu_ar.noise(x, 100.0, filter_rate=1e300),
        lambda x: imu_ar.noise(x, 100.0, filter_rate=1e-300),
        lambda x: imu_ar.noise(x, 100.0).kalman(1e300),
    ],
)
def test_huge_numbers_in_messages_are_short(call):
    x = np.random.default_rng(0).normal(size=5000)
    with pytest.raises(ValueError) as e:
        call(x)
    assert len(str(e.value)) < 300, str(e.value)


def test_huge_characterise_options_in_messages_are_short(adis):
    for kw in ({"filter_rate": 1e300}, {"horizon": 1e-300}):
        with pytest.raises(ValueError) as e:
            imu_ar.characterise(adis, columns="gx,gy,gz,ax,ay,az", gyro_unit="deg/s",
                                accel_unit="g", **kw)
        assert len(str(e.value)) < 300, str(e.value)


def test_fixed_point_offsets_and_scales_are_checked():
    x = np.random.default_rng(0).normal(size=3000)
    with pytest.raises(ValueError, match="offset 1e300"):
        imu_ar.FixedLattice(2, offset=1e300)
    with pytest.raises(ValueError, match="offset 1e300"):
        imu_ar.Lattice(2, scalar="f32", offset=1e300)
    with pytest.raises(ValueError, match="default.*offset 1e22"):
        imu_ar.FixedLattice(2, offset=1e22).update(x)
    with pytest.raises(ValueError, match="scale"):
        imu_ar.Lattice(2, scale=2.0)
    # A spike moves the default offset (the mean) so far that every sample saturates: the
    # refusal of a model says so.
    z = x.copy()
    z[1500] = 1e6
    est = imu_ar.FixedLattice(2, delta=0.1, scale=2.0)
    est.update(z)
    with pytest.raises(ValueError, match="saturated 3000"):
        est.model()


def test_models_pickle_and_estimators_copy(small_csv):
    import copy
    import pickle

    _, x = small_csv
    model = imu_ar.noise(x, rate=100.0, gm_states=1)
    again = pickle.loads(pickle.dumps(model))
    assert again.to_dict() == model.to_dict()
    np.testing.assert_array_equal(again.kalman(50.0).q, model.kalman(50.0).q)
    a = imu_ar.adev(x, rate=100.0)
    b = pickle.loads(pickle.dumps(a))
    assert b.rate == 100.0 and np.array_equal(b.edf, a.edf)

    est = imu_ar.Lattice(3)
    est.update(x[:20_000])
    twin = copy.copy(est)
    deep = copy.deepcopy(est)
    e1 = est.update(x[20_000:])
    assert twin.n == deep.n == 20_000
    np.testing.assert_array_equal(twin.update(x[20_000:]), e1)
    assert twin.model() == est.model()


def test_characterise_writes_the_autopilots_steps(adis, tool, tmp_path):
    c = imu_ar.characterise(adis, columns="gx,gy,gz,ax,ay,az", gyro_unit="deg/s",
                            accel_unit="g", loop_rate=200.0, sysid=7, imu_integ_rate=250.0)
    c.write(tmp_path / "py", formats=["px4", "ardupilot"])
    tool("characterise", adis, "--columns", "gx,gy,gz,ax,ay,az", "--gyro-unit", "deg/s",
         "--accel-unit", "g", "--loop-rate", "200", "--sysid", "7", "--imu-integ-rate", "250",
         "--out", tmp_path / "tool", "--format", "px4,ardupilot")
    names = sorted(p.name for p in (tmp_path / "tool").iterdir() if p.suffix != ".png")
    assert names == sorted(p.name for p in (tmp_path / "py").iterdir() if p.suffix != ".png")
    for n in names:
        assert (tmp_path / "py" / n).read_bytes() == (tmp_path / "tool" / n).read_bytes(), n
    px4 = (tmp_path / "py" / "px4.params").read_text()
    assert "Vehicle 7" in px4 and "IMU_INTEG_RATE 250 Hz" in px4


# --- the third red-team pass ---------------------------------------------------------------


def test_a_refit_uses_the_samples_fitted_not_the_callers_buffer():
    x = np.random.default_rng(9).normal(size=50_000) + np.cumsum(
        np.random.default_rng(10).normal(0, 1e-3, 50_000))
    model = imu_ar.noise(x, rate=100.0, ar_order=0)
    want = imu_ar.noise(x.copy(), rate=100.0, ar_order=0, filter_rate=50.0).kalman()
    x *= 10.0
    np.testing.assert_array_equal(model.kalman(50.0).q, want.q)


def test_refits_and_writes_find_the_record_after_a_chdir(small_csv, tmp_path, monkeypatch):
    path, _ = small_csv
    monkeypatch.chdir(path.parent)
    model = imu_ar.noise(path.name, column="gx")
    want = imu_ar.noise(path.name, column="gx", filter_rate=50.0).kalman()
    elsewhere = tmp_path / "elsewhere"
    elsewhere.mkdir()
    monkeypatch.chdir(elsewhere)
    np.testing.assert_array_equal(model.kalman(50.0).q, want.q)


def test_read_with_a_rate_that_contradicts_the_stamps_raises(small_csv):
    path, _ = small_csv
    with pytest.raises(ValueError, match="timestamps give 100"):
        imu_ar.read(path, rate=200.0)
    rec = imu_ar.read(path, rate=100.2)
    assert rec.rate == 100.2 and rec.timing["rate_hz"] == pytest.approx(100.0, rel=1e-6)


def test_adev_make_and_equality_carry_the_rate():
    a = imu_ar.adev(np.random.default_rng(0).normal(size=4000), rate=100.0)
    with pytest.raises(TypeError, match="rate"):
        imu_ar.Adev._make(tuple(a))
    b = imu_ar.Adev._make([*a, 100.0])
    assert b == a and b.rate == 100.0
    assert imu_ar.Adev(*a, 50.0) != a


def test_a_value_equal_to_a_flag_survives_a_refit(adis, tmp_path):
    x = imu_ar.read(adis).x[:20_000]
    path = tmp_path / "odd.csv"
    with open(path, "w") as f:
        f.write("--filter-rate,gx,gy,gz,ax,ay,az\n")
        for i, row in enumerate(x):
            f.write(f"{i / 100:.2f}," + ",".join(repr(float(v)) for v in row) + "\n")
    kw = dict(time_column="--filter-rate", rate=100.0, gyro_unit="deg/s", accel_unit="g",
              gm_states=1)
    c = imu_ar.characterise(path, **kw)
    want = imu_ar.characterise(path, filter_rate=50.0, **kw)
    np.testing.assert_array_equal(c.axes["gx"].kalman(50.0).q, want.axes["gx"].kalman().q)


def test_a_bool_is_not_an_order():
    with pytest.raises(TypeError, match="integer"):
        imu_ar.Lattice(True)
