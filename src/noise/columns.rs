//! The fit's bookkeeping of its columns: dropping the zero terms, counting Kalman states,
//! merging neighbours, and ordering the terms, all without a panic path.

use super::fit::Column;
use super::indexed;
use super::model::GmTerm;

/// Moves the Gauss-Markov columns whose parameter in `x` is zero to the end; returns how many
/// columns are left before them.
pub(super) fn compact(columns: &mut [Column], x: &[f64]) -> usize {
    let mut kept = 0;
    for c in 0..columns.len() {
        let column = columns[c];
        let term = matches!(column, Column::GaussMarkov(_) | Column::Oscillator(..));
        let zero_term = term && x.get(c).is_none_or(|v| *v <= 0.0);
        if !zero_term {
            if let Some(slot) = columns.get_mut(kept) {
                *slot = column;
            }
            kept = kept.saturating_add(1);
        }
    }
    kept
}

/// Kalman states of the terms `columns`: one per Gauss-Markov term, two per oscillator.
pub(super) fn states(columns: &[Column]) -> usize {
    columns.iter().fold(0usize, |n, c| {
        n.saturating_add(match c {
            Column::GaussMarkov(_) => 1,
            Column::Oscillator(..) => 2,
            _ => 0,
        })
    })
}

/// The term replacing Gauss-Markov columns `p` and `q` of variances `vp` and `vq`: their
/// `sigma^2`-weighted geometric mean correlation time. `None` for anything else.
pub(super) fn merge(p: Column, vp: f64, q: Column, vq: f64) -> Option<f64> {
    match (p, q) {
        (Column::GaussMarkov(tp), Column::GaussMarkov(tq)) if vp + vq > 0.0 => Some(libm::exp(
            (vp * libm::log(tp) + vq * libm::log(tq)) / (vp + vq),
        )),
        _ => None,
    }
}

/// `columns` without column `i`, and with `i + 1` replaced by a term at `merged` when given;
/// into `out`, returning the count.
pub(super) fn edit(columns: &[Column], i: usize, merged: Option<f64>, out: &mut [Column]) -> usize {
    let mut k = 0;
    for (j, c) in indexed(columns.iter()) {
        let c = match (j, merged) {
            (j, _) if j == i => continue,
            (j, Some(t)) if j == i.saturating_add(1) => Column::GaussMarkov(t),
            _ => *c,
        };
        if let Some(slot) = out.get_mut(k) {
            *slot = c;
            k = k.saturating_add(1);
        }
    }
    k
}

/// The first `n` columns (all of them when there are fewer).
pub(super) fn head(columns: &[Column], n: usize) -> &[Column] {
    &columns[..n.min(columns.len())]
}

/// The first `n` columns, to change.
pub(super) fn head_mut(columns: &mut [Column], n: usize) -> &mut [Column] {
    let n = n.min(columns.len());
    &mut columns[..n]
}

/// Sorts Gauss-Markov terms by correlation time: a bubble sort of a few terms, with no panic
/// path (the library sorts check their comparison and can panic).
pub(super) fn sort_by_correlation_time(terms: &mut [GmTerm]) {
    for end in (1..terms.len()).rev() {
        for k in 0..end {
            if let Some([p, q]) = terms.get_mut(k..k.saturating_add(2))
                && p.correlation_time > q.correlation_time
            {
                core::mem::swap(p, q);
            }
        }
    }
}
