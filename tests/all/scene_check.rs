//! `ricochet check SCENE`: the JSON it prints for a good scene, and the exit status and
//! message for a bad one.

use std::process::Command;

use serde_json::Value;

fn check(path: &str) -> std::process::Output {
    Command::new(env!("CARGO_BIN_EXE_ricochet"))
        .args(["check", path])
        .current_dir(env!("CARGO_MANIFEST_DIR"))
        .output()
        .unwrap()
}

#[test]
fn check_prints_coordinates_state_mass_matrix_and_energies() {
    let out = check("scenes/kane_double_pendulum.toml");
    assert!(
        out.status.success(),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
    let v: Value = serde_json::from_slice(&out.stdout).unwrap();
    assert_eq!(v["scene"], "kane_double_pendulum");
    assert_eq!(v["coordinates"], serde_json::json!(["rodA.q", "rodB.q"]));
    assert_eq!(v["units"], serde_json::json!(["rad", "rad"]));
    let deg = std::f64::consts::PI / 180.0;
    assert_eq!(v["q"], serde_json::json!([20.0 * deg, 30.0 * deg]));
    assert_eq!(v["u"], serde_json::json!([-0.1, -0.2]));
    // M = m l² [[4/3, ½ cos 10°], [½ cos 10°, 1/3]], m l² = 12 kg·m².
    let m = &v["mass_matrix"];
    let expected = [
        [16.0, 6.0 * (10.0 * deg).cos()],
        [6.0 * (10.0 * deg).cos(), 4.0],
    ];
    for r in 0..2 {
        for c in 0..2 {
            assert!(
                (m[r][c].as_f64().unwrap() - expected[r][c]).abs() < 1e-12,
                "M = {m}"
            );
        }
    }
    // T = ½ uᵀ M u; V = −(3/2) m g l cos q1 − ½ m g l cos q2.
    let (u1, u2) = (-0.1, -0.2);
    let t = 0.5 * (16.0 * u1 * u1 + 2.0 * expected[0][1] * u1 * u2 + 4.0 * u2 * u2);
    let vpot = -(1.5 * 3.0 * 9.81 * 2.0 * (20.0 * deg).cos()
        + 0.5 * 3.0 * 9.81 * 2.0 * (30.0 * deg).cos());
    let e = &v["energy"];
    assert!((e["kinetic"].as_f64().unwrap() - t).abs() < 1e-12);
    assert!((e["potential"].as_f64().unwrap() - vpot).abs() < 1e-12);
    assert!((e["total"].as_f64().unwrap() - (t + vpot)).abs() < 1e-12);
    assert!(v["pairs"][0]["gap"].as_f64().unwrap().abs() < 1e-15);
}

#[test]
fn check_fails_with_the_location_of_the_error() {
    let dir = std::env::temp_dir().join(format!("ricochet-check-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    let path = dir.join("bad.toml");
    std::fs::write(
        &path,
        "version = 1\nname = \"x\"\n[run]\nt_end = 1.0\n[[body]]\nname = \"b\"\nmass = 1.0\ninertia = 0.1\njoint = { type = \"revolute\", angle = 20 }\n",
    )
    .unwrap();
    let out = check(path.to_str().unwrap());
    assert!(!out.status.success());
    assert!(out.stdout.is_empty());
    let err = String::from_utf8_lossy(&out.stderr);
    assert!(
        err.contains("bad.toml:9:38: body[\"b\"].joint.angle: an angle needs its unit"),
        "{err}"
    );
    std::fs::remove_dir_all(&dir).ok();
}

/// A chain of `links` links (scenes/chain.toml) written to a temporary file.
fn chain_file(links: usize) -> std::path::PathBuf {
    let text = std::fs::read_to_string(concat!(env!("CARGO_MANIFEST_DIR"), "/scenes/chain.toml"))
        .unwrap()
        .replace("links = 8", &format!("links = {links}"));
    let path = std::env::temp_dir().join(format!(
        "ricochet_check_chain_{}_{links}.toml",
        std::process::id()
    ));
    std::fs::write(&path, text).unwrap();
    path
}

#[test]
fn check_of_a_big_chain_omits_the_mass_matrix_and_lists_the_overlapping_pairs() {
    // 120 links: 120 speeds (> 100) and 120·119/2 − 119 link pairs + 120 with the floor.
    let path = chain_file(120);
    let out = check(path.to_str().unwrap());
    assert!(
        out.status.success(),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
    let v: Value = serde_json::from_slice(&out.stdout).unwrap();
    let total = 120 * 119 / 2 - 119 + 120;
    assert!(v.get("mass_matrix").is_none());
    assert_eq!(v["pairs_total"], total);
    assert_eq!(v["omitted"].as_array().unwrap().len(), 2);
    let listed = v["pairs"].as_array().unwrap();
    // The straight chain's capsules overlap only their neighbours' boxes (hinged, no
    // pair): the listed pairs are the 120 links with the floor, 1.5 − 0.02 m below.
    assert_eq!(listed.len(), 120);
    for p in listed {
        assert_eq!(p["b"], "floor");
        assert!((p["gap"].as_f64().unwrap() - 1.48).abs() < 1e-12, "{p}");
    }

    // --full: the whole matrix and every pair; each pair left out above is apart.
    let out = Command::new(env!("CARGO_BIN_EXE_ricochet"))
        .args(["check", "--full", path.to_str().unwrap()])
        .output()
        .unwrap();
    assert!(out.status.success());
    let full: Value = serde_json::from_slice(&out.stdout).unwrap();
    let m = full["mass_matrix"].as_array().unwrap();
    assert_eq!((m.len(), m[0].as_array().unwrap().len()), (120, 120));
    assert!(full.get("pairs_total").is_none() && full.get("omitted").is_none());
    let all = full["pairs"].as_array().unwrap();
    assert_eq!(all.len(), total);
    for p in all {
        if p["b"] == "floor" {
            assert!(listed.contains(p));
        } else {
            assert!(p["gap"].as_f64().unwrap() > 0.2, "{p}");
        }
    }
    std::fs::remove_file(path).unwrap();
}
