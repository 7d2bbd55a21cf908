//! What the commands share about the estimators: the methods and scalars of the command line,
//! the batch fit, the orders the tool is built for, and the Gauss-Markov form of an AR(1).

use clap::ValueEnum;
use imu_ar::ArModel;
use imu_ar::batch::{BatchConfig, BatchError, Fit, burg, covariance, yule_walker};
use imu_ar::model::GaussMarkov as Gm;
use serde::Serialize;

use crate::output::json;

/// The highest model order the tool accepts.
pub const MAX_ORDER: usize = 32;

/// The default forgetting factor of the recursive methods.
pub const DEFAULT_LAMBDA: f64 = 0.999;

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
pub(crate) use with_order;

/// An estimator of `--method`.
#[derive(Clone, Copy, ValueEnum)]
pub enum Method {
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
    /// The name on the command line and in the output.
    pub fn name(self) -> &'static str {
        match self {
            Method::Ls => "ls",
            Method::YuleWalker => "yule-walker",
            Method::Burg => "burg",
            Method::Rls => "rls",
            Method::Lattice => "lattice",
            Method::Sftf => "sftf",
        }
    }

    /// Whether the method is recursive (reports the model after the last sample).
    pub fn recursive(self) -> bool {
        matches!(self, Method::Rls | Method::Lattice | Method::Sftf)
    }
}

/// The arithmetic of `--scalar`.
#[derive(Clone, Copy, ValueEnum)]
pub enum ScalarKind {
    // The two float types say what they are; a doc comment would become `--help` text.
    #[allow(missing_docs)]
    F64,
    #[allow(missing_docs)]
    F32,
    /// The fixed-point lattice (`--method lattice` only).
    Fixed,
}

impl ScalarKind {
    /// The name on the command line and in the output.
    pub fn name(self) -> &'static str {
        match self {
            ScalarKind::F64 => "f64",
            ScalarKind::F32 => "f32",
            ScalarKind::Fixed => "fixed",
        }
    }
}

/// The batch fit of `x` by `method` (`ls`, `yule-walker` or `burg`).
pub fn batch_fit<const P: usize>(
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

/// The Gauss-Markov form of an AR(1) with `0 < a_1 < 1`, as `fit` and `kalman` print it.
#[derive(Serialize)]
pub struct GaussMarkov {
    /// Correlation time in s.
    pub correlation_time_s: f64,
    /// Standard deviation of the process.
    pub sigma: f64,
    /// PSD of the driving white noise (`kalman` only).
    #[serde(skip_serializing_if = "Option::is_none")]
    pub driving_psd: Option<f64>,
}

impl GaussMarkov {
    /// The form of `x[n] = a_1 x[n-1] + w[n]` sampled every `dt` s, when `a` is one
    /// coefficient in (0, 1).
    pub fn of(a: &[f64], noise_variance: f64, dt: f64) -> Option<Self> {
        let [a1] = a else { return None };
        let gm = ArModel::new([*a1], noise_variance, 0.0, dt)
            .ok()?
            .to_gauss_markov()
            .ok()?;
        Some(Self::from(&gm))
    }

    /// The line of the text output.
    pub fn text(&self) -> String {
        format!(
            "gauss_markov correlation_time_s {} sigma {}\n",
            json(&self.correlation_time_s),
            json(&self.sigma)
        )
    }
}

impl From<&Gm<f64>> for GaussMarkov {
    fn from(gm: &Gm<f64>) -> Self {
        Self {
            correlation_time_s: gm.correlation_time(),
            sigma: gm.sigma(),
            driving_psd: None,
        }
    }
}
