//! Reading a record: one column of CSV files ([`csv`]), averaged in blocks (`--decimate`), and
//! the checks of the settings the commands share. An error names the flag, or the files.

pub mod bag;
pub mod csv;
pub mod frame;
pub mod mcap;

use std::path::PathBuf;

use imu_ar::recursive::Channel;

use crate::error::{Fail, with_file};
use crate::method::MAX_ORDER;

/// One column of a record.
#[derive(clap::Args)]
pub struct Input {
    /// CSV files with a header row, read as one record (`-` is standard input).
    #[arg(required = true)]
    pub files: Vec<PathBuf>,
    /// Column name.
    #[arg(long)]
    pub column: String,
}

impl Input {
    /// The column's samples.
    pub fn read(&self) -> Result<Vec<f64>, Fail> {
        Ok(csv::read_column(&self.files, &self.column)?)
    }

    /// The column's samples averaged in blocks of `decimate`.
    pub fn load(&self, decimate: usize) -> Result<Vec<f64>, Fail> {
        decimated(&self.files, &self.read()?, decimate)
    }

    /// `e` after the names of the files.
    pub fn fail(&self, e: impl std::fmt::Display) -> Fail {
        with_file(&self.files, e)
    }
}

/// One column of a record, and the order of the model to fit to it.
#[derive(clap::Args)]
pub struct Record {
    /// The column.
    #[command(flatten)]
    pub input: Input,
    /// Model order, 1 to 32.
    #[arg(long, allow_negative_numbers = true)]
    pub order: usize,
}

impl Record {
    /// Checks the order, then reads the column and averages blocks of `decimate` samples.
    pub fn load(&self, decimate: usize) -> Result<Vec<f64>, Fail> {
        check_order("--order", self.order)?;
        check_decimate(decimate)?;
        self.input.load(decimate)
    }
}

/// `x` averaged in blocks of `m` samples; an error when no sample is left.
fn decimated(files: &[PathBuf], x: &[f64], m: usize) -> Result<Vec<f64>, Fail> {
    let y = block_average(x, m);
    if y.is_empty() {
        return Err(with_file(
            files,
            format!(
                "--decimate {m}: the record has {} samples, no sample is left after averaging \
                 blocks of {m}",
                x.len()
            ),
        ));
    }
    Ok(y)
}

/// Averages of consecutive blocks of `m` samples (a last, incomplete block is dropped): the
/// record at `1/m` of its rate, as sensor drift is usually modelled. `m = 1` returns `x`.
///
/// Block averaging is a low-pass filter: it keeps the slow (correlated) part of the error and
/// divides the white part's variance by `m`, so a model fitted to averaged data describes the
/// averaged sensor, not the raw one (numerics.md section 6).
pub fn block_average(x: &[f64], m: usize) -> Vec<f64> {
    match m {
        0 | 1 => x.to_vec(),
        _ => x
            .chunks_exact(m)
            .map(|block| block.iter().sum::<f64>() / m as f64)
            .collect(),
    }
}

/// A model order (`flag`) from 1 to [`MAX_ORDER`].
pub fn check_order(flag: &str, p: usize) -> Result<(), Fail> {
    if p == 0 || p > MAX_ORDER {
        return Err(Fail(format!(
            "{flag} {p}: the order must be 1 to {MAX_ORDER} (the supported maximum)"
        )));
    }
    Ok(())
}

/// A `--decimate` of at least 1.
pub fn check_decimate(m: usize) -> Result<(), Fail> {
    if m == 0 {
        return Err(Fail("--decimate 0: must be at least 1".into()));
    }
    Ok(())
}

/// A positive, finite `--rate`.
pub fn check_rate(rate: f64) -> Result<f64, Fail> {
    if !(rate.is_finite() && rate > 0.0) {
        return Err(Fail(format!(
            "--rate {rate}: must be a positive number of Hz"
        )));
    }
    Ok(rate)
}

/// A `--lambda` in (0, 1].
pub fn check_lambda(lambda: f64) -> Result<(), Fail> {
    if !(lambda > 0.0 && lambda <= 1.0) {
        return Err(Fail(format!("--lambda {lambda}: must be in (0, 1]")));
    }
    Ok(())
}

/// A `--delta` that the f64 estimators can carry (the library's range check).
pub fn check_delta(delta: f64) -> Result<(), Fail> {
    Channel::<f64>::new(delta)
        .map(|_| ())
        .map_err(|e| Fail(format!("--delta {delta}: {e}")))
}

/// `rate` (Hz, `flag`) gives finite times over `samples` samples: their span `samples / rate`
/// and the interval `1 / rate` do not overflow f64.
pub fn check_span(flag: &str, rate: f64, samples: usize) -> Result<(), Fail> {
    let span = samples.max(1) as f64 / rate;
    if !(span.is_finite() && (1.0 / rate).is_finite()) {
        return Err(Fail(format!(
            "{flag} {rate}: too small, the time of {samples} samples overflows f64"
        )));
    }
    Ok(())
}

/// 0.1 x the variance of the first 1000 samples (what firmware sees at start-up), or 1 when
/// that is 0; an error when that variance overflows f64.
pub fn default_delta(x: &[f64]) -> Result<f64, String> {
    let head = &x[..x.len().min(1000)];
    let mean = head.iter().sum::<f64>() / head.len() as f64;
    let var = head.iter().map(|v| (v - mean) * (v - mean)).sum::<f64>() / head.len() as f64;
    if !var.is_finite() {
        return Err(
            "the variance of the first 1000 samples (for the default --delta) overflows \
             f64 (values of about 1e154 or more); rescale the record"
                .into(),
        );
    }
    Ok(if var > 0.0 { 0.1 * var } else { 1.0 })
}
