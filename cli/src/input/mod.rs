//! Reading a record: one column of CSV files ([`csv`]), of a ROS 1 bag ([`bag`]) or of an MCAP
//! file ([`mcap`]), all through [`source`]; its timestamps ([`timing`]) and units ([`units`]);
//! averaged in blocks (`--decimate`); and the checks of the settings the commands share. An
//! error names the flag, or the files.

pub use imu_ar_recordings::{bag, csv, frame, mcap, rosbag2, source, timing, units};

use std::path::PathBuf;

use imu_ar::recursive::Channel;

use crate::error::{Fail, with_file};
use crate::method::MAX_ORDER;
use frame::Skipped;
use source::Request;
use timing::TimingSummary;
use units::Unit;

/// One column of a record.
#[derive(clap::Args)]
pub struct Input {
    /// CSV files with a header row (a `#`-prefixed one too, as in EuRoC), read as one record
    /// (`-` is standard input); or ROS 1 bags or MCAP files, with --topic.
    #[arg(required = true)]
    pub files: Vec<PathBuf>,
    /// Column: its name, its name without the unit bracket, or its 0-based index; for a bag or
    /// an MCAP file gx, gy, gz, ax, ay or az.
    #[arg(long)]
    pub column: String,
    /// The sensor_msgs/Imu topic of a ROS 1 bag or an MCAP file.
    #[arg(long)]
    pub topic: Option<String>,
    /// The header frame_id of the IMU to read, when the topic carries more than one.
    #[arg(long)]
    pub frame_id: Option<String>,
    /// The IMU of a PX4 ULog file or an ArduPilot DataFlash log, when it holds several (the
    /// uORB instance of sensor_gyro / sensor_accel; the `I` of the IMU messages).
    #[arg(long)]
    pub instance: Option<u8>,
    /// The CSV column of the timestamps, when --rate is not given [default: the column named
    /// timestamp, time, t or t_UNIT; its unit from its bracket or suffix (s, ms, us, ns), else
    /// from its magnitude].
    #[arg(long)]
    pub time_column: Option<String>,
    /// Drop samples whose timestamp is not after the one before (counted) instead of refusing
    /// the record.
    #[arg(long)]
    pub drop_backward: bool,
    /// The unit of the results. A column whose unit is known (a header bracket such as
    /// `[rad s^-1]`, a bag's SI units) is converted to it: rad/s, deg/s, deg/h; m/s^2, g, mg.
    /// For a column of unknown unit it is a label.
    #[arg(long)]
    pub unit: Option<String>,
}

/// The timestamp of a sample that has none ([`Input::series_stamped`]).
pub const NO_STAMP: i64 = i64::MIN;

/// A record's samples, and what its reader found.
pub struct Series {
    /// The samples, in [`Series::unit`].
    pub x: Vec<f64>,
    /// The timestamps' statistics, when they were read.
    pub timing: Option<TimingSummary>,
    /// The unit of the samples (`units` when nothing says).
    pub unit: String,
    /// Messages skipped, counted.
    pub skipped: Skipped,
    /// The samples kept with a stamp, and the span of their stamps, s, when they give one.
    pub stamped: Option<(u64, f64)>,
    /// What the stamps show that would refuse them without a rate given (see [`summary`]).
    pub unchecked: Option<String>,
    /// What the stamps cannot check of the rate they give, warned of where no rate is given.
    pub caveat: Option<String>,
}

impl Input {
    /// The column's samples.
    pub fn read(&self) -> Result<Vec<f64>, Fail> {
        Ok(self.series(false)?.x)
    }

    /// The column's samples averaged in blocks of `decimate`.
    pub fn load(&self, decimate: usize) -> Result<Vec<f64>, Fail> {
        decimated(&self.files, &self.read()?, decimate)
    }

    /// The column's samples in the unit of `--unit`, with the timestamps' statistics when
    /// `want_time` (or when the record is a bag or an MCAP file, or `--time-column` is given).
    pub fn series(&self, want_time: bool) -> Result<Series, Fail> {
        self.series_with(want_time, None)
    }

    /// [`Input::series`], with each sample's timestamp (ns since the epoch or the log's start;
    /// [`NO_STAMP`] where none was read) pushed to `stamps`.
    pub fn series_stamped(&self, want_time: bool, stamps: &mut Vec<i64>) -> Result<Series, Fail> {
        self.series_with(want_time, Some(stamps))
    }

    fn series_with(
        &self,
        want_time: bool,
        mut stamps: Option<&mut Vec<i64>>,
    ) -> Result<Series, Fail> {
        let columns = [self.column.clone()];
        let request = Request {
            columns: &columns,
            topic: self.topic.as_deref(),
            frame_id: self.frame_id.as_deref(),
            time_column: self.time_column.as_deref(),
            want_time,
            drop_backward: self.drop_backward,
            instance: self.instance,
        };
        let mut x = Vec::new();
        let read = source::stream_stamped(&self.files, &request, &mut |t, v| {
            x.push(v[0]);
            if let Some(s) = stamps.as_deref_mut() {
                s.push(t.unwrap_or(NO_STAMP));
            }
        })?;
        if let Some(w) = read.skipped.cut_short_warning() {
            eprintln!("imu-ar: warning: {}", self.fail(w).0);
        }
        if let Some(w) = read.skipped.summary() {
            eprintln!("imu-ar: warning: {}", self.fail(w).0);
        }
        if let Some(from) = &read.source {
            eprintln!(
                "imu-ar: note: {}",
                self.fail(format!("{} {from}", self.column)).0
            );
        }
        if let (Some(Some(bracket)), Some(to)) = (read.unknown.first(), &self.unit) {
            return Err(self.fail(format!(
                "--unit {to}: column '{}' is in [{bracket}], which is not a unit converted here \
                 (rad/s, deg/s, deg/h, m/s^2, g, mg)",
                self.column
            )));
        }
        let (factor, unit) = convert(read.units.first().copied().flatten(), self.unit.as_deref())?;
        if factor != 1.0 {
            x.iter_mut().for_each(|v| *v *= factor);
        }
        let stamped = read.timing.as_ref().and_then(|(t, _)| t.kept_over_span());
        let (timing, unchecked) = summary(read.timing, want_time).map_err(|e| self.fail(e))?;
        Ok(Series {
            x,
            timing,
            unit,
            skipped: read.skipped,
            stamped,
            unchecked,
            caveat: read.caveat,
        })
    }

    /// Samples a caller holds (the Python package's arrays) in place of the files': as
    /// [`Input::series`] gives them, in `--unit` (a label here), without timestamps.
    pub fn given(&self, x: &[f64]) -> Series {
        Series {
            x: x.to_vec(),
            timing: None,
            unit: self.unit.clone().unwrap_or_else(|| "units".into()),
            skipped: Skipped::default(),
            stamped: None,
            unchecked: None,
            caveat: None,
        }
    }

    /// `e` after the names of the files.
    pub fn fail(&self, e: impl std::fmt::Display) -> Fail {
        with_file(&self.files, e)
    }
}

impl Series {
    /// The sample rate: `--rate` when given (an error when the timestamps give none within
    /// 1 % of it), else the timestamps'. Errors name `input`'s files.
    pub fn rate(&self, given: Option<f64>, input: &Input) -> Result<f64, Fail> {
        let rate = resolve_rate(given, self.timing.as_ref()).map_err(|e| input.fail(e.0))?;
        check_packed(given, self.stamped).map_err(|e| input.fail(e))?;
        if let Some(w) = unchecked(given, self.unchecked.as_deref()) {
            eprintln!("imu-ar: warning: {}", input.fail(w).0);
        }
        if let Some(w) = coarse(given, self.timing.as_ref()) {
            eprintln!("imu-ar: warning: {}", input.fail(w).0);
        }
        if let Some(w) = self.caveat.as_ref().filter(|_| given.is_none()) {
            eprintln!("imu-ar: warning: {}", input.fail(w.clone()).0);
        } else if let Some(w) = loose(given, self.timing.as_ref()) {
            eprintln!("imu-ar: warning: {}", input.fail(w).0);
        }
        Ok(rate)
    }
}

/// A rate `given` must not pack the samples kept into less time than their stamps span
/// (`stamped`: the samples, the span, s), whatever else the stamps show: rows written twice
/// read at the rate of their distinct stamps fit in half the time.
pub fn check_packed(given: Option<f64>, stamped: Option<(u64, f64)>) -> Result<(), String> {
    let (Some(r), Some((kept, span))) = (given, stamped) else {
        return Ok(());
    };
    let needs = (kept - 1) as f64 / r;
    if needs * 0.99 <= span {
        return Ok(());
    }
    Err(format!(
        "--rate {}: the {kept} samples would span {} s at it, where their stamps span {} s \
         (rows written twice, or stretches at a faster rate?)",
        number(r),
        number((needs * 1e3).round() / 1e3),
        number((span * 1e3).round() / 1e3),
    ))
}

/// The highest rate taken from timestamps without `--rate` to confirm it, Hz.
pub const MAX_STAMPED_RATE: f64 = 10_000.0;

/// The lowest rate taken from timestamps without `--rate` to confirm it, Hz.
pub const MIN_STAMPED_RATE: f64 = 5.0;

/// The sample rate: `given` (`--rate`) when there is one (an error when it is more than 1 %
/// from the timestamps' rate and from the other reading of stamps rounded to a quantum, or
/// for runs of a FIFO's reads, below it or more than [`timing::HIDDEN_LOSS`] above it), else
/// the timestamps'
/// (an error above [`MAX_STAMPED_RATE`], or below [`MIN_STAMPED_RATE`] from a time column:
/// such a rate is more often a time unit mistaken).
pub fn resolve_rate(given: Option<f64>, timing: Option<&TimingSummary>) -> Result<f64, Fail> {
    match (given, timing) {
        (Some(r), Some(t)) => {
            let r = check_rate(r)?;
            // The stamps' rate, or for stamps rounded to a quantum, the other reading of their
            // intervals (rounding, or samples missing).
            let agrees = |v: f64| (r / v - 1.0).abs() <= 0.01;
            // Runs of a FIFO's reads stamped at a period not the samples' hide the samples
            // lost within them: their rate is the least the sensor's may be, and a little
            // more is samples lost.
            let lost = t.batched.is_some()
                && r >= 0.99 * t.rate_hz
                && r <= (1.0 + timing::HIDDEN_LOSS) * t.rate_hz;
            if !(agrees(t.rate_hz) || t.other_rate_hz.is_some_and(agrees) || lost) {
                return Err(Fail(format!(
                    "--rate {}: {} give {} Hz ({} Hz over their span)",
                    number(r),
                    if t.header_stamps {
                        "the messages' stamps"
                    } else {
                        "the timestamps"
                    },
                    t.rate_hz,
                    t.span_rate_hz
                )));
            }
            Ok(r)
        }
        (Some(r), None) => check_rate(r),
        (None, Some(t)) if t.rate_hz > MAX_STAMPED_RATE && t.header_stamps => Err(Fail(format!(
            "the messages' header stamps give {} Hz: an IMU above {} kHz is rare; give --rate {} \
             to confirm the rate",
            t.rate_hz,
            MAX_STAMPED_RATE / 1e3,
            t.rate_hz
        ))),
        (None, Some(t)) if t.rate_hz > MAX_STAMPED_RATE => Err(Fail(format!(
            "the timestamps ({}) give {} Hz: an IMU above {} kHz is rare, and stamps in a unit \
             1000 times coarser than the column says (microseconds under [ns], milliseconds \
             under [us]) give a rate 1000 times too high; check the time column's unit, or \
             give --rate {} to confirm the rate",
            t.unit,
            t.rate_hz,
            MAX_STAMPED_RATE / 1e3,
            t.rate_hz
        ))),
        // (Header stamps have their unit by the format: a slow stream of them is the
        // format's own to tell, a logger's subsample.)
        (None, Some(t)) if t.rate_hz < MIN_STAMPED_RATE && !t.header_stamps => Err(Fail(format!(
            "the timestamps ({}) give {} Hz: an IMU below {} Hz is rare, and stamps in a \
                 unit 1000 times finer than the column says (milliseconds under [s], \
                 microseconds under [ms]), or a clock since boot taken for an epoch time by its \
                 size, give a rate 1000 times too low; check the time column's unit, or give \
                 --rate {} to confirm the rate",
            t.unit, t.rate_hz, MIN_STAMPED_RATE, t.rate_hz
        ))),
        (None, Some(t)) => Ok(t.rate_hz),
        (None, None) => Err(Fail(
            "--rate is required: the record has no time column (name one with \
                 --time-column)"
                .into(),
        )),
    }
}

/// The timestamps' summary: an error when they give no single rate, or repeat where they
/// resolve the interval, and it is `needed` (`--rate` was not given); otherwise such
/// timestamps are not reported, or their repeats are (the rate the others give checks
/// `--rate`), and what they show is returned beside, for [`unchecked`] to warn of where a
/// rate is given.
pub fn summary(
    timing: Option<(timing::Timing, timing::TimeUnit)>,
    needed: bool,
) -> Result<(Option<TimingSummary>, Option<String>), String> {
    match timing.map(|(t, u)| t.summary(u)) {
        Some(Err(e)) if needed => Err(e),
        Some(Err(e)) => Ok((None, Some(e))),
        None => Ok((None, None)),
        Some(Ok(s)) => match s.batch_refusal().or_else(|| s.repeat_refusal()) {
            Some(e) if needed => Err(e),
            e => Ok((Some(s), e)),
        },
    }
}

/// The warning, where no rate is `given`, that the stamps are too coarse to show samples
/// lost ([`TimingSummary::coarse_warning`]).
pub fn coarse(given: Option<f64>, timing: Option<&TimingSummary>) -> Option<String> {
    timing
        .filter(|_| given.is_none())
        .and_then(TimingSummary::coarse_warning)
}

/// The warnings, where no rate is `given`, that a few places left empty on the stamps'
/// quantum do not tell samples lost from a slower clock
/// ([`TimingSummary::quantum_warning`]), and that the stamps' jitter leaves the rate's
/// standard error past a third of 1e-4 ([`TimingSummary::loose_warning`]).
pub fn loose(given: Option<f64>, timing: Option<&TimingSummary>) -> Option<String> {
    let timing = timing.filter(|_| given.is_none())?;
    match (timing.quantum_warning(), timing.loose_warning()) {
        (Some(a), Some(b)) => Some(format!("{a}; {b}")),
        (a, b) => a.or(b),
    }
}

/// The warning, where a rate is `given`, of what the stamps show that would refuse them
/// without it (`why`, from [`summary`]): mixed rates, samples repeated, too short a span.
pub fn unchecked(given: Option<f64>, why: Option<&str>) -> Option<String> {
    let (Some(r), Some(why)) = (given, why) else {
        return None;
    };
    Some(format!(
        "read at --rate {}, but {}",
        number(r),
        without_rate(why)
    ))
}

/// A refusal's reason without its way past (the last "give --rate" and what follows, with
/// the words that lead to it), a parenthesis it opened closed.
fn without_rate(why: &str) -> String {
    let Some(at) = why.rfind("give --rate") else {
        return why.into();
    };
    let mut head = why[..at].trim_end();
    while let Some(rest) = ["(or", " or", "(", ";", ":", ","]
        .iter()
        .find_map(|s| head.strip_suffix(s))
    {
        head = rest.trim_end();
    }
    let open = head
        .matches('(')
        .count()
        .saturating_sub(head.matches(')').count());
    format!("{head}{}", ")".repeat(open))
}

/// The factor from a column in `from` (where known) to `--unit` `to`, and the unit of the result.
pub fn convert(from: Option<Unit>, to: Option<&str>) -> Result<(f64, String), Fail> {
    if let Some(t) = to
        && t.chars().any(char::is_control)
    {
        return Err(Fail(format!(
            "--unit {t:?}: must not contain control characters"
        )));
    }
    match (from, to) {
        (Some(f), Some(t)) => match Unit::parse(t) {
            Some(u) => Ok((
                f.factor_to(u)
                    .map_err(|e| Fail(format!("--unit {t}: {e}")))?,
                u.name.into(),
            )),
            None => Err(Fail(format!(
                "--unit {t}: the column is in {}, which converts to rad/s, deg/s, deg/h (a rate) \
                 or m/s^2, g, mg (an acceleration)",
                f.name
            ))),
        },
        (Some(f), None) => Ok((1.0, f.name.into())),
        (None, Some(t)) => Ok((1.0, t.into())),
        (None, None) => Ok((1.0, "units".into())),
    }
}

/// One column of a record, and the order of the model to fit to it.
#[derive(clap::Args)]
pub struct Record {
    /// The column.
    #[command(flatten)]
    pub input: Input,
    /// Model order, 1 to 32.
    #[arg(long, allow_negative_numbers = true)]
    pub order: usize,
}

impl Record {
    /// Checks the order, then reads the column and averages blocks of `decimate` samples.
    pub fn load(&self, decimate: usize) -> Result<Vec<f64>, Fail> {
        check_order("--order", self.order)?;
        check_decimate(decimate)?;
        self.input.load(decimate)
    }
}

/// `x` averaged in blocks of `m` samples; an error when no sample is left.
pub fn decimated(files: &[PathBuf], x: &[f64], m: usize) -> Result<Vec<f64>, Fail> {
    let y = block_average(x, m);
    if y.is_empty() {
        return Err(with_file(
            files,
            format!(
                "--decimate {m}: the record has {} samples, no sample is left after averaging \
                 blocks of {m}",
                x.len()
            ),
        ));
    }
    Ok(y)
}

/// Averages of consecutive blocks of `m` samples (a last, incomplete block is dropped): the
/// record at `1/m` of its rate, as sensor drift is usually modelled. `m = 1` returns `x`.
///
/// Block averaging is a low-pass filter: it keeps the slow (correlated) part of the error and
/// divides the white part's variance by `m`, so a model fitted to averaged data describes the
/// averaged sensor, not the raw one (numerics.md section 6).
pub fn block_average(x: &[f64], m: usize) -> Vec<f64> {
    match m {
        0 | 1 => x.to_vec(),
        _ => x
            .chunks_exact(m)
            .map(|block| block.iter().sum::<f64>() / m as f64)
            .collect(),
    }
}

/// A model order (`flag`) from 1 to [`MAX_ORDER`].
pub fn check_order(flag: &str, p: usize) -> Result<(), Fail> {
    if p == 0 || p > MAX_ORDER {
        return Err(Fail(format!(
            "{flag} {p}: the order must be 1 to {MAX_ORDER} (the supported maximum)"
        )));
    }
    Ok(())
}

/// A `--decimate` of at least 1.
pub fn check_decimate(m: usize) -> Result<(), Fail> {
    if m == 0 {
        return Err(Fail("--decimate 0: must be at least 1".into()));
    }
    Ok(())
}

/// A positive, finite `--rate`.
pub fn check_rate(rate: f64) -> Result<f64, Fail> {
    if !(rate.is_finite() && rate > 0.0) {
        return Err(Fail(format!(
            "--rate {}: must be a positive number of Hz",
            number(rate)
        )));
    }
    Ok(rate)
}

/// A number given on the command line, as an error shows it: as written for most, in
/// exponent form where that is shorter (`1e-300`, not three hundred digits).
pub fn number(v: f64) -> String {
    let plain = v.to_string();
    let exponent = format!("{v:e}");
    // Up to ten characters as written (1000, 0.0001); past that the shorter.
    if plain.len() > 10 && exponent.len() < plain.len() {
        exponent
    } else {
        plain
    }
}

/// A `--lambda` in (0, 1].
pub fn check_lambda(lambda: f64) -> Result<(), Fail> {
    if !(lambda > 0.0 && lambda <= 1.0) {
        return Err(Fail(format!(
            "--lambda {}: must be in (0, 1]",
            number(lambda)
        )));
    }
    Ok(())
}

/// A `--delta` that the f64 estimators can carry (the library's range check).
pub fn check_delta(delta: f64) -> Result<(), Fail> {
    check_weight("--delta", delta)
}

/// A regularisation weight (`flag`) that the f64 estimators can carry.
fn check_weight(flag: &str, delta: f64) -> Result<(), Fail> {
    Channel::<f64>::new(delta)
        .map(|_| ())
        .map_err(|e| Fail(format!("{flag} {}: {e}", number(delta))))
}

/// A prior model to start a recursive estimator from, and its weight (`fit`, `report`).
#[derive(clap::Args)]
pub struct Prior {
    /// Start from this model, a_1,..,a_P: the regularisation is centred on it,
    /// `delta lambda^n (a - a0)^T D (a - a0)`.
    #[arg(long, value_delimiter = ',', allow_hyphen_values = true)]
    pub prior_a: Option<Vec<f64>>,
    /// The weight of `--prior-a`: the `delta` of its term (`--prior-a 0,..,0 --prior-weight D`
    /// is `--delta D`) [default: the --delta in use].
    #[arg(
        long,
        allow_negative_numbers = true,
        conflicts_with = "delta",
        requires = "prior_a"
    )]
    pub prior_weight: Option<f64>,
}

impl Prior {
    /// `--prior-a`, if given, checked against `--order`: `order` coefficients, all finite;
    /// and `--prior-weight`, if given, a `delta` the estimators can carry.
    pub fn check(&self, order: usize) -> Result<Option<&[f64]>, Fail> {
        if let Some(w) = self.prior_weight {
            check_weight("--prior-weight", w)?;
        }
        let Some(a) = &self.prior_a else {
            return Ok(None);
        };
        if a.len() != order {
            return Err(Fail(format!(
                "--prior-a has {} coefficients; --order {order} needs {order}",
                a.len()
            )));
        }
        if let Some(v) = a.iter().find(|v| !v.is_finite()) {
            return Err(Fail(format!("--prior-a {v}: coefficients must be finite")));
        }
        Ok(Some(a))
    }
}

/// `rate` (Hz, `flag`) gives finite times over `samples` samples: their span `samples / rate`
/// and the interval `1 / rate` do not overflow f64.
pub fn check_span(flag: &str, rate: f64, samples: usize) -> Result<(), Fail> {
    let span = samples.max(1) as f64 / rate;
    if !(span.is_finite() && (1.0 / rate).is_finite()) {
        return Err(Fail(format!(
            "{flag} {}: too small, the time of {samples} samples overflows f64",
            number(rate)
        )));
    }
    Ok(())
}

/// The samples the record's gaps miss (`timing`, as its stamps tell them) against the `n`
/// it holds: more than a tenth is refused. The Allan variance takes the samples as one run;
/// each gap joins stretches whose biases have walked apart over it, and makes the long
/// averaging times up (two 10-minute stretches 2 h apart gave a random walk 2 to 4 times
/// the sensor's), by about the gaps' share of the record.
pub fn check_gaps(timing: Option<&TimingSummary>, n: usize) -> Result<(), String> {
    let Some(t) = timing.filter(|t| t.missing_samples as f64 > 0.1 * n as f64) else {
        return Ok(());
    };
    Err(format!(
        "{} gaps miss {} samples, {:.0} % as many as the {n} the record holds: the Allan \
         variance takes the samples as one run, and stretches so far apart join biases that \
         walked apart meanwhile; read the stretches one at a time",
        t.gaps,
        t.missing_samples,
        100.0 * t.missing_samples as f64 / n.max(1) as f64
    ))
}

/// The least rate of a PX4 sensor topic read as the sensor's own samples, Hz.
pub use imu_ar_recordings::ulog::LEAST_SENSOR_RATE as LEAST_ULOG_RATE;

/// A PX4 or ArduPilot log's sensor samples at a rate under [`LEAST_ULOG_RATE`] (`timing`, as
/// their stamps tell it): see [`subsampled`]. Refused for a noise model.
pub fn check_subsampled(files: &[PathBuf], timing: Option<&TimingSummary>) -> Result<(), String> {
    match (files.first(), timing) {
        (Some(f), Some(t)) => subsampled(source::Kind::of(f), t.rate_hz).map_or(Ok(()), Err),
        _ => Ok(()),
    }
}

/// Why a log of `kind` whose sensor samples come at `rate` Hz gives no noise model: under
/// [`LEAST_ULOG_RATE`] they are the logger's subsample of the sensor's stream, single
/// readings whose spread is the sensor's at its own rate (through its filter), not an
/// average over the interval (the noise density read at the subsample's rate is
/// `sqrt(sensor rate / logged rate)` times the sensor's: 16 times for 250 Hz logged at 1 Hz).
/// PX4's logger profiles write `sensor_gyro` and `sensor_accel` once a second (the default)
/// or ten times (thermal calibration); ArduCopter writes its `IMU` messages at 25 Hz unless
/// `LOG_BITMASK` asks for them fast. `None` for other sources and faster logs.
pub fn subsampled(kind: source::Kind, rate: f64) -> Option<String> {
    if rate >= LEAST_ULOG_RATE {
        return None;
    }
    match kind {
        source::Kind::Ulog => Some(format!(
            "the PX4 log holds the sensor's samples at {} Hz: the logger's subsample of its \
             stream (its default profile writes sensor_gyro and sensor_accel once a second, the \
             thermal calibration profile ten times), single readings whose noise is the sensor's \
             at its own rate; log the IMU at full rate (SDLOG_PROFILE's high rate or raw FIFO \
             bits) for its noise model",
            number(rate)
        )),
        source::Kind::DataFlash => Some(format!(
            "the ArduPilot log holds the IMU messages at {} Hz: the logger's subsample of the \
             sensor's stream (ArduCopter writes IMU at 25 Hz unless LOG_BITMASK's fast IMU bit, \
             IMU_FAST, is set), single filtered readings whose noise is not the sensor's at \
             this rate; log the IMU fast (IMU_FAST, or IMU_RAW for the unfiltered samples) for \
             its noise model",
            number(rate)
        )),
        _ => None,
    }
}

/// 0.1 x the variance of the finite samples among the first 1000 (what firmware sees at
/// start-up; NaN and infinities are rejected there), or 1 when that is 0 or there are none;
/// an error when that variance overflows f64.
pub fn default_delta(x: &[f64]) -> Result<f64, String> {
    // The finite ones among the first 1000 (the estimators reject the others).
    let head = || x[..x.len().min(1000)].iter().filter(|v| v.is_finite());
    let n = head().count().max(1) as f64;
    let mean = head().sum::<f64>() / n;
    let var = head().map(|v| (v - mean) * (v - mean)).sum::<f64>() / n;
    if !var.is_finite() {
        return Err(
            "the variance of the first 1000 samples (for the default --delta) overflows \
             f64 (values of about 1e154 or more); rescale the record"
                .into(),
        );
    }
    Ok(if var > 0.0 { 0.1 * var } else { 1.0 })
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_warning_for_a_rate_given_does_not_ask_for_it() {
        // The refusals' ways past, as the timing gives them ("... phase tells neither: give
        // --rate" was read at --rate 4000 with that ending, before).
        for (why, kept) in [
            (
                "their phase tells neither: give --rate",
                "their phase tells neither",
            ),
            (
                "one record must have one rate (or give --rate)",
                "one record must have one rate",
            ),
            ("the rate is not told; give --rate", "the rate is not told"),
            (
                "read the stretches apart, or give --rate",
                "read the stretches apart",
            ),
            (
                "samples repeated? give --rate (--drop-backward would drop the others too)",
                "samples repeated?",
            ),
            (
                "drops them (a faster clock repeats them evenly: give --rate)",
                "drops them (a faster clock repeats them evenly)",
            ),
            (
                "too few to tell the rate to 1 % (give --rate)",
                "too few to tell the rate to 1 %",
            ),
            ("no way past", "no way past"),
        ] {
            let w = unchecked(Some(4000.0), Some(why)).unwrap();
            assert_eq!(w, format!("read at --rate 4000, but {kept}"));
        }
        assert_eq!(unchecked(None, Some("x: give --rate")), None);
    }

    #[test]
    fn numbers_are_shown_as_written_unless_long() {
        for (v, shown) in [
            (1000.0, "1000"),
            (325.5, "325.5"),
            (0.0001, "0.0001"),
            (1e300, "1e300"),
            (1e-300, "1e-300"),
            (123456.789, "123456.789"),
        ] {
            assert_eq!(number(v), shown);
        }
    }

    #[test]
    fn the_default_delta_is_that_of_the_finite_samples() {
        let x: Vec<f64> = (0..1500).map(|i| f64::from(i % 7)).collect();
        let mut holed = x.clone();
        for i in [0, 3, 500] {
            holed[i] = f64::NAN;
        }
        holed[9] = f64::INFINITY;
        let finite: Vec<f64> = x[..1000]
            .iter()
            .enumerate()
            .filter(|(i, _)| ![0, 3, 9, 500].contains(i))
            .map(|(_, v)| *v)
            .collect();
        let mean = finite.iter().sum::<f64>() / finite.len() as f64;
        let var = finite.iter().map(|v| (v - mean).powi(2)).sum::<f64>() / finite.len() as f64;
        assert_eq!(default_delta(&holed), Ok(0.1 * var));
        assert_eq!(default_delta(&[f64::NAN; 10]), Ok(1.0));
        assert!(default_delta(&[1e200, -1e200]).is_err());
    }
}
