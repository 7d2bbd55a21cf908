//! The tool's commands on records and on arrays: the Python layer passes the command line it
//! would run (`noise <array> --column x --rate 100 ...`), which is parsed and checked by the
//! tool's own argument definitions, and the samples when they come from Python; the result is
//! the tool's JSON object, byte for byte what `imu-ar ... --json` prints.

use std::ffi::OsString;
use std::path::PathBuf;

use clap::{CommandFactory, Parser};
use imu_ar_cli::error::{Fail, clap_error};
use imu_ar_cli::input::csv::{header, position};
use imu_ar_cli::input::source::{Kind, is_time};
use imu_ar_cli::input::{Input, check_rate};
use imu_ar_cli::output::json_line;
use imu_ar_cli::{characterise as ch, fit as fi, noise as no, order as or, parity as pa};
use numpy::{IntoPyArray, PyArray1, PyReadonlyArray1};
use pyo3::prelude::*;

use crate::errors::{guarded, to_py_checked};

/// The commands that the Python package runs.
#[derive(Parser)]
#[command(name = "imu-ar")]
pub enum Command {
    /// `imu-ar fit`.
    Fit(fi::Args),
    /// `imu-ar noise`.
    Noise(no::Args),
    /// `imu-ar order`.
    Order(or::Args),
    /// `imu-ar characterise`.
    Characterise(ch::Args),
    /// Reads one column (`imu_ar.read`).
    Read(ReadArgs),
}

/// What `imu_ar.read` reads.
#[derive(clap::Args)]
pub struct ReadArgs {
    /// The column.
    #[command(flatten)]
    pub input: Input,
    /// The sample rate, Hz: the timestamps need not then pass the checks, but where they give
    /// a rate it must agree within 1 %.
    #[arg(long)]
    pub rate: Option<f64>,
}

/// `argv` (without the program's name) parsed as the tool parses it; its error is the tool's
/// one line.
pub fn parse(argv: &[OsString]) -> Result<Command, Fail> {
    let args: Vec<OsString> = std::iter::once(OsString::from("imu-ar"))
        .chain(argv.iter().cloned())
        .collect();
    Command::try_parse_from(&args).map_err(|e| Fail(clap_error(&e, &Command::command(), &args)))
}

/// Parses `argv`, then runs `f` on the command without the GIL; errors become exceptions.
fn run<T: Send>(
    py: Python<'_>,
    argv: &[OsString],
    f: impl FnOnce(Command) -> Result<T, Fail> + Send,
) -> PyResult<T> {
    py.detach(|| guarded(|| f(parse(argv)?)))
        .map_err(to_py_checked)
}

/// The contiguous samples of `x`, if given.
fn samples<'a>(x: &'a Option<PyReadonlyArray1<'_, f64>>) -> PyResult<Option<&'a [f64]>> {
    Ok(match x {
        Some(a) => Some(a.as_slice()?),
        None => None,
    })
}

/// A command other than the one asked for (never: the Python layer names it).
fn other() -> Fail {
    Fail("the command line names another command".into())
}

/// What `_native.noise` returns: the JSON object, the measurement variance, the filter's
/// states, the unit and the measurement row.
pub type Noise = (String, f64, Vec<String>, String, Vec<f64>);

/// `_native.noise(argv, x=None)`: `imu-ar noise` on the files of `argv`, or on `x`; the JSON
/// object, the measurement variance, the filter's states, the unit and the measurement row.
#[pyfunction]
#[pyo3(signature = (argv, x=None))]
pub fn noise(
    py: Python<'_>,
    argv: Vec<OsString>,
    x: Option<PyReadonlyArray1<'_, f64>>,
) -> PyResult<Noise> {
    let x = samples(&x)?;
    run(py, &argv, |c| {
        let Command::Noise(args) = c else {
            return Err(other());
        };
        let r = no::run_with(&args, x)?;
        Ok((
            json_line(&r)?,
            r.measurement_variance(),
            r.states().to_vec(),
            r.unit().to_string(),
            r.h().to_vec(),
        ))
    })
}

/// `_native.fit(argv, x=None)`: `imu-ar fit --json` on the files of `argv`, or on `x`.
#[pyfunction]
#[pyo3(signature = (argv, x=None))]
pub fn fit(
    py: Python<'_>,
    argv: Vec<OsString>,
    x: Option<PyReadonlyArray1<'_, f64>>,
) -> PyResult<String> {
    let x = samples(&x)?;
    run(py, &argv, |c| match c {
        Command::Fit(args) => json_line(&fi::run_with(&args, x)?),
        _ => Err(other()),
    })
}

/// `_native.order(argv, x=None)`: `imu-ar order --json` on the files of `argv`, or on `x`.
#[pyfunction]
#[pyo3(signature = (argv, x=None))]
pub fn order(
    py: Python<'_>,
    argv: Vec<OsString>,
    x: Option<PyReadonlyArray1<'_, f64>>,
) -> PyResult<String> {
    let x = samples(&x)?;
    run(py, &argv, |c| match c {
        Command::Order(args) => json_line(&or::run_with(&args, x)?),
        _ => Err(other()),
    })
}

/// Per axis of a characterisation: the filter's measurement variance, its states' names, its
/// rate and its measurement row.
pub type AxisFilter = (f64, Vec<String>, f64, Vec<f64>);

/// `_native.characterise(argv)`: `imu-ar characterise --json`, and per axis the measurement
/// variance, the states and the rate of its filter form.
#[pyfunction]
pub fn characterise(py: Python<'_>, argv: Vec<OsString>) -> PyResult<(String, Vec<AxisFilter>)> {
    run(py, &argv, |c| {
        let Command::Characterise(args) = c else {
            return Err(other());
        };
        let r = ch::run(&args)?;
        let axes = r
            .axes
            .iter()
            .map(|a| {
                let m = &a.model;
                (
                    m.measurement_variance(),
                    m.states().to_vec(),
                    m.filter_rate(),
                    m.h().to_vec(),
                )
            })
            .collect();
        Ok((json_line(&r)?, axes))
    })
}

/// A column read: the samples, their stamps, the timestamps' report as JSON, the unit, the
/// skipped messages.
pub type Column<'py> = (
    Bound<'py, PyArray1<f64>>,
    Bound<'py, PyArray1<i64>>,
    Option<String>,
    String,
    Option<String>,
);

/// `_native.read(argv, want_time)`: one column of a record, in `--unit`: the samples, their
/// timestamps (ns; the least int64 where a sample has none), the timestamps' report as JSON
/// (or `None`), the unit and the skipped messages' summary.
#[pyfunction]
pub fn read<'py>(py: Python<'py>, argv: Vec<OsString>, want_time: bool) -> PyResult<Column<'py>> {
    let (x, t, timing, unit, skipped) = run(py, &argv, |c| {
        let Command::Read(args) = c else {
            return Err(other());
        };
        if let Some(r) = args.rate {
            check_rate(r)?;
        }
        let mut t = Vec::new();
        let s = args
            .input
            .series_stamped(want_time && args.rate.is_none(), &mut t)?;
        // A rate given must agree with the stamps where they give one, as everywhere.
        if args.rate.is_some() {
            s.rate(args.rate, &args.input)?;
        }
        let timing = s.timing.as_ref().map(json_line).transpose()?;
        Ok((s.x, t, timing, s.unit, s.skipped.summary()))
    })?;
    Ok((
        x.into_pyarray(py),
        t.into_pyarray(py),
        timing,
        unit,
        skipped,
    ))
}

/// `_native.csv_columns(path)`: the data columns of a CSV file's header (every column but a
/// time column or `time_column`), as the tool reads the header.
#[pyfunction]
#[pyo3(signature = (path, time_column=None))]
pub fn csv_columns(path: PathBuf, time_column: Option<String>) -> PyResult<Vec<String>> {
    let header =
        guarded(|| header(&[path]).map_err(|e| Fail(e.to_string()))).map_err(to_py_checked)?;
    // As the reader picks it (a `time_column` that names none is the reader's to refuse).
    let time = match time_column {
        Some(t) => position(&header, &t).ok(),
        None => header.iter().position(|c| is_time(c)),
    };
    Ok(header
        .into_iter()
        .enumerate()
        .filter(|&(i, _)| Some(i) != time)
        .map(|(_, c)| c)
        .collect())
}

/// `_native.kind(path)`: the kind of recording `path` is (`Csv`, `Bag`, `Mcap`, ...).
#[pyfunction]
pub fn kind(path: PathBuf) -> String {
    match Kind::of(&path) {
        Kind::Other(_) => "Other".into(),
        k => format!("{k:?}"),
    }
}

/// `_native.parity_input()`: the input sequence of the parity run (float32, every 997th NaN).
#[pyfunction]
pub fn parity_input(py: Python<'_>) -> PyResult<Bound<'_, PyArray1<f32>>> {
    let x = guarded(pa::input).map_err(to_py_checked)?;
    Ok(x.into_pyarray(py))
}

/// `_native.parity()`: the checksums `imu-ar parity` prints, `(f32, fixed, noise)`.
#[pyfunction]
pub fn parity(py: Python<'_>) -> PyResult<(u64, u64, u64)> {
    py.detach(|| guarded(|| pa::run().map(|c| (c.f32, c.fixed, c.noise))))
        .map_err(to_py_checked)
}

/// `_native.centre(x)`: the offset `imu-ar fit` removes in f64 before an f32 or fixed-point
/// fit (the mean of the samples f32 can hold).
#[pyfunction]
pub fn centre(x: PyReadonlyArray1<'_, f64>) -> PyResult<f64> {
    Ok(fi::centre(x.as_slice()?, true))
}

#[cfg(test)]
mod tests {
    use super::*;

    fn line(args: &[&str]) -> Vec<OsString> {
        args.iter().map(OsString::from).collect()
    }

    #[test]
    fn a_bad_flag_is_the_tool_s_one_line_error() {
        let e = parse(&line(&[
            "noise",
            "a.csv",
            "--column",
            "x",
            "--gm-states",
            "x",
        ]))
        .err()
        .map(|f| f.0)
        .unwrap_or_default();
        assert!(e.contains("--gm-states"), "{e}");
        assert!(!e.contains('\n'), "{e}");
    }

    #[test]
    fn noise_on_samples_is_the_tool_s_model() {
        // White noise from an LCG.
        let mut s = 1u32;
        let x: Vec<f64> = (0..20_000)
            .map(|_| {
                s = s.wrapping_mul(1_664_525).wrapping_add(1_013_904_223);
                f64::from(s >> 8) / 16_777_216.0 - 0.5
            })
            .collect();
        let Ok(Command::Noise(args)) = parse(&line(&[
            "noise", "<array>", "--column", "x", "--rate", "100", "--json",
        ])) else {
            panic!("parse")
        };
        let r = no::run_with(&args, Some(&x)).map_err(|f| f.0);
        let r = r.as_ref().map(|r| r.white_noise);
        assert!(
            matches!(r, Ok(Some(n)) if n > 0.02 && n < 0.04),
            "{:?}",
            r.err()
        );
    }
}
