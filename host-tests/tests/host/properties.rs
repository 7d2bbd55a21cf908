//! Properties of every estimator and batch fit on arbitrary input (proptest): finite input
//! gives finite output and consistent counters; a NaN or infinite sample is rejected, counted,
//! and changes nothing, whatever surrounds it.

use imu_ar::Scalar;
use imu_ar::batch::{BatchConfig, BatchError, burg, covariance, yule_walker};
use imu_ar::recursive::{Channel, Config, Estimator, FixedChannel, FixedConfig, FixedLattice};
use imu_ar::recursive::{FloatArith, Health, Lattice, Rls, Sftf};
use proptest::prelude::*;

/// Cases per property: 256, or `PROPTEST_CASES`.
fn cases() -> u32 {
    std::env::var("PROPTEST_CASES")
        .ok()
        .and_then(|s| s.parse().ok())
        .unwrap_or(256)
}

/// An estimator under test with its shared settings, and how to read the coefficients of its
/// current state (the lattices compute them, `Rls` and `Sftf` keep them).
struct Under<T: Scalar, E: Estimator<T, P>, const P: usize> {
    state: E,
    config: E::Config,
    coefficients: fn(&E) -> Option<[T; P]>,
}

/// What the properties read of an estimator, in `f64`, so that one list holds them all.
trait Probe {
    /// One sample; the prediction error.
    fn step(&mut self, x: f64) -> Option<f64>;
    fn health(&self) -> Health;
    /// Everything the estimator publishes: order-P coefficients, then the model's
    /// coefficients and noise variance (NaN marks "none").
    fn published(&self) -> Vec<f64>;
}

impl<T: Scalar, E: Estimator<T, P>, const P: usize> Probe for Under<T, E, P> {
    fn step(&mut self, x: f64) -> Option<f64> {
        let e = self.state.update(&self.config, T::from_f64(x));
        e.map(Scalar::to_f64)
    }
    fn health(&self) -> Health {
        self.state.health()
    }
    fn published(&self) -> Vec<f64> {
        let c = (self.coefficients)(&self.state);
        model_values(c, self.state.model(&self.config))
    }
}

/// Values that stress a float recursion: ordinary, zero, huge, tiny and subnormal.
fn value() -> impl Strategy<Value = f64> {
    prop_oneof![
        6 => -1e3..1e3f64,
        1 => Just(0.0),
        1 => prop_oneof![Just(1e30), Just(-1e30), Just(1e-30), Just(-1e-30)],
        // f32 subnormals (exact in f64 too), and f64 subnormals (0 in f32).
        1 => (1u32..1 << 23).prop_map(|b| f64::from(f32::from_bits(b))),
        1 => (1u64..1 << 52).prop_map(f64::from_bits),
    ]
}

/// Arbitrary, constant and alternating sequences of `value`s.
fn sequence() -> impl Strategy<Value = Vec<f64>> {
    prop_oneof![
        prop::collection::vec(value(), 0..300),
        (value(), 1..300usize).prop_map(|(v, n)| vec![v; n]),
        (value(), value(), 1..300usize)
            .prop_map(|(a, b, n)| (0..n).map(|i| if i % 2 == 0 { a } else { b }).collect()),
    ]
}

/// A non-finite sample.
fn bad() -> impl Strategy<Value = f64> {
    prop_oneof![Just(f64::NAN), Just(f64::INFINITY), Just(f64::NEG_INFINITY)]
}

fn config<T: FloatArith>(lambda: f64, demean: bool) -> Config<T> {
    Config::new(T::from_f64(lambda), T::from_f64(0.01))
        .unwrap()
        .with_demean(demean)
}

fn channel<T: FloatArith>() -> Channel<T> {
    Channel::new(T::from_f64(0.01)).unwrap()
}

fn model_values<T: Scalar, const P: usize>(
    coefficients: Option<[T; P]>,
    model: Option<imu_ar::ArModel<T, P>>,
) -> Vec<f64> {
    let mut v: Vec<f64> = coefficients.map_or(vec![f64::NAN; P], |a| {
        a.iter().map(|x| x.to_f64()).collect()
    });
    match model {
        Some(m) => {
            v.extend(m.a().iter().map(|x| x.to_f64()));
            v.push(m.noise_variance().to_f64());
        }
        None => v.extend(vec![f64::NAN; P + 1]),
    }
    v
}

/// A fresh float estimator at `lambda`, with or without mean removal, made by `make`.
fn float<T, E, const P: usize>(
    lambda: f64,
    demean: bool,
    make: fn(&Config<T>, &Channel<T>) -> E,
    coefficients: fn(&E) -> Option<[T; P]>,
) -> Box<dyn Probe>
where
    T: FloatArith + 'static,
    E: Estimator<T, P, Config = Config<T>> + 'static,
{
    let config = config::<T>(lambda, demean);
    let state = make(&config, &channel());
    Box::new(Under {
        state,
        config,
        coefficients,
    })
}

fn lattice<T: FloatArith + 'static, const P: usize>(lambda: f64, demean: bool) -> Box<dyn Probe> {
    float(lambda, demean, Lattice::<T, P>::new, |l| l.coefficients(P))
}

fn rls<T: FloatArith + 'static, const P: usize>(lambda: f64, demean: bool) -> Box<dyn Probe> {
    float(lambda, demean, Rls::<T, P>::new, |r| {
        Some(*r.coefficients())
    })
}

fn sftf<T: FloatArith + 'static, const P: usize>(lambda: f64, demean: bool) -> Box<dyn Probe> {
    float(lambda, demean, Sftf::<T, P>::new, |s| {
        Some(*s.coefficients())
    })
}

/// A fresh order-4 fixed-point lattice at `lambda = 0.99`, `scale = 1e-3`.
fn fixed(demean: bool) -> Box<dyn Probe> {
    let config = FixedConfig::new(&config::<f32>(0.99, demean)).unwrap();
    let channel = FixedChannel::new(&channel(), 1e-3).unwrap();
    let state = FixedLattice::<4>::new(&config, &channel);
    let coefficients = |l: &FixedLattice<4>| l.coefficients(4);
    Box::new(Under {
        state,
        config,
        coefficients,
    })
}

/// Every estimator under test, fresh: the lattice, RLS and SFTF in f32 and f64 at orders 1, 4
/// and 8, with and without mean removal, and the fixed-point lattice.
fn estimators() -> Vec<(&'static str, Box<dyn Probe>)> {
    vec![
        ("lattice f32 p=1", lattice::<f32, 1>(0.99, true)),
        ("lattice f32 p=4", lattice::<f32, 4>(0.99, true)),
        ("lattice f32 p=8 no demean", lattice::<f32, 8>(0.9, false)),
        ("lattice f64 p=4", lattice::<f64, 4>(0.999, true)),
        ("rls f32 p=1", rls::<f32, 1>(0.99, true)),
        ("rls f32 p=4", rls::<f32, 4>(0.99, true)),
        ("rls f64 p=8 no demean", rls::<f64, 8>(0.9, false)),
        ("sftf f32 p=1", sftf::<f32, 1>(0.99, true)),
        ("sftf f32 p=4", sftf::<f32, 4>(0.99, true)),
        // lambda below 1 - 1/(2p): the monitor's busiest case.
        ("sftf f64 p=8 no demean", sftf::<f64, 8>(0.9, false)),
        ("fixed lattice p=4", fixed(true)),
        ("fixed lattice p=4 no demean", fixed(false)),
    ]
}

fn all_finite(v: &[f64]) -> bool {
    v.iter().all(|x| x.is_nan() || x.is_finite())
}

proptest! {
    #![proptest_config(ProptestConfig::with_cases(cases()))]

    /// Finite input: every error and everything published is finite (NaN only marks "no
    /// model yet"), and each sample is either taken or rejected as saturated, never lost.
    #[test]
    fn finite_input_gives_finite_output(xs in sequence()) {
        for (name, mut e) in estimators() {
            for (n, &x) in xs.iter().enumerate() {
                if let Some(err) = e.step(x) {
                    prop_assert!(err.is_finite(), "{name}: error {err} at sample {n} of {xs:?}");
                }
                let published = e.published();
                prop_assert!(all_finite(&published), "{name}: {published:?} at {n}");
                let noise = published[published.len() - 1];
                prop_assert!(noise.is_nan() || noise >= 0.0, "{name}: noise variance {noise}");
            }
            let h = e.health();
            prop_assert_eq!(h.samples + h.saturated, xs.len() as u64, "{}: {:?}", name, h);
            prop_assert_eq!(h.non_finite, 0, "{}", name);
        }
    }

    /// NaN and infinite samples inserted anywhere are rejected and counted, and the run is
    /// otherwise bit-identical to the run without them.
    #[test]
    fn rejected_samples_change_nothing(
        xs in prop::collection::vec(-10.0..10.0f64, 1..200),
        inserts in prop::collection::vec((any::<prop::sample::Index>(), bad()), 1..20),
    ) {
        let mut with = xs.clone();
        for (at, v) in &inserts {
            with.insert(at.index(with.len() + 1), *v);
        }
        for ((name, mut clean), (_, mut dirty)) in estimators().into_iter().zip(estimators()) {
            let mut clean_out = Vec::new();
            for &x in &xs {
                clean_out.push((clean.step(x).map(f64::to_bits), clean.published()));
            }
            let mut dirty_out = Vec::new();
            for &x in &with {
                let before = dirty.published();
                let e = dirty.step(x);
                if x.is_finite() {
                    dirty_out.push((e.map(f64::to_bits), dirty.published()));
                } else {
                    prop_assert_eq!(e, None, "{}", name);
                    let after = dirty.published();
                    prop_assert!(same(&before, &after), "{name}: {before:?} -> {after:?}");
                }
            }
            prop_assert_eq!(clean_out.len(), dirty_out.len());
            for ((e1, p1), (e2, p2)) in clean_out.iter().zip(&dirty_out) {
                prop_assert_eq!(e1, e2, "{}", name);
                prop_assert!(same(p1, p2), "{name}: {p1:?} != {p2:?}");
            }
            let (h, hc) = (dirty.health(), clean.health());
            prop_assert_eq!(h.non_finite, inserts.len() as u64, "{}", name);
            prop_assert_eq!((h.samples, h.saturated, h.restarts), (hc.samples, hc.saturated, hc.restarts), "{}", name);
        }
    }

    /// With a saturation limit, samples at or beyond it are counted as saturated and change
    /// nothing; the rest run as without them.
    #[test]
    fn saturated_samples_are_counted_and_skipped(
        xs in prop::collection::vec(-1.0..1.0f64, 1..200),
        clipped in prop::collection::vec((any::<prop::sample::Index>(), prop_oneof![Just(2.0), Just(-2.0), 2.0..1e6f64]), 1..20),
    ) {
        let config = config::<f32>(0.99, true);
        let limit = channel::<f32>().with_saturation(2.0).unwrap();
        let mut with = xs.clone();
        for (at, v) in &clipped {
            with.insert(at.index(with.len() + 1), *v);
        }
        let mut clean = Lattice::<f32, 4>::new(&config, &limit);
        let mut dirty = Lattice::<f32, 4>::new(&config, &limit);
        let a: Vec<_> = xs.iter().map(|&x| clean.update(&config, x as f32).map(f32::to_bits)).collect();
        let b: Vec<_> = with.iter().filter_map(|&x| {
            let e = dirty.update(&config, x as f32);
            (x.abs() < 2.0).then_some(e.map(f32::to_bits))
        }).collect();
        prop_assert_eq!(a, b);
        prop_assert_eq!(dirty.health().saturated, clipped.len() as u64);
        prop_assert_eq!(dirty.coefficients(4), clean.coefficients(4));
    }

    /// The batch fits take any finite record: a model with finite coefficients and a
    /// non-negative finite noise variance, or a typed error; a non-finite sample is an error
    /// naming its index.
    #[test]
    fn batch_fits_are_finite_or_typed_errors(
        xs in sequence(),
        bad_at in any::<prop::sample::Index>(),
        bad in bad(),
    ) {
        let config = BatchConfig::new(0.01).unwrap();
        let check = |name: &str, fit: Result<imu_ar::batch::Fit<f64, 4>, BatchError>| -> Result<(), TestCaseError> {
            if let Ok(f) = fit {
                let m = f.model;
                prop_assert!(m.a().iter().all(|a| a.is_finite()), "{name}: {:?}", m.a());
                let s = m.noise_variance();
                prop_assert!(s.is_finite() && s >= 0.0, "{name}: noise variance {s}");
            }
            Ok(())
        };
        check("covariance", covariance::<f64, 4>(&xs, &config))?;
        check("burg", burg::<f64, 4>(&xs, &config))?;
        check("yule-walker", yule_walker::<f64, 4>(&xs, &config))?;
        let mut with = xs.clone();
        let at = bad_at.index(with.len() + 1);
        with.insert(at, bad);
        for fit in [covariance::<f64, 4>(&with, &config), burg::<f64, 4>(&with, &config), yule_walker::<f64, 4>(&with, &config)] {
            match fit {
                Err(BatchError::NonFinite { index }) => prop_assert_eq!(index, at),
                Err(BatchError::TooShort { .. }) => {}
                other => prop_assert!(false, "{:?}", other.map(|f| f.model)),
            }
        }
    }
}

/// Equal as published: the same bits, NaN for NaN.
fn same(a: &[f64], b: &[f64]) -> bool {
    a.len() == b.len()
        && a.iter()
            .zip(b)
            .all(|(x, y)| x.to_bits() == y.to_bits() || (x.is_nan() && y.is_nan()))
}
