//! The golden files of the bundled scenes (`tests/golden/scenes/*.golden.json`), checked
//! by the test suite through the command a user runs, and the evidence for their
//! tolerances.
//!
//! Checked here:
//! - `ricochet golden check --dir tests/golden/scenes`: exit 0, one `ok` line per bundled
//!   scene;
//! - each file's tolerances absorb the scene run from its initial state moved by one ulp
//!   (each way, in `q` and in `u`: libm's `sin` and `cos` differ between platforms in their
//!   last bits) with two decades to spare, and see a relative change of 1e-7 of the initial
//!   coordinates. The table it prints (`--nocapture`) is the measurement behind the
//!   tolerances chosen in `ARCHITECTURE.md`.

use std::path::PathBuf;
use std::process::{Command, Stdio};

use ricochet::math::Real;
use ricochet::regress::golden::{self, Golden};
use ricochet::regress::{Kind, Summary, Tolerances, compare, run_scene};

const BIN: &str = env!("CARGO_BIN_EXE_ricochet");

fn repo(rel: &str) -> PathBuf {
    PathBuf::from(env!("CARGO_MANIFEST_DIR")).join(rel)
}

/// The bundled scenes' files.
fn bundled() -> usize {
    (std::fs::read_dir(repo("scenes")).unwrap())
        .filter(|e| (e.as_ref().unwrap().path().extension()).is_some_and(|x| x == "toml"))
        .count()
}

#[test]
fn the_bundled_scenes_hold_their_golden_files() {
    let golden = repo("tests/golden/scenes");
    // From another folder: the scene paths are relative to the golden files.
    let out = Command::new(BIN)
        .args(["golden", "check", "--dir", golden.to_str().unwrap()])
        .current_dir(std::env::temp_dir())
        .stdin(Stdio::null())
        .output()
        .unwrap();
    let stdout = String::from_utf8(out.stdout).unwrap();
    assert_eq!(
        out.status.code(),
        Some(0),
        "{stdout}{}",
        String::from_utf8_lossy(&out.stderr)
    );
    let n = bundled();
    assert_eq!(
        stdout.lines().filter(|l| l.starts_with("ok ")).count(),
        n,
        "{stdout}"
    );
    assert!(stdout.contains(&format!("{n} golden files in")), "{stdout}");
}

/// The golden files of the bundled scenes, with what they hold.
fn goldens() -> Vec<(PathBuf, Golden)> {
    let files = golden::golden_files(&repo("tests/golden/scenes")).unwrap();
    assert_eq!(files.len(), bundled(), "one golden file per bundled scene");
    (files.into_iter())
        .map(|f| {
            let g = Golden::read(&f).unwrap();
            (f, g)
        })
        .collect()
}

/// The smallest power of ten `rtol` (from 1e-15) within which `b` matches `a`, with the
/// default `time_tol` and the golden file's `atol` (the default but for the rimless wheel,
/// whose quantities that are zero in theory carry the integration's drift: see
/// ARCHITECTURE.md); `None` beyond 1.
fn needed_rtol(a: &Summary, b: &Summary, atol: Real) -> Option<Real> {
    (0..16).map(|k| 10f64.powi(k - 15)).find(|&rtol| {
        let tol = Tolerances {
            rtol,
            atol,
            ..Tolerances::default()
        };
        compare(a, b, &tol).within
    })
}

#[test]
fn each_golden_files_tolerances_absorb_a_one_ulp_change_and_catch_1e_7() {
    // The independent evidence for the tolerances: libm's sin and cos differ between
    // platforms in their last bits. A one-ulp change of the initial state, each way, in q
    // and in u (a zero becomes ±5e-324, which flips the tangent of a first impact without
    // tangential speed) stands for it; each scene's tolerances must absorb it with room to
    // spare, and still see a change of 1e-7 in the initial coordinates.
    let mut table = Vec::new();
    for (path, g) in goldens() {
        let scene = ricochet::scene::load(g.scene_path(&path)).unwrap();
        let (_, base) = run_scene(&scene, &g.overrides, g.checkpoints).unwrap();
        let (mut worst, mut worst_dt): (Real, Real) = (0.0, 0.0);
        for (which, up) in [("q", true), ("q", false), ("u", true), ("u", false)] {
            let mut s = scene.clone();
            let v = if which == "q" {
                &mut s.initial.q
            } else {
                &mut s.initial.u
            };
            for x in v.iter_mut() {
                *x = if up { x.next_up() } else { x.next_down() };
            }
            let (_, moved) = run_scene(&s, &g.overrides, g.checkpoints).unwrap();
            let c = compare(&base, &moved, &g.tolerances);
            assert!(
                c.within,
                "{}: one ulp in {which} moves the run beyond its tolerances: {}",
                path.display(),
                c.first.map(|f| f.to_text()).unwrap_or_default()
            );
            let need = needed_rtol(&base, &moved, g.tolerances.atol).unwrap();
            worst = worst.max(need);
            // Room to spare: two decades below the file's rtol.
            assert!(
                need <= g.tolerances.rtol / 100.0,
                "{}: one ulp in {which} needs rtol {need:e}",
                path.display()
            );
            let times = (c.quantities.iter()).filter(|q| q.kind == Kind::Time);
            let dt = times.map(|q| q.max_abs).fold(0.0, Real::max);
            assert!(
                dt <= g.tolerances.time_tol / 100.0,
                "{}: {dt:e} s",
                path.display()
            );
            worst_dt = worst_dt.max(dt);
        }
        let mut s = scene.clone();
        for x in s.initial.q.iter_mut() {
            *x *= 1.0 + 1e-7;
        }
        let (_, moved) = run_scene(&s, &g.overrides, g.checkpoints).unwrap();
        let c = compare(&base, &moved, &g.tolerances);
        assert!(
            !c.within,
            "{}: a change of 1e-7 goes unseen",
            path.display()
        );
        table.push(format!(
            "{:24} rtol {:e}, time_tol {:e} s: one ulp needs {worst:e}, moves times {worst_dt:.1e} s",
            scene.name, g.tolerances.rtol, g.tolerances.time_tol
        ));
    }
    println!("{}", table.join("\n"));
}
