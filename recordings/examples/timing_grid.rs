//! A grid of clocks near their stamps' quantum's rate, against the rate read from the stamps.
//!
//! `cargo run --release -p imu-ar-recordings --example timing_grid`
//!
//! 24 rates from 333.3 to 2010 Hz, floored to whole ms; 3000, 20,000 and 100,000 samples;
//! Gaussian jitter of 0, 1 and 5 % of a period; 0, 1 and 3 % lost at random; two seeds each.
//! Each record is `ok` (read within 3e-4, with or without a warning), `held` (read further
//! off, with a warning whose range holds the rate, or a standard error's), `missed` (a
//! warning whose range leaves the rate out), `refused`, or `WRONG` (read further off with no
//! warning). The records neither ok nor refused are listed, then the counts.

use imu_ar_recordings::timing::{Step, TimeUnit, Timing};

/// xorshift64.
fn xorshift(mut state: u64) -> impl FnMut() -> u64 {
    move || {
        state ^= state << 13;
        state ^= state >> 7;
        state ^= state << 17;
        state
    }
}

/// Samples of a clock at `rate` jittered by `rms` periods RMS, floored to whole ms (ns),
/// each lost with the chance `lose`.
fn clock(rate: f64, n: usize, rms: f64, lose: f64, seed: u64) -> Vec<i64> {
    let mixed = (seed + (rate * 1000.0) as u64).wrapping_mul(0x9e37_79b9_7f4a_7c15) | 1;
    let mut next = xorshift(mixed);
    let mut uniform = move || ((next() >> 11) as f64 + 0.5) / (1u64 << 53) as f64;
    let mut t: Vec<i64> = (0..n)
        .filter_map(|k| {
            let (a, b) = (uniform(), uniform());
            let normal = (-2.0 * a.ln()).sqrt() * (std::f64::consts::TAU * b).cos();
            let lost = uniform() < lose;
            let at = (k as f64 + rms * normal) / (rate * 1e-3);
            (!lost).then(|| (at.floor() * 1e-3 * 1e9).round() as i64)
        })
        .collect();
    for i in 1..t.len() {
        t[i] = t[i].max(t[i - 1]);
    }
    t
}

/// The range a warning gives, Hz.
fn range(w: &str) -> Option<(f64, f64)> {
    let mut it = w.split("between ").nth(1)?.split(" Hz and ");
    let low = it.next()?.parse().ok()?;
    let high = it.next()?.split(" Hz").next()?.parse().ok()?;
    Some((low, high))
}

fn main() {
    let rates = [
        990.0, 995.0, 998.0, 999.0, 999.5, 999.9, 1000.0, 1000.1, 1000.5, 1001.0, 1002.0, 1005.0,
        1013.99, 1100.0, 1333.3, 1501.63, 1800.0, 2000.0, 1990.0, 2010.0, 500.0, 499.0, 400.0,
        333.3,
    ];
    let [mut ok, mut held, mut missed, mut refused, mut wrong] = [0u32; 5];
    for rate in rates {
        for n in [3000, 20_000, 100_000] {
            for rms in [0.0, 0.01, 0.05] {
                for lose in [0.0, 0.01, 0.03] {
                    for seed in 1..3 {
                        let what = format!(
                            "{rate} Hz, {n} samples, jitter {rms}, lost {lose}, seed {seed}"
                        );
                        let mut timing = Timing::new();
                        for s in clock(rate, n, rms, lose, seed) {
                            match timing.push(s) {
                                Step::Forward => {}
                                Step::Repeat => timing.keep_repeat(),
                                Step::Backward { .. } => unreachable!("stamps in order"),
                            }
                        }
                        let s = match timing.summary(TimeUnit::Nanoseconds) {
                            Ok(s) if s.batch_refusal().or_else(|| s.repeat_refusal()).is_none() => {
                                s
                            }
                            _ => {
                                refused += 1;
                                continue;
                            }
                        };
                        let warnings: Vec<String> =
                            [s.coarse_warning(), s.quantum_warning(), s.loose_warning()]
                                .into_iter()
                                .flatten()
                                .collect();
                        if (s.rate_hz / rate - 1.0).abs() < 3e-4 {
                            ok += 1;
                        } else if warnings.is_empty() {
                            wrong += 1;
                            println!("WRONG {what}: {} Hz", s.rate_hz);
                        } else if warnings.iter().any(|w| {
                            w.contains("standard error")
                                || range(w).is_some_and(|(a, b)| a <= rate && rate <= b)
                        }) {
                            held += 1;
                        } else {
                            missed += 1;
                            println!("missed {what}: {} Hz: {warnings:?}", s.rate_hz);
                        }
                    }
                }
            }
        }
    }
    println!("ok {ok} held {held} missed {missed} refused {refused} WRONG {wrong}");
}
