//! What every recursive estimator keeps around its recursion, written once for the float
//! and the fixed-point formats: the channel, the running mean and weight, the health counters,
//! and the last good model, held through a restart.

use core::fmt::Debug;

use super::config::{Channel, Config, Gate, Rejection};
use super::mean::RunningMean;
use crate::{ArModel, Scalar};

/// Counters that say what happened to the samples a state was given.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub struct Health {
    /// Samples that entered the estimator.
    pub samples: u64,
    /// Samples rejected as NaN or infinite.
    pub non_finite: u64,
    /// Samples rejected as saturated ([`Channel::with_saturation`]).
    pub saturated: u64,
    /// Re-initialisations after a numerical breakdown.
    pub restarts: u64,
    /// Internal values saturated to their number format (fixed point only; 0 for floats).
    pub clipped: u64,
    /// Samples rejected by the innovation gate ([`Config::with_gate`](super::Config::with_gate)).
    pub outliers: u64,
}

impl Health {
    /// All rejected samples.
    pub fn rejected(&self) -> u64 {
        self.non_finite
            .saturating_add(self.saturated)
            .saturating_add(self.outliers)
    }

    fn reject(&mut self, why: Rejection) {
        match why {
            Rejection::NonFinite => self.non_finite = self.non_finite.saturating_add(1),
            Rejection::Saturated => self.saturated = self.saturated.saturating_add(1),
        }
    }
}

/// Exponentially weighted sample count `W_n = lambda W_{n-1} + 1`, the normaliser of the
/// innovation variance `s_w^2 = E_n / W_n` (`= E_n (1-lambda)/(1-lambda^n)` for `lambda < 1`).
#[derive(Clone, Copy, Debug, Default, PartialEq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub(crate) struct WeightSum<T>(pub(crate) T);

impl<T: Scalar> WeightSum<T> {
    #[inline]
    pub(crate) fn push(&mut self, lambda: T) {
        self.0 = lambda * self.0 + T::ONE;
    }
}

/// How an estimator holds what its [`Shell`] keeps: the number formats of the float
/// estimators (every `T: Scalar`) and of the fixed-point lattice.
pub trait Format: Copy + Debug {
    /// The number type of the models, in the channel's units.
    type Out: Scalar;
    /// The settings of one channel.
    type Channel: Copy + Debug;
    /// The running mean and the weight `W_n` since the start or the last restart.
    type Moments: Copy + Debug + Default;
    /// A weighted energy.
    type Energy: Copy;

    /// The running mean, in the channel's units.
    fn mean(moments: &Self::Moments, channel: &Self::Channel) -> Self::Out;

    /// `energy / W_n` in the channel's units squared; `None` before the first sample.
    fn per_sample(
        moments: &Self::Moments,
        channel: &Self::Channel,
        energy: Self::Energy,
    ) -> Option<Self::Out>;
}

/// The running mean and the weight of a float estimator.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub struct FloatMoments<T> {
    mean: RunningMean<T>,
    weight: WeightSum<T>,
}

impl<T: Scalar> Format for T {
    type Out = T;
    type Channel = Channel<T>;
    type Moments = FloatMoments<T>;
    type Energy = T;

    fn mean(moments: &FloatMoments<T>, _: &Channel<T>) -> T {
        moments.mean.mean()
    }

    fn per_sample(moments: &FloatMoments<T>, _: &Channel<T>, energy: T) -> Option<T> {
        let w = moments.weight.0;
        (w > T::ZERO).then(|| energy / w)
    }
}

/// The shell of an estimator in the format `F` at order `P`.
///
/// The estimator refreshes the snapshot itself ([`Shell::refresh`]) every
/// [`snapshot_interval`] accepted samples while no restart is settling, so that the model held
/// after a restart does not depend on when, or whether, the caller asked for one.
#[derive(Clone, Copy, Debug)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub struct Shell<F: Format, const P: usize> {
    channel: F::Channel,
    pub(crate) moments: F::Moments,
    pub(crate) health: Health,
    /// The last good model, held while a restarted estimator settles.
    snapshot: Option<ArModel<F::Out, P>>,
    /// Samples to go before a restarted estimator publishes again.
    hold: u32,
    /// Consecutive samples the gate has rejected.
    run: u32,
    /// The gate is open: every sample is taken until one passes the test.
    open: bool,
}

/// Largest hold after a restart, in samples: three memories of `lambda = 0.9999`.
const HOLD_MAX: f64 = 30_000.0;

/// Samples for which a restarted estimator keeps publishing its last good model:
/// `3/(1 - lambda)`, at most 30 000 (at `lambda = 1`, where the memory is unbounded, and above
/// `lambda = 0.9999`, the restarted estimator has then seen 30 000 samples).
fn hold_after_restart(lambda: f64) -> u32 {
    let memory = if lambda < 1.0 {
        3.0 / (1.0 - lambda)
    } else {
        HOLD_MAX
    };
    if memory < HOLD_MAX {
        memory as u32
    } else {
        HOLD_MAX as u32
    }
}

/// The largest weight `W_n` a float estimator lets grow: `1/(4 EPSILON)`, `2^21` in `f32`
/// (`2^50` in `f64`, never reached). Beyond it `W_n + 1` and `E + e^2` lose their precision
/// (`W_n` stops at `2^24` in `f32` while the energy keeps growing), so at the limit the weight
/// and the energies are halved together: the memory of an `f32` estimator at `lambda = 1` stops
/// growing at about two million samples, and its innovation variance stays right.
fn weight_limit<T: Scalar>() -> T {
    T::ONE / (T::from_f64(4.0) * T::EPSILON)
}

/// Accepted samples between two snapshots of the model an order-`P` estimator holds through a
/// restart: `4 P^2`, at least 32, rounded up to a power of two (so that the test on the sample
/// count is a mask). Making the lattice's coefficients costs `O(P^3/3)`, so the snapshot adds
/// `O(P/12)` operations per sample on average (with the test, 1 to 7 instructions per stage of
/// the `f32` lattice on a Cortex-M4F, `cargo qemu bench`); for [`Rls`](super::Rls) and
/// [`Sftf`](super::Sftf) it is a copy of `P` coefficients, and no measurable cost.
/// Saturates for orders too large for the product (`2^63` at most), no panic.
pub const fn snapshot_interval(p: usize) -> u64 {
    let p = p as u64;
    let quadratic = p.saturating_mul(p).saturating_mul(4);
    let at_least = if quadratic > 32 { quadratic } else { 32 };
    match at_least.checked_next_power_of_two() {
        Some(interval) => interval,
        None => 1 << 63,
    }
}

impl<F: Format, const P: usize> Shell<F, P> {
    pub(crate) fn new(channel: F::Channel) -> Self {
        Self {
            channel,
            moments: F::Moments::default(),
            health: Health::default(),
            snapshot: None,
            hold: 0,
            run: 0,
            open: false,
        }
    }

    /// The gate's decision on a sample whose a-priori error `e` and innovation variance
    /// `variance` it is told (`outlier`: `e^2 > k^2 variance`, tested only once the variance
    /// is settled): `false` rejects it (counted), `true` takes it. See
    /// [`Gate`] for the rule.
    #[inline]
    pub(crate) fn pass(&mut self, gate: &Gate, outlier: bool) -> bool {
        if !outlier {
            self.run = 0;
            self.open = false;
            return true;
        }
        if self.open {
            return true;
        }
        self.health.outliers = self.health.outliers.saturating_add(1);
        self.run = self.run.saturating_add(1);
        if self.run >= gate.run() {
            self.open = true;
            self.run = 0;
        }
        false
    }

    /// The channel the estimator was made for.
    pub(crate) fn channel(&self) -> &F::Channel {
        &self.channel
    }

    /// The running mean.
    pub(crate) fn mean(&self) -> F::Out {
        F::mean(&self.moments, &self.channel)
    }

    /// `E / W_n`, the innovation variance of an energy; `None` before the first sample.
    pub(crate) fn per_sample(&self, energy: F::Energy) -> Option<F::Out> {
        F::per_sample(&self.moments, &self.channel, energy)
    }

    /// The shared screening: a rejected sample is counted and goes no further; an accepted
    /// one is counted and counts down a hold.
    #[inline]
    pub(crate) fn admit<S>(&mut self, screened: Result<S, Rejection>) -> Option<S> {
        match screened {
            Err(why) => {
                self.health.reject(why);
                None
            }
            Ok(x) => {
                self.health.samples = self.health.samples.saturating_add(1);
                self.hold = self.hold.saturating_sub(1);
                Some(x)
            }
        }
    }

    /// Counts a restart, forgets the mean and the weight, and holds the snapshot for
    /// `3/(1 - lambda)` samples, at most 30 000. A restart while a hold runs does not extend
    /// it: an estimator restarted again and again (the SFTF on data it cannot follow) still
    /// publishes its own model, and refreshes its snapshot, once the first hold is over.
    pub(crate) fn restart(&mut self, lambda: f64) {
        self.health.restarts = self.health.restarts.saturating_add(1);
        self.moments = F::Moments::default();
        if self.hold == 0 {
            self.hold = hold_after_restart(lambda);
        }
    }

    /// The model of the current state: coefficients `a` (computed only when called) and
    /// innovation variance `energy / W_n`; `None` if it is not a valid model.
    fn current(
        &self,
        dt: F::Out,
        energy: F::Energy,
        a: impl FnOnce() -> Option<[F::Out; P]>,
    ) -> Option<ArModel<F::Out, P>> {
        let variance = self.per_sample(energy)?;
        ArModel::new(a()?, variance, self.mean(), dt).ok()
    }

    /// Called by the estimator after every healthy update: every [`snapshot_interval`]
    /// accepted samples, unless a restart is settling, the current model (if valid) becomes
    /// the one held through the next restart.
    #[inline]
    pub(crate) fn refresh(
        &mut self,
        dt: F::Out,
        energy: F::Energy,
        a: impl FnOnce() -> Option<[F::Out; P]>,
    ) {
        if self.health.samples & (snapshot_interval(P) - 1) == 0 && self.hold == 0 {
            self.keep(dt, energy, a);
        }
    }

    /// Unless a restart is settling, the current model (if valid) becomes the one held
    /// through the next restart.
    pub(crate) fn keep(
        &mut self,
        dt: F::Out,
        energy: F::Energy,
        a: impl FnOnce() -> Option<[F::Out; P]>,
    ) {
        if self.hold == 0
            && let Some(m) = self.current(dt, energy, a)
        {
            self.snapshot = Some(m);
        }
    }

    /// The model of the current state, unless a restarted estimator is still settling: then,
    /// and when the current state makes no valid model, the last snapshot.
    pub(crate) fn model(
        &self,
        dt: F::Out,
        energy: F::Energy,
        a: impl FnOnce() -> Option<[F::Out; P]>,
    ) -> Option<ArModel<F::Out, P>> {
        if self.hold == 0 {
            self.current(dt, energy, a).or(self.snapshot)
        } else {
            self.snapshot
        }
    }
}

impl<T: Scalar, const P: usize> Shell<T, P> {
    /// Screens `x` (a rejection is counted and changes nothing else) and returns the sample
    /// the recursion takes: `x` less the running mean, or `x`.
    #[inline]
    pub(crate) fn intake(&mut self, config: &Config<T>, x: T) -> Option<T> {
        let x = self.admit(self.channel.screen(x))?;
        let lambda = config.lambda();
        let m = &mut self.moments;
        let y = if config.demean() {
            m.mean.center(lambda, x)
        } else {
            x
        };
        m.weight.push(lambda);
        Some(y)
    }

    /// Screens `x` for a settled start: a rejection is counted; an accepted sample is not
    /// (it is counted when the estimator starts on it).
    pub(crate) fn screen(&mut self, x: T) -> Option<T> {
        match self.channel.screen(x) {
            Ok(x) => Some(x),
            Err(why) => {
                self.health.reject(why);
                None
            }
        }
    }

    /// Starts the running mean at a settled `mean` of `samples` samples of weight `weight`
    /// (which count as accepted), with the weight `W_n` of the equations at 0.
    pub(crate) fn settle(&mut self, mean: T, weight: T, samples: u64) {
        self.moments = FloatMoments {
            mean: RunningMean::settled(mean, weight),
            weight: WeightSum(T::ZERO),
        };
        self.health.samples = self.health.samples.saturating_add(samples);
    }

    /// The gate's view of `x`: screened (a rejection is counted), then centred with the
    /// current mean, without taking it in; `None` for a rejected sample.
    #[inline]
    pub(crate) fn peek(&mut self, config: &Config<T>, x: T) -> Option<T> {
        let x = self.screen(x)?;
        Some(if config.demean() {
            self.moments.mean.peek(x)
        } else {
            x
        })
    }

    /// Whether the a-priori error `e` is an outlier for `gate` against the energy `energy`
    /// (`e^2 > k^2 energy / W_n`), once `W_n` has reached [`Gate::settled`].
    #[inline]
    pub(crate) fn outlier(&self, config: &Config<T>, gate: &Gate, e: T, energy: T) -> bool {
        let w = self.weight();
        let k = T::from_f64(f64::from(gate.k()));
        let settled = T::from_f64(Gate::settled(config.lambda().to_f64()));
        w >= settled && e * e * w > k * k * energy
    }

    /// The gate for a float estimator: `a_priori(y)` is the estimator's a-priori error of
    /// the centred sample `y`, `energy` its order-`P` energy. `false`: the sample is rejected
    /// (counted) and must change nothing.
    #[inline]
    pub(crate) fn gate(
        &mut self,
        config: &Config<T>,
        x: T,
        energy: T,
        a_priori: impl FnOnce(T) -> T,
    ) -> bool {
        let Some(gate) = config.gate() else {
            return true;
        };
        let Some(y) = self.peek(config, x) else {
            return false;
        };
        let outlier = self.outlier(config, &gate, a_priori(y), energy);
        self.pass(&gate, outlier)
    }

    /// The weight `W_n`.
    pub(crate) fn weight(&self) -> T {
        self.moments.weight.0
    }

    /// Whether the weight has reached [`weight_limit`]: then the estimator halves its
    /// energies and calls [`Shell::halve_weight`], so that energy and weight keep growing
    /// together (at `lambda = 1`, or a `lambda` within `1/weight_limit` of 1).
    #[inline]
    pub(crate) fn weight_full(&self) -> bool {
        self.weight() >= weight_limit::<T>()
    }

    /// Halves the weight `W_n` (with the estimator's energies: see [`Shell::weight_full`]).
    pub(crate) fn halve_weight(&mut self) {
        self.moments.weight.0 *= T::from_f64(0.5);
    }
}
