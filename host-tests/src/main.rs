//! `imu-ar`: characterise a recorded sensor log with the library's estimators.
//!
//! ```text
//! imu-ar fit FILE.. --column C --method ls|yule-walker|burg|rls|lattice --order P
//!     [--scalar f64|f32|fixed] [--lambda L] [--delta D] [--scale S] [--no-demean] [--decimate M]
//!     [--rate HZ] [--json]
//! imu-ar compare FILE.. --column C --order P [--lambda L] [--delta D] [--decimate M] [--train F]
//!     [--json]
//! imu-ar report FILE.. --column C --order P --rate HZ --out DIR [--lambda L] [--delta D]
//!     [--decimate M] [--train F] [--unit U] [--reference TABLE]
//! imu-ar order FILE.. --column C --max-order P --method ls|yule-walker|burg [--no-demean] [--json]
//! imu-ar adev FILE.. --column C --rate HZ [--json]
//! imu-ar kalman FILE.. --column C --order P --rate HZ [--method ls|yule-walker|burg] [--decimate M]
//!     [--filter-rate HZ] [--json]
//! imu-ar parity
//! imu-ar simulate --a A1,A2,.. [--a-end B1,B2,..] --sigma S --n N --seed K [--rate HZ] [--burn-in B]
//! ```
//!
//! Several files are read as one record, in order. Bad input exits with status 2 and one line
//! on stderr naming the file, line and problem; nothing is written to stdout.

use std::io::{BufWriter, Write};
use std::path::PathBuf;
use std::process::ExitCode;

use clap::{Args, CommandFactory, Parser, Subcommand, ValueEnum};
use imu_ar::ArModel;
use imu_ar::allan::overlapping_avar;
use imu_ar::batch::criteria::Criterion;
use imu_ar::batch::{BatchConfig, BatchError, Fit, burg, covariance, yule_walker};
use imu_ar::recursive::{Channel, Config, ConfigError, Estimator, FixedChannel, FixedConfig};
use imu_ar::recursive::{FixedLattice, FloatArith, Lattice, Rls, Sftf};
use imu_ar::sim::StandardNormal;
use imu_ar_host::data::{block_average, read_column};
use kalman::handoff;
use rand_chacha::ChaCha8Rng;
use rand_core::SeedableRng;
use report::report;
use serde_json::{Value, json};

mod kalman;
/// The parity run shared with the `parity` firmware (same file, compiled for the host).
#[path = "../../examples/common/parity.rs"]
mod parity;
mod report;

/// The highest model order the tool accepts.
const MAX_ORDER: usize = 32;

/// Calls `$f::<P>($args..)` with the const `P` equal to the runtime order `$p` (1..=32).
macro_rules! with_order {
    ($p:expr, $f:ident :: < $t:ty > $args:tt) => {
        with_order!(@typed $p, $f, $t, $args;
            1 2 3 4 5 6 7 8 9 10 11 12 13 14 15 16 17 18 19 20 21 22 23 24 25 26 27 28 29 30 31 32)
    };
    (@typed $p:expr, $f:ident, $t:ty, $args:tt; $($n:literal)*) => {
        match $p {
            $($n => $f::<$t, $n> $args,)*
            p => unreachable!("order {p} was checked against MAX_ORDER"),
        }
    };
    ($p:expr, $f:ident $args:tt) => {
        with_order!(@arms $p, $f $args;
            1 2 3 4 5 6 7 8 9 10 11 12 13 14 15 16 17 18 19 20 21 22 23 24 25 26 27 28 29 30 31 32)
    };
    (@arms $p:expr, $f:ident $args:tt; $($n:literal)*) => {
        match $p {
            $($n => $f::<$n> $args,)*
            p => unreachable!("order {p} was checked against MAX_ORDER"),
        }
    };
}

#[derive(Parser)]
#[command(
    name = "imu-ar",
    version,
    about = "AR stochastic models of MEMS sensor errors"
)]
struct Cli {
    #[command(subcommand)]
    command: Command,
}

#[derive(Clone, Copy, ValueEnum)]
pub(crate) enum Method {
    /// Covariance method (conditional least squares).
    Ls,
    /// Yule-Walker (biased autocovariance, Levinson-Durbin).
    YuleWalker,
    /// Burg.
    Burg,
    /// Conventional RLS (Bierman U-D), model after the last sample.
    Rls,
    /// EF-LSL lattice, model after the last sample.
    Lattice,
    /// Stabilised fast transversal filter with its divergence monitor, model after the last
    /// sample (the last good one if it was just rescued).
    Sftf,
}

impl Method {
    fn name(self) -> &'static str {
        match self {
            Method::Ls => "ls",
            Method::YuleWalker => "yule-walker",
            Method::Burg => "burg",
            Method::Rls => "rls",
            Method::Lattice => "lattice",
            Method::Sftf => "sftf",
        }
    }

    fn recursive(self) -> bool {
        matches!(self, Method::Rls | Method::Lattice | Method::Sftf)
    }
}

#[derive(Clone, Copy, ValueEnum)]
enum ScalarKind {
    F64,
    F32,
    /// The fixed-point lattice (`--method lattice` only).
    Fixed,
}

impl ScalarKind {
    fn name(self) -> &'static str {
        match self {
            ScalarKind::F64 => "f64",
            ScalarKind::F32 => "f32",
            ScalarKind::Fixed => "fixed",
        }
    }
}

/// The default forgetting factor of the recursive methods.
const DEFAULT_LAMBDA: f64 = 0.999;

#[derive(Subcommand)]
enum Command {
    /// Fit an AR(P) model to one column.
    Fit {
        /// CSV files with a header row, read as one record.
        #[arg(required = true)]
        files: Vec<PathBuf>,
        /// Column name.
        #[arg(long)]
        column: String,
        /// Estimator.
        #[arg(long, value_enum)]
        method: Method,
        /// Model order, 1 to 32.
        #[arg(long)]
        order: usize,
        /// Arithmetic of the recursive methods (the batch fits compute in f64).
        #[arg(long, value_enum, default_value = "f64")]
        scalar: ScalarKind,
        /// Forgetting factor of the recursive methods, in (0, 1].
        #[arg(long, default_value_t = DEFAULT_LAMBDA, allow_negative_numbers = true)]
        lambda: f64,
        /// Initial regularisation of the recursive methods [default: 0.1 x the variance of the
        /// first 1000 samples, or 1 when that is 0].
        #[arg(long, allow_negative_numbers = true)]
        delta: Option<f64>,
        /// Internal units per sensor unit of `--scalar fixed` [default: 8 / max |x|, so that the
        /// record, offset included, uses half of the +-16 range].
        #[arg(long, allow_negative_numbers = true)]
        scale: Option<f64>,
        /// Fit the data as they are, without removing the (sample or running) mean.
        #[arg(long)]
        no_demean: bool,
        /// Average blocks of M samples first (the rate, if given, becomes rate / M).
        #[arg(long, default_value_t = 1)]
        decimate: usize,
        /// Sample rate in Hz; gives the model its time scale.
        #[arg(long, allow_negative_numbers = true)]
        rate: Option<f64>,
        /// Print one JSON object.
        #[arg(long)]
        json: bool,
    },
    /// One-step prediction error of a batch LS fit on the training part against RLS and the
    /// lattice running over the whole record, on the evaluation part.
    Compare {
        #[command(flatten)]
        run: Comparison,
        /// Print one JSON object.
        #[arg(long)]
        json: bool,
    },
    /// The paper's comparison on one record, in PNG plots: coefficient convergence of RLS and
    /// the lattice against the batch fit, one-step prediction error over time, the fitted PSD
    /// against a Welch periodogram, and Allan deviations of the data and the model. Prints a
    /// JSON summary.
    Report {
        #[command(flatten)]
        run: Comparison,
        /// Sample rate in Hz of the raw record.
        #[arg(long, allow_negative_numbers = true)]
        rate: f64,
        /// The column's unit, for the axis labels.
        #[arg(long, default_value = "units")]
        unit: String,
        /// A published Allan table to draw too: CSV with `channel`, `tau_s` and `adev`
        /// columns; the rows of channel `--column` are used.
        #[arg(long)]
        reference: Option<PathBuf>,
        /// Directory for the PNG files (created if needed).
        #[arg(long)]
        out: PathBuf,
    },
    /// The Kalman filter hand-off of a batch fit: `Phi`, `Q` and the stationary covariance at
    /// the filter's rate, the Gauss-Markov form of an AR(1), and the Allan check that the model
    /// explains the data's Allan deviation.
    Kalman {
        #[command(flatten)]
        record: Record,
        /// Batch estimator.
        #[arg(long, value_enum, default_value = "burg")]
        method: Method,
        /// Sample rate in Hz of the raw record.
        #[arg(long, allow_negative_numbers = true)]
        rate: f64,
        /// Average blocks of M samples first; the model's rate becomes rate / M.
        #[arg(long, default_value_t = 1)]
        decimate: usize,
        /// The filter's rate in Hz [default: the model's]. The model's rate must be an integer
        /// multiple of it, except for an AR(1) with a Gauss-Markov equivalent, which samples
        /// at any rate.
        #[arg(long, allow_negative_numbers = true)]
        filter_rate: Option<f64>,
        /// Print one JSON object.
        #[arg(long)]
        json: bool,
    },
    /// Order criteria (AIC, AICc, BIC, FPE) of orders 0..=P.
    Order {
        /// CSV files with a header row, read as one record.
        #[arg(required = true)]
        files: Vec<PathBuf>,
        /// Column name.
        #[arg(long)]
        column: String,
        /// Highest order, 1 to 32.
        #[arg(long)]
        max_order: usize,
        /// Estimator.
        #[arg(long, value_enum)]
        method: Method,
        /// Fit the data as they are, without removing the sample mean.
        #[arg(long)]
        no_demean: bool,
        /// Print one JSON object.
        #[arg(long)]
        json: bool,
    },
    /// Overlapping Allan deviation at m = 1, 2, 4, ...
    Adev {
        /// CSV files with a header row, read as one record.
        #[arg(required = true)]
        files: Vec<PathBuf>,
        /// Column name.
        #[arg(long)]
        column: String,
        /// Sample rate in Hz.
        #[arg(long, allow_negative_numbers = true)]
        rate: f64,
        /// Print one JSON object.
        #[arg(long)]
        json: bool,
    },
    /// Checksums of the f32 and fixed-point lattices on the seeded parity sequence, to compare
    /// with `cargo qemu parity` (bit-identical results on host and target).
    Parity,
    /// Simulate an AR process; CSV `t_s,x` on stdout.
    Simulate {
        /// Coefficients a_1,..,a_P of `x[n] = sum a_k x[n-k] + w[n]`.
        #[arg(
            long,
            value_delimiter = ',',
            allow_negative_numbers = true,
            required = true
        )]
        a: Vec<f64>,
        /// Innovation standard deviation.
        #[arg(long, allow_negative_numbers = true)]
        sigma: f64,
        /// Number of samples.
        #[arg(long)]
        n: usize,
        /// Seed of the ChaCha8 generator.
        #[arg(long)]
        seed: u64,
        /// Sample rate in Hz.
        #[arg(long, default_value_t = 1.0, allow_negative_numbers = true)]
        rate: f64,
        /// Samples drawn and discarded first.
        #[arg(long, default_value_t = 1000)]
        burn_in: usize,
        /// Coefficients at the last sample: they move linearly from `--a` to these over the
        /// record (a drifting process; burn-in uses `--a`).
        #[arg(long, value_delimiter = ',', allow_negative_numbers = true)]
        a_end: Option<Vec<f64>>,
    },
}

/// One column of a record, and the order of the model to fit to it.
#[derive(Args)]
struct Record {
    /// CSV files with a header row, read as one record.
    #[arg(required = true)]
    files: Vec<PathBuf>,
    /// Column name.
    #[arg(long)]
    column: String,
    /// Model order, 1 to 32.
    #[arg(long)]
    order: usize,
}

impl Record {
    /// Checks the order, then reads the column and averages blocks of `decimate` samples.
    fn load(&self, decimate: usize) -> Result<Vec<f64>, Fail> {
        check_order("--order", self.order)?;
        check_decimate(decimate)?;
        decimated(
            &self.files,
            &read_column(&self.files, &self.column)?,
            decimate,
        )
    }
}

/// The record and settings of `compare` and `report`.
#[derive(Args)]
struct Comparison {
    #[command(flatten)]
    record: Record,
    /// Forgetting factor, in (0, 1].
    #[arg(long, default_value_t = DEFAULT_LAMBDA, allow_negative_numbers = true)]
    lambda: f64,
    /// Initial regularisation [default: as for `fit`].
    #[arg(long, allow_negative_numbers = true)]
    delta: Option<f64>,
    /// Average blocks of M samples first (a rate becomes rate / M).
    #[arg(long, default_value_t = 1)]
    decimate: usize,
    /// Fraction of the record the batch model is fitted on, in (0, 1).
    #[arg(long, default_value_t = 0.5, allow_negative_numbers = true)]
    train: f64,
}

impl Comparison {
    /// Checks the settings, then reads (and decimates) the record; returns it with `delta`.
    fn load(&self) -> Result<(Vec<f64>, f64), Fail> {
        check_lambda(self.lambda)?;
        if let Some(d) = self.delta {
            check_delta(d)?;
        }
        if !(self.train > 0.0 && self.train < 1.0) {
            return Err(Fail(format!("--train {}: must be in (0, 1)", self.train)));
        }
        let x = self.record.load(self.decimate)?;
        let delta = match self.delta {
            Some(d) => d,
            None => default_delta(&x).map_err(|e| with_file(&self.record.files, e))?,
        };
        Ok((x, delta))
    }
}

/// A one-line error for stderr; the tool exits with status 2.
pub(crate) struct Fail(pub(crate) String);

impl<E: std::fmt::Display> From<E> for Fail {
    fn from(e: E) -> Self {
        Fail(e.to_string())
    }
}

fn main() -> ExitCode {
    let cli = match Cli::try_parse() {
        Ok(cli) => cli,
        Err(e) if !e.use_stderr() => {
            // Help and version: a closed pipe is a normal end.
            return write_stdout(&e.to_string());
        }
        Err(e) => {
            let msg = match e.kind() {
                // The help shown for no arguments at all.
                clap::error::ErrorKind::DisplayHelpOnMissingArgumentOrSubcommand => {
                    let command = Cli::command();
                    let names: Vec<&str> =
                        command.get_subcommands().map(|c| c.get_name()).collect();
                    format!(
                        "a subcommand is required ({}); see imu-ar --help",
                        names.join(", ")
                    )
                }
                _ => clap_message(&e.to_string()),
            };
            eprintln!("imu-ar: {}", one_line(&msg));
            return ExitCode::from(2);
        }
    };
    match run(cli.command) {
        Ok(out) => write_stdout(&out),
        Err(Fail(msg)) => {
            eprintln!("imu-ar: {}", one_line(&msg));
            ExitCode::from(2)
        }
    }
}

/// Writes `out` to stdout; a reader that closed the pipe early (`| head`) ends the run
/// normally (status 0), any other write error is status 1.
fn write_stdout(out: &str) -> ExitCode {
    let mut stdout = BufWriter::new(std::io::stdout().lock());
    match stdout
        .write_all(out.as_bytes())
        .and_then(|_| stdout.flush())
    {
        Ok(()) => ExitCode::SUCCESS,
        Err(e) if e.kind() == std::io::ErrorKind::BrokenPipe => ExitCode::SUCCESS,
        Err(e) => {
            eprintln!("imu-ar: cannot write to stdout: {e}");
            ExitCode::FAILURE
        }
    }
}

/// A clap error as one line: its message and details (the missing arguments, a tip), without
/// the usage and the pointer to `--help`.
fn clap_message(text: &str) -> String {
    let mut msg = String::new();
    // Whether the lines are the items of a list ("...not provided:" and the arguments).
    let mut list = false;
    for line in text.lines() {
        let line = line.trim();
        if line.starts_with("Usage:") {
            break;
        }
        if line.is_empty() {
            list = false;
            continue;
        }
        if line.starts_with("For more information") {
            continue;
        }
        let line = line.trim_start_matches("error: ");
        if msg.ends_with(':') {
            msg += " ";
            list = true;
        } else if list {
            msg += ", ";
        } else if !msg.is_empty() {
            msg += "; ";
        }
        msg += line;
    }
    if msg.is_empty() {
        "invalid arguments".into()
    } else {
        msg
    }
}

/// `text` with its control characters (a newline in an echoed cell, say) escaped, so that an
/// error stays on one line.
pub(crate) fn one_line(text: &str) -> String {
    imu_ar_host::data::escaped(text)
}

/// Runs a command and returns everything it prints, so that a failure prints nothing.
fn run(command: Command) -> Result<String, Fail> {
    match command {
        Command::Fit {
            files,
            column,
            method,
            order,
            scalar,
            lambda,
            delta,
            scale,
            no_demean,
            decimate,
            rate,
            json,
        } => {
            check_order("--order", order)?;
            check_decimate(decimate)?;
            let rate = rate.map(|r| r / decimate as f64);
            if matches!(scalar, ScalarKind::Fixed) && !matches!(method, Method::Lattice) {
                return Err(Fail(format!(
                    "--scalar fixed: only --method lattice runs in fixed point, not {}",
                    method.name()
                )));
            }
            if let Some(s) = scale.filter(|s| !(s.is_finite() && *s > 0.0)) {
                return Err(Fail(format!("--scale {s}: must be positive and finite")));
            }
            let dt = match rate {
                Some(r) => 1.0 / check_rate(r)?,
                None => 1.0,
            };
            check_lambda(lambda)?;
            if let Some(d) = delta {
                check_delta(d)?;
            }
            let x = decimated(&files, &read_column(&files, &column)?, decimate)?;
            if let Some(r) = rate {
                check_span("--rate", r * decimate as f64, x.len() * decimate)?;
            }
            let fit = if method.recursive() {
                let default = delta.is_none();
                let delta = match delta {
                    Some(d) => d,
                    None => default_delta(&x).map_err(|e| with_file(&files, e))?,
                };
                let r = Recursive {
                    method,
                    scalar,
                    lambda,
                    delta,
                    demean: !no_demean,
                    dt,
                    rate,
                    default_delta: default,
                };
                match scalar {
                    ScalarKind::F64 => with_order!(order, recursive_fit::<f64>(&x, &r)),
                    ScalarKind::F32 => with_order!(order, recursive_fit::<f32>(&x, &r)),
                    ScalarKind::Fixed => {
                        // The default scale is taken from the samples the fit will see (centred
                        // when the mean is removed).
                        let offset = centre(&x, r.demean);
                        let peak = x
                            .iter()
                            .map(|v| v - offset)
                            .filter(|v| v.abs() <= f64::from(f32::MAX))
                            .fold(0.0f64, |m, v| m.max(v.abs()));
                        let scale = match scale {
                            Some(s) => Scale::Given(s),
                            None => Scale::Default(if peak > 0.0 { 8.0 / peak } else { 1.0 }),
                        };
                        with_order!(order, fixed_fit(&x, &r, scale))
                    }
                }
                .map_err(|Fail(e)| with_file(&files, e))?
            } else {
                let config = BatchConfig::new(dt)?.with_demean(!no_demean);
                with_order!(order, fit_json(method, &x, &config, rate))
                    .map_err(|e| with_file(&files, e))?
            };
            if let Some(warning) = rejection_warning(&fit) {
                eprintln!("imu-ar: warning: {}", with_file(&files, warning).0);
            }
            Ok(if json {
                format!("{fit}\n")
            } else {
                fit_text(&fit)
            })
        }
        Command::Compare { run, json } => {
            let (x, delta) = run.load()?;
            let (order, lambda) = (run.record.order, run.lambda);
            let mut v = with_order!(order, compare(&x, lambda, delta, run.train))
                .map_err(|Fail(e)| with_file(&run.record.files, e))?;
            v["decimate"] = json!(run.decimate);
            Ok(if json {
                format!("{v}\n")
            } else {
                format!(
                    "AR({order}), lambda {lambda}: training {} samples, evaluation {}\n\
                     one-step prediction MSE: batch LS {}, RLS {}, lattice {}, SFTF {} \
                     ({} rescues)\n\
                     lattice against batch: {}\n",
                    v["n_train"],
                    v["n_eval"],
                    v["batch_mse"],
                    v["rls_mse"],
                    v["lattice_mse"],
                    v["sftf_mse"],
                    v["sftf_restarts"],
                    reduction_text(v["reduction_percent"].as_f64())
                )
            })
        }
        Command::Report {
            run,
            rate,
            unit,
            reference,
            out,
        } => {
            let rate = check_rate(rate)? / run.decimate.max(1) as f64;
            let reference = match reference {
                Some(path) => Some(read_reference(&path, &run.record.column)?),
                None => None,
            };
            let (x, delta) = run.load()?;
            check_span(
                "--rate",
                rate * run.decimate.max(1) as f64,
                x.len() * run.decimate.max(1),
            )?;
            let r = report::Report {
                x: &x,
                rate,
                lambda: run.lambda,
                delta,
                train: run.train,
                unit: &unit,
                reference,
                out: &out,
            };
            let v = with_order!(run.record.order, report(&r))
                .map_err(|Fail(e)| with_file(&run.record.files, e))?;
            Ok(format!("{v}\n"))
        }
        Command::Kalman {
            record,
            method,
            rate,
            decimate,
            filter_rate,
            json,
        } => {
            if method.recursive() {
                return Err(Fail(format!(
                    "--method {}: the hand-off takes a batch fit (ls, yule-walker, burg)",
                    method.name()
                )));
            }
            let rate = check_rate(rate)? / decimate as f64;
            let filter_rate = match filter_rate {
                Some(f) => check_rate(f).map_err(|_| {
                    Fail(format!(
                        "--filter-rate {f}: must be a positive number of Hz"
                    ))
                })?,
                None => rate,
            };
            let x = record.load(decimate)?;
            check_span("--rate", rate * decimate as f64, x.len() * decimate)?;
            let v = with_order!(record.order, handoff(method, &x, rate, filter_rate))
                .map_err(|Fail(e)| with_file(&record.files, e))?;
            Ok(if json {
                format!("{v}\n")
            } else {
                kalman::text(&v)
            })
        }
        Command::Order {
            files,
            column,
            max_order,
            method,
            no_demean,
            json,
        } => {
            check_order("--max-order", max_order)?;
            if method.recursive() {
                return Err(Fail(format!(
                    "--method {}: order criteria need a batch method (ls, yule-walker, burg)",
                    method.name()
                )));
            }
            let x = read_column(&files, &column)?;
            let config = BatchConfig::new(1.0)?.with_demean(!no_demean);
            let report = with_order!(max_order, order_json(method, &x, &config))
                .map_err(|e| with_file(&files, e))?;
            Ok(if json {
                format!("{report}\n")
            } else {
                order_text(&report)
            })
        }
        Command::Adev {
            files,
            column,
            rate,
            json,
        } => {
            let rate = check_rate(rate)?;
            let x = read_column(&files, &column)?;
            if x.len() < 2 {
                return Err(with_file(
                    &files,
                    format!("{} sample(s), at least 2 needed", x.len()),
                ));
            }
            check_span("--rate", rate, x.len())?;
            let (mut tau, mut avar) = (Vec::new(), Vec::new());
            let mut m = 1usize;
            while x.len() / 2 >= m {
                tau.push(m as f64 / rate);
                avar.push(overlapping_avar(&x, m)?);
                m *= 2;
            }
            let adev: Vec<f64> = avar.iter().map(|v| v.sqrt()).collect();
            Ok(if json {
                let v = json!({"rate_hz": rate, "tau_s": tau, "avar": avar, "adev": adev, "n": x.len()});
                format!("{v}\n")
            } else {
                let mut s = format!("# n = {}, rate = {rate} Hz\n# tau_s avar adev\n", x.len());
                for ((t, v), d) in tau.iter().zip(&avar).zip(&adev) {
                    s += &format!("{t} {v:e} {d:e}\n");
                }
                s
            })
        }
        Command::Parity => {
            let (f, q) = parity::checksums().ok_or_else(|| Fail("parity run refused".into()))?;
            Ok(format!("parity f32 {f:016x} fixed {q:016x}\n"))
        }
        Command::Simulate {
            a,
            sigma,
            n,
            seed,
            rate,
            burn_in,
            a_end,
        } => {
            check_order("--a (number of coefficients)", a.len())?;
            let rate = check_rate(rate)?;
            check_span("--rate", rate, n)?;
            if !(sigma.is_finite() && sigma >= 0.0) {
                return Err(Fail(format!("--sigma {sigma}: must be finite and >= 0")));
            }
            let a_end = a_end.unwrap_or_else(|| a.clone());
            if a_end.len() != a.len() {
                return Err(Fail(format!(
                    "--a-end has {} coefficients, --a has {}",
                    a_end.len(),
                    a.len()
                )));
            }
            let sim = Simulation {
                a: &a,
                a_end: &a_end,
                sigma,
                n,
                seed,
                rate,
                burn_in,
            };
            with_order!(a.len(), simulate(&sim))
        }
    }
}

fn check_order(flag: &str, p: usize) -> Result<(), Fail> {
    if p == 0 || p > MAX_ORDER {
        return Err(Fail(format!(
            "{flag} {p}: the order must be 1 to {MAX_ORDER} (the supported maximum)"
        )));
    }
    Ok(())
}

/// `(tau_s, adev)` of `channel` from a published Allan table.
fn read_reference(path: &std::path::Path, channel: &str) -> Result<Vec<(f64, f64)>, Fail> {
    let files = [path.to_path_buf()];
    let channels = imu_ar_host::data::read_text_column(&files, "channel")?;
    let tau = read_column(&files, "tau_s")?;
    let adev = read_column(&files, "adev")?;
    let rows: Vec<(f64, f64)> = channels
        .iter()
        .zip(tau.into_iter().zip(adev))
        .filter(|(c, _)| c.as_str() == channel)
        .map(|(_, p)| p)
        .collect();
    if rows.is_empty() {
        return Err(Fail(format!(
            "{}: no rows of channel '{channel}'",
            path.display()
        )));
    }
    Ok(rows)
}

fn check_decimate(m: usize) -> Result<(), Fail> {
    if m == 0 {
        return Err(Fail("--decimate 0: must be at least 1".into()));
    }
    Ok(())
}

fn check_rate(rate: f64) -> Result<f64, Fail> {
    if !(rate.is_finite() && rate > 0.0) {
        return Err(Fail(format!(
            "--rate {rate}: must be a positive number of Hz"
        )));
    }
    Ok(rate)
}

fn check_lambda(lambda: f64) -> Result<(), Fail> {
    if !(lambda > 0.0 && lambda <= 1.0) {
        return Err(Fail(format!("--lambda {lambda}: must be in (0, 1]")));
    }
    Ok(())
}

/// A `--delta` that the f64 estimators can carry (the library's range check).
fn check_delta(delta: f64) -> Result<(), Fail> {
    Channel::<f64>::new(delta)
        .map(|_| ())
        .map_err(|e| Fail(format!("--delta {delta}: {e}")))
}

/// `rate` (Hz, `flag`) gives finite times over `samples` samples: their span `samples / rate`
/// and the interval `1 / rate` do not overflow f64.
fn check_span(flag: &str, rate: f64, samples: usize) -> Result<(), Fail> {
    let span = samples.max(1) as f64 / rate;
    if !(span.is_finite() && (1.0 / rate).is_finite()) {
        return Err(Fail(format!(
            "{flag} {rate}: too small, the time of {samples} samples overflows f64"
        )));
    }
    Ok(())
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

/// 0.1 x the variance of the first 1000 samples (what firmware sees at start-up), or 1 when
/// that is 0; an error when that variance overflows f64.
fn default_delta(x: &[f64]) -> Result<f64, String> {
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

/// The offset removed in f64 before a fit in f32 or fixed point: the mean of the samples that
/// f32 can hold when the mean is removed (so that rounding to f32 does not erase a small
/// signal on a large offset), else 0.
fn centre(x: &[f64], demean: bool) -> f64 {
    if !demean {
        return 0.0;
    }
    let (sum, n) = x
        .iter()
        .filter(|v| v.abs() <= f64::from(f32::MAX))
        .fold((0.0, 0usize), |(s, n), v| (s + v, n + 1));
    if n == 0 { 0.0 } else { sum / n as f64 }
}

/// "x % lower" or "x % higher" for a reduction in percent ("undefined" without one: a batch
/// MSE of 0).
fn reduction_text(percent: Option<f64>) -> String {
    let Some(percent) = percent else {
        return "undefined (batch MSE 0)".into();
    };
    if percent < 0.0 {
        format!("{:.1} % higher", -percent)
    } else {
        format!("{percent:.1} % lower")
    }
}

/// A warning when most samples of a fit were rejected (saturated, non-finite).
fn rejection_warning(v: &Value) -> Option<String> {
    let n = v["n"].as_u64()?;
    let rejected = v["saturated"].as_u64().unwrap_or(0) + v["non_finite"].as_u64().unwrap_or(0);
    (2 * rejected > n).then(|| {
        format!("{rejected} of {n} samples were rejected (saturated or non-finite); the model rests on the rest")
    })
}

fn with_file(files: &[PathBuf], e: impl std::fmt::Display) -> Fail {
    let names: Vec<String> = files.iter().map(|f| f.display().to_string()).collect();
    Fail(format!("{}: {e}", names.join("+")))
}

pub(crate) fn batch_fit<const P: usize>(
    method: Method,
    x: &[f64],
    config: &BatchConfig<f64>,
) -> Result<Fit<f64, P>, BatchError> {
    match method {
        Method::Ls => covariance::<f64, P>(x, config),
        Method::YuleWalker => yule_walker::<f64, P>(x, config),
        Method::Burg => burg::<f64, P>(x, config),
        Method::Rls | Method::Lattice | Method::Sftf => {
            unreachable!("recursive methods go to recursive_fit")
        }
    }
}

/// The settings of a recursive fit.
struct Recursive {
    method: Method,
    scalar: ScalarKind,
    lambda: f64,
    delta: f64,
    demean: bool,
    dt: f64,
    rate: Option<f64>,
    /// Whether `delta` is the default (not given).
    default_delta: bool,
}

/// The scale of `--scalar fixed`: given, or the default `8 / max |x|`.
#[derive(Clone, Copy)]
enum Scale {
    Given(f64),
    Default(f64),
}

/// The configuration in `T`, with an error that says which setting `T` cannot carry.
fn config_in<T: FloatArith>(r: &Recursive) -> Result<(Config<T>, Channel<T>), Fail> {
    let config = Config::new(T::from_f64(r.lambda), T::from_f64(r.dt));
    // Checked in the order lambda, delta, interval.
    match (config, Channel::new(T::from_f64(r.delta))) {
        (Ok(config), Ok(channel)) => Ok((config, channel)),
        (Err(ConfigError::Lambda), _) => Err(ConfigError::Lambda),
        (_, Err(e)) | (Err(e), _) => Err(e),
    }
    .map_err(|e| {
        if r.default_delta {
            Fail(format!(
                "{e}: the default --delta (0.1 x the variance of the first 1000 samples) is {}, \
                 which --scalar {} cannot carry; give --delta",
                r.delta,
                r.scalar.name()
            ))
        } else {
            Fail(e.to_string())
        }
    })
}

/// Runs RLS, the lattice or the SFTF in `T` over `x` and reports the model after the last sample.
///
/// In f32 the mean (of the samples f32 can hold) is removed in f64 first and added back to
/// the reported mean, so that rounding to f32 does not erase a small signal on a large offset.
fn recursive_fit<T: FloatArith, const P: usize>(x: &[f64], r: &Recursive) -> Result<Value, Fail> {
    let (config, channel) = config_in::<T>(r)?;
    let config = config.with_demean(r.demean);
    let offset = if core::mem::size_of::<T>() < 8 {
        centre(x, r.demean)
    } else {
        0.0
    };
    let (model, health, reflection) = match r.method {
        Method::Rls => {
            let mut rls = Rls::<T, P>::new(&config, &channel);
            for &v in x {
                rls.update(&config, T::from_f64(v - offset));
            }
            (rls.model(&config), rls.health(), None)
        }
        Method::Sftf => {
            let mut sftf = Sftf::<T, P>::new(&config, &channel);
            for &v in x {
                sftf.update(&config, T::from_f64(v - offset));
            }
            (sftf.model(&config), sftf.health(), None)
        }
        _ => {
            let mut lattice = Lattice::<T, P>::new(&config, &channel);
            for &v in x {
                lattice.update(&config, T::from_f64(v - offset));
            }
            let model = lattice.model(&config);
            let k = model.and_then(|m| m.reflection().ok());
            (model, lattice.health(), k)
        }
    };
    let model = model.ok_or_else(|| Fail("no finite model".into()))?;
    let a: Vec<f64> = model.a().iter().map(|v| v.to_f64()).collect();
    let mut v = json!({
        "method": r.method.name(),
        "scalar": r.scalar.name(),
        "order": P,
        "n": x.len(),
        "mean": model.mean().to_f64() + offset,
        "a": a,
        "noise_variance": model.noise_variance().to_f64(),
        "lambda": r.lambda,
        "delta": r.delta,
        "restarts": health.restarts,
        "non_finite": health.non_finite,
    });
    if let Some(k) = reflection {
        v["reflection"] = json!(k.iter().map(|v| v.to_f64()).collect::<Vec<_>>());
    }
    if let Some(rate) = r.rate {
        v["rate_hz"] = json!(rate);
        gauss_markov_json(&mut v, &a, model.noise_variance().to_f64(), r.dt);
    }
    Ok(v)
}

/// Runs the fixed-point lattice over `x` (in sensor units, scaled by `scale`); the mean is
/// removed in f64 first, as for f32.
fn fixed_fit<const P: usize>(x: &[f64], r: &Recursive, scale: Scale) -> Result<Value, Fail> {
    let (config, channel) = config_in::<f32>(r)?;
    let config = config.with_demean(r.demean);
    let scale_value = match scale {
        Scale::Given(s) | Scale::Default(s) => s,
    };
    let settings = FixedChannel::new(&channel, scale_value as f32)
        .and_then(|channel| Ok((FixedConfig::new(&config)?, channel)));
    let (fixed, fixed_channel) = settings.map_err(|e| {
        let product = r.delta * scale_value * scale_value;
        if e == ConfigError::FixedLambda {
            return Fail(format!("--lambda {}: {e}", r.lambda));
        }
        match scale {
            Scale::Given(s) => Fail(format!(
                "--scale {s}: {e} (delta x scale^2 = {product:e} must be in [1e-9, 1e6))"
            )),
            Scale::Default(s) => Fail(format!(
                "{e}: the default --scale 8 / max |x - mean| = {s:e} and delta {} give \
                 delta x scale^2 = {product:e}, outside [1e-9, 1e6); give --scale or --delta",
                r.delta
            )),
        }
    })?;
    let offset = centre(x, r.demean);
    let mut lattice = FixedLattice::<P>::new(&fixed, &fixed_channel);
    for &v in x {
        lattice.update(&fixed, (v - offset) as f32);
    }
    let health = lattice.health();
    let model = lattice
        .model(&fixed)
        .ok_or_else(|| Fail("no finite model".into()))?;
    let a: Vec<f64> = model.a().iter().map(|&v| f64::from(v)).collect();
    let mut v = json!({
        "method": "lattice",
        "scalar": "fixed",
        "order": P,
        "n": x.len(),
        "mean": f64::from(model.mean()) + offset,
        "a": a,
        "noise_variance": f64::from(model.noise_variance()),
        "lambda": fixed.lambda(),
        "delta": r.delta,
        "scale": f64::from(fixed_channel.scale()),
        "restarts": health.restarts,
        "saturated": health.saturated,
        "clipped": health.clipped,
        "non_finite": health.non_finite,
    });
    if let Ok(k) = model.reflection() {
        v["reflection"] = json!(k.iter().map(|&v| f64::from(v)).collect::<Vec<_>>());
    }
    if let Some(rate) = r.rate {
        v["rate_hz"] = json!(rate);
        gauss_markov_json(&mut v, &a, f64::from(model.noise_variance()), r.dt);
    }
    Ok(v)
}

/// Adds `gauss_markov` to a fit's JSON for an AR(1) with `0 < a_1 < 1`.
fn gauss_markov_json(v: &mut Value, a: &[f64], noise_variance: f64, dt: f64) {
    let [a1] = a else { return };
    let Ok(ar1) = ArModel::new([*a1], noise_variance, 0.0, dt) else {
        return;
    };
    if let Ok(gm) = ar1.to_gauss_markov() {
        v["gauss_markov"] = json!({
            "correlation_time_s": gm.correlation_time(),
            "sigma": gm.sigma(),
        });
    }
}

/// One-step prediction MSE on the evaluation part `x[n_train..]`: batch LS fitted on
/// `x[..n_train]`, RLS, lattice and SFTF (f64) running over the whole record. The SFTF's MSE
/// is over the samples it returned an error for (all but its rescues, `sftf_restarts`).
fn compare<const P: usize>(x: &[f64], lambda: f64, delta: f64, train: f64) -> Result<Value, Fail> {
    let n_train = (train * x.len() as f64) as usize;
    let n_eval = x.len() - n_train;
    if n_eval == 0 {
        return Err(Fail("the evaluation part is empty".into()));
    }
    let batch = match covariance::<f64, P>(&x[..n_train], &BatchConfig::new(1.0)?) {
        Err(BatchError::TooShort { needed, given }) => {
            return Err(Fail(format!(
                "the training part (--train {train} of {} samples) has {given} samples, at least \
                 {needed} needed for order {P}",
                x.len()
            )));
        }
        fit => fit?.model,
    };
    let config = Config::new(lambda, 1.0)?;
    let channel = Channel::new(delta)?;
    let mut rls = Rls::<f64, P>::new(&config, &channel);
    let mut lattice = Lattice::<f64, P>::new(&config, &channel);
    let mut sftf = Sftf::<f64, P>::new(&config, &channel);
    let (mut batch_se, mut rls_se, mut lattice_se) = (0.0, 0.0, 0.0);
    let (mut sftf_se, mut sftf_n) = (0.0, 0usize);
    for (n, &v) in x.iter().enumerate() {
        let e_rls = rls.update(&config, v).unwrap_or(f64::NAN);
        let e_lattice = lattice.update(&config, v).unwrap_or(f64::NAN);
        let e_sftf = sftf.update(&config, v);
        if n < n_train {
            continue;
        }
        if let Some(e) = e_sftf {
            sftf_se += e * e;
            sftf_n += 1;
        }
        let past: [f64; P] = core::array::from_fn(|k| x[n - 1 - k]);
        let e_batch = v - batch.predict(&past);
        batch_se += e_batch * e_batch;
        rls_se += e_rls * e_rls;
        lattice_se += e_lattice * e_lattice;
    }
    let m = n_eval as f64;
    let (batch_mse, rls_mse, lattice_mse) = (batch_se / m, rls_se / m, lattice_se / m);
    for (name, mse) in [
        ("batch LS", batch_mse),
        ("RLS", rls_mse),
        ("lattice", lattice_mse),
    ] {
        if !mse.is_finite() {
            return Err(Fail(format!(
                "{name} gives no finite model (no finite prediction error on the evaluation part)"
            )));
        }
    }
    Ok(json!({
        "order": P,
        "lambda": lambda,
        "n_train": n_train,
        "n_eval": n_eval,
        "batch_mse": batch_mse,
        "rls_mse": rls_mse,
        "lattice_mse": lattice_mse,
        "sftf_mse": finite_or_null(sftf_se / sftf_n as f64),
        "sftf_restarts": sftf.health().restarts,
        "reduction_percent": finite_or_null(100.0 * (batch_mse - lattice_mse) / batch_mse),
    }))
}

fn fit_json<const P: usize>(
    method: Method,
    x: &[f64],
    config: &BatchConfig<f64>,
    rate: Option<f64>,
) -> Result<Value, BatchError> {
    let fit = batch_fit::<P>(method, x, config)?;
    let model = &fit.model;
    let mut v = json!({
        "method": method.name(),
        "scalar": "f64",
        "order": P,
        "n": x.len(),
        "mean": model.mean(),
        "a": model.a().to_vec(),
        "noise_variance": model.noise_variance(),
    });
    if let Some(k) = fit.reflection {
        v["reflection"] = json!(k.to_vec());
    }
    if let Some(rate) = rate {
        v["rate_hz"] = json!(rate);
        let a: Vec<f64> = model.a().to_vec();
        gauss_markov_json(&mut v, &a, model.noise_variance(), model.dt());
    }
    Ok(v)
}

fn fit_text(v: &Value) -> String {
    let mut s = format!(
        "{} AR({}) fit of {} samples\nmean {}\na {}\nnoise_variance {}\n",
        v["method"].as_str().unwrap_or(""),
        v["order"],
        v["n"],
        v["mean"],
        v["a"],
        v["noise_variance"]
    );
    if let Some(k) = v.get("reflection") {
        s += &format!("reflection {k}\n");
    }
    // Every count that qualifies the result.
    for key in ["restarts", "non_finite", "saturated", "clipped"] {
        if let Some(c) = v.get(key) {
            s += &format!("{key} {c}\n");
        }
    }
    if let Some(gm) = v.get("gauss_markov") {
        s += &format!(
            "gauss_markov correlation_time_s {} sigma {}\n",
            gm["correlation_time_s"], gm["sigma"]
        );
    }
    s
}

fn order_json<const P: usize>(
    method: Method,
    x: &[f64],
    config: &BatchConfig<f64>,
) -> Result<Value, BatchError> {
    let fit = batch_fit::<P>(method, x, config)?;
    let variances: Vec<f64> = (0..=P)
        .map(|m| fit.innovation_variance(m).unwrap_or(f64::NAN))
        .collect();
    let n = fit.n_effective;
    let keys = ["aic", "aicc", "bic", "fpe"];
    let mut criteria = serde_json::Map::new();
    let mut selected = serde_json::Map::new();
    for (key, c) in keys.iter().zip(Criterion::ALL) {
        let values: Vec<Value> = variances
            .iter()
            .enumerate()
            .map(|(k, &s2)| finite_or_null(c.value(n, k, s2)))
            .collect();
        criteria.insert(key.to_string(), Value::Array(values));
        // An order whose criterion is not finite is no selection (too few samples).
        let best = c.select(n, variances.iter().copied());
        let finite = c.value(n, best, variances[best]).is_finite();
        selected.insert(
            key.to_string(),
            if finite { json!(best) } else { Value::Null },
        );
    }
    Ok(json!({
        "method": method.name(),
        "max_order": P,
        "n": x.len(),
        "criteria": criteria,
        "selected": selected,
    }))
}

fn finite_or_null(v: f64) -> Value {
    if v.is_finite() { json!(v) } else { Value::Null }
}

fn order_text(v: &Value) -> String {
    let mut s = format!(
        "{} orders 0..={} over {} samples\norder aic aicc bic fpe\n",
        v["method"].as_str().unwrap_or(""),
        v["max_order"],
        v["n"]
    );
    let p = v["max_order"].as_u64().unwrap_or(0) as usize;
    for k in 0..=p {
        let cell = |key: &str| v["criteria"][key][k].to_string();
        s += &format!(
            "{k} {} {} {} {}\n",
            cell("aic"),
            cell("aicc"),
            cell("bic"),
            cell("fpe")
        );
    }
    let sel = |key: &str| match &v["selected"][key] {
        Value::Null => "none".to_string(),
        k => k.to_string(),
    };
    s += &format!(
        "selected aic {} aicc {} bic {} fpe {}\n",
        sel("aic"),
        sel("aicc"),
        sel("bic"),
        sel("fpe")
    );
    if v["selected"]
        .as_object()
        .is_some_and(|m| m.values().all(Value::is_null))
    {
        s += "no order selected: every criterion needs more samples\n";
    }
    s
}

/// The settings of `imu-ar simulate`.
struct Simulation<'a> {
    a: &'a [f64],
    a_end: &'a [f64],
    sigma: f64,
    n: usize,
    seed: u64,
    rate: f64,
    burn_in: usize,
}

/// Draws the record: coefficients move linearly from `a` (sample 0) to `a_end` (last sample).
/// The CSV is streamed to stdout (any `--n` runs in constant memory); nothing is written
/// before the settings are checked.
fn simulate<const P: usize>(sim: &Simulation) -> Result<String, Fail> {
    let at =
        |f: f64| -> [f64; P] { core::array::from_fn(|k| sim.a[k] + f * (sim.a_end[k] - sim.a[k])) };
    // Stationary along the path (checked at 101 points).
    let mut gain = 1.0f64;
    for i in 0..=100 {
        let a = at(i as f64 / 100.0);
        let model = ArModel::new(a, 1.0, 0.0, 1.0)?;
        if !model.is_stable() {
            return Err(Fail(format!(
                "--a {:?} / --a-end {:?}: the model is not stationary (a pole on or outside the unit circle)",
                sim.a, sim.a_end
            )));
        }
        gain = gain.max(impulse_l1(&a));
    }
    // |x| <= sigma x max |w| x sum |h_k|; the polar method's variates stay below 13 in
    // magnitude, and a margin of 1e3 covers the drift between the checked points.
    if !(sim.sigma * 13.0 * gain * 1e3).is_finite() {
        return Err(Fail(format!(
            "--sigma {}: too large, the simulated process would overflow f64",
            sim.sigma
        )));
    }
    let mut rng = ChaCha8Rng::seed_from_u64(sim.seed);
    let mut normal = StandardNormal::new();
    let mut past = [0.0f64; P];
    let mut step = |a: &[f64; P], rng: &mut ChaCha8Rng| -> f64 {
        let x = a
            .iter()
            .zip(&past)
            .fold(sim.sigma * normal.sample(rng), |x, (a, p)| x + a * p);
        past.rotate_right(1);
        past[0] = x;
        x
    };
    let start = at(0.0);
    for _ in 0..sim.burn_in {
        step(&start, &mut rng);
    }
    let mut out = BufWriter::new(std::io::stdout().lock());
    let span = sim.n.saturating_sub(1).max(1) as f64;
    let mut write = || -> std::io::Result<()> {
        out.write_all(b"t_s,x\n")?;
        for i in 0..sim.n {
            let x = step(&at(i as f64 / span), &mut rng);
            if !x.is_finite() {
                return Err(std::io::Error::other(format!(
                    "--sigma {}: too large, the simulated process overflows f64 at sample {i}",
                    sim.sigma
                )));
            }
            writeln!(out, "{},{}", i as f64 / sim.rate, x)?;
        }
        out.flush()
    };
    match write() {
        Ok(()) => Ok(String::new()),
        Err(e) if e.kind() == std::io::ErrorKind::Other => Err(Fail(e.to_string())),
        // A closed pipe (`| head`) ends the run quietly.
        Err(e) if e.kind() == std::io::ErrorKind::BrokenPipe => Ok(String::new()),
        Err(e) => Err(Fail(format!("cannot write to stdout: {e}"))),
    }
}

/// `sum |h_k|` of the impulse response of `x[n] = sum a_k x[n-k] + w[n]` (a stable model),
/// over its first 100,000 terms.
fn impulse_l1<const P: usize>(a: &[f64; P]) -> f64 {
    let mut past = [0.0f64; P];
    let mut sum = 0.0;
    for n in 0..100_000 {
        let h = if n == 0 {
            1.0
        } else {
            a.iter().zip(&past).map(|(a, p)| a * p).sum()
        };
        past.rotate_right(1);
        past[0] = h;
        sum += f64::abs(h);
        if n > 10 * P && past.iter().all(|p| p.abs() < 1e-17 * sum) {
            break;
        }
    }
    sum
}
