//! AR process simulation on any `rand_core::RngCore`.

use rand_core::RngCore;

use crate::{ArModel, Scalar};

/// Standard normal variates by Marsaglia's polar method (Marsaglia & Bray 1964) from uniform
/// `f64`s made of the top 53 bits of `next_u64`. Pure `f64` arithmetic and `libm`, so a seeded
/// generator gives the same sequence, bit for bit, on the host and on the target.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct StandardNormal {
    spare: Option<f64>,
}

impl StandardNormal {
    /// A generator with no cached variate.
    pub const fn new() -> Self {
        Self { spare: None }
    }

    /// The next `N(0, 1)` variate.
    pub fn sample<R: RngCore + ?Sized>(&mut self, rng: &mut R) -> f64 {
        if let Some(z) = self.spare.take() {
            return z;
        }
        loop {
            let u = 2.0 * uniform(rng) - 1.0;
            let v = 2.0 * uniform(rng) - 1.0;
            let s = u * u + v * v;
            if s > 0.0 && s < 1.0 {
                let f = libm::sqrt(-2.0 * libm::log(s) / s);
                self.spare = Some(v * f);
                return u * f;
            }
        }
    }
}

fn uniform<R: RngCore + ?Sized>(rng: &mut R) -> f64 {
    (rng.next_u64() >> 11) as f64 * (1.0 / (1u64 << 53) as f64)
}

/// Draws `x[n] = mean + sum_k a_k (x[n-k] - mean) + w[n]`, `w ~ N(0, noise_variance)`.
///
/// Starts from `x = mean` for all past samples: discard the first few multiples of the slowest
/// time constant (`burn_in`) when a stationary record is wanted. Arithmetic in `f64`.
///
/// ```
/// use imu_ar::{ArModel, sim::ArSimulator};
/// # struct Counter(u64);
/// # impl rand_core::RngCore for Counter {
/// #     fn next_u32(&mut self) -> u32 { self.next_u64() as u32 }
/// #     fn next_u64(&mut self) -> u64 { self.0 = self.0.wrapping_mul(6364136223846793005).wrapping_add(1442695040888963407); self.0 }
/// #     fn fill_bytes(&mut self, d: &mut [u8]) { rand_core::impls::fill_bytes_via_next(self, d) }
/// # }
/// let model = ArModel::new([0.9f32], 1.0, 5.0, 0.01).unwrap();
/// let mut sim = ArSimulator::new(model);
/// let mut rng = Counter(1);
/// sim.burn_in(&mut rng, 100);
/// let x: f32 = sim.next(&mut rng);
/// assert!(x.is_finite());
/// ```
#[derive(Clone, Copy, Debug)]
pub struct ArSimulator<T, const P: usize> {
    model: ArModel<T, P>,
    a: [f64; P],
    sigma: f64,
    mean: f64,
    /// `x[n-1] - mean, .., x[n-P] - mean`.
    past: [f64; P],
    normal: StandardNormal,
}

impl<T: Scalar, const P: usize> ArSimulator<T, P> {
    /// A simulator of `model`, started at the mean.
    pub fn new(model: ArModel<T, P>) -> Self {
        Self {
            a: model.a().map(Scalar::to_f64),
            sigma: libm::sqrt(model.noise_variance().to_f64()),
            mean: model.mean().to_f64(),
            model,
            past: [0.0; P],
            normal: StandardNormal::new(),
        }
    }

    /// The simulated model.
    pub fn model(&self) -> &ArModel<T, P> {
        &self.model
    }

    /// The next sample.
    pub fn next<R: RngCore + ?Sized>(&mut self, rng: &mut R) -> T {
        let w = self.sigma * self.normal.sample(rng);
        let y = self.a.iter().zip(&self.past).fold(w, |y, (a, p)| y + a * p);
        self.past.copy_within(0..P - 1, 1);
        self.past[0] = y;
        T::from_f64(self.mean + y)
    }

    /// Draws and discards `n` samples.
    pub fn burn_in<R: RngCore + ?Sized>(&mut self, rng: &mut R, n: usize) {
        for _ in 0..n {
            self.next(rng);
        }
    }
}
