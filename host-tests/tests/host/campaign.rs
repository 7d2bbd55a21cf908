//! The identification campaign (`imu_ar_host::campaign`): white + random walk, white +
//! GM(30 s) + random walk, white + three GM (1, 20, 300 s) + random walk and white only, at 100
//! and 400 Hz, 1 h and 4 h, six seeds each: 96 records, each fitted by the identified fit and
//! by the curve fit that fills the budget. The table of both is printed with
//! `cargo test -p imu-ar-host --test host -- campaign --nocapture`.

use imu_ar_host::campaign::{self, CASES};

#[test]
fn the_identified_fit_finds_the_truth_of_the_campaign() {
    let threads = std::thread::available_parallelism().map_or(1, |n| n.get());
    let records = campaign::run(6, threads);
    println!("{}", campaign::table(&records));
    let s = campaign::summary(&records, true);
    assert_eq!(s.records, 96);
    // K where the random walk dominates the last 1.5 decades: within 30 % on 90 %, never
    // missing.
    assert!(s.walk_records >= 24, "{s:?}");
    assert!(10 * s.k_within_30pc >= 9 * s.walk_records, "{s:?}");
    assert_eq!(s.k_missing, 0, "{s:?}");
    // N within 3 % on every record; the Allan check at every octave on 95 %.
    assert_eq!(s.n_within_3pc, s.records, "{s:?}");
    assert!(100 * s.check_holds >= 95 * s.records, "{s:?}");
    // White only: a spurious K in at most 1 of 6 runs of each configuration, and then with an
    // interval reaching zero.
    for (rate, span) in campaign::RATES
        .iter()
        .flat_map(|r| campaign::SPANS.iter().map(move |s| (*r, *s)))
    {
        let white: Vec<_> = records
            .iter()
            .filter(|r| CASES[r.case].random_walk == 0.0 && r.rate == rate && r.span == span)
            .collect();
        let spurious = white.iter().filter(|r| r.identified.k > 0.0).count();
        assert!(spurious <= 1, "{rate} Hz {span} s: K on {spurious} of 6");
    }
    assert_eq!(
        s.white_spurious_k, s.white_spurious_k_reaching_zero,
        "{s:?}"
    );
    // The 95 % intervals of N and K contain the truth in 85 to 99 % of the records.
    for (covered, of) in [(s.n_covered, s.n_intervals), (s.k_covered, s.k_intervals)] {
        assert!(of > 0);
        let rate = covered as f64 / of as f64;
        assert!(
            (0.85..=0.99).contains(&rate),
            "coverage {covered} of {of}: {s:?}"
        );
    }
}
