//! A run without samples (an observer that wants none, as a sweep's) reports the same
//! impacts, messages, mode changes and summary as the same run with samples: the loop
//! then reports the pending passages to persistent contact (stamped at the end of an
//! accumulation, `t∞`) once per step, up to the last output time, instead of once per
//! output time (`Simulation::samples_until`), and must not change their order or times.

use std::path::Path;

use ricochet::scene::Scene;
use ricochet::sim::{MaterialOverride, Recorder, RunSummary, Simulation};

fn scene(path: &str) -> Scene {
    let path = Path::new(env!("CARGO_MANIFEST_DIR")).join(path);
    ricochet::scene::load(&path).unwrap_or_else(|e| panic!("{e}"))
}

fn run(scene: &Scene, samples: bool) -> (Recorder, RunSummary) {
    let mut sim =
        Simulation::new(&scene.model, &scene.settings, MaterialOverride::default()).unwrap();
    let mut rec = Recorder {
        keep_samples: samples,
        ..Recorder::default()
    };
    let summary = sim.run(&scene.initial, &mut rec, None);
    (rec, summary)
}

/// Kane's pendulum 5 s (its accumulation ends in a passage to sliding at `t∞`), and the
/// bundled scenes with persistent contact or impacts: every record but the samples is
/// the same, bit for bit; only the count of samples differs.
#[test]
fn a_run_without_samples_reports_the_same_as_with_them() {
    let mut kane = scene("scenes/kane_double_pendulum.toml");
    kane.settings.t_end = 5.0;
    kane.settings.integrator.rtol = 1e-10;
    let mut scenes = vec![("kane 5 s".to_owned(), kane)];
    for name in [
        "rocking_block",
        "rimless_wheel",
        "painleve_rod",
        "falling_rod",
        "chain",
        "newtons_cradle",
        "sled_rock",
        "wagon_curb",
    ] {
        scenes.push((name.to_owned(), scene(&format!("scenes/{name}.toml"))));
    }
    let mut passages = 0;
    for (name, s) in &scenes {
        let (with, with_summary) = run(s, true);
        let (without, mut without_summary) = run(s, false);
        assert!(
            !with.samples.is_empty() && without.samples.is_empty(),
            "{name}"
        );
        assert_eq!(without_summary.counters.samples, 0, "{name}");
        without_summary.counters.samples = with_summary.counters.samples;
        assert_eq!(
            format!("{without_summary:?}"),
            format!("{with_summary:?}"),
            "{name}: summary"
        );
        assert_eq!(
            format!("{:?}", without.impacts),
            format!("{:?}", with.impacts),
            "{name}"
        );
        assert_eq!(
            format!("{:?}", without.messages),
            format!("{:?}", with.messages),
            "{name}"
        );
        assert_eq!(
            format!("{:?}", without.transitions),
            format!("{:?}", with.transitions),
            "{name}"
        );
        let stamped = (with.transitions.iter())
            .filter(|tr| tr.t_accumulation.is_some())
            .count();
        println!(
            "{name}: {} transitions, {stamped} passages",
            with.transitions.len()
        );
        passages += stamped;
    }
    assert!(passages > 0, "no passage reported: the test sees nothing");
}
