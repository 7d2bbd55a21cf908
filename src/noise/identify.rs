//! Identification ([`NoiseModel::identify`](super::NoiseModel::identify)): terms added one at a
//! time by an information criterion, their correlation times refined off the grid, then each
//! tried without, all on rows whitened for the correlation between neighbouring octaves.

use super::columns::states;
use super::fit::{Column, Full, MAX, OSCILLATOR_MIN_HZ, Problem, RECORD_OCTAVES};
use super::uncertainty::Z95;
use super::{NoiseError, indexed};

/// Golden-section steps of a refinement: the bracket shrinks to `0.618^14`, 0.1 % of it.
const GOLDEN_STEPS: usize = 14;
/// The most alternations of an oscillator's frequency and decay searches.
const OSCILLATOR_ROUNDS: usize = 12;

/// A Gauss-Markov term with a correlation time of at most this many samples is white noise.
const WHITE_SAMPLES: f64 = 3.0;

/// Forward and backward rounds at most.
const ROUNDS: usize = 4;

/// Reweighting passes of a set before it is judged.
const JUDGING_PASSES: usize = 2;

/// The longest decay of a refined oscillator, in periods.
const MAX_CYCLES: f64 = 50.0;

/// The shortest decay of a refined oscillator, in periods (damping ratio 0.32).
const MIN_CYCLES: f64 = 0.5;

/// A set of columns, by value.
#[derive(Clone, Copy)]
struct Set {
    columns: [Column; MAX],
    len: usize,
}

impl Set {
    fn new() -> Self {
        Self {
            columns: [Column::default(); MAX],
            len: 0,
        }
    }

    fn columns(&self) -> &[Column] {
        &self.columns[..self.len.min(MAX)]
    }

    fn with(mut self, column: Column) -> Self {
        if let Some(slot) = self.columns.get_mut(self.len) {
            *slot = column;
            self.len = self.len.saturating_add(1);
        }
        self
    }

    fn without(&self, i: usize) -> Self {
        let kept = indexed(self.columns().iter()).filter(|(k, _)| *k != i);
        kept.fold(Self::new(), |set, (_, c)| set.with(*c))
    }

    fn replaced(mut self, i: usize, column: Column) -> Self {
        if let Some(slot) = self.columns.get_mut(i).filter(|_| i < self.len) {
            *slot = column;
        }
        self
    }

    fn contains(&self, column: Column) -> bool {
        self.columns().contains(&column)
    }
}

/// The parameters a column adds: its variance, and a Gauss-Markov term's correlation time or
/// an oscillator's frequency and decay time.
fn parameters(column: Column) -> f64 {
    match column {
        Column::GaussMarkov(_) => 2.0,
        Column::Oscillator(..) => 3.0,
        _ => 1.0,
    }
}

/// Whether a column may be left out: white noise and the AR part stay.
fn optional(column: Column) -> bool {
    !matches!(column, Column::White | Column::Ar)
}

impl<const P: usize, const L: usize> Problem<'_, P, L> {
    /// The Hannan-Quinn criterion's charge per parameter, `2 ln ln L` for `L` octaves (at least
    /// 2, the AIC's). BIC's `ln L` charges a term more than the record's evidence warrants when
    /// the octaves are as few and as correlated as here: measured over the campaign of
    /// `host-tests` (seeds 0..12 and 12..24), `K` within 30 % on 85 and 87 of 96 records with
    /// `ln L`, 87 and 88 with `2 ln ln L`.
    fn penalty(&self) -> f64 {
        let octaves = self.octaves.avar().len() as f64;
        (2.0 * libm::log(libm::log(octaves))).max(2.0)
    }

    /// `chi^2` of the best fit over `set`: the whitened rows have variance 2 (an estimate with
    /// `nu` degrees of freedom has relative variance `2 / nu`), so half the squared residual.
    fn chi2(&self, set: &Set) -> Result<([f64; MAX], f64), NoiseError> {
        let (x, r) = self.nnls(set.columns())?;
        Ok((x, r * r / 2.0))
    }

    /// `chi^2 + ln(L) k` of `set`, and its parameters.
    ///
    /// Each set is judged by its own fit: weighted by its own model (two passes from the
    /// current weights, which are restored after), with the likelihood's normalisation
    /// `sum ln var_j + ln det C` (the estimates' variances `2 AVAR_j^2 / nu_j` of that model,
    /// and their correlation), so that a model cannot look better by predicting small
    /// variances where it bends below the data.
    fn criterion(&mut self, set: &Set) -> Result<(f64, [f64; MAX]), NoiseError> {
        let saved = (self.weight, self.rho);
        let (mut x, _) = self.nnls(set.columns())?;
        let mut chi2 = 0.0;
        let mut normalisation = 0.0;
        for _ in 0..JUDGING_PASSES {
            let model = self.model_of(set.columns(), &x)?;
            self.reweight(Some(&model));
            let (y, r) = self.nnls(set.columns())?;
            (x, chi2) = (y, r * r / 2.0);
            // ln var_j = ln 2 - 2 ln w_j with the weights w_j = sqrt(nu_j) / AVAR_j, and
            // ln det C = sum ln (1 - rho_j^2) for the rows' Markov chain.
            normalisation = self
                .weight
                .iter()
                .zip(&self.rho)
                .filter(|(w, _)| **w > 0.0)
                .map(|(w, rho)| -2.0 * libm::log(*w) + libm::log(1.0 - rho * rho))
                .sum::<f64>();
        }
        (self.weight, self.rho) = saved;
        let k: f64 = set.columns().iter().map(|c| parameters(*c)).sum();
        Ok((chi2 + normalisation + self.penalty() * k, x))
    }

    /// `set` without its optional columns of zero variance in `x`.
    fn compact(set: &Set, x: &[f64]) -> Set {
        let kept = set.columns().iter().zip(x);
        kept.filter(|(c, v)| !optional(**c) || **v > 0.0)
            .fold(Set::new(), |out, (c, _)| out.with(*c))
    }

    /// Weights from the best fit over `set`.
    fn reweight_by(&mut self, set: &Set) -> Result<(), NoiseError> {
        let (x, _) = self.nnls(set.columns())?;
        let model = self.model_of(set.columns(), &x)?;
        self.reweight(Some(&model));
        Ok(())
    }

    /// Identifies the model among `columns`, with at most `budget` Gauss-Markov states;
    /// `spacing` is the grid's, in octaves. Returns the model and whether the budget limited
    /// it (see [`super::NoiseModel::identify`]).
    // Its own frame: the curve fit that shares `fit_unit` does not carry its locals.
    #[inline(never)]
    pub(super) fn identify(
        &mut self,
        columns: &[Column],
        budget: usize,
        spacing: f64,
    ) -> Result<(Full<P>, bool), NoiseError> {
        let mut set = columns
            .iter()
            .filter(|c| !optional(**c))
            .fold(Set::new(), |set, c| set.with(*c));
        self.reweight::<MAX>(None);
        let mut limited = false;
        // Whether the random walk took a Gauss-Markov term's place (it then carries that
        // term's power, and stays).
        let mut from_term = false;
        // Forward, then backward, until neither changes the set: a term dropped backward
        // frees a state for one that the budget kept out.
        for _ in 0..ROUNDS {
            let before = set;
            limited = false;
            // Forward: each step adds a column or ends; a column may come back after a later one
            // took its place, so the steps are bounded by the columns' count twice.
            for _ in 0..columns.len().saturating_mul(2) {
                self.reweight_by(&set)?;
                let (current, _) = self.criterion(&set)?;
                let mut within: Option<(f64, Column)> = None;
                let mut beyond: Option<f64> = None;
                let candidates = columns
                    .iter()
                    .filter(|c| optional(**c) && !set.contains(**c));
                for &c in candidates {
                    let (ic, _) = self.criterion(&set.with(c))?;
                    if states(set.columns()).saturating_add(states(&[c])) <= budget {
                        if within.is_none_or(|b| ic < b.0) {
                            within = Some((ic, c));
                        }
                    } else if beyond.is_none_or(|b| ic < b) {
                        beyond = Some(ic);
                    }
                }
                match within {
                    Some((ic, c)) if ic < current => {
                        let grown = set.with(c);
                        let grown =
                            self.refine_term(grown, grown.len.saturating_sub(1), spacing)?;
                        let (_, x) = self.criterion(&grown)?;
                        set = Self::compact(&grown, &x);
                    }
                    _ => {
                        limited = beyond.is_some_and(|ic| ic < current);
                        break;
                    }
                }
            }
            // Backward: drop a term, or take a Gauss-Markov term as the random walk it is over the
            // record, while that lowers the criterion. Each step shortens the set.
            for _ in 0..columns.len() {
                self.reweight_by(&set)?;
                let (current, _) = self.criterion(&set)?;
                let mut best: Option<(f64, Set)> = None;
                for (i, c) in indexed(set.columns().iter()).filter(|(_, c)| optional(**c)) {
                    let without = set.without(i);
                    let walk = matches!(c, Column::GaussMarkov(_))
                        && !set.contains(Column::RandomWalk)
                        && columns.contains(&Column::RandomWalk);
                    let alternatives = [
                        Some(without),
                        walk.then(|| without.with(Column::RandomWalk)),
                    ];
                    for alternative in alternatives.into_iter().flatten() {
                        let (ic, _) = self.criterion(&alternative)?;
                        if best.as_ref().is_none_or(|b| ic < b.0) {
                            best = Some((ic, alternative));
                        }
                    }
                }
                match best {
                    Some((ic, smaller)) if ic < current => set = smaller,
                    _ => break,
                }
            }
            // A Gauss-Markov term whose correlation time the record cannot bound (its 95 % upper
            // end beyond the longest tau) is the random walk it looks like there.
            if columns.contains(&Column::RandomWalk) {
                let taken;
                (set, taken) = self.walks(set)?;
                from_term |= taken;
            }
            if set.columns() == before.columns() {
                break;
            }
        }
        for i in 0..set.len {
            set = self.refine_term(set, i, spacing)?;
        }
        if columns.contains(&Column::RandomWalk) {
            let taken;
            (set, taken) = self.walks(set)?;
            from_term |= taken;
        }
        let (mut set, mut model) = self.settle(set)?;
        // A Gauss-Markov term that forgets within a few samples is white noise at every octave
        // but the first few: it takes no state where the model without it passes the check.
        let dt = self.octaves.dt();
        for _ in 0..set.len {
            let short = set
                .columns()
                .iter()
                .position(|c| matches!(c, Column::GaussMarkov(t) if *t <= WHITE_SAMPLES * dt));
            let Some(i) = short else { break };
            let (smaller, without) = self.settle(set.without(i))?;
            if !without.check_whole(self.octaves)?.holds() {
                break;
            }
            (set, model) = (smaller, without);
        }
        // A set without the random walk that fails the whole-curve check: a term fitted to
        // the last octaves' chance lows levels off where the record still rises. The walk,
        // added or in a Gauss-Markov term's place, stands where it passes (the best of those
        // that pass by the criterion), before the curve fit is asked.
        if columns.contains(&Column::RandomWalk)
            && !set.contains(Column::RandomWalk)
            && !model.check_whole(self.octaves)?.holds()
        {
            let mut best: Option<(f64, Set, Full<P>)> = None;
            for i in 0..=set.len {
                let candidate = match set.columns().get(i) {
                    None => set.with(Column::RandomWalk),
                    Some(Column::GaussMarkov(_)) => set.without(i).with(Column::RandomWalk),
                    Some(_) => continue,
                };
                let (settled, fitted) = self.settle(candidate)?;
                if !settled.contains(Column::RandomWalk)
                    || !fitted.check_whole(self.octaves)?.holds()
                {
                    continue;
                }
                let (ic, _) = self.criterion(&settled)?;
                if best.as_ref().is_none_or(|b| ic < b.0) {
                    best = Some((ic, settled, fitted));
                }
            }
            if let Some((_, settled, fitted)) = best {
                (set, model) = (settled, fitted);
            }
        }
        // A random walk less than one standard deviation above zero, without which the model
        // still passes the Allan check at every octave, is not identified.
        self.reweight(Some(&model));
        let walk = set.columns().iter().position(|c| *c == Column::RandomWalk);
        // A long Gauss-Markov term may carry the walk's rise: then the walk stays.
        let reach = self
            .octaves
            .tau(self.octaves.avar().len().saturating_sub(1))
            / RECORD_OCTAVES;
        let long = model
            .gauss_markov()
            .iter()
            .any(|t| t.correlation_time > reach / 4.0);
        let candidate = walk.filter(|_| model.random_walk() > 0.0 && !long && !from_term);
        if let Some(i) = candidate
            && !model.walk_significant(self)?
        {
            let (_, without) = self.settle(set.without(i))?;
            if without.check_whole(self.octaves)?.holds() {
                return Ok((without, limited));
            }
        }
        Ok((model, limited))
    }

    /// The fit of `set` (its zero terms left out, the set returned without them), from the
    /// data's own weights (another model's would judge the set by where that model bends:
    /// one that levels off predicts small variances at the last octaves, where a single low
    /// estimate then puts a rising term at zero), refined by its own weights; where that reweighting talks a term the data need down to zero, so
    /// that the refined fit fails the whole-curve check that the set's own fit passes, the
    /// set's own fit.
    fn settle(&mut self, set: Set) -> Result<(Set, Full<P>), NoiseError> {
        self.reweight::<MAX>(None);
        let (x, _) = self.nnls(set.columns())?;
        let set = Self::compact(&set, &x);
        let (x, _) = self.nnls(set.columns())?;
        let start = self.model_of(set.columns(), &x)?;
        let (refined, _) = self.refine(set.columns(), Some(&start))?;
        let model = if !refined.check_whole(self.octaves)?.holds()
            && start.check_whole(self.octaves)?.holds()
        {
            start
        } else {
            refined
        };
        Ok((set, model))
    }

    /// `set` with every Gauss-Markov term that [`Self::unbounded_term`] finds taken as the
    /// random walk, and whether one was.
    fn walks(&mut self, mut set: Set) -> Result<(Set, bool), NoiseError> {
        let mut taken = false;
        for _ in 0..set.len {
            match self.unbounded_term(&set)? {
                Some(i) => {
                    let walk = set.without(i);
                    let walk = if walk.contains(Column::RandomWalk) {
                        walk
                    } else {
                        walk.with(Column::RandomWalk)
                    };
                    // Unless the record contradicts the walk: the term explains every octave
                    // and the walk does not (a rise that levels off, as a long term's does).
                    // Each settled from the data's own weights (`settle`).
                    let (_, term) = self.settle(set)?;
                    let (_, walked) = self.settle(walk)?;
                    if term.check_whole(self.octaves)?.holds()
                        && !walked.check_whole(self.octaves)?.holds()
                    {
                        break;
                    }
                    taken = true;
                    set = walk;
                }
                None => break,
            }
        }
        Ok((set, taken))
    }

    /// The column of the Gauss-Markov term of `set` whose correlation time's 95 % upper end
    /// lies furthest beyond the longest `tau` (or that sits at the longest correlation time
    /// the record tells, [`RECORD_OCTAVES`]), if one does.
    fn unbounded_term(&mut self, set: &Set) -> Result<Option<usize>, NoiseError> {
        let (x, _) = self.nnls(set.columns())?;
        let model = self.model_of(set.columns(), &x)?;
        self.reweight(Some(&model));
        let spread = model.log_time_spread(self)?;
        let longest = self
            .octaves
            .tau(self.octaves.avar().len().saturating_sub(1));
        let mut worst: Option<(f64, f64)> = None;
        for (t, s) in model.gauss_markov().iter().zip(&spread) {
            let high = t.correlation_time * libm::exp(Z95 * s);
            // Pressed against the longest correlation time the record tells (the refinement's
            // bound), a term would be longer still: a random walk there too.
            let pressed = t.correlation_time >= 0.97 * longest / RECORD_OCTAVES;
            let beyond = pressed || high.partial_cmp(&longest) != Some(core::cmp::Ordering::Less);
            if beyond && worst.is_none_or(|w| high > w.0) {
                worst = Some((high, t.correlation_time));
            }
        }
        Ok(worst.and_then(|(_, t)| {
            set.columns()
                .iter()
                .position(|c| *c == Column::GaussMarkov(t))
        }))
    }

    /// `set` with column `i`'s correlation time (an oscillator's frequency and decay time)
    /// refined: a Gauss-Markov term's between `spacing` octaves either side (within one sample
    /// and [`RECORD_OCTAVES`] times less than the longest `tau`), an oscillator's frequency within half an octave and its decay
    /// within [`MIN_CYCLES`] to [`MAX_CYCLES`] periods.
    fn refine_term(&self, set: Set, i: usize, spacing: f64) -> Result<Set, NoiseError> {
        let dt = self.octaves.dt();
        let longest = self
            .octaves
            .tau(self.octaves.avar().len().saturating_sub(1));
        let ln = libm::log;
        match set.columns().get(i).copied() {
            Some(Column::GaussMarkov(t)) => {
                let half = spacing.max(1.0) * core::f64::consts::LN_2;
                let (lo, hi) = (
                    (ln(t) - half).max(ln(dt)),
                    (ln(t) + half).min(ln(longest / RECORD_OCTAVES)),
                );
                let u = self.golden(ln(t), lo, hi, |u| {
                    set.replaced(i, Column::GaussMarkov(libm::exp(u)))
                })?;
                Ok(set.replaced(i, Column::GaussMarkov(libm::exp(u))))
            }
            Some(Column::Oscillator(mut f, mut t)) => {
                // Frequency and decay trade along a narrow valley of the misfit (a longer decay
                // narrows the line as a lower frequency moves it): the two searches alternate
                // until neither moves.
                let half = core::f64::consts::LN_2 / 2.0;
                for _ in 0..OSCILLATOR_ROUNDS {
                    let lo = (ln(f) - half).max(ln(OSCILLATOR_MIN_HZ));
                    let hi = (ln(f) + half).min(ln(0.25 / dt));
                    let u = self.golden(ln(f), lo, hi, |u| {
                        set.replaced(i, Column::Oscillator(libm::exp(u), t))
                    })?;
                    let moved_f = libm::fabs(u - ln(f));
                    f = libm::exp(u);
                    let (lo, hi) = (ln(MIN_CYCLES / f), ln(MAX_CYCLES / f));
                    let v = self.golden(ln(t), lo, hi, |v| {
                        set.replaced(i, Column::Oscillator(f, libm::exp(v)))
                    })?;
                    let moved_t = libm::fabs(v - ln(t));
                    t = libm::exp(v);
                    if moved_f < 1e-4 && moved_t < 1e-3 {
                        break;
                    }
                }
                Ok(set.replaced(i, Column::Oscillator(f, t)))
            }
            _ => Ok(set),
        }
    }

    /// The `u` in `[lo, hi]` of least `chi^2` of `at(u)` by golden-section search, or `start`
    /// where that is no worse.
    fn golden(
        &self,
        start: f64,
        lo: f64,
        hi: f64,
        at: impl Fn(f64) -> Set,
    ) -> Result<f64, NoiseError> {
        let misfit = |u: f64| self.chi2(&at(u)).map(|(_, c)| c);
        let at_start = misfit(start)?;
        if lo.partial_cmp(&hi) != Some(core::cmp::Ordering::Less) {
            return Ok(start);
        }
        let r = (libm::sqrt(5.0) - 1.0) / 2.0;
        let (mut a, mut b) = (lo, hi);
        let (mut c, mut d) = (b - r * (b - a), a + r * (b - a));
        let (mut fc, mut fd) = (misfit(c)?, misfit(d)?);
        for _ in 0..GOLDEN_STEPS {
            if fc < fd {
                (b, d, fd) = (d, c, fc);
                c = b - r * (b - a);
                fc = misfit(c)?;
            } else {
                (a, c, fc) = (c, d, fd);
                d = a + r * (b - a);
                fd = misfit(d)?;
            }
        }
        let (u, best) = if fc < fd { (c, fc) } else { (d, fd) };
        Ok(if best < at_start { u } else { start })
    }
}
