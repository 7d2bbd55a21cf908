//! Recursive estimators: one sample in, an updated AR model out, online on the MCU.
//!
//! Every estimator here solves, after every sample, the prewindowed exponentially weighted
//! least-squares problem of numerics.md section 0 (`x_i = 0` for `i <= 0`):
//!
//! ```text
//! a_n = argmin_a  sum_{i=1..n} lambda^(n-i) (y_i - a^T phi_i)^2 + delta lambda^n a^T D a,
//! phi_i = [y_{i-1} .. y_{i-P}],   D = diag(lambda^(P-1), .., lambda, 1)
//! ```
//!
//! with `y = x - mean` (see [`RunningMean`]) or `y = x`. `D` is the one initial weighting that
//! the O(P) lattice can start from exactly; it is the problem's fictitious sample `sqrt(delta)` at
//! time `-P`. [`Rls`] can also start from the textbook `P_0 = I / delta` (ridge weight
//! `delta lambda^n ||a||^2`).
//!
//! | estimator | scalar | cost per sample | output |
//! |---|---|---|---|
//! | [`Lattice`] | `f32`, `f64` | `O(P)` (a-priori error-feedback LSL) | errors and energies of every order every sample; coefficients on request |
//! | [`FixedLattice`] | fixed point (I5F27 errors, I24F40 energies, ...) | `O(P)`, integer only | as the lattice, from `i16` counts or scaled floats; models in `f32` |
//! | [`Rls`] | `f32`, `f64` | `O(P^2)` (Bierman U-D) | coefficients every sample |
//! | [`Sftf`] | `f32`, `f64` | `O(P)` (stabilised fast transversal filter) | coefficients every sample; a divergence monitor restarts it when needed |
//!
//! All four implement [`Estimator`]: `update` takes a sample and returns the a-priori
//! prediction error, `model` the current [`ArModel`](crate::ArModel), `health` what happened to
//! the samples.
//!
//! A start from a known model. Every estimator can start from a prior `a0` instead
//! (`with_prior`): the regularisation is then centred on it, `delta lambda^n (a - a0)^T D
//! (a - a0)`, and `a0 = 0` is the problem above. [`Rls`] and [`Sftf`] solve it from `a = a0`
//! (the SFTF with a second transversal filter on its gain, since its forward predictor makes
//! the gain); the lattices with a joint-process ladder (the derivation is in `ladder.rs`'s
//! docs). All four are exact against the direct solve of that problem (`host-tests`, `prior`).
//! [`Settled`] holds the first `N` samples and starts from their batch fit, with the running
//! mean settled and no prewindowed equation: at `lambda = 1`, where the start is never
//! forgotten, that is the difference between 25 times batch least squares and batch least
//! squares ([Results](crate::guide::results)).
//!
//! Settings are split by what they belong to. A [`Config`] (forgetting factor, sample
//! interval, mean removal) is validated once and shared by the estimators of all the channels
//! of a sensor; `update` and `model` take it. A [`Channel`] (initial regularisation `delta`,
//! saturation limit, both in that channel's units) is given to each estimator when it is made,
//! and kept. The fixed-point lattice takes the same two, converted: [`FixedConfig`] and
//! [`FixedChannel`] (which adds the channel's scale to internal units).
//!
//! `update` is infallible and never panics: a NaN, infinite or saturated sample is rejected
//! and counted and changes nothing; a numerical breakdown re-initialises the state while the
//! last good model stays published ([`Health`] counts all three).

mod arith;
mod config;
mod estimator;
mod fixed_arith;
mod fixed_lattice;
mod ladder;
mod lattice;
mod mean;
mod order;
mod rls;
mod settled;
mod sftf;
mod shell;

pub use arith::FloatArith;
pub use config::{Channel, Config, ConfigError, Gate};
pub use estimator::Estimator;
pub use fixed_lattice::{FixedChannel, FixedConfig, FixedLattice};
pub use lattice::Lattice;
pub use mean::RunningMean;
pub use order::{OrderRule, OrderSelector};
pub use rls::{Rls, RlsInit};
pub use settled::{Settled, Start};
pub use sftf::Sftf;
pub use shell::{Health, snapshot_interval};
