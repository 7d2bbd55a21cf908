//! The PNG plots of `imu-ar report`: four, and prior.png with `--prior-a`.

use std::path::{Path, PathBuf};

use imu_ar::ArModel;
use imu_ar::allan::overlapping_avar;
use plotters::chart::SeriesAnno;
use plotters::coord::types::RangedCoordf64;
use plotters::element::DashedPathElement;
use plotters::prelude::*;
use rustfft::{FftPlanner, num_complex::Complex};

use super::{FromPrior, Report, Track};
use crate::chart::{SIZE, builder, draw_err, legend};
use crate::error::Fail;

fn caption(r: &Report, what: &str) -> String {
    format!(
        "{what} (n = {}, {} Hz, lambda = {})",
        r.x.len(),
        r.rate,
        r.lambda
    )
}

/// A linear axis label: plain decimals from 0.01 up, scientific below.
fn tick(v: f64) -> String {
    if v == 0.0 || (1e-2..1e4).contains(&v.abs()) {
        format!("{v:.3}")
    } else {
        format!("{v:.2e}")
    }
}

/// `v` to 4 significant digits: decimals from 0.01 up, scientific below.
fn significant(v: f64) -> String {
    if (1e-2..1e4).contains(&v.abs()) {
        let decimals = (3 - v.abs().log10().floor() as i32).max(0) as usize;
        format!("{v:.decimals$}")
    } else {
        format!("{v:.3e}")
    }
}

/// `v` to 4 significant digits without trailing zeros: 300, 0.822.
fn short(v: f64) -> String {
    let s = significant(v);
    if s.contains('.') && !s.contains('e') {
        s.trim_end_matches('0').trim_end_matches('.').to_string()
    } else {
        s
    }
}

/// Range of finite values, widened a little.
fn span(values: impl Iterator<Item = f64>) -> (f64, f64) {
    let (lo, hi) = values
        .filter(|v| v.is_finite())
        .fold((f64::INFINITY, f64::NEG_INFINITY), |(l, h), v| {
            (l.min(v), h.max(v))
        });
    if lo > hi {
        return (0.0, 1.0);
    }
    let pad = 0.05 * (hi - lo).max(1e-12 * hi.abs().max(1.0));
    (lo - pad, hi + pad)
}

/// The coefficients of a track after its first tenth (to `t_end`), the transient, which is left
/// out of the y range.
fn settled<const P: usize>(s: &Track<P>, t_end: f64) -> impl Iterator<Item = f64> + '_ {
    s.iter()
        .filter(move |c| c.0 > 0.1 * t_end)
        .flat_map(|c| c.1)
}

/// The time axes of the coefficient plots.
type TimeChart<'a, DB> = ChartContext<'a, DB, Cartesian2d<RangedCoordf64, RangedCoordf64>>;

/// A dashed horizontal line at `a` from time 0 to `t_end`, `dash` its dashes and gaps.
fn level<'a, 'b, DB: DrawingBackend + 'a>(
    chart: &'b mut TimeChart<'a, DB>,
    a: f64,
    t_end: f64,
    (size, spacing): (u32, u32),
    style: ShapeStyle,
) -> Result<&'b mut SeriesAnno<'a, DB>, Fail> {
    chart
        .draw_series(DashedLineSeries::new(
            [(0.0, a), (t_end, a)],
            size,
            spacing,
            style,
        ))
        .map_err(draw_err)
}

pub(super) fn coefficients_png<const P: usize>(
    r: &Report,
    dir: &Path,
    coef: &(Track<P>, Track<P>),
    batch: &ArModel<f64, P>,
) -> Result<PathBuf, Fail> {
    let path = dir.join("coefficients.png");
    let root = crate::chart::bitmap(&path, SIZE)?.into_drawing_area();
    root.fill(&WHITE).map_err(draw_err)?;
    let t_end = coef.0.last().map_or(1.0, |c| c.0);
    let (lo, hi) = span(
        settled(&coef.0, t_end)
            .chain(settled(&coef.1, t_end))
            .chain(batch.a().iter().copied()),
    );
    let mut chart = builder(
        &root,
        caption(r, "AR coefficients: RLS and lattice against the batch fit"),
        70,
    )
    .build_cartesian_2d(0.0..t_end, lo..hi)
    .map_err(draw_err)?;
    chart
        .configure_mesh()
        .light_line_style(WHITE)
        .x_desc("time (s)")
        .x_label_formatter(&|t| format!("{t:.0}"))
        .y_desc("coefficient a_k (1)")
        .y_label_formatter(&|v| tick(*v))
        .draw()
        .map_err(draw_err)?;
    for k in 0..P {
        let color = Palette99::pick(k).to_rgba();
        chart
            .draw_series(LineSeries::new(
                coef.0.iter().map(|c| (c.0, c.1[k])),
                color.stroke_width(1),
            ))
            .map_err(draw_err)?
            .label(format!("a_{} RLS", k + 1))
            .legend(move |(x, y)| PathElement::new([(x, y), (x + 20, y)], color.stroke_width(1)));
        chart
            .draw_series(
                coef.1
                    .iter()
                    .step_by(4)
                    .map(|c| Circle::new((c.0, c.1[k]), 2, color.filled())),
            )
            .map_err(draw_err)?
            .label(format!("a_{} lattice", k + 1))
            .legend(move |(x, y)| Circle::new((x + 10, y), 3, color.filled()));
        let a = batch.a()[k];
        level(&mut chart, a, t_end, (8, 5), color.stroke_width(2))?
            .label(format!("a_{} batch LS, first part ({a:.3})", k + 1))
            .legend(move |(x, y)| PathElement::new([(x, y), (x + 20, y)], color.stroke_width(2)));
    }
    legend(&mut chart, SeriesLabelPosition::UpperRight)?;
    root.present().map_err(draw_err)?;
    Ok(path.clone())
}

pub(super) fn error_png(
    r: &Report,
    dir: &Path,
    se: &[Vec<(f64, f64)>; 3],
    mse: &[f64; 3],
    t_train: f64,
) -> Result<PathBuf, Fail> {
    let path = dir.join("prediction_error.png");
    let root = crate::chart::bitmap(&path, SIZE)?.into_drawing_area();
    root.fill(&WHITE).map_err(draw_err)?;
    let t_end = se[0].last().map_or(1.0, |p| p.0);
    // The first tenth of the record is the recursive estimators' start: leave it out of the range.
    let settled = se.iter().flatten().filter(|p| p.0 > 0.1 * t_end);
    let hi = settled
        .map(|p| p.1)
        .filter(|v| v.is_finite())
        .fold(0.0f64, f64::max);
    let hi = if hi > 0.0 { hi * 1.1 } else { 1.0 };
    let mut chart = builder(
        &root,
        caption(r, "One-step prediction error, block means"),
        80,
    )
    .build_cartesian_2d(0.0..t_end, 0.0..hi)
    .map_err(draw_err)?;
    chart
        .configure_mesh()
        .x_desc(format!(
            "time (s); batch LS fitted before {t_train:.0} s, MSE over the rest"
        ))
        .light_line_style(WHITE)
        .x_label_formatter(&|t| format!("{t:.0}"))
        .y_desc(format!("mean squared error ({})^2", r.unit))
        .y_label_formatter(&|v| tick(*v))
        .draw()
        .map_err(draw_err)?;
    let names = ["batch LS", "RLS", "lattice"];
    let colors = [BLACK, BLUE, RED];
    for (((series, name), color), mse) in se.iter().zip(names).zip(colors).zip(mse) {
        chart
            .draw_series(LineSeries::new(
                series.iter().copied().map(|(t, v)| (t, v.min(hi))),
                color.stroke_width(1),
            ))
            .map_err(draw_err)?
            .label(format!("{name}: MSE {}", significant(*mse)))
            .legend(move |(x, y)| PathElement::new([(x, y), (x + 20, y)], color.stroke_width(2)));
    }
    chart
        .draw_series(DashedLineSeries::new(
            [(t_train, 0.0), (t_train, hi)],
            6,
            4,
            BLACK.stroke_width(2),
        ))
        .map_err(draw_err)?;
    legend(&mut chart, SeriesLabelPosition::UpperRight)?;
    root.present().map_err(draw_err)?;
    Ok(path.clone())
}

/// One-sided Welch PSD (Hann window, half-overlapping segments), in units^2/Hz.
fn welch(x: &[f64], rate: f64) -> Vec<(f64, f64)> {
    let len = (x.len() / 8).clamp(16, 4096).next_power_of_two() / 2;
    let window: Vec<f64> = (0..len)
        .map(|i| 0.5 - 0.5 * (2.0 * std::f64::consts::PI * i as f64 / len as f64).cos())
        .collect();
    let norm: f64 = window.iter().map(|w| w * w).sum::<f64>() * rate;
    let mean = x.iter().sum::<f64>() / x.len() as f64;
    let fft = FftPlanner::new().plan_fft_forward(len);
    let mut sum = vec![0.0; len / 2 + 1];
    let mut count = 0;
    for start in (0..=x.len().saturating_sub(len)).step_by(len / 2) {
        let mut buf: Vec<Complex<f64>> = x[start..start + len]
            .iter()
            .zip(&window)
            .map(|(v, w)| Complex::new((v - mean) * w, 0.0))
            .collect();
        fft.process(&mut buf);
        for (s, c) in sum.iter_mut().zip(&buf) {
            *s += c.norm_sqr();
        }
        count += 1;
    }
    sum.iter()
        .enumerate()
        .skip(1)
        .map(|(k, s)| {
            let one_sided = if 2 * k == len { 1.0 } else { 2.0 };
            (
                k as f64 * rate / len as f64,
                one_sided * s / (norm * count as f64),
            )
        })
        .collect()
}

pub(super) fn psd_png<const P: usize>(
    r: &Report,
    dir: &Path,
    model: &ArModel<f64, P>,
) -> Result<PathBuf, Fail> {
    let path = dir.join("psd.png");
    let data = welch(r.x, r.rate);
    let psd = |f: f64| {
        model
            .psd(f)
            .map_err(|e| Fail(format!("model spectrum: {e}")))
    };
    let fitted = data
        .iter()
        .map(|&(f, _)| Ok((f, 2.0 * psd(f)?)))
        .collect::<Result<Vec<(f64, f64)>, Fail>>()?;
    let root = crate::chart::bitmap(&path, SIZE)?.into_drawing_area();
    root.fill(&WHITE).map_err(draw_err)?;
    let (f_lo, f_hi) = (data[0].0, data[data.len() - 1].0);
    let values = data.iter().chain(&fitted).map(|p| p.1).filter(|v| *v > 0.0);
    let (lo, hi) = values.fold((f64::INFINITY, 0.0f64), |(l, h), v| (l.min(v), h.max(v)));
    let mut chart = builder(
        &root,
        caption(
            r,
            "PSD: Welch periodogram of the data and the fitted AR model",
        ),
        80,
    )
    .build_cartesian_2d((f_lo..f_hi).log_scale(), (lo * 0.8..hi * 1.25).log_scale())
    .map_err(draw_err)?;
    chart
        .configure_mesh()
        .x_desc("frequency (Hz)")
        .y_desc(format!("one-sided PSD ({})^2/Hz", r.unit))
        .draw()
        .map_err(draw_err)?;
    chart
        .draw_series(LineSeries::new(data, BLUE.mix(0.6).stroke_width(1)))
        .map_err(draw_err)?
        .label("data (Welch, Hann)")
        .legend(|(x, y)| PathElement::new([(x, y), (x + 20, y)], BLUE.stroke_width(2)));
    chart
        .draw_series(LineSeries::new(fitted, RED.stroke_width(2)))
        .map_err(draw_err)?
        .label(format!("AR({P}) batch LS fit"))
        .legend(|(x, y)| PathElement::new([(x, y), (x + 20, y)], RED.stroke_width(2)));
    legend(&mut chart, SeriesLabelPosition::UpperRight)?;
    root.present().map_err(draw_err)?;
    Ok(path.clone())
}

pub(super) fn adev_png<const P: usize>(
    r: &Report,
    dir: &Path,
    model: &ArModel<f64, P>,
) -> Result<PathBuf, Fail> {
    let path = dir.join("adev.png");
    let dt = 1.0 / r.rate;
    let ms: Vec<usize> = (0..)
        .map(|k| 1usize << k)
        .take_while(|m| 2 * m <= r.x.len())
        .collect();
    let data: Vec<(f64, f64)> = ms
        .iter()
        .filter_map(|&m| Some((m as f64 * dt, overlapping_avar(r.x, m).ok()?.sqrt())))
        .collect();
    let fitted: Vec<(f64, f64)> = ms
        .iter()
        .filter_map(|&m| {
            Some((
                m as f64 * dt,
                model.allan_variance(u32::try_from(m).ok()?).ok()?.sqrt(),
            ))
        })
        .collect();
    let reference = r.reference.clone().unwrap_or_default();
    let all = data.iter().chain(&fitted).chain(&reference);
    let (t_lo, t_hi) = all.clone().fold((f64::INFINITY, 0.0f64), |(l, h), p| {
        (l.min(p.0), h.max(p.0))
    });
    let (lo, hi) = all
        .map(|p| p.1)
        .filter(|v| *v > 0.0)
        .fold((f64::INFINITY, 0.0f64), |(l, h), v| (l.min(v), h.max(v)));
    let root = crate::chart::bitmap(&path, SIZE)?.into_drawing_area();
    root.fill(&WHITE).map_err(draw_err)?;
    let mut chart = builder(
        &root,
        caption(r, "Allan deviation: data and fitted AR model"),
        80,
    )
    .build_cartesian_2d(
        (t_lo * 0.8..t_hi * 1.25).log_scale(),
        (lo * 0.8..hi * 1.25).log_scale(),
    )
    .map_err(draw_err)?;
    chart
        .configure_mesh()
        .x_desc("averaging time tau (s)")
        .y_desc(format!("Allan deviation ({})", r.unit))
        .draw()
        .map_err(draw_err)?;
    chart
        .draw_series(LineSeries::new(data.clone(), BLUE.stroke_width(2)))
        .map_err(draw_err)?
        .label("data (overlapping)")
        .legend(|(x, y)| PathElement::new([(x, y), (x + 20, y)], BLUE.stroke_width(2)));
    chart
        .draw_series(data.iter().map(|&p| Circle::new(p, 3, BLUE.filled())))
        .map_err(draw_err)?;
    chart
        .draw_series(LineSeries::new(fitted, RED.stroke_width(2)))
        .map_err(draw_err)?
        .label(format!("AR({P}) batch LS fit"))
        .legend(|(x, y)| PathElement::new([(x, y), (x + 20, y)], RED.stroke_width(2)));
    if !reference.is_empty() {
        chart
            .draw_series(
                reference
                    .iter()
                    .map(|&p| Cross::new(p, 5, BLACK.stroke_width(2))),
            )
            .map_err(draw_err)?
            .label("published table")
            .legend(|(x, y)| Cross::new((x + 10, y), 5, BLACK.stroke_width(2)));
    }
    legend(&mut chart, SeriesLabelPosition::LowerLeft)?;
    root.present().map_err(draw_err)?;
    Ok(path.clone())
}

/// Decimals of the labels of an axis spanning `span`: about two significant digits.
fn decimals(span: f64) -> usize {
    (1.0 - span.abs().max(1e-6).log10().floor()).clamp(0.0, 6.0) as usize
}

/// One panel of prior.png: each `a_k` of the plain lattice and of the lattice from the prior
/// over time, and, if given, the prior's value; `lo..hi` is the y range.
fn prior_panel<const P: usize, DB: DrawingBackend>(
    area: &DrawingArea<DB, plotters::coord::Shift>,
    title: String,
    (plain, prior): (&Track<P>, &Track<P>),
    a0: Option<&[f64; P]>,
    (lo, hi): (f64, f64),
) -> Result<(), Fail> {
    let t_end = plain.last().map_or(1.0, |c| c.0);
    // Room on the right for the last time label.
    let mut chart = builder(area, title, 70)
        .margin_right(30)
        .build_cartesian_2d(0.0..t_end, lo..hi)
        .map_err(draw_err)?;
    let d = decimals(t_end);
    // A tick at 0 computed as 1e-16 is 0.
    let zero = 1e-9 * (hi - lo);
    chart
        .configure_mesh()
        .light_line_style(WHITE)
        .x_labels(5)
        .x_desc("time (s)")
        .x_label_formatter(&|t| format!("{t:.d$}"))
        .y_desc("coefficient a_k (1)")
        .y_label_formatter(&|v| tick(if v.abs() < zero { 0.0 } else { *v }))
        .draw()
        .map_err(draw_err)?;
    let finite = |s: &Track<P>, k: usize| {
        s.iter()
            .map(move |c| (c.0, c.1[k]))
            .filter(|p| p.1.is_finite())
            .collect::<Vec<_>>()
    };
    for k in 0..P {
        let color = Palette99::pick(k).to_rgba();
        // The lattice from the prior as a band of opaque light dots under the plain one's
        // line (a wide line would spike at the sharp turns of the start).
        let (r, g, b) = color.rgb();
        let light = |c: u8| 255 - ((255 - u16::from(c)) * 2 / 5) as u8;
        let band = RGBColor(light(r), light(g), light(b)).filled();
        chart
            .draw_series(
                finite(prior, k)
                    .into_iter()
                    .map(|p| Circle::new(p, 2, band)),
            )
            .map_err(draw_err)?
            .label(format!("a_{} from the prior", k + 1))
            .legend(move |(x, y)| Rectangle::new([(x, y - 2), (x + 20, y + 2)], band));
        chart
            .draw_series(LineSeries::new(finite(plain, k), color.stroke_width(1)))
            .map_err(draw_err)?
            .label(format!("a_{} plain start", k + 1))
            .legend(move |(x, y)| PathElement::new([(x, y), (x + 20, y)], color.stroke_width(1)));
        if let Some(a0) = a0 {
            let a = a0[k];
            level(&mut chart, a, t_end, (6, 4), color.stroke_width(1))?
                .label(format!("a_{} prior ({a})", k + 1))
                .legend(move |(x, y)| {
                    DashedPathElement::new([(x, y), (x + 20, y)], 6, 4, color.stroke_width(1))
                });
        }
    }
    legend(&mut chart, SeriesLabelPosition::MiddleRight)
}

/// prior.png: the lattice from the prior against the plain lattice, over the first [`HEAD`]
/// samples one by one (left, with the prior) and over the whole record (right).
///
/// [`HEAD`]: super::HEAD
pub(super) fn prior_png<const P: usize>(
    r: &Report,
    dir: &Path,
    prior: &FromPrior<P>,
    plain: &Track<P>,
) -> Result<PathBuf, Fail> {
    let path = dir.join("prior.png");
    let root = crate::chart::bitmap(&path, SIZE)?.into_drawing_area();
    root.fill(&WHITE).map_err(draw_err)?;
    // A long prior is cut after four coefficients.
    let mut a0: Vec<String> = prior.a0.iter().take(4).map(|v| v.to_string()).collect();
    if P > 4 {
        a0.push("...".into());
    }
    let root = root
        .titled(
            &format!(
                "Lattice from the prior a0 = ({}) against the plain start",
                a0.join(", ")
            ),
            ("sans-serif", 20),
        )
        .map_err(draw_err)?
        .titled(
            &format!(
                "n = {}, {} Hz, lambda = {}; the prior's weight {}, the plain start's delta {}",
                r.x.len(),
                r.rate,
                r.lambda,
                short(prior.weight),
                short(r.delta)
            ),
            ("sans-serif", 15),
        )
        .map_err(draw_err)?;
    let (left, right) = root.split_horizontally(SIZE.0 / 2);
    let head = &prior.head;
    let range = span(
        head.0
            .iter()
            .chain(&head.1)
            .flat_map(|c| c.1)
            .chain(prior.a0),
    );
    let title = format!("the first {} samples", head.1.len() - 1);
    prior_panel(&left, title, (&head.0, &head.1), Some(&prior.a0), range)?;
    let t_end = plain.last().map_or(1.0, |c| c.0);
    let range = span(
        settled(plain, t_end)
            .chain(settled(&prior.whole, t_end))
            .chain(prior.a0),
    );
    let title = "the whole record".to_string();
    prior_panel(&right, title, (plain, &prior.whole), None, range)?;
    root.present().map_err(draw_err)?;
    Ok(path.clone())
}
