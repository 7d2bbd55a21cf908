//! `imu-ar compare`: the one-step prediction error, on the evaluation part, of a batch LS fit on
//! the training part against RLS, the lattice and the SFTF running over the whole record.

use imu_ar::batch::{BatchConfig, BatchError, covariance};
use imu_ar::recursive::{Channel, Config, Estimator};
use serde::Serialize;

use crate::error::Fail;
use crate::method::with_order;
use crate::output::{Output, finite, json};
use crate::predict::{Comparison, SquaredErrors, predict};

/// The arguments of `imu-ar compare`.
#[derive(clap::Args)]
pub struct Args {
    /// The record and the settings.
    #[command(flatten)]
    run: Comparison,
    /// Print one JSON object.
    #[arg(long)]
    pub json: bool,
}

/// The one-step prediction MSE of each estimator on the evaluation part.
#[derive(Serialize)]
pub struct CompareResult {
    /// The model order.
    pub order: usize,
    /// The forgetting factor of the recursive estimators.
    pub lambda: f64,
    /// Samples averaged into one (`--decimate`).
    pub decimate: usize,
    /// Samples in the training part.
    pub n_train: usize,
    /// Samples in the evaluation part.
    pub n_eval: usize,
    /// The batch LS model's MSE.
    pub batch_mse: f64,
    /// RLS's.
    pub rls_mse: f64,
    /// The lattice's.
    pub lattice_mse: f64,
    /// The SFTF's, over the samples it returned an error for (all but its rescues).
    pub sftf_mse: Option<f64>,
    /// The SFTF's rescues.
    pub sftf_restarts: u64,
    /// The lattice's MSE below the batch model's, in percent (`None` for a batch MSE of 0).
    pub reduction_percent: Option<f64>,
}

impl Output for CompareResult {
    fn text(&self) -> String {
        format!(
            "AR({}), lambda {}: training {} samples, evaluation {}\n\
             one-step prediction MSE: batch LS {}, RLS {}, lattice {}, SFTF {} ({} rescues)\n\
             lattice against batch: {}\n",
            self.order,
            self.lambda,
            self.n_train,
            self.n_eval,
            json(&self.batch_mse),
            json(&self.rls_mse),
            json(&self.lattice_mse),
            json(&self.sftf_mse),
            self.sftf_restarts,
            reduction_text(self.reduction_percent)
        )
    }
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

/// Checks the settings, reads the record and compares the estimators on it.
pub fn run(args: &Args) -> Result<CompareResult, Fail> {
    let run = &args.run;
    let (x, delta) = run.load()?;
    let (lambda, train, decimate) = (run.lambda, run.train, run.decimate);
    with_order!(
        run.record.order,
        compare(&x, lambda, delta, train, decimate)
    )
    .map_err(|Fail(e)| run.record.input.fail(e))
}

/// One-step prediction MSE on the evaluation part `x[n_train..]`: batch LS fitted on
/// `x[..n_train]`, RLS, lattice and SFTF (f64) running over the whole record. The SFTF's MSE
/// is over the samples it returned an error for (all but its rescues, `sftf_restarts`).
fn compare<const P: usize>(
    x: &[f64],
    lambda: f64,
    delta: f64,
    train: f64,
    decimate: usize,
) -> Result<CompareResult, Fail> {
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
    let (config, channel) = (Config::new(lambda, 1.0)?, Channel::new(delta)?);
    let eval = predict(x, n_train, &batch, &config, &channel, |_, _, _| {});
    // An estimator that returned no error for a sample has no MSE.
    let mse = |s: SquaredErrors| {
        if s.count == n_eval {
            s.mean(n_eval)
        } else {
            f64::NAN
        }
    };
    let (batch_mse, rls_mse, lattice_mse) = (mse(eval.batch), mse(eval.rls), mse(eval.lattice));
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
    Ok(CompareResult {
        order: P,
        lambda,
        decimate,
        n_train,
        n_eval,
        batch_mse,
        rls_mse,
        lattice_mse,
        sftf_mse: finite(eval.sftf.mean(eval.sftf.count)),
        sftf_restarts: eval.estimators.sftf.health().restarts,
        reduction_percent: finite(100.0 * (batch_mse - lattice_mse) / batch_mse),
    })
}
