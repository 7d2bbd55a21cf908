//! `imu-ar simulate`: an AR process, optionally with drifting coefficients, as CSV `t_s,x` on
//! stdout.

use std::io::{BufWriter, Write};

use imu_ar::ArModel;
use imu_ar::sim::StandardNormal;
use rand_chacha::ChaCha8Rng;
use rand_core::SeedableRng;

use crate::error::Fail;
use crate::input::{check_order, check_rate, check_span};
use crate::method::with_order;

/// The arguments of `imu-ar simulate`.
#[derive(clap::Args)]
pub struct Args {
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
    #[arg(long, allow_negative_numbers = true)]
    n: usize,
    /// Seed of the ChaCha8 generator.
    #[arg(long, allow_negative_numbers = true)]
    seed: u64,
    /// Sample rate in Hz.
    #[arg(long, default_value_t = 1.0, allow_negative_numbers = true)]
    rate: f64,
    /// Samples drawn and discarded first.
    #[arg(long, default_value_t = 1000, allow_negative_numbers = true)]
    burn_in: usize,
    /// Coefficients at the last sample: they move linearly from `--a` to these over the
    /// record (a drifting process; burn-in uses `--a`).
    #[arg(long, value_delimiter = ',', allow_negative_numbers = true)]
    a_end: Option<Vec<f64>>,
}

/// Checks the settings and streams the record to stdout.
///
/// The process is drawn here rather than by `imu_ar::sim::ArSimulator`, which holds its
/// coefficients fixed (no `--a-end`) and keeps the innovation as a variance (`--sigma` 1e200
/// would overflow it).
pub fn run(args: &Args) -> Result<(), Fail> {
    let Args {
        ref a,
        sigma,
        n,
        seed,
        rate,
        burn_in,
        ref a_end,
    } = *args;
    check_order("--a (number of coefficients)", a.len())?;
    let rate = check_rate(rate)?;
    check_span("--rate", rate, n)?;
    if !(sigma.is_finite() && sigma >= 0.0) {
        return Err(Fail(format!("--sigma {sigma}: must be finite and >= 0")));
    }
    let a_end = a_end.as_ref().unwrap_or(a);
    if a_end.len() != a.len() {
        return Err(Fail(format!(
            "--a-end has {} coefficients, --a has {}",
            a_end.len(),
            a.len()
        )));
    }
    let sim = Simulation {
        a,
        a_end,
        sigma,
        n,
        seed,
        rate,
        burn_in,
    };
    with_order!(a.len(), simulate(&sim))
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
fn simulate<const P: usize>(sim: &Simulation) -> Result<(), Fail> {
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
        Ok(()) => Ok(()),
        Err(e) if e.kind() == std::io::ErrorKind::Other => Err(Fail(e.to_string())),
        // A closed pipe (`| head`) ends the run quietly.
        Err(e) if e.kind() == std::io::ErrorKind::BrokenPipe => Ok(()),
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
