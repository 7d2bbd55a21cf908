//! Behaviour of the recursive estimators around the numbers: bad samples, stuck sensors,
//! restarts, order selection.

use imu_ar::ArModel;
use imu_ar::recursive::{Config, ConfigError, Lattice, OrderRule, OrderSelector, Rls, RlsInit};
use imu_ar::sim::ArSimulator;
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
    assert_eq!(Config::new(0.0f32, 1.0, 0.01), Err(ConfigError::Lambda));
    assert_eq!(Config::new(1.0001f32, 1.0, 0.01), Err(ConfigError::Lambda));
    assert_eq!(Config::new(f32::NAN, 1.0, 0.01), Err(ConfigError::Lambda));
    assert_eq!(Config::new(0.99f32, 0.0, 0.01), Err(ConfigError::Delta));
    assert_eq!(
        Config::new(0.99f32, f32::INFINITY, 0.01),
        Err(ConfigError::Delta)
    );
    assert_eq!(Config::new(0.99f32, 1.0, -0.01), Err(ConfigError::Interval));
    let c = Config::new(1.0f32, 1.0, 0.01).unwrap();
    assert_eq!(c.effective_samples(), None);
    assert_eq!(c.with_saturation(0.0), Err(ConfigError::Saturation));
    assert_eq!(c.with_saturation(f32::NAN), Err(ConfigError::Saturation));
}

#[test]
fn rejected_samples_change_nothing_and_are_counted() {
    let config = Config::new(0.99f32, 0.1, 0.01)
        .unwrap()
        .with_saturation(100.0)
        .unwrap();
    let x = ar2(5_000, 1);
    let mut lattice = Lattice::<f32, 4>::new(&config);
    let mut rls = Rls::<f32, 4>::new(&config, RlsInit::ShiftConsistent);
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
    // 100,000 identical samples, then the AR(2) again: every output stays finite, nothing
    // restarts, and the model recovers within a few memory lengths.
    let config = Config::new(0.99f32, 0.1, 0.01).unwrap();
    let mut lattice = Lattice::<f32, 2>::new(&config);
    let mut rls = Rls::<f32, 2>::new(&config, RlsInit::ShiftConsistent);
    for _ in 0..100_000 {
        let e = lattice.update(&config, 3.25).unwrap();
        assert!(e.is_finite());
        assert!(rls.update(&config, 3.25).unwrap().is_finite());
    }
    let m = lattice.model(&config).unwrap();
    assert!(m.a().iter().all(|a| a.is_finite()) && m.noise_variance().is_finite());
    for &v in &ar2(2_000, 2) {
        assert!(lattice.update(&config, v).unwrap().is_finite());
        assert!(rls.update(&config, v).unwrap().is_finite());
    }
    let a = *lattice.model(&config).unwrap().a();
    assert!(
        (a[0] - 1.2).abs() < 0.1 && (a[1] + 0.5).abs() < 0.1,
        "lattice a = {a:?}"
    );
    let a = *rls.model(&config).unwrap().a();
    assert!(
        (a[0] - 1.2).abs() < 0.1 && (a[1] + 0.5).abs() < 0.1,
        "RLS a = {a:?}"
    );
    assert_eq!(lattice.health().restarts + rls.health().restarts, 0);
}

#[test]
fn huge_input_restarts_and_keeps_publishing_the_last_good_model() {
    // A value whose square overflows f32 breaks the recursion down: the lattice restarts,
    // counts it, and hands out the model it had before for 3/(1 - lambda) samples.
    let config = Config::new(0.99f32, 0.1, 0.01).unwrap();
    let mut lattice = Lattice::<f32, 2>::new(&config);
    let x = ar2(3_000, 3);
    for &v in &x {
        lattice.update(&config, v);
    }
    let good = lattice.model(&config).unwrap();
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
    let config = Config::new(0.999f32, 0.1, 0.01).unwrap();
    let x = ar2(40_000, 4);
    for rule in [OrderRule::Pls, OrderRule::Aic, OrderRule::Bic] {
        let mut lattice = Lattice::<f32, 6>::new(&config);
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
