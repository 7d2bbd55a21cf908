//! A random sweep of the rate read from timestamps, against the rate the stamps were made at.
//!
//! `cargo run --release -p imu-ar-recordings --example timing_sweep -- KIND SEED COUNT [INDEX]`
//!
//! KIND `clock`: a sensor stamped sample by sample (ns, us or ms floored; a counter of some
//! 20 kHz to 10 MHz rounded to ns or us; float32 seconds since boot; float64 epoch seconds;
//! epoch ns through a double), with jitter up to a tenth of a period, up to 1 % lost, drift up
//! to 1000 ppm. KIND `fifo`: a sensor 0.01 % to 3 % off a nominal rate, drifting up to
//! 1000 ppm, whose FIFO is read on a timer of its own (1 to 50 ms, jittered up to 1 ms), each
//! read's samples stamped back from the read at the sensor's period or a nominal one, ns, us
//! or ms, up to 1 % of the messages lost after stamping. Each record is `ok` (read within
//! 3e-4 of the rate it was made at), `refused`, `warned` (read further off, with the warning
//! that losses within stamps far coarser than the period leave no mark) or `WRONG` (read
//! further off, no error and no warning), as the host tool reads a time column without
//! `--rate`; the records not `ok` are
//! listed, then the counts. INDEX reads that record alone, and CSV (after it) writes its stamps
//! there, a `t_ns,gx` CSV the host tool reads.

use imu_ar_recordings::timing::{Step, TimeUnit, Timing};

/// xorshift64, uniform in [0, 1).
struct Rng(u64);

impl Rng {
    fn uniform(&mut self) -> f64 {
        self.0 ^= self.0 << 13;
        self.0 ^= self.0 >> 7;
        self.0 ^= self.0 << 17;
        (self.0 >> 11) as f64 / (1u64 << 53) as f64
    }

    fn pick<T: Copy>(&mut self, v: &[T]) -> T {
        v[(self.uniform() * v.len() as f64) as usize % v.len()]
    }

    fn log_uniform(&mut self, a: f64, b: f64) -> f64 {
        (a.ln() + self.uniform() * (b.ln() - a.ln())).exp()
    }
}

/// A stamp of `s` seconds written as `form` (`counter` Hz, or float32 seconds from `counter`
/// s), in ns.
fn stamp(form: &str, s: f64, counter: f64) -> i64 {
    match form {
        "ns" => (s * 1e9).floor() as i64,
        "us" => (s * 1e6).floor() as i64 * 1_000,
        "ms" => (s * 1e3).floor() as i64 * 1_000_000,
        "counter_ns" => ((s * counter).floor() / counter * 1e9).round() as i64,
        "counter_us" => ((s * counter).floor() / counter * 1e6).round() as i64 * 1_000,
        "float32" => (f64::from((s + counter) as f32) * 1e9).round() as i64,
        "epoch_seconds" => ((1.6e9 + s) * 1e9).round() as i64 - 1_600_000_000_000_000_000,
        _ => (1.6e18 + s * 1e9) as i64 - 1_600_000_000_000_000_000,
    }
}

/// Stamps of a sensor stamped sample by sample; the rate they were made at; what they are.
fn clock(r: &mut Rng) -> (Vec<i64>, f64, String) {
    let rate = r.log_uniform(50.0, 8000.0);
    let seconds = r.log_uniform(10.0, 60.0).min(300_000.0 / rate);
    let form = r.pick(&[
        "ns",
        "us",
        "ms",
        "counter_ns",
        "counter_us",
        "float32",
        "epoch_seconds",
        "epoch_ns",
    ]);
    let form = if form == "ms" && rate > 300.0 {
        "us"
    } else {
        form
    };
    let counter = match form {
        "counter_ns" | "counter_us" => {
            let any = r.log_uniform(2e4, 1e7);
            r.pick(&[32768.0, 48e3, 44.1e3, 15625.0, 1.3125e6, 120e3, 3e6, any])
        }
        "float32" => {
            let any = r.log_uniform(1.0, 1e5);
            r.pick(&[0.0, 10.0, 1000.0, any])
        }
        _ => 0.0,
    };
    let jitter = r.pick(&[0.0, 0.0, 0.01, 0.1]);
    let lost = r.pick(&[0.0, 0.0, 1e-4, 1e-3, 1e-2]);
    let drift = r.pick(&[0.0, 0.0, 1e-5, 1e-4, 1e-3]);
    let n = (rate * seconds) as usize;
    let (mut t, mut phase, mut kept) = (Vec::new(), 0.0, (None, 0.0));
    for k in 0..n {
        let local = rate * (1.0 + drift * k as f64 / n as f64);
        phase += 1.0 / local;
        let at = phase + jitter * r.uniform() / local;
        if k > 0 && k + 1 < n && r.uniform() < lost {
            continue;
        }
        kept = (kept.0.or(Some(phase)), phase);
        t.push(stamp(form, at, counter));
    }
    let made = (n - 1) as f64 / (kept.1 - kept.0.unwrap_or(0.0));
    let what = format!(
        "clock {rate:.3} Hz {seconds:.1} s {form} {counter:.1} jitter {jitter} lost {lost} \
         drift {drift}"
    );
    (t, made, what)
}

/// Stamps of a FIFO read on a timer and stamped back; the sensor's rate; what they are.
fn fifo(r: &mut Rng) -> (Vec<i64>, f64, String) {
    let nominal = r.pick(&[
        100.0, 200.0, 250.0, 400.0, 500.0, 800.0, 1000.0, 1600.0, 2000.0, 3200.0, 4000.0,
    ]);
    let rate = nominal * (1.0 + r.pick(&[-1.0, 1.0]) * r.log_uniform(1e-4, 0.03));
    let every = r.pick(&[
        1e-3,
        2e-3,
        2.5e-3,
        4e-3,
        5e-3,
        10e-3,
        1.0 / 60.0,
        20e-3,
        50e-3,
    ]);
    let every = if every * rate < 1.5 {
        every * 4.0
    } else {
        every
    };
    let late = r.pick(&[0.0, 0.0, 1e-5, 1e-4, 1e-3]);
    let spacing = r.pick(&[
        1.0 / rate,
        1.0 / nominal,
        (1e6 / nominal).round() * 1e-6 + 1e-6,
    ]);
    let form = r.pick(&["ns", "us", "ms"]);
    let form = if form == "ms" && rate > 300.0 {
        "us"
    } else {
        form
    };
    let lost = r.pick(&[0.0, 0.0, 1e-3, 1e-2]);
    let drift = r.pick(&[0.0, 0.0, 5e-5, 5e-4, 1e-3]);
    let seconds = r.log_uniform(10.0, 60.0).min(300_000.0 / rate);
    let mut times = Vec::new();
    let mut phase = 0.0;
    while phase < seconds {
        phase += 1.0 / (rate * (1.0 + drift * phase / seconds));
        times.push(phase);
    }
    let made = (times.len() - 1) as f64 / (times[times.len() - 1] - times[0]);
    let (mut t, mut next, mut read) = (Vec::new(), 0usize, every);
    while next < times.len() && read < seconds + 1.0 {
        let at = read + late * r.uniform();
        let first = next;
        while next < times.len() && times[next] <= at {
            next += 1;
        }
        for k in first..next {
            let s = at + 2e-4 - (next - 1 - k) as f64 * spacing;
            if k == 0 || k + 1 == times.len() || r.uniform() >= lost {
                t.push(stamp(form, s, 0.0));
            }
        }
        read += every;
    }
    let what = format!(
        "fifo {rate:.3} Hz every {every:.5} s late {late} spacing {spacing:.7} s {form} lost \
         {lost} drift {drift} {seconds:.1} s"
    );
    (t, made, what)
}

/// The rate read from `t` and whether it comes with a warning, or the refusal, as the host
/// tool reads a time column without `--rate`: repeats kept, the summary's refusals (runs of a
/// FIFO's reads, repeats the stamps resolve) refusals, the coarse stamps', the quantum's and
/// the rate's standard error's warnings a warning.
fn read(t: &[i64]) -> Result<(f64, bool, String), String> {
    let mut timing = Timing::new();
    for &s in t {
        match timing.push(s) {
            Step::Forward => {}
            Step::Repeat => timing.keep_repeat(),
            Step::Backward { .. } => return Err("a stamp before the last".into()),
        }
    }
    let s = timing.summary(TimeUnit::Nanoseconds)?;
    match s.batch_refusal().or_else(|| s.repeat_refusal()) {
        Some(e) => Err(e),
        None => Ok((
            s.rate_hz,
            s.coarse_warning().is_some()
                || s.quantum_warning().is_some()
                || s.loose_warning().is_some(),
            format!(
                "{} kept, {} gaps, {} missing, {} short, jitter {:.2e}, span's {:.4} Hz",
                t.len(),
                s.gaps,
                s.missing_samples,
                s.short_intervals,
                s.jitter_rms,
                s.span_rate_hz
            ),
        )),
    }
}

fn main() {
    let args: Vec<String> = std::env::args().skip(1).collect();
    let number = |i: usize| args.get(i).and_then(|a| a.parse::<u64>().ok());
    let (Some(kind), Some(seed), Some(count)) = (args.first(), number(1), number(2)) else {
        eprintln!("usage: timing_sweep clock|fifo SEED COUNT [INDEX [CSV]]");
        std::process::exit(2);
    };
    let only = number(3);
    let (mut ok, mut refused, mut warned, mut wrong) = (0, 0, 0, 0);
    // Records read right that carry a warning all the same.
    let mut ok_warned = 0;
    for i in (0..count).filter(|&i| only.is_none_or(|o| o == i)) {
        let mut r = Rng((seed.wrapping_mul(0x9E37_79B9_7F4A_7C15)
            ^ (i + 1).wrapping_mul(0xD1B5_4A32_D192_ED03))
            | 1);
        let (t, made, what) = if kind == "fifo" {
            fifo(&mut r)
        } else {
            clock(&mut r)
        };
        let (verdict, shown) = match read(&t) {
            Ok((hz, warning, _)) if (hz / made - 1.0).abs() < 3e-4 => {
                ok += 1;
                ok_warned += u64::from(warning);
                let verdict = if warning { "ok, warned" } else { "ok" };
                (verdict, format!("{hz:.4} Hz"))
            }
            Ok((hz, warning, what)) => {
                let verdict = if warning {
                    warned += 1;
                    "warned"
                } else {
                    wrong += 1;
                    "WRONG"
                };
                (
                    verdict,
                    format!("{hz:.4} Hz ({:+.1e}; {what})", hz / made - 1.0),
                )
            }
            Err(e) => {
                refused += 1;
                ("refused", e.chars().take(100).collect())
            }
        };
        if let (Some(_), Some(path)) = (only, args.get(4)) {
            let mut noise = Rng(0x2545_F491_4F6C_DD1D);
            let rows: String = t
                .iter()
                .map(|s| format!("{s},{:.6}\n", noise.uniform() - 0.5))
                .collect();
            std::fs::write(path, format!("t_ns,gx\n{rows}")).expect("the CSV is written");
        }
        if verdict != "ok" || only.is_some() {
            println!("#{i} {verdict}: made at {made:.4} Hz, {what}: {shown}");
        }
    }
    println!(
        "ok {ok} refused {refused} warned {warned} WRONG {wrong} (ok with a warning {ok_warned})"
    );
}
