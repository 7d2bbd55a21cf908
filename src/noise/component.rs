//! The Allan variance of each component of the composite model at `tau = m dt`.
//!
//! Every expression is the expectation of the overlapping (and of the non-overlapping) Allan
//! variance estimator for the sampled process, exact for every `m >= 1`
//! (`noise-model.md` section 1 of the design; IEEE Std 952-1997, Annex C for the
//! large-`tau` forms):
//!
//! | component | parameter | `AVAR(m)` |
//! |---|---|---|
//! | quantisation | `Q` (u s) | `3 Q^2 / tau^2` |
//! | white noise | `N` (u/sqrt(Hz)) | `N^2 / tau` |
//! | Gauss-Markov | `sigma` (u), `T` (s) | that of the AR(1) with `a = exp(-dt/T)` (below) |
//! | random walk | `K` (u/s/sqrt(Hz)) | `K^2 dt (2 m^2 + 1) / (6 m)` |
//! | rate ramp | `R` (u/s) | `R^2 tau^2 / 2` |
//!
//! With `S_m` the sum of `m` consecutive samples, `AVAR(m) = (2 Var S_m - Var S_2m / 2) / m^2`.

use crate::model::{ArModel, ModelError};

/// `AVAR` of quantisation noise of unit `Q^2` at `m` samples of `dt`: `3 / tau^2`.
pub fn quantization(dt: f64, m: u64) -> f64 {
    let tau = m as f64 * dt;
    3.0 / (tau * tau)
}

/// `AVAR` of white noise of unit `N^2`: `1 / tau`.
pub fn white(dt: f64, m: u64) -> f64 {
    1.0 / (m as f64 * dt)
}

/// `AVAR` of a random walk of unit `K^2`: `dt (2 m^2 + 1) / (6 m)` (tends to `tau / 3`).
pub fn random_walk(dt: f64, m: u64) -> f64 {
    let m = m as f64;
    dt * (2.0 * m * m + 1.0) / (6.0 * m)
}

/// `AVAR` of a rate ramp of unit `R^2`: `tau^2 / 2`.
pub fn ramp(dt: f64, m: u64) -> f64 {
    let tau = m as f64 * dt;
    tau * tau / 2.0
}

/// `AVAR` of a first-order Gauss-Markov process of unit variance `sigma^2` and correlation
/// time `t`, sampled every `dt`: the AR(1) with `phi = exp(-c)`, `c = dt / t`.
///
/// `Var S_m = m + 2 phi (g(m c) - m g(c)) / (1 - phi)^2` with `g(x) = e^-x - 1 + x`, which
/// keeps full precision where `phi` is close to 1 (`m (1 - phi) - (1 - phi^m)` written
/// directly loses it). Where `tau << t` the leading terms of the difference of the two `Var S`
/// cancel: the result keeps about `16 + log10(tau / t)` digits.
pub fn gauss_markov(dt: f64, t: f64, m: u64) -> f64 {
    let c = dt / t;
    let phi = libm::exp(-c);
    let u = -libm::expm1(-c);
    let var_sum = |m: f64| m + 2.0 * phi * (g(m * c) - m * g(c)) / (u * u);
    let m = m as f64;
    (2.0 * var_sum(m) - var_sum(2.0 * m) / 2.0) / (m * m)
}

/// `g(x) = e^-x - 1 + x >= 0`, by its series below 0.1 (ten terms: relative error below
/// 1e-17) and directly above.
fn g(x: f64) -> f64 {
    if x >= 0.1 {
        return libm::expm1(-x) + x;
    }
    // x^2/2 - x^3/6 + x^4/24 - ...: terms k = 2..=11.
    let mut term = x * x / 2.0;
    let mut sum = 0.0;
    for k in 3..=12 {
        sum += term;
        term *= -x / k as f64;
    }
    sum
}

/// `AVAR` at `m = 2^j` of a second-order Gauss-Markov process (a damped oscillator) of unit
/// variance, centre frequency `frequency` (Hz) and decay time `t` (s), sampled every `dt`: the
/// AR(2) with poles `exp(-dt/t) exp(+-i 2 pi f dt)`, `a = [2 r cos(theta), -r^2]`. Its Allan
/// deviation has the bump of a spectral line, at `tau` near `0.37 / f`.
///
/// # Errors
///
/// [`ModelError::Unstable`] for `t` not positive (a pole on the unit circle);
/// [`ModelError::NonFinite`] for a non-finite parameter.
pub fn oscillator(dt: f64, frequency: f64, t: f64, j: usize) -> Result<f64, ModelError> {
    let r = libm::exp(-dt / t);
    let theta = 2.0 * core::f64::consts::PI * frequency * dt;
    let ar = ArModel::new([2.0 * r * libm::cos(theta), -r * r], 1.0, 0.0, dt)?;
    let r0 = ar.autocovariances()?.next().unwrap_or(1.0);
    let mut out = [0.0; 64];
    let out = &mut out[..j.min(63) + 1];
    ar_octaves(&ar, out)?;
    Ok(out.last().copied().unwrap_or(0.0) / r0)
}

/// The Allan variances of a stationary AR model at `m = 1, 2, 4, .., 2^(L-1)` into `out`.
///
/// With the autocovariances `r_k`, `Var S_m = m (2 A_m - r_0) - 2 B_m` where
/// `A_m = sum_{k<m} r_k` and `B_m = sum_{k<m} k r_k`. Both follow from the companion matrix
/// `Phi` (`g_{k+1} = Phi g_k` for `g_k = [r_k, .., r_{k-P+1}]`, `r_{-j} = r_j`) by doubling:
/// `S_m = sum_{k<m} Phi^k` and `T_m = sum_{k<m} k Phi^k` obey `S_2m = S_m + Phi^m S_m` and
/// `T_2m = T_m + Phi^m (T_m + m S_m)`. So every octave costs three `P x P` products, whatever
/// the model's memory, instead of the `O(m P)` of a sum over lags.
///
/// # Errors
///
/// [`ModelError::Unstable`] when the model is not stationary.
pub fn ar_octaves<const P: usize>(
    model: &ArModel<f64, P>,
    out: &mut [f64],
) -> Result<(), ModelError> {
    let mut r = model.autocovariances()?;
    let mut g0 = [0.0; P];
    for (slot, v) in g0.iter_mut().zip(&mut r) {
        *slot = v;
    }
    let r0 = g0.first().copied().unwrap_or(0.0);
    let mut phi = model.transition(); // Phi^m
    let mut s = identity::<P>(); // S_m
    let mut t = [[0.0; P]; P]; // T_m
    let mut m = 1.0;
    // Var S at m = 1 is r_0.
    let mut previous = r0;
    for slot in out.iter_mut() {
        // Double: T first (it needs S_m), then S, then Phi^2m.
        let mut tm = t;
        add_scaled(&mut tm, &s, m);
        let mut t2 = t;
        add_product(&mut t2, &phi, &tm);
        let mut s2 = s;
        add_product(&mut s2, &phi, &s);
        let mut phi2 = [[0.0; P]; P];
        add_product(&mut phi2, &phi, &phi);
        (t, s, phi) = (t2, s2, phi2);
        let m2 = 2.0 * m;
        let first_row = |m: &[[f64; P]; P]| -> f64 {
            m.first()
                .map_or(0.0, |row| row.iter().zip(&g0).map(|(p, q)| p * q).sum())
        };
        let (a, b) = (first_row(&s), first_row(&t));
        let var2 = m2 * (2.0 * a - r0) - 2.0 * b;
        *slot = (2.0 * previous - var2 / 2.0) / (m * m);
        previous = var2;
        m = m2;
    }
    Ok(())
}

fn identity<const P: usize>() -> [[f64; P]; P] {
    let mut i = [[0.0; P]; P];
    for (k, row) in super::indexed(i.iter_mut()) {
        if let Some(v) = row.get_mut(k) {
            *v = 1.0;
        }
    }
    i
}

/// `acc += f x`.
fn add_scaled<const P: usize>(acc: &mut [[f64; P]; P], x: &[[f64; P]; P], f: f64) {
    for (ra, rx) in acc.iter_mut().zip(x) {
        ra.iter_mut().zip(rx).for_each(|(a, x)| *a += f * x);
    }
}

/// `acc += x y`.
fn add_product<const P: usize>(acc: &mut [[f64; P]; P], x: &[[f64; P]; P], y: &[[f64; P]; P]) {
    for (ra, rx) in acc.iter_mut().zip(x) {
        for (xk, yk) in rx.iter().zip(y) {
            ra.iter_mut().zip(yk).for_each(|(a, y)| *a += xk * y);
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn rel(a: f64, b: f64) -> f64 {
        ((a - b) / b).abs()
    }

    #[test]
    fn gauss_markov_is_the_ar1_allan_variance() {
        let dt = 0.01;
        for t in [0.003, 0.05, 1.0, 37.0, 1e4] {
            let phi = libm::exp(-dt / t);
            let ar = ArModel::new([phi], 1.0 - phi * phi, 0.0, dt).unwrap();
            for m in [1u32, 2, 3, 8, 64, 1000] {
                let want = ar.allan_variance(m).unwrap();
                let got = gauss_markov(dt, t, u64::from(m));
                // Cancellation where tau << T (see the function's docs).
                let tol = 1e-12 * (t / (f64::from(m) * dt)).max(1.0);
                assert!(rel(got, want) < tol, "T {t} m {m}: {got} vs {want}");
            }
        }
    }

    #[test]
    fn ar_octaves_match_the_sum_over_lags() {
        let models: [[f64; 3]; 3] = [[0.5, 0.2, -0.1], [0.22, -0.33, -0.30], [1.5, -0.7, 0.1]];
        for a in models {
            let ar = ArModel::new(a, 0.7, 0.0, 0.01).unwrap();
            let mut out = [0.0; 12];
            ar_octaves(&ar, &mut out).unwrap();
            for (j, got) in out.iter().enumerate() {
                let want = ar.allan_variance(1 << j).unwrap();
                assert!(rel(*got, want) < 1e-10, "{a:?} m 2^{j}: {got} vs {want}");
            }
        }
    }

    #[test]
    fn closed_forms_at_large_tau() {
        let dt = 0.01;
        let m = 1u64 << 20;
        let tau = m as f64 * dt;
        assert!(rel(random_walk(dt, m), tau / 3.0) < 1e-12);
        // A Gauss-Markov process looks white (N^2 = 2 sigma^2 T) far beyond T.
        assert!(rel(gauss_markov(dt, 0.5, m), 2.0 * 0.5 / tau) < 1e-3);
        // ... and like a random walk (K^2 = 2 sigma^2 / T) far below it.
        assert!(rel(gauss_markov(dt, 1e6, 1 << 10), 2.0 / 1e6 * 10.24 / 3.0) < 1e-3);
    }
}
