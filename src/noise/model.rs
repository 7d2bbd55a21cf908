//! The fitted composite model: its Allan variance, its IEEE 952 readings, its Kalman filter
//! form and its Allan check.

use crate::model::ArModel;

use super::component;
use super::{NoiseError, NoiseType, Octaves, indexed};

/// One first-order Gauss-Markov term: `dx/dt = -x / T + u`, stationary standard deviation
/// `sigma`.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub struct GmTerm {
    /// Stationary standard deviation, in u.
    pub sigma: f64,
    /// Correlation time `T`, in s.
    pub correlation_time: f64,
}

/// One second-order Gauss-Markov term (a damped oscillator, two Kalman states): the stationary
/// process with poles `-1/T +- i 2 pi f`, variance `sigma^2`.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub struct Oscillator {
    /// Stationary standard deviation, in u.
    pub sigma: f64,
    /// Centre frequency `f`, Hz.
    pub frequency: f64,
    /// Decay time `T`, s.
    pub decay_time: f64,
}

/// The composite noise model of one sensor axis, with at most `G` Gauss-Markov terms and an
/// optional AR(`P`) part; see the [module docs](super) for the components and units.
#[derive(Clone, Copy, Debug, PartialEq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub struct NoiseModel<const P: usize, const G: usize> {
    pub(super) dt: f64,
    pub(super) quantization: f64,
    pub(super) white: f64,
    pub(super) random_walk: f64,
    pub(super) ramp: f64,
    pub(super) gm: [GmTerm; G],
    pub(super) gm_len: usize,
    pub(super) osc: [Oscillator; G],
    pub(super) osc_len: usize,
    pub(super) ar: Option<ArModel<f64, P>>,
}

/// The IEEE Std 952-1997 (Annex C) readings of a model and the data it was fitted to.
#[derive(Clone, Copy, Debug, PartialEq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub struct Ieee952 {
    /// Angle (velocity) random walk `N` of the whole model, u/sqrt(Hz): the white term and the
    /// AR part's white equivalent at long `tau`, `sqrt(N_w^2 + N_ar^2)`.
    pub white_noise: f64,
    /// `N` read as the data's Allan deviation at `tau = 1 s` (interpolated log-log between
    /// octaves), the reading of Kalibr and allan_variance_ros users; `None` when the data do
    /// not reach 1 s.
    pub white_noise_at_1s: Option<f64>,
    /// Quantisation `Q`, u s.
    pub quantization: f64,
    /// Rate random walk `K`, u/s/sqrt(Hz).
    pub random_walk: f64,
    /// Rate ramp `R`, u/s.
    pub ramp: f64,
    /// Bias instability `B = min ADEV / 0.664` of the data, u, and the `tau` of that minimum, s.
    pub bias_instability: (f64, f64),
}

/// One filter state of a Gauss-Markov term at the filter's step `Dt`.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub struct GmState {
    /// `Phi = exp(-Dt / T)`.
    pub phi: f64,
    /// `Qd = sigma^2 (1 - exp(-2 Dt / T))`, u^2.
    pub q: f64,
    /// Stationary `P0 = sigma^2`, u^2.
    pub p0: f64,
}

/// The two filter states `[x, dx/dt]` of an oscillator at the filter's step `Dt`: the
/// continuous-time process `x'' + 2 x' / T + (w^2 + 1/T^2) x = noise` (`w = 2 pi f`) with the
/// oscillator's poles and variance, sampled exactly: `Phi = exp(A Dt)`, `P0 = diag(sigma^2,
/// (w^2 + 1/T^2) sigma^2)` and `Qd = P0 - Phi P0 Phi^T`, computed as the integral it equals
/// so that it keeps its precision at any filter rate.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub struct OscillatorState {
    /// `Phi`, row-major.
    pub phi: [[f64; 2]; 2],
    /// `Qd`, u^2 and u^2/s^2.
    pub q: [[f64; 2]; 2],
    /// Stationary `P0`.
    pub p0: [[f64; 2]; 2],
}

impl OscillatorState {
    fn new(o: &Oscillator, dt: f64) -> Self {
        let (alpha, w) = (
            1.0 / o.decay_time,
            2.0 * core::f64::consts::PI * o.frequency,
        );
        let wn2 = w * w + alpha * alpha;
        // exp(A t) = exp(-alpha t) [cos(w t) I + sin(w t) / w (A + alpha I)],
        // A = [[0, 1], [-wn^2, -2 alpha]].
        let (e, c, sn) = (
            libm::exp(-alpha * dt),
            libm::cos(w * dt),
            libm::sin(w * dt) / w,
        );
        let phi = [
            [e * (c + sn * alpha), e * sn],
            [-e * sn * wn2, e * (c - sn * alpha)],
        ];
        let s2 = o.sigma * o.sigma;
        let p = [s2, wn2 * s2];
        // The noise drives dx/dt with density 4 alpha wn^2 sigma^2, which keeps P0 stationary.
        let qc = 4.0 * alpha * wn2 * s2;
        let [i11, i12, i22] = response_integrals(alpha, w, dt);
        let q12 = qc * i12;
        Self {
            phi,
            q: [[qc * i11, q12], [q12, qc * i22]],
            p0: [[p[0], 0.0], [0.0, p[1]]],
        }
    }
}

/// `int_0^dt exp(-2 alpha s) g_i(s) g_j(s) ds` for the oscillator's impulse response into its
/// two states, `g_1 = sin(w s) / w`, `g_2 = cos(w s) - alpha sin(w s) / w` (the second column
/// of `exp(A s)` without its `exp(-alpha s)`): `[I_11, I_12, I_22]`, so that
/// `Qd = q_c I`. `P0 - Phi P0 Phi^T` gives the same in exact arithmetic but cancels where the
/// step is short against the period and the decay (a relative error of `eps / (alpha dt)`);
/// here every entry is computed to a few `eps` of its own size.
///
/// Up to [`QUADRATURE_SPAN`] radians of `|alpha + i w| dt` (`dt` at most 40 decay times):
/// composite Gauss-Legendre, 16 nodes
/// on each piece of at most a quarter radian (the integrands are entire, and the rule exact to
/// degree 31). Beyond: the integrals in closed form, `sin^2`, `cos^2` and `sin cos` written with
/// `K = int_0^dt exp((-2 alpha + 2 i w) s) ds`, and `exp(z dt) - 1` evaluated without
/// cancellation (`expm1`, and `cos - 1 = -2 sin^2(/2)`).
fn response_integrals(alpha: f64, w: f64, dt: f64) -> [f64; 3] {
    // Past 40 decay times the integrands are below exp(-80) of their start: not integrated.
    let span = if alpha > 0.0 {
        dt.min(40.0 / alpha)
    } else {
        dt
    };
    let reach = libm::hypot(alpha, w) * span;
    // With w <= alpha the reach is at most 40 sqrt(2): the closed form below has w > 0.
    if reach <= QUADRATURE_SPAN {
        let pieces = libm::ceil(reach / 0.25).max(1.0);
        let h = span / pieces;
        let mut sum = [0.0; 3];
        let mut a = 0.0;
        // `pieces` is at most QUADRATURE_SPAN / 0.25 + 1.
        for _ in 0..pieces as u32 {
            for (x, wt) in GAUSS_16 {
                for sign in [-1.0, 1.0] {
                    let s = a + 0.5 * h * (1.0 + sign * x);
                    let (sin, cos) = (libm::sin(w * s), libm::cos(w * s));
                    let decay = libm::exp(-2.0 * alpha * s);
                    let g1 = if w > 0.0 { sin / w } else { s };
                    let g2 = cos - alpha * g1;
                    let c = 0.5 * h * wt * decay;
                    sum[0] += c * g1 * g1;
                    sum[1] += c * g1 * g2;
                    sum[2] += c * g2 * g2;
                }
            }
            a += h;
        }
        return sum;
    }
    let (beta, gamma) = (2.0 * alpha, 2.0 * w);
    // J0 = int exp(-beta s) ds; K = (exp(z dt) - 1) / z, z = -beta + i gamma.
    let j0 = if beta > 0.0 {
        -libm::expm1(-beta * dt) / beta
    } else {
        dt
    };
    let em = libm::expm1(-beta * dt);
    let half = libm::sin(0.5 * gamma * dt);
    let (re_num, im_num) = (
        em * libm::cos(gamma * dt) - 2.0 * half * half,
        (1.0 + em) * libm::sin(gamma * dt),
    );
    // Divided by z = -beta + i gamma.
    let norm = beta * beta + gamma * gamma;
    let (re_k, im_k) = (
        (-re_num * beta + im_num * gamma) / norm,
        (-im_num * beta - re_num * gamma) / norm,
    );
    let (ss, cc, sc) = (0.5 * (j0 - re_k), 0.5 * (j0 + re_k), 0.5 * im_k);
    let w2 = w * w;
    [
        ss / w2,
        sc / w - alpha * ss / w2,
        cc - 2.0 * alpha * sc / w + alpha * alpha * ss / w2,
    ]
}

/// The reach `|alpha + i w| dt` up to which [`response_integrals`] integrates numerically.
const QUADRATURE_SPAN: f64 = 64.0;

/// The positive nodes of the 16-point Gauss-Legendre rule on [-1, 1], with their weights.
const GAUSS_16: [(f64, f64); 8] = [
    (0.095_012_509_837_637_44, 0.189_450_610_455_068_64),
    (0.281_603_550_779_258_9, 0.182_603_415_044_923_64),
    (0.458_016_777_657_227_37, 0.169_156_519_395_002_65),
    (0.617_876_244_402_643_8, 0.149_595_988_816_576_7),
    (0.755_404_408_355_003, 0.124_628_971_255_534_07),
    (0.865_631_202_387_831_8, 0.095_158_511_682_492_6),
    (0.944_575_023_073_232_6, 0.062_253_523_938_647_456),
    (0.989_400_934_991_649_9, 0.027_152_459_411_754_176),
];

/// The two filter states `[q_k / Dt, q_(k-1) / Dt]` of quantisation `Q` at the filter's step
/// `Dt`: the quantisation error `q_k ~ N(0, Q^2)` of the integrated sensor (angle or velocity)
/// at the end of step `k`, over `Dt`, and the same at the end of the step before.
///
/// A quantised sample carries `(q_n - q_(n-1)) / dt`, white noise on the integrated angle; its
/// Allan variance is `3 Q^2 / tau^2`. The filter's measurement, the sensor averaged over one
/// step, carries `(q_k - q_(k-1)) / Dt` (the terms of the samples inside the step cancel in
/// pairs), so the same `Q` holds at any step `Dt` that is a multiple of the data's `dt`. The
/// term is a moving average of order 1 across steps, which white measurement noise cannot
/// represent: white noise of its variance `2 Q^2 / Dt^2` has the Allan variance
/// `2 Q^2 / (Dt tau)`, `2 tau / (3 Dt)` times the true one (too small at `tau = Dt`, too large
/// from `2 Dt` on, without bound).
///
/// - `Phi = [[0, 0], [1, 0]]`: the new error is fresh, the old one is the last step's new one.
/// - `Qd = diag(Q^2 / Dt^2, 0)`.
/// - `P0 = diag(Q^2 / Dt^2, Q^2 / Dt^2)`, the stationary covariance.
/// - Measurement row `h = [1, -1]`.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub struct QuantizationStates {
    /// Quantisation `Q`, u s.
    pub coefficient: f64,
    /// `Phi = [[0, 0], [1, 0]]`, row-major.
    pub phi: [[f64; 2]; 2],
    /// `Qd = diag(Q^2 / Dt^2, 0)`, u^2.
    pub q: [[f64; 2]; 2],
    /// Stationary `P0 = diag(Q^2 / Dt^2, Q^2 / Dt^2)`, u^2.
    pub p0: [[f64; 2]; 2],
    /// The pair's measurement row, `[1, -1]`.
    pub h: [f64; 2],
}

impl QuantizationStates {
    /// The pair of quantisation `Q` (u s) at the filter's step `Dt` (s).
    pub fn new(q: f64, dt: f64) -> Self {
        let v = (q / dt) * (q / dt);
        Self {
            coefficient: q,
            phi: [[0.0, 0.0], [1.0, 0.0]],
            q: [[v, 0.0], [0.0, 0.0]],
            p0: [[v, 0.0], [0.0, v]],
            h: [1.0, -1.0],
        }
    }
}

/// The model as a Kalman filter stepping every `Dt` takes it: one state per Gauss-Markov term,
/// two per oscillator, one random-walk state, two quantisation states, and the white part as
/// measurement noise or as a process-noise density. The AR part, if any, is folded into the
/// white part (its equivalent at long `tau`): a filter that needs its short-term colouring
/// takes [`NoiseModel::ar`] in companion form ([`ArModel::discretize`]) instead.
///
/// The states are independent blocks, each `x_(k+1) = Phi x_k + w_k` with `Cov(w_k) = Qd` and
/// `x_0 ~ (0, P0)`. The sensor averaged over step `k` (a filter that uses it as a
/// measurement) is
///
/// `z_k = sum gm + sum osc.x + random_walk + (q_k / Dt - q_(k-1) / Dt) + v_k`,
///
/// `v_k` white of variance [`measurement_variance`](Self::measurement_variance): the
/// measurement row is 1 on every Gauss-Markov state, on each oscillator's `x` and on the
/// random walk, 0 on an oscillator's `dx/dt`, and [`QuantizationStates::h`] `= [1, -1]` on
/// the quantisation pair. The Allan variance of `z` at `tau = m Dt` is the model's: exactly
/// for quantisation and the white part; for the Gauss-Markov terms and the random walk, up to
/// the difference between their values at the end of a step and their means over it, which
/// is negligible where they matter (`tau >> Dt`).
///
/// A filter that keeps no quantisation states takes the equivalent noise of the pair: a
/// measurement noise of variance `N^2 / Dt + 2 Q^2 / Dt^2` whose lag-1 covariance is
/// `-Q^2 / Dt^2` (zero beyond). A strapdown filter that integrates the sensor sees
/// quantisation as white noise of variance `Q^2` on the integrated angle or velocity (an error
/// that does not accumulate), and the white part as process noise of density
/// [`white_psd`](Self::white_psd).
#[derive(Clone, Copy, Debug, PartialEq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub struct KalmanForm<const G: usize> {
    /// The filter's step `Dt`, s.
    pub dt: f64,
    /// The Gauss-Markov states, `[..gm_len]`.
    pub gm: [GmState; G],
    /// How many Gauss-Markov states.
    pub gm_len: usize,
    /// The oscillators' state pairs, `[..osc_len]`.
    pub osc: [OscillatorState; G],
    /// How many oscillators.
    pub osc_len: usize,
    /// The random-walk state (`Phi = 1`, `Qd = K^2 Dt`, `P0` the turn-on bias variance the
    /// caller gave), or `None` when the model has no random walk.
    pub random_walk: Option<GmState>,
    /// The quantisation pair `[q_k / Dt, q_(k-1) / Dt]`, or `None` when the model has no
    /// quantisation.
    pub quantization: Option<QuantizationStates>,
    /// Variance of the white part of the sensor averaged over one step `Dt`, `N^2 / Dt`, u^2:
    /// the measurement noise `v_k` besides the states. Quantisation is not in it: it is the
    /// [`quantization`](Self::quantization) pair.
    pub measurement_variance: f64,
    /// Two-sided PSD of the white part, `N^2`, u^2/Hz (u^2 s): the process noise density of the
    /// integrated angle or velocity in a strapdown filter.
    pub white_psd: f64,
}

/// One row of the Allan check.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub struct AllanRow {
    /// `tau`, s.
    pub tau: f64,
    /// The data's Allan deviation, u.
    pub data_adev: f64,
    /// The model's Allan deviation, u.
    pub model_adev: f64,
    /// The relative standard error of the measured deviation, `1 / sqrt(2 nu)`, with the
    /// degrees of freedom `nu` of the estimator and of the noise type that dominates the model
    /// there.
    pub standard_error: f64,
    /// `z` standard errors of the measured deviation, `z / sqrt(2 nu)`, or 0.1 where that is
    /// larger, as a fraction; `z` is the check's ([`Check::z`]).
    pub tolerance: f64,
    /// `data / model` within the `z`-standard-error interval of the measured deviation: the
    /// chi^2 interval at `+-z` for `nu` degrees of freedom (Wilson-Hilferty), widened to at
    /// least `[0.9, 1.1]`. For many degrees of freedom this is `1 +- tolerance`; for few, it is
    /// skewed as the chi^2 distribution is (at `z = 2`: with 4 degrees of freedom, 0.33 to
    /// 1.68; with 1, 0.03 to 2.2), so that a model far above the data fails however wide the
    /// tolerance.
    pub agrees: bool,
}

/// The Allan check of a model against the octaves it describes.
#[derive(Clone, Copy, Debug, PartialEq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub struct Check<const L: usize> {
    z: f64,
    rows: [AllanRow; L],
    len: usize,
}

impl<const L: usize> Check<L> {
    /// The normal deviate of every row's test, so that the check as a whole is a 95 % test
    /// (see [`NoiseModel::check`]).
    pub fn z(&self) -> f64 {
        self.z
    }

    /// The rows, one per octave.
    pub fn rows(&self) -> &[AllanRow] {
        &self.rows[..self.len.min(L)]
    }

    /// The largest `tau` up to which every row agrees, or `None` when the first does not.
    pub fn explained_up_to(&self) -> Option<f64> {
        self.rows()
            .iter()
            .take_while(|r| r.agrees)
            .last()
            .map(|r| r.tau)
    }

    /// Whether every row agrees.
    pub fn holds(&self) -> bool {
        self.rows().iter().all(|r| r.agrees)
    }
}

impl<const P: usize, const G: usize> NoiseModel<P, G> {
    /// The data's sample interval, s.
    pub fn dt(&self) -> f64 {
        self.dt
    }

    /// Quantisation `Q`, u s.
    pub fn quantization(&self) -> f64 {
        self.quantization
    }

    /// `N` of the white term alone, u/sqrt(Hz).
    pub fn white_term(&self) -> f64 {
        self.white
    }

    /// `N` of the whole model, u/sqrt(Hz): the white term and the AR part's white equivalent
    /// at long `tau`, `N_ar^2 = sigma_w^2 dt / (1 - sum a_k)^2`.
    pub fn white_noise(&self) -> f64 {
        libm::sqrt(self.white * self.white + self.ar_white_psd())
    }

    /// Rate random walk `K`, u/s/sqrt(Hz).
    pub fn random_walk(&self) -> f64 {
        self.random_walk
    }

    /// Rate ramp `R`, u/s.
    pub fn ramp(&self) -> f64 {
        self.ramp
    }

    /// The Gauss-Markov terms, by increasing correlation time.
    pub fn gauss_markov(&self) -> &[GmTerm] {
        &self.gm[..self.gm_len.min(G)]
    }

    /// The second-order Gauss-Markov terms (two Kalman states each), by increasing frequency.
    pub fn oscillators(&self) -> &[Oscillator] {
        &self.osc[..self.osc_len.min(G)]
    }

    /// The AR part, with the noise variance the fit scaled it to.
    pub fn ar(&self) -> Option<&ArModel<f64, P>> {
        self.ar.as_ref()
    }

    pub(super) fn ar_white_psd(&self) -> f64 {
        self.ar
            .as_ref()
            .map_or(0.0, |ar| ar_white_equivalent(ar, self.dt))
    }

    /// The model's Allan variance at `tau = 2^j dt` for `j < out.len()`, in u^2.
    ///
    /// # Errors
    ///
    /// [`NoiseError::Ar`] when the AR part is not stationary (a fitted model's always is).
    pub fn avar_octaves(&self, out: &mut [f64]) -> Result<(), NoiseError> {
        match &self.ar {
            Some(ar) => component::ar_octaves(ar, out).map_err(NoiseError::Ar)?,
            None => out.fill(0.0),
        }
        for (j, v) in indexed(out.iter_mut()) {
            let (_, total) = self.dominant(1u64 << j.min(63));
            *v += total;
            for o in self.oscillators() {
                let unit = component::oscillator(self.dt, o.frequency, o.decay_time, j)
                    .map_err(NoiseError::Ar)?;
                *v += o.sigma * o.sigma * unit;
            }
        }
        Ok(())
    }

    /// The noise type that dominates the model's Allan variance at `m` (the AR part counts as
    /// white, oscillators do not count), and the Allan variance of every component but the AR
    /// part and the oscillators.
    pub(super) fn dominant(&self, m: u64) -> (NoiseType, f64) {
        let dt = self.dt;
        let tau = m as f64 * dt;
        let sq = |v: f64| v * v;
        // A component that is absent adds nothing, even where its unit curve overflows.
        let term = |p: f64, unit: f64| if p == 0.0 { 0.0 } else { p * unit };
        let mut parts = [
            (
                NoiseType::WhitePhase,
                term(sq(self.quantization), component::quantization(dt, m)),
            ),
            (
                NoiseType::WhiteFrequency,
                term(
                    sq(self.white) + self.ar_white_psd(),
                    component::white(dt, m),
                ),
            ),
            (
                NoiseType::RandomWalkFrequency,
                term(sq(self.random_walk), component::random_walk(dt, m))
                    + term(sq(self.ramp), component::ramp(dt, m)),
            ),
            (NoiseType::FlickerFrequency, 0.0),
        ];
        let mut total = parts[0].1 + parts[2].1 + term(sq(self.white), component::white(dt, m));
        for t in self.gauss_markov() {
            let v = sq(t.sigma) * component::gauss_markov(dt, t.correlation_time, m);
            total += v;
            let kind = match tau / t.correlation_time {
                r if r < 0.5 => 2,
                r if r > 4.0 => 1,
                _ => 3,
            };
            parts[kind].1 += v;
        }
        let kind = parts
            .iter()
            .max_by(|p, q| p.1.total_cmp(&q.1))
            .map_or(NoiseType::WhiteFrequency, |p| p.0);
        (kind, total)
    }

    /// The Allan check against `octaves` (the data the model describes): at every octave, the
    /// model's deviation must be within `z` standard errors of the measured one, or within
    /// 10 %, whichever is larger (`noise-model.md` section 4). The standard error is that of
    /// the estimator that measured the octaves, with the degrees of freedom of the noise type
    /// that dominates the model there ([`super::Estimator::edf`]).
    ///
    /// Here `z = 2`: a test at 95 % per octave. [`NoiseModel::check_whole`] is the check as one
    /// 95 % test of the whole curve.
    ///
    /// # Errors
    ///
    /// [`NoiseError::Ar`] when the AR part is not stationary.
    pub fn check<const L: usize>(&self, octaves: &Octaves<L>) -> Result<Check<L>, NoiseError> {
        self.check_at(octaves, 2.0)
    }

    /// The Allan check as one 95 % test of the whole curve: each of the `L` octaves held at the
    /// level `0.95^(1/L)` (Sidak), so that the true model passes every octave of 95 % of
    /// records (`z = 2.98` for 18 octaves, 3.02 for 20). Per octave at `z = 2`
    /// ([`NoiseModel::check`]), the true model failed somewhere on a quarter of the records of
    /// the identification campaign (`host-tests`, 24 of 96).
    ///
    /// # Errors
    ///
    /// As [`NoiseModel::check`].
    pub fn check_whole<const L: usize>(
        &self,
        octaves: &Octaves<L>,
    ) -> Result<Check<L>, NoiseError> {
        self.check_at(octaves, family_z(octaves.avar().len()))
    }

    fn check_at<const L: usize>(
        &self,
        octaves: &Octaves<L>,
        z: f64,
    ) -> Result<Check<L>, NoiseError> {
        let mut model = [0.0; L];
        self.avar_octaves(&mut model)?;
        let mut rows = [AllanRow::default(); L];
        let data = octaves.avar();
        for (j, ((row, d), v)) in indexed(rows.iter_mut().zip(data).zip(&model)) {
            let m = 1u64 << j.min(63);
            let nu = octaves.edf(j, self.dominant(m).0);
            let (data_adev, model_adev) = (libm::sqrt(*d), libm::sqrt(*v));
            let standard_error = 1.0 / libm::sqrt(2.0 * nu);
            let tolerance = (z * standard_error).max(0.1);
            *row = AllanRow {
                tau: octaves.tau(j),
                data_adev,
                model_adev,
                standard_error,
                tolerance,
                agrees: agrees(data_adev / model_adev, nu, z),
            };
        }
        Ok(Check {
            z,
            rows,
            len: data.len(),
        })
    }

    /// The IEEE 952 readings of the model, with `B` and the 1 s reading of `N` taken from the
    /// data `octaves`.
    pub fn ieee952<const L: usize>(&self, octaves: &Octaves<L>) -> Ieee952 {
        let adev = |j: usize| libm::sqrt(octaves.avar().get(j).copied().unwrap_or(0.0));
        let lowest = (0..octaves.avar().len())
            .min_by(|&p, &q| adev(p).total_cmp(&adev(q)))
            .map_or((0.0, 0.0), |j| (adev(j) / 0.664, octaves.tau(j)));
        // Log-log interpolation between the octaves around 1 s.
        let at_1s = (1..octaves.avar().len())
            .find(|&j| octaves.tau(j - 1) <= 1.0 && octaves.tau(j) >= 1.0)
            .map(|j| {
                let (t0, t1) = (octaves.tau(j - 1), octaves.tau(j));
                let f = libm::log(1.0 / t0) / libm::log(t1 / t0);
                libm::exp(libm::log(adev(j - 1)) * (1.0 - f) + libm::log(adev(j)) * f)
            })
            .filter(|v| v.is_finite());
        Ieee952 {
            white_noise: self.white_noise(),
            white_noise_at_1s: at_1s,
            quantization: self.quantization,
            random_walk: self.random_walk,
            ramp: self.ramp,
            bias_instability: lowest,
        }
    }

    /// The model as a Kalman filter stepping every `dt_filter` seconds takes it (see
    /// [`KalmanForm`]); `random_walk_p0` is the random-walk state's initial variance (the
    /// turn-on bias uncertainty, which one recording cannot give), u^2.
    ///
    /// Gauss-Markov terms and the random walk are continuous-time processes, sampled exactly
    /// at any step. White noise and quantisation are exact for a filter that averages the
    /// data's samples over each step, at a step `Dt` that is a multiple of the data's `dt`
    /// (the mean of `N^2 / dt` white samples over `Dt` has the variance `N^2 / Dt`, and the mean
    /// of `(q_n - q_(n-1)) / dt` is `(q_end - q_start) / Dt`, the same `Q`).
    ///
    /// # Errors
    ///
    /// [`NoiseError::Interval`] for a step that is not positive and finite or so small or
    /// large that `1 / Dt^2` or `Dt^2` overflows (whether or not the model has quantisation), a
    /// negative or non-finite `random_walk_p0`, or a step that makes a variance overflow.
    pub fn kalman(&self, dt_filter: f64, random_walk_p0: f64) -> Result<KalmanForm<G>, NoiseError> {
        let square = dt_filter * dt_filter;
        let step_ok = dt_filter.is_finite()
            && dt_filter > 0.0
            && square.is_finite()
            && (1.0 / square).is_finite();
        let p0_ok = random_walk_p0.is_finite() && random_walk_p0 >= 0.0;
        if !(step_ok && p0_ok) {
            return Err(NoiseError::Interval);
        }
        let mut gm = [GmState::default(); G];
        for (state, t) in gm.iter_mut().zip(self.gauss_markov()) {
            let s2 = t.sigma * t.sigma;
            *state = GmState {
                phi: libm::exp(-dt_filter / t.correlation_time),
                q: -s2 * libm::expm1(-2.0 * dt_filter / t.correlation_time),
                p0: s2,
            };
        }
        let mut osc = [OscillatorState::default(); G];
        for (state, o) in osc.iter_mut().zip(self.oscillators()) {
            *state = OscillatorState::new(o, dt_filter);
        }
        let k2 = self.random_walk * self.random_walk;
        let n2 = self.white_noise() * self.white_noise();
        let form = KalmanForm {
            dt: dt_filter,
            gm,
            gm_len: self.gm_len,
            osc,
            osc_len: self.osc_len,
            random_walk: (k2 > 0.0).then_some(GmState {
                phi: 1.0,
                q: k2 * dt_filter,
                p0: random_walk_p0,
            }),
            quantization: (self.quantization > 0.0)
                .then(|| QuantizationStates::new(self.quantization, dt_filter)),
            measurement_variance: n2 / dt_filter,
            white_psd: n2,
        };
        // A step so short or so long that a variance overflows has no filter form.
        let states = form.gm.iter().chain(form.random_walk.as_ref());
        let pairs = form.osc.iter().map(|s| (&s.phi, &s.q, &s.p0));
        let pairs = pairs.chain(form.quantization.iter().map(|s| (&s.phi, &s.q, &s.p0)));
        let finite = states.flat_map(|s| [s.phi, s.q, s.p0]).all(f64::is_finite)
            && pairs
                .flat_map(|(phi, q, p0)| phi.iter().chain(q).chain(p0).flatten())
                .copied()
                .all(f64::is_finite)
            && form.measurement_variance.is_finite();
        if finite {
            Ok(form)
        } else {
            Err(NoiseError::Interval)
        }
    }
}

/// Whether `ratio = data / model` is within the check's interval for a deviation measured with
/// `nu` degrees of freedom (see [`AllanRow::agrees`]).
fn agrees(ratio: f64, nu: f64, z: f64) -> bool {
    // No degrees of freedom: no estimate to agree with.
    if nu.is_nan() || nu <= 0.0 {
        return false;
    }
    // Wilson-Hilferty: chi^2_nu / nu at z standard normal deviations is about
    // (1 - c + z sqrt(c))^3 with c = 2 / (9 nu).
    let c = 2.0 / (9.0 * nu);
    let quantile = |z: f64| {
        let b = 1.0 - c + z * libm::sqrt(c);
        if b > 0.0 { b * b * b } else { 0.0 }
    };
    // Below a few degrees of freedom that lower bound reaches 0; the lower tail of chi^2
    // there, P(chi^2 < x) ~ (x/2)^(nu/2) / Gamma(nu/2 + 1), keeps one (the -z tail's
    // probability is erfc(z / sqrt 2) / 2).
    let p = libm::erfc(z / core::f64::consts::SQRT_2) / 2.0;
    let tail = 2.0 * libm::pow(p * libm::tgamma(nu / 2.0 + 1.0), 2.0 / nu) / nu;
    let lower = libm::sqrt(quantile(-z).max(tail)).min(0.9);
    let upper = libm::sqrt(quantile(z)).max(1.1);
    (lower..=upper).contains(&ratio)
}

/// The normal deviate `z` of a 95 % test over `rows` octaves together: each at the two-sided
/// level `1 - 0.95^(1/rows)` (Sidak), by bisection of `erfc(z / sqrt 2) = alpha`.
pub(super) fn family_z(rows: usize) -> f64 {
    let rows = rows.max(1) as f64;
    let alpha = -libm::expm1(libm::log(0.95) / rows);
    let (mut lo, mut hi) = (0.0f64, 10.0f64);
    for _ in 0..60 {
        let mid = (lo + hi) / 2.0;
        if libm::erfc(mid / core::f64::consts::SQRT_2) > alpha {
            lo = mid;
        } else {
            hi = mid;
        }
    }
    (lo + hi) / 2.0
}

/// The white equivalent of the AR part `ar` sampled every `dt`: `sigma^2 dt / (1 - sum a)^2`,
/// u^2/Hz, the level its Allan variance times `tau` reaches past its memory.
pub(super) fn ar_white_equivalent<const P: usize>(ar: &ArModel<f64, P>, dt: f64) -> f64 {
    let gain = 1.0 - ar.a().iter().sum::<f64>();
    ar.noise_variance() * dt / (gain * gain)
}

#[cfg(test)]
mod tests {
    use super::*;

    /// `[I_11, I_12, I_22]` of [`response_integrals`] by composite Simpson on 400,000 panels
    /// with compensated sums: slow, and independent of the rule under test.
    fn simpson(alpha: f64, w: f64, dt: f64) -> [f64; 3] {
        const PANELS: usize = 400_000;
        let h = dt / PANELS as f64;
        let mut sum = [(0.0f64, 0.0f64); 3];
        for i in 0..=PANELS {
            let s = i as f64 * h;
            let weight = if i == 0 || i == PANELS {
                1.0
            } else if i % 2 == 1 {
                4.0
            } else {
                2.0
            };
            let decay = (-2.0 * alpha * s).exp();
            let g1 = (w * s).sin() / w;
            let g2 = (w * s).cos() - alpha * g1;
            for (acc, v) in sum.iter_mut().zip([g1 * g1, g1 * g2, g2 * g2]) {
                // Kahan: acc.0 the sum, acc.1 its lost low part.
                let y = weight * decay * v - acc.1;
                let t = acc.0 + y;
                acc.1 = (t - acc.0) - y;
                acc.0 = t;
            }
        }
        sum.map(|(v, _)| v * h / 3.0)
    }

    #[test]
    fn the_oscillator_noise_keeps_its_precision_at_every_filter_rate() {
        // (frequency Hz, decay s): a 0.6 Hz line with damping 0.05, a fast damped one, a
        // slow one that barely decays.
        for (f, decay) in [(0.6, 5.3), (12.0, 0.8), (0.1, 1000.0)] {
            let o = Oscillator {
                sigma: 0.3,
                frequency: f,
                decay_time: decay,
            };
            let (alpha, w) = (1.0 / decay, 2.0 * core::f64::consts::PI * f);
            for rate in [0.05, 1.0, 10.0, 100.0, 1e3, 1e4, 1e5, 1e6] {
                let dt = 1.0 / rate;
                let got = response_integrals(alpha, w, dt);
                let want = simpson(alpha, w, dt);
                let scale = (want[0] * want[2]).sqrt();
                for (k, (g, r)) in got.iter().zip(want).enumerate() {
                    let size = if k == 1 { scale } else { r };
                    assert!(
                        (g - r).abs() <= 1e-12 * size,
                        "f {f} decay {decay} rate {rate}: I[{k}] {g:e}, reference {r:e}"
                    );
                }
                // Stationary: Phi P0 Phi^T + Qd = P0, and Qd positive definite.
                let s = OscillatorState::new(&o, dt);
                assert!(s.q[0][0] > 0.0 && s.q[0][0] * s.q[1][1] > s.q[0][1] * s.q[0][1]);
                for i in 0..2 {
                    for k in 0..2 {
                        let fpf: f64 = (0..2).map(|l| s.phi[i][l] * s.p0[l][l] * s.phi[k][l]).sum();
                        let p = s.p0[i][k];
                        let size = (s.p0[i][i] * s.p0[k][k]).sqrt();
                        assert!((fpf + s.q[i][k] - p).abs() <= 1e-12 * size, "rate {rate}");
                    }
                }
            }
        }
    }
}
