//! `imu-ar order`: the order criteria (AIC, AICc, BIC, FPE) of orders `0..=P`.

use imu_ar::batch::criteria::Criterion;
use imu_ar::batch::{BatchConfig, BatchError};
use serde::Serialize;

use crate::error::Fail;
use crate::input::{Input, check_order};
use crate::method::{Method, batch_fit, with_order};
use crate::output::{Output, finite, json};

/// The arguments of `imu-ar order`.
#[derive(clap::Args)]
pub struct Args {
    /// The column.
    #[command(flatten)]
    input: Input,
    /// Highest order, 1 to 32.
    #[arg(long, allow_negative_numbers = true)]
    max_order: usize,
    /// Estimator.
    #[arg(long, value_enum)]
    method: Method,
    /// Fit the data as they are, without removing the sample mean.
    #[arg(long)]
    no_demean: bool,
    /// Print one JSON object.
    #[arg(long)]
    pub json: bool,
}

/// One value per criterion.
#[derive(Serialize)]
pub struct Criteria<T> {
    /// Akaike's information criterion.
    pub aic: T,
    /// AIC with the small-sample correction.
    pub aicc: T,
    /// Schwarz's Bayesian criterion.
    pub bic: T,
    /// Akaike's final prediction error.
    pub fpe: T,
}

impl<T> Criteria<T> {
    /// `f` of each criterion.
    fn from_fn(f: impl FnMut(Criterion) -> T) -> Self {
        let [aic, aicc, bic, fpe] = Criterion::ALL.map(f);
        Self {
            aic,
            aicc,
            bic,
            fpe,
        }
    }

    /// The four values, in the order of the table.
    fn all(&self) -> [&T; 4] {
        [&self.aic, &self.aicc, &self.bic, &self.fpe]
    }
}

/// The criteria of orders `0..=max_order`, and the order each selects.
#[derive(Serialize)]
pub struct OrderResult {
    /// The batch estimator.
    pub method: &'static str,
    /// The highest order.
    pub max_order: usize,
    /// Samples in the record.
    pub n: usize,
    /// Each criterion at orders `0..=max_order` (`None` where it is undefined).
    pub criteria: Criteria<Vec<Option<f64>>>,
    /// The order each criterion selects (`None`: no order, too few samples).
    pub selected: Criteria<Option<usize>>,
}

impl Output for OrderResult {
    fn text(&self) -> String {
        let mut s = format!(
            "{} orders 0..={} over {} samples\norder aic aicc bic fpe\n",
            self.method, self.max_order, self.n
        );
        for k in 0..=self.max_order {
            let [aic, aicc, bic, fpe] = self.criteria.all().map(|c| json(&c[k]));
            s += &format!("{k} {aic} {aicc} {bic} {fpe}\n");
        }
        let [aic, aicc, bic, fpe] = self.selected.all().map(|k| match k {
            Some(k) => k.to_string(),
            None => "none".to_string(),
        });
        s += &format!("selected aic {aic} aicc {aicc} bic {bic} fpe {fpe}\n");
        if self.selected.all().iter().all(|k| k.is_none()) {
            s += "no order selected: every criterion needs more samples\n";
        }
        s
    }
}

/// Checks the settings, reads the record and evaluates the criteria.
pub fn run(args: &Args) -> Result<OrderResult, Fail> {
    run_with(args, None)
}

/// [`run`] on the samples `given` (the Python package's arrays) in place of the files'.
pub fn run_with(args: &Args, given: Option<&[f64]>) -> Result<OrderResult, Fail> {
    check_order("--max-order", args.max_order)?;
    if args.method.recursive() {
        return Err(Fail(format!(
            "--method {}: order criteria need a batch method (ls, yule-walker, burg)",
            args.method.name()
        )));
    }
    let x = match given {
        Some(x) => x.to_vec(),
        None => args.input.read()?,
    };
    let config = BatchConfig::new(1.0)?.with_demean(!args.no_demean);
    with_order!(args.max_order, criteria(args.method, &x, &config)).map_err(|e| args.input.fail(e))
}

/// The criteria of the orders `0..=P` of one fit of order `P`.
fn criteria<const P: usize>(
    method: Method,
    x: &[f64],
    config: &BatchConfig<f64>,
) -> Result<OrderResult, BatchError> {
    let fit = batch_fit::<P>(method, x, config)?;
    let variances: Vec<f64> = (0..=P)
        .map(|m| fit.innovation_variance(m).unwrap_or(f64::NAN))
        .collect();
    let n = fit.n_effective;
    Ok(OrderResult {
        method: method.name(),
        max_order: P,
        n: x.len(),
        criteria: Criteria::from_fn(|c| {
            let values = variances.iter().enumerate();
            values.map(|(k, &s2)| finite(c.value(n, k, s2))).collect()
        }),
        // An order whose criterion is not finite is no selection (too few samples).
        selected: Criteria::from_fn(|c| {
            let best = c.select(n, variances.iter().copied());
            c.value(n, best, variances[best])
                .is_finite()
                .then_some(best)
        }),
    })
}
