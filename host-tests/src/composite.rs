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
