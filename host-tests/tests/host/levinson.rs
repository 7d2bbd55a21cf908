//! Levinson-Durbin (f32 and f64) against a dense Cholesky solve of the same Toeplitz system.

use imu_ar::batch::levinson_durbin;
use imu_ar_host::reference::{autocovariance, yule_walker};

/// AR(4) data from the recursion x[n] = sum a_k x[n-k] + w[n] with a small deterministic
/// generator (xorshift, sum of 12 uniforms for a near-Gaussian w).
fn ar_data(a: &[f64], n: usize, seed: u64) -> Vec<f64> {
    let mut state = seed;
    let mut uniform = || {
        state ^= state << 13;
        state ^= state >> 7;
        state ^= state << 17;
        (state >> 11) as f64 / (1u64 << 53) as f64
    };
    let mut x = vec![0.0; n];
    for i in 0..n {
        let w = (0..12).map(|_| uniform()).sum::<f64>() - 6.0;
        x[i] = w + a
            .iter()
            .enumerate()
            .filter(|(k, _)| *k < i)
            .map(|(k, ak)| ak * x[i - 1 - k])
            .sum::<f64>();
    }
    x
}

#[test]
fn matches_dense_solve_at_every_order() {
    let x = ar_data(&[1.2, -0.5, 0.1, 0.05], 20_000, 0x9E37_79B9_7F4A_7C15);
    let r = autocovariance(&x, 6);
    let fit = levinson_durbin::<f64, 6>(&r).unwrap();
    // The final order against the dense solve...
    let (a_ref, var_ref) = yule_walker(&r, 6).unwrap();
    let err = fit
        .a
        .iter()
        .zip(&a_ref)
        .map(|(a, b)| (a - b).abs())
        .fold(0.0, f64::max);
    assert!(err < 1e-12, "max |a - a_ref| = {err:e}");
    assert!((fit.error_power[5] - var_ref).abs() < 1e-12 * var_ref);
    // ...and every lower order's innovation variance against its own dense solve.
    for m in 1..=6 {
        let (_, var_m) = yule_walker(&r, m).unwrap();
        let got = fit.innovation_variance(m).unwrap();
        assert!(
            (got - var_m).abs() < 1e-12 * var_m,
            "order {m}: {got} vs {var_m}"
        );
    }
}

#[test]
fn f32_is_within_its_precision_of_the_f64_solve() {
    let x = ar_data(&[0.9], 5_000, 7);
    let r = autocovariance(&x, 3);
    let (a_ref, _) = yule_walker(&r, 3).unwrap();
    let r32: Vec<f32> = r.iter().map(|&v| v as f32).collect();
    let fit = levinson_durbin::<f32, 3>(&r32).unwrap();
    for (k, (a, b)) in fit.a.iter().zip(&a_ref).enumerate() {
        assert!(
            (f64::from(*a) - b).abs() < 1e-5,
            "a_{}: f32 {a} vs f64 {b}",
            k + 1
        );
    }
}
