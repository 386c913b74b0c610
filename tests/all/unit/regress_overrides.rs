//! The unit tests of `regress::overrides` (`src/regress/overrides.rs`).

// The source module's own imports.
use ricochet::math::Real;
use ricochet::settings::Settings;

use ricochet::regress::overrides::*;

#[test]
fn overrides_apply_and_refuse_out_of_range_values() {
    let mut s = Settings::default();
    let o = RunOverrides {
        t_end: Some(2.5),
        e: Some(0.25),
        rtol: Some(1e-8),
        max_drift: Some(1e-9),
        ..RunOverrides::default()
    };
    let m = o.apply(&mut s).unwrap();
    assert_eq!((s.t_end, s.integrator.rtol), (2.5, 1e-8));
    assert_eq!(s.max_drift, Some(1e-9));
    assert_eq!((m.e, m.mu, m.law), (Some(0.25), None, None));
    for (o, field) in [
        (
            RunOverrides {
                t_end: Some(0.0),
                ..Default::default()
            },
            "t_end",
        ),
        (
            RunOverrides {
                e: Some(1.5),
                ..Default::default()
            },
            "e",
        ),
        (
            RunOverrides {
                e: Some(Real::NAN),
                ..Default::default()
            },
            "e",
        ),
        (
            RunOverrides {
                mu: Some(-1.0),
                ..Default::default()
            },
            "mu",
        ),
        (
            RunOverrides {
                mu: Some(Real::INFINITY),
                ..Default::default()
            },
            "mu",
        ),
        (
            RunOverrides {
                dt: Some(-1e-3),
                ..Default::default()
            },
            "dt",
        ),
        (
            RunOverrides {
                max_drift: Some(Real::NAN),
                ..Default::default()
            },
            "max_drift",
        ),
    ] {
        let err = o.apply(&mut Settings::default()).unwrap_err();
        assert_eq!(err.field, field, "{err}");
    }
    let err = RunOverrides {
        e: Some(2.0),
        ..Default::default()
    }
    .apply(&mut Settings::default())
    .unwrap_err();
    assert_eq!(err.to_string(), "`e` must lie in [0, 1], not 2");
}
