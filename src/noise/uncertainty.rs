//! 95 % intervals of a model's parameters from the sampling distribution of the octave Allan
//! variances ([`NoiseModel::uncertainty`]).

use super::component;
use super::fit::{Column, Problem, RECORD_OCTAVES};
use super::model::NoiseModel;
use super::octaves::{DRIFT_OCTAVES, chi2_quantile_over_nu};
use super::{NoiseError, NoiseType, Octaves, indexed};

/// The most parameters whose covariance is computed: white noise, quantisation, random walk,
/// ramp and the AR part's scale, two per Gauss-Markov term and three per oscillator.
pub const MAX_PARAMETERS: usize = 32;

/// The normal quantile of a two-sided 95 % interval.
pub(super) const Z95: f64 = 1.959_963_984_540_054;

/// Doublings, and then bisections, of the search for an absent term's room.
const ROOM_STEPS: usize = 40;

/// Relative step of the numerical derivatives in `ln T` and `ln f`.
const STEP: f64 = 1e-4;

/// A 95 % interval, `low <= high`, in the parameter's unit (`high` infinite when the data do
/// not bound it).
#[derive(Clone, Copy, Debug, Default, PartialEq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub struct Interval {
    /// Lower end.
    pub low: f64,
    /// Upper end.
    pub high: f64,
}

impl Interval {
    /// Whether `v` is inside.
    pub fn contains(&self, v: f64) -> bool {
        self.low <= v && v <= self.high
    }
}

/// The intervals of a Gauss-Markov term.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub struct TermUncertainty {
    /// `sigma`, u.
    pub sigma: Interval,
    /// Correlation time `T`, s.
    pub correlation_time: Interval,
}

/// The intervals of an oscillator.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub struct OscillatorUncertainty {
    /// `sigma`, u.
    pub sigma: Interval,
    /// Frequency, Hz.
    pub frequency: Interval,
    /// Decay time, s.
    pub decay_time: Interval,
}

/// The 95 % intervals of a model's parameters ([`NoiseModel::uncertainty`]), and of its Allan
/// deviation at every octave (the band a plot draws).
#[derive(Clone, Copy, Debug, PartialEq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub struct Uncertainty<const G: usize, const L: usize> {
    /// `N` of the whole model (white term and the AR part's white equivalent), u/sqrt(Hz).
    pub white_noise: Interval,
    /// `Q`, u s; from 0 when the model has none.
    pub quantization: Interval,
    /// `K`, u/s/sqrt(Hz); from 0 when the model has none or the data do not exclude 0.
    pub random_walk: Interval,
    /// `R`, u/s; from 0 when the model has none.
    pub ramp: Interval,
    /// `B`, u: the data's minimum Allan deviation over 0.664, with that octave's degrees of
    /// freedom.
    pub bias_instability: Interval,
    gm: [TermUncertainty; G],
    gm_len: usize,
    osc: [OscillatorUncertainty; G],
    osc_len: usize,
    band: [Interval; L],
    band_len: usize,
}

impl<const G: usize, const L: usize> Uncertainty<G, L> {
    /// The Gauss-Markov terms', in the model's order.
    pub fn gauss_markov(&self) -> &[TermUncertainty] {
        &self.gm[..self.gm_len.min(G)]
    }

    /// The oscillators', in the model's order.
    pub fn oscillators(&self) -> &[OscillatorUncertainty] {
        &self.osc[..self.osc_len.min(G)]
    }

    /// The model's Allan deviation at `tau = 2^j dt`, u.
    pub fn adev_band(&self) -> &[Interval] {
        &self.band[..self.band_len.min(L)]
    }
}

impl<const G: usize, const L: usize> Uncertainty<G, L> {
    /// The intervals of the model with every variance times `2^exponent`: the coefficients,
    /// `sigma`s, `B` and the band times `2^(exponent / 2)`; times and frequencies as they are.
    fn scaled(mut self, exponent: i32) -> Self {
        let root = |v: f64| libm::sqrt(libm::scalbn(v * v, exponent));
        let interval = |i: &mut Interval| {
            i.low = root(i.low);
            i.high = root(i.high);
        };
        for i in [
            &mut self.white_noise,
            &mut self.quantization,
            &mut self.random_walk,
            &mut self.ramp,
            &mut self.bias_instability,
        ] {
            interval(i);
        }
        for t in self.gm.iter_mut() {
            interval(&mut t.sigma);
        }
        for o in self.osc.iter_mut() {
            interval(&mut o.sigma);
        }
        for b in self.band.iter_mut() {
            interval(b);
        }
        self
    }
}

/// One parameter of the covariance.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
enum Parameter {
    /// The variance of a column (`N^2`, `Q^2`, `K^2`, `R^2`, `sigma^2`, the AR part's scale).
    #[default]
    None,
    Variance(Column),
    /// `ln T` of Gauss-Markov term `i`.
    LnCorrelationTime(usize),
    /// `ln f` of oscillator `i`.
    LnFrequency(usize),
    /// `ln T` of oscillator `i`.
    LnDecay(usize),
}

/// The covariance of a list of parameters: the inverse of the Fisher information
/// `J^T W^T C^-1 W J / 2`.
struct Covariance {
    parameters: [Parameter; MAX_PARAMETERS],
    len: usize,
    cov: [[f64; MAX_PARAMETERS]; MAX_PARAMETERS],
    /// The misfit's inflation (reduced `chi^2`, at least 1).
    scale: f64,
}

impl Covariance {
    fn index(&self, p: Parameter) -> Option<usize> {
        self.parameters[..self.len.min(MAX_PARAMETERS)]
            .iter()
            .position(|q| *q == p)
    }

    fn get(&self, i: usize, k: usize) -> f64 {
        self.scale
            * self
                .cov
                .get(i)
                .and_then(|row| row.get(k))
                .copied()
                .unwrap_or(f64::INFINITY)
    }

    fn variance(&self, p: Parameter) -> f64 {
        self.index(p).map_or(f64::INFINITY, |i| self.get(i, i))
    }
}

impl<const P: usize, const G: usize> NoiseModel<P, G> {
    /// 95 % intervals of every parameter, from the sampling distribution of the octave Allan
    /// variances the model was fitted to.
    ///
    /// Each octave's estimate has the variance `2 AVAR^2 / nu`, `nu` its equivalent degrees of
    /// freedom for the noise that dominates the model there ([`super::Estimator::edf`]), and
    /// neighbouring octaves are correlated ([`super::Estimator::octave_correlation`]). The
    /// covariance of the parameters is the inverse of the Fisher information of that
    /// distribution at the model (the variances, and the logarithms of the correlation times,
    /// frequencies and decay times, the latter by numerical derivatives). Then:
    ///
    /// - a variance `v` (`N^2`, `Q^2`, `K^2`, `R^2`, `sigma^2`) with standard deviation `s` has
    ///   the interval of a chi^2 estimate with `2 (v / s)^2` degrees of freedom, or
    ///   `[0, v + 1.96 s]` where `v < 1.96 s` (the data do not exclude 0); `N`, `Q`, `K`, `R`
    ///   and `sigma` are the square roots;
    /// - a coefficient the model does not have (no random walk, say) gets `[0, high]`, `high`
    ///   the largest value with which the model still passes the Allan check as one test of
    ///   the whole curve, and at least `1.96 s`, `s` from the information with that term added
    ///   at 0: the room the record leaves for it;
    /// - correlation times, frequencies and decay times are log-normal;
    /// - `B` is read from the data, with the degrees of freedom of its octave;
    /// - where the record's parts show its short-term level moving more than sampling explains
    ///   ([`Octaves::with_parts`]), `N^2`'s variance gains that movement's.
    ///
    /// Checked by simulation over the campaign of `host-tests` (`campaign`): the intervals of
    /// `N` and `K` contain the truth in 85 to 99 % of the records.
    ///
    /// # Errors
    ///
    /// [`NoiseError::Capacity`] for more than [`MAX_PARAMETERS`] parameters;
    /// [`NoiseError::Ar`] when the AR part is not stationary.
    pub fn uncertainty<const L: usize>(
        &self,
        octaves: &Octaves<L>,
    ) -> Result<Uncertainty<G, L>, NoiseError> {
        // In units where the largest Allan variance is about 1, as the fit works (a power of two
        // away, so that the scaling is exact): the information holds variances squared, which
        // leave f64 for Allan deviations past 1e77 or below 1e-77.
        let largest = octaves.avar().iter().copied().fold(0.0, f64::max);
        let exponent = if largest.is_normal() {
            libm::ilogb(largest)
        } else {
            0
        };
        let model = self.scaled(exponent.saturating_neg())?;
        let unit = model.uncertainty_unit(&octaves.scaled(exponent.saturating_neg()))?;
        Ok(unit.scaled(exponent))
    }

    /// [`NoiseModel::uncertainty`] in the units of `octaves`.
    fn uncertainty_unit<const L: usize>(
        &self,
        octaves: &Octaves<L>,
    ) -> Result<Uncertainty<G, L>, NoiseError> {
        let rows = octaves.avar().len().min(L);
        let mut problem = Problem {
            octaves,
            ar: self.ar.as_ref(),
            ar_curve: [0.0; L],
            weight: [0.0; L],
            rho: [0.0; L],
            correlated: true,
        };
        if let Some(ar) = &self.ar {
            component::ar_octaves(ar, &mut problem.ar_curve[..rows]).map_err(NoiseError::Ar)?;
        }
        problem.reweight(Some(self));
        let (own, len) = self.parameters()?;
        let main = self.covariance(&problem, own.get(..len).unwrap_or(&[]))?;

        let interval_of = |p: Parameter, v: f64, cov: &Covariance| {
            root(variance_interval(v, libm::sqrt(cov.variance(p))))
        };
        // N^2 = N_w^2 + s N_ar^2 (s the AR part's scale, 1 at the model).
        let n_ar2 = self.ar_white_psd();
        let white = Parameter::Variance(Column::White);
        let ar = Parameter::Variance(Column::Ar);
        let n2_variance = match (main.index(white), main.index(ar)) {
            (Some(w), Some(a)) => {
                main.get(w, w) + 2.0 * n_ar2 * main.get(w, a) + n_ar2 * n_ar2 * main.get(a, a)
            }
            (Some(w), None) => main.get(w, w),
            _ => f64::INFINITY,
        };
        // Where the record's short-term level moves between its parts more than sampling
        // explains, N^2 varies with it.
        let n2 = self.white * self.white + n_ar2;
        let mut curve = [0.0; L];
        self.avar_octaves(&mut curve[..rows])?;
        let drift = self.level_drift_unit(octaves)?.map_or(0.0, |(_, d)| d);
        let white_noise = root(variance_interval(
            n2,
            libm::sqrt(n2_variance.max(0.0) + n2 * n2 * drift),
        ));
        // The random walk's rise may be shared with a Gauss-Markov term as long as the record
        // tells (`tau_max / RECORD_OCTAVES`: a longer one the identification takes as the walk
        // itself): K's interval allows for one.
        let reach = octaves.tau(rows.saturating_sub(1)) / RECORD_OCTAVES;
        let near = self
            .gauss_markov()
            .iter()
            .any(|t| t.correlation_time > reach / 2.0 && t.correlation_time < reach * 2.0);
        let walk_cov = if self.random_walk > 0.0 && !near && reach > 2.0 * self.dt {
            let mut with = own;
            let slot = with.get_mut(len).ok_or(NoiseError::Capacity)?;
            *slot = Parameter::Variance(Column::GaussMarkov(reach));
            Some(self.covariance(&problem, with.get(..len.saturating_add(1)).unwrap_or(&[]))?)
        } else {
            None
        };
        let coefficient = |value: f64, column: Column| -> Result<Interval, NoiseError> {
            let p = Parameter::Variance(column);
            if value > 0.0 {
                let cov = match (&walk_cov, column) {
                    (Some(c), Column::RandomWalk) => c,
                    _ => &main,
                };
                return Ok(interval_of(p, value * value, cov));
            }
            // Absent: how large the data leave room for, with the term added at 0.
            let mut with = own;
            let slot = with.get_mut(len).ok_or(NoiseError::Capacity)?;
            *slot = p;
            let cov =
                self.covariance(&problem, with.get(..len.saturating_add(1)).unwrap_or(&[]))?;
            let s = libm::sqrt(cov.variance(p));
            Ok(root(Interval {
                low: 0.0,
                high: self.room(octaves, column, Z95 * s)?,
            }))
        };
        let quantization = coefficient(self.quantization, Column::Quantization)?;
        let random_walk = coefficient(self.random_walk, Column::RandomWalk)?;
        let ramp = coefficient(self.ramp, Column::Ramp)?;

        let log_normal = |value: f64, p: Parameter| {
            let s = libm::sqrt(main.variance(p));
            Interval {
                low: value * libm::exp(-Z95 * s),
                high: value * libm::exp(Z95 * s),
            }
        };
        let mut gm = [TermUncertainty::default(); G];
        for (i, (slot, t)) in indexed(gm.iter_mut().zip(self.gauss_markov())) {
            let column = Column::GaussMarkov(t.correlation_time);
            *slot = TermUncertainty {
                sigma: interval_of(Parameter::Variance(column), t.sigma * t.sigma, &main),
                correlation_time: log_normal(t.correlation_time, Parameter::LnCorrelationTime(i)),
            };
        }
        let mut osc = [OscillatorUncertainty::default(); G];
        for (i, (slot, o)) in indexed(osc.iter_mut().zip(self.oscillators())) {
            let column = Column::Oscillator(o.frequency, o.decay_time);
            *slot = OscillatorUncertainty {
                sigma: interval_of(Parameter::Variance(column), o.sigma * o.sigma, &main),
                frequency: log_normal(o.frequency, Parameter::LnFrequency(i)),
                decay_time: log_normal(o.decay_time, Parameter::LnDecay(i)),
            };
        }

        // The model's Allan variance at each octave, and its standard deviation from the
        // parameters' covariance.
        let mut band = [Interval::default(); L];
        for (j, (slot, a)) in indexed(band.iter_mut().zip(&curve).take(rows)) {
            let mut g = [0.0; MAX_PARAMETERS];
            for (gk, p) in g.iter_mut().zip(own.get(..len).unwrap_or(&[])) {
                *gk = self.derivative(&problem, *p, j);
            }
            let mut var = 0.0;
            for (i, gi) in indexed(g.iter().take(len)) {
                for (k, gk) in indexed(g.iter().take(len)) {
                    var += gi * main.get(i, k) * gk;
                }
            }
            let s = libm::sqrt(var.max(0.0)) / a.max(f64::MIN_POSITIVE);
            *slot = Interval {
                low: libm::sqrt(a * libm::exp(-Z95 * s)),
                high: libm::sqrt(a * libm::exp(Z95 * s)),
            };
        }

        Ok(Uncertainty {
            white_noise,
            quantization,
            random_walk,
            ramp,
            bias_instability: bias_instability(self, octaves),
            gm,
            gm_len: self.gm_len.min(G),
            osc,
            osc_len: self.osc_len.min(G),
            band,
            band_len: rows,
        })
    }

    /// The movement of the record's short-term level that [`NoiseModel::uncertainty`] counts
    /// in `N`'s interval: the largest [`Octaves::drift`] of the octaves where white noise
    /// (with the AR part's white equivalent) makes at least half this model's Allan variance,
    /// with its octave; `None` where there is none.
    ///
    /// # Errors
    ///
    /// [`NoiseError::Ar`] when the AR part is not stationary.
    pub fn level_drift<const L: usize>(
        &self,
        octaves: &Octaves<L>,
    ) -> Result<Option<(usize, f64)>, NoiseError> {
        // In units where the largest Allan variance is about 1, as `uncertainty` works.
        let largest = octaves.avar().iter().copied().fold(0.0, f64::max);
        let exponent = if largest.is_normal() {
            libm::ilogb(largest)
        } else {
            0
        };
        self.scaled(exponent.saturating_neg())?
            .level_drift_unit(&octaves.scaled(exponent.saturating_neg()))
    }

    /// [`NoiseModel::level_drift`] in the units of `octaves`.
    fn level_drift_unit<const L: usize>(
        &self,
        octaves: &Octaves<L>,
    ) -> Result<Option<(usize, f64)>, NoiseError> {
        let rows = octaves.avar().len().min(L).min(DRIFT_OCTAVES);
        let mut curve = [0.0; DRIFT_OCTAVES];
        self.avar_octaves(&mut curve[..rows])?;
        let n2 = self.white * self.white + self.ar_white_psd();
        Ok(indexed(curve.iter().take(rows))
            .filter(|(j, a)| n2 / octaves.tau(*j) >= 0.5 * **a && octaves.drift(*j) > 0.0)
            .map(|(j, _)| (j, octaves.drift(j)))
            .max_by(|a, b| a.1.total_cmp(&b.1)))
    }

    /// The standard deviation of `ln T` of each Gauss-Markov term, with `problem` weighted by
    /// this model.
    pub(super) fn log_time_spread<const L: usize>(
        &self,
        problem: &Problem<'_, P, L>,
    ) -> Result<[f64; G], NoiseError> {
        let (own, len) = self.parameters()?;
        let cov = self.covariance(problem, own.get(..len).unwrap_or(&[]))?;
        let mut out = [f64::INFINITY; G];
        for (i, slot) in indexed(out.iter_mut().take(self.gm_len)) {
            *slot = libm::sqrt(cov.variance(Parameter::LnCorrelationTime(i)));
        }
        Ok(out)
    }

    /// Whether the random walk's variance is more than one standard deviation above zero,
    /// with `problem` weighted by this model.
    pub(super) fn walk_significant<const L: usize>(
        &self,
        problem: &Problem<'_, P, L>,
    ) -> Result<bool, NoiseError> {
        let (own, len) = self.parameters()?;
        let cov = self.covariance(problem, own.get(..len).unwrap_or(&[]))?;
        let k2 = self.random_walk * self.random_walk;
        Ok(k2 > libm::sqrt(cov.variance(Parameter::Variance(Column::RandomWalk))))
    }

    /// The largest variance of the absent coefficient `column` (quantisation, random walk or
    /// ramp) with which the model still passes the Allan check as one test of the whole curve
    /// ([`NoiseModel::check_whole`]), at least `start`: the room the record leaves for it. The
    /// information at zero alone understates it where the model is far below the data's noise
    /// at the octaves the term would raise. Doubling, then bisection on the logarithm.
    fn room<const L: usize>(
        &self,
        octaves: &Octaves<L>,
        column: Column,
        start: f64,
    ) -> Result<f64, NoiseError> {
        let passes = |v: f64| -> Result<bool, NoiseError> {
            let mut with = *self;
            let root = libm::sqrt(v);
            match column {
                Column::Quantization => with.quantization = root,
                Column::RandomWalk => with.random_walk = root,
                Column::Ramp => with.ramp = root,
                _ => return Ok(false),
            }
            Ok(with.check_whole(octaves)?.holds())
        };
        if !(start.is_finite() && start > 0.0 && passes(start)?) {
            return Ok(start);
        }
        let (mut lo, mut hi) = (start, start);
        for _ in 0..ROOM_STEPS {
            hi *= 2.0;
            if !hi.is_finite() || !passes(hi)? {
                break;
            }
            lo = hi;
        }
        if lo == hi {
            return Ok(lo);
        }
        for _ in 0..ROOM_STEPS {
            let mid = libm::sqrt(lo * hi);
            if passes(mid)? {
                lo = mid;
            } else {
                hi = mid;
            }
        }
        Ok(lo)
    }

    /// The model's own parameters (see [`NoiseModel::uncertainty`]).
    fn parameters(&self) -> Result<([Parameter; MAX_PARAMETERS], usize), NoiseError> {
        let mut own = [Parameter::None; MAX_PARAMETERS];
        let mut len = 0usize;
        let mut push = |p: Parameter, list: &mut [Parameter; MAX_PARAMETERS]| {
            let slot = list.get_mut(len).ok_or(NoiseError::Capacity)?;
            *slot = p;
            len = len.saturating_add(1);
            Ok::<(), NoiseError>(())
        };
        push(Parameter::Variance(Column::White), &mut own)?;
        let present = [
            (self.quantization, Column::Quantization),
            (self.random_walk, Column::RandomWalk),
            (self.ramp, Column::Ramp),
        ];
        for (_, c) in present.iter().filter(|(v, _)| *v > 0.0) {
            push(Parameter::Variance(*c), &mut own)?;
        }
        if self.ar.is_some() {
            push(Parameter::Variance(Column::Ar), &mut own)?;
        }
        for (i, t) in indexed(self.gauss_markov().iter()) {
            push(
                Parameter::Variance(Column::GaussMarkov(t.correlation_time)),
                &mut own,
            )?;
            push(Parameter::LnCorrelationTime(i), &mut own)?;
        }
        for (i, o) in indexed(self.oscillators().iter()) {
            let column = Column::Oscillator(o.frequency, o.decay_time);
            push(Parameter::Variance(column), &mut own)?;
            push(Parameter::LnFrequency(i), &mut own)?;
            push(Parameter::LnDecay(i), &mut own)?;
        }
        Ok((own, len))
    }

    /// `d AVAR_j / d p` at the model.
    fn derivative<const L: usize>(
        &self,
        problem: &Problem<'_, P, L>,
        p: Parameter,
        j: usize,
    ) -> f64 {
        let (up, down) = (libm::exp(STEP), libm::exp(-STEP));
        let central = |f: &dyn Fn(f64) -> Column, v: f64| {
            (problem.unit(f(v * up), j) - problem.unit(f(v * down), j)) / (2.0 * STEP)
        };
        match p {
            Parameter::None => 0.0,
            Parameter::Variance(c) => problem.unit(c, j),
            Parameter::LnCorrelationTime(i) => self.gauss_markov().get(i).map_or(0.0, |t| {
                t.sigma * t.sigma * central(&Column::GaussMarkov, t.correlation_time)
            }),
            Parameter::LnFrequency(i) => self.oscillators().get(i).map_or(0.0, |o| {
                let at = |f: f64| Column::Oscillator(f, o.decay_time);
                o.sigma * o.sigma * central(&at, o.frequency)
            }),
            Parameter::LnDecay(i) => self.oscillators().get(i).map_or(0.0, |o| {
                let at = |t: f64| Column::Oscillator(o.frequency, t);
                o.sigma * o.sigma * central(&at, o.decay_time)
            }),
        }
    }

    /// The covariance of `parameters` at the model: `2 (J~^T J~)^-1` with `J~` the weighted,
    /// whitened Jacobian, its columns scaled to unit norm for the solve.
    // One frame, reused by every call (inlined, each call's matrices would stack up).
    #[inline(never)]
    fn covariance<const L: usize>(
        &self,
        problem: &Problem<'_, P, L>,
        parameters: &[Parameter],
    ) -> Result<Covariance, NoiseError> {
        let rows = problem.octaves.avar().len().min(L);
        let k = parameters.len();
        if k > MAX_PARAMETERS {
            return Err(NoiseError::Capacity);
        }
        let mut jac = [[0.0; L]; MAX_PARAMETERS];
        let mut norm = [0.0; MAX_PARAMETERS];
        for ((col, p), c) in jac.iter_mut().zip(parameters).zip(norm.iter_mut()) {
            for (j, (v, w)) in indexed(col.iter_mut().zip(&problem.weight).take(rows)) {
                *v = w * self.derivative(problem, *p, j);
            }
            problem.whiten(&mut col[..rows]);
            let big = col.iter().fold(0.0f64, |m, v| m.max(libm::fabs(*v)));
            *c = if big > 0.0 && big.is_finite() {
                big * libm::sqrt(col.iter().map(|v| (v / big) * (v / big)).sum::<f64>())
            } else {
                0.0
            };
            if *c > 0.0 {
                col.iter_mut().for_each(|v| *v /= *c);
            }
        }
        // The Gram matrix of the unit columns, and its inverse by Cholesky; a pivot that
        // vanishes (a parameter the data do not determine) leaves that parameter's variance
        // infinite.
        let mut gram = [[0.0; MAX_PARAMETERS]; MAX_PARAMETERS];
        for (i, row) in indexed(gram.iter_mut().take(k)) {
            for (l, g) in indexed(row.iter_mut().take(k)) {
                if let (Some(a), Some(b)) = (jac.get(i), jac.get(l)) {
                    *g = a.iter().zip(b).map(|(x, y)| x * y).sum();
                }
            }
        }
        let inverse = cholesky_inverse(&gram, k);
        let mut cov = [[0.0; MAX_PARAMETERS]; MAX_PARAMETERS];
        for (i, row) in indexed(cov.iter_mut().take(k)) {
            for (l, v) in indexed(row.iter_mut().take(k)) {
                let (ci, cl) = (
                    norm.get(i).copied().unwrap_or(0.0),
                    norm.get(l).copied().unwrap_or(0.0),
                );
                let g = inverse
                    .get(i)
                    .and_then(|r| r.get(l))
                    .copied()
                    .unwrap_or(0.0);
                *v = if ci > 0.0 && cl > 0.0 {
                    2.0 * g / (ci * cl)
                } else if i == l {
                    f64::INFINITY
                } else {
                    0.0
                };
            }
        }
        let mut list = [Parameter::None; MAX_PARAMETERS];
        list.iter_mut().zip(parameters).for_each(|(d, s)| *d = *s);
        // The misfit at the model: where it is larger than its degrees of freedom allow, the
        // model does not describe the data as well as its information says (a term missed or
        // misplaced), and every variance is scaled up by the reduced chi^2.
        let mut r = [0.0; L];
        let mut curve = [0.0; L];
        self.avar_octaves(&mut curve[..rows])?;
        let data = problem.octaves.avar();
        let cells = r.iter_mut().zip(&problem.weight).zip(&curve).zip(data);
        for (((v, w), m), d) in cells.take(rows) {
            *v = w * (m - d);
        }
        problem.whiten(&mut r[..rows]);
        let chi2: f64 = r.iter().map(|v| v * v / 2.0).sum();
        let informative = problem.weight.iter().take(rows).fold(0usize, |n, w| {
            if *w > 0.0 { n.saturating_add(1) } else { n }
        });
        let dof = informative.saturating_sub(k);
        let scale = if dof > 0 {
            (chi2 / dof as f64).max(1.0)
        } else {
            1.0
        };
        Ok(Covariance {
            parameters: list,
            len: k,
            cov,
            scale: if scale.is_finite() { scale } else { 1.0 },
        })
    }
}

/// The inverse of the symmetric positive semi-definite `a[..k][..k]` by Cholesky; a pivot
/// below `1e-12` (of a unit diagonal) is taken as 1e-12, so that an undetermined parameter gets a
/// huge variance instead of a failure.
#[allow(clippy::needless_range_loop)] // triangular loops over a fixed-size matrix read best by index
#[inline(never)]
fn cholesky_inverse(
    a: &[[f64; MAX_PARAMETERS]; MAX_PARAMETERS],
    k: usize,
) -> [[f64; MAX_PARAMETERS]; MAX_PARAMETERS] {
    const FLOOR: f64 = 1e-12;
    let k = k.min(MAX_PARAMETERS);
    let mut l = [[0.0; MAX_PARAMETERS]; MAX_PARAMETERS];
    for i in 0..k {
        for j in 0..=i {
            let mut s = a[i][j];
            for m in 0..j {
                s -= l[i][m] * l[j][m];
            }
            if i == j {
                l[i][i] = libm::sqrt(s.max(FLOOR));
            } else {
                l[i][j] = s / l[j][j];
            }
        }
    }
    // L^-1, then (L^-1)^T L^-1.
    let mut li = [[0.0; MAX_PARAMETERS]; MAX_PARAMETERS];
    for c in 0..k {
        for i in c..k {
            let mut s = if i == c { 1.0 } else { 0.0 };
            for m in c..i {
                s -= l[i][m] * li[m][c];
            }
            li[i][c] = s / l[i][i];
        }
    }
    let mut inv = [[0.0; MAX_PARAMETERS]; MAX_PARAMETERS];
    for i in 0..k {
        for j in 0..k {
            let mut s = 0.0;
            for m in i.max(j)..k {
                s += li[m][i] * li[m][j];
            }
            inv[i][j] = s;
        }
    }
    inv
}

/// The interval of a variance `v` with standard deviation `s`: a chi^2 estimate of
/// `2 (v / s)^2` degrees of freedom (Wilson-Hilferty quantiles), or `[0, v + 1.96 s]` where the
/// data do not exclude 0.
fn variance_interval(v: f64, s: f64) -> Interval {
    if !(s.is_finite() && v.is_finite()) {
        return Interval {
            low: 0.0,
            high: f64::INFINITY,
        };
    }
    if v <= Z95 * s || s <= 0.0 {
        return Interval {
            low: if s <= 0.0 { v } else { 0.0 },
            high: v + Z95 * s,
        };
    }
    let nu = 2.0 * (v / s) * (v / s);
    Interval {
        low: v / chi2_quantile_over_nu(nu, Z95),
        high: v / chi2_quantile_over_nu(nu, -Z95).max(f64::MIN_POSITIVE),
    }
}

/// The square roots of a variance's interval.
fn root(i: Interval) -> Interval {
    Interval {
        low: libm::sqrt(i.low.max(0.0)),
        high: libm::sqrt(i.high.max(0.0)),
    }
}

/// `B` of the data (minimum Allan deviation over 0.664) with the chi^2 interval of its
/// octave's estimate.
fn bias_instability<const P: usize, const G: usize, const L: usize>(
    model: &NoiseModel<P, G>,
    octaves: &Octaves<L>,
) -> Interval {
    let data = octaves.avar();
    let lowest = indexed(data.iter()).min_by(|p, q| p.1.total_cmp(q.1));
    let Some((j, a)) = lowest else {
        return Interval::default();
    };
    let kind = model.dominant(1u64 << j.min(63)).0;
    let kind = if kind == NoiseType::WhitePhase {
        NoiseType::WhiteFrequency
    } else {
        kind
    };
    let nu = octaves.edf(j, kind);
    let b = |q: f64| libm::sqrt(*a / q) / 0.664;
    Interval {
        low: b(chi2_quantile_over_nu(nu, Z95)),
        high: b(chi2_lower_over_nu(nu)),
    }
}

/// `chi^2_nu / nu` at its 2.5 % quantile: Wilson-Hilferty, and below a few degrees of freedom,
/// where that reaches 0, the lower tail `P(chi^2 < x) ~ (x/2)^(nu/2) / Gamma(nu/2 + 1)`.
fn chi2_lower_over_nu(nu: f64) -> f64 {
    // In logarithms: Gamma(nu/2 + 1) overflows f64 beyond 340 degrees of freedom, and the tail
    // then read infinite, which put the interval's upper end at 0.
    let ln_tail = (libm::log(0.025) + libm::lgamma(nu / 2.0 + 1.0)) * 2.0 / nu;
    let tail = 2.0 * libm::exp(ln_tail) / nu;
    let q = chi2_quantile_over_nu(nu, -Z95).max(tail);
    if q > 0.0 { q } else { f64::MIN_POSITIVE }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_lower_quantile_holds_at_every_degree_of_freedom() {
        // Beyond 340 degrees of freedom Gamma(nu/2 + 1) overflows f64: the quantile read
        // infinite, and B's interval had its upper end at 0, below its value.
        let mut previous = 0.0;
        for nu in [0.5, 1.0, 2.0, 4.0, 10.0, 100.0, 340.0, 400.0, 1e4, 1e6, 1e9] {
            let q = chi2_lower_over_nu(nu);
            assert!(q.is_finite() && q > 0.0 && q < 1.0, "nu {nu}: {q}");
            assert!(q > previous, "nu {nu}: {q} after {previous}");
            previous = q;
        }
        // The 2.5 % quantile of chi^2_400 / 400 is 0.8667.
        assert!((chi2_lower_over_nu(400.0) / 0.8667 - 1.0).abs() < 2e-3);
    }
}
