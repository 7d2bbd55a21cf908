//! A record's timestamps: their unit, and the rate, jitter, gaps and backward steps they show,
//! gathered in one streaming pass with bounded memory.

use serde::Serialize;

/// The unit of a time column.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum TimeUnit {
    /// Seconds.
    Seconds,
    /// Milliseconds.
    Milliseconds,
    /// Microseconds.
    Microseconds,
    /// Nanoseconds.
    Nanoseconds,
    /// The header stamps of a bag's or an MCAP file's messages, in nanoseconds.
    HeaderStamps,
}

impl TimeUnit {
    /// The unit of a time column named `name` with unit bracket `bracket`: the bracket (`[ns]`,
    /// `[s]`, ...) or the name's suffix (`t_ns`, `time_s`, ...); `None` when neither says, an
    /// error for a bracket that names no time unit.
    pub fn of(name: &str, bracket: Option<&str>) -> Result<Option<Self>, String> {
        let unit = match bracket {
            Some(b) => b.trim(),
            None => name.rsplit_once('_').map_or("", |(_, suffix)| suffix),
        };
        let found = match unit.to_ascii_lowercase().as_str() {
            "s" | "sec" | "secs" | "second" | "seconds" => Some(Self::Seconds),
            "ms" | "msec" | "msecs" | "millisecond" | "milliseconds" => Some(Self::Milliseconds),
            "us" | "usec" | "usecs" | "\u{b5}s" | "\u{3bc}s" | "microsecond" | "microseconds" => {
                Some(Self::Microseconds)
            }
            "ns" | "nsec" | "nsecs" | "nanosecond" | "nanoseconds" => Some(Self::Nanoseconds),
            _ => None,
        };
        match (found, bracket) {
            (None, Some(b)) => Err(format!(
                "time column '{name}': '[{b}]' is not a time unit (s, ms, us or ns)"
            )),
            (found, _) => Ok(found),
        }
    }

    /// The unit of stamps whose first value is `first` when the column does not say: an epoch
    /// time (1e9 to 4.1e9 s, that is 2001 to 2099) in s, ms, us or ns by its magnitude; `None`
    /// for any other value (a clock since boot, say), whose unit cannot be told.
    pub fn by_magnitude(first: f64) -> Option<Self> {
        let epoch = |scale: f64| (1e9 * scale..=4.1e9 * scale).contains(&first);
        [
            (1.0, Self::Seconds),
            (1e3, Self::Milliseconds),
            (1e6, Self::Microseconds),
            (1e9, Self::Nanoseconds),
        ]
        .into_iter()
        .find(|(scale, _)| epoch(*scale))
        .map(|(_, u)| u)
    }

    /// Its name.
    pub fn name(self) -> &'static str {
        match self {
            Self::Seconds => "s",
            Self::Milliseconds => "ms",
            Self::Microseconds => "us",
            Self::Nanoseconds | Self::HeaderStamps => "ns",
        }
    }

    /// A cell in this unit as nanoseconds. Integer cells are read exactly (an epoch time in ns
    /// has more digits than f64 holds).
    pub fn nanoseconds(self, cell: &str) -> Result<i64, String> {
        let scale: i64 = match self {
            Self::Seconds => 1_000_000_000,
            Self::Milliseconds => 1_000_000,
            Self::Microseconds => 1_000,
            Self::Nanoseconds | Self::HeaderStamps => 1,
        };
        if let Ok(v) = cell.parse::<i64>() {
            return v
                .checked_mul(scale)
                .ok_or_else(|| format!("timestamp '{cell}' {} is out of range", self.name()));
        }
        match cell.parse::<f64>() {
            Ok(v) if v.is_finite() && (v * scale as f64).abs() < 9.2e18 => {
                Ok((v * scale as f64).round() as i64)
            }
            Ok(_) => Err(format!(
                "timestamp '{cell}' {} is out of range",
                self.name()
            )),
            Err(_) => Err(format!("timestamp '{cell}' is not a number")),
        }
    }
}

/// Whether a timestamp moved forward.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Step {
    /// After the last one (or the first): the sample counts.
    Forward,
    /// At or before the last one: `last` is the last accepted stamp, ns.
    Backward {
        /// The last accepted stamp, ns.
        last: i64,
    },
}

/// The most distinct intervals held before they are rounded to a coarser quantum.
const DISTINCT: usize = 1 << 16;

/// Intervals taken before they are sorted into the histogram, all at once.
const PENDING: usize = 1 << 15;

/// Timestamps taken one by one: their intervals in a histogram (exact for a clock with a few
/// distinct intervals; rounded to a coarser quantum past 65,536 of them).
#[derive(Clone, Debug, Default)]
pub struct Timing {
    first: Option<i64>,
    last: i64,
    accepted: u64,
    dropped: u64,
    /// The histogram: (interval / quantum, count), in the order of the intervals.
    intervals: Vec<(i64, u64)>,
    /// Intervals / quantum not yet in the histogram (sorting them in at once costs a fraction
    /// of a table's lookup per interval: a table of 65,536 intervals is no cache's size).
    pending: Vec<i64>,
    quantum: i64,
    spoiled: bool,
}

impl Timing {
    /// No stamps yet.
    pub fn new() -> Self {
        Self {
            quantum: 1,
            ..Self::default()
        }
    }

    /// Takes the stamp `t` (ns) of the next sample: [`Step::Forward`] when it is later than the
    /// last accepted one, which it then becomes.
    pub fn push(&mut self, t: i64) -> Step {
        let Some(_) = self.first else {
            self.first = Some(t);
            self.last = t;
            self.accepted = 1;
            return Step::Forward;
        };
        if t <= self.last {
            return Step::Backward { last: self.last };
        }
        let interval = t.saturating_sub(self.last);
        self.pending.push(if self.quantum == 1 {
            interval
        } else {
            interval / self.quantum
        });
        if self.pending.len() == PENDING {
            let (intervals, quantum) = self.histogram();
            self.intervals = intervals;
            self.quantum = quantum;
            self.pending.clear();
        }
        self.last = t;
        self.accepted += 1;
        Step::Forward
    }

    /// Marks the stamps as giving no rate (a backward step kept when the rate is given).
    pub fn spoil(&mut self) {
        self.spoiled = true;
    }

    /// Counts a sample dropped for its backward stamp.
    pub fn drop_one(&mut self) {
        self.dropped += 1;
    }

    /// The samples dropped so far.
    pub fn dropped(&self) -> u64 {
        self.dropped
    }

    /// The histogram with the pending intervals in, and its quantum: rounded to a coarser
    /// quantum, ten times coarser at a time, while it holds more than [`DISTINCT`] intervals.
    fn histogram(&self) -> (Vec<(i64, u64)>, i64) {
        let mut pending = self.pending.clone();
        pending.sort_unstable();
        let mut merged: Vec<(i64, u64)> = Vec::with_capacity(self.intervals.len() + pending.len());
        let mut add = |k: i64, n: u64| match merged.last_mut() {
            Some((last, m)) if *last == k => *m += n,
            _ => merged.push((k, n)),
        };
        let mut counted = self.intervals.iter().peekable();
        for k in pending {
            while let Some(&&(c, n)) = counted.peek()
                && c < k
            {
                add(c, n);
                counted.next();
            }
            add(k, 1);
        }
        counted.for_each(|&(c, n)| add(c, n));
        let mut quantum = self.quantum;
        while merged.len() > DISTINCT {
            // Rounding down keeps the order: equal keys end up side by side.
            let mut coarse: Vec<(i64, u64)> = Vec::with_capacity(merged.len());
            for (k, n) in merged {
                match coarse.last_mut() {
                    Some((last, m)) if *last == k / 10 => *m += n,
                    _ => coarse.push((k / 10, n)),
                }
            }
            merged = coarse;
            quantum = quantum.saturating_mul(10);
        }
        (merged, quantum)
    }

    /// The summary of the stamps taken; an error when they give no rate (fewer than two) or
    /// several (less than 90 % of the intervals within 25 % of the median).
    pub fn summary(&self, unit: TimeUnit) -> Result<TimingSummary, String> {
        if self.spoiled {
            return Err("the timestamps go backwards".into());
        }
        // In the order of the intervals: the median, and sums that do not depend on the
        // order the stamps came in.
        let (sorted, quantum) = self.histogram();
        let intervals: u64 = sorted.iter().map(|&(_, n)| n).sum();
        if intervals == 0 {
            return Err("fewer than two timestamps: no rate".into());
        }
        // The median interval, ns (the middle of its quantum).
        let mut seen = 0;
        let mut median = 0.0;
        for (k, n) in &sorted {
            seen += n;
            if 2 * seen >= intervals {
                median = (*k as f64 + if quantum > 1 { 0.5 } else { 0.0 }) * quantum as f64;
                break;
            }
        }
        // Intervals are judged against the median; where that leaves under 90 % regular (stamps
        // rounded to a coarse clock: 5 and 6 ms at 180 Hz), against the mean interval.
        let span = self.last.saturating_sub(self.first.unwrap_or(self.last)) as f64;
        let mut classes = classes(&sorted, quantum, median);
        if (classes.regular as f64) < 0.9 * intervals as f64 {
            let by_mean = self::classes(&sorted, quantum, span / intervals as f64);
            if by_mean.regular > classes.regular {
                classes = by_mean;
            }
        }
        let Classes {
            reference,
            short,
            gaps,
            missing,
            regular,
            sum,
            sq,
            worst,
        } = classes;
        // The rate: the mean of the regular intervals (exact for rounded stamps).
        let mean = sum / regular.max(1) as f64;
        let summary = TimingSummary {
            unit: unit.name(),
            header_stamps: unit == TimeUnit::HeaderStamps,
            rate_hz: 1e9 / mean,
            median_interval_s: median * 1e-9,
            jitter_rms: (sq / regular.max(1) as f64).sqrt(),
            jitter_max: worst,
            gaps,
            missing_samples: missing,
            short_intervals: short,
            dropped_backward: self.dropped,
            span_s: span * 1e-9,
        };
        if (regular as f64) < 0.9 * intervals as f64 {
            return Err(format!(
                "the timestamps show mixed rates: only {regular} of {intervals} intervals lie \
                 within 25 % of the interval {:.6e} s ({short} shorter, {gaps} longer); \
                 one record must have one rate (or give --rate)",
                reference * 1e-9
            ));
        }
        if !(0.01..=1e6).contains(&summary.rate_hz) {
            return Err(if unit == TimeUnit::HeaderStamps {
                format!(
                    "the messages' header stamps give {:.6e} Hz, not an IMU's rate: give --rate",
                    summary.rate_hz
                )
            } else {
                format!(
                    "the timestamps, read as {}, give {:.6e} Hz, not an IMU's rate: state the \
                     time column's unit in its header ([s], [ms], [us], [ns]), or give --rate",
                    unit.name(),
                    summary.rate_hz
                )
            });
        }
        Ok(summary)
    }
}

/// The intervals of the histogram `sorted` (keys in units of `quantum` ns) against
/// `reference` (ns): within 25 % of it regular, else short or gaps.
fn classes(sorted: &[(i64, u64)], quantum: i64, reference: f64) -> Classes {
    let mut c = Classes {
        reference,
        ..Classes::default()
    };
    for (k, n) in sorted {
        let v = (*k as f64 + if quantum > 1 { 0.5 } else { 0.0 }) * quantum as f64;
        let r = v / reference;
        if r < 0.75 {
            c.short += n;
        } else if r > 1.25 {
            c.gaps += n;
            c.missing += n * ((r.round() as u64).saturating_sub(1));
        } else {
            c.regular += n;
            c.sum += *n as f64 * v;
            c.sq += *n as f64 * (r - 1.0) * (r - 1.0);
            c.worst = c.worst.max((r - 1.0).abs());
        }
    }
    c
}

/// Intervals by class.
#[derive(Default)]
struct Classes {
    reference: f64,
    short: u64,
    gaps: u64,
    missing: u64,
    regular: u64,
    sum: f64,
    sq: f64,
    worst: f64,
}

/// What a record's timestamps show.
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct TimingSummary {
    /// The unit of the time column (`ns` for a bag's header stamps).
    pub unit: &'static str,
    /// Whether they are the header stamps of a bag's or an MCAP file's messages.
    #[serde(skip)]
    pub header_stamps: bool,
    /// The rate, the reciprocal of the mean regular interval, Hz.
    pub rate_hz: f64,
    /// The median interval, s.
    pub median_interval_s: f64,
    /// The RMS deviation of the regular intervals (within 25 % of the median, or of the mean
    /// interval for coarsely rounded stamps) from that reference, relative to it.
    pub jitter_rms: f64,
    /// Their largest deviation, relative.
    pub jitter_max: f64,
    /// Intervals longer than 1.25 times the median.
    pub gaps: u64,
    /// The samples those gaps miss (each gap's interval over the median, rounded, less one).
    pub missing_samples: u64,
    /// Intervals shorter than 0.75 times the median.
    pub short_intervals: u64,
    /// Samples dropped for a timestamp at or before the last one (`--drop-backward`).
    pub dropped_backward: u64,
    /// From the first stamp to the last, s.
    pub span_s: f64,
}

impl TimingSummary {
    /// One line for the text outputs.
    pub fn text(&self) -> String {
        format!(
            "timestamps ({}): rate {} Hz (median interval {:e} s), jitter {:.3} % RMS, {:.3} % \
             at most; {} gaps ({} samples missing), {} short intervals, {} backward dropped",
            self.unit,
            short(self.rate_hz),
            self.median_interval_s,
            100.0 * self.jitter_rms,
            100.0 * self.jitter_max,
            self.gaps,
            self.missing_samples,
            self.short_intervals,
            self.dropped_backward
        )
    }
}

/// `v` to 7 significant digits, without trailing zeros.
fn short(v: f64) -> String {
    let s = format!("{v:.6}");
    let s = s.trim_end_matches('0').trim_end_matches('.');
    s.to_string()
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Stamps 2.5 ms apart with a jitter of up to `jitter` ns, from a fixed generator.
    fn stamps(n: usize, jitter: i64) -> Vec<i64> {
        let mut state = 0x2545_f491_4f6c_dd1du64;
        let mut t = 1_700_000_000_000_000_000i64;
        (0..n)
            .map(|_| {
                state ^= state << 13;
                state ^= state >> 7;
                state ^= state << 17;
                t += 2_500_000 + (state % (2 * jitter as u64 + 1)) as i64 - jitter;
                t
            })
            .collect()
    }

    /// The summary's median and rate computed directly from every interval at `quantum`.
    fn direct(t: &[i64], quantum: i64) -> (f64, f64) {
        let centre = |iv: i64| {
            (((iv / quantum) as f64) + if quantum > 1 { 0.5 } else { 0.0 }) * quantum as f64
        };
        let mut v: Vec<f64> = t.windows(2).map(|w| centre(w[1] - w[0])).collect();
        v.sort_by(f64::total_cmp);
        // The first interval at which half of them are counted.
        let median = v[v.len().div_ceil(2) - 1];
        let regular: Vec<f64> = v
            .iter()
            .copied()
            .filter(|x| (0.75..=1.25).contains(&(x / median)))
            .collect();
        let mean = regular.iter().sum::<f64>() / regular.len() as f64;
        (median, 1e9 / mean)
    }

    #[test]
    fn the_histogram_is_exact_below_its_size_and_rounded_past_it() {
        // 40,001 distinct intervals at most (exact); 800,001 (80,001 at 10 ns: rounded to
        // 100 ns).
        for (jitter, quantum) in [(20_000, 1), (400_000, 100)] {
            let t = stamps(300_000, jitter);
            let mut timing = Timing::new();
            for &s in &t {
                assert_eq!(timing.push(s), Step::Forward);
            }
            let summary = timing.summary(TimeUnit::Nanoseconds).unwrap();
            let (median, rate) = direct(&t, quantum);
            assert_eq!(summary.median_interval_s, median * 1e-9, "jitter {jitter}");
            assert!(
                (summary.rate_hz / rate - 1.0).abs() < 1e-12,
                "jitter {jitter}"
            );
            assert!((summary.rate_hz / 400.0 - 1.0).abs() < 1e-3);
        }
    }

    #[test]
    fn a_clean_clock_gives_its_rate_exactly() {
        let mut timing = Timing::new();
        for i in 0..100_000i64 {
            timing.push(1_000 + 2_500_000 * i);
        }
        let summary = timing.summary(TimeUnit::Nanoseconds).unwrap();
        assert_eq!(summary.rate_hz, 400.0);
        assert_eq!(summary.median_interval_s, 2.5e-3);
        assert_eq!(summary.jitter_rms, 0.0);
    }
}
