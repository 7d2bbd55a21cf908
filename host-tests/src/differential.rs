//! The differential check of the fixed-point lattice against the f64 lattice, shared by the
//! property test (`host-tests/tests/host/differential.rs`) and the `fixed_differential` fuzz target.
//!
//! Between restarts the fixed lattice must agree with an f64 lattice fed the same samples
//! (restarted where the fixed one restarts), to [`TOL`] on the coefficients and the mean; a
//! saturation must come with a restart; and after the first restart the published model must
//! be the one a fresh fixed lattice gives on the samples before it (the last good model), for
//! as long as the hold lasts. A silently wrong model fails.

use imu_ar::ArModel;
use imu_ar::recursive::Lattice;
use imu_ar::recursive::{Channel, Config, Estimator, FixedChannel, FixedConfig, FixedLattice};

/// The fixed-point tolerance against the f64 lattice, on the coefficients and on the mean (in
/// internal units: `scale = 1`), as in issue 22's acceptance. Where the data leave the
/// coefficients undetermined (a constant stretch without mean removal: any `a` with the same
/// sum fits it), the coefficients are compared in the data's own metric instead: the two
/// models' predictions of the data may differ by `TOL` times their RMS. Where the f64 lattice's
/// recursion itself loses its accuracy (a jump after a long constant stretch at a short
/// memory, its coefficients in the millions), the fixed lattice's predictions are held to
/// those of a direct least-squares solve of the same data, to the same `TOL`.
pub const TOL: f64 = 0.01;

macro_rules! ensure {
    ($cond:expr, $($fmt:tt)*) => {
        if !$cond {
            return Err(format!($($fmt)*));
        }
    };
}

/// The f64 lattice with the fixed lattice's own (rounded) `lambda`, and its settings.
fn reference<const P: usize>(
    fixed: &FixedConfig,
    demean: bool,
) -> (Lattice<f64, P>, Config<f64>, Channel<f64>) {
    let config = Config::new(fixed.lambda(), 0.01)
        .unwrap()
        .with_demean(demean);
    let channel = Channel::new(f64::from(0.01f32)).unwrap();
    (Lattice::new(&config, &channel), config, channel)
}

/// The weighted second moments of the input the f64 lattice saw, `R = sum lambda^(n-i) phi_i
/// phi_i^T` (prewindowed regressors) and `sum lambda^(n-i) y_i^2`, accumulated here from the
/// f64 lattice's `input()`.
struct Moments<const P: usize> {
    lambda: f64,
    r: [[f64; P]; P],
    /// `sum lambda^(n-i) phi_i y_i`.
    ry: [f64; P],
    yy: f64,
    phi: [f64; P],
}

impl<const P: usize> Moments<P> {
    fn new(lambda: f64) -> Self {
        Self {
            lambda,
            r: [[0.0; P]; P],
            ry: [0.0; P],
            yy: 0.0,
            phi: [0.0; P],
        }
    }

    fn push(&mut self, y: f64) {
        for i in 0..P {
            for j in 0..P {
                self.r[i][j] = self.lambda * self.r[i][j] + self.phi[i] * self.phi[j];
            }
        }
        for i in 0..P {
            self.ry[i] = self.lambda * self.ry[i] + self.phi[i] * y;
        }
        self.yy = self.lambda * self.yy + y * y;
        self.phi.rotate_right(1);
        self.phi[0] = y;
    }

    /// Whether the predictions of `a` and `b` on the data differ by at most `TOL` times the
    /// data's RMS: `(a - b)^T R (a - b) <= TOL^2 sum lambda^(n-i) y_i^2`.
    fn predict_alike(&self, a: &[f32; P], b: &[f64; P]) -> bool {
        let d: Vec<f64> = a.iter().zip(b).map(|(a, b)| f64::from(*a) - b).collect();
        let q: f64 = (0..P)
            .map(|i| (0..P).map(|j| d[i] * self.r[i][j] * d[j]).sum::<f64>())
            .sum();
        q <= TOL * TOL * self.yy
    }
}

impl<const P: usize> Moments<P> {
    /// The weighted squared prediction error of `a` on the data (`y_i ~ a . phi_i`).
    fn cost(&self, a: &[f64; P]) -> f64 {
        let quadratic: f64 = (0..P)
            .map(|i| (0..P).map(|j| a[i] * self.r[i][j] * a[j]).sum::<f64>())
            .sum();
        let linear: f64 = (0..P).map(|i| a[i] * self.ry[i]).sum();
        self.yy - 2.0 * linear + quadratic
    }

    /// The least-squares coefficients of the data, by a direct solve of `R a = r` (Gaussian
    /// elimination with partial pivoting, a ridge of 1e-12 of `R`'s trace against a singular
    /// `R`): the reference where the f64 lattice's own recursion loses its accuracy.
    fn solve(&self) -> [f64; P] {
        let trace: f64 = (0..P).map(|i| self.r[i][i]).sum();
        let mut m = self.r;
        let mut b = self.ry;
        for (i, row) in m.iter_mut().enumerate() {
            row[i] += 1e-12 * trace.max(f64::MIN_POSITIVE);
        }
        for col in 0..P {
            let pivot = (col..P)
                .max_by(|&i, &j| m[i][col].abs().total_cmp(&m[j][col].abs()))
                .unwrap_or(col);
            m.swap(col, pivot);
            b.swap(col, pivot);
            if m[col][col] == 0.0 {
                continue;
            }
            let pivot_row = m[col];
            for i in col + 1..P {
                let f = m[i][col] / pivot_row[col];
                for (x, p) in m[i][col..].iter_mut().zip(&pivot_row[col..]) {
                    *x -= f * p;
                }
                b[i] -= f * b[col];
            }
        }
        let mut a = [0.0; P];
        for i in (0..P).rev() {
            let s: f64 = (i + 1..P).map(|j| m[i][j] * a[j]).sum();
            a[i] = if m[i][i] == 0.0 {
                0.0
            } else {
                (b[i] - s) / m[i][i]
            };
        }
        a
    }

    /// Whether `a` predicts the data within `TOL` times their RMS of the least-squares
    /// coefficients: `J(a) - J(a*) <= TOL^2 sum lambda^(n-i) y_i^2`.
    fn fits_as_well(&self, a: &[f32; P]) -> bool {
        let a: [f64; P] = core::array::from_fn(|i| f64::from(a[i]));
        self.cost(&a) - self.cost(&self.solve()) <= TOL * TOL * self.yy
    }
}

fn worst<const P: usize>(a: &[f32; P], b: &[f64; P]) -> f64 {
    a.iter()
        .zip(b)
        .fold(0.0, |m, (a, b)| m.max((f64::from(*a) - b).abs()))
}

/// Runs the check on one in-range record (`|x| < 16`, at `scale = 1`) at order `P`. Between restarts the fixed lattice must agree with an f64
/// lattice fed the same samples (restarted where the fixed one restarts); a saturation must
/// come with a restart; and after the first restart the published model must be the one a
/// fresh fixed lattice gives on the samples before it (the last good model), for as long as the
/// hold lasts. Returns the number of restarts.
pub fn differential<const P: usize>(x: &[f64], lambda: f32, demean: bool) -> Result<u64, String> {
    let config = Config::new(lambda, 0.01).unwrap().with_demean(demean);
    let fixed_config = FixedConfig::new(&config).unwrap();
    let fixed_channel = FixedChannel::new(&Channel::new(0.01).unwrap(), 1.0).unwrap();
    let (mut float, float_config, float_channel) = reference(&fixed_config, demean);
    let mut moments = Moments::new(fixed_config.lambda());
    let mut fixed = FixedLattice::<P>::new(&fixed_config, &fixed_channel);
    let hold = 3.0 / (1.0 - fixed_config.lambda());
    let mut segment_start = 0;
    let mut first_restart: Option<(usize, Option<ArModel<f32, P>>)> = None;
    for (n, &v) in x.iter().enumerate() {
        let before = fixed.health();
        // `None` also for a sample that restarted the lattice: the counts say whether it
        // was rejected.
        fixed.update(&fixed_config, v as f32);
        let h = fixed.health();
        ensure!(
            h.rejected() == before.rejected(),
            "sample {n} ({v}) rejected"
        );
        ensure!(
            h.clipped == before.clipped || h.restarts > before.restarts,
            "sample {n}: a saturation without a restart: {h:?}"
        );
        if h.restarts > before.restarts {
            if first_restart.is_none() {
                // The last good model, from a lattice that never had `model` called on the
                // way: the samples before this one.
                let mut replay = FixedLattice::<P>::new(&fixed_config, &fixed_channel);
                for &u in &x[..n] {
                    replay.update(&fixed_config, u as f32);
                }
                ensure!(replay.health().restarts == 0, "the replay restarted");
                first_restart = Some((n, replay.model(&fixed_config)));
            }
            // The fixed lattice starts again from the next sample: so does the reference.
            float = Lattice::new(&float_config, &float_channel);
            moments = Moments::new(fixed_config.lambda());
            segment_start = n + 1;
            continue;
        }
        float.update(&float_config, f64::from(v as f32));
        moments.push(float.input());
        let (a, a_ref) = (
            fixed.coefficients(P).unwrap(),
            float.coefficients(P).unwrap(),
        );
        let (mean, mean_ref) = (f64::from(fixed.mean()), float.mean());
        ensure!(
            (worst(&a, &a_ref) <= TOL
                || moments.predict_alike(&a, &a_ref)
                || moments.fits_as_well(&a))
                && (mean - mean_ref).abs() <= TOL,
            "sample {n} (segment from {segment_start}): fixed a {a:?} mean {mean}, \
             f64 a {a_ref:?} mean {mean_ref}, {h:?}"
        );
        if let Some((at, held)) = first_restart
            && ((n - at) as f64) < hold - 2.0
        {
            let m = fixed.model(&fixed_config);
            let (m, held) = (
                m.map(|m| (*m.a(), m.noise_variance(), m.mean())),
                held.map(|m| (*m.a(), m.noise_variance(), m.mean())),
            );
            ensure!(
                m == held,
                "sample {n}: {m:?}, not the last good model {held:?} from before sample {at}"
            );
        }
    }
    Ok(fixed.health().restarts)
}
