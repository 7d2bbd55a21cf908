//! The white + random-walk curve `sqrt(N^2/tau + K^2 tau/3)` that the six parameter files can
//! say, against the composite model's Allan deviation: the smallest pair `(N_H, K_H)` whose
//! curve overbounds the model from `tau = 1 s` to a horizon `H`, and how far a curve reaches.
//!
//! None of the six files has a bias-instability (Gauss-Markov) term, so a filter fed `N` and
//! `K` alone underrates the drift where those terms dominate. Instead of the folklore "multiply
//! the random walk by 10", the files carry the pair `(N_H, K_H)` that minimises
//! `log(N_H/N) + log(K_H/K)` subject to `N_H >= N`, `K_H >= K` and `N_H^2/tau + K_H^2 tau/3 >=
//! AVAR_model(tau)` at every octave `tau` in `[1 s, H]`. In `u = N_H^2`, `v = K_H^2` every
//! constraint is a half-plane and `log u + log v` is concave, so the minimum is at a vertex of
//! the feasible region: [`smallest_overbound`] enumerates the intersections of every pair of
//! constraint lines and keeps the feasible one with the smallest `u v`. Raising `N` tenfold
//! costs as much as raising `K` tenfold, so a bump the white noise can cover no longer forces
//! the random walk up alone.

use super::AxisModel;

/// A curve counts as at or above the model when it is within this relative margin (the
/// rounding of `N_H` and `K_H` themselves at the octaves that set them).
const ROUNDING: f64 = 1e-12;

/// A vertex counts as feasible when it breaks no constraint by more than this relative margin
/// (the rounding of the intersection of two lines); the pair returned is then raised to meet
/// every constraint exactly.
const FEASIBLE: f64 = 1e-9;

/// The first averaging time of the overbound and of the statements, s: the shortest `tau` a
/// horizon may be.
pub const FROM_TAU: f64 = 1.0;

/// How much a floor (the `N` or `K` a model without one is given) raises the curve where it is
/// set: 1 %.
pub const FLOOR_RISE: f64 = 0.01;

/// `N^2 / tau + K^2 tau / 3`.
pub fn white_rw_avar(n: f64, k: f64, tau: f64) -> f64 {
    n * n / tau + k * k * tau / 3.0
}

/// The random walk that raises the white curve `sqrt(N^2/tau)` by [`FLOOR_RISE`] at `tau`:
/// `K = N sqrt(3 ((1 + r)^2 - 1)) / tau`; positive for positive `n` and finite `tau`.
pub fn k_floor(n: f64, tau: f64) -> f64 {
    n * (3.0 * ((1.0 + FLOOR_RISE).powi(2) - 1.0)).sqrt() / tau
}

/// The white noise that raises the random-walk curve `sqrt(K^2 tau/3)` by [`FLOOR_RISE`] at
/// `tau`: `N = K tau sqrt(((1 + r)^2 - 1) / 3)`.
pub fn n_floor(k: f64, tau: f64) -> f64 {
    k * tau * (((1.0 + FLOOR_RISE).powi(2) - 1.0) / 3.0).sqrt()
}

/// The octaves `(axis index, tau, model AVAR)` of `axes` with `tau` in `[1 s, upper]`.
pub fn octaves<'a>(
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

/// The longest octave `tau` of `axes`, s (the last of the model's Allan variance).
pub fn longest_octave(axes: &[(usize, &AxisModel)]) -> Option<f64> {
    axes.iter()
        .filter_map(|(_, a)| {
            let last = a.model_avar.len().checked_sub(1)?;
            Some(a.dt * 2f64.powi(last as i32))
        })
        .max_by(f64::total_cmp)
}

/// One of the constraints that meet at the vertex of an [`Overbound`].
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Limit {
    /// `N_H = N` (the reference white noise).
    White,
    /// `K_H = K` (the reference random walk).
    RandomWalk,
    /// The curve meets the model at this octave: an index into the octaves given.
    Octave(usize),
}

/// The smallest white + random-walk overbound of a set of octaves.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Overbound {
    /// `N_H`, SI/sqrt(Hz).
    pub n: f64,
    /// `K_H`, SI/s/sqrt(Hz).
    pub k: f64,
    /// The two constraints that meet at `(N_H^2, K_H^2)`.
    pub limits: [Limit; 2],
}

/// The pair `(N_H, K_H)` that minimises `log(N_H / n) + log(K_H / k)` subject to `N_H >= n`,
/// `K_H >= k` and `N_H^2 / tau + K_H^2 tau / 3 >= avar` at every `(tau, avar)` of `octaves`,
/// with the two constraints that set it.
///
/// `n` is the model's white noise and `k` its random walk; a model without one passes a
/// positive floor instead ([`n_floor`], [`k_floor`]). In `u = N_H^2`, `v = K_H^2` the
/// constraints are the half-planes `u >= n^2`, `v >= k^2` and `u / tau + v tau / 3 >= avar`,
/// and `log u + log v` is concave: the minimum is at one of their vertices, each the
/// intersection of two constraint lines. Every intersection is tried and the feasible one with
/// the smallest `u v` kept (on a tie within 1e-9, the first: `(n, k)` itself before any
/// octave). The pair returned meets every constraint exactly (`white_rw_avar(N_H, K_H, tau) >=
/// avar`).
///
/// `None` when `n` or `k` is not positive and finite, or an octave has a `tau` that is not
/// positive and finite or an `avar` that is NaN or infinite.
pub fn smallest_overbound(n: f64, k: f64, octaves: &[(f64, f64)]) -> Option<Overbound> {
    let positive = |x: f64| x.is_finite() && x > 0.0;
    if !(positive(n) && positive(k))
        || octaves
            .iter()
            .any(|(tau, avar)| !positive(*tau) || !avar.is_finite())
    {
        return None;
    }
    let (u0, v0) = (n * n, k * k);
    // Every constraint as a line `a u + b v = c`.
    let line = |limit: Limit| -> (f64, f64, f64) {
        match limit {
            Limit::White => (1.0, 0.0, u0),
            Limit::RandomWalk => (0.0, 1.0, v0),
            Limit::Octave(j) => {
                let (tau, avar) = octaves[j];
                (1.0 / tau, tau / 3.0, avar)
            }
        }
    };
    let limits: Vec<Limit> = [Limit::White, Limit::RandomWalk]
        .into_iter()
        .chain(
            (0..octaves.len())
                .filter(|&j| octaves[j].1 > 0.0)
                .map(Limit::Octave),
        )
        .collect();
    let feasible = |u: f64, v: f64| {
        limits.iter().all(|&l| {
            let (a, b, c) = line(l);
            a * u + b * v >= c * (1.0 - FEASIBLE)
        })
    };
    let mut best: Option<(f64, f64, [Limit; 2])> = None;
    for (p, &lp) in limits.iter().enumerate() {
        for &lq in &limits[p + 1..] {
            let (a1, b1, c1) = line(lp);
            let (a2, b2, c2) = line(lq);
            let det = a1 * b2 - a2 * b1;
            // Parallel lines (two axes at one octave) meet nowhere.
            if det.abs() <= 1e-12 * (a1 * b2).abs().max((a2 * b1).abs()) {
                continue;
            }
            let u = (c1 * b2 - c2 * b1) / det;
            let v = (a1 * c2 - a2 * c1) / det;
            if !(positive(u) && positive(v) && feasible(u, v)) {
                continue;
            }
            // Within the rounding of the floors: on them.
            let (u, v) = (u.max(u0), v.max(v0));
            let smaller = best.is_none_or(|(bu, bv, _)| u * v < bu * bv * (1.0 - FEASIBLE));
            if smaller {
                best = Some((u, v, [lp, lq]));
            }
        }
    }
    // (n^2, k^2) and the octave lines always leave a vertex: (n^2, the v that u = n^2 needs).
    let (u, v, limits) = best?;
    let (mut nh, mut kh) = (u.sqrt(), v.sqrt());
    // Raise the pair onto every constraint that the rounding left it just below.
    let short = octaves
        .iter()
        .map(|&(tau, avar)| avar / white_rw_avar(nh, kh, tau))
        .fold(1.0, f64::max);
    if short > 1.0 {
        let s = short.sqrt() * (1.0 + 4.0 * f64::EPSILON);
        nh *= s;
        kh *= s;
    }
    Some(Overbound {
        n: nh,
        k: kh,
        limits,
    })
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

#[cfg(test)]
mod tests {
    use super::*;

    /// Octaves `tau = 2^j dt` from 1 s to `upper` of an Allan variance `avar(tau)`.
    fn grid(dt: f64, upper: f64, avar: impl Fn(f64) -> f64) -> Vec<(f64, f64)> {
        (0..64)
            .map(|j| dt * 2f64.powi(j))
            .filter(|tau| (FROM_TAU..=upper).contains(tau))
            .map(|tau| (tau, avar(tau)))
            .collect()
    }

    /// A Gauss-Markov term's Allan variance: `sigma^2`, correlation time `t`.
    fn gauss_markov(sigma: f64, t: f64, tau: f64) -> f64 {
        let x = tau / t;
        sigma * sigma / (x * x) * (2.0 * x - 3.0 + 4.0 * (-x).exp() - (-2.0 * x).exp())
    }

    fn covers(n: f64, k: f64, octaves: &[(f64, f64)]) -> bool {
        octaves
            .iter()
            .all(|&(tau, avar)| white_rw_avar(n, k, tau) >= avar)
    }

    /// The smallest `u v` over a log grid in `(u, v)` from `(n^2, k^2)` up, `steps` per decade.
    fn brute_force(n: f64, k: f64, octaves: &[(f64, f64)], steps: i32) -> (f64, f64) {
        let (u0, v0) = (n * n, k * k);
        let mut best = (f64::INFINITY, 0.0, 0.0);
        for i in 0..8 * steps {
            let u = u0 * 10f64.powf(f64::from(i) / f64::from(steps));
            for j in 0..8 * steps {
                let v = v0 * 10f64.powf(f64::from(j) / f64::from(steps));
                if u * v < best.0 && covers(u.sqrt(), v.sqrt(), octaves) {
                    best = (u * v, u, v);
                }
            }
        }
        (best.1.sqrt(), best.2.sqrt())
    }

    #[test]
    fn a_white_and_random_walk_model_is_its_own_overbound() {
        for (n, k) in [(2e-4, 2e-6), (1e-3, 5e-5), (3e-2, 1e-7)] {
            let octaves = grid(0.01, 1e5, |tau| white_rw_avar(n, k, tau));
            let b = smallest_overbound(n, k, &octaves).unwrap();
            assert!((b.n / n - 1.0).abs() < 1e-12, "{n}, {k}: {b:?}");
            assert!((b.k / k - 1.0).abs() < 1e-12, "{n}, {k}: {b:?}");
            assert_eq!(b.limits, [Limit::White, Limit::RandomWalk]);
        }
    }

    #[test]
    fn the_vertex_is_the_grid_searchs_minimum() {
        // White noise and random walk with Gauss-Markov bumps at several correlation times.
        let cases = [
            (2e-4, 2e-6, vec![(3e-5, 50.0)]),
            (3e-4, 1e-6, vec![(4e-5, 100.0), (2e-5, 5.0)]),
            (1e-3, 3e-5, vec![(2e-4, 20.0)]),
            (1e-3, 3e-7, vec![(1e-4, 1000.0)]),
            (5e-3, 1e-4, vec![(5e-4, 2.0), (3e-4, 300.0)]),
        ];
        for (n, k, gm) in cases {
            let octaves = grid(0.005, 2000.0, |tau| {
                white_rw_avar(n, k, tau)
                    + gm.iter()
                        .map(|&(s, t)| gauss_markov(s, t, tau))
                        .sum::<f64>()
            });
            let b = smallest_overbound(n, k, &octaves).unwrap();
            assert!(b.n >= n && b.k >= k, "{b:?}");
            assert!(covers(b.n, b.k, &octaves), "{b:?} does not overbound");
            let (gn, gk) = brute_force(n, k, &octaves, 200);
            let (exact, searched) = (b.n * b.k, gn * gk);
            // The grid's best is feasible, so no smaller than the minimum; and within one grid
            // step (10^(1/200) in u and in v: 1.2 % in N K) of it.
            assert!(
                exact <= searched * (1.0 + 1e-9),
                "{b:?} against the grid's ({gn}, {gk})"
            );
            assert!(
                searched <= exact * 1.012,
                "{b:?} against the grid's ({gn}, {gk})"
            );
            // A vertex: two constraints meet there.
            assert_ne!(b.limits[0], b.limits[1]);
        }
    }

    #[test]
    fn a_bump_the_white_noise_covers_does_not_raise_the_random_walk() {
        // A bump at a few seconds, far below where the random walk dominates: raising N by a
        // few per cent covers it, raising K would take a large factor.
        let (n, k) = (1e-3, 1e-6);
        let octaves = grid(0.01, 600.0, |tau| {
            white_rw_avar(n, k, tau) + gauss_markov(1e-4, 2.0, tau)
        });
        let b = smallest_overbound(n, k, &octaves).unwrap();
        assert!(b.k / k < 1.0 + 1e-9, "{b:?}");
        assert!(b.n / n > 1.0 && b.n / n < 1.5, "{b:?}");
        assert_eq!(b.limits[0], Limit::RandomWalk, "{b:?}");
        // The old rule (K alone) needs a large factor.
        let k_alone = octaves
            .iter()
            .map(|&(tau, v)| (3.0 * (v - n * n / tau) / tau).max(k * k))
            .fold(0.0, f64::max)
            .sqrt();
        assert!(k_alone / k > 5.0, "{k_alone}");
    }

    #[test]
    fn floors_raise_the_curve_by_one_per_cent_where_they_are_set() {
        let (n, tau) = (1e-3, 300.0);
        let k = k_floor(n, tau);
        assert!(k > 0.0);
        let rise = (white_rw_avar(n, k, tau) / white_rw_avar(n, 0.0, tau)).sqrt();
        assert!((rise - 1.0 - FLOOR_RISE).abs() < 1e-12, "{rise}");
        let (k, tau) = (1e-5, 1.0);
        let n = n_floor(k, tau);
        let rise = (white_rw_avar(n, k, tau) / white_rw_avar(0.0, k, tau)).sqrt();
        assert!((rise - 1.0 - FLOOR_RISE).abs() < 1e-12, "{rise}");
        // A white-noise model with a floor: nothing in range needs more.
        let octaves = grid(0.01, 300.0, |tau| white_rw_avar(1e-3, 0.0, tau));
        let b = smallest_overbound(1e-3, k_floor(1e-3, 163.84), &octaves).unwrap();
        assert_eq!(b.limits, [Limit::White, Limit::RandomWalk]);
    }

    #[test]
    fn several_axes_at_one_octave_and_bad_inputs() {
        let (n, k) = (1e-3, 1e-5);
        let mut octaves = grid(0.01, 600.0, |tau| white_rw_avar(n, k, tau));
        // A second axis, higher at every octave: the same taus twice (parallel lines).
        let second: Vec<(f64, f64)> = octaves.iter().map(|&(t, v)| (t, 1.5 * v)).collect();
        octaves.extend(second);
        let b = smallest_overbound(n, k, &octaves).unwrap();
        assert!(covers(b.n, b.k, &octaves));
        let (gn, gk) = brute_force(n, k, &octaves, 200);
        assert!(b.n * b.k <= gn * gk * (1.0 + 1e-9));
        assert!(smallest_overbound(0.0, k, &octaves).is_none());
        assert!(smallest_overbound(n, f64::NAN, &octaves).is_none());
        assert!(smallest_overbound(n, k, &[(0.0, 1.0)]).is_none());
        assert!(smallest_overbound(n, k, &[(1.0, f64::INFINITY)]).is_none());
        // No octave: the references themselves.
        let b = smallest_overbound(n, k, &[]).unwrap();
        assert_eq!((b.n, b.k), (n, k));
    }
}
