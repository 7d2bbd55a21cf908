//! The white + random-walk curve `sqrt(N^2/tau + K^2 tau/3)` that the six parameter files can
//! say, against the composite model's Allan deviation: how far it overbounds the model as it
//! is, and the smallest random walk `K_H >= K` that overbounds it up to a horizon `H`.
//!
//! None of the six files has a bias-instability (Gauss-Markov) term, so a filter fed `N` and
//! `K` alone underrates the drift where those terms dominate. Instead of the folklore "multiply
//! the random walk by 10", `K_H^2 = max(K^2, max_j 3 (AVAR_model(tau_j) - N^2/tau_j) / tau_j)`
//! over the octaves `tau_j` in `[1 s, H]` is the stated, checked choice.

use super::AxisModel;

/// A curve counts as at or above the model when it is within this relative margin (the
/// rounding of `K_H` itself at the octave that sets it).
const ROUNDING: f64 = 1e-12;

/// The first averaging time of the statements, s.
pub const FROM_TAU: f64 = 1.0;

/// `N^2 / tau + K^2 tau / 3`.
pub fn white_rw_avar(n: f64, k: f64, tau: f64) -> f64 {
    n * n / tau + k * k * tau / 3.0
}

/// The octaves `(axis index, tau, model AVAR)` of `axes` with `tau` in `[1 s, upper]`.
fn octaves<'a>(
    axes: &'a [(usize, &'a AxisModel)],
    upper: f64,
) -> impl Iterator<Item = (usize, f64, f64)> + 'a {
    axes.iter().flat_map(move |&(i, a)| {
        a.model_avar
            .iter()
            .enumerate()
            .map(move |(j, v)| (i, a.dt * 2f64.powi(j as i32), *v))
            .filter(move |(_, tau, _)| *tau >= FROM_TAU && *tau <= upper)
    })
}

/// The smallest `K_H >= k` with `sqrt(N^2/tau + K_H^2 tau/3)` at or above the model's Allan
/// deviation of every one of `axes` at every octave in `[1 s, horizon]`, and the octave that
/// sets it (`(axis index, tau)`), if one does.
pub fn horizon_random_walk(
    n: f64,
    k: f64,
    axes: &[(usize, &AxisModel)],
    horizon: f64,
) -> (f64, Option<(usize, f64)>) {
    let mut best = (k * k, None);
    for (i, tau, v) in octaves(axes, horizon) {
        let need = 3.0 * (v - n * n / tau) / tau;
        if need > best.0 {
            best = (need, Some((i, tau)));
        }
    }
    (best.0.sqrt(), best.1)
}

/// How far the curve of `(n, k)` overbounds the model's Allan deviation of `axes`, from 1 s.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Reach {
    /// The largest octave `tau` up to which every octave from 1 s holds; `None` when the first
    /// does not (or no octave reaches 1 s).
    pub up_to: Option<f64>,
    /// The last octave of the model, s.
    pub last: Option<f64>,
    /// Beyond: the largest shortfall `1 - curve / model ADEV`, its `tau` and axis index.
    pub shortfall: Option<(f64, f64, usize)>,
}

/// The reach of the curve of `(n, k)` against `axes`.
pub fn reach(n: f64, k: f64, axes: &[(usize, &AxisModel)]) -> Reach {
    // Per octave, the axis the curve covers least: (tau, curve / model ADEV, axis).
    let mut rows: Vec<(f64, f64, usize)> = Vec::new();
    for (i, tau, v) in octaves(axes, f64::INFINITY) {
        let ratio = (white_rw_avar(n, k, tau) / v).sqrt();
        match rows.iter_mut().find(|r| r.0 == tau) {
            Some(r) if ratio < r.1 => *r = (tau, ratio, i),
            Some(_) => {}
            None => rows.push((tau, ratio, i)),
        }
    }
    rows.sort_by(|p, q| p.0.total_cmp(&q.0));
    let holds = |r: &(f64, f64, usize)| r.1 >= 1.0 - ROUNDING;
    let kept = rows.iter().take_while(|r| holds(r)).count();
    let shortfall = rows[kept..]
        .iter()
        .filter(|r| !holds(r))
        .max_by(|p, q| q.1.total_cmp(&p.1))
        .map(|r| (1.0 - r.1, r.0, r.2));
    Reach {
        up_to: kept.checked_sub(1).map(|j| rows[j].0),
        last: rows.last().map(|r| r.0),
        shortfall,
    }
}
