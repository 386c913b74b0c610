//! [P] Table 2, both halves, every printed column, through the public API.
//!
//! The expected values, their source and the known print errors are in
//! `tests/golden/paper_table_2.toml`. The double pendulum is built here from its closed
//! form (independently of the simulator's model): two uniform rods of mass m = 3 kg and
//! length l = 2 m, absolute angles q1 = 20°, q2 = 30° from the downward vertical,
//! u = (−0.1, −0.2) rad/s, the tip of rod B striking a horizontal floor.

use nalgebra::Vector2;

use crate::common::paper::{Golden, golden, pendulum, printed};
use ricochet::impact::{self, ImpactProblem, Law, kane_levinson};

fn law_of(name: &str) -> Law {
    name.parse().expect("a law name")
}

#[test]
fn the_pendulum_matches_the_papers_data() {
    // [P, Sect. 5] prints v^A = −0.2684 n + 0.5343 t and α = 1.9908; ERRATA item 3 gives
    // m_nn = 0.3365, m_tt = 0.8134, m_nt = −0.5071, Δ = 0.0166.
    let p = pendulum();
    let (w, v) = (p.w(), p.v_a());
    let close = |x: f64, s: &str| (x - printed(s).value).abs() <= 0.5 * printed(s).unit;
    assert!(close(v.n, "-0.2684") && close(v.t, "0.5343"), "{v:?}");
    assert!(close(w.nn, "0.3365") && close(w.tt, "0.8134") && close(w.nt, "-0.5071"));
    assert!(close(w.det(), "0.0166") && close(v.t / -v.n, "1.9908"));
}

#[test]
fn table_2_reproduces_to_the_printed_digits() {
    let golden: Golden = golden();
    let p = pendulum();
    let (w, v_a) = (p.w(), p.v_a());
    let mut failures = Vec::new();
    let mut exceptions_seen = 0;
    println!(
        "{}: value got / printed (tolerance one unit in the last printed place)",
        golden.source
    );
    for row in &golden.row {
        let law = law_of(&row.law);
        let exception = |column: &str| {
            golden
                .exception
                .iter()
                .find(|x| x.law == row.law && x.row == row.row && x.column == column)
        };
        let pb = ImpactProblem::new(w, v_a, row.e, row.mu);
        let out = impact::solve(law, &pb).unwrap();
        let c = out.coefficients;
        let du = p.delta_u(out.impulse.n, out.impulse.t);
        let mut line = format!("{:>13} row {}:", row.law, row.row);
        let tag = format!("{} row {}", row.law, row.row);
        let mut check = |line: &mut String, name: &str, got: f64, s: &str| {
            let pr = printed(s);
            let ok = (got - pr.value).abs() <= pr.unit;
            line.push_str(&format!(
                " {name}={got:.5}/{s}{}",
                if ok { "" } else { "!" }
            ));
            if !ok {
                failures.push(format!("{tag} {name}: got {got}, printed {s}"));
            }
        };
        check(&mut line, "r_m", c.r_m(), &row.r_m);
        check(
            &mut line,
            "(1+e)r_m",
            (1.0 + row.e) * c.r_m(),
            &row.one_plus_e_r_m,
        );
        check(
            &mut line,
            "-(1+e)r_p",
            -(1.0 + row.e) * c.r_p(),
            &row.minus_one_plus_e_r_p,
        );
        if let Some(s) = &row.v_n_s {
            check(&mut line, "v_n^S", out.v_s.n, s);
        }
        if let Some(s) = &row.delta_e {
            check(&mut line, "ΔE", out.delta_e, s);
        }
        if let Some([s1, _]) = &row.delta_u {
            check(&mut line, "Δu1", du[0], s1);
        }
        match exception("delta_u_2") {
            Some(x) => {
                exceptions_seen += 1;
                // v_n^S = e|v_n^A| by Newton's hypothesis (30), exactly; v_t^S as printed,
                // within half a unit: Δu = J⁻¹ (v^S − v^A) bounds Δu₂.
                let vt = printed(row.v_t_s.as_deref().unwrap());
                let jinv = p.jac.try_inverse().unwrap();
                let bound =
                    |vts: f64| (jinv * Vector2::new(row.e * -v_a.n - v_a.n, vts - v_a.t))[1];
                let (a, b) = (
                    bound(vt.value - 0.5 * vt.unit),
                    bound(vt.value + 0.5 * vt.unit),
                );
                let (lo, hi) = (a.min(b), a.max(b));
                let pr = printed(&row.delta_u.as_ref().unwrap()[1]);
                assert!((du[1] - pr.value).abs() > pr.unit, "{}", x.reason);
                assert!(
                    lo <= du[1] && du[1] <= hi,
                    "Δu₂ {} not in [{lo}, {hi}]: {}",
                    du[1],
                    x.reason
                );
                assert!(!(lo..=hi).contains(&pr.value), "{}", x.reason);
                line.push_str(&format!(" Δu2={:.5}/≠{} (exception)", du[1], pr.value));
            }
            None => {
                if let Some([_, s2]) = &row.delta_u {
                    check(&mut line, "Δu2", du[1], s2);
                }
            }
        }
        match exception("v_t_s") {
            Some(x) => {
                exceptions_seen += 1;
                // Eq. (29) solved for v_t^S with the printed ΔE (within half a unit).
                let de = printed(row.delta_e.as_deref().unwrap());
                let (i, vns) = (out.impulse, out.v_s.n);
                let from_de = |de: f64| (2.0 * de - i.n * (vns + v_a.n)) / i.t - v_a.t;
                let (a, b) = (
                    from_de(de.value - 0.5 * de.unit),
                    from_de(de.value + 0.5 * de.unit),
                );
                let (lo, hi) = (a.min(b), a.max(b));
                let pr = printed(row.v_t_s.as_deref().unwrap());
                assert!((out.v_s.t - pr.value).abs() > pr.unit, "{}", x.reason);
                assert!(
                    lo <= out.v_s.t && out.v_s.t <= hi,
                    "v_t^S {} not in [{lo}, {hi}]",
                    out.v_s.t
                );
                assert!(!(lo..=hi).contains(&pr.value), "{}", x.reason);
                line.push_str(&format!(
                    " v_t^S={:.5}/≠{} (exception)",
                    out.v_s.t, pr.value
                ));
            }
            None => {
                if let Some(s) = &row.v_t_s {
                    check(&mut line, "v_t^S", out.v_s.t, s);
                }
            }
        }
        match (row.kind, exception("type")) {
            (Some(t), None) => {
                let ok = out.kind.number() == t;
                line.push_str(&format!(
                    " type={}/{t}{}",
                    out.kind.number(),
                    if ok { "" } else { "!" }
                ));
                if !ok {
                    check(&mut line, "type", out.kind.number().into(), &t.to_string());
                }
            }
            (None, Some(x)) => {
                exceptions_seen += 1;
                // Inequality (77) with the printed α and −(1+e) r_p, and the candidates of
                // Appendix C: exactly one is coherent, reverse sliding, and it gains energy.
                assert!(
                    1.9908 < printed(&row.minus_one_plus_e_r_p).value,
                    "{}",
                    x.reason
                );
                let coherent: Vec<_> = kane_levinson::candidates(&pb, &c)
                    .into_iter()
                    .filter(|k| k.coherent)
                    .collect();
                assert_eq!(coherent.len(), 1, "{}", x.reason);
                assert_eq!(out.kind.name(), "reverse_sliding", "{}", x.reason);
                assert!(
                    (out.delta_e - 0.61).abs() < 0.005,
                    "ΔE = {}: {}",
                    out.delta_e,
                    x.reason
                );
                line.push_str(&format!(
                    " type={} ΔE={:.4} (printed: no solution; exception)",
                    out.kind.number(),
                    out.delta_e
                ));
            }
            (kind, exc) => panic!(
                "row {} of {}: type {kind:?} with exception {}",
                row.row,
                row.law,
                exc.is_some()
            ),
        }
        println!("{line}");
    }
    assert_eq!(
        exceptions_seen,
        golden.exception.len(),
        "every exception is used"
    );
    assert!(failures.is_empty(), "mismatches:\n{}", failures.join("\n"));
}

#[test]
fn design_example_line_is_table_2_lower_row_1() {
    // ../shared/DESIGN.md's example output of `ricochet impact`.
    let p = pendulum();
    let out = impact::solve(Law::Newton, &ImpactProblem::new(p.w(), p.v_a(), 0.5, 0.2)).unwrap();
    let close = |x: f64, y: f64| (x - y).abs() <= 0.5e-4;
    assert_eq!((out.kind.name(), out.case.number()), ("reverse_sliding", 3));
    assert!(close(out.coefficients.alpha(), 1.9908));
    assert!(close(out.impulse.n, 1.0242) && close(out.impulse.t, -0.1143));
    assert!(close(out.v_s.n, 0.1342) && close(out.v_s.t, -0.0780));
    assert!(close(out.delta_e, -0.0948));
}
