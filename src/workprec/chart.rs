//! Log–log charts (plotters, SVG backend): one curve per method.
//!
//! A point whose value is not a positive finite number (a missed impact gives an infinite
//! error) is drawn at the top edge of the chart with a cross; an error of exactly zero at
//! the bottom edge with a triangle. The caption says so.

use std::path::Path;

use plotters::prelude::*;

use super::WorkprecError;
use crate::math::Real;

/// One curve: a name and its points `(x, y)`, in the order they are joined.
#[derive(Clone, Debug, PartialEq)]
pub struct Series {
    /// The legend.
    pub name: String,
    /// The points.
    pub points: Vec<(Real, Real)>,
}

/// Labels of a chart.
#[derive(Clone, Copy, Debug)]
pub struct Labels<'a> {
    /// The caption.
    pub title: &'a str,
    /// The x axis.
    pub x: &'a str,
    /// The y axis.
    pub y: &'a str,
}

const COLORS: [RGBColor; 6] = [
    RGBColor(31, 119, 180),
    RGBColor(255, 127, 14),
    RGBColor(44, 160, 44),
    RGBColor(214, 39, 40),
    RGBColor(148, 103, 189),
    RGBColor(140, 86, 75),
];

/// The decade range `[10^⌊log min⌋, 10^⌈log max⌉]` of the positive finite values, or
/// `None` if there are none.
fn decades(values: impl Iterator<Item = Real>) -> Option<(Real, Real)> {
    let (lo, hi) = values
        .filter(|v| v.is_finite() && *v > 0.0)
        .fold((Real::INFINITY, 0.0 as Real), |(lo, hi), v| {
            (lo.min(v), hi.max(v))
        });
    (hi > 0.0).then(|| {
        let lo = 10f64.powf(lo.log10().floor());
        let hi = 10f64.powf(hi.log10().ceil());
        (lo, if hi > lo { hi } else { 10.0 * lo })
    })
}

/// The corner of the legend: the one whose quarter of the plot (in log coordinates, the
/// half of each axis nearest it) holds the fewest points, upper right on a tie (the
/// 128-link point of the rope on the floor sat under an upper-right legend).
#[doc(hidden)]
pub fn legend_corner(
    points: impl Iterator<Item = (Real, Real)>,
    (x0, x1): (Real, Real),
    (y0, y1): (Real, Real),
) -> SeriesLabelPosition {
    let (xm, ym) = ((x0 * x1).sqrt(), (y0 * y1).sqrt());
    // Counts in the order upper right, upper left, lower right, lower left.
    let mut counts = [0usize; 4];
    for (x, y) in points.filter(|p| p.0.is_finite() && p.1.is_finite() && p.1 > 0.0) {
        let (right, upper) = (x >= xm, y >= ym);
        let k = match (upper, right) {
            (true, true) => 0,
            (true, false) => 1,
            (false, true) => 2,
            (false, false) => 3,
        };
        counts[k] += 1;
    }
    match (0..4).min_by_key(|&k| (counts[k], k)).unwrap_or(0) {
        0 => SeriesLabelPosition::UpperRight,
        1 => SeriesLabelPosition::UpperLeft,
        2 => SeriesLabelPosition::LowerRight,
        _ => SeriesLabelPosition::LowerLeft,
    }
}

/// Draws `series` on log–log axes into the SVG file `path`.
pub fn loglog(path: &Path, labels: Labels<'_>, series: &[Series]) -> Result<(), WorkprecError> {
    draw(path, labels, series).map_err(|e| WorkprecError::Chart {
        path: path.to_owned(),
        reason: e.to_string(),
    })
}

fn draw(
    path: &Path,
    labels: Labels<'_>,
    series: &[Series],
) -> Result<(), Box<dyn std::error::Error>> {
    let all = || series.iter().flat_map(|s| s.points.iter());
    let (x0, x1) = decades(all().map(|p| p.0)).unwrap_or((1e-6, 1.0));
    let (y0, y1) = decades(all().map(|p| p.1)).unwrap_or((1e-16, 1.0));
    let root = SVGBackend::new(path, (800, 560)).into_drawing_area();
    root.fill(&WHITE)?;
    let mut chart = ChartBuilder::on(&root)
        .caption(labels.title, ("sans-serif", 20))
        .margin(12)
        .x_label_area_size(44)
        .y_label_area_size(70)
        .build_cartesian_2d((x0..x1).log_scale(), (y0..y1).log_scale())?;
    chart
        .configure_mesh()
        .x_desc(labels.x)
        .y_desc(labels.y)
        .x_label_formatter(&|v| format!("{v:.0e}"))
        .y_label_formatter(&|v| format!("{v:.0e}"))
        .draw()?;
    for (k, s) in series.iter().enumerate() {
        let color = COLORS[k % COLORS.len()];
        // Off-scale values on the edges.
        let placed: Vec<(Real, Real, bool)> = s
            .points
            .iter()
            .map(|&(x, y)| {
                if !(y.is_finite() && y > 0.0) && y != 0.0 {
                    (x, y1, false)
                } else if y == 0.0 {
                    (x, y0, false)
                } else {
                    (x, y, true)
                }
            })
            .collect();
        chart
            .draw_series(LineSeries::new(
                placed.iter().map(|p| (p.0, p.1)),
                color.stroke_width(2),
            ))?
            .label(&s.name)
            .legend(move |(x, y)| PathElement::new(vec![(x, y), (x + 20, y)], color));
        chart.draw_series(
            placed
                .iter()
                .filter(|p| p.2)
                .map(|p| Circle::new((p.0, p.1), 4, color.filled())),
        )?;
        chart.draw_series(
            placed
                .iter()
                .filter(|p| !p.2 && p.1 == y1)
                .map(|p| Cross::new((p.0, p.1), 6, color.stroke_width(2))),
        )?;
        chart.draw_series(
            placed
                .iter()
                .filter(|p| !p.2 && p.1 == y0)
                .map(|p| TriangleMarker::new((p.0, p.1), 6, color.filled())),
        )?;
    }
    let corner = legend_corner(all().copied(), (x0, x1), (y0, y1));
    chart
        .configure_series_labels()
        .position(corner)
        .background_style(WHITE.mix(0.85))
        .border_style(BLACK)
        .draw()?;
    root.present()?;
    Ok(())
}
