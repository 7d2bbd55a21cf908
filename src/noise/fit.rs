//! Fitting a [`NoiseModel`] to octave Allan variances (`noise-model.md` section 2).

use crate::model::ArModel;

use super::columns::{compact, edit, head, head_mut, merge, sort_by_correlation_time, states};
use super::model::{Check, GmTerm, NoiseModel, Oscillator};
use super::{NoiseError, NoiseType, Octaves, component, indexed, nnls};

/// How to fit a [`NoiseModel`].
///
/// ```
/// use imu_ar::noise::FitConfig;
///
/// let config = FitConfig::new(3).with_spacing(0.5).unwrap().with_ramp(true);
/// assert_eq!(config.gm_states(), 3);
/// ```
#[derive(Clone, Copy, Debug, PartialEq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub struct FitConfig {
    gm_states: usize,
    spacing: f64,
    quantization: bool,
    ramp: bool,
    oscillators: bool,
    identify: bool,
}

impl FitConfig {
    /// At most `gm_states` Gauss-Markov terms (the caller's budget of Kalman states), a grid
    /// of correlation times one octave apart, with quantisation, without rate ramp.
    pub const fn new(gm_states: usize) -> Self {
        Self {
            gm_states,
            spacing: 1.0,
            quantization: true,
            ramp: false,
            oscillators: false,
            identify: false,
        }
    }

    /// Whether terms are identified (default: no): added one at a time while each lowers the
    /// misfit by more than an information criterion charges for it, their correlation times
    /// (an oscillator's frequency and decay) refined off the grid, a Gauss-Markov term that
    /// the record cannot tell from a random walk taken as one (see [`NoiseModel::identify`]).
    /// Without, every state of the budget is spent on the grid's best terms, as a pure curve
    /// fit: a model that explains the Allan curve, whose parameters may not be the sensor's.
    /// The identification is checked by the campaign of `host-tests` (`campaign`).
    pub const fn with_identification(self, on: bool) -> Self {
        Self {
            identify: on,
            ..self
        }
    }

    /// The grid's spacing in octaves (the density of the grid is its inverse): correlation
    /// times `dt 2^(i s)` up to the longest `tau`.
    ///
    /// # Errors
    ///
    /// [`NoiseError::Spacing`] outside [0.5, 8].
    pub fn with_spacing(self, octaves: f64) -> Result<Self, NoiseError> {
        if !(0.5..=8.0).contains(&octaves) {
            return Err(NoiseError::Spacing);
        }
        Ok(Self {
            spacing: octaves,
            ..self
        })
    }

    /// Whether the model has a quantisation term (default: yes).
    pub const fn with_quantization(self, on: bool) -> Self {
        Self {
            quantization: on,
            ..self
        }
    }

    /// Whether the model has a rate-ramp term (default: no; in a static record a ramp is
    /// usually a temperature drift).
    pub const fn with_ramp(self, on: bool) -> Self {
        Self { ramp: on, ..self }
    }

    /// Whether the model may have second-order Gauss-Markov terms (damped oscillators, two
    /// states each; default: no), for a spectral line below the AR part's reach: candidates
    /// at `f = 0.371 / tau` for every octave from `8 dt`, down to [`OSCILLATOR_MIN_HZ`],
    /// decaying over [`OSCILLATOR_CYCLES`] periods; identified, a term's frequency and decay
    /// are then refined.
    pub const fn with_oscillators(self, on: bool) -> Self {
        Self {
            oscillators: on,
            ..self
        }
    }

    /// The budget of Gauss-Markov terms.
    pub const fn gm_states(&self) -> usize {
        self.gm_states
    }
}

/// The decay time of a candidate oscillator, in periods: `T = OSCILLATOR_CYCLES / f`.
pub const OSCILLATOR_CYCLES: f64 = 10.0;

/// The lowest candidate oscillator frequency, Hz: a slower line is a bump that Gauss-Markov
/// terms fit as well within a record's reach, for one state instead of two.
pub const OSCILLATOR_MIN_HZ: f64 = 0.1;

/// How far inside the record a Gauss-Markov term's correlation time must lie to be told from
/// a random walk: `T <= tau_max / 16`. Its Allan deviation peaks at `1.89 T` and falls beyond;
/// with `T` longer, that fall would rest on the last three octaves alone, whose overlapping
/// estimates hold about 1, 2 and 4 degrees of freedom where a random walk dominates (Riley's
/// formula): a bend there is as likely the noise of the estimate. Over the record, such a term
/// is a random walk (`K^2 = 2 sigma^2 / T`, its form for `tau << T`). The refinement stops at
/// this bound, and a term it leaves within 3 % of it (pressed against it) is taken as the
/// random walk too.
pub const RECORD_OCTAVES: f64 = 16.0;

/// A column of the fit: a component of unit parameter.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub(super) enum Column {
    #[default]
    Quantization,
    White,
    RandomWalk,
    Ramp,
    Ar,
    GaussMarkov(f64),
    /// Frequency (Hz) and decay time (s).
    Oscillator(f64, f64),
}

/// Weighted solves before and after the reduction to the state budget.
const PASSES: usize = 3;

/// The weighted problem over the octaves: data, the AR part's curve, the row weights and the
/// correlation of each row with the one before.
pub(super) struct Problem<'a, const P: usize, const L: usize> {
    pub(super) octaves: &'a Octaves<L>,
    pub(super) ar: Option<&'a ArModel<f64, P>>,
    pub(super) ar_curve: [f64; L],
    /// `sqrt(nu_j) / AVAR_j` of the reference curve.
    pub(super) weight: [f64; L],
    /// The correlation of octave `j`'s estimate with octave `j - 1`'s
    /// ([`super::Estimator::octave_correlation`]); 0 for the first.
    pub(super) rho: [f64; L],
    /// Whether the rows are taken as correlated (identification) or independent.
    pub(super) correlated: bool,
}

impl<const P: usize, const G: usize> NoiseModel<P, G> {
    /// Fits the composite to `octaves`, with the AR part `ar` (shape fixed, scale fitted) if
    /// given.
    ///
    /// 1. Columns: quantisation, white noise, random walk, optionally ramp and the AR part, and
    ///    a Gauss-Markov term at every correlation time of the grid ([`FitConfig`]), each the
    ///    exact Allan curve of unit parameter ([`component`]).
    /// 2. Rows: the octaves, weighted by `sqrt(nu) / AVAR` (the inverse standard error
    ///    `AVAR sqrt(2 / nu)` of each estimate, up to a constant, [`super::Estimator::edf`]), first with the data's `AVAR` and white-noise
    ///    degrees of freedom, then, for two more passes, with the model's `AVAR` and the
    ///    degrees of freedom of the noise type that dominates it there, so that a noisy
    ///    long-`tau` estimate does not pull the fit. Columns are scaled to unit norm.
    /// 3. Lawson-Hanson NNLS ([`nnls::nnls`]), in units where the largest Allan variance is 1
    ///    (scaled by a power of two), so that any magnitude of data fits alike.
    /// 4. While more Gauss-Markov terms are positive than the budget allows, the one change
    ///    that raises the weighted residual least is made: two neighbours merged into one at
    ///    their `sigma^2`-weighted geometric mean correlation time, or one term dropped, and
    ///    the rest refitted. Then the weights are refined again.
    ///
    /// ```
    /// use imu_ar::noise::{Estimator, FitConfig, NoiseModel, Octaves, component};
    ///
    /// // The exact curve of white noise N = 0.01 and random walk K = 1e-4 at 100 Hz.
    /// let dt = 0.01;
    /// let avar: Vec<f64> = (0..20)
    ///     .map(|j| {
    ///         let m = 1u64 << j;
    ///         1e-4 * component::white(dt, m) + 1e-8 * component::random_walk(dt, m)
    ///     })
    ///     .collect();
    /// let octaves = Octaves::<20>::new(dt, &avar, Estimator::Overlapping { n: 1 << 21 })?;
    /// let model = NoiseModel::<1, 2>::fit(&octaves, None, &FitConfig::new(2))?;
    /// assert!((model.white_noise() / 0.01 - 1.0).abs() < 1e-6);
    /// assert!((model.random_walk() / 1e-4 - 1.0).abs() < 1e-3);
    /// assert!(model.check(&octaves)?.holds());
    /// # Ok::<(), imu_ar::noise::NoiseError>(())
    /// ```
    ///
    /// # Errors
    ///
    /// [`NoiseError::Budget`] for a budget above `G`; [`NoiseError::TooFewOctaves`] for fewer
    /// than 2 octaves; [`NoiseError::Constant`] when every Allan variance is zero;
    /// [`NoiseError::Interval`] when `1 / tau^2` at the first octave or `tau^2` at the last
    /// overflows; [`NoiseError::Capacity`] for an `L` too small for the fixed columns;
    /// [`NoiseError::Overflow`] when a fitted parameter overflows `f64`; [`NoiseError::Range`]
    /// when the Allan variances span too many decades to weigh (about 1e300);
    /// [`NoiseError::Ar`] for a non-stationary AR part.
    pub fn fit<const L: usize>(
        octaves: &Octaves<L>,
        ar: Option<&ArModel<f64, P>>,
        config: &FitConfig,
    ) -> Result<Self, NoiseError> {
        Self::identify(octaves, ar, config).map(|fit| fit.model)
    }

    /// [`NoiseModel::fit`], and whether the budget of states, not the data, limited the
    /// model.
    ///
    /// Identification ([`FitConfig::with_identification`]) works on the rows
    /// whitened for the correlation between neighbouring octaves
    /// ([`super::Estimator::octave_correlation`]), so that the weighted misfit `chi^2` is that
    /// of independent rows of unit variance:
    ///
    /// 1. It starts from white noise (and the AR part, if given and of short memory: its
    ///    Allan variance within 10 % of its white equivalent at the longest correlation time
    ///    the record tells, `tau_max / RECORD_OCTAVES`; an AR part still colouring the
    ///    octaves there, such as one whose root near 1 took a random walk or a slow drift,
    ///    would hand its white equivalent, up to a hundred times the data's level, to `N`,
    ///    and the walk it took to no term: the fit goes without it).
    /// 2. It adds, one at a time, the candidate (quantisation, random walk, ramp, a
    ///    Gauss-Markov term at a grid correlation time from `dt` to [`RECORD_OCTAVES`]
    ///    times less than the longest `tau`, an
    ///    oscillator) that lowers `chi^2 + 2 ln(ln L) k` most, `k` its parameters (1; 2 for
    ///    a Gauss-Markov term; 3 for an oscillator) and `L` the octaves (Hannan-Quinn), as
    ///    long as one lowers it. The new term's correlation time (an oscillator's frequency and decay
    ///    time) is refined by golden-section search between its grid neighbours.
    /// 3. When a candidate would pass but the budget has no state left for it,
    ///    [`Identified::budget_limited`] says so.
    /// 4. Then each term is tried without: dropped, or, for a Gauss-Markov term, replaced by
    ///    the random walk that it is over the record (`K^2 = 2 sigma^2 / T` where
    ///    `tau << T`), while that lowers the criterion: a term of a few samples is kept only
    ///    where the first octaves need it, and is otherwise the white noise it is at longer
    ///    `tau` (`N^2 = 2 sigma^2 T`).
    /// 5. Last, every correlation time is refined again and the weights refined as in
    ///    [`NoiseModel::fit`].
    /// 6. Where the identified model has no random walk and fails the whole-curve check
    ///    ([`NoiseModel::check_whole`]), the walk added, or in place of one of its Gauss-Markov
    ///    terms, stands if it passes (the best of those by the criterion): a term fitted to
    ///    chance lows at the last octaves levels off where the record still rises.
    /// 7. Where the identified model still fails the check and the curve fit fails it at fewer
    ///    octaves, the curve fit stands ([`Identified::curve_fit`]).
    ///
    /// # Errors
    ///
    /// As [`NoiseModel::fit`].
    pub fn identify<const L: usize>(
        octaves: &Octaves<L>,
        ar: Option<&ArModel<f64, P>>,
        config: &FitConfig,
    ) -> Result<Identified<P, G>, NoiseError> {
        if config.gm_states > G {
            return Err(NoiseError::Budget {
                requested: config.gm_states,
                capacity: G,
            });
        }
        let data = octaves.avar();
        if data.len() < 2 {
            return Err(NoiseError::TooFewOctaves { given: data.len() });
        }
        if data.iter().all(|v| *v == 0.0) {
            return Err(NoiseError::Constant);
        }
        let (first, last) = (octaves.tau(0), octaves.tau(data.len() - 1));
        if !((1.0 / (first * first)).is_finite() && (last * last).is_finite()) {
            return Err(NoiseError::Interval);
        }
        // Fit in units where the largest Allan variance is 1 (a power of two away, so that
        // the scaling is exact), and scale back.
        let exponent = libm::ilogb(data.iter().copied().fold(0.0, f64::max));
        let scaled = octaves.scaled(exponent.saturating_neg());
        let ar = match ar {
            Some(ar) => Some(
                ArModel::new(
                    *ar.a(),
                    libm::scalbn(ar.noise_variance(), exponent.saturating_neg()),
                    ar.mean(),
                    ar.dt(),
                )
                .map_err(NoiseError::Ar)?,
            ),
            None => None,
        };
        let ar = ar.filter(|ar| short_memory(ar, &scaled));
        let (mut model, budget_limited) = Self::fit_unit(&scaled, ar.as_ref(), config)?;
        // Identified terms that fail the whole-curve check at octaves where the curve fit
        // passes it: the data hold more than the criterion found terms for, and the curve fit
        // stands.
        let mut curve_fit = !config.identify;
        let failing = |c: &Check<L>| {
            c.rows()
                .iter()
                .fold(0usize, |n, r| n.saturating_add(usize::from(!r.agrees)))
        };
        if config.identify {
            let failed = failing(&model.check_whole(&scaled)?);
            if failed > 0 {
                let (curve, _) =
                    Self::fit_unit(&scaled, ar.as_ref(), &config.with_identification(false))?;
                if failing(&curve.check_whole(&scaled)?) < failed {
                    (model, curve_fit) = (curve, true);
                }
            }
        }
        // A model of no noise at all for data with some: the weights spanned more than f64
        // can hold.
        let mut curve = [0.0; L];
        model.avar_octaves(&mut curve[..data.len().min(L)])?;
        if curve.iter().all(|v| *v == 0.0) {
            return Err(NoiseError::Range);
        }
        Ok(Identified {
            model: model.scaled(exponent)?,
            budget_limited,
            curve_fit,
        })
    }

    /// [`NoiseModel::fit`] in the scaled units (the AR part one of short memory).
    fn fit_unit<const L: usize>(
        octaves: &Octaves<L>,
        ar: Option<&ArModel<f64, P>>,
        config: &FitConfig,
    ) -> Result<(Self, bool), NoiseError> {
        let data = octaves.avar();
        let mut problem = Problem {
            octaves,
            ar,
            ar_curve: [0.0; L],
            weight: [0.0; L],
            rho: [0.0; L],
            correlated: config.identify,
        };
        if let Some(ar) = ar {
            component::ar_octaves(ar, &mut problem.ar_curve[..data.len().min(L)])
                .map_err(NoiseError::Ar)?;
        }
        let mut store = [[Column::default(); L]; 2];
        let columns = store.as_flattened_mut();
        let capacity = columns.len().min(MAX);
        let mut n = 0;
        let mut push = |c: Column| match columns.get_mut(n).filter(|_| n < capacity) {
            Some(slot) => {
                *slot = c;
                n = n.saturating_add(1);
                true
            }
            None => false,
        };
        let fixed_columns = [
            config.quantization.then_some(Column::Quantization),
            Some(Column::White),
            Some(Column::RandomWalk),
            config.ramp.then_some(Column::Ramp),
            ar.map(|_| Column::Ar),
        ];
        for c in fixed_columns.into_iter().flatten() {
            if !push(c) {
                return Err(NoiseError::Capacity);
            }
        }
        let mut t = octaves.dt();
        let longest = octaves.tau(data.len().saturating_sub(1));
        let longest = if config.identify {
            longest / RECORD_OCTAVES
        } else {
            longest
        };
        while t <= longest * (1.0 + 1e-9) && push(Column::GaussMarkov(t)) {
            t *= libm::exp2(config.spacing);
        }
        for j in (3..data.len()).filter(|_| config.oscillators) {
            let f = 0.371 / octaves.tau(j);
            if f < OSCILLATOR_MIN_HZ || !push(Column::Oscillator(f, OSCILLATOR_CYCLES / f)) {
                break;
            }
        }
        let fixed = fixed_columns.iter().flatten().count();

        let (full, budget_limited) = if config.identify {
            problem.identify(head(columns, n), config.gm_states, config.spacing)?
        } else {
            let fit = problem.refine(head(columns, n), None)?;
            n = compact(head_mut(columns, n), &fit.1);
            n = problem.reduce(columns, fixed, n, config.gm_states)?;
            (problem.refine(head(columns, n), Some(&fit.0))?.0, false)
        };
        let mut model = Self::default_at(octaves.dt());
        (
            model.quantization,
            model.white,
            model.random_walk,
            model.ramp,
            model.ar,
        ) = (
            full.quantization,
            full.white,
            full.random_walk,
            full.ramp,
            full.ar,
        );
        model.gm_len = full.gauss_markov().len().min(G);
        model
            .gm
            .iter_mut()
            .zip(full.gauss_markov())
            .for_each(|(d, s)| *d = *s);
        model.osc_len = full.oscillators().len().min(G);
        model
            .osc
            .iter_mut()
            .zip(full.oscillators())
            .for_each(|(d, s)| *d = *s);
        Ok((model, budget_limited))
    }

    /// The model with every variance times `2^exponent`.
    pub(super) fn scaled(mut self, exponent: i32) -> Result<Self, NoiseError> {
        let root = |v: f64| libm::sqrt(libm::scalbn(v * v, exponent));
        self.quantization = root(self.quantization);
        self.white = root(self.white);
        self.random_walk = root(self.random_walk);
        self.ramp = root(self.ramp);
        for t in self.gm.iter_mut() {
            t.sigma = root(t.sigma);
        }
        for o in self.osc.iter_mut() {
            o.sigma = root(o.sigma);
        }
        if let Some(ar) = self.ar {
            let variance = libm::scalbn(ar.noise_variance(), exponent);
            self.ar = Some(
                ArModel::new(*ar.a(), variance, ar.mean(), ar.dt())
                    .map_err(|_| NoiseError::Overflow)?,
            );
        }
        let terms = self.gm.iter().map(|t| t.sigma);
        let sigmas = terms.chain(self.osc.iter().map(|o| o.sigma));
        let parameters = [self.quantization, self.white, self.random_walk, self.ramp];
        if parameters.into_iter().chain(sigmas).all(f64::is_finite) {
            Ok(self)
        } else {
            Err(NoiseError::Overflow)
        }
    }

    fn default_at(dt: f64) -> Self {
        Self {
            dt,
            quantization: 0.0,
            white: 0.0,
            random_walk: 0.0,
            ramp: 0.0,
            gm: [GmTerm::default(); G],
            gm_len: 0,
            osc: [Oscillator::default(); G],
            osc_len: 0,
            ar: None,
        }
    }
}

impl<const P: usize, const L: usize> Problem<'_, P, L> {
    /// The unit Allan variance of `column` at octave `j`.
    pub(super) fn unit(&self, column: Column, j: usize) -> f64 {
        let (dt, m) = (self.octaves.dt(), 1u64 << j.min(63));
        match column {
            Column::Quantization => component::quantization(dt, m),
            Column::White => component::white(dt, m),
            Column::RandomWalk => component::random_walk(dt, m),
            Column::Ramp => component::ramp(dt, m),
            Column::Ar => self.ar_curve.get(j).copied().unwrap_or(0.0),
            Column::GaussMarkov(t) => component::gauss_markov(dt, t, m),
            // The candidates' poles are inside the unit circle by construction.
            Column::Oscillator(f, t) => component::oscillator(dt, f, t, j).unwrap_or(0.0),
        }
    }

    /// Row weights `sqrt(nu) / AVAR` from the data (no model yet) or from `model`, and the
    /// rows' correlations.
    pub(super) fn reweight<const G: usize>(&mut self, model: Option<&NoiseModel<P, G>>) {
        let data = self.octaves.avar();
        let floor = data
            .iter()
            .copied()
            .filter(|v| *v > 0.0)
            .fold(f64::INFINITY, f64::min);
        let mut curve = [0.0; L];
        if let Some(model) = model {
            // A fitted model's AR part is the (stationary) one given: this cannot fail.
            let _ = model.avar_octaves(&mut curve[..data.len().min(L)]);
        }
        let estimator = self.octaves.estimator();
        let rows = data.iter().zip(&curve).zip(self.weight.iter_mut());
        let rows = rows.zip(self.rho.iter_mut());
        let mut previous = 0.0;
        for (j, (((d, c), weight), rho)) in indexed(rows) {
            let m = 1u64 << j.min(63);
            let (kind, reference) = match model {
                Some(model) if *c > 0.0 => (model.dominant(m).0, *c),
                _ => (NoiseType::WhiteFrequency, d.max(floor)),
            };
            let nu = self.octaves.edf(j, kind);
            *weight = libm::sqrt(nu) / reference;
            // A row without an estimate, or after one, is uncorrelated.
            *rho = if !self.correlated || j == 0 || previous == 0.0 || *weight == 0.0 {
                0.0
            } else {
                estimator.octave_correlation(kind)
            };
            previous = *weight;
        }
    }

    /// `v` (weighted rows) whitened in place for the rows' correlation: with the rows a Markov
    /// chain of neighbour correlations `rho_j`, `(v_j - rho_j v_(j-1)) / sqrt(1 - rho_j^2)`
    /// are uncorrelated.
    pub(super) fn whiten(&self, v: &mut [f64]) {
        let rows = v.len().min(L);
        for j in (1..rows).rev() {
            let rho = self.rho.get(j).copied().unwrap_or(0.0);
            if let (Some(&before), true) = (v.get(j - 1), rho != 0.0)
                && let Some(vj) = v.get_mut(j)
            {
                *vj = (*vj - rho * before) / libm::sqrt(1.0 - rho * rho);
            }
        }
    }

    /// Weights from `start` (the data when `None`), then [`PASSES`] solves, each weighted by
    /// the model of the one before.
    pub(super) fn refine(
        &mut self,
        columns: &[Column],
        start: Option<&Full<P>>,
    ) -> Result<(Full<P>, [f64; MAX]), NoiseError> {
        self.reweight(start);
        let mut fit = self.solve(columns)?;
        for _ in 1..PASSES {
            self.reweight(Some(&fit.0));
            fit = self.solve(columns)?;
        }
        Ok(fit)
    }

    /// Solves the weighted NNLS over `columns`: the model and the parameters (variances).
    pub(super) fn solve(&self, columns: &[Column]) -> Result<(Full<P>, [f64; MAX]), NoiseError> {
        let (x, _) = self.nnls(columns)?;
        Ok((self.model_of(columns, &x)?, x))
    }

    /// The model of the parameters (variances) `x` of `columns`.
    pub(super) fn model_of(&self, columns: &[Column], x: &[f64]) -> Result<Full<P>, NoiseError> {
        let mut model = Full::<P>::default_at(self.octaves.dt());
        for (column, &v) in columns.iter().zip(x) {
            let root = libm::sqrt(v);
            match *column {
                Column::Quantization => model.quantization = root,
                Column::White => model.white = root,
                Column::RandomWalk => model.random_walk = root,
                Column::Ramp => model.ramp = root,
                Column::Ar => {
                    model.ar = match self.ar {
                        Some(ar) if v > 0.0 => Some(
                            ArModel::new(*ar.a(), ar.noise_variance() * v, ar.mean(), ar.dt())
                                .map_err(NoiseError::Ar)?,
                        ),
                        _ => None,
                    }
                }
                Column::GaussMarkov(t) if v > 0.0 => {
                    if let Some(slot) = model.gm.get_mut(model.gm_len) {
                        *slot = GmTerm {
                            sigma: root,
                            correlation_time: t,
                        };
                        model.gm_len = model.gm_len.saturating_add(1);
                    }
                }
                Column::Oscillator(f, t) if v > 0.0 => {
                    if let Some(slot) = model.osc.get_mut(model.osc_len) {
                        *slot = Oscillator {
                            sigma: root,
                            frequency: f,
                            decay_time: t,
                        };
                        model.osc_len = model.osc_len.saturating_add(1);
                    }
                }
                Column::GaussMarkov(_) | Column::Oscillator(..) => {}
            }
        }
        sort_by_correlation_time(&mut model.gm[..model.gm_len.min(MAX)]);
        Ok(model)
    }

    /// The weighted NNLS over `columns`: the parameters (variances) and the weighted residual
    /// norm.
    pub(super) fn nnls(&self, columns: &[Column]) -> Result<([f64; MAX], f64), NoiseError> {
        let rows = self.octaves.avar().len();
        let mut a = [[[0.0; L]; L]; 2];
        let a = &mut a.as_flattened_mut()[..columns.len().min(2 * L)];
        let mut scale = [0.0; MAX];
        for ((col, column), s) in a.iter_mut().zip(columns).zip(scale.iter_mut()) {
            let cells = indexed(col.iter_mut().zip(&self.weight)).take(rows);
            for (j, (v, w)) in cells {
                *v = w * self.unit(*column, j);
            }
            self.whiten(&mut col[..rows.min(L)]);
            // The norm scaled by the largest entry, so that squares neither overflow nor
            // underflow.
            let big = col.iter().fold(0.0f64, |m, v| m.max(libm::fabs(*v)));
            *s = if big > 0.0 && big.is_finite() {
                big * libm::sqrt(col.iter().map(|v| (v / big) * (v / big)).sum::<f64>())
            } else {
                big
            };
            if *s > 0.0 {
                col.iter_mut().for_each(|v| *v /= *s);
            }
        }
        let mut b = [0.0; L];
        let weighted = b.iter_mut().zip(self.octaves.avar()).zip(&self.weight);
        for ((bj, d), w) in weighted {
            *bj = w * d;
        }
        self.whiten(&mut b[..rows.min(L)]);
        let mut work = [[[0.0; L]; L]; 2];
        let work = work.as_flattened_mut();
        let mut x = [0.0; MAX];
        let residual = nnls::nnls(
            a,
            &b,
            &mut x[..columns.len().min(MAX)],
            &mut work[..columns.len().min(2 * L)],
        )?;
        for (v, s) in x.iter_mut().zip(&scale).take(columns.len()) {
            *v = if *s > 0.0 { *v / s } else { 0.0 };
        }
        Ok((x, residual))
    }

    /// Reduces the Gauss-Markov columns `columns[fixed..n]` to at most `budget`; returns the
    /// new `n`.
    fn reduce(
        &self,
        columns: &mut [Column],
        fixed: usize,
        mut n: usize,
        budget: usize,
    ) -> Result<usize, NoiseError> {
        while states(head(columns, n).get(fixed..).unwrap_or(&[])) > budget {
            let (x, _) = self.nnls(head(columns, n))?;
            let mut best: Option<(f64, usize, Option<f64>)> = None;
            let mut trial = [[Column::default(); L]; 2];
            let trial = trial.as_flattened_mut();
            for i in fixed..n {
                // Drop term i, or merge it with the next one.
                let pair = i..i.saturating_add(2);
                let merged = match (columns.get(pair.clone()), x.get(pair)) {
                    (Some(&[p, q]), Some(&[vp, vq])) if i.saturating_add(1) < n => {
                        merge(p, vp, q, vq)
                    }
                    _ => None,
                };
                for candidate in [None, merged] {
                    let k = edit(head(columns, n), i, candidate, trial);
                    let (_, r) = self.nnls(head(trial, k))?;
                    if best.is_none_or(|b| r < b.0) {
                        best = Some((r, i, candidate));
                    }
                }
            }
            let Some((_, i, candidate)) = best else { break };
            let k = edit(head(columns, n), i, candidate, trial);
            columns
                .iter_mut()
                .zip(head(trial, k))
                .for_each(|(c, t)| *c = *t);
            let (x, _) = self.nnls(head(columns, k))?;
            n = compact(head_mut(columns, k), &x);
        }
        Ok(n)
    }
}

/// The model while it is fitted: room for a term at every column.
pub(super) type Full<const P: usize> = NoiseModel<P, MAX>;

/// The most columns (the limit of [`nnls::nnls`]).
pub(super) const MAX: usize = nnls::MAX_COLUMNS;

/// A model identified by [`NoiseModel::identify`].
#[derive(Clone, Copy, Debug, PartialEq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub struct Identified<const P: usize, const G: usize> {
    /// The model.
    pub model: NoiseModel<P, G>,
    /// Whether a term that the data call for was left out for want of states: the budget,
    /// not the data, limited the model (its random walk, say, then also carries what a
    /// Gauss-Markov term would have taken).
    pub budget_limited: bool,
    /// Whether the model is the curve fit's, which fills the budget: asked for (identification
    /// off), or because the identified terms failed the whole-curve check
    /// ([`NoiseModel::check_whole`]) at more octaves than the curve fit. Its parameters then
    /// describe the curve, and may not be the sensor's.
    pub curve_fit: bool,
}

/// Whether the AR part `ar` is short-term colouring over `octaves`: its Allan variance times
/// `tau` within 10 % of its white equivalent (`ar_white_equivalent`) at the octave of the
/// longest correlation time the record tells (`tau_max / RECORD_OCTAVES`, the first octave
/// for a record shorter than that). One that is not stationary is left to the fit to refuse.
fn short_memory<const P: usize, const L: usize>(
    ar: &ArModel<f64, P>,
    octaves: &Octaves<L>,
) -> bool {
    let len = octaves.avar().len().min(L);
    let mut curve = [0.0; L];
    if component::ar_octaves(ar, &mut curve[..len]).is_err() {
        return true;
    }
    let reach = octaves.tau(len.saturating_sub(1)) / RECORD_OCTAVES;
    let j = (0..len)
        .rev()
        .find(|j| octaves.tau(*j) <= reach * (1.0 + 1e-9))
        .unwrap_or(0);
    let white = super::model::ar_white_equivalent(ar, octaves.dt());
    let ratio = curve.get(j).copied().unwrap_or(0.0) * octaves.tau(j) / white;
    (0.9..=1.1).contains(&ratio)
}
