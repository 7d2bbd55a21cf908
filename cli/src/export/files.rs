//! The YAML files: Kalibr's `imu.yaml`, the OpenVINS IMU chain, VINS-Mono and ORB-SLAM3 (OpenCV
//! YAML), and what every single-number file shares: the worst axis, its comments and the
//! statement of the white noise and random walk written, the smallest overbound of the model
//! up to a horizon.

use std::ops::Range;

use super::bound::{self, FROM_TAU, Limit, Overbound};
use super::{AXIS_NAMES, AxisModel, ImuModel};
use crate::error::Fail;

/// The tool, in every file's first line.
pub const TOOL: &str = concat!("imu-ar ", env!("CARGO_PKG_VERSION"), " (imu-ar-cli export)");

/// One sensor of the IMU: three axes of one unit.
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct Sensor {
    /// `gyroscope` or `accelerometer`.
    pub name: &'static str,
    /// Its SI unit.
    pub unit: &'static str,
    /// Its axes in [`ImuModel::axes`].
    pub axes: Range<usize>,
}

/// The gyroscope, rad/s.
pub const GYRO: Sensor = Sensor {
    name: "gyroscope",
    unit: "rad/s",
    axes: 0..3,
};

/// The accelerometer, m/s^2.
pub const ACCEL: Sensor = Sensor {
    name: "accelerometer",
    unit: "m/s^2",
    axes: 3..6,
};

impl Sensor {
    /// The sensor of the axis named `name` (one of [`AXIS_NAMES`]).
    pub fn of_axis(name: &str) -> &'static Sensor {
        if name.starts_with("gyro") {
            &GYRO
        } else {
            &ACCEL
        }
    }
}

/// What a single-number file says of one sensor: the continuous `N_H` and `K_H` it stands
/// for, and its comment lines.
#[derive(Clone, Debug, PartialEq)]
pub struct Written {
    /// `N_H` written: the smallest overbound's white noise, SI/sqrt(Hz).
    pub n: f64,
    /// `K_H` written: the smallest overbound's random walk, SI/s/sqrt(Hz).
    pub k: f64,
    /// The comments: per-axis values, which axis sets the references, the overbound and its
    /// reach.
    pub lines: Vec<String>,
}

/// `v` to 4 significant digits, for comments.
pub fn short(v: f64) -> String {
    format!("{v:.4e}")
}

/// `v` exactly (the shortest text that reads back as `v`), in a form that YAML 1.1 (PyYAML,
/// which needs a point and a signed exponent), OpenCV's YAML and the parameter-file readers
/// all read as a float: `1.7e-04`, `2.0e+02`.
pub fn num(v: f64) -> String {
    let text = format!("{v:e}");
    let (mantissa, exponent) = text.split_once('e').unwrap_or((&text, "0"));
    let mantissa = if mantissa.contains('.') {
        mantissa.to_string()
    } else {
        format!("{mantissa}.0")
    };
    let e: i32 = exponent.parse().unwrap_or(0);
    let sign = if e < 0 { '-' } else { '+' };
    format!("{mantissa}e{sign}{:02}", e.unsigned_abs())
}

/// `v` if finite, else a [`Fail`] naming `what`.
pub fn finite(what: &str, v: f64) -> Result<f64, Fail> {
    if v.is_finite() {
        Ok(v)
    } else {
        Err(Fail(format!("{what} is not finite ({v})")))
    }
}

/// `text` as a double-quoted YAML scalar (`\` and `"` escaped); control characters are refused.
pub fn yaml_string(what: &str, text: &str) -> Result<String, Fail> {
    if text.chars().any(char::is_control) {
        return Err(Fail(format!(
            "{what} {:?}: must not contain control characters",
            crate::error::escaped(text)
        )));
    }
    Ok(format!(
        "\"{}\"",
        text.replace('\\', "\\\\").replace('"', "\\\"")
    ))
}

/// The comment block: `lines` behind `# `.
pub fn comments(lines: &[String]) -> String {
    lines
        .iter()
        .map(|l| {
            if l.is_empty() {
                "#\n".to_string()
            } else {
                format!("# {l}\n")
            }
        })
        .collect()
}

/// The opening comment lines of a file for `target`, with its `convention`.
pub fn header(model: &ImuModel, target: &str, convention: &[&str]) -> Vec<String> {
    let mut lines = vec![
        format!("{target}: IMU noise parameters written by {TOOL}"),
        format!(
            "from the composite noise model (imu-ar noise) of six axes sampled at {} Hz.",
            model.rate_hz
        ),
        "Units: SI (gyroscope rad/s, accelerometer m/s^2).".to_string(),
    ];
    lines.extend(model.origin.iter().cloned());
    lines.extend(convention.iter().map(|l| l.to_string()));
    lines
}

/// The comment lines of a file for `target`: its header with `convention`, then the lines of
/// each sensor written.
pub fn document(
    model: &ImuModel,
    target: &str,
    convention: &[&str],
    sensors: &[&Written],
) -> Vec<String> {
    let mut lines = header(model, target, convention);
    for w in sensors {
        lines.extend(w.lines.iter().cloned());
    }
    lines
}

/// The overbound of some axes of a sensor up to a horizon: the references it starts from, and
/// the octaves it covers.
struct Bounded {
    /// The reference white noise: the model's `N`, or a floor when it has none.
    n_ref: f64,
    /// The reference random walk: the model's `K`, or a floor when it has none.
    k_ref: f64,
    /// What the floors taken for a zero `N` and a zero `K` are.
    floors: Vec<String>,
    /// The octaves `(axis index, tau, model AVAR)` in `[1 s, H]`, as given to the overbound.
    rows: Vec<(usize, f64, f64)>,
    /// The pair written.
    bound: Overbound,
}

/// The smallest overbound from `(n, k)` of the model of `axes` at every octave in `[1 s, h]`.
/// A zero `n` or `k` is replaced by its floor: for `K`, the largest upper end of the 95 %
/// intervals of the axes without a random walk, or without one [`bound::k_floor`] at the
/// longest octave in range; for `N`, [`bound::n_floor`] at the shortest (or, when the model
/// has neither, [`bound::FLOOR_RISE`] of its Allan deviation there, as white noise). A `k`
/// below such an upper end is raised to it: the file never carries less random walk than an
/// axis's record allows.
fn bounded(n: f64, k: f64, axes: &[(usize, &AxisModel)], h: f64) -> Result<Bounded, Fail> {
    // An axis without K: the upper end of its K's 95 % interval, the largest random walk its
    // data leave room for; the largest of the axes without K.
    let k_high = axes
        .iter()
        .filter(|(_, a)| a.random_walk <= 0.0)
        .filter_map(|(_, a)| a.random_walk_interval.map(|i| i.1))
        .filter(|v| v.is_finite() && *v > 0.0)
        .max_by(f64::total_cmp);
    let rows: Vec<(usize, f64, f64)> = bound::octaves(axes, h).collect();
    let first = rows.iter().map(|r| r.1).min_by(f64::total_cmp).unwrap_or(h);
    let last = rows.iter().map(|r| r.1).max_by(f64::total_cmp).unwrap_or(h);
    let rise = 100.0 * bound::FLOOR_RISE;
    let mut floors = Vec::new();
    let n_ref = if n > 0.0 {
        n
    } else if k > 0.0 {
        let floor = bound::n_floor(k, first);
        floors.push(format!(
            "The model has no white noise: N is taken as {} (never zero), the white noise that \
             raises the random-walk curve by {rise} % at tau = {} s, the shortest octave from \
             {FROM_TAU} s.",
            short(floor),
            short(first)
        ));
        floor
    } else {
        // Neither: white noise at FLOOR_RISE of the model's Allan deviation at the first
        // octave in range, or at the model's first octave.
        let (tau, avar) = rows
            .iter()
            .filter(|r| r.1 == first)
            .map(|r| (r.1, r.2))
            .max_by(|p, q| p.1.total_cmp(&q.1))
            .or_else(|| axes.first().map(|(_, a)| (a.dt, a.model_avar[0])))
            .unwrap_or((0.0, 0.0));
        let floor = bound::FLOOR_RISE * (avar * tau).sqrt();
        floors.push(format!(
            "The model has no white noise and no random walk: N is taken as {} (never zero), \
             white noise at {rise} % of the model's Allan deviation at tau = {} s.",
            short(floor),
            short(tau)
        ));
        floor
    };
    let k_ref = if let Some(high) = k_high.filter(|high| k > 0.0 && *high > k) {
        floors.push(format!(
            "An axis without a random walk leaves room for more than the largest fitted K ({}): \
             K is taken as {} (never below what an axis's record allows), the upper end of \
             that axis's 95 % interval.",
            short(k),
            short(high)
        ));
        high
    } else if k > 0.0 {
        k
    } else if let Some(high) = k_high {
        floors.push(format!(
            "The model has no random walk: K is taken as {} (never zero), the upper end of its 95 % \
             interval, the largest random walk the record leaves room for.",
            short(high)
        ));
        high
    } else {
        let floor = bound::k_floor(n_ref, last);
        floors.push(format!(
            "The model has no random walk: K is taken as {} (never zero), the random walk that \
             raises the white curve by {rise} % at tau = {} s, the longest octave up to H.",
            short(floor),
            short(last)
        ));
        floor
    };
    let pairs: Vec<(f64, f64)> = rows.iter().map(|r| (r.1, r.2)).collect();
    let bound = bound::smallest_overbound(n_ref, k_ref, &pairs).ok_or_else(|| {
        Fail(format!(
            "no white noise and random walk overbound the model (N {n_ref}, K {k_ref}): its Allan \
             deviation is zero or not finite"
        ))
    })?;
    Ok(Bounded {
        n_ref,
        k_ref,
        floors,
        rows,
        bound,
    })
}

/// The sensor's written `N_H` and `K_H` (the smallest overbound of the model of its axes from
/// 1 s to `horizon`, or without one to the model's longest octave) and their comments.
///
/// # Errors
///
/// A [`Fail`] when no overbound can be formed (a model whose Allan deviation is zero or not
/// finite).
pub fn written(model: &ImuModel, sensor: &Sensor, horizon: Option<f64>) -> Result<Written, Fail> {
    let axes: Vec<(usize, &AxisModel)> = sensor.axes.clone().map(|i| (i, &model.axes[i])).collect();
    let worst = |f: fn(&AxisModel) -> f64| {
        axes.iter()
            .max_by(|p, q| f(p.1).total_cmp(&f(q.1)))
            .map_or((0.0, 0), |(i, a)| (f(a), *i))
    };
    let (n, n_axis) = worst(|a| a.white_noise);
    let (k, k_axis) = worst(|a| a.random_walk);
    let longest = bound::longest_octave(&axes).unwrap_or(FROM_TAU);
    let h = horizon.unwrap_or(longest);
    let u = sensor.unit;
    let mut lines = vec![
        String::new(),
        format!(
            "{} per axis: continuous N ({u}/sqrt(Hz)), K ({u}/s/sqrt(Hz)), bias instability B \
             ({u}) at its tau (none of these files has a term for B), and the overbound N_H, K_H \
             of the axis alone (see below):",
            sensor.name
        ),
    ];
    let interval = |i: Option<(f64, f64)>| {
        i.map_or(String::new(), |(lo, hi)| {
            format!(" [{}, {}]", short(lo), short(hi))
        })
    };
    lines.push(
        "  (N and K with their 95 % intervals, from the Allan variances' sampling distribution)"
            .into(),
    );
    for &(i, a) in &axes {
        let alone = bounded(a.white_noise, a.random_walk, &[(i, a)], h)?.bound;
        lines.push(format!(
            "  {}: N = {}{}, K = {}{}, B = {} at tau = {} s; alone: N_H = {}, K_H = {}",
            AXIS_NAMES[i],
            short(a.white_noise),
            interval(a.white_noise_interval),
            short(a.random_walk),
            interval(a.random_walk_interval),
            short(a.bias_instability.0),
            short(a.bias_instability.1),
            short(alone.n),
            short(alone.k)
        ));
    }
    lines.push(format!(
        "One number for the three axes: from the worst (largest) fitted values, N of {} and K of \
         {}, over the model of all three axes.",
        AXIS_NAMES[n_axis], AXIS_NAMES[k_axis]
    ));
    let b = bounded(n, k, &axes, h)?;
    lines.extend(overbound_lines(n, k, &b, h, horizon.is_some()));
    lines.extend(reach_lines(b.bound.n, b.bound.k, &axes));
    Ok(Written {
        n: b.bound.n,
        k: b.bound.k,
        lines,
    })
}

/// The statement of the overbound `b` of the model up to `h`, from the fitted `n` and `k`.
fn overbound_lines(n: f64, k: f64, b: &Bounded, h: f64, asked: bool) -> Vec<String> {
    let Overbound {
        n: nh,
        k: kh,
        limits,
    } = b.bound;
    let first = b.rows.iter().map(|r| r.1).min_by(f64::total_cmp);
    let last = b.rows.iter().map(|r| r.1).max_by(f64::total_cmp);
    let which = if asked {
        "the horizon asked for"
    } else {
        "the model's longest octave"
    };
    let mut lines = vec![format!(
        "White noise and random walk: the smallest overbound of the model's Allan deviation from \
         tau = {FROM_TAU} s to H = {} s, {which} (log N_H/N + log K_H/K minimal), every axis at \
         every octave{}:",
        short(h),
        match (first, last) {
            (Some(f), Some(l)) => format!(" ({} s to {} s)", short(f), short(l)),
            _ => String::new(),
        }
    )];
    // Against the fitted value, and against the floor where the overbound started from one
    // (a zero fit, or a K raised to what an axis without one leaves room for).
    let ratio = |x: f64, of: f64, fitted: f64, name: &str| {
        if of == fitted {
            format!("{name}_H/{name} = {}", short(x / of))
        } else if fitted > 0.0 {
            format!(
                "{name}_H/floor = {}, {name}_H/{name} = {}",
                short(x / of),
                short(x / fitted)
            )
        } else {
            format!("{name}_H/floor = {}", short(x / of))
        }
    };
    lines.push(format!(
        "  N_H = {} (fitted N = {}, {}), K_H = {} (fitted K = {}, {}).",
        short(nh),
        short(n),
        ratio(nh, b.n_ref, n, "N"),
        short(kh),
        short(k),
        ratio(kh, b.k_ref, k, "K")
    ));
    let octave = |j: usize| {
        let (i, tau, _) = b.rows[j];
        format!("the model at tau = {} s ({})", short(tau), AXIS_NAMES[i])
    };
    let (n_at, k_at) = (
        if b.n_ref == n { "N" } else { "N's floor" },
        if b.k_ref == k { "K" } else { "K's floor" },
    );
    lines.push(match limits {
        _ if b.rows.is_empty() => format!(
            "  No octave of the model lies in [{FROM_TAU} s, H]: N and K written as fitted."
        ),
        [Limit::White, Limit::RandomWalk] if b.n_ref == n && b.k_ref == k => {
            "  N_H = N and K_H = K: the fitted white noise and random walk already overbound \
             the model there."
                .to_string()
        }
        [Limit::White, Limit::RandomWalk] => {
            format!("  N_H = {n_at} and K_H = {k_at}: they already overbound the model there.")
        }
        [Limit::White, Limit::Octave(j)] => format!("  N_H = {n_at}; K_H set by {}.", octave(j)),
        [Limit::RandomWalk, Limit::Octave(j)] => {
            format!("  K_H = {k_at}; N_H set by {}.", octave(j))
        }
        [Limit::Octave(p), Limit::Octave(q)] => {
            format!("  Set by {} and {}.", octave(p), octave(q))
        }
        _ => String::new(),
    });
    lines.extend(b.floors.iter().cloned());
    lines.retain(|l| !l.is_empty());
    lines
}

/// The statement of how far the curve of `(n, k)` overbounds the model of `axes`.
fn reach_lines(n: f64, k: f64, axes: &[(usize, &AxisModel)]) -> Vec<String> {
    let curve = "With N_H and K_H, sqrt(N_H^2/tau + K_H^2 tau/3)";
    let r = bound::reach(n, k, axes);
    let Some(last) = r.last else {
        return vec![format!(
            "The model has no octave at or above {FROM_TAU} s: no statement of its reach."
        )];
    };
    let mut lines = vec![match r.up_to {
        Some(t) if t >= last => format!(
            "{curve} stays at or above the model's Allan deviation of every axis at every octave \
             from {FROM_TAU} s to the last, tau = {} s.",
            short(last)
        ),
        Some(t) => format!(
            "{curve} stays at or above the model's Allan deviation of every axis at every octave \
             from {FROM_TAU} s up to tau = {} s.",
            short(t)
        ),
        None => format!(
            "{curve} is below the model's Allan deviation already at the first octave from \
             {FROM_TAU} s."
        ),
    }];
    if let Some((short_by, tau, i)) = r.shortfall {
        lines.push(format!(
            "{} it falls short by up to {:.1} % (of the Allan deviation, {} at tau = {} s); a \
             filter that must coast longer: export with a longer horizon.",
            if r.up_to.is_some() {
                "Beyond,"
            } else {
                "There"
            },
            100.0 * short_by,
            AXIS_NAMES[i],
            short(tau),
        ));
    }
    lines
}

/// The written values of both sensors, checked finite.
fn both(model: &ImuModel, horizon: Option<f64>) -> Result<[Written; 2], Fail> {
    let out = [
        written(model, &GYRO, horizon)?,
        written(model, &ACCEL, horizon)?,
    ];
    for (w, s) in out.iter().zip([&GYRO, &ACCEL]) {
        finite(&format!("{} N", s.name), w.n)?;
        finite(&format!("{} K", s.name), w.k)?;
    }
    Ok(out)
}

/// Both sensors written, and the comment lines of a file for `target` with its `convention`.
fn opened(
    model: &ImuModel,
    horizon: Option<f64>,
    target: &str,
    convention: &[&str],
) -> Result<([Written; 2], Vec<String>), Fail> {
    let [g, a] = both(model, horizon)?;
    let lines = document(model, target, convention, &[&g, &a]);
    Ok(([g, a], lines))
}

/// Kalibr's `imu.yaml`: continuous-time densities, one per sensor.
///
/// Convention (<https://github.com/ethz-asl/kalibr/wiki/IMU-Noise-Model> and
/// `aslam_offline_calibration/kalibr/python/kalibr_common/ConfigReader.py`, lines 473 and 491
/// at 1f60227442d25e36365ef5f72cd80b9666d73467): `*_noise_density` is the continuous `N`
/// (SI/sqrt(Hz)), which Kalibr discretises itself as `N / sqrt(1 / update_rate)`;
/// `*_random_walk` is the continuous `K` (SI/s/sqrt(Hz)). Read with PyYAML (YAML 1.1).
pub fn kalibr(model: &ImuModel, horizon: Option<f64>) -> Result<String, Fail> {
    let ([g, a], lines) = opened(
        model,
        horizon,
        "Kalibr imu.yaml",
        &[
            "Kalibr takes continuous-time densities and discretises them itself with update_rate",
            "(ethz-asl/kalibr ConfigReader.py: N_d = N / sqrt(1/update_rate); wiki IMU-Noise-Model).",
        ],
    )?;
    Ok(comments(&lines)
        + &kalibr_keys("", model, [&g, &a])?
        + &format!("update_rate: {}  # Hz\n", num(model.rate_hz)))
}

/// Kalibr's four densities and its topic, each line behind `indent`.
fn kalibr_keys(indent: &str, model: &ImuModel, [g, a]: [&Written; 2]) -> Result<String, Fail> {
    let topic = yaml_string("topic", model.topic.as_deref().unwrap_or("/imu0"))?;
    let keys = [
        ("accelerometer_noise_density", a.n, "m/s^2/sqrt(Hz)"),
        ("accelerometer_random_walk", a.k, "m/s^3/sqrt(Hz)"),
        ("gyroscope_noise_density", g.n, "rad/s/sqrt(Hz)"),
        ("gyroscope_random_walk", g.k, "rad/s^2/sqrt(Hz)"),
    ];
    let mut text: String = keys
        .iter()
        .map(|(key, v, unit)| format!("{indent}{key}: {}  # {unit}, continuous\n", num(*v)))
        .collect();
    text += &format!("{indent}rostopic: {topic}\n");
    Ok(text)
}

/// The rows of a 3x3 or 4x4 identity (or zero) matrix as an OpenCV YAML sequence.
fn matrix(size: usize, identity: bool) -> String {
    (0..size)
        .map(|i| {
            let row: Vec<&str> = (0..size)
                .map(|j| if identity && i == j { "1.0" } else { "0.0" })
                .collect();
            format!("    - [ {} ]\n", row.join(", "))
        })
        .collect()
}

/// OpenVINS's `kalibr_imu_chain.yaml`: Kalibr's continuous densities under `imu0`, with the
/// IMU intrinsics it expects (identity, `Tg` zero: no intrinsic error).
///
/// Convention (rpng/open_vins at 69488123ed9362dd44b6f28e7f4680abbff1442b):
/// `ov_msckf/src/core/VioManagerOptions.h` lines 159-162 read the four densities as `sigma_w`,
/// `sigma_wb`, `sigma_a`, `sigma_ab`; `ov_msckf/src/state/Propagator.cpp` lines 225-228 and
/// 463-466 discretise them (`sigma_w^2 / dt` per sample, `sigma_wb^2 dt` per step): continuous
/// `N` and `K`. The file is read with OpenCV's `FileStorage` (`%YAML:1.0`), as in its
/// `config/euroc_mav/kalibr_imu_chain.yaml`.
pub fn openvins(model: &ImuModel, horizon: Option<f64>) -> Result<String, Fail> {
    let ([g, a], lines) = opened(
        model,
        horizon,
        "OpenVINS kalibr_imu_chain.yaml",
        &[
            "OpenVINS takes Kalibr's continuous-time densities and discretises them at each IMU",
            "step (rpng/open_vins Propagator.cpp: sigma_w^2/dt, sigma_wb^2 dt).",
            "Intrinsics: identity (Tw, R_IMUtoGYRO, Ta, R_IMUtoACC) and Tg zero: none estimated.",
        ],
    )?;
    Ok(format!("%YAML:1.0\n\n{}\nimu0:\n", comments(&lines))
        + &format!("  T_i_b:\n{}", matrix(4, true))
        + &kalibr_keys("  ", model, [&g, &a])?
        + &format!(
            "  time_offset: 0.0\n  update_rate: {}\n  model: \"kalibr\"\n",
            num(model.rate_hz)
        )
        + &format!("  Tw:\n{}", matrix(3, true))
        + &format!("  R_IMUtoGYRO:\n{}", matrix(3, true))
        + &format!("  Ta:\n{}", matrix(3, true))
        + &format!("  R_IMUtoACC:\n{}", matrix(3, true))
        + &format!("  Tg:\n{}", matrix(3, false)))
}

/// VINS-Mono's IMU keys (OpenCV YAML): standard deviations per IMU sample.
///
/// Convention (HKUST-Aerial-Robotics/VINS-Mono at 90dabb5ec79946ae42fd2e1e91d4e69aabe1e25d):
/// `vins_estimator/src/parameters.cpp` lines 70-73 read `acc_n`, `acc_w`, `gyr_n`, `gyr_w`;
/// `vins_estimator/src/factor/integration_base.h` puts `ACC_N^2`, `GYR_N^2` on each of the two
/// samples of a mid-point step and `ACC_W^2`, `GYR_W^2` on the bias (lines 22-27), with
/// `V(3,3) = V(3,9) = 0.5 dt` and `V(9,12) = V(12,15) = dt` (lines 113-120), `P = F P F^T + V
/// noise V^T` (line 125), `dt` the IMU's sample interval. Per step the angle error grows by
/// `0.5 gyr_n^2 dt^2` and the bias by `gyr_w^2 dt^2`; matching the continuous `N^2 dt` and
/// `K^2 dt`: `gyr_n = N sqrt(2 / dt)`, `gyr_w = K / sqrt(dt)` (the same for the accelerometer).
pub fn vins(model: &ImuModel, horizon: Option<f64>) -> Result<String, Fail> {
    let [g, a] = both(model, horizon)?;
    let rate = model.rate_hz;
    let white = |n: f64| finite("VINS white noise", n * (2.0 * rate).sqrt());
    let walk = |k: f64| finite("VINS random walk", k * rate.sqrt());
    let lines = document(
        model,
        "VINS-Mono IMU parameters",
        &[
            "VINS-Mono uses them per IMU sample (HKUST-Aerial-Robotics/VINS-Mono integration_base.h:",
            "mid-point step, Var(angle step) = 0.5 gyr_n^2 dt^2, Var(bias step) = gyr_w^2 dt^2):",
            &format!(
                "discrete at the IMU's rate {rate} Hz: *_n = N sqrt(2 rate), *_w = K sqrt(rate)."
            ),
            "Give the estimator IMU data at this rate; at another rate these values change.",
        ],
        &[&g, &a],
    );
    Ok(format!("%YAML:1.0\n\n{}\n", comments(&lines))
        + &format!(
            "acc_n: {}  # m/s^2: N sqrt(2 rate), on each of a mid-point step's two samples\n\
             gyr_n: {}  # rad/s: N sqrt(2 rate), on each of a mid-point step's two samples\n\
             acc_w: {}  # m/s^3: K sqrt(rate), the bias stepping by acc_w dt a sample\n\
             gyr_w: {}  # rad/s^2: K sqrt(rate), the bias stepping by gyr_w dt a sample\n",
            num(white(a.n)?),
            num(white(g.n)?),
            num(walk(a.k)?),
            num(walk(g.k)?)
        ))
}

/// ORB-SLAM3's IMU keys (OpenCV YAML): continuous densities and the IMU rate.
///
/// Convention (UZ-SLAMLab/ORB_SLAM3, `src/Tracking.cc`, `Tracking::newParameterLoader`):
/// `sf = sqrt(mImuFreq); IMU::Calib(Tbc, Ng*sf, Na*sf, Ngw/sf, Naw/sf)`, and
/// `src/ImuTypes.cc`, `Preintegrated::IntegrateNewMeasurement`: `C = A C A^T + B Nga B^T` (`B`
/// with `dt`), `C(9.., 9..) += NgaWalk` per sample. So `IMU.NoiseGyro`/`IMU.NoiseAcc` are the
/// continuous `N`, `IMU.GyroWalk`/`IMU.AccWalk` the continuous `K`, discretised with
/// `IMU.Frequency`.
pub fn orbslam3(model: &ImuModel, horizon: Option<f64>) -> Result<String, Fail> {
    // Its configuration reader without `File.version: "1.0"` takes IMU.Frequency as an
    // integer only (Tracking.cc: `node.isInt()`); the rounded rate discretises the densities.
    let frequency = model.rate_hz.round().max(1.0);
    let ([g, a], mut lines) = opened(
        model,
        horizon,
        "ORB-SLAM3 IMU parameters",
        &[
            "ORB-SLAM3 takes continuous-time densities and discretises them with IMU.Frequency",
            "(UZ-SLAMLab/ORB_SLAM3 Tracking.cc: Ng*sqrt(f), Ngw/sqrt(f); ImuTypes.cc preintegration).",
            "IMU.Frequency is an integer: ORB-SLAM3 reads it as one.",
        ],
    )?;
    if frequency != model.rate_hz {
        lines.push(format!(
            "The record's rate {} Hz is written rounded to {frequency:.0} Hz.",
            num(model.rate_hz)
        ));
    }
    Ok(format!("%YAML:1.0\n\n{}\n", comments(&lines))
        + &format!(
            "IMU.NoiseGyro: {}  # rad/s/sqrt(Hz), continuous\nIMU.NoiseAcc: {}  # \
             m/s^2/sqrt(Hz), continuous\nIMU.GyroWalk: {}  # rad/s^2/sqrt(Hz), continuous\n\
             IMU.AccWalk: {}  # m/s^3/sqrt(Hz), continuous\nIMU.Frequency: {}  # Hz\n",
            num(g.n),
            num(a.n),
            num(g.k),
            num(a.k),
            frequency as u64
        ))
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A bound from `(n_ref, k_ref)` set by both references, over one octave.
    fn bounded_at(n_ref: f64, k_ref: f64) -> Bounded {
        Bounded {
            n_ref,
            k_ref,
            floors: Vec::new(),
            rows: vec![(0, 1.0, 1e-12)],
            bound: Overbound {
                n: n_ref,
                k: k_ref,
                limits: [Limit::White, Limit::RandomWalk],
            },
        }
    }

    #[test]
    fn a_random_walk_raised_to_an_axis_floor_is_named_as_such() {
        // A fitted K of 2.0941e-5 raised to 9.0681e-5, the upper end of another axis's
        // interval: K_H is the floor, 4.33 times the fitted K.
        let lines = overbound_lines(1e-3, 2.0941e-5, &bounded_at(1e-3, 9.0681e-5), 100.0, false);
        let text = lines.join("\n");
        assert!(
            text.contains("K_H/floor = 1.0000e0, K_H/K = 4.3303e0"),
            "{text}"
        );
        assert!(
            text.contains("  N_H = N and K_H = K's floor: they already"),
            "{text}"
        );
        assert!(!text.contains("K_H = K:"), "{text}");
        // Fitted references: as they were.
        let text = overbound_lines(1e-3, 2e-5, &bounded_at(1e-3, 2e-5), 100.0, false).join("\n");
        assert!(
            text.contains(
                "N_H/N = 1.0000e0), K_H = 2.0000e-5 (fitted K = 2.0000e-5, K_H/K = 1.0000e0)"
            ),
            "{text}"
        );
        assert!(text.contains("N_H = N and K_H = K: the fitted"), "{text}");
        // No fitted K: against the floor alone.
        let text = overbound_lines(1e-3, 0.0, &bounded_at(1e-3, 5e-5), 100.0, false).join("\n");
        assert!(
            text.contains("(fitted K = 0.0000e0, K_H/floor = 1.0000e0)"),
            "{text}"
        );
    }
}
