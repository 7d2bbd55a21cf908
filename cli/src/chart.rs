//! What the PNG plots share: the embedded font, the size, the chart layout and the legend.

use plotters::prelude::*;

use crate::error::Fail;

/// The size of every plot, in pixels.
pub const SIZE: (u32, u32) = (960, 600);

/// Registers the embedded DejaVu Sans as the plots' font (no system fonts needed).
pub fn font() -> Result<(), Fail> {
    plotters::style::register_font("sans-serif", FontStyle::Normal, dejavu::sans::regular())
        .map_err(|_| Fail("cannot load the embedded font".into()))
}

/// The bitmap `path` is drawn into, `size` pixels, once a file can be created there (an error
/// naming its file and the system's reason, where the drawing would name neither well).
pub fn bitmap(path: &std::path::Path, size: (u32, u32)) -> Result<BitMapBackend<'_>, Fail> {
    // Opened as the drawing will open it, its text left as it is until then; a file made
    // only for the check removed again (a drawing that fails leaves none).
    let new = path.symlink_metadata().is_err();
    std::fs::OpenOptions::new()
        .write(true)
        .create(true)
        .truncate(false)
        .open(path)
        .map_err(|e| {
            let name = path.file_name().unwrap_or(path.as_os_str());
            Fail(format!("{}: cannot be written: {e}", name.display()))
        })?;
    if new {
        let _ = std::fs::remove_file(path);
    }
    Ok(BitMapBackend::new(path, size))
}

/// A drawing error as the tool's error.
pub fn draw_err(e: impl std::fmt::Display) -> Fail {
    Fail(format!("drawing failed: {e}"))
}

/// A chart on `root` with a caption, margins and label areas.
pub fn builder<'a, 'b, DB: DrawingBackend>(
    root: &'a DrawingArea<DB, plotters::coord::Shift>,
    caption: String,
    y_labels: u32,
) -> ChartBuilder<'a, 'b, DB> {
    let mut builder = ChartBuilder::on(root);
    builder
        .caption(caption, ("sans-serif", 20))
        .margin(12)
        .x_label_area_size(45)
        .y_label_area_size(y_labels);
    builder
}

/// The legend of every series that has a label.
pub fn legend<'a, DB: DrawingBackend + 'a, CT: plotters::coord::CoordTranslate>(
    chart: &mut ChartContext<'a, DB, CT>,
    position: SeriesLabelPosition,
) -> Result<(), Fail> {
    chart
        .configure_series_labels()
        .position(position)
        .background_style(WHITE.mix(0.8))
        .border_style(BLACK)
        .draw()
        .map_err(draw_err)
}
