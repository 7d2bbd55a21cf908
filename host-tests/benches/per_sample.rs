//! Host cost per sample of the recursive cores: `cargo bench -p imu-ar-host --bench per_sample`.
//!
//! Each iteration feeds a block of 1000 samples of an AR(2) record; criterion reports the time
//! per block and, through the throughput, per sample. `tools/perf-table.sh` reads the results.

use std::hint::black_box;
use std::time::Duration;

use criterion::{BenchmarkId, Criterion, Throughput, criterion_group, criterion_main};
use imu_ar::recursive::{Config, Lattice, Rls, RlsInit};
use imu_ar::sim::ArSimulator;
use imu_ar::{ArModel, Scalar};
use rand_chacha::ChaCha8Rng;
use rand_core::SeedableRng;

const BLOCK: usize = 1000;

fn record<T: Scalar>() -> Vec<T> {
    let model = ArModel::new([1.2f64, -0.5], 1.0, 0.0, 0.01).unwrap();
    let mut sim = ArSimulator::new(model);
    let mut rng = ChaCha8Rng::seed_from_u64(1);
    (0..BLOCK)
        .map(|_| T::from_f64(sim.next(&mut rng)))
        .collect()
}

/// Criterion group `name`, id `p`: `update` over one block of the record.
fn bench_block<T: Scalar>(c: &mut Criterion, name: &str, p: usize, mut update: impl FnMut(T)) {
    let x = record::<T>();
    let mut group = c.benchmark_group(name);
    group.throughput(Throughput::Elements(BLOCK as u64));
    group.bench_function(BenchmarkId::from_parameter(p), |b| {
        b.iter(|| {
            for &v in &x {
                update(black_box(v));
            }
        })
    });
    group.finish();
}

fn config<T: Scalar>() -> Config<T> {
    Config::new(T::from_f64(0.999), T::from_f64(0.1), T::from_f64(0.01)).unwrap()
}

fn lattice<T: imu_ar::recursive::FloatArith, const P: usize>(c: &mut Criterion, name: &str) {
    let config = config::<T>();
    let mut state = Lattice::<T, P>::new(&config);
    bench_block(c, name, P, |v| {
        black_box(state.update(&config, v));
    });
}

fn rls<T: Scalar, const P: usize>(c: &mut Criterion, name: &str) {
    let config = config::<T>();
    let mut state = Rls::<T, P>::new(&config, RlsInit::ShiftConsistent);
    bench_block(c, name, P, |v| {
        black_box(state.update(&config, v));
    });
}

fn per_sample(c: &mut Criterion) {
    macro_rules! orders {
        ($f:ident, $t:ty, $name:expr) => {
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
