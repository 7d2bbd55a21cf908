//! A composite model from its parts, validated: a model fitted elsewhere (on the host, or by
//! an earlier run of the firmware) given to the device.

use crate::model::ArModel;

use super::NoiseError;
use super::model::{GmTerm, NoiseModel, Oscillator};

/// The white-family and drift coefficients of a composite model (IEEE 952's `Q`, `N`, `K` and
/// `R`); see the [module docs](super) for their units.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub struct Coefficients {
    /// Quantisation `Q`, u s.
    pub quantization: f64,
    /// White noise `N` of the white term alone (without the AR part), u/sqrt(Hz).
    pub white: f64,
    /// Rate random walk `K`, u/s/sqrt(Hz).
    pub random_walk: f64,
    /// Rate ramp `R`, u/s.
    pub ramp: f64,
}

impl<const P: usize, const G: usize> NoiseModel<P, G> {
    /// A model of sample interval `dt` (s) from its coefficients, its first-order Gauss-Markov
    /// terms (by non-decreasing correlation time, as [`NoiseModel::fit`] gives them), its
    /// oscillators and its AR part; the unused term slots are zero. Every model the fit
    /// returns is accepted, and [`NoiseModel::coefficients`], [`NoiseModel::gauss_markov`],
    /// [`NoiseModel::oscillators`] and [`NoiseModel::ar`] give back what was passed.
    ///
    /// ```
    /// use imu_ar::noise::{Coefficients, GmTerm, NoiseError, NoiseModel};
    ///
    /// let white = Coefficients { white: 0.01, ..Coefficients::default() };
    /// let drift = [GmTerm { sigma: 0.002, correlation_time: 30.0 }];
    /// let model = NoiseModel::<1, 2>::new(0.01, white, &drift, &[], None)?;
    /// assert_eq!(model.gauss_markov(), &drift);
    /// let negative = Coefficients { white: -0.01, ..white };
    /// let refused = NoiseModel::<1, 2>::new(0.01, negative, &drift, &[], None);
    /// assert_eq!(refused, Err(NoiseError::Parameter));
    /// # Ok::<(), NoiseError>(())
    /// ```
    ///
    /// # Errors
    ///
    /// [`NoiseError::Interval`] for a `dt` that is not positive and finite;
    /// [`NoiseError::Budget`] for more than `G` Gauss-Markov terms or more than `G`
    /// oscillators; [`NoiseError::Parameter`] for a coefficient or `sigma` that is negative
    /// or not finite, a correlation time, decay time or frequency that is not positive and
    /// finite, or Gauss-Markov terms out of order; [`NoiseError::Ar`] for an AR part that is
    /// not stationary.
    pub fn new(
        dt: f64,
        coefficients: Coefficients,
        gauss_markov: &[GmTerm],
        oscillators: &[Oscillator],
        ar: Option<ArModel<f64, P>>,
    ) -> Result<Self, NoiseError> {
        if !(dt.is_finite() && dt > 0.0) {
            return Err(NoiseError::Interval);
        }
        for requested in [gauss_markov.len(), oscillators.len()] {
            if requested > G {
                return Err(NoiseError::Budget {
                    requested,
                    capacity: G,
                });
            }
        }
        let nonnegative = |v: f64| v.is_finite() && v >= 0.0;
        let positive = |v: f64| v.is_finite() && v > 0.0;
        let Coefficients {
            quantization,
            white,
            random_walk,
            ramp,
        } = coefficients;
        let coefficients_ok = [quantization, white, random_walk, ramp]
            .into_iter()
            .all(nonnegative);
        let terms_ok = gauss_markov
            .iter()
            .all(|t| nonnegative(t.sigma) && positive(t.correlation_time));
        let ordered = gauss_markov
            .windows(2)
            .all(|w| matches!(w, [p, q] if p.correlation_time <= q.correlation_time));
        let oscillators_ok = oscillators
            .iter()
            .all(|o| nonnegative(o.sigma) && positive(o.frequency) && positive(o.decay_time));
        if !(coefficients_ok && terms_ok && ordered && oscillators_ok) {
            return Err(NoiseError::Parameter);
        }
        if let Some(ar) = &ar {
            ar.reflection().map_err(NoiseError::Ar)?;
        }
        let mut gm = [GmTerm::default(); G];
        for (slot, t) in gm.iter_mut().zip(gauss_markov) {
            *slot = *t;
        }
        let mut osc = [Oscillator::default(); G];
        for (slot, o) in osc.iter_mut().zip(oscillators) {
            *slot = *o;
        }
        Ok(Self {
            dt,
            quantization,
            white,
            random_walk,
            ramp,
            gm,
            gm_len: gauss_markov.len(),
            osc,
            osc_len: oscillators.len(),
            ar,
        })
    }

    /// The coefficients `Q`, `N` (of the white term alone), `K` and `R`.
    pub fn coefficients(&self) -> Coefficients {
        Coefficients {
            quantization: self.quantization,
            white: self.white,
            random_walk: self.random_walk,
            ramp: self.ramp,
        }
    }

    /// Whether the model passes [`NoiseModel::new`]'s checks (every fitted model does).
    pub(crate) fn validate(&self) -> Result<(), NoiseError> {
        Self::new(
            self.dt,
            self.coefficients(),
            self.gauss_markov(),
            self.oscillators(),
            self.ar,
        )
        .map(|_| ())
    }
}
