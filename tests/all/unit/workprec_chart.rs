//! The unit tests of `workprec::chart` (`src/workprec/chart.rs`).

// The source module's own imports.
use plotters::prelude::*;

use ricochet::workprec::chart::*;

/// A rising curve (cost against size) leaves the upper left empty; a falling one
/// (error against time) the upper right; with every corner holding points, the one
/// with the fewest.
#[test]
fn the_legend_goes_to_the_emptiest_corner() {
    let rising = [(1.0, 1.0), (3.0, 3.0), (30.0, 30.0), (100.0, 100.0)];
    let c = legend_corner(rising.into_iter(), (1.0, 100.0), (1.0, 100.0));
    assert!(matches!(c, SeriesLabelPosition::UpperLeft));
    let falling = rising.map(|(x, y)| (x, 100.0 / y));
    let c = legend_corner(falling.into_iter(), (1.0, 100.0), (1.0, 100.0));
    assert!(matches!(c, SeriesLabelPosition::UpperRight));
    // Three points upper right, two upper left, one lower right, two lower left.
    let pts = [
        (5.0, 5.0),
        (6.0, 6.0),
        (7.0, 7.0),
        (0.5, 5.0),
        (0.6, 6.0),
        (5.0, 0.5),
        (0.5, 0.5),
        (0.6, 0.6),
    ];
    let c = legend_corner(pts.into_iter(), (0.1, 10.0), (0.1, 10.0));
    assert!(matches!(c, SeriesLabelPosition::LowerRight));
}
