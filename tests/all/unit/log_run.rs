//! The unit tests of `log::run` (`src/log/run.rs`).

// The source module's own imports.
use ricochet::log::LogWriter;
use ricochet::math::Pose;
use ricochet::sim::{MaterialOverride, Observer, Sample};

use std::io::Cursor;

use ricochet::log::run::*;
use ricochet::sim::Simulation;

/// The log of `scene` (in `scenes/`) run to `t_end` (s) at 100 Hz, with the samples
/// handed to the writer thread as numbers (`Some(true)`: the poses of `/tf` as numbers
/// whose rotations the writer thread computes), encoded on the simulation's thread
/// (`Some(false)`), or as the writer thread's progress decides (`None`).
fn log_of(scene: &str, t_end: f64, defer: Option<bool>) -> Vec<u8> {
    let path = std::path::Path::new(env!("CARGO_MANIFEST_DIR"))
        .join("scenes")
        .join(scene);
    let mut s = ricochet::scene::load(&path).expect("a bundled scene");
    s.settings.t_end = t_end;
    s.settings.output_rate = 100.0;
    let over = MaterialOverride::default();
    let mut sim = Simulation::new(&s.model, &s.settings, over).expect("a run");
    let mut writer =
        LogWriter::new(Cursor::new(Vec::new()), Default::default()).expect("a log in memory");
    writer.defer_samples(defer);
    let mut log = RunLogger::for_scene(writer, &s, &over, sim.scales().gap_tol).expect("a logger");
    let summary = sim.run(&s.initial, &mut log, None);
    log.finish(&summary).expect("finished").into_inner()
}

/// A sample whose poses hold a NaN or an infinity meets the same outcome whether the
/// `/tf` poses would go to the writer thread as numbers or be encoded here: a NaN
/// position is refused with the same error (naming the transform's field), at the same
/// call; an infinite rotation part (a finite angle, `atan2`) is written as before.
/// Either way the log holds the same bytes.
#[test]
fn non_finite_poses_meet_the_same_outcome_either_way() {
    let path =
        std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("scenes/kane_double_pendulum.toml");
    let s = ricochet::scene::load(&path).expect("a bundled scene");
    let over = MaterialOverride::default();
    let gap_tol = Simulation::new(&s.model, &s.settings, over)
        .expect("a run")
        .scales()
        .gap_tol;
    let poses_of = |k: usize| {
        let mut poses = [Pose::identity(); 2];
        poses[1].translation.x = 0.5;
        match k {
            0 => poses[0].translation.x = f64::NAN,
            1 => poses[1].translation.y = f64::INFINITY,
            2 => poses[1].rotation.re = f64::INFINITY,
            3 => poses[0].rotation.im = f64::NEG_INFINITY,
            _ => {}
        }
        poses
    };
    let run = |defer: Option<bool>| {
        let mut writer =
            LogWriter::new(Cursor::new(Vec::new()), Default::default()).expect("a log in memory");
        writer.defer_samples(defer);
        let mut log = RunLogger::for_scene(writer, &s, &over, gap_tol).expect("a logger");
        let (q, u) = (s.initial.q.as_slice(), s.initial.u.as_slice());
        let outcomes: Vec<String> = (0..6)
            .map(|k| {
                let poses = poses_of(k);
                let sample = Sample {
                    t: 0.01 * k as f64,
                    q,
                    u,
                    energy: ricochet::dynamics::Energy {
                        kinetic: 1.0,
                        potential: -2.0,
                    },
                    pairs: &[],
                    gaps: &[],
                    poses: &poses,
                    at_impact: false,
                    modes: &[],
                    slips: &[],
                    contact_stages: 0,
                };
                match log.sample(&s.model, &sample) {
                    Ok(()) => "ok".to_owned(),
                    Err(e) => ricochet::sim::describe(&*e),
                }
            })
            .collect();
        let bytes = log.writer.finish().expect("finished").into_inner();
        (outcomes, bytes)
    };
    let (here, here_bytes) = run(Some(false));
    assert!(
        here[0].contains("non-finite `transforms[0].translation.x` in /tf"),
        "{here:?}"
    );
    assert!(
        here[1].contains("non-finite `transforms[1].translation.y` in /tf"),
        "{here:?}"
    );
    assert_eq!(here[2..], ["ok", "ok", "ok", "ok"]);
    let (numbers, numbers_bytes) = run(Some(true));
    assert_eq!(numbers, here);
    assert!(numbers_bytes == here_bytes);
}

/// A run's log is the same bytes whether its samples (the `/tf` poses among them) go to
/// the writer thread as numbers, are encoded on the simulation's thread, or either as
/// the writer thread keeps up: scenes of one to seven bodies, with impacts, sliding
/// contacts and a view that follows the mechanism.
#[test]
fn samples_as_numbers_or_encoded_here_give_the_same_log() {
    for (scene, t_end) in [
        ("kane_double_pendulum.toml", 2.0),
        ("chain_floor.toml", 0.5),
        ("rimless_wheel.toml", 1.0),
        ("newtons_cradle.toml", 0.5),
    ] {
        let here = log_of(scene, t_end, Some(false));
        assert!(here.len() > 10_000, "{scene}: {} bytes", here.len());
        assert!(
            log_of(scene, t_end, Some(true)) == here,
            "{scene}: as numbers"
        );
        assert!(log_of(scene, t_end, None) == here, "{scene}: either");
    }
}
