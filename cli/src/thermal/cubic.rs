//! The bias as a polynomial in temperature (at most a cubic, as both autopilots use), fitted
//! to the temperature bins with a robust loss.
//!
//! The fit minimises `sum_i rho((y_i - p(T_i)) / s)` over the bins `(T_i, y_i)`, with Huber's
//! `rho` (quadratic within `k = 1.345` scales of zero, linear beyond: 95 % of least squares'
//! efficiency on normal noise) and the scale `s` the bins' residuals' median absolute
//! deviation times 1.4826, by iteratively reweighted least squares (Huber 1981, ch. 7). Each
//! least-squares step is solved in the normalised temperature `u = (T - T_ref) / h`, `|u| <= 1`,
//! so that the powers stay of one size.

use super::bins::median;

/// Huber's tuning constant.
const HUBER_K: f64 = 1.345;

/// A polynomial in `T - reference` (deg C): `sum_k coefficients[k] (T - reference)^k`.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Poly {
    /// The temperature the powers are taken about, deg C.
    pub reference: f64,
    /// The coefficients of `(T - reference)^0 .. ^3`, per kelvin to that power.
    pub coefficients: [f64; 4],
}

impl Poly {
    /// The value at `celsius`.
    pub fn at(&self, celsius: f64) -> f64 {
        let d = celsius - self.reference;
        self.coefficients
            .iter()
            .rev()
            .fold(0.0, |acc, c| acc * d + c)
    }

    /// The same polynomial in powers of `T - reference`: `q_j = sum_{k>=j} C(k, j) c_k d^(k-j)`,
    /// `d = reference - self.reference`.
    pub fn about(&self, reference: f64) -> Poly {
        let d = reference - self.reference;
        let c = &self.coefficients;
        let mut q = [0.0; 4];
        for (j, qj) in q.iter_mut().enumerate() {
            let mut binomial = 1.0;
            let mut power = 1.0;
            for (k, ck) in c.iter().enumerate().skip(j) {
                *qj += binomial * ck * power;
                binomial = binomial * (k + 1) as f64 / (k + 1 - j) as f64;
                power *= d;
            }
        }
        Poly {
            reference,
            coefficients: q,
        }
    }
}

/// The robust fit of a polynomial of `degree` (at most 3) in `T - reference` to `points`
/// (temperature, value): `None` when fewer than `degree + 1` distinct temperatures hold it.
pub fn fit(points: &[(f64, f64)], degree: usize, reference: f64) -> Option<Poly> {
    let degree = degree.min(3);
    let mut temperatures: Vec<f64> = points.iter().map(|p| p.0).collect();
    temperatures.sort_by(f64::total_cmp);
    temperatures.dedup();
    if temperatures.len() <= degree
        || points
            .iter()
            .any(|(t, y)| !(t.is_finite() && y.is_finite()))
    {
        return None;
    }
    let h = points
        .iter()
        .map(|(t, _)| (t - reference).abs())
        .fold(0.0, f64::max)
        .max(f64::MIN_POSITIVE);
    let mut weights = vec![1.0; points.len()];
    let mut a = solve(points, &weights, degree, reference, h)?;
    for _ in 0..100 {
        let residuals: Vec<f64> = points
            .iter()
            .map(|&(t, y)| y - eval(&a, (t - reference) / h))
            .collect();
        let mut absolute: Vec<f64> = residuals.iter().map(|r| r.abs()).collect();
        let scale = 1.4826 * median(&mut absolute);
        if scale == 0.0 {
            break;
        }
        for (w, r) in weights.iter_mut().zip(&residuals) {
            *w = (HUBER_K * scale / r.abs()).min(1.0);
        }
        let next = solve(points, &weights, degree, reference, h)?;
        let change = next
            .iter()
            .zip(&a)
            .map(|(x, y)| (x - y).abs())
            .fold(0.0, f64::max);
        let size = next.iter().map(|x| x.abs()).fold(0.0, f64::max);
        a = next;
        if change <= 1e-13 * size.max(f64::MIN_POSITIVE) {
            break;
        }
    }
    // From the normalised temperature back to kelvins.
    let mut coefficients = [0.0; 4];
    let mut scale = 1.0;
    for (c, ak) in coefficients.iter_mut().zip(a) {
        *c = ak / scale;
        scale *= h;
    }
    Some(Poly {
        reference,
        coefficients,
    })
}

/// The variance of the least-squares polynomial of `degree` in `T - reference` at each
/// temperature, fitted with equal weights to values at `temperatures` whose standard errors
/// are `se`: `x(T)^T (X^T X)^-1 (sum_i se_i^2 x_i x_i^T) (X^T X)^-1 x(T)`, `x(T)` the powers of
/// the normalised temperature. (The robust fit's weights are 1 but at outliers.) `None` when
/// the temperatures do not determine the polynomial.
pub fn prediction_variance(
    temperatures: &[f64],
    se: &[f64],
    degree: usize,
    reference: f64,
) -> Option<impl Fn(f64) -> f64> {
    let n = degree.min(3) + 1;
    let h = temperatures
        .iter()
        .map(|t| (t - reference).abs())
        .fold(0.0, f64::max)
        .max(f64::MIN_POSITIVE);
    let powers = move |t: f64| {
        let u = (t - reference) / h;
        let mut x = [0.0; 4];
        let mut p = 1.0;
        for v in x.iter_mut().take(n) {
            *v = p;
            p *= u;
        }
        x
    };
    let (mut m, mut s) = ([[0.0f64; 4]; 4], [[0.0f64; 4]; 4]);
    for (&t, &e) in temperatures.iter().zip(se) {
        let x = powers(t);
        for i in 0..n {
            for j in 0..n {
                m[i][j] += x[i] * x[j];
                s[i][j] += e * e * x[i] * x[j];
            }
        }
    }
    let inverse = invert(m, n)?;
    let product = |a: &[[f64; 4]; 4], b: &[[f64; 4]; 4]| {
        let mut c = [[0.0; 4]; 4];
        for i in 0..n {
            for j in 0..n {
                c[i][j] = (0..n).map(|k| a[i][k] * b[k][j]).sum();
            }
        }
        c
    };
    let covariance = product(&product(&inverse, &s), &inverse);
    Some(move |t: f64| {
        let x = powers(t);
        let mut v = 0.0;
        for i in 0..n {
            for j in 0..n {
                v += x[i] * covariance[i][j] * x[j];
            }
        }
        v.max(0.0)
    })
}

/// The inverse of the leading `n` by `n` block of `m` (Gauss-Jordan, partial pivoting).
fn invert(mut m: [[f64; 4]; 4], n: usize) -> Option<[[f64; 4]; 4]> {
    let mut inverse = [[0.0; 4]; 4];
    for (i, row) in inverse.iter_mut().enumerate().take(n) {
        row[i] = 1.0;
    }
    let largest = (0..n).map(|i| m[i][i].abs()).fold(0.0, f64::max);
    for col in 0..n {
        let pivot = (col..n).max_by(|&a, &b| m[a][col].abs().total_cmp(&m[b][col].abs()))?;
        if m[pivot][col].abs() <= 1e-12 * largest {
            return None;
        }
        m.swap(col, pivot);
        inverse.swap(col, pivot);
        let d = m[col][col];
        for k in 0..n {
            m[col][k] /= d;
            inverse[col][k] /= d;
        }
        for row in 0..n {
            if row != col {
                let f = m[row][col];
                for k in 0..n {
                    m[row][k] -= f * m[col][k];
                    inverse[row][k] -= f * inverse[col][k];
                }
            }
        }
    }
    Some(inverse)
}

/// `sum_k a_k u^k`.
fn eval(a: &[f64; 4], u: f64) -> f64 {
    a.iter().rev().fold(0.0, |acc, c| acc * u + c)
}

/// Weighted least squares in `u = (T - reference) / h`: the normal equations, solved by their
/// inverse ([`invert`]).
fn solve(
    points: &[(f64, f64)],
    weights: &[f64],
    degree: usize,
    reference: f64,
    h: f64,
) -> Option<[f64; 4]> {
    let n = degree + 1;
    let (mut m, mut b) = ([[0.0f64; 4]; 4], [0.0f64; 4]);
    for (&(t, y), &w) in points.iter().zip(weights) {
        let u = (t - reference) / h;
        let mut phi = [0.0; 4];
        let mut p = 1.0;
        for v in phi.iter_mut().take(n) {
            *v = p;
            p *= u;
        }
        for i in 0..n {
            for j in 0..n {
                m[i][j] += w * phi[i] * phi[j];
            }
            b[i] += w * phi[i] * y;
        }
    }
    // At most 4 unknowns with |u| <= 1: the normal equations are well conditioned.
    let inverse = invert(m, n)?;
    let mut a = [0.0; 4];
    for (ai, row) in a.iter_mut().zip(&inverse).take(n) {
        *ai = row.iter().zip(&b).take(n).map(|(x, y)| x * y).sum();
    }
    a.iter().all(|v| v.is_finite()).then_some(a)
}

#[cfg(test)]
mod tests {
    use super::*;

    fn cubic(t: f64) -> f64 {
        0.02 - 3e-4 * (t - 40.0) + 2e-5 * (t - 40.0).powi(2) - 4e-7 * (t - 40.0).powi(3)
    }

    /// An exact cubic is recovered to rounding, about any reference; re-expressed about
    /// another reference it is the same function.
    #[test]
    fn an_exact_cubic_is_recovered() {
        let points: Vec<(f64, f64)> = (0..41)
            .map(|i| (20.0 + i as f64, cubic(20.0 + i as f64)))
            .collect();
        let p = fit(&points, 3, 40.0).unwrap();
        let want = [0.02, -3e-4, 2e-5, -4e-7];
        for (got, want) in p.coefficients.iter().zip(want) {
            assert!(
                (got - want).abs() <= 1e-12 * want.abs().max(1e-3),
                "{got} vs {want}"
            );
        }
        let q = fit(&points, 3, 35.0).unwrap();
        let r = q.about(40.0);
        for (got, want) in r.coefficients.iter().zip(want) {
            assert!(
                (got - want).abs() <= 1e-12 * want.abs().max(1e-3),
                "{got} vs {want}"
            );
        }
        for t in [20.0, 33.3, 60.0] {
            assert!((q.at(t) - cubic(t)).abs() < 1e-14);
        }
    }

    /// Three bins knocked far off: the robust fit stays on the cubic, least squares does not.
    #[test]
    fn knocked_bins_do_not_bend_the_fit() {
        let mut points: Vec<(f64, f64)> = (0..41)
            .map(|i| (20.0 + i as f64, cubic(20.0 + i as f64)))
            .collect();
        for i in [5, 6, 30] {
            points[i].1 += 0.01;
        }
        let p = fit(&points, 3, 40.0).unwrap();
        let worst = (0..41)
            .map(|i| (p.at(20.0 + i as f64) - cubic(20.0 + i as f64)).abs())
            .fold(0.0, f64::max);
        assert!(worst < 2e-4, "robust: {worst}");
        let weights = vec![1.0; points.len()];
        let h = 20.0;
        let a = solve(&points, &weights, 3, 40.0, h).unwrap();
        let plain = (0..41)
            .map(|i| (eval(&a, i as f64 / h - 1.0) - cubic(20.0 + i as f64)).abs())
            .fold(0.0, f64::max);
        assert!(
            plain > 5.0 * worst,
            "least squares: {plain}, robust: {worst}"
        );
    }

    /// A straight line through two points of error 1 at -1 and 1: its variance is 1 at the
    /// points, 0.5 midway, and 5 at 3 (`(1 + t^2) / 2`).
    #[test]
    fn the_prediction_variance_of_a_line() {
        let v = prediction_variance(&[-1.0, 1.0], &[1.0, 1.0], 1, 0.0).unwrap();
        for (t, want) in [(-1.0, 1.0), (0.0, 0.5), (1.0, 1.0), (3.0, 5.0)] {
            assert!((v(t) - want).abs() < 1e-12, "{t}: {}", v(t));
        }
        assert!(prediction_variance(&[1.0, 1.0], &[1.0, 1.0], 1, 0.0).is_none());
    }

    #[test]
    fn too_few_temperatures_give_no_fit() {
        assert!(fit(&[(20.0, 1.0), (20.0, 2.0), (21.0, 1.0)], 3, 20.0).is_none());
        assert!(
            fit(
                &[(20.0, 1.0), (21.0, f64::NAN), (22.0, 1.0), (23.0, 0.0)],
                3,
                20.0
            )
            .is_none()
        );
        assert!(fit(&[(20.0, 1.0), (21.0, 2.0)], 1, 20.0).is_some());
    }
}
