//! The one interface of every recursive estimator.

use super::shell::{Format, Health, Shell};
use crate::{ArModel, Scalar};

/// What the estimators are built on; not for implementation outside this crate.
pub(crate) mod sealed {
    use super::{Format, Shell};

    /// The parts of an estimator the [`Estimator`](super::Estimator) methods read.
    pub trait Sealed<T, const P: usize> {
        /// The number formats of its shell.
        type Format: Format<Out = T>;
        /// Its shell.
        fn shell(&self) -> &Shell<Self::Format, P>;
        /// Its order-`P` energy (`F_P`, `E_n` or `alpha_n`).
        fn energy(&self) -> <Self::Format as Format>::Energy;
        /// The order-`P` coefficients of its current state.
        fn current(&self) -> Option<[T; P]>;
    }

    /// The settings an estimator's `update` and `model` take.
    pub trait Settings<T> {
        /// The sample interval, in seconds.
        fn dt(&self) -> T;
    }
}

impl<T: Scalar> sealed::Settings<T> for super::Config<T> {
    fn dt(&self) -> T {
        super::Config::dt(self)
    }
}

/// A recursive AR estimator of order `P` on one channel: one sample in, the a-priori
/// prediction error out, and an [`ArModel`] in `T` on request.
///
/// Implemented by the float estimators [`Lattice`](super::Lattice), [`Rls`](super::Rls) and
/// [`Sftf`](super::Sftf) (`T` = `f32` or `f64`, [`Config<T>`](super::Config) shared by the
/// channels) and by the fixed-point [`FixedLattice`](super::FixedLattice) (`T = f32`, a
/// [`FixedConfig`](super::FixedConfig)); sealed, so that its contract stays theirs. Each
/// estimator is made from the shared configuration and its own
/// [`Channel`](super::Channel) (or [`FixedChannel`](super::FixedChannel)), which it keeps;
/// `update` and `model` take the shared configuration, so six axes keep one copy of it.
///
/// Code written against the trait runs every estimator:
///
/// ```
/// use imu_ar::recursive::{Channel, Config, Estimator, FixedChannel, FixedConfig};
/// use imu_ar::recursive::{FixedLattice, Lattice, Rls, Sftf};
///
/// /// The order-1 coefficient after 5000 samples of an AR(1) with `a_1 = 0.5`.
/// fn a1<E: Estimator<f32, 1>>(mut e: E, config: &E::Config) -> f32 {
///     let (mut x, mut seed) = (0.0f32, 1u32);
///     for _ in 0..5000 {
///         seed = seed.wrapping_mul(1_664_525).wrapping_add(1_013_904_223);
///         x = 0.5 * x + ((seed >> 8) as f32 / 16_777_216.0 - 0.5);
///         e.update(config, x);
///     }
///     e.model(config).map_or(f32::NAN, |m| m.a()[0])
/// }
///
/// let config = Config::new(0.999f32, 0.01)?;
/// let channel = Channel::new(0.01)?;
/// let fixed = FixedConfig::new(&config)?;
/// let fixed_channel = FixedChannel::new(&channel, 2.0)?;
/// let a = [
///     a1(Lattice::new(&config, &channel), &config),
///     a1(Rls::new(&config, &channel), &config),
///     a1(Sftf::new(&config, &channel), &config),
///     a1(FixedLattice::new(&fixed, &fixed_channel), &fixed),
/// ];
/// // The same least-squares problem, four ways: the same answer.
/// assert!(a.iter().all(|&x| (x - a[0]).abs() < 1e-3), "{a:?}");
/// assert!((a[0] - 0.5).abs() < 0.1);
/// # Ok::<(), imu_ar::recursive::ConfigError>(())
/// ```
pub trait Estimator<T: Scalar, const P: usize>: sealed::Sealed<T, P> {
    /// The settings the channels share: [`Config<T>`](super::Config) for the float
    /// estimators, [`FixedConfig`](super::FixedConfig) for the fixed-point lattice.
    type Config: sealed::Settings<T>;

    /// Takes one sample and returns the a-priori order-`P` prediction error
    /// `x_n - xhat_n` (the one-step prediction error, the paper's figure of merit), in the
    /// channel's units.
    ///
    /// Returns `None` when the sample was rejected: NaN or infinite, or at or beyond the
    /// channel's saturation limit (counted in [`Estimator::health`]; the state is unchanged);
    /// and when it broke the recursion down, which re-initialises the estimator (counted as a
    /// restart; [`Estimator::model`] then holds the last good model). Never panics.
    fn update(&mut self, config: &Self::Config, x: T) -> Option<T>;

    /// The order-`P` model after the last sample: coefficients, innovation variance, the
    /// running mean and `dt`. A pure getter: calling it changes nothing, and what it returns
    /// does not depend on whether it was called before.
    ///
    /// After a restart, and while the current state makes no valid model, it returns the last
    /// good model instead: the estimator itself takes a snapshot of its model every
    /// [`snapshot_interval`](super::snapshot_interval)`(P)` accepted samples (never while a
    /// restart settles) and returns that snapshot for `3/(1 - lambda)` samples after a
    /// restart, at most 30 000 (so also at `lambda = 1`). `None` before the first sample, or
    /// if no valid model has existed yet.
    ///
    /// The lattices compute the coefficients from their reflection coefficients on each call
    /// (`O(P^3/3)` operations and `2 P^2` scalars of stack; see
    /// [`Lattice::coefficients`](super::Lattice::coefficients)); [`Rls`](super::Rls) and
    /// [`Sftf`](super::Sftf) copy theirs.
    fn model(&self, config: &Self::Config) -> Option<ArModel<T, P>> {
        use sealed::Settings;
        self.shell()
            .model(config.dt(), self.energy(), || self.current())
    }

    /// What happened to the samples so far.
    fn health(&self) -> Health {
        self.shell().health
    }

    /// The weighted running mean removed from the input, in the channel's units (0 without
    /// mean removal).
    fn mean(&self) -> T {
        self.shell().mean()
    }

    /// The innovation variance of the current state, `E_n / W_n` with `E_n` the order-`P`
    /// energy and `W_n = sum_{i<=n} lambda^(n-i)` (`= E_n (1 - lambda)/(1 - lambda^n)`), in
    /// the channel's units squared: the [`ArModel::noise_variance`] of the current model,
    /// without the hold after a restart. `None` before the first sample.
    fn noise_variance(&self) -> Option<T> {
        self.shell().per_sample(self.energy())
    }
}

/// The outputs of an estimator that keeps its transversal coefficients `a` every sample
/// ([`Rls`](super::Rls), [`Sftf`](super::Sftf)), in fields `a`, `energy`, `error` and
/// `shell`: the [`Estimator`] parts and the accessors of `a` and of the last error.
macro_rules! transversal {
    ($estimator:ident) => {
        impl<T: Scalar, const P: usize> $estimator<T, P> {
            /// The coefficients `a_1..a_P` after the last sample.
            pub fn coefficients(&self) -> &[T; P] {
                &self.a
            }

            /// The last a-priori prediction error (what [`Estimator::update`] returned for the
            /// last sample it took).
            pub fn error(&self) -> T {
                self.error
            }
        }

        impl<T: Scalar, const P: usize> Sealed<T, P> for $estimator<T, P> {
            type Format = T;

            fn shell(&self) -> &Shell<T, P> {
                &self.shell
            }

            fn energy(&self) -> T {
                self.energy
            }

            fn current(&self) -> Option<[T; P]> {
                Some(self.a)
            }
        }
    };
}

pub(crate) use transversal;
