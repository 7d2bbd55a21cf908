//! The seeds of the `model_decode` fuzz target (`fuzz/corpus/model_decode/seed-*`), written by
//! an encoder of their own (Python's `struct` and `zlib.crc32`) from the layout in the
//! `persist` module docs: each decodes to the model written, and encodes back to its bytes.

use std::fmt::Debug;
use std::path::Path;

use imu_ar::ArModel;
use imu_ar::noise::NoiseModel;
use imu_ar::persist::{FlashStore, Record};
use imu_ar_host::flash::RamFlash;

fn seed(name: &str) -> Vec<u8> {
    let dir = Path::new(env!("CARGO_MANIFEST_DIR")).join("../fuzz/corpus/model_decode");
    std::fs::read(dir.join(name)).unwrap_or_else(|e| panic!("{name}: {e}"))
}

/// The model in seed `name`, whose encoding is the seed itself.
fn decoded<M: Record + Debug>(name: &str) -> M {
    let bytes = seed(name);
    let m = M::decode(&bytes).unwrap_or_else(|e| panic!("{name}: {e}"));
    assert_eq!(super::encode(&m), bytes, "{name}");
    m
}

#[test]
fn seed_records_written_from_the_documented_layout_decode() {
    let m: ArModel<f32, 1> = decoded("seed-ar-f32-1");
    assert_eq!((m.a(), m.noise_variance()), (&[0.99], 1e-6));
    let m: ArModel<f32, 4> = decoded("seed-ar-f32-4");
    assert_eq!(
        (m.a(), m.mean(), m.dt()),
        (&[0.9, -0.2, 0.05, 0.01], 0.02, 0.01)
    );
    let m: ArModel<f64, 4> = decoded("seed-ar-f64-4");
    assert_eq!(
        (m.a(), m.mean()),
        (&[2.7607, -3.8106, 2.6535, -0.9238], -3.5)
    );
    let m: ArModel<f32, 8> = decoded("seed-ar-f32-8");
    assert_eq!(m.dt(), 0.0025);
    let m: NoiseModel<4, 2> = decoded("seed-noise-4-2");
    assert_eq!(m, super::sample_noise());
    let m: NoiseModel<1, 1> = decoded("seed-noise-1-1");
    assert_eq!((m.white_term(), m.ar()), (1e-2, None));
    let m: NoiseModel<8, 3> = decoded("seed-noise-8-3");
    let times: Vec<f64> = m
        .gauss_markov()
        .iter()
        .map(|t| t.correlation_time)
        .collect();
    assert_eq!((times, m.ramp()), (vec![2.0, 40.0, 900.0], 1e-7));
    let m: [ArModel<f32, 4>; 6] = decoded("seed-axes-f32-4x6");
    assert_eq!((m[5].a()[3], m[5].mean()), (0.05, 2.0));
    // A store's slot with two entries (sequence numbers 6 and 7): the second is loaded.
    let mut flash = RamFlash::<1, 4, 256>::new(2);
    flash.bytes_mut()[..256].copy_from_slice(&seed("seed-flash-ar-f32-4"));
    let mut buf = [0u8; 44];
    let mut store = FlashStore::new(&mut flash, 0..512).unwrap();
    let m: ArModel<f32, 4> = store.load(&mut buf).unwrap();
    assert_eq!(m.a(), &[0.8, -0.1, 0.05, 0.0]);
    // The next save appends after it, numbered 8.
    assert_eq!(store.save(&m, &mut buf), Ok(8));
}
