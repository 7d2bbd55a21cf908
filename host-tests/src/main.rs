//! `imu-ar`: characterise a recorded sensor log with the library's estimators.
//!
//! ```text
//! imu-ar fit FILE.. --column C --method ls|yule-walker|burg --order P [--no-demean] [--rate HZ] [--json]
//! imu-ar order FILE.. --column C --max-order P --method ls|yule-walker|burg [--no-demean] [--json]
//! imu-ar adev FILE.. --column C --rate HZ [--json]
//! imu-ar simulate --a A1,A2,.. --sigma S --n N --seed K [--rate HZ] [--burn-in B]
//! ```
//!
//! Several files are read as one record, in order. Bad input exits with status 2 and one line
//! on stderr naming the file, line and problem; nothing is written to stdout.

use std::io::{BufWriter, Write};
use std::path::PathBuf;
use std::process::ExitCode;

use clap::{Parser, Subcommand, ValueEnum};
use imu_ar::allan::overlapping_avar;
use imu_ar::batch::criteria::Criterion;
use imu_ar::batch::{BatchConfig, BatchError, Fit, burg, covariance, yule_walker};
use imu_ar::sim::ArSimulator;
use imu_ar::{ArModel, Scalar};
use imu_ar_host::data::read_column;
use rand_chacha::ChaCha8Rng;
use rand_core::SeedableRng;
use serde_json::{Value, json};

/// The highest model order the tool accepts.
const MAX_ORDER: usize = 32;

/// Calls `$f::<P>($args..)` with the const `P` equal to the runtime order `$p` (1..=32).
macro_rules! with_order {
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
enum Method {
    /// Covariance method (conditional least squares).
    Ls,
    /// Yule-Walker (biased autocovariance, Levinson-Durbin).
    YuleWalker,
    /// Burg.
    Burg,
}

impl Method {
    fn name(self) -> &'static str {
        match self {
            Method::Ls => "ls",
            Method::YuleWalker => "yule-walker",
            Method::Burg => "burg",
        }
    }
}

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
        /// Fit the data as they are, without removing the sample mean.
        #[arg(long)]
        no_demean: bool,
        /// Sample rate in Hz; gives the model its time scale.
        #[arg(long, allow_negative_numbers = true)]
        rate: Option<f64>,
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
    },
}

/// A one-line error for stderr; the tool exits with status 2.
struct Fail(String);

impl<E: std::fmt::Display> From<E> for Fail {
    fn from(e: E) -> Self {
        Fail(e.to_string())
    }
}

fn main() -> ExitCode {
    let cli = match Cli::try_parse() {
        Ok(cli) => cli,
        Err(e) if !e.use_stderr() => {
            print!("{e}");
            return ExitCode::SUCCESS;
        }
        Err(e) => {
            let text = e.to_string();
            let first = text.lines().next().unwrap_or("invalid arguments");
            eprintln!("imu-ar: {}", first.trim_start_matches("error: "));
            return ExitCode::from(2);
        }
    };
    match run(cli.command) {
        Ok(out) => {
            let mut stdout = BufWriter::new(std::io::stdout().lock());
            if stdout
                .write_all(out.as_bytes())
                .and_then(|_| stdout.flush())
                .is_err()
            {
                return ExitCode::FAILURE;
            }
            ExitCode::SUCCESS
        }
        Err(Fail(msg)) => {
            eprintln!("imu-ar: {msg}");
            ExitCode::from(2)
        }
    }
}

/// Runs a command and returns everything it prints, so that a failure prints nothing.
fn run(command: Command) -> Result<String, Fail> {
    match command {
        Command::Fit {
            files,
            column,
            method,
            order,
            no_demean,
            rate,
            json,
        } => {
            check_order("--order", order)?;
            let dt = match rate {
                Some(r) => 1.0 / check_rate(r)?,
                None => 1.0,
            };
            let x = read_column(&files, &column)?;
            let config = BatchConfig::new(dt)?.with_demean(!no_demean);
            let fit = with_order!(order, fit_json(method, &x, &config, rate))
                .map_err(|e| with_file(&files, e))?;
            Ok(if json {
                format!("{fit}\n")
            } else {
                fit_text(&fit)
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
        Command::Simulate {
            a,
            sigma,
            n,
            seed,
            rate,
            burn_in,
        } => {
            check_order("--a (number of coefficients)", a.len())?;
            let rate = check_rate(rate)?;
            if !(sigma.is_finite() && sigma >= 0.0) {
                return Err(Fail(format!("--sigma {sigma}: must be finite and >= 0")));
            }
            with_order!(a.len(), simulate(&a, sigma, n, seed, rate, burn_in))
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

fn check_rate(rate: f64) -> Result<f64, Fail> {
    if !(rate.is_finite() && rate > 0.0) {
        return Err(Fail(format!(
            "--rate {rate}: must be a positive number of Hz"
        )));
    }
    Ok(rate)
}

fn with_file(files: &[PathBuf], e: impl std::fmt::Display) -> Fail {
    let names: Vec<String> = files.iter().map(|f| f.display().to_string()).collect();
    Fail(format!("{}: {e}", names.join("+")))
}

fn batch_fit<const P: usize>(
    method: Method,
    x: &[f64],
    config: &BatchConfig<f64>,
) -> Result<Fit<f64, P>, BatchError> {
    match method {
        Method::Ls => covariance::<f64, P>(x, config),
        Method::YuleWalker => yule_walker::<f64, P>(x, config),
        Method::Burg => burg::<f64, P>(x, config),
    }
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
        if P == 1 {
            let ar1 = ArModel::new(
                [model.a()[0]],
                model.noise_variance(),
                model.mean(),
                model.dt(),
            )
            .expect("a fitted model is valid");
            if let Ok(gm) = ar1.to_gauss_markov() {
                v["gauss_markov"] = json!({
                    "correlation_time_s": gm.correlation_time(),
                    "sigma": gm.sigma(),
                });
            }
        }
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
        selected.insert(
            key.to_string(),
            json!(c.select(n, variances.iter().copied())),
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
    let sel = &v["selected"];
    s += &format!(
        "selected aic {} aicc {} bic {} fpe {}\n",
        sel["aic"], sel["aicc"], sel["bic"], sel["fpe"]
    );
    s
}

fn simulate<const P: usize>(
    a: &[f64],
    sigma: f64,
    n: usize,
    seed: u64,
    rate: f64,
    burn_in: usize,
) -> Result<String, Fail> {
    let coeffs: [f64; P] = core::array::from_fn(|k| a[k]);
    let model = ArModel::new(coeffs, sigma * sigma, 0.0, 1.0 / rate)?;
    if !model.is_stable() {
        return Err(Fail(format!(
            "--a {a:?}: the model is not stationary (a pole on or outside the unit circle)"
        )));
    }
    let mut sim = ArSimulator::new(model);
    let mut rng = ChaCha8Rng::seed_from_u64(seed);
    sim.burn_in(&mut rng, burn_in);
    let mut s = String::with_capacity(24 * n + 8);
    s += "t_s,x\n";
    for i in 0..n {
        let x: f64 = sim.next(&mut rng);
        s += &format!("{},{}\n", i as f64 / rate, Scalar::to_f64(x));
    }
    Ok(s)
}
