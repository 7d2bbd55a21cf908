//! The composite of one axis as the block-diagonal state space a Kalman filter takes: the
//! Gauss-Markov states, the oscillators' pairs and the random-walk state, named, with `Phi`,
//! `Qd` and `P0` (`noise-model.md` section 3). Shared by `imu-ar noise` and the exports.

use imu_ar::noise::KalmanForm;
use serde::Serialize;

/// The composite of one axis at a filter's step: state names, `Phi`, `Qd` and `P0` (block
/// diagonal), and the variance of one sample used as a measurement.
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct StateSpace {
    /// The states: `gauss_markov[i]`, the oscillators' `(x)` and `(dx/dt)`, `random_walk`.
    pub states: Vec<String>,
    /// The transition over one step.
    pub phi: Vec<Vec<f64>>,
    /// The process noise of one step, unit^2.
    pub q: Vec<Vec<f64>>,
    /// The initial covariance: stationary for the Gauss-Markov states, the caller's turn-on
    /// bias variance for the random walk, unit^2.
    pub p0: Vec<Vec<f64>>,
    /// The variance of one sample averaged over the step, `N^2 / Dt + 2 Q^2 / Dt^2`, unit^2.
    pub measurement_variance: f64,
    /// The filter's step `Dt`, s.
    pub dt: f64,
}

/// A diagonal block of the filter: one state, or an oscillator's pair.
struct Block {
    phi: [[f64; 2]; 2],
    q: [[f64; 2]; 2],
    p0: [[f64; 2]; 2],
    size: usize,
}

impl StateSpace {
    /// The state space of `form`, with every variance (`Qd`, `P0`, the measurement variance)
    /// times `scale2` (the square of a unit conversion; `Phi` does not change with the unit).
    pub fn of<const G: usize>(form: &KalmanForm<G>, scale2: f64) -> Self {
        let one = |v: f64| [[v, 0.0], [0.0, 0.0]];
        let mut blocks = Vec::new();
        let mut states = Vec::new();
        let gm = &form.gm[..form.gm_len.min(G)];
        for (i, s) in gm.iter().enumerate() {
            blocks.push(Block {
                phi: one(s.phi),
                q: one(s.q),
                p0: one(s.p0),
                size: 1,
            });
            states.push(format!("gauss_markov[{i}]"));
        }
        for (i, s) in form.osc[..form.osc_len.min(G)].iter().enumerate() {
            blocks.push(Block {
                phi: s.phi,
                q: s.q,
                p0: s.p0,
                size: 2,
            });
            let k = gm.len() + i;
            states.push(format!("gauss_markov[{k}] (x)"));
            states.push(format!("gauss_markov[{k}] (dx/dt)"));
        }
        if let Some(s) = form.random_walk {
            blocks.push(Block {
                phi: one(s.phi),
                q: one(s.q),
                p0: one(s.p0),
                size: 1,
            });
            states.push("random_walk".into());
        }
        let n = states.len();
        let scaled = |v: [[f64; 2]; 2]| v.map(|row| row.map(|x| x * scale2));
        Self {
            phi: matrix(n, &blocks, |b| b.phi),
            q: matrix(n, &blocks, |b| scaled(b.q)),
            p0: matrix(n, &blocks, |b| scaled(b.p0)),
            states,
            measurement_variance: form.measurement_variance * scale2,
            dt: form.dt,
        }
    }

    /// Whether every number is finite.
    pub fn is_finite(&self) -> bool {
        let cells = self.phi.iter().chain(&self.q).chain(&self.p0).flatten();
        cells
            .chain([&self.measurement_variance, &self.dt])
            .all(|v| v.is_finite())
    }
}

/// The `n` x `n` block-diagonal matrix of `part` of each block.
fn matrix(n: usize, blocks: &[Block], part: impl Fn(&Block) -> [[f64; 2]; 2]) -> Vec<Vec<f64>> {
    let mut m = vec![vec![0.0; n]; n];
    let mut at = 0;
    for b in blocks {
        let v = part(b);
        for (i, row) in v.iter().enumerate().take(b.size) {
            m[at + i][at..at + b.size].copy_from_slice(&row[..b.size]);
        }
        at += b.size;
    }
    m
}
