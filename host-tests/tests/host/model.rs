//! The AR model's hand-over forms against simulation and closed forms.

use imu_ar::sim::ArSimulator;
use imu_ar::{ArModel, GaussMarkov, ModelError};
use rand_chacha::ChaCha8Rng;
use rand_core::SeedableRng;

#[test]
fn q_m_matches_the_sample_covariance_of_a_long_simulation() {
    // AR(2), filter step M = 10 samples: s_{k+M} - Phi^M s_k over K disjoint windows.
    const M: usize = 10;
    let model = ArModel::new([1.5f64, -0.7], 0.5, 0.0, 0.01).unwrap();
    let (phi_m, q_m) = model.discretize(M as u32);
    let mut sim = ArSimulator::new(model);
    let mut rng = ChaCha8Rng::seed_from_u64(5);
    sim.burn_in(&mut rng, 1_000);
    let x: Vec<f64> = (0..2_000_000).map(|_| sim.next(&mut rng)).collect();
    let mut acc = [[0.0f64; 2]; 2];
    let mut k = 0usize;
    let mut t = 1;
    while t + M < x.len() {
        let s0 = [x[t], x[t - 1]];
        let s1 = [x[t + M], x[t + M - 1]];
        let d: [f64; 2] =
            core::array::from_fn(|i| s1[i] - phi_m[i][0] * s0[0] - phi_m[i][1] * s0[1]);
        for i in 0..2 {
            for j in 0..2 {
                acc[i][j] += d[i] * d[j];
            }
        }
        k += 1;
        t += M + 1;
    }
    for i in 0..2 {
        for j in 0..2 {
            let sample = acc[i][j] / k as f64;
            // Standard error of a Gaussian sample covariance from k independent draws.
            let se = ((q_m[i][i] * q_m[j][j] + q_m[i][j] * q_m[i][j]) / k as f64).sqrt();
            assert!(
                (sample - q_m[i][j]).abs() < 5.0 * se,
                "Q_M[{i}][{j}] = {}, sample {sample}, 5 se = {}",
                q_m[i][j],
                5.0 * se
            );
        }
    }
    // M = 1 is (Phi, Q) itself.
    let (phi1, q1) = model.discretize(1);
    assert_eq!(phi1, model.transition());
    assert_eq!(q1, model.process_noise());
}

#[test]
fn simulated_autocovariances_match_the_model() {
    let model = ArModel::new([1.2f64, -0.5, 0.1, 0.05], 1.0, 3.0, 0.01).unwrap();
    let mut sim = ArSimulator::new(model);
    let mut rng = ChaCha8Rng::seed_from_u64(8);
    sim.burn_in(&mut rng, 1_000);
    let n = 1_000_000;
    let x: Vec<f64> = (0..n).map(|_| sim.next(&mut rng)).collect();
    let mean = x.iter().sum::<f64>() / n as f64;
    assert!((mean - 3.0).abs() < 0.02, "mean {mean}");
    for (lag, r) in model.autocovariances().unwrap().take(8).enumerate() {
        let sample: f64 = x
            .iter()
            .zip(&x[lag..])
            .map(|(a, b)| (a - mean) * (b - mean))
            .sum::<f64>()
            / n as f64;
        assert!(
            (sample - r).abs() < 0.03 * model.autocovariances().unwrap().next().unwrap(),
            "r({lag}) = {r}, sample {sample}"
        );
    }
}

#[test]
fn gauss_markov_round_trips() {
    let gm = GaussMarkov::new(100.0f64, 0.01).unwrap();
    let ar1 = gm.to_ar1(0.01, 0.2).unwrap();
    assert!((ar1.a()[0] - (-1e-4f64).exp()).abs() < 1e-15);
    let back = ar1.to_gauss_markov().unwrap();
    assert!((back.correlation_time() - 100.0).abs() < 1e-9 * 100.0);
    assert!((back.sigma() - 0.01).abs() < 1e-12);
    assert!((gm.driving_psd() - 2.0 * 1e-4 / 100.0).abs() < 1e-18);
    // The model's stationary variance is the Gauss-Markov sigma^2.
    let r0 = ar1.autocovariances().unwrap().next().unwrap();
    assert!((r0 - 1e-4).abs() < 1e-15);
    // AR(1) -> GM -> AR(1).
    let m = ArModel::new([0.95f32], 0.04, 0.0, 0.01).unwrap();
    let again = m.to_gauss_markov().unwrap().to_ar1(0.01, 0.0).unwrap();
    assert!((again.a()[0] - 0.95).abs() < 1e-6);
    assert!((again.noise_variance() - 0.04).abs() < 1e-7);
    assert_eq!(
        GaussMarkov::new(0.0f64, 1.0),
        Err(ModelError::InvalidGaussMarkov)
    );
    assert_eq!(gm.to_ar1(-1.0, 0.0), Err(ModelError::Interval));
}

#[test]
fn model_allan_variance_approaches_the_continuous_gauss_markov_curve() {
    // IEEE Std 952-1997 Annex C: AVAR(tau) = (2 s^2 Tc / tau) [1 - Tc/(2 tau)(3 - 4e^-x + e^-2x)].
    let gm = GaussMarkov::new(1.0f64, 1.0).unwrap();
    let ar1 = gm.to_ar1(0.001, 0.0).unwrap();
    for m in [100u32, 1000, 5000] {
        let tau = m as f64 * 0.001;
        let x = tau / 1.0;
        let continuous =
            2.0 / tau * (1.0 - 1.0 / (2.0 * tau) * (3.0 - 4.0 * (-x).exp() + (-2.0 * x).exp()));
        let discrete = ar1.allan_variance(m).unwrap();
        assert!(
            (discrete - continuous).abs() < 2e-3 * continuous,
            "tau {tau}: {discrete} vs {continuous}"
        );
    }
}

#[test]
fn psd_integrates_to_the_variance() {
    let model = ArModel::new([1.2f64, -0.5], 0.3, 0.0, 0.01).unwrap();
    let r0 = model.autocovariances().unwrap().next().unwrap();
    let nyquist = 50.0;
    let steps = 20_000;
    let df = 2.0 * nyquist / steps as f64;
    let integral: f64 = (0..steps)
        .map(|i| model.psd(-nyquist + (i as f64 + 0.5) * df).unwrap() * df)
        .sum();
    assert!((integral - r0).abs() < 1e-6 * r0, "{integral} vs {r0}");
}

#[test]
fn ar1_allan_variance_equals_the_closed_form() {
    // Zhang 2008, Metrologia 45(5):549: AVAR(m) = s2 [m - 3phi - m phi^2 + 4 phi^(m+1)
    // - phi^(2m+1)] / [m^2 (1-phi)^2 (1-phi^2)]. Evaluated in f64 the closed form itself loses
    // about eps / (1-phi)^3 relative to cancellation, so phi stops at 0.99 for a 1e-9 check.
    for phi in [-0.5f64, 0.3, 0.9, 0.99] {
        let model = ArModel::new([phi], 2.0, 0.0, 0.01).unwrap();
        for m in [1u32, 2, 3, 7, 64, 1000] {
            let mf = m as f64;
            let closed = 2.0
                * (mf - 3.0 * phi - mf * phi * phi + 4.0 * phi.powi(m as i32 + 1)
                    - phi.powi(2 * m as i32 + 1))
                / (mf * mf * (1.0 - phi).powi(2) * (1.0 - phi * phi));
            let got = model.allan_variance(m).unwrap();
            assert!(
                (got - closed).abs() < 1e-9 * closed,
                "phi {phi}, m {m}: {got} vs {closed}"
            );
        }
    }
}

/// f32 AR(1) of a slow Gauss-Markov process (issue 23, item 4): the stationary variance is
/// sigma^2 and the correlation time survives the round trip wherever f32 can represent the
/// process; where it cannot (`dt / T_c` of 1e-7 and 1e-8), a typed error, not a model with the
/// wrong variance (0.839 instead of 1) or a random walk (`a = 1`).
#[test]
fn f32_gauss_markov_at_small_dt_over_t() {
    let gm = GaussMarkov::new(1000.0f32, 1.0).unwrap();
    for dt in [1e-2f32, 3e-2, 0.1, 1.0] {
        let ar1 = gm.to_ar1(dt, 0.0).unwrap();
        let p = ar1.stationary_covariance().unwrap()[0][0];
        assert!((p - 1.0).abs() < 1e-6, "dt {dt}: stationary variance {p}");
        let tc = ar1.to_gauss_markov().unwrap().correlation_time();
        assert!((tc - 1000.0).abs() < 10.0, "dt {dt}: correlation time {tc}");
    }
    for dt in [1e-4f32, 1e-5] {
        assert_eq!(
            gm.to_ar1(dt, 0.0),
            Err(ModelError::Unrepresentable),
            "dt {dt}"
        );
    }
    // f64 represents the same processes.
    let gm64 = GaussMarkov::new(1000.0f64, 1.0).unwrap();
    for dt in [1e-5, 1e-4] {
        let ar1 = gm64.to_ar1(dt, 0.0).unwrap();
        let p = ar1.stationary_covariance().unwrap()[0][0];
        assert!(
            (p - 1.0).abs() < 1e-9,
            "f64, dt {dt}: stationary variance {p}"
        );
    }
}

/// A non-stationary model has no spectrum: `psd` says so instead of returning a finite number
/// (issue 23, item 12).
#[test]
fn psd_of_an_unstable_model_is_an_error() {
    for a in [[1.0f64, 0.0], [0.5, 0.6], [2.0, -0.5]] {
        let m = ArModel::new(a, 1.0, 0.0, 0.01).unwrap();
        for f in [0.0, 10.0, 25.0] {
            assert!(
                matches!(m.psd(f), Err(ModelError::Unstable { .. })),
                "a = {a:?}, f = {f}: {:?}",
                m.psd(f)
            );
        }
    }
    let stable = ArModel::new([0.5f64, 0.3], 1.0, 0.0, 0.01).unwrap();
    // S(0) = sigma^2 dt / (1 - 0.5 - 0.3)^2.
    assert!((stable.psd(0.0).unwrap() - 0.01 / 0.04).abs() < 1e-12);
}
