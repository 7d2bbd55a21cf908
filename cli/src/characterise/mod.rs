//! `imu-ar characterise`: all six axes of a recording in one streaming pass. Per axis: the
//! overlapping Allan deviation, the composite noise model of `imu-ar noise` (its AR part from the
//! streamed autocovariances, Yule-Walker, order by BIC), the Allan check and the IEEE 952
//! readings; then two decomposition plots (gyros, accelerometers), the parameter files of
//! `--format`, and a summary table.
//!
//! Nothing but the streaming statistics is held ([`stream`]: about 2.6 MB per axis), so a
//! recording of any length fits in memory. `imu-ar noise` holds its column (its AR part is a
//! Burg fit over the samples), as do `fit`, `compare`, `report`, `order`, `kalman` and `adev`.

pub mod stream;

use std::io::IsTerminal;
use std::path::{Path, PathBuf};
use std::sync::{Mutex, MutexGuard, PoisonError};

use imu_ar::ArModel;
use imu_ar::batch::criteria::Criterion;
use imu_ar::batch::levinson_durbin;
use imu_ar::noise::Octaves;
use serde::Serialize;

use crate::error::{Fail, escaped, with_file};
use crate::export::{AxisModel, Format, ImuModel, write};
use crate::input::source::{self, AXES, Kind, Request};
use crate::input::timing::TimingSummary;
use crate::input::units::{Quantity, Unit};
use crate::input::{check_rate, check_span, number, resolve_rate, summary};
use crate::method::with_order;
use crate::noise::units::Units;
use crate::noise::{Fitted, Fitting, ModelArgs, NoiseResult, OCTAVES, plot};
use crate::output::{Output, json};
use stream::{AxisStream, LAGS};

/// The arguments of `imu-ar characterise`.
#[derive(clap::Args)]
pub struct Args {
    /// The recording: CSV files read as one record (`-` is standard input), or ROS 1 bags or
    /// MCAP files with --topic.
    #[arg(required = true)]
    files: Vec<PathBuf>,
    /// The sensor_msgs/Imu topic of a bag or an MCAP file.
    #[arg(long)]
    topic: Option<String>,
    /// The header frame_id of the IMU to read, when the topic carries more than one.
    #[arg(long)]
    frame_id: Option<String>,
    /// The IMU of an ArduPilot DataFlash log, when it holds several (the `I` of its IMU
    /// messages).
    #[arg(long)]
    instance: Option<u8>,
    /// The six CSV columns: gyro x, y, z, then accelerometer x, y, z (names, names without
    /// their unit bracket, or 0-based indices) [default: w_RS_S_x .. a_RS_S_z (EuRoC), or
    /// gx .. az].
    #[arg(long, value_delimiter = ',')]
    columns: Option<Vec<String>>,
    /// The CSV column of the timestamps [default: timestamp, time, t or t_UNIT].
    #[arg(long)]
    time_column: Option<String>,
    /// Drop samples whose timestamp is not after the one before (counted).
    #[arg(long)]
    drop_backward: bool,
    /// Sample rate in Hz [default: from the timestamps].
    #[arg(long, allow_negative_numbers = true)]
    rate: Option<f64>,
    /// The gyro columns' unit when their header does not say: rad/s, deg/s or deg/h.
    #[arg(long)]
    gyro_unit: Option<String>,
    /// The accelerometer columns' unit when their header does not say: m/s^2, g or mg.
    #[arg(long)]
    accel_unit: Option<String>,
    /// The composite's settings, per axis.
    #[command(flatten)]
    model: ModelArgs,
    /// Directory for the plots and parameter files (created if needed).
    #[arg(long)]
    out: PathBuf,
    /// The parameter files to write: kalibr, openvins, vins, orbslam3, px4, ardupilot,
    /// state-space, comma-separated, or all.
    #[arg(long, default_value = "all")]
    format: String,
    /// The time (s) the filter must coast: the six white + random walk formats then carry the
    /// smallest random walk whose Allan deviation overbounds the model's at every octave from
    /// 1 s to it [default: the model's random walk, and the files say how far it overbounds].
    #[arg(long, allow_negative_numbers = true)]
    horizon: Option<f64>,
    /// ArduPilot's main loop rate (SCHED_LOOP_RATE), Hz: it sets EKF3's step, 12.5 ms at the
    /// default 400 Hz (EKF3 sums the loop's IMU samples to about 12 ms).
    #[arg(long, allow_negative_numbers = true)]
    loop_rate: Option<f64>,
    /// The vehicle ID (MAV_SYS_ID, 1 to 255) of the PX4 parameter file: QGroundControl loads
    /// it only into that vehicle [default: 1].
    #[arg(long, value_parser = clap::value_parser!(u8).range(1..))]
    sysid: Option<u8>,
    /// PX4's IMU_INTEG_RATE, Hz (100 to 1000): EKF2 steps whole messages of that rate, so
    /// the PX4 file's EKF2_PREDICT_US is the whole number of them nearest the filter rate's
    /// step [default: 200].
    #[arg(long, allow_negative_numbers = true)]
    imu_integ_rate: Option<f64>,
    /// Print one JSON object instead of the table.
    #[arg(long)]
    pub json: bool,
}

/// The six axes' models and what was written.
#[derive(Serialize)]
pub struct Characterisation {
    /// The rate, Hz.
    pub rate_hz: f64,
    /// Samples per axis.
    pub n: u64,
    /// What the timestamps show, when the rate came from them.
    pub timing: Option<TimingSummary>,
    /// Messages skipped, counted.
    pub skipped: SkippedCounts,
    /// Per axis (gx, gy, gz, ax, ay, az): the model, in SI units (rad/s, m/s^2).
    pub axes: Vec<AxisResult>,
    /// The files written.
    pub files: Vec<String>,
}

/// Skipped messages, by cause.
#[derive(Serialize)]
pub struct SkippedCounts {
    /// Undecodable messages.
    pub undecodable: u64,
    /// Messages with a NaN or infinite axis.
    pub non_finite: u64,
    /// Samples whose timestamp went backwards (with --drop-backward).
    pub backward: u64,
    /// Messages of the topic's other IMUs (those --frame-id did not choose).
    pub other_frame_id: u64,
    /// Samples of a PX4 ULog file's gyro or accelerometer without a partner of the same time
    /// in the other.
    pub unpaired: u64,
    /// 1 when the log's last message is cut short by the end of the file.
    pub cut_short: u64,
    /// Messages that mark a sensor read as not provided (`sensor_msgs/Imu`'s covariance
    /// flag), skipped.
    pub not_provided: u64,
    /// Samples kept in file order though their stamp is not after the one before (a given
    /// `--rate`).
    pub backward_kept: u64,
}

/// One axis.
#[derive(Serialize)]
pub struct AxisResult {
    /// gx .. az.
    pub axis: &'static str,
    /// The column it was read from.
    pub column: String,
    /// rad/s or m/s^2.
    pub unit: &'static str,
    /// The model, as `imu-ar noise --json` gives it.
    pub model: NoiseResult,
}

/// Reads the recording once, fits every axis and writes the files.
pub fn run(args: &Args) -> Result<Characterisation, Fail> {
    if let Some(r) = args.rate {
        check_rate(r)?;
    }
    let config = args.model.config()?;
    let given = [
        args.gyro_unit.as_deref().map(parse_unit).transpose()?,
        args.accel_unit.as_deref().map(parse_unit).transpose()?,
    ];
    let formats = Format::list(&args.format)?;
    if let Some(h) = args.horizon
        && !(h.is_finite() && h >= 1.0)
    {
        return Err(Fail(format!(
            "--horizon {}: must be a number of seconds from 1 (the overbound runs from 1 s)",
            number(h)
        )));
    }
    let columns = columns(args)?;
    // Created now, so that a folder that cannot be made fails before the record is read;
    // removed again with the parents it needed (while still empty) when the run fails.
    if args.out.exists() && !args.out.is_dir() {
        return Err(Fail(format!(
            "--out {}: is a file, not a folder",
            args.out.display()
        )));
    }
    make_output(&args.out)?;
    let result = characterise(args, &config, given, &formats, &columns);
    output_done(result.is_ok());
    result
}

/// [`run`] once its arguments are checked and `--out` exists.
fn characterise(
    args: &Args,
    config: &imu_ar::noise::FitConfig,
    given: [Option<Unit>; 2],
    formats: &[Format],
    columns: &[String],
) -> Result<Characterisation, Fail> {
    let axes: Vec<AxisStream<OCTAVES>> = (0..6).map(|_| AxisStream::new()).collect();
    let progress = Progress::new();
    crate::input::csv::quiet_progress();
    let request = Request {
        columns,
        topic: args.topic.as_deref(),
        frame_id: args.frame_id.as_deref(),
        time_column: args.time_column.as_deref(),
        want_time: args.rate.is_none(),
        drop_backward: args.drop_backward,
        instance: args.instance,
    };
    // The rows go in batches to a second thread, which keeps the six axes' statistics while
    // this one reads and parses: the two halves of the work overlap. The queue holds 32
    // batches (6 MB) so that neither waits while the other is off its core (three threads
    // share two cores on small machines).
    let (send, receive) = std::sync::mpsc::sync_channel::<Vec<[f64; 6]>>(32);
    let worker = |mut axes: Vec<AxisStream<OCTAVES>>| {
        let mut column = Vec::with_capacity(BATCH);
        for batch in receive {
            for (i, axis) in axes.iter_mut().enumerate() {
                column.clear();
                column.extend(batch.iter().map(|row| row[i]));
                axis.extend(&column);
            }
        }
        axes
    };
    let (read, kept) = std::thread::scope(|scope| {
        let kept = scope.spawn(move || worker(axes));
        let mut batch = Vec::with_capacity(BATCH);
        let mut rows = 0u64;
        let read = source::stream(&args.files, &request, &mut |v| {
            let mut row = [0.0; 6];
            for (r, x) in row.iter_mut().zip(v) {
                *r = *x;
            }
            batch.push(row);
            if batch.len() == BATCH {
                // A closed channel means the worker is gone; its join says why.
                let _ = send.send(std::mem::replace(&mut batch, Vec::with_capacity(BATCH)));
            }
            rows += 1;
            progress.tick(rows);
        });
        if !batch.is_empty() {
            let _ = send.send(batch);
        }
        drop(send);
        (read, kept.join())
    });
    let axes = kept.map_err(|_| Fail("the statistics thread stopped".into()))?;
    let read = read?;
    if let Some(w) = read.skipped.cut_short_warning() {
        eprintln!("imu-ar: warning: {}", with_file(&args.files, w).0);
    }
    if let Some(w) = read.skipped.summary() {
        eprintln!("imu-ar: warning: {}", with_file(&args.files, w).0);
    }
    progress.finish();
    let n = axes[0].samples();
    let backward = read.timing.as_ref().map_or(0, |(t, _)| t.dropped());
    let stamped = read.timing.as_ref().and_then(|(t, _)| t.kept_over_span());
    let (timing, unchecked) =
        summary(read.timing, args.rate.is_none()).map_err(|e| with_file(&args.files, e))?;
    let rate = resolve_rate(args.rate, timing.as_ref()).map_err(|e| with_file(&args.files, e.0))?;
    crate::input::check_packed(args.rate, stamped).map_err(|e| with_file(&args.files, e))?;
    // The rate's warnings, printed once the record is known to be read (a refusal is one
    // line).
    let warnings: Vec<String> = [
        crate::input::unchecked(args.rate, unchecked.as_deref()),
        crate::input::coarse(args.rate, timing.as_ref()),
        read.caveat
            .clone()
            .filter(|_| args.rate.is_none())
            .or_else(|| crate::input::loose(args.rate, timing.as_ref())),
    ]
    .into_iter()
    .flatten()
    .collect();
    check_span("--rate", rate, n as usize)?;
    crate::input::check_gaps(timing.as_ref(), n as usize)
        .and_then(|()| crate::input::check_subsampled(&args.files, timing.as_ref()))
        .map_err(|e| with_file(&args.files, e))?;
    let kind = Kind::of(&args.files[0]);
    let units: Vec<Unit> = (0..6)
        .map(|i| {
            axis_unit(
                i,
                read.units.get(i).copied().flatten(),
                read.unknown.get(i).and_then(Option::as_deref),
                given[i / 3],
                &columns[i],
                kind,
            )
        })
        .collect::<Result<_, _>>()
        .map_err(|e| with_file(&args.files, e.0))?;
    for w in warnings {
        eprintln!("imu-ar: warning: {}", with_file(&args.files, w).0);
    }
    if let Some(w) = gravity(
        std::array::from_fn(|k| axes[3 + k].mean() * units[3 + k].to_si),
        units[3].name,
        kind,
    )
    .map_err(|e| with_file(&args.files, e))?
    {
        eprintln!("imu-ar: warning: {}", with_file(&args.files, w).0);
    }
    let fits: Vec<Fitting> = units
        .iter()
        .map(|u| Fitting {
            n: n as usize,
            rate,
            filter_rate: args.model.filter_rate.unwrap_or(rate),
            config: *config,
            units: Units::of(u.si().name),
            export: true,
        })
        .collect();
    let octaves = axes
        .iter()
        .zip(&units)
        .map(|(a, u)| a.octaves(1.0 / rate, u.to_si * u.to_si))
        .collect::<Result<Vec<_>, _>>()
        .map_err(|e| with_file(&args.files, e))?;
    // The gyros' fits on a thread of their own beside the accelerometers': the first axis
    // that fails (in their order) is the one named.
    let fit = |i: usize| -> Result<Fitted<'_>, Fail> {
        let fail = |e: String| with_file(&args.files, format!("{} ({}): {e}", AXES[i], columns[i]));
        if axes[i].is_constant() {
            return Err(fail("constant (a stuck sensor?): no noise to model".into()));
        }
        fit_axis(&fits[i], &axes[i], &octaves[i], units[i].to_si).map_err(|Fail(e)| {
            // Every Allan variance underflowed, though the samples differ.
            if e == imu_ar::noise::NoiseError::Constant.to_string() {
                fail(
                    "the Allan variance underflows f64 (differences of about 1e-160 or less); \
                     rescale the record"
                        .into(),
                )
            } else {
                fail(e)
            }
        })
    };
    let fitted: Vec<Result<Fitted<'_>, Fail>> = std::thread::scope(|scope| {
        let gyros = scope.spawn(|| (0..3).map(fit).collect::<Vec<_>>());
        let accelerometers: Vec<_> = (3..6).map(fit).collect();
        let mut all = gyros
            .join()
            .unwrap_or_else(|_| vec![Err(Fail("the gyros' fits stopped".into()))]);
        all.extend(accelerometers);
        all
    });
    let mut results = Vec::new();
    let mut paints = Vec::new();
    let mut models = Vec::new();
    for (i, fitted) in fitted.into_iter().enumerate() {
        let Fitted {
            result,
            paint,
            axis,
        } = fitted?;
        results.push(AxisResult {
            axis: AXES[i],
            column: columns[i].clone(),
            unit: units[i].si().name,
            model: result,
        });
        paints.push(paint);
        models.extend(axis);
    }
    let axes: [AxisModel; 6] = models
        .try_into()
        .map_err(|_| Fail("an axis has no model for the parameter files".into()))?;
    let imu = ImuModel {
        axes,
        rate_hz: rate,
        topic: args.topic.clone(),
        filter_rate_hz: args.model.filter_rate,
        loop_rate_hz: args.loop_rate,
        sysid: args.sysid,
        imu_integ_rate_hz: args.imu_integ_rate,
        origin: None,
    };
    // The two plots drawn side by side, the gyros' on a thread of their own.
    let draw = |dir: &Path| -> Result<Vec<PathBuf>, Fail> {
        let one = |(name, range, what): (&str, std::ops::Range<usize>, &str)| {
            let path = dir.join(name);
            let panels: Vec<(&crate::noise::Paint, String)> = range
                .map(|i| {
                    (
                        &paints[i],
                        format!(
                            "{what} {} ({}), {}",
                            AXES[i],
                            escaped(&columns[i]),
                            units[i].si().name
                        ),
                    )
                })
                .collect();
            plot::png(&path, (1800, 600), &panels).map_err(|e| {
                Fail(format!(
                    "{}: cannot draw: {e}",
                    args.out.join(name).display()
                ))
            })?;
            Ok(path)
        };
        let (gyro, accel) = std::thread::scope(|scope| {
            let gyro = scope.spawn(|| one(("gyro.png", 0..3, "gyro")));
            let accel = one(("accel.png", 3..6, "accelerometer"));
            let gyro = gyro
                .join()
                .unwrap_or_else(|_| Err(Fail("the gyros' plot stopped".into())));
            (gyro, accel)
        });
        Ok(vec![gyro?, accel?])
    };
    let files = write_all(formats, &imu, args.horizon, &args.out, &draw)?;

    Ok(Characterisation {
        rate_hz: rate,
        n,
        skipped: SkippedCounts {
            undecodable: read.skipped.undecodable,
            non_finite: read.skipped.non_finite,
            backward,
            other_frame_id: read.skipped.other_frame_id,
            unpaired: read.skipped.unpaired,
            cut_short: read.skipped.cut_short,
            not_provided: read.skipped.disregarded,
            backward_kept: read.skipped.backward_kept,
        },
        timing,
        axes: results,
        files,
    })
}

/// The output folders a run writes into, for a signal's handler ([`remove_staging`]).
struct Staging {
    /// The fresh folder [`write_staged`] writes into while it does (made while this is held).
    folder: Option<PathBuf>,
    /// The folders made for the output (the output folder and those above it that were not
    /// there), deepest first, while the run may still fail.
    made: Vec<PathBuf>,
    /// Whether the process is ending: no folder is made after.
    ending: bool,
    /// Whether the output is in place: the run is done but for its report, and a signal
    /// then lets it end as it would have.
    written: bool,
}

/// The run's output folders; the moves into `out` hold it.
static STAGING: Mutex<Staging> = Mutex::new(Staging {
    folder: None,
    made: Vec::new(),
    ending: false,
    written: false,
});

/// The run's output folders, locked.
fn staging() -> MutexGuard<'static, Staging> {
    STAGING.lock().unwrap_or_else(PoisonError::into_inner)
}

/// Removes the folder `write_staged` is writing into, if any, once the moves into `out` are
/// done, and the folders made for the output that are left empty: for a process that ends on
/// a signal (SIGINT, SIGTERM, SIGHUP), which leaves `out` as it was. Whether the process is
/// to end: not once the whole new set is in place (the run then ends as it would have, its
/// report written, rather than in a failure that left its output); else the lock stays
/// taken, so no folder is made after this, and the caller ends the process.
pub fn remove_staging() -> bool {
    let mut held = staging();
    if held.written {
        return false;
    }
    held.ending = true;
    if let Some(folder) = held.folder.take() {
        // A file the run creates between a removal's listing and its end leaves the folder
        // standing: again, until it is gone (no file can be created in it after that).
        for _ in 0..1000 {
            match std::fs::remove_dir_all(&folder) {
                Err(e) if e.kind() != std::io::ErrorKind::NotFound => {}
                _ => break,
            }
        }
    }
    remove_empty(&held.made);
    std::mem::forget(held);
    true
}

/// Makes the folder `out` and those above it that are missing, which [`output_done`] (and a
/// signal's handler) removes again while they are empty; an error naming `out`.
pub(crate) fn make_output(out: &Path) -> Result<(), Fail> {
    let mut held = staging();
    if held.ending {
        return Err(Fail("ended by a signal".into()));
    }
    let made: Vec<PathBuf> = out
        .ancestors()
        .filter(|p| !p.as_os_str().is_empty())
        .take_while(|p| p.symlink_metadata().is_err())
        .map(Path::to_path_buf)
        .collect();
    let made_now = std::fs::create_dir_all(out);
    held.made.extend(made.iter().cloned());
    made_now.map_err(|e| {
        remove_empty(&made);
        Fail(format!("--out {}: cannot create: {e}", out.display()))
    })
}

/// The run is over: the folders [`make_output`] made are kept where it wrote (`ok`), else
/// removed while they are empty.
pub(crate) fn output_done(ok: bool) {
    let mut held = staging();
    if !ok {
        remove_empty(&held.made);
    }
    held.made.clear();
}

/// Removes the folders `made` (deepest first) that are empty, up to the first that is not.
fn remove_empty(made: &[PathBuf]) {
    for folder in made {
        if std::fs::remove_dir(folder).is_err() {
            break;
        }
    }
}

/// Removes the folders `.imu-ar-PID` in `out` whose process no longer runs (killed before it
/// could remove its own), where the system lists its processes in `/proc`.
fn sweep(out: &Path) {
    if !Path::new("/proc/self").exists() {
        return;
    }
    let Ok(entries) = std::fs::read_dir(out) else {
        return;
    };
    for entry in entries.flatten() {
        let name = entry.file_name();
        let pid = name
            .to_str()
            .and_then(|n| n.strip_prefix(".imu-ar-"))
            .and_then(|p| p.parse::<u32>().ok());
        if let Some(pid) = pid
            && pid != std::process::id()
            && !Path::new("/proc").join(pid.to_string()).exists()
        {
            let _ = std::fs::remove_dir_all(entry.path());
        }
    }
}

/// Writes every file of `formats` and the plots `draw` makes, or none ([`write_staged`]); the
/// files of the other formats an earlier run left in `out` are set aside.
pub(crate) fn write_all(
    formats: &[Format],
    imu: &ImuModel,
    horizon: Option<f64>,
    out: &Path,
    draw: &dyn Fn(&Path) -> Result<Vec<PathBuf>, Fail>,
) -> Result<Vec<String>, Fail> {
    write_staged(out, &stale(formats), &|folder| {
        let mut paths = formats
            .iter()
            .map(|f| write(*f, imu, horizon, folder))
            .collect::<Result<Vec<PathBuf>, Fail>>()?;
        paths.extend(draw(folder)?);
        Ok(paths)
    })
}

/// The files of the formats not in `formats`: an earlier run's, where an export wrote them.
pub(crate) fn stale(formats: &[Format]) -> Vec<&'static str> {
    Format::ALL
        .iter()
        .filter(|f| !formats.contains(f))
        .map(|f| f.file_name())
        .collect()
}

/// Writes the files `write` writes into a folder, or none: into a fresh folder in `out`
/// first, moved into `out` once all are written ([`commit`]), the files named `stale` there
/// that an export wrote set aside with them (so that the folder holds one run's files; a file
/// of such a name that no export wrote is left as it is). The paths written, in `out`.
pub(crate) fn write_staged(
    out: &Path,
    stale: &[&str],
    write: &dyn Fn(&Path) -> Result<Vec<PathBuf>, Fail>,
) -> Result<Vec<String>, Fail> {
    let made = !out.is_dir();
    make_output(out)?;
    sweep(out);
    let staging_folder = out.join(format!(".imu-ar-{}", std::process::id()));
    let staging_folder = &staging_folder;
    {
        let mut held = staging();
        if held.ending {
            return Err(Fail("ended by a signal".into()));
        }
        held.folder = Some(staging_folder.clone());
        if let Err(e) = std::fs::create_dir_all(staging_folder) {
            held.folder = None;
            drop(held);
            if made {
                output_done(false);
            }
            return Err(Fail(format!("{}: {e}", out.display())));
        }
    }
    let written = write(staging_folder);
    // A signal's handler waits for the moves and the folder's removal.
    let mut held = staging();
    let moved = written.and_then(|paths| {
        commit(
            &paths,
            stale,
            out,
            &staging_folder.join("kept"),
            &|from, to| std::fs::rename(from, to),
        )
    });
    let _ = std::fs::remove_dir_all(staging_folder);
    held.folder = None;
    held.written = moved.is_ok();
    drop(held);
    if made {
        output_done(moved.is_ok());
    }
    moved
}

/// Whether the file at `path` is one an export wrote: its first MiB names the exporter.
fn exported(path: &Path) -> bool {
    use std::io::Read;
    let exporter = crate::export::files::TOOL;
    let exporter = &exporter[exporter.find('(').unwrap_or(0)..];
    let mut head = Vec::new();
    std::fs::File::open(path)
        .and_then(|f| f.take(1 << 20).read_to_end(&mut head))
        .is_ok()
        && head
            .windows(exporter.len())
            .any(|w| w == exporter.as_bytes())
}

/// Moves the files `paths` into `out` by `rename`, and the files named `stale` there that an
/// export wrote (of an earlier run) out of it, all or none. The files of the same names already there are kept
/// first (linked, or copied, into the folder `kept`, where the stale ones go too); when a
/// move fails, the ones before it are undone and the kept files put back, and the error names
/// the file that could not be replaced.
fn commit(
    paths: &[PathBuf],
    stale: &[&str],
    out: &Path,
    kept: &Path,
    rename: &dyn Fn(&Path, &Path) -> std::io::Result<()>,
) -> Result<Vec<String>, Fail> {
    let target = |p: &PathBuf| out.join(p.file_name().unwrap_or_default());
    let unchanged = "; the files in the folder are as they were";
    if let Some(to) = paths.iter().map(target).find(|to| to.is_dir()) {
        return Err(Fail(format!(
            "{}: is a directory; no file was written",
            to.display()
        )));
    }
    std::fs::create_dir_all(kept).map_err(|e| Fail(format!("{}: {e}", kept.display())))?;
    // Each new file, where it goes, and the old file kept.
    let mut moves: Vec<(&PathBuf, PathBuf, Option<PathBuf>)> = Vec::new();
    for p in paths {
        let to = target(p);
        let old = match to.symlink_metadata() {
            Ok(_) => {
                let keep = kept.join(p.file_name().unwrap_or_default());
                std::fs::hard_link(&to, &keep)
                    .or_else(|_| std::fs::copy(&to, &keep).map(drop))
                    .map_err(|e| {
                        Fail(format!(
                            "{}: cannot be kept while it is replaced: {e}; no file was written",
                            to.display()
                        ))
                    })?;
                Some(keep)
            }
            Err(_) => None,
        };
        moves.push((p, to, old));
    }
    // A stale file set aside is a move from the folder into `kept`, undone the same way.
    let aside: Vec<(PathBuf, PathBuf)> = stale
        .iter()
        .map(|name| (out.join(name), kept.join(name)))
        .filter(|(at, _)| at.is_file() && exported(at))
        .collect();
    for (k, (at, keep)) in aside.iter().enumerate() {
        if let Err(e) = rename(at, keep) {
            for (at, keep) in aside[..k].iter().rev() {
                let _ = rename(keep, at);
            }
            return Err(Fail(format!(
                "{}: an earlier run's file, cannot be set aside: {e}{unchanged}",
                at.display()
            )));
        }
    }
    let restore_aside = || {
        for (at, keep) in aside.iter().rev() {
            let _ = rename(keep, at);
        }
    };
    for (k, (from, to, _)) in moves.iter().enumerate() {
        if let Err(e) = rename(from, to) {
            restore_aside();
            for (from, to, old) in moves[..k].iter().rev() {
                match old {
                    Some(old) => {
                        let _ = rename(old, to);
                    }
                    None => {
                        let _ = rename(to, from);
                    }
                }
            }
            return Err(Fail(format!("{}: {e}{unchanged}", to.display())));
        }
    }
    Ok(moves
        .iter()
        .map(|(_, to, _)| to.display().to_string())
        .collect())
}

/// The accelerometers' mean (m/s^2, as read in the unit `read`) against gravity's: a record
/// at rest reads 9.81 m/s^2 in magnitude whatever way the sensor lies. A magnitude within 20 %
/// of what values in another of m/s^2, g and mg read in `read` give (1 or 1000 for g or mg
/// read as m/s^2, 96 for m/s^2 read as g, 9807 for mg read as g, ...) is a unit mistaken:
/// refused, naming the unit and how to say it; another outside 7 to 13 m/s^2 (a record not at
/// rest, gravity taken out) is a warning, returned.
fn gravity(mean: [f64; 3], read: &str, kind: Kind) -> Result<Option<String>, String> {
    const G: f64 = 9.806_65;
    const UNITS: [(&str, f64); 3] = [("m/s^2", 1.0), ("g", G), ("mg", 1e-3 * G)];
    let magnitude = mean.iter().map(|a| a * a).sum::<f64>().sqrt();
    let shown = format!(
        "the accelerometers read {magnitude:.4} m/s^2 on average (x, y, z: {:.4}, {:.4}, \
         {:.4}), where a sensor at rest reads gravity's {G} whatever way it lies",
        mean[0], mean[1], mean[2]
    );
    let read_si = UNITS.iter().find(|u| u.0 == read).map_or(1.0, |u| u.1);
    for &(unit, si) in UNITS.iter().filter(|u| u.0 != read) {
        let reading = G * read_si / si;
        if (0.8 * reading..=1.25 * reading).contains(&magnitude) {
            let how = match kind {
                Kind::Csv => format!(
                    ": say so in the header's bracket ([{unit}]), or with --accel-unit {unit} \
                     for columns without one"
                ),
                Kind::Bag | Kind::Mcap | Kind::Rosbag2 | Kind::Db3 if read == "m/s^2" => {
                    format!(
                        " (a driver that does not keep REP 103): --accel-unit {unit} reads them \
                         so"
                    )
                }
                Kind::Bag | Kind::Mcap | Kind::Rosbag2 | Kind::Db3 => {
                    format!(" (the messages' own unit, REP 103): leave --accel-unit {read} out")
                }
                _ => String::new(),
            };
            return Err(format!(
                "{shown}: the values are in {unit}, not {read}{how}"
            ));
        }
    }
    Ok((!(7.0..=13.0).contains(&magnitude)).then(|| {
        format!("{shown}: a record not at rest, or in another unit, gives noise in that unit")
    }))
}

/// One axis's composite, with the AR part (order by BIC, 0 to [`LAGS`]) from its streamed
/// autocovariances; without one when none fits.
pub(crate) fn fit_axis<'a>(
    fit: &'a Fitting,
    axis: &AxisStream<OCTAVES>,
    octaves: &'a Octaves<OCTAVES>,
    to_si: f64,
) -> Result<Fitted<'a>, Fail> {
    let c = axis.autocovariances().map(|v| v * to_si * to_si);
    let order = match levinson_durbin::<f64, LAGS>(&c) {
        Ok(l) => {
            let variances = std::iter::once(c[0]).chain(l.error_power.iter().copied());
            Criterion::Bic.select(axis.samples() as usize, variances)
        }
        Err(_) => 0,
    };
    let mean = axis.mean() * to_si;
    let with_ar = match order {
        0 => None,
        p => Some(with_order!(p, ar_part(fit, &c, mean, octaves))),
    };
    match with_ar {
        Some(Ok(fitted)) => Ok(fitted),
        _ => fit.model::<1>(octaves, None),
    }
}

/// The composite with the Yule-Walker AR(`P`) part of autocovariances `c`.
fn ar_part<'a, const P: usize>(
    fit: &'a Fitting,
    c: &[f64],
    mean: f64,
    octaves: &'a Octaves<OCTAVES>,
) -> Result<Fitted<'a>, Fail> {
    let l = levinson_durbin::<f64, P>(c).map_err(|e| Fail(e.to_string()))?;
    let ar = ArModel::new(l.a, l.error_power[P - 1], mean, 1.0 / fit.rate)?;
    fit.model::<P>(octaves, Some(&ar))
}

/// The six columns to read.
fn columns(args: &Args) -> Result<Vec<String>, Fail> {
    if let Some(c) = &args.columns {
        if c.len() != 6 {
            return Err(Fail(format!(
                "--columns: {} names given; six are needed (gyro x, y, z, accelerometer x, y, z)",
                c.len()
            )));
        }
        return Ok(c.clone());
    }
    let named = |names: [&str; 6]| names.map(String::from).to_vec();
    if args.topic.is_some() || Kind::of(&args.files[0]) != Kind::Csv {
        return Ok(named(AXES));
    }
    let header = crate::input::csv::header(&args.files).map_err(|e| Fail(e.to_string()))?;
    let euroc = [
        "w_RS_S_x", "w_RS_S_y", "w_RS_S_z", "a_RS_S_x", "a_RS_S_y", "a_RS_S_z",
    ];
    for names in [euroc, AXES] {
        let found: Vec<Result<usize, String>> = names
            .iter()
            .map(|n| crate::input::csv::position(&header, n))
            .collect();
        if found.iter().all(Result::is_ok) {
            return Ok(named(names));
        }
        // All six there, some more than once (two IMUs side by side): which to read.
        if found
            .iter()
            .all(|f| f.as_ref().is_ok() || f.as_ref().is_err_and(|e| e.contains(" times")))
            && let Some(Err(e)) = found.into_iter().find(Result::is_err)
        {
            return Err(with_file(
                &args.files,
                format!("{e}: name the six to read with --columns (by number where names repeat)"),
            ));
        }
    }
    Err(with_file(
        &args.files,
        "no EuRoC (w_RS_S_x .. a_RS_S_z) or gx .. az columns: name the six with --columns",
    ))
}

/// Rows handed to the statistics thread at a time.
const BATCH: usize = 4096;

/// A `--gyro-unit` or `--accel-unit`.
pub(crate) fn parse_unit(name: &str) -> Result<Unit, Fail> {
    Unit::parse(name).ok_or_else(|| {
        Fail(format!(
            "unit '{}': rad/s, deg/s, deg/h (gyros) or m/s^2, g, mg (accelerometers)",
            escaped(name)
        ))
    })
}

/// The unit of axis `i`: its header's (or the message's), else the flag's, checked to measure
/// what the axis measures. `bracket` is a header bracket that names no unit known here;
/// `kind`: the recording's kind, which says where `read` comes from. A ROS message's unit
/// (SI, REP 103) gives way to a flag that names another (a driver that publishes g), with a
/// warning; a CSV header's, a ULog's or a DataFlash log's does not.
pub(crate) fn axis_unit(
    i: usize,
    read: Option<Unit>,
    bracket: Option<&str>,
    given: Option<Unit>,
    column: &str,
    kind: Kind,
) -> Result<Unit, Fail> {
    let (want, flag) = match i {
        0..3 => (Quantity::AngularRate, "--gyro-unit"),
        _ => (Quantity::Acceleration, "--accel-unit"),
    };
    let mut read = read;
    if let (Some(r), Some(g)) = (read, given)
        && r != g
    {
        let what = match kind {
            Kind::Bag | Kind::Mcap | Kind::Rosbag2 | Kind::Db3 if g.quantity == want => {
                eprintln!(
                    "imu-ar: warning: {flag} {}: {} read in {}, not in the {} a sensor_msgs/Imu \
                     message gives (SI units, REP 103)",
                    g.name,
                    escaped(column),
                    g.name,
                    r.name
                );
                read = None;
                None
            }
            Kind::Bag | Kind::Mcap | Kind::Rosbag2 | Kind::Db3 => Some(format!(
                "a sensor_msgs/Imu message gives {} in {} (SI units, REP 103)",
                escaped(column),
                r.name
            )),
            Kind::Ulog => Some(format!(
                "a ULog's sensor topics give {} in {} (PX4's SI units)",
                escaped(column),
                r.name
            )),
            Kind::DataFlash => Some(format!(
                "an ArduPilot IMU message gives {} in {} (SI units)",
                escaped(column),
                r.name
            )),
            _ => Some(format!(
                "the header of column '{}' says {}",
                escaped(column),
                r.name
            )),
        };
        if let Some(what) = what {
            return Err(Fail(format!(
                "{flag} {}: {what}; {flag} is for CSV columns without a unit{}",
                g.name,
                if matches!(kind, Kind::Bag | Kind::Mcap | Kind::Rosbag2 | Kind::Db3) {
                    " or a driver's messages in another unit"
                } else {
                    ""
                }
            )));
        }
    }
    if let Some(g) = given
        && g.quantity != want
    {
        return Err(Fail(format!(
            "{flag} {}: not a unit of what {} measures",
            g.name, AXES[i]
        )));
    }
    let unit = read.or(given).ok_or_else(|| match bracket {
        Some(b) => Fail(format!(
            "column '{}': its unit [{}] is not one known here (rad/s, deg/s, deg/h for a gyro; \
             m/s^2, g, mg for an accelerometer; G and mG are read as gauss); give {flag}",
            escaped(column),
            escaped(b)
        )),
        None => Fail(format!(
            "column '{}': its unit is unknown (no unit bracket in the header); give {flag}",
            escaped(column)
        )),
    })?;
    if unit.quantity != want {
        return Err(Fail(format!(
            "column '{}' is in {}, which is not what {} measures",
            escaped(column),
            unit.name,
            AXES[i]
        )));
    }
    Ok(unit)
}

/// A spinner with the messages read, on a terminal only.
struct Progress(Option<indicatif::ProgressBar>);

impl Progress {
    fn new() -> Self {
        if !std::io::stderr().is_terminal() {
            return Self(None);
        }
        let bar = indicatif::ProgressBar::new_spinner();
        if let Ok(style) = indicatif::ProgressStyle::with_template(
            "{spinner} {human_pos} samples per axis read, {per_sec}, {elapsed}",
        ) {
            bar.set_style(style);
        }
        Self(Some(bar))
    }

    fn tick(&self, n: u64) {
        if let Some(bar) = &self.0
            && n.is_multiple_of(1 << 16)
        {
            bar.set_position(n);
        }
    }

    fn finish(&self) {
        if let Some(bar) = &self.0 {
            bar.finish_and_clear();
        }
    }
}

impl Output for Characterisation {
    fn text(&self) -> String {
        let mut s = format!(
            "{} samples per axis at {} Hz; skipped: {} undecodable, {} not finite, {} backward, \
             {} of other frame_ids{}\n",
            self.n,
            json(&self.rate_hz),
            self.skipped.undecodable,
            self.skipped.non_finite,
            self.skipped.backward,
            self.skipped.other_frame_id,
            [
                (
                    self.skipped.unpaired,
                    "without a partner in the other sensor's topic"
                ),
                (
                    self.skipped.not_provided,
                    "marking a sensor read as not provided"
                ),
                (
                    self.skipped.backward_kept,
                    "kept though stamped before the one before"
                ),
            ]
            .iter()
            .filter(|(n, _)| *n > 0)
            .map(|(n, what)| format!(", {n} {what}"))
            .collect::<String>()
        );
        if let Some(t) = &self.timing {
            s += &t.text();
            s += "\n";
        }
        s += "axis unit   N (u/sqrt(Hz)) ADEV(1 s)   K (u/s/sqrt(Hz)) B (u)       tau_B (s)  GM AR explained_up_to_s\n";
        for a in &self.axes {
            let m = &a.model;
            let e = |v: Option<f64>| v.map_or("-".to_string(), |v| format!("{v:.4e}"));
            s += &format!(
                "{:<4} {:<6} {:<14} {:<11} {:<16} {:<11} {:<10} {:<2} {:<2} {}\n",
                a.axis,
                a.unit,
                e(m.white_noise),
                e(m.white_noise_at_1s()),
                e(m.random_walk),
                e(Some(m.bias_instability.value)),
                seconds(m.bias_instability.tau_s),
                m.gauss_markov.len(),
                m.ar.as_ref().map_or(0, |a| a.order),
                m.explained_up_to_s.map_or("none".to_string(), seconds)
            );
        }
        s += &format!("wrote {}\n", self.files.join(", "));
        s
    }
}

/// An averaging time in the text table: five significant digits, trailing zeros left out
/// (514.01, 0.104, 131072); the JSON keeps every digit.
fn seconds(t: f64) -> String {
    if !t.is_finite() || t == 0.0 {
        return t.to_string();
    }
    let digits = (4 - t.abs().log10().floor() as i32).clamp(0, 12) as usize;
    let text = format!("{t:.digits$}");
    match text.contains('.') {
        true => text.trim_end_matches('0').trim_end_matches('.').to_string(),
        false => text,
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn averaging_times_are_shown_to_five_digits() {
        for (t, shown) in [
            (131_072.0 / 255.0, "514.01"),
            (0.104_000_000_000_000_01, "0.104"),
            (131_072.0, "131072"),
            (2.5e-3, "0.0025"),
            (1.0, "1"),
        ] {
            assert_eq!(seconds(t), shown, "{t}");
        }
    }

    /// An earlier run's file `f`.
    fn old(f: &str) -> String {
        format!("old {f}, written by {}", crate::export::files::TOOL)
    }

    /// A folder `out` with the old files `a`, `b`, `c` and `e` (a format not asked for this
    /// time), and new `a` to `d` staged in it.
    fn staged(name: &str) -> (PathBuf, Vec<PathBuf>) {
        let out = std::env::temp_dir().join(format!("imu-ar-commit-{}-{name}", std::process::id()));
        let _ = std::fs::remove_dir_all(&out);
        let staging = out.join(".staging");
        std::fs::create_dir_all(&staging).unwrap();
        for f in ["a", "b", "c", "e"] {
            std::fs::write(out.join(f), old(f)).unwrap();
        }
        let paths = ["a", "b", "c", "d"]
            .iter()
            .map(|f| {
                let p = staging.join(f);
                std::fs::write(&p, format!("new {f}")).unwrap();
                p
            })
            .collect();
        (out, paths)
    }

    fn contents(out: &Path) -> Vec<(String, String)> {
        let mut v: Vec<(String, String)> = std::fs::read_dir(out)
            .unwrap()
            .map(|e| e.unwrap().path())
            .filter(|p| p.is_file())
            .map(|p| {
                let name = p.file_name().unwrap().to_string_lossy().into_owned();
                (name, std::fs::read_to_string(&p).unwrap())
            })
            .collect();
        v.sort();
        v
    }

    #[test]
    fn a_move_that_fails_leaves_the_old_files_as_they_were() {
        let old = |out: &Path| {
            ["a", "b", "c", "e"]
                .iter()
                .map(|f| (f.to_string(), old(f)))
                .collect::<Vec<_>>()
                == contents(out)
        };
        // The move of each file in turn fails (as an immutable file's replacement does), the
        // stale `e` set aside too.
        for failing in ["a", "b", "c", "d", "e"] {
            let (out, paths) = staged(failing);
            let rename = |from: &Path, to: &Path| {
                let forward =
                    from.parent() == Some(&out.join(".staging")) || from.parent() == Some(&out);
                if from.file_name() == Some(failing.as_ref()) && forward {
                    Err(std::io::Error::from(std::io::ErrorKind::PermissionDenied))
                } else {
                    std::fs::rename(from, to)
                }
            };
            let Err(e) = commit(&paths, &["e"], &out, &out.join(".staging/kept"), &rename) else {
                panic!("{failing}: committed");
            };
            assert!(
                e.0.starts_with(&format!("{}: ", out.join(failing).display())),
                "{}",
                e.0
            );
            assert!(
                e.0.ends_with("the files in the folder are as they were"),
                "{}",
                e.0
            );
            assert!(old(&out), "{failing}: {:?}", contents(&out));
            std::fs::remove_dir_all(&out).unwrap();
        }
        // And none fails: every new file is in place, the stale one gone.
        let (out, paths) = staged("none");
        let written = commit(
            &paths,
            &["e"],
            &out,
            &out.join(".staging/kept"),
            &|from, to| std::fs::rename(from, to),
        )
        .unwrap_or_else(|e| panic!("{}", e.0));
        assert_eq!(written.len(), 4);
        let new: Vec<(String, String)> = ["a", "b", "c", "d"]
            .iter()
            .map(|f| (f.to_string(), format!("new {f}")))
            .collect();
        assert_eq!(contents(&out), new);
        std::fs::remove_dir_all(&out).unwrap();
    }

    #[test]
    fn a_file_named_as_a_format_not_asked_for_that_no_export_wrote_is_kept() {
        // A hand-written `e` (a format's name) beside the run's files: it stays as it is
        // (it was set aside with the commit, and lost, before); an earlier run's `e` goes.
        let (out, paths) = staged("foreign");
        std::fs::write(out.join("e"), "gyroscope_noise_density: 1.0e-3 # by hand").unwrap();
        let rename = |from: &Path, to: &Path| std::fs::rename(from, to);
        commit(&paths, &["e"], &out, &out.join(".staging/kept"), &rename)
            .unwrap_or_else(|e| panic!("{}", e.0));
        let mut expected: Vec<(String, String)> = ["a", "b", "c", "d"]
            .iter()
            .map(|f| (f.to_string(), format!("new {f}")))
            .collect();
        expected.push((
            "e".into(),
            "gyroscope_noise_density: 1.0e-3 # by hand".into(),
        ));
        assert_eq!(contents(&out), expected);
        std::fs::remove_dir_all(&out).unwrap();
    }
}
