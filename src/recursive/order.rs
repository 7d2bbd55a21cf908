//! Online order selection from the lattice's errors and energies of every order.

use super::{Config, FloatArith, Lattice};
use crate::Scalar;
use crate::batch::criteria::Criterion;

/// How [`OrderSelector`] scores the orders `0..=P`.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub enum OrderRule {
    /// Predictive least squares (Rissanen 1986; Wax 1988): the exponentially weighted sum of
    /// squared *a-priori* errors `Pi_k(n) = lambda Pi_k(n-1) + f_k(n)^2`. Needs no sample size
    /// or penalty: an over-fitted order predicts worse out of sample.
    Pls,
    /// [`Criterion::Aic`], `N_eff ln s2_k + 2k`, with `s2_k = F_k / W_n` and
    /// `N_eff = (1 + lambda)/(1 - lambda)`; at `lambda = 1` (growing memory) `N_eff` is the
    /// number of samples, [`Lattice::weight`].
    Aic,
    /// [`Criterion::Bic`], `N_eff ln s2_k + k ln N_eff`, with `N_eff` as for
    /// [`OrderRule::Aic`].
    Bic,
}

/// Chooses the model order online, with hysteresis so that it does not flap.
///
/// Every `interval` samples the rule's best order is found; the selected order changes only
/// after the same new order has won `patience` evaluations in a row. `O(P)` work per sample
/// (PLS sums), `O(P)` logarithms per evaluation (AIC, BIC).
///
/// For AIC and BIC the memory must be long enough for the orders to be told apart:
/// `N_eff >> P`.
#[derive(Clone, Copy, Debug)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub struct OrderSelector<T, const P: usize> {
    rule: OrderRule,
    interval: u32,
    patience: u32,
    /// PLS sums of orders 1..=P; `pls0` is order 0.
    pls: [T; P],
    pls0: T,
    countdown: u32,
    selected: usize,
    candidate: usize,
    streak: u32,
}

impl<T: FloatArith, const P: usize> OrderSelector<T, P> {
    /// A selector starting at order `P`; `interval` and `patience` are at least 1.
    pub fn new(rule: OrderRule, interval: u32, patience: u32) -> Self {
        let interval = interval.max(1);
        Self {
            rule,
            interval,
            patience: patience.max(1),
            pls: [T::ZERO; P],
            pls0: T::ZERO,
            countdown: interval,
            selected: P,
            candidate: P,
            streak: 0,
        }
    }

    /// The selected order, `0..=P`.
    pub fn order(&self) -> usize {
        self.selected
    }

    /// Call after every accepted [`update`](super::Estimator::update) of `lattice`; returns
    /// the selected order.
    pub fn update(&mut self, config: &Config<T>, lattice: &Lattice<T, P>) -> usize {
        let lambda = config.lambda();
        let y = lattice.input();
        self.pls0 = lambda * self.pls0 + y * y;
        for (pi, f) in self.pls.iter_mut().zip(lattice.errors()) {
            *pi = lambda * *pi + f * f;
        }
        self.countdown = self.countdown.saturating_sub(1);
        if self.countdown > 0 {
            return self.selected;
        }
        self.countdown = self.interval;
        // One huge sample the lattice accepted (it restarts and recovers) can make a sum
        // infinite, and `lambda inf` stays infinite: every score would be infinite for good.
        // Start the sums afresh instead, keeping the selected order.
        let total = self.pls.iter().fold(self.pls0, |s, &p| s + p);
        if !total.is_finite() {
            self.pls = [T::ZERO; P];
            self.pls0 = T::ZERO;
            self.streak = 0;
            return self.selected;
        }
        let best = self.best(config, lattice);
        if best == self.selected {
            self.streak = 0;
        } else {
            self.streak = if best == self.candidate {
                self.streak.saturating_add(1)
            } else {
                1
            };
            self.candidate = best;
            if self.streak >= self.patience {
                self.selected = best;
                self.streak = 0;
            }
        }
        self.selected
    }

    fn best(&self, config: &Config<T>, lattice: &Lattice<T, P>) -> usize {
        // At lambda = 1 (also an f32 lambda that rounds to 1) the memory grows: the effective
        // sample size is the number of samples since the start or the last restart.
        let n_eff = config
            .effective_samples()
            .unwrap_or_else(|| lattice.weight())
            .to_f64();
        let score = |k: usize| -> f64 {
            match self.rule {
                OrderRule::Pls => {
                    if k == 0 {
                        self.pls0.to_f64()
                    } else {
                        self.pls[k - 1].to_f64()
                    }
                }
                OrderRule::Aic | OrderRule::Bic => {
                    let s2 = lattice.innovation_variance(k).map_or(0.0, Scalar::to_f64);
                    if !(s2 > 0.0 && n_eff >= 1.0 && n_eff.is_finite()) {
                        return f64::INFINITY;
                    }
                    let criterion = match self.rule {
                        OrderRule::Aic => Criterion::Aic,
                        _ => Criterion::Bic,
                    };
                    criterion.formula(n_eff, k as f64, s2)
                }
            }
        };
        let mut best = (0, f64::INFINITY);
        for k in 0..=P {
            let s = score(k);
            if s < best.1 {
                best = (k, s);
            }
        }
        best.0
    }
}
