//! The decomposition plot of `imu-ar noise`, and the text that names where the check fails.

use std::path::Path;

use imu_ar::noise::{Check, NoiseModel, Octaves, component};
use plotters::coord::Shift;
use plotters::prelude::*;

use crate::chart::{builder, font, legend};
use crate::error::Fail;
use crate::kalman::AllanRow;

/// A path the plot can be written to: a `.png` file in a folder that exists.
pub(super) fn check_path(path: &Path) -> Result<(), Fail> {
    let png = path
        .extension()
        .is_some_and(|e| e.eq_ignore_ascii_case("png"));
    let folder = match path.parent() {
        Some(p) if !p.as_os_str().is_empty() => p,
        _ => Path::new("."),
    };
    if path.is_dir() {
        return Err(Fail(format!(
            "--plot {}: is a directory; name a .png file",
            path.display()
        )));
    }
    if !png {
        return Err(Fail(format!(
            "--plot {}: must name a .png file",
            path.display()
        )));
    }
    if !folder.is_dir() {
        return Err(Fail(format!(
            "--plot {}: the folder {} does not exist",
            path.display(),
            folder.display()
        )));
    }
    Ok(())
}

/// One line per run of octaves where the check fails: the `tau` range, which side the data
/// are on, and for an excess the frequency of a sinusoid whose Allan deviation peaks at the
/// worst `tau` (`f = 0.371 / tau`).
pub(super) fn failures(rows: &[AllanRow]) -> Vec<String> {
    let mut lines = Vec::new();
    let mut i = 0;
    while i < rows.len() {
        if rows[i].agrees {
            i += 1;
            continue;
        }
        let start = i;
        while i < rows.len() && !rows[i].agrees {
            i += 1;
        }
        let run = &rows[start..i];
        let worst = run
            .iter()
            .max_by(|p, q| (p.data_over_model.ln().abs()).total_cmp(&q.data_over_model.ln().abs()))
            .expect("a run has a row");
        let (from, to) = (run[0].tau_s, run[run.len() - 1].tau_s);
        let cause = if worst.data_over_model > 1.0 {
            format!(
                "the data are above the model, by x{:.2} at tau {} s: excess power there, \
                 such as a periodic disturbance near {:.3} Hz (--oscillators models lines \
                 from 0.1 Hz) or a drift the components do not follow",
                worst.data_over_model,
                worst.tau_s,
                0.371 / worst.tau_s
            )
        } else {
            format!(
                "the data are below the model, by x{:.2} at tau {} s: the model is \
                 pessimistic there",
                worst.data_over_model, worst.tau_s
            )
        };
        lines.push(format!("check fails at tau {from} to {to} s: {cause}"));
    }
    lines
}

/// A drawing area of the PNG plots.
pub(crate) type Area<'a> = DrawingArea<BitMapBackend<'a>, Shift>;

/// A PNG file of `size` pixels with the panels `paint` side by side, each with its caption
/// (empty for the default one).
pub(crate) fn png(
    path: &Path,
    size: (u32, u32),
    paint: &[(&super::Paint, String)],
) -> Result<(), String> {
    font().map_err(|Fail(e)| e)?;
    let root = crate::chart::bitmap(path, size)
        .map_err(|Fail(e)| e)?
        .into_drawing_area();
    let panels = root.split_evenly((1, paint.len().max(1)));
    for (area, (p, caption)) in panels.iter().zip(paint) {
        p(area, caption)?;
    }
    root.present().map_err(|e| e.to_string())
}

/// The data's Allan deviation with one standard error either side, the model's with its 95 % band
/// (when `band` holds one interval per octave), and each component's, on log-log axes, on `root`;
/// octaves where the check fails are crossed.
pub(crate) fn decomposition<const P: usize, const G: usize, const L: usize>(
    root: &Area,
    model: &NoiseModel<P, G>,
    octaves: &Octaves<L>,
    check: &Check<L>,
    band: &[(f64, f64)],
    caption: &str,
) -> Result<(), String> {
    let draw_err = |e: DrawingAreaErrorKind<_>| e.to_string();
    let rows = check.rows();
    let tau: Vec<f64> = rows.iter().map(|r| r.tau).collect();
    let components = components(model, octaves).map_err(|Fail(e)| e)?;
    let lowest_data = rows
        .iter()
        .map(|r| r.data_adev)
        .fold(f64::INFINITY, f64::min);
    let floor = lowest_data / 30.0;
    let top = rows
        .iter()
        .map(|r| r.data_adev * (1.0 + r.standard_error))
        .chain(rows.iter().map(|r| r.model_adev))
        .chain(components.iter().flat_map(|c| c.1.iter().copied()))
        .filter(|v| v.is_finite())
        .fold(0.0f64, f64::max);
    root.fill(&WHITE).map_err(draw_err)?;
    let (t_lo, t_hi) = (tau[0], tau[tau.len() - 1]);
    let mut chart = builder(root, caption.to_string(), 80)
        .build_cartesian_2d(
            (t_lo * 0.8..t_hi * 1.25).log_scale(),
            (floor..top * 1.5).log_scale(),
        )
        .map_err(draw_err)?;
    chart
        .configure_mesh()
        .x_desc("averaging time tau (s)")
        .y_desc("Allan deviation")
        .draw()
        .map_err(draw_err)?;
    for (k, (label, curve)) in components.iter().enumerate() {
        let colour = Palette99::pick(k + 2).mix(0.9);
        let points = tau.iter().zip(curve).filter(|p| *p.1 >= floor);
        chart
            .draw_series(LineSeries::new(
                points.map(|(t, v)| (*t, *v)),
                colour.stroke_width(1),
            ))
            .map_err(draw_err)?
            .label(label.as_str())
            .legend(move |(x, y)| PathElement::new([(x, y), (x + 20, y)], colour.stroke_width(1)));
    }
    // The model's 95 % band (its parameters' intervals), under the model's line.
    if band.len() == rows.len() && band.iter().all(|(lo, hi)| lo.is_finite() && hi.is_finite()) {
        let shade = RED.mix(0.15);
        let outline: Vec<(f64, f64)> = tau
            .iter()
            .zip(band)
            .map(|(t, (lo, _))| (*t, lo.max(floor)))
            .chain(
                tau.iter()
                    .zip(band)
                    .rev()
                    .map(|(t, (_, hi))| (*t, hi.max(floor))),
            )
            .collect();
        chart
            .draw_series(std::iter::once(Polygon::new(outline, shade.filled())))
            .map_err(draw_err)?
            .label("model, 95 % band")
            .legend(move |(x, y)| Rectangle::new([(x, y - 4), (x + 20, y + 4)], shade.filled()));
    }
    let model_curve = rows.iter().map(|r| (r.tau, r.model_adev));
    chart
        .draw_series(LineSeries::new(model_curve, RED.stroke_width(3)))
        .map_err(draw_err)?
        .label("model")
        .legend(|(x, y)| PathElement::new([(x, y), (x + 20, y)], RED.stroke_width(3)));
    chart
        .draw_series(rows.iter().map(|r| {
            let se = r.standard_error;
            let lo = (r.data_adev * (1.0 - se)).max(floor);
            ErrorBar::new_vertical(
                r.tau,
                lo,
                r.data_adev,
                r.data_adev * (1.0 + se),
                BLUE.stroke_width(2),
                8,
            )
        }))
        .map_err(draw_err)?
        .label("data, +- 1 standard error")
        .legend(|(x, y)| Circle::new((x + 10, y), 3, BLUE.filled()));
    if !check.holds() {
        chart
            .draw_series(
                rows.iter()
                    .filter(|r| !r.agrees)
                    .map(|r| Cross::new((r.tau, r.data_adev), 9, BLACK.stroke_width(2))),
            )
            .map_err(draw_err)?
            .label("check fails")
            .legend(|(x, y)| Cross::new((x + 10, y), 5, BLACK.stroke_width(2)));
    }
    legend(&mut chart, SeriesLabelPosition::LowerLeft).map_err(|Fail(e)| e)
}

/// Each non-zero component's Allan deviation at the octaves, with its label.
fn components<const P: usize, const G: usize, const L: usize>(
    model: &NoiseModel<P, G>,
    octaves: &Octaves<L>,
) -> Result<Vec<(String, Vec<f64>)>, Fail> {
    let (dt, len) = (octaves.dt(), octaves.avar().len());
    let curve = |scale: f64, unit: &dyn Fn(u64) -> f64| -> Vec<f64> {
        (0..len).map(|j| scale * unit(1u64 << j).sqrt()).collect()
    };
    let mut out = Vec::new();
    let g = |v: f64| format!("{v:.3e}");
    if model.quantization() > 0.0 {
        let label = format!("quantisation Q = {}", g(model.quantization()));
        out.push((
            label,
            curve(model.quantization(), &|m| component::quantization(dt, m)),
        ));
    }
    // With an AR part, the model's N is the white term and the AR part's white equivalent
    // together (`NoiseModel::white_noise`, the caption's N): each is labelled as what it is.
    let total = model.white_noise();
    let ar_white = (total * total - model.white_term() * model.white_term())
        .max(0.0)
        .sqrt();
    if model.white_term() > 0.0 {
        let label = if model.ar().is_some() {
            format!("white beside the AR part N_w = {}", g(model.white_term()))
        } else {
            format!("white noise N = {}", g(model.white_term()))
        };
        out.push((
            label,
            curve(model.white_term(), &|m| component::white(dt, m)),
        ));
    }
    if let Some(ar) = model.ar() {
        let mut avar = vec![0.0; len];
        component::ar_octaves(ar, &mut avar).map_err(|e| Fail(format!("AR part: {e}")))?;
        out.push((
            format!("AR({P}) part, white equivalent N_ar = {}", g(ar_white)),
            avar.iter().map(|v| v.sqrt()).collect(),
        ));
    }
    for t in model.gauss_markov() {
        let label = format!(
            "Gauss-Markov sigma = {}, T = {} s",
            g(t.sigma),
            g(t.correlation_time)
        );
        let c = t.correlation_time;
        out.push((
            label,
            curve(t.sigma, &|m| component::gauss_markov(dt, c, m)),
        ));
    }
    for o in model.oscillators() {
        let label = format!(
            "oscillator sigma = {}, f = {:.3} Hz",
            g(o.sigma),
            o.frequency
        );
        let unit = (0..len)
            .map(|j| {
                component::oscillator(dt, o.frequency, o.decay_time, j).map(|v| o.sigma * v.sqrt())
            })
            .collect::<Result<Vec<f64>, _>>()
            .map_err(|e| Fail(format!("oscillator: {e}")))?;
        out.push((label, unit));
    }
    if model.random_walk() > 0.0 {
        let label = format!("random walk K = {}", g(model.random_walk()));
        out.push((
            label,
            curve(model.random_walk(), &|m| component::random_walk(dt, m)),
        ));
    }
    if model.ramp() > 0.0 {
        let label = format!("rate ramp R = {}", g(model.ramp()));
        out.push((label, curve(model.ramp(), &|m| component::ramp(dt, m))));
    }
    Ok(out)
}
