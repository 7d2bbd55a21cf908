//! The joint-process (ladder) part of a lattice that starts from a prior model `a0`.
//!
//! With a prior, the problem of the [module docs](super) is centred on `a0`:
//!
//! ```text
//! a_n = argmin_a  sum_{i=1..n} lambda^(n-i) (y_i - a^T phi_i)^2 + delta lambda^n (a - a0)^T D (a - a0)
//! ```
//!
//! With `a = a0 + b` and `d_i = y_i - a0^T phi_i` it is the joint-process problem
//! `b_n = argmin_b sum lambda^(n-i) (d_i - b^T phi_i)^2 + delta lambda^n b^T D b`: a desired
//! signal `d` regressed on the same delay line of `y`. The lattice's backward errors
//! `psi_i(n-1)` orthogonalise that delay line whatever the desired signal is, so `b` needs
//! only a ladder of `P` more coefficients `c_1..c_P`, updated with the error feedback of the
//! forward stages (Ling, Manolakis & Proakis 1986, the joint-process form):
//!
//! ```text
//! e_0       = d_n = y_n - a0^T phi_n
//! e_{i+1}   = e_i - c_{i+1} bp_i                              a-priori joint-process error
//! c_{i+1}  <- c_{i+1} + (gp_i bp_i) e_{i+1} / B_i             B_i still B_i(n-1)
//! E        <- lambda E + gp_P e_P^2                           E_0 = delta lambda^P
//! ```
//!
//! run on the lattice's state before it takes the sample (`bp_i = psi_i(n-1)`,
//! `gp_i = gamma_i(n-1)`, `B_i(n-1)`). The forward stages are this ladder for `d = y`: with
//! `a0 = 0` the ladder computes the forward chain's `f_P`, `kf` and `F_P` bit for bit. The
//! coefficients follow from the ladder's as the forward ones from `kf`:
//! `a_n = a0 + sum_k c_k(n) B_{k-1}(n-1)`, the backward predictors of the time before
//! ([`Core::coefficients`](super::lattice::Core::coefficients)). `e_P` is the a-priori error
//! `y_n - a_{n-1}^T phi_n` of the centred problem and `E` its energy
//! `min J_n + delta lambda^(n+P)`.
//!
//! A start from a recorded history (a settled start, [`Settled`](super::Settled)) feeds the
//! history's samples through the lattice with `d = 0`: they fill the delay line and add their
//! regressors' Gram matrix `sum lambda^(n-i) phi_i phi_i^T` to the prior's weight, but no
//! equation of their own. See the [`Estimator`](super::Estimator) docs for the problem in full.

use super::arith::Arith;
use super::lattice::Core;

/// The ladder of a lattice with a prior: the centre `a0`, the delay line for `d_n`, the
/// coefficients `c` and the energy `E`.
#[derive(Clone, Copy, Debug)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub(crate) struct Ladder<A: Arith, const P: usize> {
    /// `a0`, in the coefficient format.
    pub(crate) centre: [A::Coef; P],
    /// `y_{n-1} .. y_{n-P}`.
    past: [A::Err; P],
    /// `c_1..c_P`.
    pub(crate) c: [A::Acc; P],
    /// `E`, the order-`P` energy of the centred problem.
    pub(crate) energy: A::Energy,
    /// `e_P(n)` of the last sample, the centred problem's a-priori error.
    pub(crate) error: A::Err,
}

impl<A: Arith, const P: usize> Ladder<A, P> {
    /// The initial state for centre `a0`: zero ladder coefficients, an empty delay line and
    /// `E = delta lambda^P`, the lattice's `F_P`.
    pub(crate) fn new(centre: [A::Coef; P], energy: A::Energy) -> Self {
        Self {
            centre,
            past: [A::ERR_ZERO; P],
            c: [A::ACC_ZERO; P],
            energy,
            error: A::ERR_ZERO,
        }
    }

    /// The a-priori error `e_P(n)` of `y_n`, without taking it (for the gate).
    pub(crate) fn a_priori(&self, core: &Core<A, P>, y: A::Err) -> A::Err {
        let mut clip = 0;
        let mut e = y;
        for (&a, &x) in self.centre.iter().zip(&self.past) {
            e = A::predict(e, a, x, &mut clip);
        }
        for (&c, stage) in self.c.iter().zip(&core.stages) {
            e = A::predict(e, A::coef(c), stage.bp, &mut clip);
        }
        e
    }

    /// Takes `y_n` on the state of `core` before [`Core::step`] takes it; keeps the
    /// a-priori error `e_P(n)` in `error` and returns it. A history sample (`equation = false`) enters the delay line
    /// only: `d_n = 0`, so that it adds no equation. Out of line: a lattice without a prior
    /// keeps the forward stages' code as it is.
    #[inline(never)]
    pub(crate) fn step(
        &mut self,
        core: &Core<A, P>,
        params: &A::Params,
        y: A::Err,
        equation: bool,
        clip: &mut u32,
    ) -> A::Err {
        let mut e = A::ERR_ZERO;
        if equation {
            e = y;
            for (&a, &x) in self.centre.iter().zip(&self.past) {
                e = A::predict(e, a, x, clip);
            }
        }
        for (c, stage) in self.c.iter_mut().zip(&core.stages) {
            let (bp, gp) = (stage.bp, stage.gp);
            let next = A::predict(e, A::coef(*c), bp, clip);
            let gbp = A::gain(gp, bp, clip);
            *c = A::feedback(*c, gbp, next, &stage.b_kept, clip);
            e = next;
        }
        let ge = A::gain(core.gp_p, e, clip);
        self.energy = A::energy(params, self.energy, ge, e, clip);
        self.past.rotate_right(1);
        if let Some(first) = self.past.first_mut() {
            *first = y;
        }
        self.error = e;
        e
    }
}
