//! A settled start: the estimator waits for `N` samples, then starts from their batch fit.

use super::Config;
use super::estimator::{Estimator, sealed::Sealed};
use super::shell::Health;
use crate::batch::{BatchConfig, covariance};
use crate::{ArModel, Scalar};

/// What a [`Settled`] start needs from an estimator: implemented by [`Lattice`](super::Lattice),
/// [`Rls`](super::Rls) and [`Sftf`](super::Sftf); sealed (through [`Estimator`]).
pub trait Start<T: Scalar, const P: usize>: Estimator<T, P, Config = Config<T>> {
    /// Screens a sample of the warm-up as [`Estimator::update`] would; a rejection is
    /// counted.
    fn screen(&mut self, x: T) -> Option<T>;

    /// Restarts from the prior `a0` (weight: the channel's `delta`), with the centred
    /// `history` (newest first, `y_0 .. y_{1-P}`) in the delay line and the running mean
    /// `(mean, weight, samples)` already settled.
    fn start(&mut self, config: &Config<T>, a0: &[T; P], history: &[T; P], mean: (T, T, u64));

    /// Starts on the held samples `held` (accepted ones, oldest first) as [`Settled`] does
    /// with its `N`: the settled mean, the batch fit as the prior, the last `P` as history.
    /// For firmware that keeps the samples elsewhere, and for a number of samples known only
    /// at run time.
    fn settle(&mut self, config: &Config<T>, held: &[T]) {
        let lambda = config.lambda();
        let mean = if config.demean() {
            mean_of(held)
        } else {
            T::ZERO
        };
        let a0 = BatchConfig::new(config.dt())
            .ok()
            .and_then(|b| covariance::<T, P>(held, &b.with_demean(config.demean())).ok())
            .map_or([T::ZERO; P], |fit| *fit.model.a());
        let weight = held.iter().fold(T::ZERO, |w, _| lambda * w + T::ONE);
        let history: [T; P] = core::array::from_fn(|k| {
            let i = held.len().checked_sub(k + 1);
            i.and_then(|i| held.get(i)).map_or(T::ZERO, |&v| v - mean)
        });
        self.start(config, &a0, &history, (mean, weight, held.len() as u64));
    }
}

/// An estimator with a settled start, the answer to the start of the prewindowed problem at
/// `lambda = 1`, which is never forgotten there.
///
/// The first `N` accepted samples are held (`N` values of `T` in this struct, no allocation);
/// [`update`](Estimator::update) returns `None` for them (rejections are counted as usual).
/// With the `N`-th, the estimator starts:
///
/// * the running mean starts settled, at the mean of the `N` samples (with their weight
///   `sum lambda^(N-i)`), instead of at the first sample;
/// * the prior `a0` is the batch least-squares fit of the `N` samples (the covariance method,
///   [`covariance`], mean removed as the [`Config`] says), with the channel's `delta` as its
///   weight; if that fit fails (constant or degenerate data) the prior is 0;
/// * the last `P` samples of the `N` enter the delay line as history: they add their
///   regressors to the prior's weight but no equation, so that the first equation has a full
///   regressor `[y_{n-1} .. y_{n-P}]` of real samples. No prewindowed equation (the zeros
///   before the first sample) is ever in the problem.
///
/// The problem solved from then on is that of [`Lattice::with_prior`](super::Lattice::with_prior) centred on `a0` with the
/// history rows added to the prior's weight (see `ladder.rs`); `a0 = 0` and no history is the
/// plain start. On the Percival-Walden AR(4) at `lambda = 1` and `n = 100,000`
/// ([Results](crate::guide::results)) it brings the recursive estimators from 25 times batch least squares to batch
/// least squares.
///
/// ```
/// use imu_ar::recursive::{Channel, Config, Estimator, Lattice, Settled};
///
/// let config = Config::new(1.0f64, 0.01)?;
/// let channel = Channel::new(0.1)?;
/// let mut lattice: Settled<_, f64, 64> = Settled::new(Lattice::<f64, 2>::new(&config, &channel));
/// let (mut x, mut x1, mut seed) = (0.0f64, 0.0f64, 1u32);
/// for n in 0..5000 {
///     seed = seed.wrapping_mul(1_664_525).wrapping_add(1_013_904_223);
///     let w = (seed >> 8) as f64 / 16_777_216.0 - 0.5;
///     (x, x1) = (1.5 * x - 0.7 * x1 + w, x);
///     let e = lattice.update(&config, 10.0 + x);
///     assert_eq!(e.is_none(), n < 64); // held until 64 samples have come
/// }
/// let a = lattice.model(&config).unwrap();
/// assert!((a.a()[0] - 1.5).abs() < 0.05 && (a.a()[1] + 0.7).abs() < 0.05);
/// # Ok::<(), imu_ar::recursive::ConfigError>(())
/// ```
#[derive(Clone, Copy, Debug)]
pub struct Settled<E, T, const N: usize> {
    estimator: E,
    held: [T; N],
    /// Samples held so far; `N` once started.
    len: usize,
}

impl<E, T: Scalar, const N: usize> Settled<E, T, N> {
    /// Wraps a freshly made estimator (its prior, if any, is replaced by the batch fit).
    pub fn new(estimator: E) -> Self {
        Self {
            estimator,
            held: [T::ZERO; N],
            len: 0,
        }
    }

    /// The estimator (still at its initial state while the samples are held).
    pub fn estimator(&self) -> &E {
        &self.estimator
    }

    /// Whether the estimator has started.
    pub fn started(&self) -> bool {
        self.len >= N
    }
}

impl<E: Start<T, P>, T: Scalar, const P: usize, const N: usize> Sealed<T, P> for Settled<E, T, N> {
    type Format = E::Format;

    fn shell(&self) -> &super::shell::Shell<E::Format, P> {
        self.estimator.shell()
    }

    fn energy(&self) -> <E::Format as super::shell::Format>::Energy {
        self.estimator.energy()
    }

    fn current(&self) -> Option<[T; P]> {
        self.estimator.current()
    }
}

impl<E: Start<T, P>, T: Scalar, const P: usize, const N: usize> Estimator<T, P>
    for Settled<E, T, N>
{
    type Config = Config<T>;

    /// `None` while the first `N` accepted samples are held, and for the `N`-th (on which the
    /// estimator starts); then the estimator's own.
    fn update(&mut self, config: &Config<T>, x: T) -> Option<T> {
        if self.len >= N {
            return self.estimator.update(config, x);
        }
        let x = self.estimator.screen(x)?;
        if let Some(slot) = self.held.get_mut(self.len) {
            *slot = x;
            // `len < N` here: the sum cannot saturate.
            self.len = self.len.saturating_add(1);
        }
        if self.len >= N {
            self.estimator.settle(config, &self.held);
        }
        None
    }

    fn model(&self, config: &Config<T>) -> Option<ArModel<T, P>> {
        self.estimator.model(config)
    }

    fn health(&self) -> Health {
        self.estimator.health()
    }
}

/// The mean of `x`, summed in `f64`.
fn mean_of<T: Scalar>(x: &[T]) -> T {
    let sum = x.iter().fold(0.0f64, |s, v| s + v.to_f64());
    T::from_f64(if x.is_empty() {
        0.0
    } else {
        sum / x.len() as f64
    })
}
