//! The a-priori least-squares lattice with error feedback (EF-LSL), `O(P)` per sample.

use super::arith::{Arith, FloatArith, FloatParams, float_params};
use super::estimator::{Estimator, sealed::Sealed};
use super::ladder::Ladder;
use super::shell::Shell;
use super::{Channel, Config};
use crate::Scalar;

/// The accessors both lattices have over their `core` and `shell`: the errors, energies,
/// innovation variances and reflection coefficients of every order after the last sample, of
/// the types `$err`, `$coef`, `$energy` and `$variance`, measured as `$units` says; `$ratio`
/// is how the innovation variance is formed. Used in the `impl` blocks of [`Lattice`] and
/// [`FixedLattice`](super::FixedLattice).
macro_rules! lattice_accessors {
    ($err:ty, $coef:ty, $energy:ty, $variance:ty, $units:literal, $ratio:literal) => {
        #[doc = concat!(
            "A-priori forward prediction errors `f_1(n)..f_P(n)` of the last accepted sample ",
            "(`f_m(n) = y_n - a^(m)_{n-1}^T phi_n`), ", $units, "; `f_0(n) = y_n` is ",
            "[`input`](Self::input)."
        )]
        pub fn errors(&self) -> [$err; P] {
            self.core.stages.map(|s| s.error)
        }

        #[doc = concat!(
            "The last accepted sample after mean removal, `y_n` (the order-0 prediction ",
            "error), ", $units, "."
        )]
        pub fn input(&self) -> $err {
            self.core.input
        }

        #[doc = concat!(
            "Forward energy `F_m(n) = min J^(m)_n + delta lambda^(n+P)` of order `m` in ",
            "`0..=P`, ", $units, " squared; `None` above `P`."
        )]
        pub fn energy(&self, m: usize) -> Option<$energy> {
            self.core.energy(m)
        }

        #[doc = concat!(
            "Innovation variance of order `m` in the input's units squared: ", $ratio,
            ", `W_n = sum_{i<=n} lambda^(n-i)` (`= F_m (1 - lambda)/(1 - lambda^n)`); `None` ",
            "above `P` or before the first sample. Order `P` is ",
            "[`Estimator::noise_variance`](crate::recursive::Estimator::noise_variance)."
        )]
        pub fn innovation_variance(&self, m: usize) -> Option<$variance> {
            self.shell.per_sample(self.energy(m)?)
        }

        /// Forward reflection coefficients `kf_1..kf_P` (lattice sign: `kf_1 = a_1` of the
        /// order-1 model, minus the error-filter reflection coefficient).
        pub fn forward_reflection(&self) -> [$coef; P] {
            self.core.forward_reflection()
        }

        /// Backward reflection coefficients `kb_1..kb_P`.
        pub fn backward_reflection(&self) -> [$coef; P] {
            self.core.backward_reflection()
        }
    };
}

pub(crate) use lattice_accessors;

/// The state stage `i` carries from one sample to the next, kept together so that one
/// pointer reaches all of it.
#[derive(Clone, Copy, Debug)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
// `pub` in a private module, as `Core`.
pub struct Stage<A: Arith> {
    /// The forward energy `F_i`.
    pub(crate) f_energy: A::Energy,
    /// The backward energy `B_i`, holding `B_i(n-1)` between samples.
    pub(crate) b_energy: A::Energy,
    /// What the stage keeps for the next sample's update of `kf_{i+1}` ([`Arith::Kept`]).
    pub(crate) b_kept: A::Kept,
    /// `psi_i(n-1)`.
    pub(crate) bp: A::Err,
    /// `gamma_i(n-1)`.
    pub(crate) gp: A::Gamma,
    /// `[kf_{i+1}, kb_{i+1}]` after the last sample.
    pub(crate) k: [A::Acc; 2],
    /// The a-priori forward error `f_{i+1}(n)` of the last sample.
    pub(crate) error: A::Err,
}

/// The lattice recursion of numerics.md section 2.1, written once over the typed steps of
/// [`Arith`]: the state of all stages, the last sample's errors, and the reflection
/// coefficients of the last `P` samples for the exact transversal coefficients.
///
/// [`Lattice`] (floats) and [`FixedLattice`](super::FixedLattice) wrap it with their input
/// handling (screening, mean removal, scaling) and outputs.
#[derive(Clone, Copy, Debug)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
// `pub` in a private module, as `Arith`, whose `step` names it: reachable by no one outside
// the crate.
pub struct Core<A: Arith, const P: usize> {
    /// Stages `0..P`.
    pub(crate) stages: [Stage<A>; P],
    /// `F_P`.
    pub(crate) f_energy_p: A::Energy,
    /// `gamma_P(n-1)`.
    pub(crate) gp_p: A::Gamma,
    /// `y_n` of the last sample, the order-0 error.
    pub(crate) input: A::Err,
    /// `[kf_m, kb_m]` (index `m - 1` for order `m`) of the `P` samples before the last one,
    /// newest at `head` (the last sample's are in `stages`): a sample writes the coefficients
    /// it replaces over the oldest slot, and [`Core::rewind`] reads them back.
    pub(crate) ring: [[[A::Coef; 2]; P]; P],
    head: usize,
}

impl<A: Arith, const P: usize> Core<A, P> {
    /// The initial state: `F_i = f0`, `B_i = b[i]`, zero reflection coefficients and errors,
    /// unit conversion factors.
    pub(crate) fn new(f0: A::Energy, b: [A::Energy; P]) -> Self {
        Self {
            stages: b.map(|b| Stage {
                f_energy: f0,
                b_energy: b,
                b_kept: A::kept(b),
                bp: A::ERR_ZERO,
                gp: A::GAMMA_ONE,
                k: [A::ACC_ZERO; 2],
                error: A::ERR_ZERO,
            }),
            f_energy_p: f0,
            gp_p: A::GAMMA_ONE,
            input: A::ERR_ZERO,
            ring: [[[A::COEF_ZERO; 2]; P]; P],
            head: 0,
        }
    }

    /// One sample `y` through all stages; returns `f_P(n)`.
    #[inline(always)]
    pub(crate) fn step(&mut self, params: &A::Params, y: A::Err, clip: &mut u32) -> A::Err {
        A::step(self, params, y, clip)
    }

    /// The ring slot that receives the coefficients a sample replaces: the oldest one.
    #[inline(always)]
    pub(crate) fn next_head(&self) -> usize {
        // `% P` keeps the index provably in range: no bounds check on the per-sample path.
        (self.head % P + P - 1) % P
    }

    /// The state after a sample's stages: `F_P`, `gamma_P`, the input and the ring's head.
    #[inline(always)]
    pub(crate) fn finish(&mut self, f_energy_p: A::Energy, gp_p: A::Gamma, y: A::Err, new: usize) {
        self.f_energy_p = f_energy_p;
        self.gp_p = gp_p;
        self.input = y;
        self.head = new;
    }

    /// The a-priori error `f_P(n)` of `y_n`, without taking it (for the gate): the forward
    /// chain alone, `P` multiplications.
    pub(crate) fn a_priori(&self, y: A::Err) -> A::Err {
        let mut clip = 0;
        self.stages
            .iter()
            .fold(y, |f, s| A::predict(f, A::coef(s.k[0]), s.bp, &mut clip))
    }

    /// `kf_1..kf_P` after the last sample.
    pub(crate) fn forward_reflection(&self) -> [A::Coef; P] {
        self.stages.map(|s| A::coef(s.k[0]))
    }

    /// `kb_1..kb_P` after the last sample.
    pub(crate) fn backward_reflection(&self) -> [A::Coef; P] {
        self.stages.map(|s| A::coef(s.k[1]))
    }

    /// The reflection coefficients of `t` samples before the last one, `t < P`.
    fn past(&self, t: usize) -> [[A::Coef; 2]; P] {
        match t.checked_sub(1) {
            None => self.stages.map(|s| s.k.map(A::coef)),
            // `head % P + t < 2 P`: no wrap.
            Some(t) => self.ring[(self.head % P).wrapping_add(t) % P],
        }
    }

    /// Undoes the last [`Core::step`] as far as [`Core::coefficients`] and `F_P` are
    /// concerned, given the `F_P` from before it: the coefficients it replaced are read back
    /// from the ring (without guard bits: what the model is built from).
    pub(crate) fn rewind(&mut self, f_energy_p: A::Energy) {
        let last = self.head % P;
        for (stage, &k) in self.stages.iter_mut().zip(&self.ring[last]) {
            stage.k = k.map(A::acc);
        }
        self.head = (last + 1) % P;
        self.f_energy_p = f_energy_p;
    }

    /// Forward energy of order `m` in `0..=P`.
    pub(crate) fn energy(&self, m: usize) -> Option<A::Energy> {
        if m == P {
            Some(self.f_energy_p)
        } else {
            self.stages.get(m).map(|s| s.f_energy)
        }
    }

    /// The exact least-squares coefficients of order `m <= P`, computed in `T` from the
    /// reflection coefficients of the last `m` samples (converted by `to_t`); see
    /// [`Lattice::coefficients`].
    ///
    /// With a ladder (a lattice started from a prior `a0`, see `ladder.rs`), order `P` is the
    /// centred problem's: `a0 + sum_k c_k(n) B_{k-1}(n-1)`.
    pub(crate) fn coefficients<T: Scalar>(
        &self,
        m: usize,
        ladder: Option<&Ladder<A, P>>,
        to_t: impl Fn(A::Coef) -> T,
    ) -> Option<[T; P]> {
        if m > P {
            return None;
        }
        let ladder = ladder.filter(|_| m == P);
        // The tail of `[1, -b]`, `b = a - a0`, from the ladder's coefficients.
        let mut beta = [T::ZERO; P];
        // rows[parity][j][..j]: the leading j coefficients of B_j (its last one is 1), for
        // the time being built (written) and the one after it in age (read), alternating.
        // alpha: the tail of A_k (its first one is 1).
        let mut rows = [[[T::ZERO; P]; P]; 2];
        let mut alpha = [T::ZERO; P];
        for t in (0..m).rev() {
            let ring = self.past(t);
            alpha = [T::ZERO; P];
            let (first, second) = rows.split_at_mut(1);
            let (older, newer) = if t % 2 == 0 {
                (&second[0], &mut first[0])
            } else {
                (&first[0], &mut second[0])
            };
            for (k, &[kf_k, kb_k]) in (1..=P).zip(ring.iter().take(m - t)) {
                let (kf_k, kb_k) = (to_t(kf_k), to_t(kb_k));
                // B_{k-1}(n-t-1), with its trailing 1 (`k >= 1`: no wrap).
                let b_prev = older.get(k.wrapping_sub(1));
                // `i < P`: `i + 1` cannot wrap.
                let b_full_prev = |i: usize| match (i.wrapping_add(1) == k, b_prev) {
                    (true, _) => T::ONE,
                    (false, Some(row)) => row.get(i).copied().unwrap_or(T::ZERO),
                    (false, None) => T::ZERO,
                };
                if let (true, Some(dst)) = (t > 0, newer.get_mut(k)) {
                    // B_k(n-t), needed by the next newer time step.
                    for (i, d) in dst.iter_mut().enumerate().take(k) {
                        let shifted = if i == 0 { T::ZERO } else { b_full_prev(i - 1) };
                        let a_full = match i.checked_sub(1) {
                            None => T::ONE,
                            Some(j) => alpha.get(j).copied().unwrap_or(T::ZERO),
                        };
                        *d = shifted - kb_k * a_full;
                    }
                }
                for (j, aj) in alpha.iter_mut().enumerate().take(k) {
                    *aj -= kf_k * b_full_prev(j);
                }
                if let (0, Some(l)) = (t, ladder) {
                    let c_k = to_t(
                        l.c.get(k.wrapping_sub(1))
                            .map_or(A::COEF_ZERO, |&c| A::coef(c)),
                    );
                    for (j, bj) in beta.iter_mut().enumerate().take(k) {
                        *bj -= c_k * b_full_prev(j);
                    }
                }
            }
        }
        Some(match ladder {
            Some(l) => core::array::from_fn(|j| to_t(l.centre[j]) - beta[j]),
            None => alpha.map(|v| -v),
        })
    }
}

impl<T: FloatArith, const P: usize> Core<T, P> {
    /// [`Core::step`] in floats: the recursion as written in [`Lattice`]'s docs.
    #[inline(always)]
    pub(crate) fn float_step(&mut self, params: &FloatParams<T>, y: T) -> T {
        let clip = &mut 0;
        let (mut f, mut psi, mut g) = (y, y, T::ONE);
        let new = self.next_head();
        for (kept, stage) in self.ring[new].iter_mut().zip(&self.stages) {
            *kept = stage.k;
        }
        for stage in &mut self.stages {
            let [kf, kb] = stage.k;
            let (bp, gp, b) = (stage.bp, stage.gp, stage.b_energy);
            let gf = T::gain(gp, f, clip);
            let fe = T::energy(params, stage.f_energy, gf, f, clip);
            let f_next = T::predict(f, kf, bp, clip);
            let psi_next = T::predict(bp, kb, f, clip);
            let gbp = T::gain(gp, bp, clip);
            let k = [
                T::feedback(kf, gbp, f_next, &stage.b_kept, clip),
                T::feedback(kb, gf, psi_next, &(T::ONE / fe), clip),
            ];
            let gpsi = T::gain(g, psi, clip);
            let be = T::energy(params, b, gpsi, psi, clip);
            let be_recip = T::ONE / be;
            // The ratio form of `g - gpsi^2 / B_i(n)` needs no clamp: `B_i(n) >= lambda
            // B_i(n-1)` holds after rounding.
            let g_next = g * (params.lambda * b) * be_recip;
            *stage = Stage {
                f_energy: fe,
                b_energy: be,
                b_kept: be_recip,
                bp: psi,
                gp: g,
                k,
                error: f_next,
            };
            f = f_next;
            psi = psi_next;
            g = g_next;
        }
        let gf = T::gain(self.gp_p, f, clip);
        let f_energy_p = T::energy(params, self.f_energy_p, gf, f, clip);
        self.finish(f_energy_p, g, y, new);
        f
    }

    /// Halves every energy (the weight of every past sample), keeping the reflection
    /// coefficients: see `Shell::weight_full`.
    fn halve_energies(&mut self) {
        let half = T::from_f64(0.5);
        self.f_energy_p *= half;
        for stage in &mut self.stages {
            stage.f_energy *= half;
            stage.b_energy *= half;
            stage.b_kept = T::kept(stage.b_energy);
        }
    }
}

/// Exponentially weighted least-squares AR estimator of all orders `0..=P` at `O(P)` cost: the
/// a-priori lattice with error feedback of Ling, Manolakis & Proakis (1986, IEEE Trans. ASSP
/// 34(4):837-845), as written in numerics.md section 2.1.
///
/// Stage `i` maps order `i` to order `i + 1`; per sample, with `f_0 = psi_0 = y_n`, `g_0 = 1`:
///
/// ```text
/// F_i      <- lambda F_i + (gp_i f_i) f_i                 forward energy F_i(n)
/// f_{i+1}   = f_i  - kf_{i+1} bp_i                         a-priori forward error
/// psi_{i+1} = bp_i - kb_{i+1} f_i                          a-priori backward error
/// kf_{i+1} <- kf_{i+1} + (gp_i bp_i) f_{i+1} / B_i          B_i still B_i(n-1)
/// kb_{i+1} <- kb_{i+1} + (gp_i f_i) psi_{i+1} / F_i
/// B_i      <- lambda B_i + (g_i psi_i) psi_i               backward energy B_i(n)
/// g_{i+1}   = g_i - (g_i psi_i)^2 / B_i                    conversion factor gamma_{i+1}(n)
/// ```
///
/// then `bp_i <- psi_i`, `gp_i <- g_i`. The reflection coefficients are updated directly, not
/// as a ratio of two accumulators, which is why this form stays accurate in `f32` and fixed
/// point as `lambda -> 1`. After every sample it holds, for every order `m <= P`, the a-priori
/// error `f_m(n) = y_n - a^(m)_{n-1}^T phi_n` (the one-step prediction error, the paper's
/// figure of merit) and the exact weighted energy `F_m(n) = min J^(m)_n + delta lambda^(n+P)` of
/// the problem in the [module docs](super) (with `D_m = diag(lambda^(P-1), .., lambda^(P-m))`).
///
/// The transversal coefficients `a_1..a_m` are computed on request ([`Lattice::coefficients`],
/// [`Estimator::model`]) exactly, from the reflection coefficients of the last `P` samples
/// (numerics.md section 1, option 1): `O(P^3/3)` operations per request, `O(P)` per sample.
///
/// Safeguards: every energy update adds a tiny positive value (the floor `delta EPSILON^2`,
/// at least the smallest normal value, so that `F_m` exceeds the exact energy by `floor W_n`),
/// which keeps the energies divisible however long the input is exactly zero. The floor is
/// relative to `delta`, so a record in other units (with `delta` in those units) gives the
/// same coefficients. The conversion factor is formed as a ratio that stays in `[0, 1]`; a
/// non-finite state re-initialises the lattice (counted in
/// [`Health::restarts`](super::Health::restarts)) and [`Estimator::model`] keeps returning the
/// last good model while the restarted lattice settles.
///
/// # Stack
///
/// The order updates of [`Lattice::coefficients`] and [`Estimator::model`] keep two `P x P`
/// tables of `T` on the stack, `2 P^2 size_of::<T>()` bytes, on top of the estimator's own
/// state: for `Lattice<f32, 64>`, 32 KiB of tables. Measured on the Cortex-M4F
/// (thumbv7em-none-eabihf, release profile, stack painted below the caller under QEMU): 33,544
/// bytes of stack for `model()` at `P = 64`, next to a 34,656-byte `Lattice<f32, 64>`.
/// [`update`](Estimator::update) takes its snapshot through the same code once every
/// [`snapshot_interval`](super::snapshot_interval)`(P)` samples, so it needs that stack too.
/// Size the stack for it at high orders.
///
/// ```
/// use imu_ar::recursive::{Channel, Config, Estimator, Lattice};
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
/// let mut lattice = Lattice::<f32, 2>::new(&config, &Channel::new(0.1).unwrap());
/// for _ in 0..20_000 {
///     lattice.update(&config, sensor.next(&mut rng));
/// }
/// let model = lattice.model(&config).unwrap();
/// assert!((model.a()[0] - 1.2).abs() < 0.05 && (model.a()[1] + 0.5).abs() < 0.05);
/// assert_eq!(lattice.health().restarts, 0);
/// ```
#[derive(Clone, Copy, Debug)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub struct Lattice<T: FloatArith, const P: usize> {
    core: Core<T, P>,
    shell: Shell<T, P>,
    /// The joint-process ladder of a lattice with a prior.
    ladder: Option<Ladder<T, P>>,
}

impl<T: FloatArith, const P: usize> Lattice<T, P> {
    /// A lattice for `channel` at the initial state of the problem: `F_i = delta lambda^P`,
    /// `B_i = delta lambda^(P-i)`, zero reflection coefficients, unit conversion factors.
    pub fn new(config: &Config<T>, channel: &Channel<T>) -> Self {
        const { assert!(P > 0, "the model order P must be at least 1") };
        Self {
            core: Self::initial_core(config, channel),
            ladder: None,
            shell: Shell::new(*channel),
        }
    }

    /// A lattice that starts from the prior model `a0` with the weight `delta` of `channel`:
    /// the problem of the [module docs](super) with its regularisation centred on `a0`,
    /// `delta lambda^n (a - a0)^T D (a - a0)`. Order `P` (the a-priori error
    /// [`update`](Estimator::update) returns, [`Estimator::model`], [`Estimator::noise_variance`],
    /// [`coefficients(P)`](Self::coefficients)) is that problem's, computed by a joint-process
    /// ladder of `P` more coefficients (about `3 P` more multiplications per sample, and `P`
    /// for `d_n = y_n - a0^T phi_n`); the lower orders, [`errors`](Self::errors) and
    /// [`energy`](Self::energy) stay those of the problem centred on 0. With `a0 = 0` it is
    /// [`Lattice::new`], bit for bit.
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
        let core = Self::initial_core(config, channel);
        Ok(Self {
            ladder: Some(Ladder::new(a0, core.f_energy_p)),
            core,
            shell: Shell::new(*channel),
        })
    }

    fn initial_core(config: &Config<T>, channel: &Channel<T>) -> Core<T, P> {
        let lambda = config.lambda();
        Core::new(
            channel.delta_lambda_pow(lambda, P),
            core::array::from_fn(|i| channel.delta_lambda_pow(lambda, P - i)),
        )
    }

    /// Back to the initial state, keeping the prior.
    fn initialise(&mut self, config: &Config<T>) {
        self.core = Self::initial_core(config, self.shell.channel());
        if let Some(l) = &mut self.ladder {
            *l = Ladder::new(l.centre, self.core.f_energy_p);
        }
    }

    lattice_accessors!(T, T, T, T, "in the input's units", "`F_m(n) / W_n`");

    /// The weighted number of samples since the start or the last restart,
    /// `W_n = sum_{i<=n} lambda^(n-i)`: `n` at `lambda = 1`, `(1 - lambda^n)/(1 - lambda)` below.
    /// It stays below `1/(4 EPSILON)` (`2^21` in `f32`): there it is halved with the energies,
    /// so that both keep their precision (the memory stops growing).
    pub fn weight(&self) -> T {
        self.shell.weight()
    }

    /// The exact least-squares coefficients `a_1..a_m` of order `m <= P` after the last
    /// sample (entries past `m` are zero), from the reflection coefficients of the last `m`
    /// samples by the order updates
    ///
    /// ```text
    /// A_m(n) = [A_{m-1}(n); 0] - kf_m(n) [0; B_{m-1}(n-1)]
    /// B_m(n) = [0; B_{m-1}(n-1)] - kb_m(n) [A_{m-1}(n); 0]
    /// ```
    ///
    /// with `A_m = [1, -a^(m)]`; for a lattice with a prior, order `P` is
    /// `a0 + sum_k c_k(n) B_{k-1}(n-1)` from the ladder's coefficients `c`. `O(m^3/3)`
    /// operations, no allocation (see the stack use in the [type docs](Lattice)); `None` for
    /// `m > P`.
    pub fn coefficients(&self, m: usize) -> Option<[T; P]> {
        self.core.coefficients(m, self.ladder.as_ref(), |k| k)
    }

    /// The order-`P` energy of the published problem: the ladder's with a prior, else `F_P`.
    fn energy_p(&self) -> T {
        self.ladder
            .as_ref()
            .map_or(self.core.f_energy_p, |l| l.energy)
    }
}

impl<T: FloatArith, const P: usize> Sealed<T, P> for Lattice<T, P> {
    type Format = T;

    fn shell(&self) -> &Shell<T, P> {
        &self.shell
    }

    fn energy(&self) -> T {
        self.energy_p()
    }

    fn current(&self) -> Option<[T; P]> {
        self.coefficients(P)
    }
}

impl<T: FloatArith, const P: usize> Estimator<T, P> for Lattice<T, P> {
    type Config = Config<T>;

    fn update(&mut self, config: &Config<T>, x: T) -> Option<T> {
        if config.gate().is_some() && !self.gate(config, x) {
            return None;
        }
        let y = self.shell.intake(config, x)?;
        self.step(config, y, true)
    }
}

impl<T: FloatArith, const P: usize> super::settled::Start<T, P> for Lattice<T, P> {
    fn screen(&mut self, x: T) -> Option<T> {
        self.shell.screen(x)
    }

    fn start(&mut self, config: &Config<T>, a0: &[T; P], history: &[T; P], mean: (T, T, u64)) {
        self.core = Self::initial_core(config, self.shell.channel());
        self.ladder = Some(Ladder::new(*a0, self.core.f_energy_p));
        for &y in history.iter().rev() {
            self.step(config, y, false);
        }
        self.shell.settle(mean.0, mean.1, mean.2);
    }
}

impl<T: FloatArith, const P: usize> Lattice<T, P> {
    /// The gate's decision on `x` (see [`Gate`](super::Gate)): `false` rejects it, counted.
    /// Out of line: an estimator without a gate pays one test for it.
    #[inline(never)]
    fn gate(&mut self, config: &Config<T>, x: T) -> bool {
        let energy = self.energy_p();
        let (core, ladder) = (&self.core, &self.ladder);
        self.shell.gate(config, x, energy, |y| match ladder {
            Some(l) => l.a_priori(core, y),
            None => core.a_priori(y),
        })
    }

    /// Takes the centred sample `y`; a history sample (`equation = false`, a settled start)
    /// goes through the stages and enters the ladder's delay line with `d = 0`.
    #[inline(always)]
    fn step(&mut self, config: &Config<T>, y: T, equation: bool) -> Option<T> {
        let params = float_params(config, self.shell.channel());
        let mut clip = 0;
        // The ladder keeps its error (no value of its own lives through the stages).
        if let Some(l) = &mut self.ladder {
            l.step(&self.core, &params, y, equation, &mut clip);
        }
        let f = self.core.step(&params, y, &mut clip);
        let e = self.ladder.as_ref().map_or(f, |l| l.error);
        // A non-finite value anywhere reaches f_P within a sample or two (the reflection
        // coefficients feed the errors), and an overflowing input reaches F_0 and F_P at once.
        let c = &self.core;
        let check = e + f + c.f_energy_p + c.stages[0].f_energy + self.energy_p();
        if !check.is_finite() {
            self.initialise(config);
            self.shell.restart(config.lambda().to_f64());
            return None;
        }
        if self.shell.weight_full() {
            self.core.halve_energies();
            if let Some(l) = &mut self.ladder {
                l.energy *= T::from_f64(0.5);
            }
            self.shell.halve_weight();
        }
        let (core, ladder) = (&self.core, self.ladder.as_ref());
        self.shell.refresh(config.dt(), self.energy_p(), || {
            core.coefficients(P, ladder, |k| k)
        });
        Some(e)
    }
}
