//! The identification campaign (`imu_ar_host::campaign`): white + random walk, white +
//! GM(30 s) + random walk, white + three GM (1, 20, 300 s) + random walk and white only, at 100
//! and 400 Hz, 1 h and 4 h, twelve seeds each: 192 records, each fitted by the identified fit
//! and by the curve fit that fills the budget. The table of both is printed with
//! `cargo test -p imu-ar-host --test host -- campaign --nocapture`.

use imu_ar_host::campaign::{self, CASES};

#[test]
fn the_identified_fit_finds_the_truth_of_the_campaign() {
    let threads = std::thread::available_parallelism().map_or(1, |n| n.get());
    // IMU_AR_CAMPAIGN_SEED=S runs the seeds S..S+12 instead (the figures below are those of 0..12).
    let first = std::env::var("IMU_AR_CAMPAIGN_SEED")
        .ok()
        .and_then(|s| s.parse().ok())
        .unwrap_or(0);
    let records = campaign::run_from(first, 12, threads);
    println!("{}", campaign::table(&records));
    let s = campaign::summary(&records, true);
    assert_eq!(s.records, 192);
    // K where the random walk dominates the last 1.5 decades: within 30 % on at least 90 %,
    // never missing. Measured: seeds 0..12, 87 of 96 (91 %); seeds 12..24, 88 of 96 (92 %);
    // missing on none. The misses are 1 h records whose 30 s Gauss-Markov term (its
    // random-walk equivalent above the true K) the criterion leaves out, so that K carries its
    // rise, or where a spurious 20-40 s term takes part of the walk's.
    assert!(s.walk_records >= 48, "{s:?}");
    assert!(10 * s.k_within_30pc >= 9 * s.walk_records, "{s:?}");
    assert_eq!(s.k_missing, 0, "{s:?}");
    // N within 3 % on every record; the Allan check at every octave on 95 %.
    assert_eq!(s.n_within_3pc, s.records, "{s:?}");
    assert!(100 * s.check_holds >= 95 * s.records, "{s:?}");
    // White only: a spurious K in at most 1 of 6 runs of each configuration (2 of 12), and
    // then with an interval reaching zero.
    for (rate, span) in campaign::RATES
        .iter()
        .flat_map(|r| campaign::SPANS.iter().map(move |s| (*r, *s)))
    {
        let white: Vec<_> = records
            .iter()
            .filter(|r| CASES[r.case].random_walk == 0.0 && r.rate == rate && r.span == span)
            .collect();
        let spurious = white.iter().filter(|r| r.identified.k > 0.0).count();
        assert!(spurious <= 2, "{rate} Hz {span} s: K on {spurious} of 12");
    }
    assert_eq!(
        s.white_spurious_k, s.white_spurious_k_reaching_zero,
        "{s:?}"
    );
    // The 95 % intervals of N and K contain the truth in 85 to 99 % of the records. Measured
    // on seeds 0..12: N 184 of 192 (96 %), K 133 of 144 (92 %); on seeds 12..24: N 182 of 192
    // (95 %), K 135 of 144 (94 %).
    for (covered, of) in [(s.n_covered, s.n_intervals), (s.k_covered, s.k_intervals)] {
        assert!(of > 0);
        let rate = covered as f64 / of as f64;
        assert!(
            (0.85..=0.99).contains(&rate),
            "coverage {covered} of {of}: {s:?}"
        );
    }
}

/// A 0.6 Hz line with damping 0.05 (decay time 5.3 s) over white noise and a random walk, one
/// hour at 100 Hz: identified with oscillators allowed and a budget of five states, its
/// frequency is found within 2 %, and no second oscillator is spent on it.
#[test]
fn a_damped_line_is_found_once_within_two_percent() {
    use imu_ar::noise::{FitConfig, NoiseModel, Octaves};
    use imu_ar_host::composite::{Composite, oscillator};
    let dt = 0.01;
    let truth = Composite {
        dt,
        white: 0.01,
        quantization: 0.0,
        gm: Vec::new(),
        random_walk: 1e-4,
    };
    let config = FitConfig::new(5)
        .with_oscillators(true)
        .with_identification(true);
    let mut covered = 0;
    for seed in 0..6 {
        let n = 360_000;
        let line = oscillator(0.02, 0.6, 0.05, dt, n, 900 + seed);
        let x: Vec<f64> = truth
            .simulate(n, 700 + seed)
            .iter()
            .zip(&line)
            .map(|(a, b)| a + b)
            .collect();
        let octaves = Octaves::<24>::overlapping(&x, dt).unwrap();
        let fit = NoiseModel::<1, 5>::identify(&octaves, None, &config).unwrap();
        let m = fit.model;
        let u = m.uncertainty(&octaves).unwrap();
        let lines: Vec<_> = m
            .oscillators()
            .iter()
            .map(|o| (o.frequency, o.decay_time))
            .collect();
        println!(
            "seed {seed}: oscillators (f Hz, decay s) {lines:?}, f interval {:?}, GM {:?}",
            u.oscillators()
                .first()
                .map(|o| (o.frequency.low, o.frequency.high)),
            m.gauss_markov()
                .iter()
                .map(|t| (t.sigma, t.correlation_time))
                .collect::<Vec<_>>()
        );
        assert_eq!(lines.len(), 1, "seed {seed}: {lines:?}");
        let (f, _) = lines[0];
        assert!((f / 0.6 - 1.0).abs() <= 0.02, "seed {seed}: {f} Hz");
        assert!(m.check_whole(&octaves).unwrap().holds(), "seed {seed}");
        // No state on a term that forgets within a few samples: that is white noise.
        let short = m
            .gauss_markov()
            .iter()
            .find(|t| t.correlation_time <= 3.0 * dt);
        assert!(short.is_none(), "seed {seed}: {short:?}");
        covered += usize::from(u.oscillators()[0].frequency.contains(0.6));
    }
    // The 95 % interval of the frequency holds the line's on (nearly) every record.
    assert!(covered >= 5, "{covered} of 6");
}

/// A white + random-walk record (400 Hz, 1 h, seed 19) whose last octave dips: the forward
/// steps took a 655 s term, and the walk that should replace it was solved first under the
/// term's weights, which put it at zero, so that the walk "failed" the check and the term, then
/// the curve fit, stood without a `K`. Judged by its own weights, the walk is found.
#[test]
fn a_walk_that_replaces_a_long_term_is_judged_by_its_own_weights() {
    let r = campaign::record(0, 400.0, 3600.0, 19);
    assert!(r.walk_dominates);
    let k = r.identified.k / CASES[0].random_walk;
    assert!((0.7..=1.3).contains(&k), "K / K_true = {k}: {r:?}");
    assert!(r.identified.check_holds && !r.identified.curve_fit, "{r:?}");
}

/// White + random-walk records at 10 Hz for 4 h, 24 seeds: the last octaves (3277 and 6554 s)
/// hold one or two degrees of freedom, and a chance low there made a Gauss-Markov term fit
/// better than the walk; that term levels off where the record still rises, so the identified
/// set failed the whole-curve check and the curve fit stood, on seed 213 without a `K` (its
/// bound below the truth; the curve fit stood on 2 of seeds 0..300, `K` missing on 1). The
/// walk, added or in the term's place, passes: it stands, and `K` is never missing.
#[test]
fn a_chance_low_at_the_last_octaves_does_not_lose_the_walk() {
    let records: Vec<_> = (200..224)
        .map(|seed| campaign::record(0, 10.0, 14_400.0, seed))
        .collect();
    for r in &records {
        let k = r.identified.k / CASES[0].random_walk;
        eprintln!(
            "seed {:2}: K / K_true {k:.3}, terms {:?}, curve fit {}, check {}",
            r.seed, r.identified.times, r.identified.curve_fit, r.identified.check_holds
        );
    }
    let missing = records.iter().filter(|r| r.identified.k == 0.0).count();
    let within = records
        .iter()
        .filter(|r| (0.7..=1.3).contains(&(r.identified.k / CASES[0].random_walk)))
        .count();
    assert_eq!(missing, 0, "K missing on {missing} of 24");
    assert!(records.iter().all(|r| !r.identified.curve_fit));
    assert!(within >= 21, "K within 30 % on {within} of 24");
    assert!(records.iter().all(|r| r.identified.check_holds));
}
