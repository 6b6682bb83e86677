//! PNG plots of 1D profiles (particles against an exact curve), drawn with plotters and the
//! DejaVu font bytes from the `dejavu` crate, so no system font library is needed.

use plotters::prelude::*;
use std::path::Path;

/// One panel: particle values as dots, a curve (the exact solution, or a time series) as a
/// line labelled `line_label`, against `x_desc`.
pub struct Panel<'a> {
    pub title: &'a str,
    pub particles: &'a [(f64, f64)],
    pub exact: &'a [(f64, f64)],
    pub x_desc: &'a str,
    /// The y axis: quantity and unit, e.g. "force (N/m)".
    pub y_desc: &'a str,
    pub line_label: &'a str,
}

/// Head room above the data, as a share of its range, where the legend goes: the legend sits
/// in the upper right corner of the panel, above every point and curve, so it covers none.
const LEGEND_ROOM: f64 = 0.32;

fn register_font() {
    // Registration is idempotent; plotters keeps the bytes in its own table.
    let _ =
        plotters::style::register_font("sans-serif", FontStyle::Normal, dejavu::sans::regular());
}

/// Axis ranges: x over both sets, y over the particles and the curve's points that lie within
/// one particle range (at least |max|) of the particles' values. A curve that diverges (Sedov's
/// exact u at the centre) is drawn whole and runs off the panel instead of flattening the
/// particles into a line; the chart area clips it.
fn bounds(pts: &[(f64, f64)], other: &[(f64, f64)]) -> (f64, f64, f64, f64) {
    let finite = |&&(x, y): &&(f64, f64)| x.is_finite() && y.is_finite();
    let (mut x0, mut x1, mut y0, mut y1) = (
        f64::INFINITY,
        f64::NEG_INFINITY,
        f64::INFINITY,
        f64::NEG_INFINITY,
    );
    for &(x, y) in pts.iter().filter(finite) {
        x0 = x0.min(x);
        x1 = x1.max(x);
        y0 = y0.min(y);
        y1 = y1.max(y);
    }
    let (lo, hi) = if y0 <= y1 {
        let reach = (y1 - y0).max(y0.abs().max(y1.abs()));
        (y0 - reach, y1 + reach)
    } else {
        (f64::NEG_INFINITY, f64::INFINITY)
    };
    for &(x, y) in other.iter().filter(finite) {
        x0 = x0.min(x);
        x1 = x1.max(x);
        if (lo..=hi).contains(&y) {
            y0 = y0.min(y);
            y1 = y1.max(y);
        }
    }
    if y0.is_nan() || y1.is_nan() || y0 > y1 {
        (y0, y1) = (0.0, 1.0);
    }
    let range = (y1 - y0).max(1e-12 * y1.abs().max(1.0));
    let pad = 0.06 * range;
    (x0, x1.max(x0 + 1e-12), y0 - pad, y1 + LEGEND_ROOM * range)
}

/// The curve within y0 ≤ y ≤ y1: points outside are dropped and a segment that crosses an edge
/// ends on it (interpolated), so a diverging curve meets the panel's edge at the right x
/// instead of running flat along it.
fn clip_to(curve: &[(f64, f64)], y0: f64, y1: f64) -> Vec<(f64, f64)> {
    let inside = |y: f64| (y0..=y1).contains(&y);
    let mut out = Vec::with_capacity(curve.len());
    for (k, &(x, y)) in curve.iter().enumerate() {
        if k > 0 {
            let (xa, ya) = curve[k - 1];
            if inside(ya) != inside(y) && ya.is_finite() && y.is_finite() {
                let edge = if ya.max(y) > y1 { y1 } else { y0 };
                let t = (edge - ya) / (y - ya);
                out.push((xa + t * (x - xa), edge));
            }
        }
        if inside(y) {
            out.push((x, y));
        }
    }
    out
}

/// Write a PNG with the panels stacked in a grid (2 columns).
pub fn profile_png(path: &Path, caption: &str, panels: &[Panel<'_>]) -> Result<(), String> {
    register_font();
    let rows = panels.len().div_ceil(2) as u32;
    let root = BitMapBackend::new(path, (1200, 40 + 380 * rows)).into_drawing_area();
    root.fill(&WHITE).map_err(|e| e.to_string())?;
    let root = root
        .titled(caption, ("sans-serif", 24))
        .map_err(|e| e.to_string())?;
    let areas = root.split_evenly((rows as usize, 2));
    for (panel, area) in panels.iter().zip(areas.iter()) {
        let (x0, x1, y0, y1) = bounds(panel.particles, panel.exact);
        let mut chart = ChartBuilder::on(area)
            .caption(panel.title, ("sans-serif", 18))
            .margin(12)
            .x_label_area_size(40)
            .y_label_area_size(80)
            .build_cartesian_2d(x0..x1, y0..y1)
            .map_err(|e| e.to_string())?;
        chart
            .configure_mesh()
            .x_desc(panel.x_desc)
            .y_desc(panel.y_desc)
            .draw()
            .map_err(|e| e.to_string())?;
        if !panel.particles.is_empty() {
            chart
                .draw_series(
                    panel
                        .particles
                        .iter()
                        .map(|&(x, y)| Circle::new((x, y), 2, BLUE.filled())),
                )
                .map_err(|e| e.to_string())?
                .label("sphfmu")
                .legend(|(x, y)| Circle::new((x, y), 3, BLUE.filled()));
        }
        chart
            .draw_series(LineSeries::new(
                clip_to(panel.exact, y0, y1),
                RED.stroke_width(2),
            ))
            .map_err(|e| e.to_string())?
            .label(panel.line_label)
            .legend(|(x, y)| PathElement::new(vec![(x, y), (x + 20, y)], RED.stroke_width(2)));
        chart
            .configure_series_labels()
            .position(SeriesLabelPosition::UpperRight)
            .background_style(WHITE)
            .border_style(BLACK)
            .draw()
            .map_err(|e| e.to_string())?;
    }
    root.present().map_err(|e| e.to_string())
}
