//! Host cost per sample of the recursive cores: `cargo bench -p imu-ar-bench --bench per_sample`.
//!
//! The rows of the target's `cargo qemu bench`, and the f64 cores: each iteration feeds a block
//! of 1000 samples of an AR(2) record (as raw counts for the fixed-point lattice; an AR(1) for
//! the SFTF, which must not be rescued while it is timed); criterion
//! reports the time per block and, through the throughput, per sample. `extract` times one
//! request of the exact coefficients, `frame6` one six-axis frame of order-4 lattices.
//! `tools/bench-report.sh` reads the results.

use std::hint::black_box;
use std::time::Duration;

use criterion::{BenchmarkId, Criterion, Throughput, criterion_group, criterion_main};
use imu_ar::recursive::{Channel, Config, Estimator, FixedChannel, FixedConfig, FixedLattice};
use imu_ar::recursive::{Lattice, Rls, Sftf};
use imu_ar::sim::ArSimulator;
use imu_ar::{ArModel, Scalar};
use rand_chacha::ChaCha8Rng;
use rand_core::SeedableRng;

const BLOCK: usize = 1000;

fn record<T: Scalar>() -> Vec<T> {
    ar_record([1.2, -0.5])
}

/// One block of the AR process `a`, unit innovation variance.
fn ar_record<T: Scalar, const Q: usize>(a: [f64; Q]) -> Vec<T> {
    let model = ArModel::new(a, 1.0, 0.0, 0.01).unwrap();
    let mut sim = ArSimulator::new(model);
    let mut rng = ChaCha8Rng::seed_from_u64(1);
    (0..BLOCK)
        .map(|_| T::from_f64(sim.next(&mut rng)))
        .collect()
}

/// Criterion group `name`, id `p`: `update` over one block of `x`.
fn bench_block<T: Copy>(
    c: &mut Criterion,
    name: &str,
    p: usize,
    x: &[T],
    mut update: impl FnMut(T),
) {
    let mut group = c.benchmark_group(name);
    group.throughput(Throughput::Elements(x.len() as u64));
    group.bench_function(BenchmarkId::from_parameter(p), |b| {
        b.iter(|| {
            for &v in x {
                update(black_box(v));
            }
        })
    });
    group.finish();
}

fn config<T: Scalar>() -> (Config<T>, Channel<T>) {
    let config = Config::new(T::from_f64(0.999), T::from_f64(0.01)).unwrap();
    (config, Channel::new(T::from_f64(0.1)).unwrap())
}

fn lattice<T: imu_ar::recursive::FloatArith, const P: usize>(c: &mut Criterion, name: &str) {
    let (config, channel) = config::<T>();
    let mut state = Lattice::<T, P>::new(&config, &channel);
    bench_block(c, name, P, &record::<T>(), |v| {
        black_box(state.update(&config, v));
    });
}

fn lattice_fixed<const P: usize>(c: &mut Criterion) {
    let config = Config::new(0.999f32, 0.01).unwrap();
    let channel = Channel::new(1e-3).unwrap();
    let fixed = FixedConfig::new(&config).unwrap();
    let fixed_channel = FixedChannel::for_counts(&channel, 0.05).unwrap();
    let mut state = FixedLattice::<P>::new(&fixed, &fixed_channel);
    let counts: Vec<i16> = record::<f32>().iter().map(|&v| (v * 20.0) as i16).collect();
    bench_block(c, "lattice_fixed", P, &counts, |v| {
        black_box(state.update_counts(&fixed, v));
    });
}

/// The exact coefficients on request, after one block.
fn extract<const P: usize>(c: &mut Criterion) {
    let (config, channel) = config::<f32>();
    let mut state = Lattice::<f32, P>::new(&config, &channel);
    for v in record::<f32>() {
        state.update(&config, v);
    }
    bench_block(c, "extract_f32", P, &[()], |()| {
        black_box(black_box(&state).coefficients(P));
    });
}

fn frame6(c: &mut Criterion) {
    let (config, channel) = config::<f32>();
    let mut axes = [Lattice::<f32, 4>::new(&config, &channel); 6];
    let x = record::<f32>();
    let frames: Vec<[f32; 6]> = (0..BLOCK)
        .map(|i| core::array::from_fn(|k| x[(i + k) % BLOCK]))
        .collect();
    bench_block(c, "frame6_f32", 4, &frames, |frame| {
        for (lattice, v) in axes.iter_mut().zip(frame) {
            black_box(lattice.update(&config, v));
        }
    });
}

fn rls<T: Scalar, const P: usize>(c: &mut Criterion, name: &str) {
    let (config, channel) = config::<T>();
    let mut state = Rls::<T, P>::new(&config, &channel);
    bench_block(c, name, P, &record::<T>(), |v| {
        black_box(state.update(&config, v));
    });
}

fn sftf<T: Scalar, const P: usize>(c: &mut Criterion, name: &str) {
    let (config, channel) = config::<T>();
    let mut state = Sftf::<T, P>::new(&config, &channel);
    // An AR(1): the AR(2) record would make the order-1 filter under-fit and diverge, and
    // the rescues would be timed with it.
    bench_block(c, name, P, &ar_record::<T, 1>([0.9]), |v| {
        black_box(state.update(&config, v));
    });
    assert_eq!(state.health().restarts, 0, "{name} p = {P}: rescued");
}

fn per_sample(c: &mut Criterion) {
    macro_rules! orders {
        ($f:ident, $t:ty, $name:expr) => {
            $f::<$t, 1>(c, $name);
            $f::<$t, 2>(c, $name);
            $f::<$t, 4>(c, $name);
            $f::<$t, 8>(c, $name);
            $f::<$t, 16>(c, $name);
            $f::<$t, 32>(c, $name);
        };
    }
    orders!(lattice, f32, "lattice_f32");
    orders!(lattice, f64, "lattice_f64");
    orders!(rls, f32, "rls_f32");
    orders!(rls, f64, "rls_f64");
    orders!(sftf, f32, "sftf_f32");
    orders!(sftf, f64, "sftf_f64");
    lattice_fixed::<1>(c);
    lattice_fixed::<2>(c);
    lattice_fixed::<4>(c);
    lattice_fixed::<8>(c);
    lattice_fixed::<16>(c);
    lattice_fixed::<32>(c);
    extract::<1>(c);
    extract::<2>(c);
    extract::<4>(c);
    extract::<8>(c);
    extract::<16>(c);
    extract::<32>(c);
    frame6(c);
}

criterion_group! {
    name = benches;
    config = Criterion::default()
        .warm_up_time(Duration::from_millis(300))
        .measurement_time(Duration::from_secs(1))
        .sample_size(20);
    targets = per_sample
}
criterion_main!(benches);
