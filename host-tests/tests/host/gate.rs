//! The innovation gate: shocks rejected and counted, a genuine level step taken within the
//! stated bound (at most `run` consecutive rejections), for every estimator.

use imu_ar::recursive::{
    Channel, Config, Estimator, FixedChannel, FixedConfig, FixedLattice, Gate, Lattice, Rls, Sftf,
};
use imu_ar_host::fixtures::{add, ar};
use rand_chacha::ChaCha8Rng;
use rand_core::{RngCore, SeedableRng};

const N: usize = 200_000;
const RUN: u32 = 8;

/// An AR(1) (a = 0.95, sigma 1) plus white noise (sigma 0.5): an ARMA(1,1) that AR(4)
/// approximates closely.
fn clean() -> Vec<f64> {
    add(&ar([0.95], 1.0, N, 31), &ar([0.0], 0.5, N, 32))
}

/// The innovation variance after `x` of each estimator (order 4, `lambda = 0.999`), with or
/// without the gate, and the outliers they counted.
fn variances(x: &[f64], gate: bool) -> [(f64, u64); 4] {
    let mut config = Config::new(0.999f32, 0.01).unwrap();
    if gate {
        config = config.with_gate(Gate::new(5.0, RUN).unwrap());
    }
    let channel = Channel::new(0.1f32).unwrap();
    let fixed = FixedConfig::new(&config).unwrap();
    let fixed_channel = FixedChannel::new(&channel, 0.25).unwrap();
    let mut lattice = Lattice::<f32, 4>::new(&config, &channel);
    let mut rls = Rls::<f32, 4>::new(&config, &channel);
    let mut sftf = Sftf::<f32, 4>::new(&config, &channel);
    let mut fixed_lattice = FixedLattice::<4>::new(&fixed, &fixed_channel);
    for &v in x {
        let v = v as f32;
        lattice.update(&config, v);
        rls.update(&config, v);
        sftf.update(&config, v);
        fixed_lattice.update(&fixed, v);
    }
    let out = |v: Option<f32>, h: imu_ar::recursive::Health| {
        assert_eq!(h.restarts, 0, "{h:?}");
        (f64::from(v.unwrap()), h.outliers)
    };
    [
        out(lattice.noise_variance(), lattice.health()),
        out(rls.noise_variance(), rls.health()),
        out(sftf.noise_variance(), sftf.health()),
        out(fixed_lattice.noise_variance(), fixed_lattice.health()),
    ]
}

/// 1 % of the samples carry a shock of 20 innovation standard deviations: gated, the
/// innovation variance is within 5 % of the clean record's (ungated it is many times it).
#[test]
fn shocks_are_rejected_and_the_variance_stays_that_of_the_clean_record() {
    let x = clean();
    let clean_var = variances(&x, false);
    let sigma = clean_var[0].0.sqrt();
    let mut rng = ChaCha8Rng::seed_from_u64(33);
    let mut shocked = x.clone();
    let mut shocks = 0u64;
    for v in &mut shocked {
        if rng.next_u32() % 100 == 0 {
            *v += if rng.next_u32() % 2 == 0 { 20.0 } else { -20.0 } * sigma;
            shocks += 1;
        }
    }
    let ungated = variances(&shocked, false);
    let gated = variances(&shocked, true);
    for (k, name) in ["lattice", "RLS", "SFTF", "fixed lattice"]
        .iter()
        .enumerate()
    {
        let (c, (u, _), (g, outliers)) = (clean_var[k].0, ungated[k], gated[k]);
        println!(
            "{name}: clean {c:.4}, shocked ungated {u:.4} ({:.1}x), gated {g:.4} ({:+.2} %), \
             outliers {outliers} of {shocks} shocks",
            u / c,
            100.0 * (g / c - 1.0)
        );
        assert!(
            (g / c - 1.0).abs() < 0.05,
            "{name}: gated {g} against clean {c}"
        );
        assert!(u / c > 2.0, "{name}: the shocks should matter ungated");
        assert!(
            outliers >= shocks * 9 / 10,
            "{name}: {outliers} of {shocks}"
        );
    }
}

/// A genuine step of 10 standard deviations in the mean: no run of rejections is longer than
/// the bound `RUN`, and the estimator follows the new level.
#[test]
fn a_genuine_step_is_taken_within_the_bound() {
    let mut x = clean();
    let sigma = {
        let m = x.iter().sum::<f64>() / N as f64;
        (x.iter().map(|v| (v - m).powi(2)).sum::<f64>() / N as f64).sqrt()
    };
    let step_at = N / 2;
    for v in &mut x[step_at..] {
        *v += 10.0 * sigma;
    }
    let config = Config::new(0.999f32, 0.01)
        .unwrap()
        .with_gate(Gate::new(5.0, RUN).unwrap());
    let channel = Channel::new(0.1f32).unwrap();
    let fixed = FixedConfig::new(&config).unwrap();
    let fixed_channel = FixedChannel::new(&channel, 0.25).unwrap();
    let mut lattice = Lattice::<f32, 4>::new(&config, &channel);
    let mut rls = Rls::<f32, 4>::new(&config, &channel);
    let mut sftf = Sftf::<f32, 4>::new(&config, &channel);
    let mut fixed_lattice = FixedLattice::<4>::new(&fixed, &fixed_channel);
    let mut runs = [0u32; 4];
    let mut longest = [0u32; 4];
    let mut first_taken = [None::<usize>; 4];
    for (n, &v) in x.iter().enumerate() {
        let v = v as f32;
        let taken = [
            lattice.update(&config, v).is_some(),
            rls.update(&config, v).is_some(),
            sftf.update(&config, v).is_some(),
            fixed_lattice.update(&fixed, v).is_some(),
        ];
        for k in 0..4 {
            runs[k] = if taken[k] { 0 } else { runs[k] + 1 };
            longest[k] = longest[k].max(runs[k]);
            if n >= step_at && taken[k] && first_taken[k].is_none() {
                first_taken[k] = Some(n - step_at);
            }
        }
    }
    // The level the gated estimators should follow: the data's own weighted mean at the end.
    let level = x.iter().fold((0.0f64, 0.0f64), |(m, w), &v| {
        let w = 0.999 * w + 1.0;
        (m + (v - m) / w, w)
    });
    let means = [
        lattice.mean(),
        rls.mean(),
        sftf.mean(),
        fixed_lattice.mean(),
    ];
    for (k, name) in ["lattice", "RLS", "SFTF", "fixed lattice"]
        .iter()
        .enumerate()
    {
        println!(
            "{name}: longest run of rejections {}, first sample taken {:?} after the step, \
             mean at the end {:.3} (the data's {:.3}, the step {:.3})",
            longest[k],
            first_taken[k],
            means[k],
            level.0,
            10.0 * sigma
        );
        assert!(
            longest[k] <= RUN,
            "{name}: {} rejections in a row",
            longest[k]
        );
        assert!(first_taken[k].is_some_and(|n| n <= RUN as usize), "{name}");
        assert!(
            (f64::from(means[k]) - level.0).abs() < 0.05 * sigma,
            "{name}"
        );
    }
}
