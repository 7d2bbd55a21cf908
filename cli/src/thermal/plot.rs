//! `thermal.png`: per axis, the temperature bins' biases with the fitted cubic, and what the
//! fit leaves of each bin.

use std::path::Path;

use plotters::prelude::*;

use super::axis::AxisFit;
use crate::chart::{builder, draw_err, font};
use crate::error::Fail;
use crate::input::source::AXES;

/// The size of the plot, in pixels: four rows of three panels.
const SIZE: (u32, u32) = (1800, 1600);

/// The range of the finite `values`, widened a little (a flat one by its magnitude).
fn span(values: impl Iterator<Item = f64>) -> (f64, f64) {
    let (lo, hi) = values
        .filter(|v| v.is_finite())
        .fold((f64::INFINITY, f64::NEG_INFINITY), |(l, h), v| {
            (l.min(v), h.max(v))
        });
    if lo > hi {
        return (-1.0, 1.0);
    }
    let pad = 0.08 * (hi - lo).max(1e-9 * hi.abs().max(lo.abs()).max(1e-12));
    (lo - pad, hi + pad)
}

/// Draws `thermal.png` at `path`: for each sensor a row of the three axes' bins (medians) and
/// fits against temperature, and a row of the bins' residuals; `units` the gyro's and the
/// accelerometer's.
pub fn png(path: &Path, fits: &[AxisFit], units: [&str; 2]) -> Result<(), Fail> {
    font()?;
    let root = crate::chart::bitmap(path, SIZE)?.into_drawing_area();
    root.fill(&WHITE).map_err(draw_err)?;
    let panels = root.split_evenly((4, 3));
    for (i, fit) in fits.iter().enumerate().take(6) {
        let unit = units[i / 3];
        let (row, column) = (2 * (i / 3), i % 3);
        let (t0, t1) = span(fit.bins.iter().map(|b| b.celsius));
        // The bins and the fit.
        let curve: Vec<(f64, f64)> = (0..=200)
            .map(|k| {
                let t = t0 + (t1 - t0) * f64::from(k) / 200.0;
                (t, fit.poly.at(t))
            })
            .collect();
        let (y0, y1) = span(
            fit.bins
                .iter()
                .map(|b| b.value)
                .chain(curve.iter().map(|p| p.1)),
        );
        let area = &panels[3 * row + column];
        let mut chart = builder(area, format!("{} bias ({unit}): bins and fit", AXES[i]), 80)
            .build_cartesian_2d(t0..t1, y0..y1)
            .map_err(draw_err)?;
        chart
            .configure_mesh()
            .light_line_style(WHITE)
            .x_desc("temperature (deg C)")
            .y_label_formatter(&|v| format!("{v:.2e}"))
            .draw()
            .map_err(draw_err)?;
        chart
            .draw_series(
                fit.bins
                    .iter()
                    .map(|b| Circle::new((b.celsius, b.value), 3, BLUE.filled())),
            )
            .map_err(draw_err)?;
        chart
            .draw_series(LineSeries::new(curve, RED.stroke_width(2)))
            .map_err(draw_err)?;
        // What the fit leaves of each bin.
        let left: Vec<(f64, f64)> = fit
            .bins
            .iter()
            .map(|b| (b.celsius, b.value - fit.poly.at(b.celsius)))
            .collect();
        let (r0, r1) = span(left.iter().map(|p| p.1).chain([0.0]));
        let area = &panels[3 * (row + 1) + column];
        let mut chart = builder(area, format!("{} left after the fit ({unit})", AXES[i]), 80)
            .build_cartesian_2d(t0..t1, r0..r1)
            .map_err(draw_err)?;
        chart
            .configure_mesh()
            .light_line_style(WHITE)
            .x_desc("temperature (deg C)")
            .y_label_formatter(&|v| format!("{v:.2e}"))
            .draw()
            .map_err(draw_err)?;
        chart
            .draw_series(LineSeries::new(
                [(t0, 0.0), (t1, 0.0)],
                BLACK.stroke_width(1),
            ))
            .map_err(draw_err)?;
        chart
            .draw_series(left.iter().map(|&p| Circle::new(p, 3, BLUE.filled())))
            .map_err(draw_err)?;
    }
    root.present().map_err(draw_err)?;
    Ok(())
}
