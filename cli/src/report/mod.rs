//! `imu-ar report`: the paper's comparison on one record, in four PNG plots and a JSON summary;
//! with `--prior-a`, a fifth: a lattice from that prior against the plain start.

mod plot;

use std::path::{Path, PathBuf};

use imu_ar::batch::{BatchConfig, covariance};
use imu_ar::recursive::{Channel, Config, Estimator, Lattice};
use serde::Serialize;

use crate::chart::font;
use crate::error::Fail;
use crate::input::{Prior, check_rate, check_span, csv};
use crate::method::with_order;
use crate::output::finite;
use crate::predict::{Comparison, predict};
use plot::{adev_png, coefficients_png, error_png, prior_png, psd_png};

/// The arguments of `imu-ar report`.
#[derive(clap::Args)]
#[command(mut_arg("prior_a", |a| a.help(
    "Also run a lattice from this model, a_1,..,a_P (its regularisation centred on it, \
     `delta lambda^n (a - a0)^T D (a - a0)`), and draw it against the plain start in prior.png"
)))]
pub struct Args {
    /// The record and the settings.
    #[command(flatten)]
    run: Comparison,
    /// A prior to start a second lattice from.
    #[command(flatten)]
    prior: Prior,
    /// Sample rate in Hz of the raw record.
    #[arg(long, allow_negative_numbers = true)]
    rate: f64,
    /// A published Allan table to draw too: CSV with `channel`, `tau_s` and `adev`
    /// columns (`-` is standard input); the rows of channel `--column` are used.
    #[arg(long)]
    reference: Option<PathBuf>,
    /// Directory for the PNG files (created if needed).
    #[arg(long)]
    out: PathBuf,
}

/// The summary of a report, printed as JSON: the comparison of `compare` on the record, and
/// the plots written.
#[derive(Serialize)]
pub struct Summary {
    /// The model order.
    pub order: usize,
    /// The forgetting factor of the recursive estimators.
    pub lambda: f64,
    /// The rate in Hz of the record after `--decimate`.
    pub rate_hz: f64,
    /// Samples in the record after `--decimate`.
    pub n: usize,
    /// Samples in the training part.
    pub n_train: usize,
    /// The batch LS model's one-step prediction MSE on the evaluation part.
    pub batch_mse: f64,
    /// RLS's.
    pub rls_mse: f64,
    /// The lattice's.
    pub lattice_mse: f64,
    /// The SFTF's, over the samples it returned an error for (all but its rescues).
    pub sftf_mse: Option<f64>,
    /// The SFTF's rescues.
    pub sftf_restarts: u64,
    /// The lattice's MSE below the batch model's, in percent.
    pub reduction_percent: f64,
    /// The batch model's coefficients.
    pub batch_a: Vec<f64>,
    /// The lattice's after the last sample.
    pub lattice_a: Option<Vec<f64>>,
    /// The lattice's from `--prior-a` after the last sample.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub prior_lattice_a: Option<Vec<f64>>,
    /// The PNG files.
    pub files: Vec<String>,
}

/// Checks the settings, reads the record, and writes the plots.
pub fn run(args: &Args) -> Result<Summary, Fail> {
    check_out(&args.out)?;
    let run = &args.run;
    let rate = check_rate(args.rate)? / run.decimate.max(1) as f64;
    let prior_a = args.prior.check(run.record.order)?;
    let reference = match &args.reference {
        Some(path) => Some(read_reference(path, &run.record.input.column)?),
        None => None,
    };
    let (x, delta) = run.load()?;
    check_span(
        "--rate",
        rate * run.decimate.max(1) as f64,
        x.len() * run.decimate.max(1),
    )?;
    let r = Report {
        x: &x,
        rate,
        lambda: run.lambda,
        delta,
        train: run.train,
        unit: run.record.input.unit.as_deref().unwrap_or("units"),
        reference,
        prior: prior_a.map(|a| (a, args.prior.prior_weight.unwrap_or(delta))),
    };
    let (mut summary, draw) =
        with_order!(run.record.order, report(&r)).map_err(|Fail(e)| run.record.input.fail(e))?;
    // All the plots or none, as characterise writes its files.
    summary.files = crate::characterise::write_staged(&args.out, &[], &*draw)?;
    Ok(summary)
}

/// Whether `out` can be a directory: it is one, or its nearest existing ancestor is one.
/// Checked before the input is read, so that its error names the output, not the input;
/// the directory itself is made only once the input has passed every check.
fn check_out(out: &Path) -> Result<(), Fail> {
    let blocked = out
        .ancestors()
        .filter(|p| !p.as_os_str().is_empty())
        .find(|p| p.exists())
        .filter(|p| !p.is_dir());
    match blocked {
        Some(p) if p == out => Err(Fail(format!(
            "{}: cannot create: it exists and is not a directory",
            out.display()
        ))),
        Some(p) => Err(Fail(format!(
            "{}: cannot create: {} is not a directory",
            out.display(),
            p.display()
        ))),
        None => Ok(()),
    }
}

/// `(tau_s, adev)` of `channel` from a published Allan table.
fn read_reference(path: &Path, channel: &str) -> Result<Vec<(f64, f64)>, Fail> {
    let files = [path.to_path_buf()];
    let channels = csv::read_text_column(&files, "channel")?;
    let tau = csv::read_column(&files, "tau_s")?;
    let adev = csv::read_column(&files, "adev")?;
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

/// What the report shows and where it goes.
struct Report<'a> {
    /// The record (already decimated), in sensor units.
    x: &'a [f64],
    /// Sample rate of `x` in Hz.
    rate: f64,
    lambda: f64,
    delta: f64,
    /// Fraction of the record the batch model is fitted on.
    train: f64,
    /// The sensor unit, for the axis labels.
    unit: &'a str,
    /// Published Allan deviations `(tau_s, adev)` to draw with the data's.
    reference: Option<Vec<(f64, f64)>>,
    /// `--prior-a` and its weight, the `delta` of the lattice that starts from it.
    prior: Option<(&'a [f64], f64)>,
}

/// Fewest samples a report is drawn from: enough for a periodogram of 8-sample segments.
const MIN_SAMPLES: usize = 64;

/// Coefficients `a_1..a_P` at sampled times (s).
type Track<const P: usize> = Vec<(f64, [f64; P])>;
/// Points per drawn time series: the plots stay small and readable for any record length.
const POINTS: usize = 400;
/// Samples of the start that prior.png draws one by one.
const HEAD: usize = 1000;

/// The lattice from `--prior-a`, run next to the plain one, and what prior.png draws of both.
struct FromPrior<const P: usize> {
    lattice: Lattice<f64, P>,
    /// The prior `a0`.
    a0: [f64; P],
    /// The weight of the prior (the lattice's `delta`).
    weight: f64,
    /// The first [`HEAD`] samples, every one, from time 0: the plain lattice's coefficients
    /// and this one's.
    head: (Track<P>, Track<P>),
    /// This lattice's coefficients over the whole record, sampled as the plain one's.
    whole: Track<P>,
}

impl<const P: usize> FromPrior<P> {
    /// The lattice from `a0` with weight `weight`, and the plain one's start next to it.
    fn new(
        config: &Config<f64>,
        channel: &Channel<f64>,
        a0: &[f64],
        weight: f64,
    ) -> Result<Self, Fail> {
        let a0: [f64; P] = core::array::from_fn(|k| a0[k]);
        let lattice = Lattice::<f64, P>::with_prior(config, &Channel::new(weight)?, &a0)?;
        let start = |l: &Lattice<f64, P>| (0.0, l.coefficients(P).unwrap_or([f64::NAN; P]));
        let plain = Lattice::<f64, P>::new(config, channel);
        Ok(Self {
            head: (vec![start(&plain)], vec![start(&lattice)]),
            whole: Vec::new(),
            lattice,
            a0,
            weight,
        })
    }
}

/// The plots of a report, drawn into a folder: their paths.
type Draw<'r> = Box<dyn Fn(&Path) -> Result<Vec<PathBuf>, Fail> + 'r>;

/// The summary (its files left empty), and what draws the four PNGs (five with a prior).
fn report<'r, const P: usize>(r: &'r Report) -> Result<(Summary, Draw<'r>), Fail> {
    let x = r.x;
    if x.len() < MIN_SAMPLES {
        return Err(Fail(format!(
            "report needs at least {MIN_SAMPLES} samples (after --decimate), not {}",
            x.len()
        )));
    }
    font()?;
    let dt = 1.0 / r.rate;
    let n_train = (r.train * x.len() as f64) as usize;
    let batch_config = BatchConfig::new(dt)?;
    let train_fit = covariance::<f64, P>(&x[..n_train], &batch_config)?.model;
    let whole_fit = covariance::<f64, P>(x, &batch_config)?.model;

    // The recursive estimators over the whole record; their errors and coefficients sampled.
    let (config, channel) = (Config::new(r.lambda, dt)?, Channel::new(r.delta)?);
    let stride = (x.len() / POINTS).max(1);
    let mut coef = (Vec::new(), Vec::new());
    let mut se = [vec![], vec![], vec![]];
    let mut block = [0.0; 3];
    let mut missing = 0usize;
    let mut from_prior = match r.prior {
        Some((a0, weight)) => Some(FromPrior::<P>::new(&config, &channel, a0, weight)?),
        None => None,
    };
    let mut eval = predict(x, n_train, &train_fit, &config, &channel, |n, e, est| {
        if n >= n_train && (e.rls.is_none() || e.lattice.is_none()) {
            missing += 1;
        }
        for (k, e) in [e.batch, e.rls, e.lattice].into_iter().enumerate() {
            let e = e.unwrap_or(0.0);
            block[k] += e * e;
        }
        if (n + 1) % stride == 0 {
            let t = (n + 1) as f64 * dt;
            for (k, b) in block.iter_mut().enumerate() {
                se[k].push((t, *b / stride as f64));
                *b = 0.0;
            }
            let a_lattice = est.lattice.coefficients(P).unwrap_or([f64::NAN; P]);
            coef.0.push((t, *est.rls.coefficients()));
            coef.1.push((t, a_lattice));
        }
        if let Some(p) = &mut from_prior {
            p.lattice.update(&config, x[n]);
            let (head, sampled) = (n < HEAD, (n + 1) % stride == 0);
            if head || sampled {
                let t = (n + 1) as f64 * dt;
                let a = p.lattice.coefficients(P).unwrap_or([f64::NAN; P]);
                if head {
                    let a_plain = est.lattice.coefficients(P).unwrap_or([f64::NAN; P]);
                    p.head.0.push((t, a_plain));
                    p.head.1.push((t, a));
                }
                if sampled {
                    p.whole.push((t, a));
                }
            }
        }
    });
    let m = x.len() - n_train;
    let mse = [eval.batch, eval.rls, eval.lattice].map(|s| s.mean(m));
    // An estimator that broke down (no error, counted as 0 above, on most samples) is no
    // result.
    let (rls, lattice) = (&mut eval.estimators.rls, &mut eval.estimators.lattice);
    let modelled = rls.model(&config).is_some() && lattice.model(&config).is_some();
    if !modelled || mse.iter().any(|v| !v.is_finite()) || 2 * missing > x.len() - n_train {
        return Err(Fail(
            "RLS or the lattice gives no finite model (no finite prediction error on the \
             evaluation part)"
                .into(),
        ));
    }

    let prior_lattice_a = match &from_prior {
        Some(p) => Some(
            p.lattice
                .coefficients(P)
                .map(|a| a.to_vec())
                .ok_or_else(|| Fail("the lattice from --prior-a gives no finite model".into()))?,
        ),
        None => None,
    };
    let summary = Summary {
        order: P,
        lambda: r.lambda,
        rate_hz: r.rate,
        n: x.len(),
        n_train,
        batch_mse: mse[0],
        rls_mse: mse[1],
        lattice_mse: mse[2],
        sftf_mse: finite(eval.sftf.mean(eval.sftf.count)),
        sftf_restarts: eval.estimators.sftf.health().restarts,
        reduction_percent: 100.0 * (mse[0] - mse[2]) / mse[0],
        batch_a: train_fit.a().to_vec(),
        lattice_a: lattice.coefficients(P).map(|a| a.to_vec()),
        prior_lattice_a,
        files: Vec::new(),
    };
    let t_train = n_train as f64 * dt;
    let draw = move |dir: &Path| {
        let mut files = vec![
            coefficients_png::<P>(r, dir, &coef, &train_fit)?,
            error_png(r, dir, &se, &mse, t_train)?,
            psd_png(r, dir, &whole_fit)?,
            adev_png(r, dir, &whole_fit)?,
        ];
        if let Some(p) = &from_prior {
            files.push(prior_png(r, dir, p, &coef.1)?);
        }
        Ok(files)
    };
    Ok((summary, Box::new(draw)))
}
