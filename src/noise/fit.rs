//! Fitting a [`NoiseModel`] to octave Allan variances (`noise-model.md` section 2).

use crate::model::ArModel;

use super::model::{GmTerm, NoiseModel, Oscillator};
use super::{NoiseError, NoiseType, Octaves, component, nnls};

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
    /// decaying over [`OSCILLATOR_CYCLES`] periods.
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

/// A column of the fit: a component of unit parameter.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
enum Column {
    #[default]
    Quantization,
    White,
    RandomWalk,
    Ramp,
    Ar,
    GaussMarkov(f64),
    Oscillator(f64),
}

/// Weighted solves before and after the reduction to the state budget.
const PASSES: usize = 3;

/// The weighted problem over the octaves: data, the AR part's curve and the row weights.
struct Problem<'a, const P: usize, const L: usize> {
    octaves: &'a Octaves<L>,
    ar: Option<&'a ArModel<f64, P>>,
    ar_curve: [f64; L],
    /// `sqrt(nu_j) / AVAR_j` of the reference curve.
    weight: [f64; L],
}

impl<const P: usize, const G: usize> NoiseModel<P, G> {
    /// Fits the composite to `octaves`, with the AR part `ar` (shape fixed, scale fitted) if
    /// given.
    ///
    /// 1. Columns: quantisation, white noise, random walk, optionally ramp and the AR part, and
    ///    a Gauss-Markov term at every correlation time of the grid ([`FitConfig`]), each the
    ///    exact Allan curve of unit parameter ([`component`]).
    /// 2. Rows: the octaves, weighted by `nu / AVAR` (the inverse standard error of each
    ///    estimate, [`super::Estimator::edf`]), first with the data's `AVAR` and white-noise
    ///    degrees of freedom, then, for two more passes, with the model's `AVAR` and the
    ///    degrees of freedom of the noise type that dominates it there, so that a noisy
    ///    long-`tau` estimate does not pull the fit. Columns are scaled to unit norm.
    /// 3. Lawson-Hanson NNLS ([`nnls::nnls`]).
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
    /// [`NoiseError::Ar`] for a non-stationary AR part.
    pub fn fit<const L: usize>(
        octaves: &Octaves<L>,
        ar: Option<&ArModel<f64, P>>,
        config: &FitConfig,
    ) -> Result<Self, NoiseError> {
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
        let mut problem = Problem {
            octaves,
            ar,
            ar_curve: [0.0; L],
            weight: [0.0; L],
        };
        if let Some(ar) = ar {
            component::ar_octaves(ar, &mut problem.ar_curve[..data.len()])
                .map_err(NoiseError::Ar)?;
        }
        let mut store = [[Column::default(); L]; 2];
        let columns = store.as_flattened_mut();
        let mut n = 0;
        let mut push = |c: Column| {
            columns[n] = c;
            n += 1;
        };
        if config.quantization {
            push(Column::Quantization);
        }
        push(Column::White);
        push(Column::RandomWalk);
        if config.ramp {
            push(Column::Ramp);
        }
        if ar.is_some() {
            push(Column::Ar);
        }
        let fixed = n;
        let longest = octaves.tau(data.len() - 1);
        let mut t = octaves.dt();
        let capacity = columns.len().min(MAX);
        while t <= longest * (1.0 + 1e-9) && n < capacity {
            columns[n] = Column::GaussMarkov(t);
            n += 1;
            t *= libm::exp2(config.spacing);
        }
        for j in (3..data.len()).filter(|_| config.oscillators) {
            if n == capacity || 0.371 / octaves.tau(j) < OSCILLATOR_MIN_HZ {
                break;
            }
            columns[n] = Column::Oscillator(0.371 / octaves.tau(j));
            n += 1;
        }

        let fit = problem.refine(&columns[..n], None)?;
        n = compact(&mut columns[..n], &fit.1);
        n = problem.reduce(columns, fixed, n, config.gm_states)?;
        let fit = problem.refine(&columns[..n], Some(&fit.0))?;
        let full = fit.0;
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
        model.gm_len = full.gm_len.min(G);
        model.gm[..model.gm_len].copy_from_slice(&full.gm[..model.gm_len]);
        model.osc_len = full.osc_len.min(G);
        model.osc[..model.osc_len].copy_from_slice(&full.osc[..model.osc_len]);
        Ok(model)
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
    fn unit(&self, column: Column, j: usize) -> f64 {
        let (dt, m) = (self.octaves.dt(), 1u64 << j.min(63));
        match column {
            Column::Quantization => component::quantization(dt, m),
            Column::White => component::white(dt, m),
            Column::RandomWalk => component::random_walk(dt, m),
            Column::Ramp => component::ramp(dt, m),
            Column::Ar => self.ar_curve[j],
            Column::GaussMarkov(t) => component::gauss_markov(dt, t, m),
            // The candidates' poles are inside the unit circle by construction.
            Column::Oscillator(f) => {
                component::oscillator(dt, f, OSCILLATOR_CYCLES / f, j).unwrap_or(0.0)
            }
        }
    }

    /// Row weights `sqrt(nu) / AVAR` from the data (no model yet) or from `model`.
    fn reweight<const G: usize>(&mut self, model: Option<&NoiseModel<P, G>>) {
        let data = self.octaves.avar();
        let floor = data
            .iter()
            .copied()
            .filter(|v| *v > 0.0)
            .fold(f64::INFINITY, f64::min);
        let mut curve = [0.0; L];
        if let Some(model) = model {
            // A fitted model's AR part is the (stationary) one given: this cannot fail.
            let _ = model.avar_octaves(&mut curve[..data.len()]);
        }
        for (j, d) in data.iter().enumerate() {
            let m = 1u64 << j.min(63);
            let (kind, reference) = match model {
                Some(model) if curve[j] > 0.0 => (model.dominant(m).0, curve[j]),
                _ => (NoiseType::WhiteFrequency, d.max(floor)),
            };
            let nu = self.octaves.edf(j, kind);
            self.weight[j] = libm::sqrt(nu) / reference;
        }
    }

    /// Weights from `start` (the data when `None`), then [`PASSES`] solves, each weighted by
    /// the model of the one before.
    fn refine(
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
    fn solve(&self, columns: &[Column]) -> Result<(Full<P>, [f64; MAX]), NoiseError> {
        let (x, _) = self.nnls(columns)?;
        let mut model = Full::<P>::default_at(self.octaves.dt());
        for (column, &v) in columns.iter().zip(&x) {
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
                    model.gm[model.gm_len] = GmTerm {
                        sigma: root,
                        correlation_time: t,
                    };
                    model.gm_len += 1;
                }
                Column::Oscillator(f) if v > 0.0 => {
                    model.osc[model.osc_len] = Oscillator {
                        sigma: root,
                        frequency: f,
                        decay_time: OSCILLATOR_CYCLES / f,
                    };
                    model.osc_len += 1;
                }
                Column::GaussMarkov(_) | Column::Oscillator(_) => {}
            }
        }
        model.gm[..model.gm_len]
            .sort_unstable_by(|p, q| p.correlation_time.total_cmp(&q.correlation_time));
        Ok((model, x))
    }

    /// The weighted NNLS over `columns`: the parameters (variances) and the weighted residual
    /// norm.
    fn nnls(&self, columns: &[Column]) -> Result<([f64; MAX], f64), NoiseError> {
        let rows = self.octaves.avar().len();
        let mut a = [[[0.0; L]; L]; 2];
        let a = &mut a.as_flattened_mut()[..columns.len()];
        let mut scale = [0.0; MAX];
        for ((col, column), s) in a.iter_mut().zip(columns).zip(scale.iter_mut()) {
            for (j, v) in col.iter_mut().enumerate().take(rows) {
                *v = self.weight[j] * self.unit(*column, j);
            }
            *s = libm::sqrt(col.iter().map(|v| v * v).sum::<f64>());
            if *s > 0.0 {
                col.iter_mut().for_each(|v| *v /= *s);
            }
        }
        let mut b = [0.0; L];
        for (j, (bj, d)) in b.iter_mut().zip(self.octaves.avar()).enumerate() {
            *bj = self.weight[j] * d;
        }
        let mut work = [[[0.0; L]; L]; 2];
        let mut x = [0.0; MAX];
        let residual = nnls::nnls(
            a,
            &b,
            &mut x[..columns.len()],
            &mut work.as_flattened_mut()[..columns.len()],
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
        while states(&columns[fixed..n]) > budget {
            let (x, _) = self.nnls(&columns[..n])?;
            let mut best: Option<(f64, usize, Option<f64>)> = None;
            let mut trial = [[Column::default(); L]; 2];
            let trial = trial.as_flattened_mut();
            for i in fixed..n {
                // Drop term i, or merge it with the next one.
                let merged = (i + 1 < n).then(|| merge(columns[i], x[i], columns[i + 1], x[i + 1]));
                for candidate in [None, merged.flatten()] {
                    let k = edit(&columns[..n], i, candidate, trial);
                    let (_, r) = self.nnls(&trial[..k])?;
                    if best.is_none_or(|b| r < b.0) {
                        best = Some((r, i, candidate));
                    }
                }
            }
            let Some((_, i, candidate)) = best else { break };
            let k = edit(&columns[..n], i, candidate, trial);
            columns[..k].copy_from_slice(&trial[..k]);
            let (x, _) = self.nnls(&columns[..k])?;
            n = compact(&mut columns[..k], &x);
        }
        Ok(n)
    }
}

/// The model while it is fitted: room for a term at every column.
type Full<const P: usize> = NoiseModel<P, MAX>;

/// The most columns (the limit of [`nnls::nnls`]).
const MAX: usize = nnls::MAX_COLUMNS;

/// Moves the Gauss-Markov columns whose parameter in `x` is zero to the end; returns how many
/// columns are left before them.
fn compact(columns: &mut [Column], x: &[f64]) -> usize {
    let mut kept = 0;
    for c in 0..columns.len() {
        let term = matches!(columns[c], Column::GaussMarkov(_) | Column::Oscillator(_));
        let zero_term = term && x[c] <= 0.0;
        if !zero_term {
            columns[kept] = columns[c];
            kept += 1;
        }
    }
    kept
}

/// Kalman states of the terms `columns`: one per Gauss-Markov term, two per oscillator.
fn states(columns: &[Column]) -> usize {
    columns
        .iter()
        .map(|c| match c {
            Column::GaussMarkov(_) => 1,
            Column::Oscillator(_) => 2,
            _ => 0,
        })
        .sum()
}

/// The term replacing Gauss-Markov columns `p` and `q` of variances `vp` and `vq`: their
/// `sigma^2`-weighted geometric mean correlation time. `None` for anything else.
fn merge(p: Column, vp: f64, q: Column, vq: f64) -> Option<f64> {
    match (p, q) {
        (Column::GaussMarkov(tp), Column::GaussMarkov(tq)) if vp + vq > 0.0 => Some(libm::exp(
            (vp * libm::log(tp) + vq * libm::log(tq)) / (vp + vq),
        )),
        _ => None,
    }
}

/// `columns` without column `i`, and with `i + 1` replaced by a term at `merged` when given;
/// into `out`, returning the count.
fn edit(columns: &[Column], i: usize, merged: Option<f64>, out: &mut [Column]) -> usize {
    let mut k = 0;
    for (j, c) in columns.iter().enumerate() {
        let c = match (j, merged) {
            (j, _) if j == i => continue,
            (j, Some(t)) if j == i + 1 => Column::GaussMarkov(t),
            _ => *c,
        };
        out[k] = c;
        k += 1;
    }
    k
}
