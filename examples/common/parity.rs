//! The parity run: one documented input sequence through the f32 lattice and the fixed-point
//! lattice, hashed to two checksums. The `parity` firmware and `imu-ar parity` on the host run
//! this same code; equal checksums mean bit-identical results on both.
//!
//! Input: `SAMPLES` samples of `x[n] = 3 + 1.2 (x[n-1] - 3) - 0.5 (x[n-2] - 3) + w[n]`,
//! `w ~ N(0, 0.25)` from `imu_ar::sim::ArSimulator` on `ChaCha8Rng::seed_from_u64(SEED)`
//! (1000 samples burn-in), as `f32`; every 997th sample is replaced by NaN (rejected by both).
//! Both lattices: order `P = 4`, `lambda = 0.999`, `delta = 0.1`, `dt = 0.01`, running mean
//! removed; the fixed one with `scale = 2` (internal units per sensor unit).
//!
//! Checksum: 64-bit FNV-1a over the little-endian bit patterns of, per accepted sample, the
//! order-`P` error (what the f32 `update` returns; `f_P` in internal units for the fixed
//! point), the errors `f_1..f_P`, the energies `F_0..F_P` and the reflection
//! coefficients `kf`, `kb`; then the final coefficients `a_1..a_P` and innovation variance.
//!
//! The noise model: `NOISE_SAMPLES` samples of white noise + a Gauss-Markov drift + a random
//! walk (uniform steps from a 32-bit LCG, [`noise_input`]) into an `AllanStream<NOISE_L>`, at
//! `dt = 0.01`; the identified fit (`NoiseModel::<8, 3>`, three states, no AR part) and its
//! 95 % intervals. Checksum: FNV-1a over the bit patterns of N, Q, K, R, every Gauss-Markov
//! term's sigma and T and every oscillator's sigma, f and decay time, then the intervals of
//! N, Q, K, R, B, of every term's parameters and of the Allan deviation at every octave. Equal
//! checksums mean the device identifies the same model as the host on the same octaves.

use imu_ar::ArModel;
use imu_ar::allan::AllanStream;
use imu_ar::noise::{FitConfig, Interval, NoiseModel, Octaves};
use imu_ar::recursive::Lattice;
use imu_ar::recursive::{Channel, Config, Estimator, FixedChannel, FixedConfig, FixedLattice};
use imu_ar::sim::ArSimulator;
use rand_chacha::ChaCha8Rng;
use rand_core::SeedableRng;

/// Seed of the input sequence.
pub const SEED: u64 = 2010;
/// Samples in the run.
pub const SAMPLES: usize = 20_000;
const P: usize = 4;

/// 64-bit FNV-1a.
struct Fnv(u64);

impl Fnv {
    fn new() -> Self {
        Fnv(0xcbf2_9ce4_8422_2325)
    }

    fn bytes(&mut self, bytes: &[u8]) {
        for &b in bytes {
            self.0 ^= u64::from(b);
            self.0 = self.0.wrapping_mul(0x0000_0100_0000_01b3);
        }
    }
}

/// Samples of the noise-model run.
pub const NOISE_SAMPLES: u32 = 1 << 20;
/// Octaves of its Allan stream.
pub const NOISE_L: usize = 19;

/// The noise-model run's input: uniform steps from a 32-bit LCG (seed 777) make white noise
/// (+-0.5), a Gauss-Markov drift (`phi = 0.999`, steps +-0.005) and a random walk (steps
/// +-5e-5), summed as `f32`.
pub fn noise_input() -> impl Iterator<Item = f32> {
    let (mut seed, mut drift, mut walk) = (777u32, 0.0f32, 0.0f32);
    let mut uniform = move || {
        seed = seed.wrapping_mul(1_664_525).wrapping_add(1_013_904_223);
        (seed >> 8) as f32 / 16_777_216.0 - 0.5
    };
    (0..NOISE_SAMPLES).map(move |_| {
        drift = 0.999 * drift + 0.01 * uniform();
        walk += 1e-4 * uniform();
        uniform() + drift + walk
    })
}

/// The checksum of the identified noise model and its intervals, or `None` if the fit fails.
pub fn noise_checksum() -> Option<u64> {
    let mut stream = AllanStream::<NOISE_L>::new();
    for x in noise_input() {
        stream.push(x);
    }
    let octaves = Octaves::from_stream(&stream, 0.01).ok()?;
    let config = FitConfig::new(3).with_identification(true);
    let model = NoiseModel::<8, 3>::fit(&octaves, None, &config).ok()?;
    let u = model.uncertainty(&octaves).ok()?;
    let mut h = Fnv::new();
    let mut f = |v: f64| h.bytes(&v.to_bits().to_le_bytes());
    for v in [
        model.white_term(),
        model.quantization(),
        model.random_walk(),
        model.ramp(),
    ] {
        f(v);
    }
    for g in model.gauss_markov() {
        f(g.sigma);
        f(g.correlation_time);
    }
    for o in model.oscillators() {
        f(o.sigma);
        f(o.frequency);
        f(o.decay_time);
    }
    let mut interval = |i: &Interval| {
        f(i.low);
        f(i.high);
    };
    for i in [
        &u.white_noise,
        &u.quantization,
        &u.random_walk,
        &u.ramp,
        &u.bias_instability,
    ] {
        interval(i);
    }
    for t in u.gauss_markov() {
        interval(&t.sigma);
        interval(&t.correlation_time);
    }
    for o in u.oscillators() {
        interval(&o.sigma);
        interval(&o.frequency);
        interval(&o.decay_time);
    }
    for i in u.adev_band() {
        interval(i);
    }
    Some(h.0)
}

/// The input sequence of the lattices' run: `SAMPLES` samples of the seeded AR(2), every
/// 997th one NaN; `None` if the simulator refuses its model.
pub fn input() -> Option<impl Iterator<Item = f32>> {
    let truth = ArModel::new([1.2f32, -0.5], 0.25, 3.0, 0.01).ok()?;
    let mut sim = ArSimulator::new(truth);
    let mut rng = ChaCha8Rng::seed_from_u64(SEED);
    sim.burn_in(&mut rng, 1000);
    Some((0..SAMPLES).map(move |n| {
        let x: f32 = sim.next(&mut rng);
        if n % 997 == 996 { f32::NAN } else { x }
    }))
}

/// `(f32 checksum, fixed-point checksum)`, or `None` if a configuration is refused.
pub fn checksums() -> Option<(u64, u64)> {
    let mut input = input()?;
    let config = Config::new(0.999f32, 0.01).ok()?;
    let channel = Channel::new(0.1).ok()?;
    let fixed_config = FixedConfig::new(&config).ok()?;
    let fixed_channel = FixedChannel::new(&channel, 2.0).ok()?;
    let mut float = Lattice::<f32, P>::new(&config, &channel);
    let mut fixed = FixedLattice::<P>::new(&fixed_config, &fixed_channel);
    let (mut hf, mut hq) = (Fnv::new(), Fnv::new());
    for x in &mut input {
        if let Some(e) = float.update(&config, x) {
            hf.bytes(&e.to_bits().to_le_bytes());
            for v in float
                .errors()
                .into_iter()
                .chain(float.forward_reflection())
                .chain(float.backward_reflection())
            {
                hf.bytes(&v.to_bits().to_le_bytes());
            }
            for m in 0..=P {
                hf.bytes(&float.energy(m)?.to_bits().to_le_bytes());
            }
        }
        if fixed.update(&fixed_config, x).is_some() {
            hq.bytes(&fixed.errors()[P - 1].to_bits().to_le_bytes());
            for v in fixed.errors() {
                hq.bytes(&v.to_bits().to_le_bytes());
            }
            for k in fixed
                .forward_reflection()
                .into_iter()
                .chain(fixed.backward_reflection())
            {
                hq.bytes(&k.to_bits().to_le_bytes());
            }
            for m in 0..=P {
                hq.bytes(&fixed.energy(m)?.to_bits().to_le_bytes());
            }
        }
    }
    let mf = float.model(&config)?;
    for v in mf.a().iter().chain([&mf.noise_variance()]) {
        hf.bytes(&v.to_bits().to_le_bytes());
    }
    let mq = fixed.model(&fixed_config)?;
    for v in mq.a().iter().chain([&mq.noise_variance()]) {
        hq.bytes(&v.to_bits().to_le_bytes());
    }
    Some((hf.0, hq.0))
}
