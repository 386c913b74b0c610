//! Issue 12: a run whose steps keep shrinking at t = 0 never failed on its step size —
//! the smallest step was 10 ε |t|, which is 0 at t = 0 — and ran for ever. The floor is
//! now 10 ε t_end: the run fails at once, naming the time and the step.

use std::sync::Arc;
use std::sync::atomic::{AtomicBool, Ordering};
use std::time::Duration;

use parry2d_f64::shape::SharedShape;
use ricochet::math::{Pose, Vec2};
use ricochet::model::{Body, Collider, Joint, JointForce, Model};
use ricochet::settings::Settings;
use ricochet::sim::{MaterialOverride, NullObserver, Simulation, StopReason};
use ricochet::state::State;

#[test]
fn a_run_stuck_at_the_start_fails_on_its_step_size() {
    // A pendulum on a spring of 1e250 N·m/rad (the library takes it; a scene file would
    // refuse it): its period is 1e-125 s, so DOPRI5's steps shrink towards 1e-126 s and
    // the run cannot leave t = 0.
    let mut b = Model::builder();
    let mut joint = Joint::revolute("arm", None, Pose::IDENTITY);
    joint.force = JointForce {
        stiffness: 1e250,
        ..JointForce::default()
    };
    let id = b.add_body(Body::new("arm", 1.0, Vec2::new(0.0, -0.5), 0.1), joint);
    b.add_collider(Collider::new(
        "arm",
        Some(id),
        SharedShape::ball(0.1),
        Pose::IDENTITY,
    ));
    let model = b.build().unwrap();
    let settings = Settings {
        t_end: 1.0,
        ..Settings::default()
    };
    let initial = State::new(0.0, vec![0.1].into(), vec![0.0].into());
    let stop = Arc::new(AtomicBool::new(false));
    let watch = Arc::clone(&stop);
    std::thread::spawn(move || {
        std::thread::sleep(Duration::from_secs(60));
        watch.store(true, Ordering::SeqCst);
    });
    let mut sim = Simulation::new(&model, &settings, MaterialOverride::default()).unwrap();
    let summary = sim.run(&initial, &mut NullObserver, Some(&stop));
    println!("{}", summary.stop);
    match &summary.stop {
        StopReason::Failed(e) => {
            let shown = e.to_string();
            assert!(shown.contains("step"), "{shown}");
        }
        other => panic!("expected a failure on the step size, got {other}"),
    }
    assert!(summary.state.t < 1e-9, "t = {}", summary.state.t);
}
