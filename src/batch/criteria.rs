//! Order selection from the innovation variances of every order.
//!
//! With `s2_k` the innovation variance of order `k` and `N` the number of terms behind it
//! ([`Fit::n_effective`](super::Fit::n_effective)):
//!
//! | criterion | value | source |
//! |---|---|---|
//! | AIC | `N ln s2_k + 2k` | Akaike 1974, IEEE Trans. AC 19(6) |
//! | AICc | `AIC + 2(k+1)(k+2)/(N-k-2)` | Hurvich & Tsai 1989, Biometrika 76(2) |
//! | BIC / MDL | `N ln s2_k + k ln N` | Schwarz 1978; Rissanen 1978 |
//! | FPE | `s2_k (N+k+1)/(N-k-1)` | Akaike 1970, Ann. Inst. Statist. Math. 22 |
//!
//! A variance that is not positive and finite, or an `N` too small for the correction terms,
//! gives `+inf`, so that order is never selected.

/// An order-selection criterion.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub enum Criterion {
    /// Akaike's information criterion.
    Aic,
    /// AIC with the small-sample correction.
    Aicc,
    /// Schwarz's Bayesian criterion, equal to Rissanen's MDL.
    Bic,
    /// Akaike's final prediction error.
    Fpe,
}

impl Criterion {
    /// All four, in the order of the table above.
    pub const ALL: [Criterion; 4] = [Self::Aic, Self::Aicc, Self::Bic, Self::Fpe];

    /// The criterion's value for order `k` with innovation variance `s2` from `n` terms.
    ///
    /// ```
    /// use imu_ar::batch::criteria::Criterion;
    ///
    /// assert_eq!(Criterion::Aic.value(100, 2, 1.0), 4.0);
    /// assert_eq!(Criterion::Fpe.value(100, 0, 2.0), 2.0 * 101.0 / 99.0);
    /// ```
    pub fn value(self, n: usize, k: usize, s2: f64) -> f64 {
        if !(s2.is_finite() && s2 > 0.0) || n <= k + 2 {
            return f64::INFINITY;
        }
        self.formula(n as f64, k as f64, s2)
    }

    /// The formula of the table above for `n` terms, `k` coefficients and variance `s2`,
    /// without the range checks of [`Criterion::value`]: `n` may be an effective sample size
    /// (the [`OrderSelector`](crate::recursive::OrderSelector) scores with
    /// `(1 + lambda)/(1 - lambda)`), and the caller keeps it in range.
    pub(crate) fn formula(self, n: f64, k: f64, s2: f64) -> f64 {
        let fit = || n * libm::log(s2);
        match self {
            Self::Aic => fit() + 2.0 * k,
            Self::Aicc => fit() + 2.0 * k + 2.0 * (k + 1.0) * (k + 2.0) / (n - k - 2.0),
            Self::Bic => fit() + k * libm::log(n),
            Self::Fpe => s2 * (n + k + 1.0) / (n - k - 1.0),
        }
    }

    /// The order `0..` whose variance (the iterator's `k`-th item) minimises the criterion;
    /// the lowest such order on ties, 0 for an empty iterator.
    pub fn select(self, n: usize, variances: impl IntoIterator<Item = f64>) -> usize {
        let mut best = (0, f64::INFINITY);
        for (k, s2) in variances.into_iter().enumerate() {
            let v = self.value(n, k, s2);
            if v < best.1 {
                best = (k, v);
            }
        }
        best.0
    }
}
