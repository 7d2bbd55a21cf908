//! Records of known composite noise (`noise-model.md` section 1): white noise, quantisation,
//! first-order Gauss-Markov terms and a random walk, simulated sample by sample as the design
//! states them, for tests of the noise-model fit. The truth's Allan variance is computed here
//! without the library's closed forms: the Gauss-Markov terms by `ArModel::allan_variance` (a
//! sum over lags), the rest by the textbook expressions.

use imu_ar::ArModel;
use imu_ar::sim::StandardNormal;
use rand_chacha::ChaCha8Rng;
use rand_core::SeedableRng;

/// A composite process: `N` (u/sqrt(Hz)), `Q` (u s), `(sigma, T)` Gauss-Markov terms and `K`
/// (u/s/sqrt(Hz)), sampled every `dt` seconds.
#[derive(Clone, Debug, PartialEq)]
pub struct Composite {
    /// Sample interval, s.
    pub dt: f64,
    /// White noise `N`.
    pub white: f64,
    /// Quantisation `Q`.
    pub quantization: f64,
    /// Gauss-Markov `(sigma, T)`.
    pub gm: Vec<(f64, f64)>,
    /// Random walk `K`.
    pub random_walk: f64,
}

impl Composite {
    /// `n` samples from seed `seed`; Gauss-Markov terms start stationary, the random walk at 0.
    pub fn simulate(&self, n: usize, seed: u64) -> Vec<f64> {
        let mut rng = ChaCha8Rng::seed_from_u64(seed);
        let mut z = StandardNormal::new();
        let dt = self.dt;
        let mut gm: Vec<(f64, f64, f64)> = self
            .gm
            .iter()
            .map(|&(sigma, t)| {
                let a = (-dt / t).exp();
                (a, sigma * (1.0 - a * a).sqrt(), sigma * z.sample(&mut rng))
            })
            .collect();
        let mut walk = 0.0;
        let mut q_prev = self.quantization * z.sample(&mut rng);
        (0..n)
            .map(|_| {
                let mut x = self.white / dt.sqrt() * z.sample(&mut rng);
                let q = self.quantization * z.sample(&mut rng);
                x += (q - q_prev) / dt;
                q_prev = q;
                for (a, s, state) in gm.iter_mut() {
                    *state = *a * *state + *s * z.sample(&mut rng);
                    x += *state;
                }
                walk += self.random_walk * dt.sqrt() * z.sample(&mut rng);
                x + walk
            })
            .collect()
    }

    /// The expected Allan variance at `m` samples per cluster.
    pub fn avar(&self, m: u32) -> f64 {
        let (dt, mf) = (self.dt, f64::from(m));
        let tau = mf * dt;
        let mut v = self.white.powi(2) / tau
            + 3.0 * self.quantization.powi(2) / (tau * tau)
            + self.random_walk.powi(2) * dt * (2.0 * mf * mf + 1.0) / (6.0 * mf);
        for &(sigma, t) in &self.gm {
            let a = (-dt / t).exp();
            let ar = ArModel::new([a], sigma * sigma * (1.0 - a * a), 0.0, dt).unwrap();
            v += ar.allan_variance(m).unwrap();
        }
        v
    }
}

/// `n` samples of a damped oscillator (a second-order Gauss-Markov process) of standard
/// deviation `sigma`, natural frequency `frequency` (Hz) and damping ratio `damping`, sampled
/// every `dt`: the continuous poles `-zeta w +- i w sqrt(1 - zeta^2)` mapped to `z = exp(s dt)`,
/// driven by white noise, started after a run-in of ten decay times.
pub fn oscillator(
    sigma: f64,
    frequency: f64,
    damping: f64,
    dt: f64,
    n: usize,
    seed: u64,
) -> Vec<f64> {
    let mut rng = ChaCha8Rng::seed_from_u64(seed);
    let mut z = StandardNormal::new();
    let w = 2.0 * std::f64::consts::PI * frequency;
    let r = (-damping * w * dt).exp();
    let theta = w * (1.0 - damping * damping).sqrt() * dt;
    let (a1, a2) = (2.0 * r * theta.cos(), -r * r);
    // The stationary variance of x_k = a1 x_(k-1) + a2 x_(k-2) + e_k per unit innovation
    // variance.
    let gain = (1.0 - a2) / ((1.0 + a2) * ((1.0 - a2).powi(2) - a1 * a1));
    let e = sigma / gain.sqrt();
    let run_in = (10.0 / (damping * w * dt)) as usize;
    let (mut x1, mut x2) = (0.0, 0.0);
    let mut out = Vec::with_capacity(n);
    for k in 0..run_in + n {
        let x = a1 * x1 + a2 * x2 + e * z.sample(&mut rng);
        (x2, x1) = (x1, x);
        if k >= run_in {
            out.push(x);
        }
    }
    out
}
