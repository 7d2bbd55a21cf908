//! Hostile inputs and faults against the innovation gate, persistence, the thermal stage and
//! the prior / settled start. Each test states the documented promise it checks.

use imu_ar::ArModel;
use imu_ar::Scalar;
use imu_ar::noise::{Coefficients, GmTerm, NoiseModel, Oscillator};
use imu_ar::persist::{DecodeError, FlashStore, Record, StoreError};
use imu_ar::recursive::{
    Channel, Config, Estimator, FixedChannel, FixedConfig, FixedLattice, Gate, Lattice, Rls,
    Settled, Sftf,
};
use imu_ar::thermal::{ThermalBias, ThermalConfig};
use imu_ar_host::crc::reseal;
use imu_ar_host::fixtures::{add, ar};
use imu_ar_host::flash::{RamFlash, RamFlashError};
use rand_chacha::ChaCha8Rng;
use rand_core::{RngCore, SeedableRng};

// ---------------------------------------------------------------------------------------
// Helpers
// ---------------------------------------------------------------------------------------

fn uniform(rng: &mut ChaCha8Rng) -> f64 {
    (rng.next_u64() >> 11) as f64 / (1u64 << 53) as f64
}

fn gauss(rng: &mut ChaCha8Rng) -> f64 {
    let (u, v) = (uniform(rng).max(1e-300), uniform(rng));
    (-2.0 * u.ln()).sqrt() * (2.0 * std::f64::consts::PI * v).cos()
}

/// Feeds `x` and records, per sample, whether it was taken (`update` returned `Some`) and the
/// longest run of consecutive gate rejections (outlier counter increments).
fn longest_outlier_run<T: Scalar, E: Estimator<T, P>, const P: usize>(
    e: &mut E,
    config: &E::Config,
    x: &[T],
) -> (u32, u64) {
    let (mut run, mut longest) = (0u32, 0u32);
    for &v in x {
        let before = e.health().outliers;
        let out = e.update(config, v);
        if let Some(err) = out {
            assert!(err.is_finite(), "non-finite error {err:?} for input {v:?}");
        }
        if e.health().outliers > before {
            run += 1;
            longest = longest.max(run);
        } else if out.is_some() || e.health().non_finite == 0 {
            run = 0;
        }
    }
    if let Some(m) = e.model(config) {
        assert!(m.a().iter().all(|a| a.is_finite()), "{m:?}");
        assert!(m.noise_variance().is_finite(), "{m:?}");
        assert!(m.mean().is_finite(), "{m:?}");
    }
    (longest, e.health().outliers)
}

fn hostile_f32(n: usize, seed: u64) -> Vec<f32> {
    let mut rng = ChaCha8Rng::seed_from_u64(seed);
    let specials = [
        f32::NAN,
        f32::INFINITY,
        f32::NEG_INFINITY,
        f32::MAX,
        -f32::MAX,
        f32::MIN_POSITIVE,
        1e-45,
        -1e-45,
        1e30,
        -1e30,
        1e19,
        0.0,
        -0.0,
    ];
    (0..n)
        .map(|_| {
            let r = rng.next_u32();
            match r % 16 {
                0 => specials[(r as usize >> 8) % specials.len()],
                1 => f32::from_bits(rng.next_u32()),
                _ => gauss(&mut rng) as f32,
            }
        })
        .collect()
}

// ---------------------------------------------------------------------------------------
// 1. The innovation gate
// ---------------------------------------------------------------------------------------

/// The gate tests once `W_n` reaches `Gate::settled(lambda)`: 20, or half the memory where
/// that is less. With `lambda <= 0.95` the weight never reaches 20, and a gate that waited
/// for 20 samples would never reject anything (it did: shocks of 1e6 sigma all taken).
#[test]
fn the_gate_fires_at_short_memories() {
    let x = ar([0.9], 1.0, 20_000, 1);
    for lambda in [0.9f32, 0.95, 0.951] {
        let config = Config::new(lambda, 0.01)
            .unwrap()
            .with_gate(Gate::new(5.0, 8).unwrap());
        let channel = Channel::new(0.1f32).unwrap();
        let mut lattice = Lattice::<f32, 2>::new(&config, &channel);
        for (n, &v) in x.iter().enumerate() {
            let v = if n % 100 == 50 { v + 1e6 } else { v } as f32;
            lattice.update(&config, v);
        }
        println!(
            "lambda {lambda}: weight {}, outliers {}",
            lattice.weight(),
            lattice.health().outliers
        );
        // 200 shocks, each rejected.
        assert!(lattice.health().outliers >= 200, "lambda {lambda}");
    }
    // The fixed-point lattice accepts lambda down to 0.9: the same.
    let config = Config::new(0.9f32, 0.01)
        .unwrap()
        .with_gate(Gate::new(5.0, 8).unwrap());
    let fixed = FixedConfig::new(&config).unwrap();
    let channel = FixedChannel::new(&Channel::new(0.1f32).unwrap(), 0.25).unwrap();
    let mut lattice = FixedLattice::<2>::new(&fixed, &channel);
    for (n, &v) in x.iter().enumerate() {
        let v = if n % 100 == 50 { v + 30.0 } else { v } as f32;
        lattice.update(&fixed, v);
    }
    assert!(lattice.health().outliers >= 200);
}

/// Per-sample paths with the gate on hostile input (NaN, infinities, f32::MAX, subnormals,
/// random bit patterns): never a non-finite error or model, never more than `run`
/// consecutive outlier rejections, and every sample counted once.
fn hostile_gate_run<const P: usize>(k: f32, run: u32, lambda: f32, seed: u64) {
    let x = hostile_f32(30_000, seed);
    let config = Config::new(lambda, 0.01)
        .unwrap()
        .with_gate(Gate::new(k, run).unwrap());
    let channel = Channel::new(0.01f32).unwrap();
    let mut lattice = Lattice::<f32, P>::new(&config, &channel);
    let mut rls = Rls::<f32, P>::new(&config, &channel);
    let mut sftf = Sftf::<f32, P>::new(&config, &channel);
    let a0 = [0.1f32; P];
    let mut plattice = Lattice::<f32, P>::with_prior(&config, &channel, &a0).unwrap();
    let mut prls = Rls::<f32, P>::with_prior(&config, &channel, &a0).unwrap();
    let mut psftf = Sftf::<f32, P>::with_prior(&config, &channel, &a0).unwrap();
    let fixed = FixedConfig::new(&config).unwrap();
    let fchannel = FixedChannel::new(&channel, 1.0).unwrap();
    let mut flat = FixedLattice::<P>::new(&fixed, &fchannel);
    let mut pflat = FixedLattice::<P>::with_prior(&fixed, &fchannel, &[0.1; P]).unwrap();
    let results = [
        longest_outlier_run(&mut lattice, &config, &x),
        longest_outlier_run(&mut rls, &config, &x),
        longest_outlier_run(&mut sftf, &config, &x),
        longest_outlier_run(&mut plattice, &config, &x),
        longest_outlier_run(&mut prls, &config, &x),
        longest_outlier_run(&mut psftf, &config, &x),
        longest_outlier_run(&mut flat, &fixed, &x),
        longest_outlier_run(&mut pflat, &fixed, &x),
    ];
    let healths = [
        lattice.health(),
        rls.health(),
        sftf.health(),
        plattice.health(),
        prls.health(),
        psftf.health(),
        flat.health(),
        pflat.health(),
    ];
    for (i, ((longest, _), h)) in results.iter().zip(healths).enumerate() {
        assert!(
            *longest <= run,
            "estimator {i}: run {longest} > {run} ({h:?})"
        );
        assert_eq!(
            h.samples + h.non_finite + h.saturated + h.outliers,
            x.len() as u64,
            "estimator {i}: {h:?}"
        );
    }
}

#[test]
fn hostile_input_behind_the_gate_p1() {
    for (k, run, lambda, seed) in [
        (5.0, 8, 0.999, 1),
        (1.0, 1, 0.99, 2),
        (1e30, 1, 1.0, 3),
        (f32::MAX, 3, 0.999, 4),
        (1.0, u32::MAX, 0.999, 5),
        (1.5, 1, 1.0, 6),
    ] {
        hostile_gate_run::<1>(k, run, lambda, seed);
    }
}

#[test]
fn hostile_input_behind_the_gate_p32() {
    for (k, run, lambda, seed) in [(5.0, 8, 0.999, 11), (1.0, 2, 1.0, 12), (3.0, 1, 0.9999, 13)] {
        hostile_gate_run::<32>(k, run, lambda, seed);
    }
}

/// "A rejected sample changes nothing (the mean, the weight and the state stay as they
/// were)": an estimator that rejected an outlier behaves afterwards exactly as a copy that
/// never saw it (run bound large, so that the run counter never opens the gate).
fn rejected_changes_nothing<E: Estimator<f32, 4> + Clone + std::fmt::Debug>(
    mut e: E,
    config: &E::Config,
    name: &str,
) {
    let x = ar([0.9, -0.2], 1.0, 6000, 77);
    for &v in &x[..3000] {
        e.update(config, v as f32);
    }
    let before = e.clone();
    let outliers = e.health().outliers;
    assert_eq!(e.update(config, 30.0), None, "{name}: shock taken");
    assert_eq!(e.health().outliers, outliers + 1, "{name}");
    assert_eq!(e.model(config), before.model(config), "{name}: model moved");
    assert_eq!(e.mean(), before.mean(), "{name}: mean moved");
    assert_eq!(e.noise_variance(), before.noise_variance(), "{name}");
    let mut twin = before;
    for &v in &x[3000..] {
        let (a, b) = (e.update(config, v as f32), twin.update(config, v as f32));
        assert_eq!(a.map(f32::to_bits), b.map(f32::to_bits), "{name}: diverged");
    }
    assert_eq!(e.model(config), twin.model(config), "{name}");
}

#[test]
fn a_rejected_sample_changes_nothing_in_any_estimator() {
    let config = Config::new(0.999f32, 0.01)
        .unwrap()
        .with_gate(Gate::new(4.0, 1_000_000).unwrap());
    let channel = Channel::new(0.1f32).unwrap();
    let a0 = [0.5f32, -0.1, 0.0, 0.0];
    rejected_changes_nothing(
        Lattice::<f32, 4>::new(&config, &channel),
        &config,
        "lattice",
    );
    rejected_changes_nothing(Rls::<f32, 4>::new(&config, &channel), &config, "rls");
    rejected_changes_nothing(Sftf::<f32, 4>::new(&config, &channel), &config, "sftf");
    rejected_changes_nothing(
        Lattice::<f32, 4>::with_prior(&config, &channel, &a0).unwrap(),
        &config,
        "lattice prior",
    );
    rejected_changes_nothing(
        Rls::<f32, 4>::with_prior(&config, &channel, &a0).unwrap(),
        &config,
        "rls prior",
    );
    rejected_changes_nothing(
        Sftf::<f32, 4>::with_prior(&config, &channel, &a0).unwrap(),
        &config,
        "sftf prior",
    );
    rejected_changes_nothing(
        Settled::<_, f32, 64>::new(Lattice::<f32, 4>::new(&config, &channel)),
        &config,
        "settled lattice",
    );
    rejected_changes_nothing(
        Settled::<_, f32, 64>::new(Rls::<f32, 4>::new(&config, &channel)),
        &config,
        "settled rls",
    );
    rejected_changes_nothing(
        Settled::<_, f32, 64>::new(Sftf::<f32, 4>::new(&config, &channel)),
        &config,
        "settled sftf",
    );
    let fixed = FixedConfig::new(&config).unwrap();
    let fchannel = FixedChannel::new(&channel, 0.25).unwrap();
    rejected_changes_nothing(FixedLattice::<4>::new(&fixed, &fchannel), &fixed, "fixed");
    rejected_changes_nothing(
        FixedLattice::<4>::with_prior(&fixed, &fchannel, &a0).unwrap(),
        &fixed,
        "fixed prior",
    );
}

/// The documented rule, evaluated by the test in f64 from the estimator's own published
/// quantities before each sample: `e^2 > k^2 * noise_variance()` once `W_n >= 20`, where `e`
/// is the a-priori error the estimator would report. For the float lattice the error of an
/// accepted sample is returned by `update`; for a rejected one, the test runs a clone without
/// the gate. Mismatches are counted (f32 rounding near the threshold allows a few).
#[test]
fn float_gate_decisions_follow_the_documented_rule() {
    let x = add(&ar([0.95], 1.0, 50_000, 5), &ar([0.0], 0.5, 50_000, 6));
    let mut rng = ChaCha8Rng::seed_from_u64(7);
    let x: Vec<f64> = x
        .iter()
        .map(|&v| {
            if rng.next_u32() % 50 == 0 {
                v + 8.0 * gauss(&mut rng)
            } else {
                v
            }
        })
        .collect();
    let k = 3.0f32;
    let gated = Config::new(0.999f64, 0.01)
        .unwrap()
        .with_gate(Gate::new(k, 4).unwrap());
    let plain = Config::new(0.999f64, 0.01).unwrap();
    let channel = Channel::new(0.1f64).unwrap();
    let mut lattice = Lattice::<f64, 4>::new(&gated, &channel);
    let (mut mismatches, mut decisions) = (0u32, 0u32);
    let mut run = 0u32;
    let mut open = false;
    for &v in &x {
        let w = lattice.weight();
        let var = lattice.noise_variance();
        let mut probe = lattice;
        let e = probe.update(&plain, v);
        let before = lattice.health().outliers;
        lattice.update(&gated, v);
        let rejected = lattice.health().outliers > before;
        if let (Some(var), Some(e)) = (var, e)
            && w >= 20.0
        {
            let outlier = e * e > f64::from(k) * f64::from(k) * var;
            // The documented state machine.
            let expect_reject = if !outlier {
                run = 0;
                open = false;
                false
            } else if open {
                false
            } else {
                run += 1;
                if run >= 4 {
                    open = true;
                    run = 0;
                }
                true
            };
            decisions += 1;
            if expect_reject != rejected {
                mismatches += 1;
            }
        }
    }
    println!("{mismatches} mismatches in {decisions} decisions");
    assert!(mismatches <= 2, "{mismatches} mismatches in {decisions}");
}

/// Fixed-point and float gates on the same data (f32 lattice and fixed lattice, same
/// config): their decisions should agree but for samples within rounding of the threshold.
#[test]
fn fixed_and_float_gates_agree_on_the_same_data() {
    let x = add(&ar([0.95], 1.0, 100_000, 15), &ar([0.0], 0.5, 100_000, 16));
    let mut rng = ChaCha8Rng::seed_from_u64(17);
    let x: Vec<f32> = x
        .iter()
        .map(|&v| {
            let v = if rng.next_u32() % 40 == 0 {
                v + 10.0 * gauss(&mut rng)
            } else {
                v
            };
            v as f32
        })
        .collect();
    for k in [2.0f32, 5.0] {
        let config = Config::new(0.999f32, 0.01)
            .unwrap()
            .with_gate(Gate::new(k, 6).unwrap());
        let channel = Channel::new(0.1f32).unwrap();
        let fixed = FixedConfig::new(&config).unwrap();
        let fchannel = FixedChannel::new(&channel, 0.25).unwrap();
        let mut float = Lattice::<f32, 4>::new(&config, &channel);
        let mut fix = FixedLattice::<4>::new(&fixed, &fchannel);
        let mut disagree = 0u32;
        for &v in &x {
            let (a, b) = (float.health().outliers, fix.health().outliers);
            float.update(&config, v);
            fix.update(&fixed, v);
            let (ra, rb) = (float.health().outliers > a, fix.health().outliers > b);
            if ra != rb {
                disagree += 1;
            }
        }
        println!(
            "k {k}: float outliers {}, fixed outliers {}, disagreements {disagree}",
            float.health().outliers,
            fix.health().outliers
        );
        assert!(
            f64::from(disagree) <= 0.01 * float.health().outliers.max(100) as f64,
            "k {k}: {disagree} disagreements"
        );
    }
}

/// A gate below one standard deviation is refused (it would reject most samples, and the
/// fixed-point lattice, which carries `k^2` in Q16, turned `k = 0.002` into `k^2 = 0`). From
/// `k = 1` on, the f32 and the fixed lattice take the same share of samples.
#[test]
fn a_gate_below_one_sigma_is_refused_and_fixed_agrees_from_one() {
    for k in [0.002f32, 0.01, 0.999] {
        assert!(Gate::new(k, 16).is_err(), "k {k}");
    }
    let x = add(&ar([0.95], 1.0, 100_000, 15), &ar([0.0], 0.5, 100_000, 16));
    let x: Vec<f32> = x.iter().map(|&v| v as f32).collect();
    let mut worst = 0.0f64;
    for k in [1.0f32, 1.3] {
        let config = Config::new(0.999f32, 0.01)
            .unwrap()
            .with_gate(Gate::new(k, 1_000_000).unwrap());
        let channel = Channel::new(0.1f32).unwrap();
        let fixed = FixedConfig::new(&config).unwrap();
        let fchannel = FixedChannel::new(&channel, 0.25).unwrap();
        let mut float = Lattice::<f32, 4>::new(&config, &channel);
        let mut fix = FixedLattice::<4>::new(&fixed, &fchannel);
        let (mut taken_float, mut taken_fixed) = (0u32, 0u32);
        for &v in &x[..20_000] {
            // Same state for both: no gate decisions differ while they warm up.
            float.update(&config, v);
            fix.update(&fixed, v);
        }
        for &v in &x[20_000..] {
            // Each estimator's own decision on the same sample from the same history: run
            // each on a copy, so that a different decision does not make the states differ.
            let (mut f, mut q) = (float, fix);
            let (a, b) = (f.health().outliers, q.health().outliers);
            f.update(&config, v);
            q.update(&fixed, v);
            taken_float += u32::from(f.health().outliers == a);
            taken_fixed += u32::from(q.health().outliers == b);
            // Advance both without the gate's influence: take the sample ungated.
            let plain = Config::new(0.999f32, 0.01).unwrap();
            float.update(&plain, v);
            fix.update(&FixedConfig::new(&plain).unwrap(), v);
        }
        println!("k {k}: samples passing the gate: f32 lattice {taken_float}, fixed {taken_fixed}");
        let ratio = f64::from(taken_fixed) / f64::from(taken_float.max(1));
        worst = worst.max((ratio - 1.0).abs());
    }
    assert!(
        worst < 0.2,
        "passing counts differ by {:.0} %",
        100.0 * worst
    );
}

// ---------------------------------------------------------------------------------------
// 2. Persistence
// ---------------------------------------------------------------------------------------

fn store_model(i: u32) -> ArModel<f32, 4> {
    ArModel::new(
        [0.5, -0.1, 0.05, 0.001 * i as f32],
        1e-4 * (i + 1) as f32,
        i as f32,
        0.01,
    )
    .unwrap()
}

fn fsave<const R: usize, const W: usize, const E: usize, M: Record>(
    flash: &mut RamFlash<R, W, E>,
    m: &M,
) -> Result<u32, StoreError<RamFlashError>> {
    let mut buf = vec![0u8; M::LEN];
    let end = embedded_storage::nor_flash::ReadNorFlash::capacity(flash) as u32;
    FlashStore::new(flash, 0..end).unwrap().save(m, &mut buf)
}

fn fload<const R: usize, const W: usize, const E: usize, M: Record>(
    flash: &mut RamFlash<R, W, E>,
) -> Result<M, StoreError<RamFlashError>> {
    let mut buf = vec![0u8; M::LEN];
    let end = embedded_storage::nor_flash::ReadNorFlash::capacity(flash) as u32;
    FlashStore::new(flash, 0..end).unwrap().load(&mut buf)
}

/// A transient read error during `save`'s scan (the second entry of slot 0 unreadable for
/// the duration of one save) hid the newest entry (seq 1): the save took seq 0 as the newest,
/// wrote the new model as seq 1 again in slot 1 and returned `Ok(1)`; once the read error was
/// gone the tie went to slot 0 and `load` returned the model from before that save. Now the
/// save refuses, writing nothing; the next one, without the fault, is the newest.
#[test]
fn flash_transient_read_error_in_save_loses_the_saved_model() {
    let mut flash = RamFlash::<1, 4, 256>::new(2);
    fsave(&mut flash, &store_model(0)).unwrap();
    fsave(&mut flash, &store_model(1)).unwrap();
    let before = flash.bytes().to_vec();
    // The second entry (bytes 52..104) reads with an error during the next save only.
    flash.fail_reads_at(60..61);
    let saved = fsave(&mut flash, &store_model(2));
    println!("save during the read error: {saved:?}");
    assert!(matches!(saved, Err(StoreError::Flash(_))), "{saved:?}");
    assert!(
        flash.bytes() == &before[..],
        "the refused save wrote or erased"
    );
    flash.fail_reads_at(0..0); // the fault is gone
    assert_eq!(
        fload::<1, 4, 256, ArModel<f32, 4>>(&mut flash),
        Ok(store_model(1))
    );
    assert_eq!(fsave(&mut flash, &store_model(2)), Ok(2));
    let loaded: Result<ArModel<f32, 4>, _> = fload(&mut flash);
    println!("load afterwards: {loaded:?}");
    assert_eq!(
        loaded,
        Ok(store_model(2)),
        "the model saved last is not the one loaded"
    );
}

/// Slot 0 full (4 entries, seq 0..3), slot 1 holding the newest (seq 4). A read error on
/// slot 1 during a save makes the store treat slot 0 as newest and erase slot 1 - the slot
/// that holds the newest intact entry ("no save ever erases or writes a byte of the newest
/// intact entry"). A power cut during that erase then leaves seq 3 as the newest: the last
/// committed model (seq 4) is gone.
#[test]
fn flash_read_error_lets_save_erase_the_newest_entry() {
    let mut flash = RamFlash::<1, 4, 256>::new(2);
    for i in 0..5 {
        fsave(&mut flash, &store_model(i)).unwrap();
    }
    assert_eq!(
        fload::<1, 4, 256, ArModel<f32, 4>>(&mut flash),
        Ok(store_model(4))
    );
    let newest_entry = flash.bytes()[256..308].to_vec();
    flash.fail_reads_at(256..257);
    flash.cut_after(10); // the power fails 10 bytes into the save's first erase or write
    let saved = fsave(&mut flash, &store_model(5));
    println!("save: {saved:?}");
    flash.power_on();
    flash.fail_reads_at(0..0);
    let touched = flash.bytes()[256..308] != newest_entry[..];
    let loaded: Result<ArModel<f32, 4>, _> = fload(&mut flash);
    println!("newest entry touched: {touched}; load: {loaded:?}");
    assert!(!touched, "the save erased the newest intact entry");
    assert_eq!(loaded, Ok(store_model(4)));
}

/// CRC-valid records whose values are nonsense: each must decode to a typed error.
#[test]
fn crc_valid_nonsense_records_are_typed_errors() {
    let good = ArModel::new([0.5f32, -0.2], 1e-3, 0.1, 0.01).unwrap();
    let mut base = vec![0u8; ArModel::<f32, 2>::LEN];
    good.encode(&mut base).unwrap();
    // Offsets: a1 12, a2 16, variance 20, mean 24, dt 28.
    let cases: Vec<(usize, f32)> = vec![
        (20, f32::NAN),
        (20, -1e-3),
        (20, f32::INFINITY),
        (12, f32::NAN),
        (16, f32::INFINITY),
        (12, 1.5), // not stationary with a2 = -0.2? 1.5 - 0.2: k2 = -0.2, k1 ... checked below
        (12, 3.0),
        (24, f32::NAN),
        (24, f32::NEG_INFINITY),
        (28, 0.0),
        (28, -0.01),
        (28, f32::NAN),
        (28, f32::INFINITY),
    ];
    for (offset, v) in cases {
        let mut r = base.clone();
        r[offset..offset + 4].copy_from_slice(&v.to_le_bytes());
        reseal(&mut r);
        let got = ArModel::<f32, 2>::decode(&r);
        println!("offset {offset} = {v}: {got:?}");
        if let Ok(m) = got {
            assert!(m.is_stable(), "unstable model decoded: {m:?}");
            assert!(m.noise_variance() >= 0.0 && m.noise_variance().is_finite());
        }
        assert!(
            matches!(got, Err(DecodeError::Ar(_))) || got.is_ok(),
            "{got:?}"
        );
    }
    // Values the constructor accepts but that are hardly a model: zero and negative-zero
    // variance, a subnormal dt, a mean of f32::MAX. Printed for the report.
    for (offset, v) in [(20usize, 0.0f32), (20, -0.0), (28, 1e-45), (24, f32::MAX)] {
        let mut r = base.clone();
        r[offset..offset + 4].copy_from_slice(&v.to_le_bytes());
        reseal(&mut r);
        println!(
            "accepted? offset {offset} = {v:e}: {:?}",
            ArModel::<f32, 2>::decode(&r)
        );
    }
    // Headers: L below 16, L beyond the bytes, L of another type, every kind byte.
    for len in [0u16, 15, 16, 17, 43, 45, 1000, u16::MAX] {
        let mut r = base.clone();
        r[10..12].copy_from_slice(&len.to_le_bytes());
        reseal(&mut r);
        let got = ArModel::<f32, 2>::decode(&r);
        assert!(got.is_err(), "len {len}: {got:?}");
    }
    for kind in 0u8..=255 {
        let mut r = base.clone();
        r[5] = kind;
        reseal(&mut r);
        let got = ArModel::<f32, 2>::decode(&r);
        assert_eq!(got.is_ok(), kind == 1, "kind {kind}: {got:?}");
        // The same bytes as other record types never decode and never panic.
        let _ = ArModel::<f64, 2>::decode(&r);
        let _ = <[ArModel<f32, 2>; 1]>::decode(&r);
        let _ = NoiseModel::<2, 0>::decode(&r);
    }
}

fn noise() -> NoiseModel<2, 2> {
    let c = Coefficients {
        quantization: 1e-5,
        white: 3e-3,
        random_walk: 2e-5,
        ramp: 0.0,
    };
    let gm = [GmTerm {
        sigma: 4e-3,
        correlation_time: 25.0,
    }];
    let osc = [Oscillator {
        sigma: 1e-3,
        frequency: 7.5,
        decay_time: 1.0,
    }];
    let ar = ArModel::new([0.5f64, -0.1], 1e-4, 0.0, 0.01).unwrap();
    NoiseModel::new(0.01, c, &gm, &osc, Some(ar)).unwrap()
}

/// Noise records with nonsense in CRC-valid bytes: typed errors. Layout for P = 2, G = 2:
/// 12 n_gm, 14 n_osc, 16 flag, 20 dt, 28 Q N K R, 60 GM slots (16 each), 92 oscillators
/// (24 each), 140 AR part (a1, a2, variance, mean, dt), L = 88 + 80 + 16 = 184.
#[test]
fn crc_valid_nonsense_noise_records_are_typed_errors() {
    let m = noise();
    let mut base = vec![0u8; NoiseModel::<2, 2>::LEN];
    m.encode(&mut base).unwrap();
    assert_eq!(NoiseModel::<2, 2>::decode(&base), Ok(m));
    let f64_cases: Vec<(usize, f64)> = vec![
        (20, f64::NAN),
        (20, 0.0),
        (28, -1.0),
        (36, f64::INFINITY),
        (60, f64::NAN),  // GM sigma
        (68, 0.0),       // GM correlation time
        (76, 1.0),       // unused GM slot not zero
        (92, -1.0),      // oscillator sigma
        (100, f64::NAN), // frequency
        (140, 2.5),      // AR a1: unstable
        (156, f64::NAN), // AR variance
        (156, -1.0),     // AR variance negative
        (172, 0.0),      // AR dt zero
        (172, -0.0),     // AR dt negative zero
    ];
    for (offset, v) in f64_cases {
        let mut r = base.clone();
        r[offset..offset + 8].copy_from_slice(&v.to_le_bytes());
        reseal(&mut r);
        let got = NoiseModel::<2, 2>::decode(&r);
        println!("offset {offset} = {v}: {got:?}");
        assert!(got.is_err(), "offset {offset} = {v}: decoded {got:?}");
    }
    // Counts and flag.
    for (offset, bytes) in [(12usize, 3u16), (14, 3), (12, u16::MAX), (16, 2)] {
        let mut r = base.clone();
        r[offset..offset + 2].copy_from_slice(&bytes.to_le_bytes());
        reseal(&mut r);
        assert!(NoiseModel::<2, 2>::decode(&r).is_err(), "{offset}");
    }
    // n_gm = 2 with the second slot all zeros: a GM term of correlation time 0 (invalid).
    let mut r = base.clone();
    r[12..14].copy_from_slice(&2u16.to_le_bytes());
    reseal(&mut r);
    assert!(NoiseModel::<2, 2>::decode(&r).is_err());
    // The AR part's dt different from the model's dt (0.01): printed for the report.
    let mut r = base.clone();
    r[172..180].copy_from_slice(&123.0f64.to_le_bytes());
    reseal(&mut r);
    println!(
        "AR part with dt 123 in a model of dt 0.01: {:?}",
        NoiseModel::<2, 2>::decode(&r).map(|m| m.ar().map(|a| a.dt()))
    );
}

// ---------------------------------------------------------------------------------------
// 3. Thermal
// ---------------------------------------------------------------------------------------

/// Random search: small delta (down to the documented lower limit), high N, temperatures
/// clustered in a tiny part of the range, samples up to the magnitude limit, alternating.
/// "never returns NaN ... the residual is always finite", and `bias` finite.
fn thermal_search<const N: usize>(seed: u64, iters: usize) -> Option<String> {
    let mut rng = ChaCha8Rng::seed_from_u64(seed);
    for it in 0..iters {
        let lambda = [1.0f32, 0.99999, 0.999, 0.9, 0.5, 0.1, 0.01][(rng.next_u32() % 7) as usize];
        let delta = 10f32.powf(-(uniform(&mut rng) * 31.0) as f32);
        let Ok(config) =
            ThermalConfig::<f32, N>::new(lambda, 20.0, 60.0).and_then(|c| c.with_delta(delta))
        else {
            continue;
        };
        let mut stage = ThermalBias::new(&config);
        let centre = 20.0 + 40.0 * uniform(&mut rng);
        let spread = 10f64.powf(-7.0 * uniform(&mut rng)) * 40.0;
        let amp = 10f64.powf(12.0 * uniform(&mut rng));
        for i in 0..3000 {
            let t = (centre + spread * (uniform(&mut rng) - 0.5)).clamp(20.0, 60.0) as f32;
            let x = match rng.next_u32() % 3 {
                0 => {
                    if i % 2 == 0 {
                        amp
                    } else {
                        -amp
                    }
                }
                1 => amp * gauss(&mut rng),
                _ => amp * (uniform(&mut rng) - 0.5),
            } as f32;
            let x = x.clamp(-1.0e12, 1.0e12);
            if let Some(r) = stage.update(&config, x, t)
                && !r.is_finite()
            {
                return Some(format!(
                    "it {it} sample {i}: N {N} lambda {lambda} delta {delta:e} centre {centre} \
                     spread {spread:e} amp {amp:e}: residual {r} c {:?}",
                    stage.coefficients()
                ));
            }
            if let Some(b) = stage.bias(&config, 60.0)
                && !b.is_finite()
            {
                return Some(format!(
                    "it {it} sample {i}: N {N} lambda {lambda} delta {delta:e}: bias {b} c {:?}",
                    stage.coefficients()
                ));
            }
        }
    }
    None
}

#[test]
fn thermal_residual_stays_finite_in_ill_conditioned_runs() {
    let iters: usize = std::env::var("REDTEAM_THERMAL_ITERS")
        .ok()
        .and_then(|s| s.parse().ok())
        .unwrap_or(40);
    let found = [
        thermal_search::<2>(1, iters),
        thermal_search::<4>(2, iters),
        thermal_search::<8>(3, iters),
    ];
    for f in found.iter().flatten() {
        println!("{f}");
    }
    assert!(found.iter().all(Option::is_none));
}

// ---------------------------------------------------------------------------------------
// 4. Prior and settled start
// ---------------------------------------------------------------------------------------

/// A finite but huge prior made the float estimators restart every two or three samples
/// for ever (and `a0 = 1e10` gave an f32 lattice at a = 61440): it is refused, as beyond
/// `2 C(P, k)`.
#[test]
fn a_huge_finite_prior_is_refused() {
    let config = Config::new(0.999f32, 0.01).unwrap();
    let channel = Channel::new(0.1f32).unwrap();
    for a0 in [1e10f32, 1e20, 1e30, f32::MAX, 2.001] {
        assert!(Lattice::<f32, 1>::with_prior(&config, &channel, &[a0]).is_err());
        assert!(Rls::<f32, 1>::with_prior(&config, &channel, &[a0]).is_err());
        assert!(Sftf::<f32, 1>::with_prior(&config, &channel, &[a0]).is_err());
    }
}

// ---------------------------------------------------------------------------------------
// 2b. Persistence, more
// ---------------------------------------------------------------------------------------

/// A bit flipped at rest in an *older* entry (seq 1 of slot 0, whose header and length still
/// read correctly) ends the scan of slot 0 there: the intact entries after it (seq 2, 3) are
/// never seen, and `load` returns seq 0, three saves old. Docs: "FlashStore::load returns
/// the intact entry with the newest sequence number"; an entry is intact when "its record's
/// length and CRC-32 check ... and !s matches s". Seq 3 is intact by that definition. (The
/// docs' damage-at-rest bullet covers only "a bit flipped in the newest entry".)
#[test]
fn flash_damage_in_an_older_entry_hides_the_newest() {
    let mut flash = RamFlash::<1, 4, 256>::new(2);
    for i in 0..4 {
        fsave(&mut flash, &store_model(i)).unwrap();
    }
    flash.bytes_mut()[52 + 20] ^= 0x01; // the variance of seq 1's record
    let loaded: Result<ArModel<f32, 4>, _> = fload(&mut flash);
    println!("load: {loaded:?}");
    assert_eq!(loaded, Ok(store_model(3)));
}

/// Same after slots alternate: slot 0 holds seq 0..3, slot 1 seq 4..7, slot 0 erased and
/// holding seq 8..11. One bit flipped in seq 8: `load` returns seq 7 (slot 1), four saves
/// old, while seq 9, 10 and 11 are intact.
#[test]
fn flash_damage_in_the_first_entry_of_a_slot_returns_the_other_slot() {
    let mut flash = RamFlash::<1, 4, 256>::new(2);
    for i in 0..12 {
        fsave(&mut flash, &store_model(i)).unwrap();
    }
    assert_eq!(
        fload::<1, 4, 256, ArModel<f32, 4>>(&mut flash),
        Ok(store_model(11))
    );
    flash.bytes_mut()[20] ^= 0x01; // seq 8, the first entry of slot 0
    let loaded: Result<ArModel<f32, 4>, _> = fload(&mut flash);
    println!("load: {loaded:?}");
    assert_eq!(loaded, Ok(store_model(11)));
}

/// A slot of exactly one entry (WRITE 8, ERASE 56: the 52-byte entry padded to 56): every
/// save erases the other slot. A power cut at every byte of ten consecutive saves: the
/// old model or the new one, never nothing.
#[test]
fn flash_one_entry_per_slot_survives_a_cut_at_every_byte() {
    let mut flash = RamFlash::<8, 8, 56>::new(2);
    fsave(&mut flash, &store_model(0)).unwrap();
    for i in 1..10u32 {
        let old = store_model(i - 1);
        let new = store_model(i);
        let mut probe = flash.clone();
        let start = probe.ops;
        fsave(&mut probe, &new).unwrap();
        let total = probe.ops - start;
        for k in 0..total {
            let mut f = flash.clone();
            f.cut_after(k);
            assert!(fsave(&mut f, &new).is_err());
            f.power_on();
            let got: ArModel<f32, 4> =
                fload(&mut f).unwrap_or_else(|e| panic!("save {i} cut {k}: {e:?}"));
            assert!(got == old || got == new, "save {i} cut {k}: {got:?}");
            // After the cut the store still works.
            fsave(&mut f, &new).unwrap();
            assert_eq!(fload::<8, 8, 56, ArModel<f32, 4>>(&mut f), Ok(new));
        }
        fsave(&mut flash, &new).unwrap();
    }
}

/// Both slots damaged (a bit in every entry): `Empty`, and the next save works.
#[test]
fn flash_both_slots_corrupt_is_empty_then_saves() {
    let mut flash = RamFlash::<1, 4, 256>::new(2);
    for i in 0..6 {
        fsave(&mut flash, &store_model(i)).unwrap();
    }
    for at in [0usize, 52, 104, 156, 256, 308] {
        flash.bytes_mut()[at + 30] ^= 0x40;
    }
    assert_eq!(
        fload::<1, 4, 256, ArModel<f32, 4>>(&mut flash),
        Err(StoreError::Empty)
    );
    fsave(&mut flash, &store_model(9)).unwrap();
    assert_eq!(
        fload::<1, 4, 256, ArModel<f32, 4>>(&mut flash),
        Ok(store_model(9))
    );
}

/// Sequence numbers near the wrap, planted: u32::MAX itself (which the store never writes:
/// its bytes are FF FF FF FF 00 00 00 00), MAX - 1, 0, and a gap of exactly 2^31.
#[test]
fn flash_sequence_wrap_planted() {
    let entry = |seq: u32, m: &ArModel<f32, 4>| {
        let mut e = vec![0u8; 44];
        m.encode(&mut e).unwrap();
        e.extend(seq.to_le_bytes());
        e.extend((!seq).to_le_bytes());
        e
    };
    let mut flash = RamFlash::<1, 4, 256>::new(2);
    flash.bytes_mut()[..52].copy_from_slice(&entry(u32::MAX, &store_model(1)));
    assert_eq!(
        fload::<1, 4, 256, ArModel<f32, 4>>(&mut flash),
        Ok(store_model(1))
    );
    assert_eq!(fsave(&mut flash, &store_model(2)), Ok(0));
    assert_eq!(
        fload::<1, 4, 256, ArModel<f32, 4>>(&mut flash),
        Ok(store_model(2))
    );
    // A gap of exactly 2^31: neither is newer; slot 0 wins the tie. Printed.
    let mut flash = RamFlash::<1, 4, 256>::new(2);
    flash.bytes_mut()[..52].copy_from_slice(&entry(5, &store_model(3)));
    flash.bytes_mut()[256..308].copy_from_slice(&entry(5 + (1 << 31), &store_model(4)));
    let got: Result<ArModel<f32, 4>, _> = fload(&mut flash);
    println!("gap 2^31: {got:?}");
    assert!(got.is_ok());
}

/// An erase or write that fails without a power cut (the flash reports an error and stays
/// on), at every operation of a save: the newest entry stays readable, and a later save
/// works.
#[derive(Clone)]
struct Faulty {
    inner: RamFlash<1, 4, 256>,
    /// Fail the n-th erase or write call (counting from 0), with nothing done.
    fail_at: Option<usize>,
    /// Fail it after doing half of it.
    half: bool,
    calls: usize,
}

impl embedded_storage::nor_flash::ErrorType for Faulty {
    type Error = RamFlashError;
}

impl embedded_storage::nor_flash::ReadNorFlash for Faulty {
    const READ_SIZE: usize = 1;
    fn read(&mut self, offset: u32, bytes: &mut [u8]) -> Result<(), Self::Error> {
        self.inner.read(offset, bytes)
    }
    fn capacity(&self) -> usize {
        self.inner.capacity()
    }
}

impl embedded_storage::nor_flash::NorFlash for Faulty {
    const WRITE_SIZE: usize = 4;
    const ERASE_SIZE: usize = 256;
    fn erase(&mut self, from: u32, to: u32) -> Result<(), Self::Error> {
        let n = self.calls;
        self.calls += 1;
        if self.fail_at == Some(n) {
            if self.half {
                let mid = from + (to - from) / 2 / 256 * 256;
                if mid > from {
                    self.inner.erase(from, mid)?;
                }
            }
            return Err(RamFlashError::OutOfBounds);
        }
        self.inner.erase(from, to)
    }
    fn write(&mut self, offset: u32, bytes: &[u8]) -> Result<(), Self::Error> {
        let n = self.calls;
        self.calls += 1;
        if self.fail_at == Some(n) {
            if self.half {
                let h = bytes.len() / 2 / 4 * 4;
                self.inner.write(offset, &bytes[..h])?;
            }
            return Err(RamFlashError::OutOfBounds);
        }
        self.inner.write(offset, bytes)
    }
}

#[test]
fn flash_erase_and_write_errors_keep_the_newest() {
    use embedded_storage::nor_flash::ReadNorFlash;
    for saves_before in 1..10u32 {
        for fail_at in 0..3 {
            for half in [false, true] {
                let mut f = Faulty {
                    inner: RamFlash::new(4),
                    fail_at: None,
                    half,
                    calls: 0,
                };
                let mut buf = [0u8; 44];
                let cap = f.capacity() as u32;
                for i in 0..saves_before {
                    FlashStore::new(&mut f, 0..cap)
                        .unwrap()
                        .save(&store_model(i), &mut buf)
                        .unwrap();
                }
                f.calls = 0;
                f.fail_at = Some(fail_at);
                let r = FlashStore::new(&mut f, 0..cap)
                    .unwrap()
                    .save(&store_model(100), &mut buf);
                f.fail_at = None;
                let got: ArModel<f32, 4> = FlashStore::new(&mut f, 0..cap)
                    .unwrap()
                    .load(&mut buf)
                    .unwrap();
                let old = store_model(saves_before - 1);
                assert!(
                    got == old || (r.is_ok() && got == store_model(100)),
                    "before {saves_before} fail {fail_at} half {half}: {r:?} {got:?}"
                );
                // And the store goes on.
                FlashStore::new(&mut f, 0..cap)
                    .unwrap()
                    .save(&store_model(200), &mut buf)
                    .unwrap();
                let got: ArModel<f32, 4> = FlashStore::new(&mut f, 0..cap)
                    .unwrap()
                    .load(&mut buf)
                    .unwrap();
                assert_eq!(got, store_model(200));
            }
        }
    }
}

/// Regions: misaligned, beyond the flash, reversed, empty, one unit, u32 edges.
#[test]
fn flash_bad_regions_are_typed_errors() {
    let mut flash = RamFlash::<1, 4, 256>::new(4);
    #[allow(clippy::reversed_empty_ranges)]
    for r in [
        0..0u32,
        0..256,
        256..0,
        1..513,
        0..1025,
        0..u32::MAX,
        u32::MAX - 255..u32::MAX,
        512..512,
    ] {
        assert!(
            matches!(
                FlashStore::new(&mut flash, r.clone()),
                Err(StoreError::Region)
            ),
            "{r:?}"
        );
    }
    // Odd units: the last unused. Buffer too short for load: typed.
    let mut store = FlashStore::new(&mut flash, 0..768).unwrap();
    assert_eq!(store.slot_len(), 256);
    let mut short = [0u8; 11];
    assert!(matches!(
        store.load::<ArModel<f32, 4>>(&mut short),
        Err(StoreError::Buffer { .. })
    ));
}

/// Truncations and random bytes of every record type: a typed error, never a panic.
#[test]
fn decode_never_panics_on_prefixes_and_noise() {
    let mut rng = ChaCha8Rng::seed_from_u64(99);
    let mut buf = vec![0u8; NoiseModel::<2, 2>::LEN];
    noise().encode(&mut buf).unwrap();
    for n in 0..buf.len() {
        assert!(NoiseModel::<2, 2>::decode(&buf[..n]).is_err());
    }
    for _ in 0..20_000 {
        let n = (rng.next_u32() % 300) as usize;
        let mut b: Vec<u8> = (0..n).map(|_| rng.next_u32() as u8).collect();
        if n >= 16 && rng.next_u32() % 2 == 0 {
            b[..4].copy_from_slice(b"IMAR");
            b[4] = 1;
            b[5] = (rng.next_u32() % 6) as u8;
            let len = (n as u16).to_le_bytes();
            b[10..12].copy_from_slice(&len);
            reseal(&mut b);
        }
        let _ = ArModel::<f32, 2>::decode(&b);
        let _ = ArModel::<f64, 1>::decode(&b);
        let _ = <[ArModel<f32, 1>; 3]>::decode(&b);
        let _ = NoiseModel::<2, 2>::decode(&b);
        let _ = NoiseModel::<1, 0>::decode(&b);
    }
}

// ---------------------------------------------------------------------------------------
// 1b. The gate on changes: steps, ramps, noise levels, stuck sensors, lambda = 1
// ---------------------------------------------------------------------------------------

/// Runs a gated and an ungated f32 lattice (P = 4) over `x`; returns the longest run of
/// rejections, the total outliers, and the final innovation variances (gated, ungated).
fn gated_vs_plain(x: &[f64], lambda: f32, k: f32, run: u32) -> (u32, u64, f64, f64, Vec<f64>) {
    let gated = Config::new(lambda, 0.01)
        .unwrap()
        .with_gate(Gate::new(k, run).unwrap());
    let plain = Config::new(lambda, 0.01).unwrap();
    let channel = Channel::new(0.1f32).unwrap();
    let mut g = Lattice::<f32, 4>::new(&gated, &channel);
    let mut p = Lattice::<f32, 4>::new(&plain, &channel);
    let (mut cur, mut longest) = (0u32, 0u32);
    let mut trace = Vec::new();
    for (n, &v) in x.iter().enumerate() {
        let before = g.health().outliers;
        g.update(&gated, v as f32);
        p.update(&plain, v as f32);
        if g.health().outliers > before {
            cur += 1;
            longest = longest.max(cur);
        } else {
            cur = 0;
        }
        if n % (x.len() / 20).max(1) == 0 {
            trace.push(
                f64::from(g.noise_variance().unwrap_or(0.0))
                    / f64::from(p.noise_variance().unwrap_or(1.0)),
            );
        }
    }
    (
        longest,
        g.health().outliers,
        f64::from(g.noise_variance().unwrap()),
        f64::from(p.noise_variance().unwrap()),
        trace,
    )
}

/// A new noise level (sigma x10 from the middle of the record): the bound holds (at most
/// `run` in a row); how far the gated variance lags the ungated one is printed.
#[test]
fn gate_on_a_new_noise_level() {
    let n = 40_000;
    let mut x = ar([0.9], 1.0, n, 41);
    let loud = ar([0.9], 10.0, n, 42);
    x[n / 2..].copy_from_slice(&loud[n / 2..]);
    for lambda in [0.999f32, 0.9999, 1.0] {
        let (longest, outliers, g, p, trace) = gated_vs_plain(&x, lambda, 5.0, 8);
        println!(
            "lambda {lambda}: longest run {longest}, outliers {outliers}, variance gated {g:.3} \
             ungated {p:.3}; gated/ungated along the record {:?}",
            trace
                .iter()
                .map(|v| (v * 100.0).round() / 100.0)
                .collect::<Vec<_>>()
        );
        assert!(longest <= 8);
    }
}

/// A ramp in the level (a drifting bias) and a step: the bound holds at every lambda.
#[test]
fn gate_on_ramps_and_steps_keeps_its_bound() {
    let n = 60_000;
    let base = ar([0.5], 1.0, n, 43);
    for slope in [1e-3, 1e-2, 0.1, 1.0] {
        let x: Vec<f64> = base
            .iter()
            .enumerate()
            .map(|(i, v)| v + slope * i as f64)
            .collect();
        for lambda in [0.99f32, 0.999, 1.0] {
            for run in [1u32, 3, 50] {
                let (longest, outliers, g, p, _) = gated_vs_plain(&x, lambda, 4.0, run);
                if run == 3 {
                    println!(
                        "ramp {slope}/sample lambda {lambda} run {run}: longest {longest}, \
                         outliers {outliers}, variance gated {g:.3} ungated {p:.3}"
                    );
                }
                assert!(longest <= run, "{slope} {lambda} {run}: {longest}");
            }
        }
    }
}

/// A stuck sensor (constant for 50,000 samples, the energy decaying to its floor) that
/// then moves again: at most `run` rejections in a row, and the variance recovers.
#[test]
fn gate_after_a_stuck_sensor() {
    let n = 100_000;
    let mut x = ar([0.9], 1.0, n, 44);
    for v in &mut x[20_000..70_000] {
        *v = 3.25;
    }
    for lambda in [0.999f32, 1.0] {
        let (longest, outliers, g, p, trace) = gated_vs_plain(&x, lambda, 5.0, 8);
        println!(
            "lambda {lambda}: longest run {longest}, outliers {outliers}, variance gated {g:.4} \
             ungated {p:.4}; ratio trace {:?}",
            trace
                .iter()
                .map(|v| (v * 100.0).round() / 100.0)
                .collect::<Vec<_>>()
        );
        assert!(longest <= 8);
    }
}

/// lambda = 1 past the f32 weight limit (2^21): the weight and energies are halved; the
/// gate's threshold stays right: shocks of 20 sigma are still rejected and the variance
/// stays that of the clean record.
#[test]
fn gate_at_lambda_one_past_the_weight_limit() {
    let n = 2_300_000;
    let x = ar([0.8], 1.0, n, 45);
    let config = Config::new(1.0f32, 0.01)
        .unwrap()
        .with_gate(Gate::new(5.0, 8).unwrap());
    let channel = Channel::new(0.1f32).unwrap();
    let mut lattice = Lattice::<f32, 2>::new(&config, &channel);
    let mut rls = Rls::<f32, 2>::new(&config, &channel);
    let fixed = FixedConfig::new(&config).unwrap();
    let mut flat = FixedLattice::<2>::new(&fixed, &FixedChannel::new(&channel, 0.5).unwrap());
    let mut shocks = 0u64;
    for (i, &v) in x.iter().enumerate() {
        let v = if i > 100_000 && i % 1000 == 0 {
            shocks += 1;
            v + 20.0
        } else {
            v
        } as f32;
        lattice.update(&config, v);
        rls.update(&config, v);
        flat.update(&fixed, v);
    }
    for (name, var, h) in [
        ("lattice", lattice.noise_variance(), lattice.health()),
        ("rls", rls.noise_variance(), rls.health()),
        ("fixed lattice", flat.noise_variance(), flat.health()),
    ] {
        println!(
            "{name}: variance {var:?}, weight {}, {h:?}, shocks {shocks}",
            lattice.weight()
        );
        assert!((var.unwrap() - 1.0).abs() < 0.02, "{name}: {var:?}");
        assert!(
            h.outliers >= shocks && h.outliers < shocks + 200,
            "{name}: {h:?}"
        );
    }
}

/// Alternating outliers (every other sample +-50 sigma): all rejected, each clean sample
/// between resets the run. Every third sample an outlier of alternating sign: same.
#[test]
fn alternating_outliers_are_all_rejected() {
    let x = ar([0.9], 1.0, 40_000, 46);
    for period in [2usize, 3] {
        let config = Config::new(0.999f32, 0.01)
            .unwrap()
            .with_gate(Gate::new(5.0, 2).unwrap());
        let channel = Channel::new(0.1f32).unwrap();
        let mut lattice = Lattice::<f32, 4>::new(&config, &channel);
        let mut fixed_l = FixedLattice::<4>::new(
            &FixedConfig::new(&config).unwrap(),
            &FixedChannel::new(&channel, 0.2).unwrap(),
        );
        let fixed = FixedConfig::new(&config).unwrap();
        let mut planted = 0u64;
        for (i, &v) in x.iter().enumerate() {
            let v = if i > 1000 && i % period == 0 {
                planted += 1;
                v + if (i / period) % 2 == 0 { 50.0 } else { -50.0 }
            } else {
                v
            } as f32;
            lattice.update(&config, v);
            fixed_l.update(&fixed, v);
        }
        println!(
            "period {period}: planted {planted}, outliers float {} fixed {}, variance {:?} {:?}",
            lattice.health().outliers,
            fixed_l.health().outliers,
            lattice.noise_variance(),
            fixed_l.noise_variance()
        );
        // Every planted outlier rejected (the variance is then that of the record with those
        // samples dropped, which at period 2 is the AR(1) sampled every other sample:
        // 1 + 0.81 = 1.81, as documented: "the gate drops samples").
        assert!(lattice.health().outliers >= planted);
        assert!(fixed_l.health().outliers >= planted);
    }
}

/// f32 against f64 on the same data: the same decisions but for samples within rounding of
/// the threshold.
#[test]
fn f32_and_f64_gates_agree() {
    let x = add(
        &ar([0.95, -0.1], 1.0, 100_000, 47),
        &ar([0.0], 0.3, 100_000, 48),
    );
    let mut rng = ChaCha8Rng::seed_from_u64(49);
    let x: Vec<f64> = x
        .iter()
        .map(|&v| {
            if rng.next_u32() % 30 == 0 {
                v + 6.0 * gauss(&mut rng)
            } else {
                v
            }
        })
        .collect();
    let c32 = Config::new(0.999f32, 0.01)
        .unwrap()
        .with_gate(Gate::new(4.0, 5).unwrap());
    let c64 = Config::new(0.999f64, 0.01)
        .unwrap()
        .with_gate(Gate::new(4.0, 5).unwrap());
    let mut a = Rls::<f32, 4>::new(&c32, &Channel::new(0.1f32).unwrap());
    let mut b = Rls::<f64, 4>::new(&c64, &Channel::new(0.1f64).unwrap());
    let mut disagree = 0;
    for &v in &x {
        let (oa, ob) = (a.health().outliers, b.health().outliers);
        a.update(&c32, v as f32);
        b.update(&c64, v);
        if (a.health().outliers > oa) != (b.health().outliers > ob) {
            disagree += 1;
        }
    }
    println!(
        "f32 outliers {}, f64 outliers {}, disagreements {disagree}",
        a.health().outliers,
        b.health().outliers
    );
    assert!(disagree < 20);
}

// ---------------------------------------------------------------------------------------
// 4b. Settled start, hostile
// ---------------------------------------------------------------------------------------

fn settled_run<E: imu_ar::recursive::Start<f32, 4> + Clone, const N: usize>(
    e: E,
    config: &Config<f32>,
    warm: &[f32],
    rest: &[f32],
    name: &str,
) {
    let mut s = Settled::<E, f32, N>::new(e);
    for &v in warm.iter().chain(rest) {
        if let Some(err) = s.update(config, v) {
            assert!(err.is_finite(), "{name}: {err}");
        }
    }
    let m = s.model(config);
    println!(
        "{name}: started {}, {:?}, model {:?}",
        s.started(),
        s.health(),
        m.map(|m| *m.a())
    );
    if let Some(m) = m {
        assert!(m.a().iter().all(|a| a.is_finite()) && m.noise_variance().is_finite());
    }
    assert!(
        s.model(config).is_some(),
        "{name}: no model after {} samples",
        warm.len() + rest.len()
    );
}

#[test]
fn settled_start_on_hostile_warm_ups() {
    let config = Config::new(0.999f32, 0.01).unwrap();
    let channel = Channel::new(0.1f32).unwrap();
    let rest: Vec<f32> = ar([0.9], 1.0, 5000, 50).iter().map(|&v| v as f32).collect();
    let warm_sets: Vec<(&str, Vec<f32>)> = vec![
        ("constant", vec![3.0; 16]),
        (
            "huge",
            (0..16)
                .map(|i| if i % 2 == 0 { 1e30 } else { -1e30 })
                .collect(),
        ),
        ("f32::MAX", vec![f32::MAX; 16]),
        (
            "nan mix",
            (0..32)
                .map(|i| if i % 2 == 0 { f32::NAN } else { i as f32 })
                .collect(),
        ),
        ("subnormal", (0..16).map(|i| 1e-44 * i as f32).collect()),
        ("ramp", (0..16).map(|i| i as f32).collect()),
        (
            "alternating",
            (0..16)
                .map(|i| if i % 2 == 0 { 1.0 } else { -1.0 })
                .collect(),
        ),
    ];
    for (name, warm) in &warm_sets {
        settled_run::<_, 16>(
            Lattice::<f32, 4>::new(&config, &channel),
            &config,
            warm,
            &rest,
            &format!("lattice {name}"),
        );
        settled_run::<_, 16>(
            Rls::<f32, 4>::new(&config, &channel),
            &config,
            warm,
            &rest,
            &format!("rls {name}"),
        );
        settled_run::<_, 16>(
            Sftf::<f32, 4>::new(&config, &channel),
            &config,
            warm,
            &rest,
            &format!("sftf {name}"),
        );
        // N smaller than P, and N = 1.
        settled_run::<_, 2>(
            Lattice::<f32, 4>::new(&config, &channel),
            &config,
            warm,
            &rest,
            &format!("lattice N=2 {name}"),
        );
        settled_run::<_, 1>(
            Sftf::<f32, 4>::new(&config, &channel),
            &config,
            warm,
            &rest,
            &format!("sftf N=1 {name}"),
        );
    }
}

/// Outside this pass's targets (found while testing the gate at lambda = 1): the f32 SFTF at
/// exactly `lambda = 1` is rescued about every 4,000-8,000 samples on data its order
/// describes (AR(1) at P = 2 and 4, AR(2) at P = 2), with or without the gate; at
/// `lambda = 0.999999` never, and the f64 filter never. The monitor's tolerance
/// `tau (|r_f| + sqrt((1 - lambda) beta))` loses its absolute floor at `lambda = 1`, so a near-zero
/// `r_f` trips it on rounding alone. Each rescue throws away the whole (unbounded) memory that
/// `lambda = 1` asks for. Docs (Sftf): "stable for lambda > 1 - 1/(2P) on data its order
/// describes"; README's table requires no restart on such rows (all at lambda < 1).
#[test]
#[ignore = "known: the f32 SFTF is rescued about 130 times per 10^6 samples at exactly lambda = 1 (f64 and lambda < 1: none)"]
fn sftf_f32_at_lambda_one_is_not_rescued_on_data_its_order_describes() {
    let n = 1_000_000;
    let x = ar([0.8], 1.0, n, 45);
    let c32 = Config::new(1.0f32, 0.01).unwrap();
    let c64 = Config::new(1.0f64, 0.01).unwrap();
    let near = Config::new(0.999_999f32, 0.01).unwrap();
    let mut a = Sftf::<f32, 2>::new(&c32, &Channel::new(0.1f32).unwrap());
    let mut b = Sftf::<f64, 2>::new(&c64, &Channel::new(0.1f64).unwrap());
    let mut c = Sftf::<f32, 2>::new(&near, &Channel::new(0.1f32).unwrap());
    let mut first = None;
    for (i, &v) in x.iter().enumerate() {
        a.update(&c32, v as f32);
        b.update(&c64, v);
        c.update(&near, v as f32);
        if first.is_none() && a.health().restarts > 0 {
            first = Some(i);
        }
    }
    println!(
        "restarts in 10^6 samples: f32 lambda 1: {} (first at {first:?}), f64 lambda 1: {}, \
         f32 lambda 0.999999: {}",
        a.health().restarts,
        b.health().restarts,
        c.health().restarts
    );
    assert_eq!(b.health().restarts, 0);
    assert_eq!(c.health().restarts, 0);
    assert_eq!(a.health().restarts, 0);
}

// ---------------------------------------------------------------------------------------
// More probes: counts path, geometries, die temperature, gate proptest
// ---------------------------------------------------------------------------------------

/// The fixed lattice's raw-count path behind the gate: random counts, rails, huge jumps,
/// stuck counts: never a panic (overflow checks on), never more than `run` in a row.
#[test]
fn fixed_counts_behind_the_gate() {
    let mut rng = ChaCha8Rng::seed_from_u64(61);
    for (k, run) in [(5.0f32, 4u32), (1.0, 1), (f32::MAX, 2), (3.0, u32::MAX)] {
        let config = Config::new(0.999f32, 0.01)
            .unwrap()
            .with_gate(Gate::new(k, run).unwrap());
        let fixed = FixedConfig::new(&config).unwrap();
        let channel =
            FixedChannel::for_counts(&Channel::new(0.01f32).unwrap(), 1.0 / 131.0).unwrap();
        let mut l = FixedLattice::<8>::new(&fixed, &channel);
        let mut p = FixedLattice::<8>::with_prior(&fixed, &channel, &[3.99; 8]).unwrap();
        let (mut cur, mut longest) = (0u32, 0u32);
        for i in 0..50_000u32 {
            let c = match i / 5000 % 5 {
                0 => (gauss(&mut rng) * 20.0) as i16,
                1 => rng.next_u32() as i16,
                2 => 12_345,
                3 => {
                    if i % 2 == 0 {
                        32_000
                    } else {
                        -32_000
                    }
                }
                _ => [i16::MIN, i16::MAX, -32767, 32766, 0][(i % 5) as usize],
            };
            let o = l.health().outliers;
            l.update_counts(&fixed, c);
            p.update_counts(&fixed, c);
            if l.health().outliers > o {
                cur += 1;
                longest = longest.max(cur);
            } else {
                cur = 0;
            }
        }
        println!(
            "k {k} run {run}: {:?}, longest {longest}; prior {:?}",
            l.health(),
            p.health()
        );
        assert!(longest <= run);
        let h = l.health();
        assert_eq!(h.samples + h.saturated + h.outliers, 50_000);
        if let Some(m) = l.model(&fixed) {
            assert!(m.a().iter().all(|a| a.is_finite()) && m.noise_variance().is_finite());
        }
    }
}

/// Other geometries, a cut at every byte of saves that append and that erase.
fn every_cut_geometry<const R: usize, const W: usize, const E: usize>(units: usize, saves: u32) {
    let mut flash = RamFlash::<R, W, E>::new(units);
    fsave(&mut flash, &store_model(0)).unwrap();
    for i in 1..saves {
        let (old, new) = (store_model(i - 1), store_model(i));
        let mut probe = flash.clone();
        let start = probe.ops;
        fsave(&mut probe, &new).unwrap();
        let total = probe.ops - start;
        for k in (0..total).step_by(1.max(total / 300)) {
            let mut f = flash.clone();
            f.cut_after(k);
            let _ = fsave(&mut f, &new);
            f.power_on();
            let got: ArModel<f32, 4> =
                fload(&mut f).unwrap_or_else(|e| panic!("{R} {W} {E}: save {i} cut {k}: {e:?}"));
            assert!(got == old || got == new, "save {i} cut {k}");
        }
        fsave(&mut flash, &new).unwrap();
        assert_eq!(fload::<R, W, E, ArModel<f32, 4>>(&mut flash), Ok(new));
    }
}

#[test]
fn flash_other_geometries_survive_cuts() {
    every_cut_geometry::<256, 256, 256>(2, 8);
    every_cut_geometry::<256, 256, 512>(2, 8);
    every_cut_geometry::<8, 64, 128>(5, 12);
    every_cut_geometry::<2, 2, 64>(2, 8);
}

/// The die temperature formulas: the FIFO form `64 t` gives `t / 2.07 + 25`; the register
/// forms at the i16 extremes are finite.
#[test]
fn die_temperature_formulas() {
    use imu_ar::sensor::Thermometer;
    for t in -127i16..=127 {
        let c = Thermometer::ICM42688.celsius(64 * t);
        let want = f64::from(t) / 2.07 + 25.0;
        assert!((f64::from(c) - want).abs() < 1e-4, "{t}: {c} {want}");
    }
    for raw in [i16::MIN, -1, 0, 1, i16::MAX] {
        let a = Thermometer::MPU6050.celsius(raw);
        let b = Thermometer::ICM42688.celsius(raw);
        assert!(a.is_finite() && b.is_finite());
        assert!((f64::from(a) - (f64::from(raw) / 340.0 + 36.53)).abs() < 1e-4);
        assert!((f64::from(b) - (f64::from(raw) / 132.48 + 25.0)).abs() < 1e-4);
    }
}

/// Thermal: a first sample outside the range sets the start `c = [x_1, 0..]` although
/// out-of-range samples are "not learned from" (documented: "the first accepted sample ...
/// sets its start"). Printed for the report.
#[test]
fn thermal_first_sample_out_of_range_sets_the_start() {
    let config = ThermalConfig::<f32, 4>::new(0.999, 20.0, 60.0).unwrap();
    let mut s = ThermalBias::new(&config);
    let r = s.update(&config, 100.0, -40.0);
    println!(
        "first sample at -40 C: residual {r:?}, c {:?}, {:?}",
        s.coefficients(),
        s.health()
    );
    let r = s.update(&config, 0.5, 30.0);
    println!("then 0.5 at 30 C: residual {r:?}");
    // Infinite and NaN temperatures: rejected, counted, nothing changes.
    let before = s;
    for t in [f32::NAN, f32::INFINITY, f32::NEG_INFINITY] {
        assert_eq!(s.update(&config, 1.0, t), None);
    }
    assert_eq!(s.coefficients(), before.coefficients());
    assert_eq!(s.health().non_finite, 3);
    // An extreme but finite range.
    let wide = ThermalConfig::<f32, 4>::new(0.999, -f32::MAX, f32::MAX).unwrap();
    let mut w = ThermalBias::new(&wide);
    for i in 0..1000 {
        let r = w
            .update(&wide, (i % 7) as f32, (i as f32 - 500.0) * 1e35)
            .unwrap();
        assert!(r.is_finite());
    }
}

mod gate_props {
    use super::*;
    use proptest::prelude::*;

    fn value() -> impl Strategy<Value = f32> {
        prop_oneof![
            8 => -3.0f32..3.0,
            1 => prop::num::f32::ANY,
            1 => prop::sample::select(vec![f32::NAN, f32::INFINITY, -f32::MAX, f32::MAX, 1e-45, 1e30, -1e19, 0.0, 100.0, -100.0]),
        ]
    }

    /// Runs one estimator over `x`; checks finite outputs, the run bound, the counts, and that
    /// every outlier rejection left the model, mean and variance as they were.
    fn check<E: Estimator<f32, P>, const P: usize>(
        mut e: E,
        config: &E::Config,
        x: &[f32],
        run: u32,
    ) -> Result<(), TestCaseError> {
        let (mut cur, mut longest) = (0u32, 0u32);
        for &v in x {
            let (o, m, mean, var) = (
                e.health().outliers,
                e.model(config),
                e.mean(),
                e.noise_variance(),
            );
            let out = e.update(config, v);
            if let Some(err) = out {
                prop_assert!(err.is_finite(), "error {} for {}", err, v);
            }
            if e.health().outliers > o {
                cur += 1;
                longest = longest.max(cur);
                prop_assert!(out.is_none());
                prop_assert_eq!(e.model(config), m);
                prop_assert_eq!(e.mean().to_bits(), mean.to_bits());
                prop_assert_eq!(e.noise_variance().map(f32::to_bits), var.map(f32::to_bits));
            } else if out.is_some() {
                cur = 0;
            }
            if let Some(m) = e.model(config) {
                prop_assert!(
                    m.a().iter().all(|a| a.is_finite())
                        && m.noise_variance().is_finite()
                        && m.mean().is_finite()
                );
            }
            prop_assert!(e.mean().is_finite());
        }
        prop_assert!(longest <= run, "longest {} > {}", longest, run);
        let h = e.health();
        prop_assert_eq!(
            h.samples + h.non_finite + h.saturated + h.outliers,
            x.len() as u64
        );
        Ok(())
    }

    proptest! {
        #![proptest_config(ProptestConfig::with_cases(
            std::env::var("REDTEAM_CASES").ok().and_then(|s| s.parse().ok()).unwrap_or(64)))]

        #[test]
        fn gate_invariants(
            x in prop::collection::vec(value(), 0..3000),
            k in prop_oneof![Just(5.0f32), 1.0f32..100.0, Just(f32::MAX), Just(1.0f32)],
            run in prop_oneof![Just(1u32), 1u32..20, Just(u32::MAX)],
            lambda in prop_oneof![Just(1.0f32), 0.95f32..1.0, Just(0.999)],
            demean in any::<bool>(),
            prior in prop::array::uniform4(-1.9f32..1.9),
            base in prop::sample::select(vec![1.0f32, 1e-6, 1e6]),
            saturation in prop::option::of(prop::sample::select(vec![2.0f32, 50.0, 1e30])),
        ) {
            let x: Vec<f32> = x.iter().map(|v| v * base).collect();
            let config = Config::new(lambda, 0.01).unwrap().with_demean(demean).with_gate(Gate::new(k, run).unwrap());
            let mut channel = Channel::new(0.01f32 * base * base).unwrap();
            if let Some(limit) = saturation {
                channel = channel.with_saturation(limit * base).unwrap();
            }
            check(Lattice::<f32, 4>::new(&config, &channel), &config, &x, run)?;
            check(Rls::<f32, 4>::new(&config, &channel), &config, &x, run)?;
            check(Sftf::<f32, 4>::new(&config, &channel), &config, &x, run)?;
            check(Lattice::<f32, 4>::with_prior(&config, &channel, &prior).unwrap(), &config, &x, run)?;
            check(Rls::<f32, 4>::with_prior(&config, &channel, &prior).unwrap(), &config, &x, run)?;
            check(Sftf::<f32, 4>::with_prior(&config, &channel, &prior).unwrap(), &config, &x, run)?;
            if lambda >= 0.9 {
                let fixed = FixedConfig::new(&config).unwrap();
                if let Ok(fc) = FixedChannel::new(&Channel::new(0.01f32).unwrap(), 1.0 / base) {
                    check(FixedLattice::<4>::new(&fixed, &fc), &fixed, &x, run)?;
                    check(FixedLattice::<4>::with_prior(&fixed, &fc, &prior).unwrap(), &fixed, &x, run)?;
                }
            }
        }
    }
}

/// A newest entry of another layout version (planted, CRC and sequence valid): documented as
/// not intact, so the previous entry is loaded; the next save goes on.
#[test]
fn flash_entry_of_another_version_is_not_intact() {
    let mut flash = RamFlash::<1, 4, 256>::new(2);
    fsave(&mut flash, &store_model(0)).unwrap();
    let mut e = vec![0u8; 44];
    store_model(1).encode(&mut e).unwrap();
    e[4] = 2;
    reseal(&mut e);
    e.extend(1u32.to_le_bytes());
    e.extend((!1u32).to_le_bytes());
    flash.bytes_mut()[52..104].copy_from_slice(&e);
    assert_eq!(
        fload::<1, 4, 256, ArModel<f32, 4>>(&mut flash),
        Ok(store_model(0))
    );
    fsave(&mut flash, &store_model(2)).unwrap();
    assert_eq!(
        fload::<1, 4, 256, ArModel<f32, 4>>(&mut flash),
        Ok(store_model(2))
    );
}
