//! The composite of one axis as the block-diagonal state space a Kalman filter takes: the
//! Gauss-Markov states, the oscillators' pairs, the random-walk state and the quantisation
//! pair, named, with `Phi`, `Qd`, `P0` and the measurement row `h` (`noise-model.md` section 3,
//! [`KalmanForm`]). Shared by `imu-ar noise` and the exports.

use imu_ar::noise::KalmanForm;
use serde::Serialize;

/// The composite of one axis at a filter's step: state names, `Phi`, `Qd` and `P0` (block
/// diagonal), the measurement row `h`, and the variance of the white part of one sample
/// averaged over the step. The sample is `h x + v`, `v` white of that variance.
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct StateSpace {
    /// The states: `gauss_markov[i]`, the oscillators' `(x)` and `(dx/dt)`, `random_walk`,
    /// `quantization (q_k/Dt)` and `quantization (q_(k-1)/Dt)`.
    pub states: Vec<String>,
    /// The transition over one step.
    pub phi: Vec<Vec<f64>>,
    /// The process noise of one step, unit^2.
    pub q: Vec<Vec<f64>>,
    /// The initial covariance: stationary for the Gauss-Markov states, the caller's turn-on
    /// bias variance for the random walk, unit^2.
    pub p0: Vec<Vec<f64>>,
    /// The measurement row over the states: 1 on each, but 0 on an oscillator's `dx/dt` and
    /// -1 on `quantization (q_(k-1)/Dt)`.
    pub h: Vec<f64>,
    /// The variance of the white part of one sample averaged over the step, `N^2 / Dt`,
    /// unit^2 (quantisation is in the states).
    pub measurement_variance: f64,
    /// The quantisation `Q` and its form, or `None` when the model has none.
    pub quantization: Option<Quantization>,
    /// The filter's step `Dt`, s.
    pub dt: f64,
}

/// The quantisation term of the state space.
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct Quantization {
    /// `Q`, unit s (SI: rad for a gyro, m/s for an accelerometer).
    pub value: f64,
    /// How the states carry it, as a sentence.
    pub form: String,
}

/// How the quantisation states carry `Q`.
const QUANTIZATION_FORM: &str = "white noise of variance Q^2 on the integrated sensor \
    (angle or velocity): in a sample averaged over the step dt it is (q_k - q_(k-1)) / dt, \
    q_k ~ N(0, Q^2), carried by the states q_k/dt and q_(k-1)/dt with phi [[0, 0], [1, 0]], \
    q diag(Q^2/dt^2, 0), p0 diag(Q^2/dt^2, Q^2/dt^2) and h [1, -1]; its Allan variance is \
    3 Q^2/tau^2. A filter without these states takes it as measurement noise of variance \
    2 Q^2/dt^2 with lag-1 covariance -Q^2/dt^2; white measurement noise of 2 Q^2/dt^2 alone \
    overstates the Allan deviation from tau = 2 dt on";

/// A diagonal block of the filter: one state, or an oscillator's pair.
struct Block {
    phi: [[f64; 2]; 2],
    q: [[f64; 2]; 2],
    p0: [[f64; 2]; 2],
    h: [f64; 2],
    size: usize,
}

impl StateSpace {
    /// The state space of `form`, with every variance (`Qd`, `P0`, the measurement variance)
    /// times `scale2` (the square of a unit conversion; `Phi` and `h` do not change with the
    /// unit, `Q` takes its square root).
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
                h: [1.0, 0.0],
                size: 1,
            });
            states.push(format!("gauss_markov[{i}]"));
        }
        for (i, s) in form.osc[..form.osc_len.min(G)].iter().enumerate() {
            blocks.push(Block {
                phi: s.phi,
                q: s.q,
                p0: s.p0,
                h: [1.0, 0.0],
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
                h: [1.0, 0.0],
                size: 1,
            });
            states.push("random_walk".into());
        }
        if let Some(s) = form.quantization {
            blocks.push(Block {
                phi: s.phi,
                q: s.q,
                p0: s.p0,
                h: s.h,
                size: 2,
            });
            states.push("quantization (q_k/Dt)".into());
            states.push("quantization (q_(k-1)/Dt)".into());
        }
        let n = states.len();
        let scaled = |v: [[f64; 2]; 2]| v.map(|row| row.map(|x| x * scale2));
        Self {
            phi: matrix(n, &blocks, |b| b.phi),
            q: matrix(n, &blocks, |b| scaled(b.q)),
            p0: matrix(n, &blocks, |b| scaled(b.p0)),
            h: blocks
                .iter()
                .flat_map(|b| &b.h[..b.size])
                .copied()
                .collect(),
            states,
            measurement_variance: form.measurement_variance * scale2,
            quantization: form.quantization.map(|s| Quantization {
                value: s.coefficient * scale2.sqrt(),
                form: QUANTIZATION_FORM.into(),
            }),
            dt: form.dt,
        }
    }

    /// Whether every number is finite.
    pub fn is_finite(&self) -> bool {
        let cells = self.phi.iter().chain(&self.q).chain(&self.p0).flatten();
        cells
            .chain(&self.h)
            .chain([&self.measurement_variance, &self.dt])
            .chain(self.quantization.as_ref().map(|q| &q.value))
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
