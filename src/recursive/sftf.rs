//! The stabilised fast transversal filter (SFTF), `O(P)` per sample, with its divergence
//! monitor and rescue.

use super::estimator::{Estimator, sealed::Sealed};
use super::shell::Shell;
use super::{Channel, Config};
use crate::Scalar;

/// The monitor's threshold `tau` on the disagreement of the two backward errors
/// ([`Sftf::disagreement`]): `1e-2` in single precision, `1e-6` in double. The largest
/// disagreement of the healthy runs of `host-tests/tests/host/sftf.rs` is printed in the table of
/// [the SFTF head to head](crate::guide::estimators) next to their restarts; the worst is the Percival-Walden AR(4) (`cond R ~ 1e6`).
fn tau<T: Scalar>() -> T {
    if T::EPSILON > T::from_f64(1e-10) {
        T::from_f64(1e-2)
    } else {
        T::from_f64(1e-6)
    }
}

/// Largest healthy conversion factor: rounding may set `gamma` a little above 1.
const GAMMA_MAX: f64 = 1.0 + 1e-3;

/// Exponentially weighted least-squares AR estimator that outputs the transversal coefficients
/// every sample at `O(P)` cost: the stabilised fast transversal filter of Slock & Kailath
/// (1991, IEEE Trans. SP 39(1):92-114), with the conversion factor computed directly, as
/// written in numerics.md section 2.3.
///
/// State: forward and backward predictors `a`, `b`, the gain `g`, the energies `alpha`,
/// `beta`, the conversion factor `gamma` and the delay line `phi_n = [y_{n-1} .. y_{n-P}]`.
/// Per sample `y_n`:
///
/// ```text
/// e     = y_n - a^T phi_n,   eps = gamma e                a-priori / a-posteriori error
/// c     = e / (lambda alpha),   gbar = [c; g - c a]        extended gain (old a), length P+1
/// a    <- a + eps g,   alpha <- lambda alpha + eps e
/// r_f   = y_{n-P} - b^T phi_{n+1},   r_s = lambda beta gbar_P
/// r1    = 1.5 r_f - 0.5 r_s,   r2 = 2.5 r_f - 1.5 r_s     the backward error, twice, fed back
/// g    <- gbar_{0..P-1} + gbar_P b
/// gamma = 1 / (1 + g^T phi_{n+1})
/// beta <- lambda beta + gamma r2^2,   b <- b + gamma r1 g
/// ```
///
/// from `a = b = g = 0`, `gamma = 1`, `alpha = delta lambda^P`, `beta = delta`, the initial
/// state of the problem in the [module docs](super): in exact arithmetic `a` is the same
/// `a_n` the lattice and [`Rls`](super::Rls) compute, and `alpha` the lattice's order-`P`
/// energy. About `7P` multiplications and two divisions per sample.
///
/// The fast transversal filters are only conditionally stable in finite precision: the
/// feedback of `r_f - r_s` keeps this one stable for `lambda > 1 - 1/(2P)` on data its order
/// describes, but not below that, and not when the order under-fits a resonant input
/// (numerics.md section 8); there the error grows in `f64` as well as in `f32`. So every sample
/// is checked, and the state is re-initialised (a rescue, counted in
/// [`Health::restarts`](super::Health::restarts)) when
///
/// * the two backward errors disagree: `|r_f - r_s| > tau (|r_f| + sqrt((1 - lambda) beta))`,
///   `tau = 1e-2` in `f32`, `1e-6` in `f64`;
/// * `gamma` leaves `(0, 1 + 1e-3]`, or `alpha` or `beta` is not positive;
/// * any value is not finite.
///
/// The rescue zeroes the delay line and restarts from the initial state, and
/// [`Estimator::model`] keeps returning the last good model (a snapshot the filter refreshes
/// itself) for `3/(1 - lambda)` samples, at most 30 000. Where the lattice and this filter
/// both apply, prefer the [`Lattice`](super::Lattice): it never needs rescuing; this filter is
/// for firmware that must have `a` every sample.
///
/// ```
/// use imu_ar::recursive::{Channel, Config, Estimator, Sftf};
/// use imu_ar::{ArModel, sim::ArSimulator};
/// # struct Lcg(u64);
/// # impl rand_core::RngCore for Lcg {
/// #     fn next_u32(&mut self) -> u32 { (self.next_u64() >> 32) as u32 }
/// #     fn next_u64(&mut self) -> u64 { self.0 = self.0.wrapping_mul(6364136223846793005).wrapping_add(1442695040888963407); self.0 }
/// #     fn fill_bytes(&mut self, d: &mut [u8]) { rand_core::impls::fill_bytes_via_next(self, d) }
/// # }
///
/// let truth = ArModel::new([1.2f32, -0.5], 1.0, 0.0, 0.01).unwrap();
/// let mut sensor = ArSimulator::new(truth);
/// let mut rng = Lcg(7);
///
/// let config = Config::new(0.999f32, 0.01).unwrap();
/// let mut sftf = Sftf::<f32, 2>::new(&config, &Channel::new(0.1).unwrap());
/// for _ in 0..20_000 {
///     sftf.update(&config, sensor.next(&mut rng));
/// }
/// let a = sftf.coefficients();
/// assert!((a[0] - 1.2).abs() < 0.05 && (a[1] + 0.5).abs() < 0.05);
/// assert_eq!(sftf.health().restarts, 0);
/// ```
#[derive(Clone, Copy, Debug)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub struct Sftf<T: Scalar, const P: usize> {
    a: [T; P],
    b: [T; P],
    g: [T; P],
    /// `y_{n-1} .. y_{n-P}` for the next sample.
    phi: [T; P],
    /// The forward energy `alpha_n`.
    energy: T,
    beta: T,
    gamma: T,
    error: T,
    /// The backward errors `r_f`, `r_s` of the last sample, for [`Sftf::disagreement`].
    backward: (T, T),
    /// With a prior: the model's coefficients, apart from the forward predictor `a`.
    joint: Option<Joint<T, P>>,
    shell: Shell<T, P>,
}

impl<T: Scalar, const P: usize> Sftf<T, P> {
    /// A filter for `channel` at the initial state of the problem.
    pub fn new(config: &Config<T>, channel: &Channel<T>) -> Self {
        Self::centred(config, channel, [T::ZERO; P])
    }

    /// A filter that starts from the prior model `a0` with the weight `delta` of `channel`:
    /// the problem of the [module docs](super) with its regularisation centred on `a0`,
    /// `delta lambda^n (a - a0)^T D (a - a0)`. The gain `g` and the predictors `b` depend on
    /// the regressors only, and `a <- a + eps g` is the RLS update: the filter solves that
    /// problem from `a = a0` with the same recursion, and a rescue restarts it from `a0`.
    /// With `a0 = 0` it is [`Sftf::new`].
    ///
    /// # Errors
    ///
    /// [`ConfigError::Prior`](super::ConfigError::Prior) if an entry of `a0` is not finite or
    /// `|a0_k| > 2 C(P, k)`, twice the largest coefficient of an AR(`P`) model with its roots in
    /// the unit disc.
    pub fn with_prior(
        config: &Config<T>,
        channel: &Channel<T>,
        a0: &[T; P],
    ) -> Result<Self, super::ConfigError> {
        let a0 = super::config::finite_prior(a0)?;
        Ok(Self::centred(config, channel, a0))
    }

    fn centred(config: &Config<T>, channel: &Channel<T>, centre: [T; P]) -> Self {
        const { assert!(P > 0, "the model order P must be at least 1") };
        let energy = channel.delta_lambda_pow(config.lambda(), P);
        let prior = centre.iter().any(|&a| a != T::ZERO);
        Self {
            a: [T::ZERO; P],
            b: [T::ZERO; P],
            g: [T::ZERO; P],
            phi: [T::ZERO; P],
            energy,
            beta: channel.delta(),
            gamma: T::ONE,
            error: T::ZERO,
            backward: (T::ZERO, T::ZERO),
            joint: prior.then_some(Joint {
                centre,
                w: centre,
                energy,
                error: T::ZERO,
            }),
            shell: Shell::new(*channel),
        }
    }

    /// The monitor: the two backward errors agree, `gamma`, `alpha` and `beta` are in range,
    /// and every value is finite. A non-finite `g` makes `gamma` NaN or 0 in the same sample,
    /// a non-finite `b` does the same through the next sample's `g`, before either can reach
    /// `a` (which takes the `g` of the sample before), and NaN fails every comparison: so only
    /// the coefficients `a` (their sum `a_sum`) and the energies need checking here.
    fn healthy(&self, lambda: T, r_f: T, r_s: T, a_sum: T) -> bool {
        // |r_f - r_s| <= tau (|r_f| + sqrt((1 - lambda) beta)), without the square root.
        let excess = (r_f - r_s).abs() / tau::<T>() - r_f.abs();
        let agree = excess <= T::ZERO || excess * excess <= (T::ONE - lambda) * self.beta;
        let in_range = self.gamma > T::ZERO
            && self.gamma <= T::from_f64(GAMMA_MAX)
            && self.energy > T::ZERO
            && self.beta > T::ZERO;
        agree && in_range && (a_sum + self.energy + self.beta).is_finite()
    }

    /// The monitor's value after the last sample,
    /// `d = |r_f - r_s| / (|r_f| + sqrt((1 - lambda) beta))` (0 before the first): how far
    /// the two backward errors disagree. The filter is rescued when `d` passes `tau` (`1e-2`
    /// in `f32`, `1e-6` in `f64`); a healthy run stays below it.
    pub fn disagreement(&self, config: &Config<T>) -> T {
        let (r_f, r_s) = self.backward;
        let floor = libm::sqrt((1.0 - config.lambda().to_f64()) * self.beta.to_f64());
        let scale = r_f.abs().to_f64() + floor;
        let d = (r_f - r_s).abs().to_f64();
        T::from_f64(if d > 0.0 { d / scale } else { 0.0 })
    }

    /// The order-`P` energy `min J_n + delta lambda^(n+P)`: the forward energy `alpha_n`, or
    /// with a prior the joint-process energy of the centred problem.
    pub fn energy(&self) -> T {
        self.published().0
    }
}

impl<T: Scalar, const P: usize> Estimator<T, P> for Sftf<T, P> {
    type Config = Config<T>;

    fn update(&mut self, config: &Config<T>, x: T) -> Option<T> {
        let (energy, a, phi) = match &self.joint {
            Some(j) => (j.energy, &j.w, &self.phi),
            None => (self.energy, &self.a, &self.phi),
        };
        let a_priori = |y| a.iter().zip(phi).fold(y, |e, (&a, &p)| e - a * p);
        if !self.shell.gate(config, x, energy, a_priori) {
            return None;
        }
        let y = self.shell.intake(config, x)?;
        self.step(config, y, true)
    }
}

impl<T: Scalar, const P: usize> Sftf<T, P> {
    /// Takes the centred sample `y`; a history sample (`equation = false`, a settled start)
    /// goes through the forward and backward predictors and the gain, and into the joint
    /// process with a zero error.
    fn step(&mut self, config: &Config<T>, y: T, equation: bool) -> Option<T> {
        let lambda = config.lambda();
        // Added to both energy updates, as in the lattice: keeps `alpha` and `beta` positive
        // (and divisible) however long the input is exactly zero; relative to `delta`.
        let floor = self.shell.channel().floor();

        // The joint process (a prior), on the gain `g` and delay line of before the sample.
        let (gamma, g, phi) = (self.gamma, &self.g, &self.phi);
        let mut w_sum = T::ZERO;
        if let Some(j) = &mut self.joint {
            let e_w = if equation {
                j.w.iter().zip(phi).fold(y, |e, (&w, &p)| e - w * p)
            } else {
                T::ZERO
            };
            let eps_w = gamma * e_w;
            for (w, &g) in j.w.iter_mut().zip(g) {
                *w += eps_w * g;
                w_sum += *w;
            }
            j.energy = lambda * j.energy + eps_w * e_w + floor;
            j.error = e_w;
            w_sum += j.energy;
        }
        let e = self
            .a
            .iter()
            .zip(&self.phi)
            .fold(y, |e, (&a, &p)| e - a * p);
        let eps = self.gamma * e;
        let c = e / (lambda * self.energy);
        self.energy = lambda * self.energy + eps * e + floor;

        // One pass over k = 0..P-1, with the old a_k, g_k: gbar_k = [c; g - c a]_k,
        // a_k <- a_k + eps g_k, the delay line shifts to phi_{n+1}, g_k <- gbar_k + gbar_P b_k,
        // and the sums r_f = y_{n-P} - b^T phi_{n+1} and 1/gamma = 1 + g^T phi_{n+1}.
        let gbar_p = self.g[P - 1] - c * self.a[P - 1];
        let (mut gbar_k, mut shifted) = (c, y);
        let (mut r_f, mut inv_gamma, mut a_sum) = (self.phi[P - 1], T::ONE, T::ZERO);
        let state = self.a.iter_mut().zip(&mut self.g).zip(&mut self.phi);
        for (((a, g), p), &b) in state.zip(&self.b) {
            let (a_old, g_old, p_old) = (*a, *g, *p);
            *a = a_old + eps * g_old;
            a_sum += *a;
            *p = shifted;
            r_f -= b * shifted;
            *g = gbar_k + gbar_p * b;
            inv_gamma += *g * shifted;
            gbar_k = g_old - c * a_old;
            shifted = p_old;
        }
        let r_s = lambda * self.beta * gbar_p;
        let r_1 = T::from_f64(1.5) * r_f - T::from_f64(0.5) * r_s;
        let r_2 = T::from_f64(2.5) * r_f - T::from_f64(1.5) * r_s;
        self.gamma = T::ONE / inv_gamma;
        self.beta = lambda * self.beta + self.gamma * r_2 * r_2 + floor;
        let k = self.gamma * r_1;
        for (b, &g) in self.b.iter_mut().zip(&self.g) {
            *b += k * g;
        }

        if !self.healthy(lambda, r_f, r_s, a_sum + w_sum) {
            self.shell.restart(lambda.to_f64());
            *self = Self {
                shell: self.shell,
                ..Self::centred(
                    config,
                    self.shell.channel(),
                    self.joint.map_or([T::ZERO; P], |j| j.centre),
                )
            };
            return None;
        }
        if self.shell.weight_full() {
            // Halving the weight of every past sample halves the energies and doubles the
            // gain `g = R^-1 phi / lambda`, so `1/gamma - 1 = g^T phi` doubles.
            let half = T::from_f64(0.5);
            self.energy *= half;
            if let Some(j) = &mut self.joint {
                j.energy *= half;
            }
            self.beta *= half;
            for g in &mut self.g {
                *g = *g + *g;
            }
            self.gamma = self.gamma / (T::from_f64(2.0) - self.gamma);
            self.shell.halve_weight();
        }
        self.error = e;
        self.backward = (r_f, r_s);
        let (energy, a, error) = self.published();
        let a = *a;
        self.shell.refresh(config.dt(), energy, || Some(a));
        Some(error)
    }
}

impl<T: Scalar, const P: usize> super::settled::Start<T, P> for Sftf<T, P> {
    fn screen(&mut self, x: T) -> Option<T> {
        self.shell.screen(x)
    }

    fn start(&mut self, config: &Config<T>, a0: &[T; P], history: &[T; P], mean: (T, T, u64)) {
        *self = Self {
            shell: self.shell,
            ..Self::centred(config, self.shell.channel(), *a0)
        };
        // The history needs the joint process even for `a0 = 0`.
        self.joint = Some(Joint {
            centre: *a0,
            w: *a0,
            energy: self.energy,
            error: T::ZERO,
        });
        for &y in history.iter().rev() {
            self.step(config, y, false);
        }
        self.shell.settle(mean.0, mean.1, mean.2);
    }
}

/// The joint-process filter of an [`Sftf`] with a prior: the forward predictor `a` makes the
/// gain and must stay the zero-centred problem's, so the model's coefficients `w` are a second
/// transversal filter on the same gain, `w <- w + gamma e_w g`, `e_w = y_n - w^T phi_n`, from
/// `w = a0` (`2 P` multiplications more per sample).
#[derive(Clone, Copy, Debug)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
struct Joint<T, const P: usize> {
    centre: [T; P],
    w: [T; P],
    /// `E_n = lambda E_{n-1} + gamma e_w^2`, from `delta lambda^P`.
    energy: T,
    error: T,
}

impl<T: Scalar, const P: usize> Sftf<T, P> {
    /// The order-`P` energy, coefficients and last a-priori error of the published problem.
    fn published(&self) -> (T, &[T; P], T) {
        match &self.joint {
            Some(j) => (j.energy, &j.w, j.error),
            None => (self.energy, &self.a, self.error),
        }
    }

    /// The coefficients `a_1..a_P` after the last sample.
    pub fn coefficients(&self) -> &[T; P] {
        self.published().1
    }

    /// The last a-priori prediction error (what [`Estimator::update`] returned for the last
    /// sample it took).
    pub fn error(&self) -> T {
        self.published().2
    }
}

impl<T: Scalar, const P: usize> Sealed<T, P> for Sftf<T, P> {
    type Format = T;

    fn shell(&self) -> &Shell<T, P> {
        &self.shell
    }

    fn energy(&self) -> T {
        self.published().0
    }

    fn current(&self) -> Option<[T; P]> {
        Some(*self.published().1)
    }
}
