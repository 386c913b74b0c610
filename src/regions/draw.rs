//! SVG pictures of a [`RegionMap`] (plotters, SVG backend, no font system): the collision
//! type as coloured cells, the cells with `ΔE > 0` in a darker shade and outlined, the two
//! boundary curves, the scene's or the paper's points, and a legend.

use std::path::{Path, PathBuf};

use plotters::coord::Shift;
use plotters::element::DashedPathElement;
use plotters::prelude::*;
use plotters::style::text_anchor::{HPos, Pos, VPos};

use super::{Boundary, BoundaryKind, Cell, RegionMap};
use crate::impact::{CollisionType, Law};
use crate::math::Real;

/// Why a picture could not be drawn or written.
#[derive(Debug, thiserror::Error)]
pub enum DrawError {
    /// plotters failed to lay out or draw an element.
    #[error("drawing the map failed: {0}")]
    Plot(String),
    /// The file could not be written.
    #[error("cannot write {}: {source}", path.display())]
    Io {
        /// The file.
        path: PathBuf,
        /// The error.
        source: std::io::Error,
    },
}

fn plot_error<E: std::fmt::Display>(e: E) -> DrawError {
    DrawError::Plot(e.to_string())
}

/// A labelled point on the map (the scene's own `(α, μ)`, a row of the paper's Table 2).
#[derive(Clone, Debug, PartialEq)]
pub struct Marker {
    /// The label written beside it.
    pub label: String,
    /// `α`.
    pub alpha: Real,
    /// `μ`.
    pub mu: Real,
}

/// The colours of the pictures (`#RRGGBB` in the SVG).
pub mod style {
    use plotters::style::RGBColor;

    /// Sticking, `ΔE ≤ 0`.
    pub const STICKING: RGBColor = RGBColor(158, 202, 225);
    /// Sticking, `ΔE > 0`.
    pub const STICKING_GAIN: RGBColor = RGBColor(33, 102, 172);
    /// Reverse sliding, `ΔE ≤ 0`.
    pub const REVERSE: RGBColor = RGBColor(253, 208, 162);
    /// Reverse sliding, `ΔE > 0`.
    pub const REVERSE_GAIN: RGBColor = RGBColor(217, 72, 1);
    /// Forward sliding, `ΔE ≤ 0`.
    pub const FORWARD: RGBColor = RGBColor(199, 233, 192);
    /// Forward sliding, `ΔE > 0`.
    pub const FORWARD_GAIN: RGBColor = RGBColor(35, 139, 69);
    /// No solution (a jam, singular `W`).
    pub const JAM: RGBColor = RGBColor(189, 189, 189);
    /// The outline of the `ΔE > 0` region.
    pub const GAIN_OUTLINE: RGBColor = RGBColor(0, 0, 0);
    /// The curve `α = (1+e) r_m(μ)` (solid).
    pub const FORWARD_BOUNDARY: RGBColor = RGBColor(203, 24, 29);
    /// The curve `α = −(1+e) r_p(μ)` (dashed).
    pub const MIRRORED_BOUNDARY: RGBColor = RGBColor(106, 61, 154);
}

/// Picture size (px).
const SIZE: (u32, u32) = (1000, 720);
/// Width of the legend column (px).
const LEGEND_WIDTH: u32 = 270;
/// Points per boundary piece (each way, see [`super::boundary`]).
const CURVE_SAMPLES: usize = 400;

/// The long name of a law, for titles.
fn law_title(law: Law) -> &'static str {
    match law {
        Law::Newton => "Newton (Routh's path, Table 1)",
        Law::KaneLevinson => "Kane–Levinson (Appendix C)",
        Law::Poisson => "Poisson (Routh's path)",
        Law::Stronge => "Stronge (Routh's path)",
    }
}

/// The fill of a cell: its type, darker where `ΔE > 0`.
fn fill(cell: &Cell) -> RGBColor {
    use style::*;
    match (cell.kind(), cell.gains_energy()) {
        (None, _) => JAM,
        (Some(CollisionType::Sticking), false) => STICKING,
        (Some(CollisionType::Sticking), true) => STICKING_GAIN,
        (Some(CollisionType::ReverseSliding), false) => REVERSE,
        (Some(CollisionType::ReverseSliding), true) => REVERSE_GAIN,
        (Some(CollisionType::ForwardSliding), false) => FORWARD,
        (Some(CollisionType::ForwardSliding), true) => FORWARD_GAIN,
    }
}

/// Draws the map as an SVG document: cells by collision type (darker and outlined in
/// black where `ΔE > 0`), the boundaries `α = (1+e) r_m(μ)` (solid) and
/// `α = −(1+e) r_p(μ)` (dashed), the line `α = 0`, the markers, the axes `α` and `μ`, a
/// legend, and a title stating the law, `W` and `e`.
pub fn render_svg(map: &RegionMap, markers: &[Marker]) -> Result<String, DrawError> {
    let mut svg = String::new();
    {
        let root = SVGBackend::with_string(&mut svg, SIZE).into_drawing_area();
        root.fill(&WHITE).map_err(plot_error)?;
        let s = &map.spec;
        let title = format!(
            "{}: W = [m_nn, m_nt, m_tt] = [{:.4}, {:.4}, {:.4}], e = {}",
            law_title(s.law),
            s.w.nn,
            s.w.nt,
            s.w.tt,
            s.e
        );
        let body = root
            .titled(&title, ("sans-serif", 20))
            .map_err(plot_error)?;
        let (left, right) = body.split_horizontally(SIZE.0 - LEGEND_WIDTH);
        draw_chart(&left, map, markers)?;
        draw_legend(&right, map, markers)?;
        root.present().map_err(plot_error)?;
    }
    Ok(svg)
}

/// [`render_svg`] written to `path`.
pub fn write_svg(path: &Path, map: &RegionMap, markers: &[Marker]) -> Result<(), DrawError> {
    let svg = render_svg(map, markers)?;
    std::fs::write(path, svg).map_err(|source| DrawError::Io {
        path: path.to_owned(),
        source,
    })
}

fn draw_chart<DB: DrawingBackend>(
    area: &DrawingArea<DB, Shift>,
    map: &RegionMap,
    markers: &[Marker],
) -> Result<(), DrawError> {
    let (a, m) = (map.spec.alpha, map.spec.mu);
    let mut chart = ChartBuilder::on(area)
        .margin(12)
        .x_label_area_size(50)
        .y_label_area_size(60)
        .build_cartesian_2d(a.min..a.max, m.min..m.max)
        .map_err(plot_error)?;
    chart
        .configure_mesh()
        .disable_mesh()
        .x_desc("α = v_t^A / |v_n^A|")
        .y_desc("μ")
        .axis_desc_style(("sans-serif", 18))
        .label_style(("sans-serif", 14))
        .draw()
        .map_err(plot_error)?;

    // The cells: one rectangle per run of equal fill along each row of μ.
    let mut rects = Vec::new();
    for j in 0..m.n {
        let (y0, y1) = m.cell(j);
        let mut i0 = 0;
        for i in 1..=a.n {
            if i == a.n || fill(&map.cell(i, j)) != fill(&map.cell(i0, j)) {
                let colour = fill(&map.cell(i0, j));
                rects.push(Rectangle::new(
                    [(a.cell(i0).0, y0), (a.cell(i - 1).1, y1)],
                    colour.filled(),
                ));
                i0 = i;
            }
        }
    }
    chart.draw_series(rects).map_err(plot_error)?;

    // The outline of the ΔE > 0 region.
    let outline = gain_outline(map)
        .into_iter()
        .map(|seg| PathElement::new(seg, style::GAIN_OUTLINE.stroke_width(2)));
    chart.draw_series(outline).map_err(plot_error)?;

    // α = 0: v_t^A changes sign, the right half mirrors to the left.
    if a.min < 0.0 && a.max > 0.0 {
        chart
            .draw_series([PathElement::new(
                vec![(0.0, m.min), (0.0, m.max)],
                BLACK.mix(0.4).stroke_width(1),
            )])
            .map_err(plot_error)?;
    }

    // The boundary curves.
    for b in map.boundaries(CURVE_SAMPLES) {
        draw_boundary(&mut chart, &b)?;
    }

    // The markers.
    for mk in markers {
        if !(a.min..=a.max).contains(&mk.alpha) || !(m.min..=m.max).contains(&mk.mu) {
            continue;
        }
        chart
            .draw_series([Circle::new((mk.alpha, mk.mu), 5, BLACK.filled())])
            .map_err(plot_error)?;
        // The label goes away from the middle, where the boundaries usually are not.
        let (h, dx) = if mk.alpha <= 0.5 * (a.min + a.max) {
            (HPos::Left, 0.012)
        } else {
            (HPos::Right, -0.012)
        };
        let font = TextStyle::from(("sans-serif", 14).into_font()).pos(Pos::new(h, VPos::Bottom));
        chart
            .draw_series([Text::new(
                mk.label.clone(),
                (
                    mk.alpha + dx * (a.max - a.min),
                    mk.mu + 0.012 * (m.max - m.min),
                ),
                font,
            )])
            .map_err(plot_error)?;
    }
    Ok(())
}

fn draw_boundary<DB: DrawingBackend>(
    chart: &mut ChartContext<
        '_,
        DB,
        Cartesian2d<plotters::coord::types::RangedCoordf64, plotters::coord::types::RangedCoordf64>,
    >,
    b: &Boundary,
) -> Result<(), DrawError> {
    for piece in &b.pieces {
        match b.kind {
            BoundaryKind::ForwardSliding => chart
                .draw_series([PathElement::new(
                    piece.clone(),
                    style::FORWARD_BOUNDARY.stroke_width(3),
                )])
                .map(|_| ()),
            BoundaryKind::Mirrored => chart
                .draw_series([DashedPathElement::new(
                    piece.clone(),
                    10,
                    6,
                    style::MIRRORED_BOUNDARY.stroke_width(3),
                )])
                .map(|_| ()),
        }
        .map_err(plot_error)?;
    }
    Ok(())
}

/// The edges between cells with `ΔE > 0` and the others (or the map's border), merged
/// into straight segments: horizontal ones along each row edge, vertical ones along each
/// column edge.
fn gain_outline(map: &RegionMap) -> Vec<Vec<(Real, Real)>> {
    let (a, m) = (map.spec.alpha, map.spec.mu);
    let gain = |i: isize, j: isize| {
        i >= 0
            && j >= 0
            && (i as usize) < a.n
            && (j as usize) < m.n
            && map.cell(i as usize, j as usize).gains_energy()
    };
    let mut segments = Vec::new();
    // Horizontal edges: below row j (between rows j − 1 and j), j = 0..=n.
    for j in 0..=m.n as isize {
        let y = if j == m.n as isize {
            m.max
        } else {
            m.cell(j as usize).0
        };
        let mut run: Option<usize> = None;
        for i in 0..=a.n {
            let edge = i < a.n && gain(i as isize, j - 1) != gain(i as isize, j);
            match (edge, run) {
                (true, None) => run = Some(i),
                (false, Some(i0)) => {
                    segments.push(vec![(a.cell(i0).0, y), (a.cell(i - 1).1, y)]);
                    run = None;
                }
                _ => {}
            }
        }
    }
    // Vertical edges: left of column i, i = 0..=n.
    for i in 0..=a.n as isize {
        let x = if i == a.n as isize {
            a.max
        } else {
            a.cell(i as usize).0
        };
        let mut run: Option<usize> = None;
        for j in 0..=m.n {
            let edge = j < m.n && gain(i - 1, j as isize) != gain(i, j as isize);
            match (edge, run) {
                (true, None) => run = Some(j),
                (false, Some(j0)) => {
                    segments.push(vec![(x, m.cell(j0).0), (x, m.cell(j - 1).1)]);
                    run = None;
                }
                _ => {}
            }
        }
    }
    segments
}

fn draw_legend<DB: DrawingBackend>(
    area: &DrawingArea<DB, Shift>,
    map: &RegionMap,
    markers: &[Marker],
) -> Result<(), DrawError> {
    let font = ("sans-serif", 15).into_font();
    let mut present: Vec<RGBColor> = Vec::new();
    for (_, _, c) in map.nodes() {
        let f = fill(&c);
        if !present.contains(&f) {
            present.push(f);
        }
    }
    let patches = [
        (style::STICKING, "sticking, ΔE ≤ 0"),
        (style::STICKING_GAIN, "sticking, ΔE > 0"),
        (style::REVERSE, "reverse sliding, ΔE ≤ 0"),
        (style::REVERSE_GAIN, "reverse sliding, ΔE > 0"),
        (style::FORWARD, "forward sliding, ΔE ≤ 0"),
        (style::FORWARD_GAIN, "forward sliding, ΔE > 0"),
        (style::JAM, "no solution (jam)"),
    ];
    let mut y = 60;
    let x = 10;
    let step = 26;
    for (colour, label) in patches {
        if !present.contains(&colour) {
            continue;
        }
        area.draw(&Rectangle::new([(x, y), (x + 28, y + 16)], colour.filled()))
            .map_err(plot_error)?;
        area.draw(&Text::new(label, (x + 38, y + 1), font.clone()))
            .map_err(plot_error)?;
        y += step;
    }
    if present.iter().any(|c| {
        [
            style::STICKING_GAIN,
            style::REVERSE_GAIN,
            style::FORWARD_GAIN,
        ]
        .contains(c)
    }) {
        area.draw(&Rectangle::new(
            [(x, y), (x + 28, y + 16)],
            style::GAIN_OUTLINE.stroke_width(2),
        ))
        .map_err(plot_error)?;
        area.draw(&Text::new(
            "outline of ΔE > 0",
            (x + 38, y + 1),
            font.clone(),
        ))
        .map_err(plot_error)?;
    } else {
        area.draw(&Text::new("ΔE ≤ 0 everywhere", (x, y + 1), font.clone()))
            .map_err(plot_error)?;
    }
    y += step + 10;
    area.draw(&PathElement::new(
        vec![(x, y + 8), (x + 28, y + 8)],
        style::FORWARD_BOUNDARY.stroke_width(3),
    ))
    .map_err(plot_error)?;
    area.draw(&Text::new(
        BoundaryKind::ForwardSliding.label(),
        (x + 38, y + 1),
        font.clone(),
    ))
    .map_err(plot_error)?;
    y += step;
    area.draw(&DashedPathElement::new(
        vec![(x, y + 8), (x + 28, y + 8)],
        8,
        5,
        style::MIRRORED_BOUNDARY.stroke_width(3),
    ))
    .map_err(plot_error)?;
    area.draw(&Text::new(
        BoundaryKind::Mirrored.label(),
        (x + 38, y + 1),
        font.clone(),
    ))
    .map_err(plot_error)?;
    y += step;
    if !markers.is_empty() {
        area.draw(&Circle::new((x + 14, y + 8), 5, BLACK.filled()))
            .map_err(plot_error)?;
        area.draw(&Text::new("marked points", (x + 38, y + 1), font.clone()))
            .map_err(plot_error)?;
        y += step;
    }
    y += 10;
    let small = ("sans-serif", 13).into_font();
    let notes = [
        "α < 0: v_t^A < 0 (t mirrored).".to_owned(),
        format!(
            "{} × {} nodes, each solved by the law",
            map.spec.alpha.n, map.spec.mu.n
        ),
        "at v^A = (−1, α) m/s.".to_owned(),
    ];
    for note in notes {
        area.draw(&Text::new(note, (x, y), small.clone()))
            .map_err(plot_error)?;
        y += 18;
    }
    Ok(())
}
