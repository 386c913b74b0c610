//! `ricochet::regions` and `ricochet regions`: the maps of the classification against
//! [P, Table 1] and Appendix C (types recomputed here from the signs of g, h, p, q of
//! Eq. 35), [P, Sect. 4.3] (where ΔE may be positive, and its closed-form maximum), the
//! printed rows of Table 2, the boundary curves against their defining Eq. (36), the W of
//! the pendulum scene against its closed form, the SVG, and the command line.

use std::path::Path;
use std::process::{Command, Output};

use crate::common::paper::{Golden, golden, pendulum, printed};
use ricochet::impact::{CollisionType, ImpactMatrix, Law};
use ricochet::regions::{
    self, Axis, BoundaryKind, Cell, EnergySign, MapSpec, RegionMap, RegionsError,
};

use crate::common::cli;
use cli::{BIN, TempDir};

/// W of every sign case of Table 1 (and of both sides of it, through the mirror at α < 0),
/// besides the pendulum's: balanced (m_nt = 0), strongly coupled either way, nearly
/// singular, and a particle-like W.
fn matrices() -> Vec<ImpactMatrix> {
    vec![
        pendulum().w(),
        ImpactMatrix::new(1.0, 0.0, 1.0),
        ImpactMatrix::new(1.0, 0.8, 1.0),
        ImpactMatrix::new(0.5, -0.9, 2.0),
        ImpactMatrix::new(2.0, 0.3, 0.2),
        ImpactMatrix::new(1.0, 0.999, 1.0),
        ImpactMatrix::new(0.3, 0.25, 3.5),
    ]
}

/// g, h, p, q of [P, Eq. (35)] for `W` (in the frame with `v_t^A ≥ 0`).
fn ghpq(w: ImpactMatrix, mu: f64) -> [f64; 4] {
    [
        mu * w.tt - w.nt,
        w.nn - mu * w.nt,
        mu * w.tt + w.nt,
        w.nn + mu * w.nt,
    ]
}

/// The sign case of [P, Table 1], columns 2–5.
fn case_of([g, h, p, q]: [f64; 4]) -> u8 {
    match (g < 0.0, h < 0.0, p < 0.0, q < 0.0) {
        (false, false, false, false) => 1,
        (false, false, false, true) => 2,
        (false, false, true, false) => 3,
        (false, true, false, false) => 4,
        (true, false, false, false) => 5,
        other => panic!("inadmissible signs {other:?}"),
    }
}

/// The type [P, Table 1] gives (laws on Routh's path), or [P, Appendix C, Ineqs. (74),
/// (77), (80)] gives (Kane–Levinson), at `a = |α| > 0` in the frame of the slip; `None`
/// within `margin` of a boundary.
///
/// Poisson and Stronge share Table 1's type columns (derived from their end conditions):
/// in forward sliding (`h > 0`) compression ends at `I_n = V/h` and both laws end at
/// `(1+e) V/h` — Poisson's `(1+e) I_c`, Stronge's restitution work `h (I − V/h)²/2 =
/// e² V²/(2h)` — exactly where Newton's `v_n = e V` is reached; so the collision ends
/// before the slip stops at `I_n(G) = α V/g` iff `α > (1+e) r_m`. After G the contact
/// sticks if `|m_nt| ≤ μ m_tt` (`g, p ≥ 0`), else slides back (`p < 0`); with `h < 0`
/// (Case 4) compression cannot end while sliding forward, so G is always reached.
fn expected(
    law: Law,
    w: ImpactMatrix,
    e: f64,
    mu: f64,
    a: f64,
    margin: f64,
) -> Option<CollisionType> {
    use CollisionType::*;
    let c = ghpq(w, mu);
    let [g, h, p, q] = c;
    if c.iter().any(|x| x.abs() < 1e-9) || a < margin {
        return None; // on a case boundary, or at α = 0
    }
    let forward = (1.0 + e) * g / h;
    let kl = -(1.0 + e) * p / q;
    let near = |b: f64| (a - b).abs() < margin * (1.0 + b.abs());
    match case_of(c) {
        1 | 2 if near(forward) => None,
        1 | 2 => Some(if a < forward {
            Sticking
        } else {
            ForwardSliding
        }),
        3 if near(forward) => None,
        3 if a > forward => Some(ForwardSliding),
        3 if law != Law::KaneLevinson => Some(ReverseSliding),
        3 if near(kl) => None,
        3 => Some(if a < kl { ReverseSliding } else { Sticking }),
        4 => Some(Sticking),
        _ => Some(ForwardSliding),
    }
}

fn map(law: Law, w: ImpactMatrix, e: f64, alpha: Axis, mu: Axis) -> RegionMap {
    RegionMap::compute(&MapSpec {
        w,
        e,
        law,
        alpha,
        mu,
    })
    .expect("a map")
}

#[test]
fn the_grid_has_the_types_of_table_1_away_from_the_boundaries() {
    let (alpha, mu) = (Axis::new(-5.0, 5.0, 101), Axis::new(0.0, 2.0, 81));
    let mut cases_seen = [false; 5];
    let mut checked = 0;
    let mut failures = Vec::new();
    for w in matrices() {
        for e in [0.0, 0.5, 1.0] {
            for law in Law::ALL {
                let m = map(law, w, e, alpha, mu);
                for (a, mu_j, cell) in m.nodes() {
                    // α < 0 is the mirrored problem: t → −t, m_nt → −m_nt.
                    let wf = if a < 0.0 { w.mirrored() } else { w };
                    let Some(want) = expected(law, wf, e, mu_j, a.abs(), 0.02) else {
                        continue;
                    };
                    cases_seen[case_of(ghpq(wf, mu_j)) as usize - 1] = true;
                    checked += 1;
                    if cell.kind() != Some(want) {
                        failures.push(format!(
                            "{law} W={w:?} e={e} α={a} μ={mu_j}: map {cell:?}, Table 1 {want:?}"
                        ));
                    }
                }
            }
        }
    }
    println!("{checked} nodes checked, cases seen {cases_seen:?}");
    assert!(
        failures.is_empty(),
        "{} failures:\n{}",
        failures.len(),
        failures[..failures.len().min(20)].join("\n")
    );
    assert_eq!(cases_seen, [true; 5], "every case of Table 1 is exercised");
    assert!(checked > 100_000, "{checked}");
}

#[test]
fn energy_grows_only_where_section_4_3_allows() {
    let (alpha, mu) = (Axis::new(-5.0, 5.0, 101), Axis::new(0.0, 2.0, 81));
    let mut newton_gains = 0;
    for w in matrices() {
        for e in [0.0, 0.3, 0.7, 0.9, 1.0] {
            for law in Law::ALL {
                for (a, mu_j, cell) in map(law, w, e, alpha, mu).nodes() {
                    let Cell::Solved { kind, energy, .. } = cell else {
                        panic!("{law} W={w:?}: a regular W never jams ({a}, {mu_j})");
                    };
                    if energy != EnergySign::Gain {
                        continue;
                    }
                    let at = format!("{law} W={w:?} e={e} α={a} μ={mu_j}");
                    // [P, Sect. 4.3]: ΔE|₃ < 0 in forward sliding (Eqs. 67, 79); a gain
                    // only in sticking or reverse sliding, and never with Poisson's or
                    // Stronge's hypothesis (Part B, and [P] Sect. 1 on Wang and Mason).
                    assert_ne!(kind, CollisionType::ForwardSliding, "{at}");
                    assert!(matches!(law, Law::Newton | Law::KaneLevinson), "{at}");
                    newton_gains += usize::from(law == Law::Newton);
                }
            }
        }
    }
    assert!(
        newton_gains > 100,
        "Newton's energy gains must show: {newton_gains}"
    );
}

#[test]
fn the_sticking_gain_at_e_1_peaks_at_the_closed_form_of_section_4_3() {
    // [P, Sect. 4.3]: with e = 1, ΔE|₁ = −½ |v_n^A|² (2α m_nt + α² m_nn)/Δ, largest at
    // α = −m_nt/m_nn, where it is ½ |v_n^A|² m_nt² / (m_nn Δ) > 0 (Case 1, inside the
    // sticking region). The pendulum's W at μ = 1 is Case 2 (q < 0), where Table 1 also
    // gives sticking below (1+e) r_m and Eq. (65) is the same.
    let w = pendulum().w();
    let peak = -w.nt / w.nn;
    let m = map(
        Law::Newton,
        w,
        1.0,
        Axis::new(0.0, 2.0 * peak, 201),
        Axis::new(0.0, 1.0, 11),
    );
    let Some(Cell::Solved {
        kind,
        delta_e,
        energy,
        ..
    }) = m.cell_at(peak, 1.0)
    else {
        panic!("no cell at the peak");
    };
    let closed = 0.5 * w.nt * w.nt / (w.nn * w.det());
    println!("ΔE at α = {peak}: map {delta_e}, closed form {closed}");
    assert_eq!(kind, CollisionType::Sticking);
    assert_eq!(energy, EnergySign::Gain);
    assert!(
        (delta_e - closed).abs() <= 1e-12 * closed,
        "{delta_e} vs {closed}"
    );
    // Its neighbours are lower (a maximum in α), along the row μ = 1.
    let j = m.spec.mu.n - 1;
    let de = |i| match m.cell(i, j) {
        Cell::Solved { delta_e, .. } => delta_e,
        Cell::Jam => f64::NAN,
    };
    assert!(de(99) < de(100) && de(101) < de(100));
}

#[test]
fn table_2_rows_fall_in_the_cells_the_map_says() {
    let golden: Golden = golden();
    let p = pendulum();
    let (w, v) = (p.w(), p.v_a());
    let alpha_p = v.t / -v.n;
    // Node 300 of 401 over [−2α, 2α] is the pendulum's α; μ = 0.2 and 0.5 are nodes 20, 50.
    let (alpha, mu) = (
        Axis::new(-2.0 * alpha_p, 2.0 * alpha_p, 401),
        Axis::new(0.0, 1.0, 101),
    );
    assert!((alpha.value(300) - alpha_p).abs() < 1e-14);
    let mut rows = 0;
    for row in &golden.row {
        let law: Law = row.law.parse().unwrap();
        let m = map(law, w, row.e, alpha, mu);
        let tag = format!("{} row {}", row.law, row.row);
        // The printed boundaries lie on the map's curves at μ, to the printed digits.
        let [fwd, mir] = m.boundaries(400);
        for (b, s) in [
            (&fwd, &row.one_plus_e_r_m),
            (&mir, &row.minus_one_plus_e_r_p),
        ] {
            let got = alpha_on(b, row.mu).unwrap_or_else(|| panic!("{tag}: {:?} misses μ", b.kind));
            let pr = printed(s);
            assert!(
                (got - pr.value).abs() <= pr.unit,
                "{tag} {:?}: {got} vs {s}",
                b.kind
            );
        }
        // The printed type and the sign of the printed ΔE (rows printed with no solution:
        // see tests/all/paper_table_2.rs).
        let (Some(kind), Some(de)) = (row.kind, &row.delta_e) else {
            continue;
        };
        let Some(Cell::Solved {
            kind: got, energy, ..
        }) = m.cell_at(alpha_p, row.mu)
        else {
            panic!("{tag}: no cell");
        };
        assert_eq!(got.number(), kind, "{tag}");
        let want = if printed(de).value > 0.0 {
            EnergySign::Gain
        } else {
            EnergySign::Loss
        };
        assert_eq!(energy, want, "{tag}: ΔE printed {de}");
        rows += 1;
    }
    assert_eq!(rows, 9, "the nine rows with a printed solution");
}

/// `α` of the boundary at `μ`, interpolated between its samples.
fn alpha_on(b: &regions::Boundary, mu: f64) -> Option<f64> {
    b.pieces.iter().find_map(|piece| {
        piece.windows(2).find_map(|s| {
            let ((a0, m0), (a1, m1)) = (s[0], s[1]);
            (m0 <= mu && mu <= m1).then(|| a0 + (a1 - a0) * (mu - m0) / (m1 - m0))
        })
    })
}

#[test]
fn the_boundaries_are_eq_36_clipped_at_their_poles() {
    // The pendulum: q = m_nn + μ m_nt vanishes at μ = 0.664 (a pole of r_p inside [0, 1]);
    // h never does. A W with m_nt > 0 puts the pole on r_m.
    for (w, pole_on) in [
        (pendulum().w(), BoundaryKind::Mirrored),
        (
            ImpactMatrix::new(0.5, 0.9, 2.0),
            BoundaryKind::ForwardSliding,
        ),
    ] {
        let e = 0.5;
        let (alpha, mu) = ((-5.0, 5.0), (0.0, 1.0));
        for kind in [BoundaryKind::ForwardSliding, BoundaryKind::Mirrored] {
            let b = regions::boundary(kind, w, e, alpha, mu, 200);
            let curve = |m: f64| {
                let [g, h, p, q] = ghpq(w, m);
                match kind {
                    BoundaryKind::ForwardSliding => ((1.0 + e) * g / h, h),
                    BoundaryKind::Mirrored => (-(1.0 + e) * p / q, q),
                }
            };
            let pole = match kind {
                BoundaryKind::ForwardSliding => w.nn / w.nt,
                BoundaryKind::Mirrored => -w.nn / w.nt,
            };
            let crossing = pole > mu.0 && pole < mu.1;
            assert_eq!(crossing, kind == pole_on, "{kind:?} {w:?}");
            assert!(!b.pieces.is_empty(), "{kind:?} {w:?}");
            for piece in &b.pieces {
                assert!(piece.len() >= 200, "{}", piece.len());
                let side = curve(piece[0].1).1.signum();
                for &(a, m) in piece {
                    let (want, denom) = curve(m);
                    assert_eq!(denom.signum(), side, "a piece never crosses the pole");
                    assert!((alpha.0..=alpha.1).contains(&a) && (mu.0..=mu.1).contains(&m));
                    assert!(
                        (a - want).abs() <= 1e-9 * (1.0 + want.abs()),
                        "{kind:?} μ={m}: {a} vs {want}"
                    );
                }
                // Monotone in μ, and each end on the window's edge or at the μ range's end.
                assert!(piece.windows(2).all(|s| s[0].1 < s[1].1));
                for &(a, m) in [piece[0], piece[piece.len() - 1]].iter() {
                    let on_edge = (a.abs() - 5.0).abs() < 1e-9 || m == mu.0 || m == mu.1;
                    assert!(on_edge, "{kind:?} end ({a}, {m}) is inside the window");
                }
            }
            if crossing {
                // Clipped on both sides of the pole: α leaves the window before it.
                assert_eq!(b.pieces.len(), 2, "{kind:?}");
                assert!(b.pieces[0].last().unwrap().1 < pole && b.pieces[1][0].1 > pole);
            }
        }
    }
}

#[test]
fn the_scene_w_is_the_closed_form_of_the_pendulum() {
    let path = Path::new(env!("CARGO_MANIFEST_DIR")).join("scenes/kane_double_pendulum.toml");
    let scene = ricochet::scene::load(&path).unwrap();
    let c = regions::scene_contact(&scene.model, &scene.initial, None).unwrap();
    let p = pendulum();
    let (w, v) = (p.w(), p.v_a());
    assert_eq!(c.name, "rodB/floor");
    for (got, want) in [
        (c.w.nn, w.nn),
        (c.w.nt, w.nt),
        (c.w.tt, w.tt),
        (c.v.n, v.n),
        (c.v.t, v.t),
    ] {
        assert!((got - want).abs() <= 1e-12, "{c:?} vs {w:?} {v:?}");
    }
    assert!((c.alpha().unwrap() - v.t / -v.n).abs() < 1e-12);
    let by_name = regions::scene_contact(&scene.model, &scene.initial, Some("0")).unwrap();
    assert_eq!(by_name, c);
    let err = regions::scene_contact(&scene.model, &scene.initial, Some("rodA/floor")).unwrap_err();
    assert!(err.to_string().contains("rodB/floor"), "{err}");
}

#[test]
fn bad_maps_are_typed_errors() {
    let w = pendulum().w();
    let (alpha, mu) = (Axis::new(-1.0, 1.0, 5), Axis::new(0.0, 1.0, 5));
    let spec = MapSpec {
        w,
        e: 0.5,
        law: Law::Newton,
        alpha,
        mu,
    };
    let bad = |s: MapSpec| RegionMap::compute(&s).unwrap_err();
    assert!(matches!(
        bad(MapSpec { e: 1.5, ..spec }),
        RegionsError::Problem(_)
    ));
    let not_psd = ImpactMatrix::new(1.0, 2.0, 1.0);
    assert!(matches!(
        bad(MapSpec { w: not_psd, ..spec }),
        RegionsError::Problem(_)
    ));
    for axis in [
        Axis::new(1.0, 1.0, 5),
        Axis::new(0.0, 1.0, 1),
        Axis::new(0.0, f64::NAN, 5),
    ] {
        assert!(matches!(
            bad(MapSpec {
                alpha: axis,
                ..spec
            }),
            RegionsError::InvalidAxis { .. }
        ));
    }
    assert!(matches!(
        bad(MapSpec {
            mu: Axis::new(-0.1, 1.0, 5),
            ..spec
        }),
        RegionsError::InvalidAxis { .. }
    ));
    // A singular W (one degree of freedom) is accepted: the laws jam where friction holds
    // the approaching contact, and those cells say so.
    // The row μ = m_nn/m_nt = 0.5 is on the grid: for α ≥ 0 (g = h = 0 there) every node
    // of it jams (`tests/all/impact_laws.rs::singular_w_with_g_and_h_zero_jams_under_every_law`);
    // for α < 0 the mirrored W has g, h > 0.
    let singular = ImpactMatrix::new(0.25, 0.5, 1.0);
    let m = map(
        Law::Newton,
        singular,
        0.5,
        Axis::new(-3.0, 3.0, 61),
        Axis::new(0.0, 2.0, 41),
    );
    assert!(m.nodes().any(|(_, _, c)| c == Cell::Jam));
    let row: Vec<Cell> = (m.nodes())
        .filter(|(alpha, mu, _)| *mu == 0.5 && *alpha >= 0.0)
        .map(|(_, _, c)| c)
        .collect();
    assert_eq!(row.len(), 31);
    assert!(row.iter().all(|&c| c == Cell::Jam), "{row:?}");
    assert!(m.nodes().any(|(_, _, c)| c.kind().is_some()));
}

/// The start tags, end tags and self-closed tags of an XML text (no comments or CDATA in
/// plotters' SVG), checked to nest; returns the count of each start or self-closed tag.
fn xml_elements(svg: &str) -> std::collections::HashMap<String, usize> {
    let mut stack = Vec::new();
    let mut counts = std::collections::HashMap::new();
    let mut rest = svg;
    while let Some(start) = rest.find('<') {
        let end = rest[start..].find('>').expect("an unclosed tag") + start;
        let tag = &rest[start + 1..end];
        rest = &rest[end + 1..];
        if tag.starts_with('?') {
            continue;
        }
        if let Some(name) = tag.strip_prefix('/') {
            assert_eq!(
                stack.pop().as_deref(),
                Some(name.trim()),
                "mismatched </{name}>"
            );
            continue;
        }
        let name = tag
            .split_whitespace()
            .next()
            .unwrap()
            .trim_end_matches('/')
            .to_owned();
        *counts.entry(name.clone()).or_insert(0) += 1;
        if !tag.ends_with('/') {
            stack.push(name);
        }
    }
    assert!(stack.is_empty(), "unclosed: {stack:?}");
    counts
}

#[test]
fn the_svg_is_well_formed_and_holds_the_map() {
    let w = pendulum().w();
    let (alpha, mu) = (Axis::new(-4.0, 4.0, 81), Axis::new(0.0, 1.0, 51));
    let newton = map(Law::Newton, w, 0.9, alpha, mu);
    let marker = regions::Marker {
        label: "row 5".into(),
        alpha: 1.99,
        mu: 0.5,
    };
    let svg = regions::render_svg(&newton, &[marker]).unwrap();
    assert!(svg.trim_start().starts_with("<svg") && svg.trim_end().ends_with("</svg>"));
    let n = xml_elements(&svg);
    println!("{n:?}");
    assert_eq!(n["svg"], 1);
    // At least one rectangle per row of μ (merged runs), plus the legend's patches.
    assert!(n["rect"] >= mu.n, "{n:?}");
    let colour = |c: plotters::style::RGBColor| format!("\"#{:02X}{:02X}{:02X}\"", c.0, c.1, c.2);
    // The boundary curves are polylines of their colours; the gain cells are there.
    for c in [
        regions::style::FORWARD_BOUNDARY,
        regions::style::MIRRORED_BOUNDARY,
    ] {
        let stroke = format!("stroke={}", colour(c));
        assert!(svg.matches(&stroke).count() >= 2, "{stroke}");
    }
    assert!(svg.contains(&format!("fill={}", colour(regions::style::REVERSE_GAIN))));
    for text in [
        "e = 0.9",
        "0.3365",
        "α = (1+e) r_m(μ)",
        "α = −(1+e) r_p(μ)",
        "row 5",
        "μ",
    ] {
        assert!(svg.contains(text), "{text}");
    }
    // Poisson's map gains nowhere, and its legend says so.
    let poisson = regions::render_svg(&map(Law::Poisson, w, 0.9, alpha, mu), &[]).unwrap();
    xml_elements(&poisson);
    assert!(poisson.contains("ΔE ≤ 0 everywhere"));
    for c in [regions::style::STICKING_GAIN, regions::style::REVERSE_GAIN] {
        assert!(!poisson.contains(&format!("fill={}", colour(c))));
    }
}

fn ricochet(dir: &Path, args: &[&str]) -> Output {
    Command::new(BIN)
        .current_dir(dir)
        .arg("regions")
        .args(args)
        .output()
        .unwrap()
}

#[test]
fn the_cli_writes_one_svg_per_law() {
    let dir = TempDir::new("writes");
    let out = ricochet(
        dir.path(),
        &[
            "--w",
            "0.3365,-0.5071,0.8134",
            "--e",
            "0.5",
            "--law",
            "newton,stronge",
            "--resolution",
            "41",
            "-o",
            "maps",
        ],
    );
    assert!(
        out.status.success(),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
    let stdout = String::from_utf8(out.stdout).unwrap();
    let files: Vec<&str> = stdout.lines().collect();
    assert_eq!(files.len(), 2, "{stdout}");
    for (f, law) in files.iter().zip(["newton", "stronge"]) {
        assert!(f.ends_with(&format!("regions_{law}.svg")), "{f}");
        xml_elements(&std::fs::read_to_string(dir.join(f)).unwrap());
    }
    // From a scene: the four laws, named after it, the scene's point marked.
    let scene = Path::new(env!("CARGO_MANIFEST_DIR")).join("scenes/kane_double_pendulum.toml");
    let out = ricochet(
        dir.path(),
        &["--scene", scene.to_str().unwrap(), "--resolution", "21"],
    );
    assert!(
        out.status.success(),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
    let stdout = String::from_utf8(out.stdout).unwrap();
    assert_eq!(stdout.lines().count(), 4, "{stdout}");
    let svg = std::fs::read_to_string(dir.join("kane_double_pendulum_kane-levinson.svg")).unwrap();
    assert!(svg.contains("α = 1.9908, μ = 0.2"), "the scene's point");
    assert!(String::from_utf8_lossy(&out.stderr).contains("rodB/floor"));
}

#[test]
fn the_cli_rejects_bad_input_with_a_clear_message() {
    let dir = TempDir::new("errors");
    let scene = Path::new(env!("CARGO_MANIFEST_DIR")).join("scenes/kane_double_pendulum.toml");
    let scene = scene.to_str().unwrap();
    let cases: [(&[&str], &str); 9] = [
        (&["--w", "1,2,1", "--e", "0.5"], "not positive semidefinite"),
        (&["--w", "1,0,1", "--e", "1.5"], "outside [0, 1]"),
        (&["--w", "1,0"], "three numbers"),
        (&["--w", "1,0,1"], "--e is required"),
        (&[], "--w"),
        (
            &["--w", "1,0,1", "--e", "0.5", "--resolution", "1"],
            "--resolution",
        ),
        (
            &["--w", "1,0,1", "--e", "0.5", "--alpha-max", "-2"],
            "--alpha-max",
        ),
        (
            &["--scene", scene, "--pair", "nope"],
            "no contact pair `nope`",
        ),
        (&["--scene", "missing.toml"], "missing.toml"),
    ];
    for (args, message) in cases {
        let out = ricochet(dir.path(), args);
        let stderr = String::from_utf8_lossy(&out.stderr);
        assert!(!out.status.success(), "{args:?} succeeded");
        assert!(stderr.contains(message), "{args:?}: {stderr}");
        assert!(out.stdout.is_empty(), "{args:?}: nothing written");
    }
    assert_eq!(
        std::fs::read_dir(dir.path()).unwrap().count(),
        0,
        "no file written"
    );
}
