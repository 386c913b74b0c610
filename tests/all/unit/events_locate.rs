//! The unit tests of `events::locate` (`src/events/locate.rs`).

// The source module's own imports.

use ricochet::events::locate::cannot_dip;

/// A convex parabola `g = c + k (t − s)²` whose minimum `c` lies inside `[0, h]`: the
/// search is skipped only if `c > 0` (never when it dips to zero or below), and it
/// is skipped when the minimum is far from zero.
#[test]
fn a_convex_dip_is_never_skipped() {
    let h = 1e-3;
    for ks in 1..=40 {
        let k = 10f64.powf(ks as f64 / 4.0 - 3.0);
        for ss in 1..20 {
            let s = h * ss as f64 / 20.0;
            for cs in -30..=30 {
                let c = k * h * h * cs as f64 / 10.0;
                let (g, gd) = (|t: f64| c + k * (t - s).powi(2), |t: f64| 2.0 * k * (t - s));
                let (ga, gb, gda, gdb) = (g(0.0), g(h), gd(0.0), gd(h));
                if ga <= 0.0 || gb <= 0.0 {
                    continue;
                }
                let skip = cannot_dip(ga, gda, gb, gdb, h);
                assert!(!skip || c > 0.0, "k {k}, s {s}, c {c}: a dip skipped");
                if c > 4.0 * k * h * h {
                    assert!(skip, "k {k}, s {s}, c {c}: a far minimum searched");
                }
            }
        }
    }
}
