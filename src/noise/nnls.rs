//! Non-negative least squares by the active-set method of Lawson and Hanson.
//!
//! Minimises `||A x - b||_2` subject to `x >= 0` (C. L. Lawson and R. J. Hanson, *Solving Least
//! Squares Problems*, 1974, chapter 23, algorithm NNLS). Each outer step moves the column with
//! the largest positive gradient `w = A^T (b - A x)` into the passive set; the inner loop solves
//! the unconstrained problem on the passive columns (Householder QR) and steps back towards the
//! feasible region until every passive variable is positive. In exact arithmetic the residual
//! falls strictly at every outer step and no passive set repeats, so the method ends after
//! finitely many steps; in floating point a column whose solve would not be positive, or whose
//! QR pivot vanishes against its norm (it lies in the span of the passive ones), is set aside
//! until the passive set changes, and an iteration cap of `3 n` outer steps bounds the work
//! whatever the rounding.
//!
//! Columns are stored as `[[f64; M]]` (column-major, `M` rows). Allocation-free: the caller
//! lends a work area of the same size; at most 64 columns.

use super::{bit, indexed};

/// The largest number of columns [`nnls`] accepts (the passive set is a `u64` bit mask).
pub const MAX_COLUMNS: usize = 64;

/// Why [`nnls`] gave no solution.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub enum NnlsError {
    /// More than [`MAX_COLUMNS`] columns, or `x` or `work` of another length than `a`.
    Shape,
    /// A NaN or infinite entry in `A` or `b`.
    NonFinite,
    /// The outer-step cap (`3 n`) was reached; only rounding can cause this.
    NoConvergence,
}

/// Solves `min ||A x - b||, x >= 0` into `x`; returns the residual norm `||A x - b||`.
///
/// `a` holds the columns of `A`; `work` must have as many columns as `a` (its contents are
/// overwritten). Rows that should not count can be zero in every column and in `b`.
///
/// ```
/// use imu_ar::noise::nnls::nnls;
///
/// // Columns [1, 0], [0, 1], [1, 1]; b = [2, -1]: the best non-negative fit uses only
/// // the first column (x = [2, 0, 0]) and leaves the residual 1.
/// let a = [[1.0, 0.0], [0.0, 1.0], [1.0, 1.0]];
/// let mut work = [[0.0; 2]; 3];
/// let mut x = [0.0; 3];
/// let r = nnls(&a, &[2.0, -1.0], &mut x, &mut work).unwrap();
/// assert_eq!(x, [2.0, 0.0, 0.0]);
/// assert!((r - 1.0).abs() < 1e-12);
/// ```
///
/// # Errors
///
/// [`NnlsError`] for mismatched shapes, non-finite input or (rounding only) the step cap.
pub fn nnls<const M: usize>(
    a: &[[f64; M]],
    b: &[f64; M],
    x: &mut [f64],
    work: &mut [[f64; M]],
) -> Result<f64, NnlsError> {
    let n = a.len();
    if n > MAX_COLUMNS || x.len() != n || work.len() != n {
        return Err(NnlsError::Shape);
    }
    let finite = |v: &[f64]| v.iter().all(|e| e.is_finite());
    if !finite(b) || !a.iter().all(|c| finite(c)) {
        return Err(NnlsError::NonFinite);
    }
    // Work on fixed-size copies: every index below is a column number under MAX_COLUMNS.
    let mut xs = [0.0; MAX_COLUMNS];
    let mut z = [0.0; MAX_COLUMNS];
    let mut passive = 0u64;
    // Columns set aside until the passive set changes (their solve was not positive).
    let mut set_aside = 0u64;
    let xn = &mut xs[..n.min(MAX_COLUMNS)];
    // A gradient within rounding of zero is zero: `a_j . r` carries an error of a few
    // `eps |a_j| |b|`, and a column let in on that noise can cycle instead of converging.
    let b_norm = norm(b);
    for _ in 0..n.max(1).saturating_mul(3) {
        let residual = residual(a, b, xn);
        let w = |j: usize| {
            a.get(j).map_or(0.0, |c| {
                let g = dot(c, &residual);
                if g > 1e-12 * norm(c) * b_norm { g } else { 0.0 }
            })
        };
        let candidate = (0..n)
            .filter(|&j| (passive | set_aside) & bit(j) == 0)
            .map(|j| (j, w(j)))
            .filter(|&(_, wj)| wj > 0.0)
            .max_by(|p, q| p.1.total_cmp(&q.1));
        let Some((t, _)) = candidate else {
            x.iter_mut().zip(xn.iter()).for_each(|(o, v)| *o = *v);
            return Ok(norm(&residual));
        };
        let trial = passive | bit(t);
        let zn = &mut z[..n.min(MAX_COLUMNS)];
        if !solve(a, b, trial, zn, work) || zn.get(t).is_none_or(|v| *v <= 0.0) {
            set_aside |= bit(t);
            continue;
        }
        passive = trial;
        set_aside = 0;
        // Inner loop: at least one column leaves per pass, so at most n passes.
        loop {
            // Step from x towards z as far as feasibility allows; x > 0 >= z on the limiting
            // column, so the ratio is in [0, 1).
            let at = |v: &[f64], j: usize| v.get(j).copied().unwrap_or(0.0);
            let ratio = |j: usize| {
                let d = at(xn, j) - at(zn, j);
                if d > 0.0 { at(xn, j) / d } else { 0.0 }
            };
            let Some(limiting) = ones(passive)
                .filter(|&j| at(zn, j) <= 0.0)
                .min_by(|&p, &q| ratio(p).total_cmp(&ratio(q)))
            else {
                xn.iter_mut().zip(zn.iter()).for_each(|(x, z)| *x = *z);
                break;
            };
            let alpha = ratio(limiting);
            for (j, (xj, zj)) in indexed(xn.iter_mut().zip(zn.iter())) {
                if passive & bit(j) != 0 {
                    *xj += alpha * (zj - *xj);
                }
            }
            if let Some(v) = xn.get_mut(limiting) {
                *v = 0.0;
            }
            let mut gone = 0u64;
            for (j, xj) in indexed(xn.iter_mut()) {
                if passive & bit(j) != 0 && *xj <= 0.0 {
                    *xj = 0.0;
                    gone |= bit(j);
                }
            }
            passive &= !gone;
            if passive == 0 || !solve(a, b, passive, zn, work) {
                break;
            }
        }
    }
    Err(NnlsError::NoConvergence)
}

/// The indices of the set bits of `mask`, in increasing order.
fn ones(mask: u64) -> impl Iterator<Item = usize> {
    (0..MAX_COLUMNS).filter(move |&j| mask & bit(j) != 0)
}

fn dot<const M: usize>(u: &[f64; M], v: &[f64; M]) -> f64 {
    u.iter().zip(v).map(|(p, q)| p * q).sum()
}

fn norm<const M: usize>(v: &[f64; M]) -> f64 {
    libm::sqrt(dot(v, v))
}

/// `b - A x`.
fn residual<const M: usize>(a: &[[f64; M]], b: &[f64; M], x: &[f64]) -> [f64; M] {
    let mut r = *b;
    for (col, &xj) in a.iter().zip(x) {
        if xj != 0.0 {
            r.iter_mut().zip(col).for_each(|(ri, c)| *ri -= xj * c);
        }
    }
    r
}

/// Unconstrained least squares on the columns in `mask` by Householder QR; the other entries
/// of `z` are zero. Returns false when a pivot vanishes against its column's norm (the columns
/// are dependent to working precision) or there are more columns than rows.
fn solve<const M: usize>(
    a: &[[f64; M]],
    b: &[f64; M],
    mask: u64,
    z: &mut [f64],
    work: &mut [[f64; M]],
) -> bool {
    let k = mask.count_ones() as usize;
    if k > M || k > work.len() {
        return false;
    }
    for (slot, j) in work.iter_mut().zip(ones(mask)) {
        let Some(column) = a.get(j) else {
            return false;
        };
        *slot = *column;
    }
    let q = &mut work[..k.min(M)];
    let mut rhs = *b;
    for c in 0..q.len() {
        // Householder reflection zeroing q[c][c+1..].
        let Some(&column) = q.get(c) else { break };
        let scale = norm(&column);
        let tail: f64 = column.iter().skip(c).map(|v| v * v).sum();
        let pivot = column.get(c).copied().unwrap_or(0.0);
        let alpha = -libm::copysign(libm::sqrt(tail), pivot);
        // Also false for a NaN pivot.
        let independent = alpha.abs() > 1e-12 * scale;
        if !independent {
            return false;
        }
        let mut v = [0.0; M];
        v.iter_mut()
            .zip(&column)
            .skip(c)
            .for_each(|(vi, qi)| *vi = *qi);
        if let Some(vc) = v.get_mut(c) {
            *vc -= alpha;
        }
        let vv: f64 = v.iter().skip(c).map(|e| e * e).sum();
        for col in q.iter_mut().skip(c).chain(core::iter::once(&mut rhs)) {
            let s: f64 = v.iter().zip(col.iter()).skip(c).map(|(p, q)| p * q).sum();
            let f = 2.0 * s / vv;
            col.iter_mut()
                .zip(&v)
                .skip(c)
                .for_each(|(e, vi)| *e -= f * vi);
        }
    }
    // Back substitution: R is q[c][r] for r <= c.
    let mut sol = [0.0; MAX_COLUMNS];
    for c in (0..q.len().min(MAX_COLUMNS)).rev() {
        let s: f64 = q
            .iter()
            .zip(&sol)
            .skip(c.saturating_add(1))
            .map(|(col, x)| col.get(c).copied().unwrap_or(0.0) * x)
            .sum();
        let diagonal = q.get(c).and_then(|col| col.get(c)).copied();
        let (Some(r), Some(d)) = (rhs.get(c), diagonal) else {
            return false;
        };
        sol[c] = (r - s) / d;
    }
    z.fill(0.0);
    for (j, value) in ones(mask).zip(sol) {
        if let Some(slot) = z.get_mut(j) {
            *slot = value;
        }
    }
    z.iter().all(|v| v.is_finite())
}
