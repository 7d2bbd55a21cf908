//! The one-step prediction errors that `compare` and `report` evaluate: a batch model fitted on
//! the training part of a record, and RLS, the lattice and the SFTF (`f64`) running over all of
//! it; the evaluation part is the rest of the record.

use imu_ar::ArModel;
use imu_ar::recursive::{Channel, Config, Estimator, Lattice, Rls, Sftf};

use crate::error::Fail;
use crate::input::{Record, check_delta, check_lambda, default_delta};
use crate::method::DEFAULT_LAMBDA;

/// The record and settings of `compare` and `report`.
#[derive(clap::Args)]
pub struct Comparison {
    /// The record and the model order.
    #[command(flatten)]
    pub record: Record,
    /// Forgetting factor, in (0, 1].
    #[arg(long, default_value_t = DEFAULT_LAMBDA, allow_negative_numbers = true)]
    pub lambda: f64,
    /// Initial regularisation [default: as for `fit`].
    #[arg(long, allow_negative_numbers = true)]
    pub delta: Option<f64>,
    /// Average blocks of M samples first (a rate becomes rate / M).
    #[arg(long, default_value_t = 1, allow_negative_numbers = true)]
    pub decimate: usize,
    /// Fraction of the record the batch model is fitted on, in (0, 1).
    #[arg(long, default_value_t = 0.5, allow_negative_numbers = true)]
    pub train: f64,
}

impl Comparison {
    /// Checks the settings, then reads (and decimates) the record; returns it with `delta`.
    pub fn load(&self) -> Result<(Vec<f64>, f64), Fail> {
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
            None => default_delta(&x).map_err(|e| self.record.input.fail(e))?,
        };
        Ok((x, delta))
    }
}

/// The recursive estimators, run over the whole record.
pub struct Estimators<const P: usize> {
    /// Conventional RLS.
    pub rls: Rls<f64, P>,
    /// The EF-LSL lattice.
    pub lattice: Lattice<f64, P>,
    /// The stabilised fast transversal filter.
    pub sftf: Sftf<f64, P>,
}

/// One sample's one-step prediction errors: `None` where an estimator returned none, and for
/// the batch model before its first `P` past samples.
#[derive(Clone, Copy)]
pub struct Errors {
    /// The batch model's.
    pub batch: Option<f64>,
    /// RLS's.
    pub rls: Option<f64>,
    /// The lattice's.
    pub lattice: Option<f64>,
    /// The SFTF's.
    pub sftf: Option<f64>,
}

/// The squared one-step errors of one estimator over the evaluation part.
#[derive(Clone, Copy, Default)]
pub struct SquaredErrors {
    /// Their sum.
    pub sum: f64,
    /// The samples that gave an error.
    pub count: usize,
}

impl SquaredErrors {
    fn add(&mut self, e: Option<f64>) {
        if let Some(e) = e {
            self.sum += e * e;
            self.count += 1;
        }
    }

    /// Their mean over `n` samples, a sample without an error counted as 0.
    pub fn mean(&self, n: usize) -> f64 {
        self.sum / n as f64
    }
}

/// The estimators after the whole record, and each one's squared errors on the evaluation part.
pub struct Evaluation<const P: usize> {
    /// The estimators after the last sample.
    pub estimators: Estimators<P>,
    /// The batch model's squared errors.
    pub batch: SquaredErrors,
    /// RLS's.
    pub rls: SquaredErrors,
    /// The lattice's.
    pub lattice: SquaredErrors,
    /// The SFTF's.
    pub sftf: SquaredErrors,
}

/// Runs RLS, the lattice and the SFTF with `config` and `channel` over `x`, predicts each sample with
/// `batch` from the `P` before it, calls `each(n, errors, estimators)` after every sample,
/// and sums the squared errors from sample `n_train` on.
pub fn predict<const P: usize>(
    x: &[f64],
    n_train: usize,
    batch: &ArModel<f64, P>,
    config: &Config<f64>,
    channel: &Channel<f64>,
    mut each: impl FnMut(usize, &Errors, &Estimators<P>),
) -> Evaluation<P> {
    let mut estimators = Estimators {
        rls: Rls::<f64, P>::new(config, channel),
        lattice: Lattice::<f64, P>::new(config, channel),
        sftf: Sftf::<f64, P>::new(config, channel),
    };
    let none = SquaredErrors::default();
    let [mut b, mut r, mut l, mut s] = [none; 4];
    for (n, &v) in x.iter().enumerate() {
        let errors = Errors {
            batch: (n >= P).then(|| {
                let past: [f64; P] = core::array::from_fn(|k| x[n - 1 - k]);
                v - batch.predict(&past)
            }),
            rls: estimators.rls.update(config, v),
            lattice: estimators.lattice.update(config, v),
            sftf: estimators.sftf.update(config, v),
        };
        if n >= n_train {
            b.add(errors.batch);
            r.add(errors.rls);
            l.add(errors.lattice);
            s.add(errors.sftf);
        }
        each(n, &errors, &estimators);
    }
    Evaluation {
        estimators,
        batch: b,
        rls: r,
        lattice: l,
        sftf: s,
    }
}
