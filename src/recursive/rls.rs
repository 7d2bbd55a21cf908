//! Conventional recursive least squares, `O(P^2)` per sample, in Bierman's U-D form.

use super::estimator::{Estimator, sealed::Sealed, transversal};
use super::shell::Shell;
use super::{Channel, Config};
use crate::Scalar;

/// The initial inverse correlation matrix `P_0` of [`Rls`].
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub enum RlsInit {
    /// `P_0 = (delta D)^-1`, `D = diag(lambda^(P-1), .., 1)`: the exact problem of the
    /// [module docs](super), the one the lattice solves.
    #[default]
    ShiftConsistent,
    /// `P_0 = I / delta`: the textbook ridge start, weight `delta lambda^n ||a||^2`
    /// (Haykin, *Adaptive Filter Theory*, RLS chapter).
    Ridge,
}

/// Exponentially weighted recursive least-squares AR estimator, `O(P^2)` per sample.
///
/// Per sample, with `phi_n = [y_{n-1} .. y_{n-P}]`:
///
/// ```text
/// e_n   = y_n - a^T phi_n                       a-priori error
/// k_n   = P phi_n / (lambda + phi_n^T P phi_n)  gain
/// a    <- a + k_n e_n
/// P    <- (P - k_n phi_n^T P) / lambda
/// ```
///
/// `P` is kept as `U D U^T` (unit upper-triangular `U`, diagonal `D`) and updated by Bierman's
/// square-root-free algorithm (Bierman 1977, *Factorization Methods for Discrete Sequential
/// Estimation*), about `1.5 P^2` multiplications. This form keeps `P` symmetric and positive
/// definite by construction: the textbook `P <- (P - k (P phi)^T)/lambda` loses positive
/// definiteness even in `f64` on quantised, weakly exciting sensor records (numerics.md
/// section 3), which is exactly the data this crate sees.
///
/// The innovation variance is `E_n / W_n` with `E_n = lambda E_{n-1} + e_n eps_n` (a-priori
/// times a-posteriori error, `E_0 = delta lambda^P`) and `W_n = sum lambda^(n-i)`.
///
/// Safeguards: the entries of `D` are capped at `1e29 / delta` (`1e30` for `delta = 0.1`; the
/// cap scales with the data, as `delta` does), so that a stuck sensor (no excitation, `P`
/// growing as `lambda^-n`) cannot overflow it; a non-finite or non-positive factor
/// re-initialises the state (counted in [`Health::restarts`](super::Health::restarts)) while
/// [`Estimator::model`] returns the last good model.
///
/// ```
/// use imu_ar::recursive::{Channel, Config, Estimator, Rls};
///
/// let config = Config::new(0.999f32, 0.01)?;
/// let mut rls = Rls::<f32, 1>::new(&config, &Channel::new(0.01)?);
/// let (mut x, mut seed) = (0.0f32, 1u32);
/// for _ in 0..5000 {
///     // An AR(1) with a_1 = 0.5 and uniform innovations.
///     seed = seed.wrapping_mul(1_664_525).wrapping_add(1_013_904_223);
///     x = 0.5 * x + ((seed >> 8) as f32 / 16_777_216.0 - 0.5);
///     rls.update(&config, x);
/// }
/// assert!((rls.coefficients()[0] - 0.5).abs() < 0.1);
/// # Ok::<(), imu_ar::recursive::ConfigError>(())
/// ```
#[derive(Clone, Copy, Debug)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub struct Rls<T: Scalar, const P: usize> {
    a: [T; P],
    /// Strictly upper part of `U`, by columns: `ut[j][i] = U[i][j]` for `i < j`, so that the
    /// inner loops run over contiguous memory.
    ut: [[T; P]; P],
    d: [T; P],
    /// `y_{n-1} .. y_{n-P}` for the next sample.
    phi: [T; P],
    energy: T,
    error: T,
    init: RlsInit,
    /// The prior `a0` the state starts from (and restarts from).
    centre: [T; P],
    shell: Shell<T, P>,
}

impl<T: Scalar, const P: usize> Rls<T, P> {
    /// A state for `channel` at `a = 0`, with the `P_0` of the problem the lattice solves
    /// ([`RlsInit::ShiftConsistent`]).
    pub fn new(config: &Config<T>, channel: &Channel<T>) -> Self {
        Self::with_init(config, channel, RlsInit::default())
    }

    /// A state for `channel` at `a = 0` with the chosen `P_0`.
    pub fn with_init(config: &Config<T>, channel: &Channel<T>, init: RlsInit) -> Self {
        Self::centred(config, channel, init, [T::ZERO; P])
    }

    /// A state that starts from the prior model `a0` with the weight `delta` of `channel`
    /// (and `P_0 = (delta D)^-1`): the problem of the [module docs](super) with its
    /// regularisation centred on `a0`, `delta lambda^n (a - a0)^T D (a - a0)`. RLS solves it
    /// from `a = a0` with the same recursion. With `a0 = 0` it is [`Rls::new`].
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
        Ok(Self::centred(config, channel, RlsInit::default(), a0))
    }

    fn centred(config: &Config<T>, channel: &Channel<T>, init: RlsInit, centre: [T; P]) -> Self {
        const { assert!(P > 0, "the model order P must be at least 1") };
        let mut s = Self {
            a: [T::ZERO; P],
            ut: [[T::ZERO; P]; P],
            d: [T::ZERO; P],
            phi: [T::ZERO; P],
            energy: T::ZERO,
            error: T::ZERO,
            init,
            centre,
            shell: Shell::new(*channel),
        };
        s.initialise(config);
        s
    }

    fn initialise(&mut self, config: &Config<T>) {
        let (lambda, channel) = (config.lambda(), self.shell.channel());
        self.a = self.centre;
        self.ut = [[T::ZERO; P]; P];
        for (k, d) in self.d.iter_mut().enumerate() {
            *d = match self.init {
                RlsInit::ShiftConsistent => T::ONE / channel.delta_lambda_pow(lambda, P - 1 - k),
                RlsInit::Ridge => T::ONE / channel.delta(),
            };
        }
        self.phi = [T::ZERO; P];
        self.energy = channel.delta_lambda_pow(lambda, P);
        self.error = T::ZERO;
    }
}

transversal!(Rls);

impl<T: Scalar, const P: usize> Estimator<T, P> for Rls<T, P> {
    type Config = Config<T>;

    fn update(&mut self, config: &Config<T>, x: T) -> Option<T> {
        let (a, phi) = (&self.a, &self.phi);
        let a_priori = |y| a.iter().zip(phi).fold(y, |e, (&a, &p)| e - a * p);
        if !self.shell.gate(config, x, self.energy, a_priori) {
            return None;
        }
        let y = self.shell.intake(config, x)?;
        self.step(config, y, true)
    }
}

impl<T: Scalar, const P: usize> Rls<T, P> {
    /// Takes the centred sample `y`; a history sample (`equation = false`, a settled start)
    /// enters `P` and the delay line with a zero error, so that `a` stays where it is.
    fn step(&mut self, config: &Config<T>, y: T, equation: bool) -> Option<T> {
        let lambda = config.lambda();
        let e = if equation {
            self.a
                .iter()
                .zip(&self.phi)
                .fold(y, |e, (&a, &p)| e - a * p)
        } else {
            T::ZERO
        };

        // Bierman's update of U D U^T with measurement variance lambda, then D /= lambda:
        // f = U^T phi, v = D f.
        // The index from a range, not `enumerate`: its count carries an overflow check the
        // optimiser keeps (nopanic). Column 0 is empty.
        let mut f = self.phi;
        for ((fj, column), j) in f.iter_mut().zip(&self.ut).zip(0..P) {
            *fj = dot(*fj, &column[..j], &self.phi[..j]);
        }
        let v: [T; P] = core::array::from_fn(|j| self.d[j] * f[j]);
        let mut gain = v;
        let mut alpha = lambda + v[0] * f[0];
        let mut healthy = alpha > T::ZERO;
        self.d[0] = self.d[0] * lambda / alpha;
        for j in 1..P {
            let beta = alpha;
            alpha += v[j] * f[j];
            let mu = -f[j] / beta;
            self.d[j] = self.d[j] * beta / alpha;
            let (column, gains) = (&mut self.ut[j][..j], &mut gain[..j]);
            for (u, g) in column.iter_mut().zip(gains) {
                let t = *u;
                *u = t + *g * mu;
                *g += v[j] * t;
            }
        }
        let mut check = T::ZERO;
        // Without excitation (a stuck sensor) `P` grows as `lambda^-n` and would overflow
        // ("covariance wind-up"); held below `1e29 / delta` the estimator stays finite and
        // recovers as soon as the input moves again. Far above any value of a healthy run, and
        // relative to `delta`, so that it scales with the data.
        let d_max = self.shell.channel().ceiling();
        for ((a, d), g) in self.a.iter_mut().zip(&mut self.d).zip(&gain) {
            *a += *g / alpha * e;
            // Without excitation (a stuck sensor) D grows as lambda^-n: cap it.
            let scaled = *d / lambda;
            *d = if scaled > d_max { d_max } else { scaled };
            healthy &= *d > T::ZERO;
            check += *a + *d;
        }
        // a-posteriori error eps = e lambda / alpha
        // The same floor as the lattice's and the SFTF's: a stuck sensor keeps a positive
        // energy instead of one that decays as lambda^n to 0.
        self.energy =
            lambda * self.energy + e * (e * lambda / alpha) + self.shell.channel().floor();
        check += self.energy;
        if !(healthy && check.is_finite()) {
            self.shell.restart(lambda.to_f64());
            self.initialise(config);
            return None;
        }
        if self.shell.weight_full() {
            // Halving the weight of every past sample halves the energy and doubles `P`.
            self.energy *= T::from_f64(0.5);
            for d in &mut self.d {
                let doubled = *d + *d;
                *d = if doubled > d_max { d_max } else { doubled };
            }
            self.shell.halve_weight();
        }
        self.phi.copy_within(0..P - 1, 1);
        self.phi[0] = y;
        self.error = e;
        self.shell
            .refresh(config.dt(), self.energy, || Some(self.a));
        Some(e)
    }
}

impl<T: Scalar, const P: usize> super::settled::Start<T, P> for Rls<T, P> {
    fn screen(&mut self, x: T) -> Option<T> {
        self.shell.screen(x)
    }

    fn start(&mut self, config: &Config<T>, a0: &[T; P], history: &[T; P], mean: (T, T, u64)) {
        self.centre = *a0;
        self.init = RlsInit::ShiftConsistent;
        self.initialise(config);
        for &y in history.iter().rev() {
            self.step(config, y, false);
        }
        self.shell.settle(mean.0, mean.1, mean.2);
    }
}

/// `init + sum x_i y_i`, summed in order.
#[inline(always)]
fn dot<T: Scalar>(init: T, x: &[T], y: &[T]) -> T {
    x.iter().zip(y).fold(init, |s, (&a, &b)| s + a * b)
}
