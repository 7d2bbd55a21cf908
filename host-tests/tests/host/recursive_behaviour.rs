//! Behaviour of the recursive estimators around the numbers: bad samples, stuck sensors,
//! restarts, order selection.

use imu_ar::ArModel;
use imu_ar::Scalar;
use imu_ar::recursive::{
    Channel, Config, ConfigError, Estimator, FixedChannel, FixedConfig, FixedLattice, Lattice,
    OrderRule, OrderSelector, Rls, Sftf, snapshot_interval,
};
use imu_ar::sim::ArSimulator;
use imu_ar_host::reference::{Regularisation, Section0, running_mean_removed};
use rand_chacha::ChaCha8Rng;
use rand_core::SeedableRng;

fn ar2(n: usize, seed: u64) -> Vec<f32> {
    let model = ArModel::new([1.2f32, -0.5], 1.0, 3.0, 0.01).unwrap();
    let mut sim = ArSimulator::new(model);
    let mut rng = ChaCha8Rng::seed_from_u64(seed);
    sim.burn_in(&mut rng, 1000);
    (0..n).map(|_| sim.next(&mut rng)).collect()
}

#[test]
fn config_rejects_out_of_range_parameters() {
    assert_eq!(Config::new(0.0f32, 0.01), Err(ConfigError::Lambda));
    assert_eq!(Config::new(1.0001f32, 0.01), Err(ConfigError::Lambda));
    assert_eq!(Config::new(f32::NAN, 0.01), Err(ConfigError::Lambda));
    assert_eq!(Channel::new(0.0f32), Err(ConfigError::Delta));
    assert_eq!(Channel::new(f32::INFINITY), Err(ConfigError::Delta));
    assert_eq!(Config::new(0.99f32, -0.01), Err(ConfigError::Interval));
    let c = Config::new(1.0f32, 0.01).unwrap();
    let channel = Channel::new(1.0f32).unwrap();
    assert_eq!(c.effective_samples(), None);
    assert_eq!(channel.with_saturation(0.0), Err(ConfigError::Saturation));
    assert_eq!(
        channel.with_saturation(f32::NAN),
        Err(ConfigError::Saturation)
    );
}

#[test]
fn rejected_samples_change_nothing_and_are_counted() {
    let config = Config::new(0.99f32, 0.01).unwrap();
    let channel = Channel::new(0.1).unwrap().with_saturation(100.0).unwrap();
    let x = ar2(5_000, 1);
    let mut lattice = Lattice::<f32, 4>::new(&config, &channel);
    let mut rls = Rls::<f32, 4>::new(&config, &channel);
    for &v in &x {
        lattice.update(&config, v);
        rls.update(&config, v);
    }
    let (lattice_before, rls_before) = (lattice.model(&config), rls.model(&config));
    for bad in [
        f32::NAN,
        f32::INFINITY,
        f32::NEG_INFINITY,
        100.0,
        -250.0,
        1e30,
    ] {
        assert_eq!(lattice.update(&config, bad), None, "lattice took {bad}");
        assert_eq!(rls.update(&config, bad), None, "RLS took {bad}");
    }
    assert_eq!(lattice.model(&config), lattice_before);
    assert_eq!(rls.model(&config), rls_before);
    for h in [lattice.health(), rls.health()] {
        assert_eq!(
            (h.samples, h.non_finite, h.saturated, h.restarts),
            (5_000, 3, 3, 0)
        );
        assert_eq!(h.rejected(), 6);
    }
}

#[test]
fn stuck_sensor_then_normal_data() {
    // 10^6 identical samples, then the AR(2) again, at lambda 0.99 and 0.999: every output
    // stays finite, nothing restarts, and 5/(1 - lambda) samples later the f32 estimators
    // equal the f64 direct solve of everything they took (stuck run included) to 1e-4, and
    // the direct solve of the normal data alone to 1e-2: the stuck run is forgotten.
    // The same holds for the SFTF, whose energies decay to their floor in the stuck run.
    for lambda in [0.99, 0.999] {
        let config = Config::new(lambda as f32, 0.01).unwrap();
        let channel = Channel::new(0.1).unwrap();
        let mut lattice = Lattice::<f32, 2>::new(&config, &channel);
        let mut rls = Rls::<f32, 2>::new(&config, &channel);
        let mut sftf = Sftf::<f32, 2>::new(&config, &channel);
        let mut everything = Vec::new();
        for _ in 0..1_000_000 {
            assert!(lattice.update(&config, 3.25).unwrap().is_finite());
            assert!(rls.update(&config, 3.25).unwrap().is_finite());
            assert!(sftf.update(&config, 3.25).unwrap().is_finite());
            everything.push(3.25);
        }
        let m = lattice.model(&config).unwrap();
        assert!(m.a().iter().all(|a| a.is_finite()) && m.noise_variance().is_finite());
        let normal: Vec<f64> = ar2((5.0 / (1.0 - lambda)) as usize, 2)
            .into_iter()
            .map(f64::from)
            .collect();
        for &v in &normal {
            assert!(lattice.update(&config, v as f32).unwrap().is_finite());
            assert!(rls.update(&config, v as f32).unwrap().is_finite());
            assert!(sftf.update(&config, v as f32).unwrap().is_finite());
            everything.push(v);
        }
        let solve = |x: &[f64]| {
            let mut s = Section0::new(2, lambda, 0.1);
            for y in running_mean_removed(x, lambda) {
                s.push(y);
            }
            s.solve(2, Regularisation::ShiftConsistent).0
        };
        let (all, fresh) = (solve(&everything), solve(&normal));
        for (name, a) in [
            ("lattice", lattice.coefficients(2).unwrap()),
            ("RLS", *rls.coefficients()),
            ("SFTF", *sftf.coefficients()),
        ] {
            for k in 0..2 {
                let a = f64::from(a[k]);
                assert!(
                    (a - all[k]).abs() <= 1e-4,
                    "{name} {lambda}: {a} vs {all:?}"
                );
                assert!(
                    (a - fresh[k]).abs() <= 1e-2,
                    "{name} {lambda}: {a} vs {fresh:?}"
                );
            }
        }
        assert_eq!(
            lattice.health().restarts + rls.health().restarts + sftf.health().restarts,
            0
        );
    }
}

#[test]
fn saturated_sensor_is_detected_and_counted() {
    // An AR(2) of mean 3 and standard deviation about 2.3 read by a sensor with a full scale
    // of +-4, and a limit set 0.1 % inside it: every clipped sample (and every one within
    // 0.1 % of the rail) is counted as saturated and skipped, and the model is the one of the
    // samples inside the limit.
    let full_scale = 4.0f32;
    let limit = full_scale * 0.999;
    let config = Config::new(0.99f32, 0.01).unwrap();
    let channel = Channel::new(0.1).unwrap().with_saturation(limit).unwrap();
    let x = ar2(20_000, 5);
    let mut sensor = Lattice::<f32, 2>::new(&config, &channel);
    let mut inside = Lattice::<f32, 2>::new(&config, &channel);
    let (mut clipped, mut at_rail) = (0, 0);
    for &v in &x {
        let read = v.clamp(-full_scale, full_scale);
        clipped += u64::from(read.abs() == full_scale);
        let e = sensor.update(&config, read);
        if read.abs() >= limit {
            at_rail += 1;
            assert_eq!(e, None);
        } else {
            assert_eq!(e, inside.update(&config, read));
        }
    }
    assert!(clipped > 1000, "{clipped} clipped samples");
    assert!(at_rail >= clipped);
    assert_eq!(sensor.health().saturated, at_rail);
    assert_eq!(sensor.coefficients(2), inside.coefficients(2));
}

#[test]
fn huge_input_restarts_and_keeps_publishing_the_last_good_model() {
    // A value whose square overflows f32 breaks the recursion down: the lattice restarts,
    // counts it, and hands out the model of its last snapshot (taken every
    // `snapshot_interval(P)` accepted samples) for 3/(1 - lambda) samples.
    let config = Config::new(0.99f32, 0.01).unwrap();
    let channel = Channel::new(0.1).unwrap();
    let mut lattice = Lattice::<f32, 2>::new(&config, &channel);
    let x = ar2(3_000, 3);
    let mut good = None;
    for &v in &x {
        lattice.update(&config, v);
        if lattice
            .health()
            .samples
            .is_multiple_of(snapshot_interval(2))
        {
            good = lattice.model(&config);
        }
    }
    let good = good.unwrap();
    assert_ne!(
        lattice.model(&config),
        Some(good),
        "the snapshot is not the newest model"
    );
    assert_eq!(lattice.update(&config, 3e30), None);
    assert_eq!(lattice.health().restarts, 1);
    for &v in &x[..299] {
        lattice.update(&config, v);
        assert_eq!(
            lattice.model(&config),
            Some(good),
            "published model changed while held"
        );
    }
    for &v in &x[..2] {
        lattice.update(&config, v);
    }
    assert_ne!(
        lattice.model(&config),
        Some(good),
        "the restarted lattice publishes again"
    );
}

#[test]
fn order_selection_finds_the_true_order_without_flapping() {
    let config = Config::new(0.999f32, 0.01).unwrap();
    let channel = Channel::new(0.1).unwrap();
    let x = ar2(40_000, 4);
    for rule in [OrderRule::Pls, OrderRule::Aic, OrderRule::Bic] {
        let mut lattice = Lattice::<f32, 6>::new(&config, &channel);
        let mut selector = OrderSelector::<f32, 6>::new(rule, 500, 3);
        let mut changes = 0;
        let mut last = selector.order();
        for &v in &x {
            if lattice.update(&config, v).is_some() {
                let order = selector.update(&config, &lattice);
                changes += usize::from(order != last);
                last = order;
            }
        }
        println!("{rule:?}: order {}, {changes} changes", selector.order());
        match rule {
            // BIC's penalty is the strongest: it must land on the true order.
            OrderRule::Bic => assert_eq!(selector.order(), 2, "{rule:?}"),
            // AIC and PLS may keep an extra lag or two, never fewer than the true order.
            _ => assert!(
                (2..=4).contains(&selector.order()),
                "{rule:?}: {}",
                selector.order()
            ),
        }
        assert!(changes <= 3, "{rule:?} changed order {changes} times");
    }
}

/// Runs two estimators from `make` over `x`, one asked for its model after every sample and
/// one never, and returns the model each publishes at the end, with the restarts of one run
/// (the same in both: the model is a pure getter).
fn after_asking_and_not<T: Scalar, E: Estimator<T, P>, const P: usize>(
    make: impl Fn() -> E,
    config: &E::Config,
    x: &[T],
) -> (Option<ArModel<T, P>>, Option<ArModel<T, P>>, u64) {
    let (mut asked, mut never) = (make(), make());
    for &v in x {
        asked.update(config, v);
        let _ = asked.model(config);
        never.update(config, v);
    }
    assert_eq!(asked.health(), never.health());
    let restarts = never.health().restarts;
    (asked.model(config), never.model(config), restarts)
}

/// The held model is a good one: the truth is `a = [1.2, -0.5]`.
fn is_near_the_truth(m: Option<ArModel<f32, 2>>) -> bool {
    m.is_some_and(|m| (m.a()[0] - 1.2).abs() < 0.1 && (m.a()[1] + 0.5).abs() < 0.1)
}

/// The model held through a restart is the estimator's own snapshot: the same whether `model`
/// was called after every sample or never (issue 23, item 2).
#[test]
fn the_held_model_does_not_depend_on_calls_to_model() {
    let config = Config::new(0.99f32, 0.01).unwrap();
    let channel = Channel::new(0.1).unwrap();
    let x: Vec<f32> = {
        let x = ar2(3_000, 3);
        x.iter()
            .chain(&[3e30f32])
            .chain(&x[..100])
            .copied()
            .collect()
    };
    let runs = [
        after_asking_and_not(|| Lattice::<f32, 2>::new(&config, &channel), &config, &x),
        after_asking_and_not(|| Rls::<f32, 2>::new(&config, &channel), &config, &x),
        after_asking_and_not(|| Sftf::<f32, 2>::new(&config, &channel), &config, &x),
    ];
    for (asked, never, restarts) in runs {
        assert_eq!(restarts, 1);
        assert!(never.is_some());
        assert_eq!(asked, never);
        assert!(is_near_the_truth(never), "{never:?}");
    }
}

/// The same for the fixed-point lattice, whose restart comes from a saturated state: samples
/// alternating at +-15.9 internal units drive its errors past the +-16 of their format.
#[test]
fn the_fixed_lattice_held_model_does_not_depend_on_calls_to_model() {
    let config = FixedConfig::new(&Config::new(0.99f32, 0.01).unwrap()).unwrap();
    let channel = FixedChannel::new(&Channel::new(0.1).unwrap(), 1.0).unwrap();
    let x: Vec<f32> = {
        let x = ar2(3_000, 3);
        let spikes = (0..20).map(|n| if n % 2 == 0 { 15.9 } else { -15.9 });
        x.iter()
            .copied()
            .chain(spikes)
            .chain(x[..100].iter().copied())
            .collect()
    };
    let make = || FixedLattice::<2>::new(&config, &channel);
    let (asked, never, restarts) = after_asking_and_not(make, &config, &x);
    assert!(restarts >= 1, "premise: the spikes restart the lattice");
    // The model from just before the saturating sample (the spikes before it included).
    assert!(never.is_some());
    assert_eq!(asked, never);
}

/// At `lambda = 1` the memory, and `3/(1 - lambda)`, are infinite: the hold after a restart is
/// bounded at 30 000 samples, after which the lattice publishes its own model again (issue 23,
/// item 2).
#[test]
fn at_lambda_one_the_hold_after_a_restart_ends() {
    let config = Config::new(1.0f32, 0.01).unwrap();
    let channel = Channel::new(0.1).unwrap();
    let x = ar2(40_000, 8);
    let mut lattice = Lattice::<f32, 2>::new(&config, &channel);
    for &v in &x[..5_000] {
        lattice.update(&config, v);
    }
    assert_eq!(lattice.update(&config, 3e30), None);
    let held = lattice
        .model(&config)
        .expect("the model held through the restart");
    for &v in &x[5_000..34_999] {
        lattice.update(&config, v);
        assert_eq!(lattice.model(&config), Some(held), "the held model changed");
    }
    lattice.update(&config, x[34_999]);
    let own = lattice.model(&config).expect("a model");
    assert_ne!(
        own, held,
        "the lattice publishes its own model after the hold"
    );
    assert!((own.a()[0] - 1.2).abs() < 0.05 && (own.a()[1] + 0.5).abs() < 0.05);
    assert_eq!(lattice.health().restarts, 1);
}

/// AIC and BIC at `lambda = 1` (growing memory) score with the number of samples, and find the
/// true order like PLS does (issue 23, item 1: they picked order 0, every score infinite); an
/// f32 lambda that rounds to 1 is the same case.
#[test]
fn order_selection_at_lambda_one() {
    let x: Vec<f64> = ar2(50_000, 12).iter().map(|&v| f64::from(v)).collect();
    let config = Config::new(1.0f64, 0.01).unwrap();
    let channel = Channel::new(0.1).unwrap();
    let config32 = Config::new(0.999_999_99f32, 0.01).unwrap();
    let config32_channel = Channel::new(0.1).unwrap();
    assert_eq!(config32.lambda(), 1.0);
    for rule in [OrderRule::Pls, OrderRule::Aic, OrderRule::Bic] {
        let mut lattice = Lattice::<f64, 4>::new(&config, &channel);
        let mut selector = OrderSelector::<f64, 4>::new(rule, 100, 3);
        let mut lattice32 = Lattice::<f32, 4>::new(&config32, &config32_channel);
        let mut selector32 = OrderSelector::<f32, 4>::new(rule, 100, 3);
        for &v in &x {
            if lattice.update(&config, v).is_some() {
                selector.update(&config, &lattice);
            }
            if lattice32.update(&config32, v as f32).is_some() {
                selector32.update(&config32, &lattice32);
            }
        }
        println!(
            "{rule:?}: f64 order {}, f32 order {}",
            selector.order(),
            selector32.order()
        );
        assert_eq!(selector.order(), 2, "{rule:?}, f64");
        assert_eq!(selector32.order(), 2, "{rule:?}, f32");
    }
}

/// A `delta` the scalar cannot carry through the recursion is refused (issue 23, item 8: a
/// subnormal one was accepted, and then every estimator restarted on almost every sample);
/// the smallest accepted one fits without a restart.
#[test]
fn config_rejects_a_delta_the_scalar_cannot_carry() {
    assert_eq!(Channel::new(1e-40f32), Err(ConfigError::Delta));
    assert_eq!(Channel::new(1e-35f32), Err(ConfigError::Delta));
    assert_eq!(Channel::new(1e35f32), Err(ConfigError::Delta));
    assert_eq!(Channel::new(1e-310f64), Err(ConfigError::Delta));
    assert_eq!(Channel::new(1e300f64), Err(ConfigError::Delta));
    let x = ar2(2_000, 5);
    for delta in [1e-31f32, 1e31] {
        let config = Config::new(0.999f32, 0.01).unwrap();
        let channel = Channel::new(delta).unwrap();
        let mut lattice = Lattice::<f32, 2>::new(&config, &channel);
        let mut rls = Rls::<f32, 2>::new(&config, &channel);
        let mut sftf = Sftf::<f32, 2>::new(&config, &channel);
        for &v in &x {
            lattice.update(&config, v);
            rls.update(&config, v);
            sftf.update(&config, v);
        }
        let restarts = [lattice.health(), rls.health(), sftf.health()].map(|h| h.restarts);
        assert_eq!(restarts, [0, 0, 0], "delta {delta:e}");
        assert!(lattice.model(&config).is_some() && rls.model(&config).is_some());
    }
}
