//! The composite noise model fitted to simulated records of known truth (`Composite`), 100 Hz,
//! 2,000,000 samples, five seeds per case.

use imu_ar::noise::{FitConfig, NoiseModel, Octaves};
use imu_ar_host::composite::Composite;

const N: usize = 2_000_000;
const SEEDS: u64 = 5;

/// The fit of one seed, and how far its Allan deviation strays from the truth's: the largest
/// relative error where the data's own standard error is below 5 % (the fit cannot know the
/// truth better than the data where it is not), and the largest in units of that standard
/// error elsewhere.
struct Outcome {
    model: NoiseModel<1, 4>,
    within_5pc_data: f64,
    beyond_in_se: f64,
}

fn fit(truth: &Composite, seed: u64, budget: usize) -> Outcome {
    let x = truth.simulate(N, seed);
    let octaves = Octaves::<24>::overlapping(&x, truth.dt).unwrap();
    let model = NoiseModel::<1, 4>::fit(&octaves, None, &FitConfig::new(budget)).unwrap();
    let check = model.check(&octaves).unwrap();
    let (mut within, mut beyond) = (0.0f64, 0.0f64);
    for (j, row) in check.rows().iter().enumerate() {
        let err = row.model_adev / truth.avar(1 << j).sqrt() - 1.0;
        // The check's tolerance is two standard errors of the data, floored at 10 %.
        let se = row.tolerance / 2.0;
        if row.tolerance > 0.1 {
            beyond = beyond.max(err.abs() / se);
        } else {
            within = within.max(err.abs());
        }
    }
    Outcome {
        model,
        within_5pc_data: within,
        beyond_in_se: beyond,
    }
}

fn run(truth: &Composite, budget: usize) -> Vec<Outcome> {
    (0..SEEDS)
        .map(|seed| {
            let o = fit(truth, seed, budget);
            println!(
                "seed {seed}: N/true {:.4} K {:.3e} (true {:.1e}) GM {:?} |model/truth - 1| {:.3} \
                 where the data's SE < 5 %, {:.2} SE beyond",
                o.model.white_noise() / truth.white,
                o.model.random_walk(),
                truth.random_walk,
                o.model
                    .gauss_markov()
                    .iter()
                    .map(|t| (t.sigma, t.correlation_time))
                    .collect::<Vec<_>>(),
                o.within_5pc_data,
                o.beyond_in_se
            );
            o
        })
        .collect()
}

fn assert_common(truth: &Composite, outcomes: &[Outcome]) {
    for (seed, o) in outcomes.iter().enumerate() {
        let n = o.model.white_noise() / truth.white - 1.0;
        assert!(n.abs() < 0.03, "seed {seed}: N off by {n}");
        assert!(
            o.within_5pc_data < 0.10,
            "seed {seed}: ADEV off by {}",
            o.within_5pc_data
        );
        assert!(
            o.beyond_in_se < 3.0,
            "seed {seed}: ADEV off by {} SE",
            o.beyond_in_se
        );
    }
}

#[test]
fn white_gauss_markov_and_a_dominant_random_walk() {
    // The random walk dominates from about 40 s to the end of the record (5,000 s).
    let truth = Composite {
        dt: 0.01,
        white: 0.005,
        quantization: 0.0,
        gm: vec![(2e-3, 5.0)],
        random_walk: 2e-4,
    };
    let outcomes = run(&truth, 1);
    assert_common(&truth, &outcomes);
    for (seed, o) in outcomes.iter().enumerate() {
        let k = o.model.random_walk() / truth.random_walk - 1.0;
        assert!(k.abs() < 0.3, "seed {seed}: K off by {k}");
    }
}

#[test]
fn white_three_gauss_markov_terms_and_a_random_walk() {
    let truth = Composite {
        dt: 0.01,
        white: 0.01,
        quantization: 0.0,
        gm: vec![(3e-3, 1.0), (2e-3, 20.0), (1e-3, 300.0)],
        random_walk: 2e-5,
    };
    assert_common(&truth, &run(&truth, 3));
}

#[test]
fn white_and_quantization() {
    let truth = Composite {
        dt: 0.01,
        white: 0.01,
        quantization: 1e-3,
        gm: vec![],
        random_walk: 0.0,
    };
    let outcomes = run(&truth, 2);
    assert_common(&truth, &outcomes);
    for (seed, o) in outcomes.iter().enumerate() {
        let q = o.model.quantization() / truth.quantization - 1.0;
        assert!(q.abs() < 0.03, "seed {seed}: Q off by {q}");
    }
}
