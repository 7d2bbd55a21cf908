//! The identification campaign: records of known composite noise (white noise, Gauss-Markov
//! terms, random walk), at 100 and 400 Hz, 1 h and 4 h, several seeds each, fitted by the
//! identified fit ([`NoiseModel::identify`]) and by the curve fit that fills the budget
//! ([`FitConfig::with_identification`]`(false)`), and scored against the truth.

use imu_ar::noise::{Coefficients, FitConfig, GmTerm, NoiseModel, Octaves};

use crate::composite::Composite;

/// The octaves held.
pub const OCTAVES: usize = 24;

/// The Gauss-Markov budget of every fit.
pub const BUDGET: usize = 3;

/// The model type of the campaign.
pub type Model = NoiseModel<1, 4>;

/// One truth of the campaign.
#[derive(Clone, Debug)]
pub struct Case {
    /// Its name.
    pub name: &'static str,
    /// White noise `N`, u/sqrt(Hz).
    pub white: f64,
    /// Gauss-Markov `(sigma, T)`.
    pub gm: &'static [(f64, f64)],
    /// Random walk `K`, u/s/sqrt(Hz).
    pub random_walk: f64,
}

/// The four truths: white + random walk, white + GM(30 s) + random walk, white + three GM
/// (1, 20, 300 s) + random walk, white only. Units: a gyro in deg/s.
pub const CASES: [Case; 4] = [
    Case {
        name: "WN+RW",
        white: 5e-3,
        gm: &[],
        random_walk: 4e-4,
    },
    Case {
        name: "WN+GM30+RW",
        white: 5e-3,
        gm: &[(2e-3, 30.0)],
        random_walk: 4e-4,
    },
    Case {
        name: "WN+3GM+RW",
        white: 5e-3,
        gm: &[(3e-3, 1.0), (1.5e-3, 20.0), (2e-3, 300.0)],
        random_walk: 1e-4,
    },
    Case {
        name: "WN",
        white: 5e-3,
        gm: &[],
        random_walk: 0.0,
    },
];

/// Sample rates, Hz.
pub const RATES: [f64; 2] = [100.0, 400.0];

/// Record lengths, s.
pub const SPANS: [f64; 2] = [3600.0, 14_400.0];

/// What one fit gave, against the truth.
#[derive(Clone, Debug)]
pub struct Score {
    /// `N / N_true`.
    pub n_ratio: f64,
    /// `K` (0 when the model has none).
    pub k: f64,
    /// The 95 % interval of `N`, when the fit gives one.
    pub n_interval: Option<(f64, f64)>,
    /// The 95 % interval of `K`, when the fit gives one.
    pub k_interval: Option<(f64, f64)>,
    /// Whether the Allan check as one 95 % test of the whole curve holds at every octave.
    pub check_holds: bool,
    /// Gauss-Markov terms and oscillators.
    pub terms: usize,
    /// The Gauss-Markov terms' correlation times, s.
    pub times: Vec<f64>,
    /// Whether the budget limited the model.
    pub budget_limited: bool,
    /// Whether the model is the curve fit's (for the identified fit: its terms failed the
    /// whole-curve check where the curve fit passes it).
    pub curve_fit: bool,
}

/// One record of the campaign and both fits of it.
#[derive(Clone, Debug)]
pub struct Record {
    /// The truth's index in [`CASES`].
    pub case: usize,
    /// Sample rate, Hz.
    pub rate: f64,
    /// Span, s.
    pub span: f64,
    /// Seed.
    pub seed: u64,
    /// Whether the true random walk dominates the truth's Allan variance over the last 1.5
    /// decades of `tau` the record resolves.
    pub walk_dominates: bool,
    /// The identified fit.
    pub identified: Score,
    /// The curve fit that fills the budget.
    pub curve_fit: Score,
    /// Whether the true model passes the Allan check at every octave of the record.
    pub truth_holds: bool,
}

impl Case {
    /// The truth as a simulator at `dt`.
    pub fn composite(&self, dt: f64) -> Composite {
        Composite {
            dt,
            white: self.white,
            quantization: 0.0,
            gm: self.gm.to_vec(),
            random_walk: self.random_walk,
        }
    }
}

/// Whether the random walk's Allan variance exceeds the rest of `truth`'s at every octave in
/// the last 1.5 decades up to `octaves` octaves.
pub fn walk_dominates(truth: &Composite, octaves: usize) -> bool {
    let Some(last) = octaves.checked_sub(1) else {
        return false;
    };
    let tau_last = truth.dt * (1u64 << last) as f64;
    let walk = Composite {
        white: 0.0,
        gm: Vec::new(),
        ..truth.clone()
    };
    let rest = Composite {
        random_walk: 0.0,
        ..truth.clone()
    };
    (0..octaves)
        .filter(|j| truth.dt * (1u64 << j) as f64 >= tau_last / 10f64.powf(1.5))
        .all(|j| walk.avar(1 << j) > rest.avar(1 << j))
}

fn score(
    model: &Model,
    (budget_limited, curve_fit): (bool, bool),
    truth: &Composite,
    octaves: &Octaves<OCTAVES>,
    intervals: Option<((f64, f64), (f64, f64))>,
) -> Score {
    Score {
        n_ratio: model.white_noise() / truth.white,
        k: model.random_walk(),
        n_interval: intervals.map(|i| i.0),
        k_interval: intervals.map(|i| i.1),
        check_holds: model.check_whole(octaves).is_ok_and(|c| c.holds()),
        terms: model.gauss_markov().len() + model.oscillators().len(),
        times: model
            .gauss_markov()
            .iter()
            .map(|t| t.correlation_time)
            .collect(),
        budget_limited,
        curve_fit,
    }
}

/// Simulates and fits one record.
///
/// # Panics
///
/// When a fit fails: every record of the campaign has a model.
pub fn record(case: usize, rate: f64, span: f64, seed: u64) -> Record {
    let c = &CASES[case];
    let dt = 1.0 / rate;
    let truth = c.composite(dt);
    let n = (span * rate) as usize;
    let x = truth.simulate(n, seed.wrapping_mul(0x9e37_79b9).wrapping_add(case as u64));
    let octaves = Octaves::<OCTAVES>::overlapping(&x, dt).expect("octaves");
    let config = FitConfig::new(BUDGET).with_identification(true);
    let fit = Model::identify(&octaves, None, &config).expect("identified fit");
    let intervals = fit.model.uncertainty(&octaves).ok().map(|u| {
        (
            (u.white_noise.low, u.white_noise.high),
            (u.random_walk.low, u.random_walk.high),
        )
    });
    let identified = score(
        &fit.model,
        (fit.budget_limited, fit.curve_fit),
        &truth,
        &octaves,
        intervals,
    );
    let old = Model::fit(&octaves, None, &config.with_identification(false)).expect("curve fit");
    let curve_fit = score(&old, (false, true), &truth, &octaves, None);
    let terms: Vec<GmTerm> =
        c.gm.iter()
            .map(|&(sigma, correlation_time)| GmTerm {
                sigma,
                correlation_time,
            })
            .collect();
    let coefficients = Coefficients {
        white: c.white,
        random_walk: c.random_walk,
        ..Coefficients::default()
    };
    let true_model = Model::new(dt, coefficients, &terms, &[], None).expect("true model");
    let truth_holds = true_model.check_whole(&octaves).is_ok_and(|c| c.holds());
    Record {
        case,
        rate,
        span,
        seed,
        walk_dominates: c.random_walk > 0.0 && walk_dominates(&truth, octaves.avar().len()),
        identified,
        curve_fit,
        truth_holds,
    }
}

/// Every record of the campaign with `seeds` seeds, on `threads` threads.
pub fn run(seeds: u64, threads: usize) -> Vec<Record> {
    run_from(0, seeds, threads)
}

/// [`run`] with the seeds `first..first + seeds`: fresh seeds, for a check that the figures
/// do not belong to the seeds they were first measured on.
pub fn run_from(first: u64, seeds: u64, threads: usize) -> Vec<Record> {
    let mut jobs = Vec::new();
    for case in 0..CASES.len() {
        for &rate in &RATES {
            for &span in &SPANS {
                for seed in first..first.saturating_add(seeds) {
                    jobs.push((case, rate, span, seed));
                }
            }
        }
    }
    // The longest first, so that the threads finish together.
    jobs.sort_by(|p, q| (q.1 * q.2).total_cmp(&(p.1 * p.2)));
    let jobs = std::sync::Mutex::new(jobs.into_iter());
    let done = std::sync::Mutex::new(Vec::new());
    std::thread::scope(|s| {
        for _ in 0..threads.max(1) {
            s.spawn(|| {
                loop {
                    let job = jobs.lock().expect("jobs").next();
                    let Some((case, rate, span, seed)) = job else {
                        break;
                    };
                    let r = record(case, rate, span, seed);
                    done.lock().expect("records").push(r);
                }
            });
        }
    });
    let mut records = done.into_inner().expect("records");
    records.sort_by(|p, q| {
        (p.case, p.rate as u64, p.span as u64, p.seed).cmp(&(
            q.case,
            q.rate as u64,
            q.span as u64,
            q.seed,
        ))
    });
    records
}

/// The campaign's figures for one fit.
#[derive(Clone, Copy, Debug, Default)]
pub struct Summary {
    /// Records where the random walk dominates the last 1.5 decades.
    pub walk_records: usize,
    /// Of those, `K` within 30 % of the truth.
    pub k_within_30pc: usize,
    /// Of those, `K` missing.
    pub k_missing: usize,
    /// Median `K / K_true` over those.
    pub k_median: f64,
    /// Records.
    pub records: usize,
    /// `N` within 3 % of the truth.
    pub n_within_3pc: usize,
    /// The Allan check holds at every octave.
    pub check_holds: usize,
    /// White-only records.
    pub white_records: usize,
    /// White-only records with a `K`.
    pub white_spurious_k: usize,
    /// Of those, `K`'s interval reaching zero.
    pub white_spurious_k_reaching_zero: usize,
    /// `N`'s interval contains the truth (records with an interval).
    pub n_covered: usize,
    /// `K`'s interval contains the truth (records with a true random walk and an interval).
    pub k_covered: usize,
    /// Records with a true random walk and an interval of `K`.
    pub k_intervals: usize,
    /// Records with an interval of `N`.
    pub n_intervals: usize,
    /// Records where the true model passes the Allan check at every octave.
    pub truth_holds: usize,
    /// Records where the identified fit gave way to the curve fit.
    pub curve_fit_stood: usize,
}

/// The figures of `records`, for the identified fit (`identified`) or the curve fit.
pub fn summary(records: &[Record], identified: bool) -> Summary {
    let mut s = Summary::default();
    let mut ratios = Vec::new();
    for r in records {
        let c = &CASES[r.case];
        let score = if identified {
            &r.identified
        } else {
            &r.curve_fit
        };
        s.records += 1;
        s.n_within_3pc += usize::from((score.n_ratio - 1.0).abs() <= 0.03);
        s.check_holds += usize::from(score.check_holds);
        s.truth_holds += usize::from(r.truth_holds);
        s.curve_fit_stood += usize::from(identified && score.curve_fit);
        if r.walk_dominates {
            s.walk_records += 1;
            let ratio = score.k / c.random_walk;
            ratios.push(ratio);
            s.k_within_30pc += usize::from((ratio - 1.0).abs() <= 0.3);
            s.k_missing += usize::from(score.k == 0.0);
        }
        if c.random_walk == 0.0 {
            s.white_records += 1;
            if score.k > 0.0 {
                s.white_spurious_k += 1;
                s.white_spurious_k_reaching_zero +=
                    usize::from(score.k_interval.is_some_and(|i| i.0 == 0.0));
            }
        }
        if let Some((lo, hi)) = score.n_interval {
            s.n_intervals += 1;
            s.n_covered += usize::from(lo <= c.white && c.white <= hi);
        }
        if let Some((lo, hi)) = score.k_interval.filter(|_| c.random_walk > 0.0) {
            s.k_intervals += 1;
            s.k_covered += usize::from(lo <= c.random_walk && c.random_walk <= hi);
        }
    }
    ratios.sort_by(f64::total_cmp);
    s.k_median = ratios.get(ratios.len() / 2).copied().unwrap_or(f64::NAN);
    s
}

/// The campaign as a table: one line per record, then the summary of both fits.
pub fn table(records: &[Record]) -> String {
    let mut out = String::from(
        "case        rate  span seed rw-dom | identified: N/true  K/true  K 95% interval     \
         terms check limited | curve fit: N/true  K/true  terms check\n",
    );
    for r in records {
        let c = &CASES[r.case];
        let k = |v: f64| {
            if c.random_walk > 0.0 {
                format!("{:7.3}", v / c.random_walk)
            } else {
                format!("{v:7.1e}")
            }
        };
        let interval = r.identified.k_interval.map_or("-".to_string(), |(lo, hi)| {
            if c.random_walk > 0.0 {
                format!("[{:.3}, {:.3}]", lo / c.random_walk, hi / c.random_walk)
            } else {
                format!("[{lo:.1e}, {hi:.1e}]")
            }
        });
        out += &format!(
            "{:11} {:4} {:5} {:4} {:6} | {:17.4} {} {:18} {:5} {:5} {:7} | {:16.4} {} {:5} {:5} | T {:.0?} | {:.0?}\n",
            c.name,
            r.rate,
            r.span,
            r.seed,
            r.walk_dominates,
            r.identified.n_ratio,
            k(r.identified.k),
            interval,
            r.identified.terms,
            r.identified.check_holds,
            r.identified.budget_limited,
            r.curve_fit.n_ratio,
            k(r.curve_fit.k),
            r.curve_fit.terms,
            r.curve_fit.check_holds,
            r.identified.times,
            r.curve_fit.times,
        );
    }
    for (i, c) in CASES.iter().enumerate() {
        let of: Vec<Record> = records.iter().filter(|r| r.case == i).cloned().collect();
        let s = summary(&of, true);
        out += &format!(
            "{:11}: K interval covers on {} of {}, N on {} of {}; the true model passes the \
             check on {} of {}\n",
            c.name,
            s.k_covered,
            s.k_intervals,
            s.n_covered,
            s.n_intervals,
            s.truth_holds,
            s.records
        );
    }
    for (name, identified) in [("identified", true), ("curve fit (budget filled)", false)] {
        let s = summary(records, identified);
        out += &format!(
            "\n{name}:\n  random walk dominant on {} records: K within 30 % on {} ({:.0} %), \
             missing on {}, median K/true {:.3}\n  N within 3 % on {} of {}; Allan check \
             holds at every octave on {} of {} ({:.0} %)\n  white only: K on {} of {} \
             (interval reaching zero on {})\n",
            s.walk_records,
            s.k_within_30pc,
            100.0 * s.k_within_30pc as f64 / s.walk_records.max(1) as f64,
            s.k_missing,
            s.k_median,
            s.n_within_3pc,
            s.records,
            s.check_holds,
            s.records,
            100.0 * s.check_holds as f64 / s.records.max(1) as f64,
            s.white_spurious_k,
            s.white_records,
            s.white_spurious_k_reaching_zero,
        );
        if identified {
            out += &format!(
                "  the curve fit stood (identified terms failing the check) on {} of {}\n",
                s.curve_fit_stood, s.records
            );
            out += &format!(
                "  95 % intervals contain the truth: N on {} of {} ({:.0} %), K on {} of {} \
                 ({:.0} %)\n",
                s.n_covered,
                s.n_intervals,
                100.0 * s.n_covered as f64 / s.n_intervals.max(1) as f64,
                s.k_covered,
                s.k_intervals,
                100.0 * s.k_covered as f64 / s.k_intervals.max(1) as f64,
            );
        }
    }
    out
}
