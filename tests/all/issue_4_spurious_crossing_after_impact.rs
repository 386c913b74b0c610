//! Regression (issue 4): right after an impact, the gap's rounding noise (about 1e-15 m at a
//! few metres from the origin) exceeds the true separation during the first tiny step, so
//! the event locator saw a "crossing" on a contact that was separating, and the run
//! stopped with "the contact closed without approaching" (`kane_double_pendulum` with
//! `--e 0.9 --mu 0.5` at t = 1.1275 s, 1.1e-13 s after an impact leaving 8.4e-4 m/s).
//! Such an event now disarms the pair until it is clearly open, and the run goes on to
//! the genuine accumulation of impacts, which ends (issue 5) with the end of the rod
//! resting on the floor, and then to the end time.

use ricochet::sim::{ImpactCause, MaterialOverride, PairMode, Recorder, Simulation, StopReason};

#[test]
fn the_run_goes_on_to_the_genuine_accumulation() {
    let scene = ricochet::scene::load(concat!(
        env!("CARGO_MANIFEST_DIR"),
        "/scenes/kane_double_pendulum.toml"
    ))
    .unwrap();
    for (e, mu) in [(0.9, 0.5), (0.9, 0.2)] {
        let overrides = MaterialOverride {
            e: Some(e),
            mu: Some(mu),
            ..Default::default()
        };
        let mut sim = Simulation::new(&scene.model, &scene.settings, overrides).unwrap();
        let mut rec = Recorder::default();
        let summary = sim.run(&scene.initial, &mut rec, None);
        assert!(
            matches!(summary.stop, StopReason::EndTime),
            "e {e} μ {mu}: {}",
            summary.stop
        );
        // The genuine accumulation: the hop after its last impact would have been slower
        // than the resting speed; that impact was made plastic (e = 0, cause
        // accumulation_end) and the contact stayed on, in the mode it enters (it slides
        // or sticks), reported at the extrapolated end of the hops t∞.
        let end = (rec.transitions.iter())
            .find(|tr| tr.t_accumulation.is_some())
            .unwrap_or_else(|| panic!("e {e} μ {mu}: no accumulation"));
        assert_eq!(end.from, PairMode::Free, "e {e} μ {mu}");
        assert!(
            matches!(end.to, PairMode::Sliding | PairMode::Sticking),
            "e {e} μ {mu}: {:?}",
            end.to
        );
        assert_eq!(Some(end.t), end.t_accumulation);
        let closing: Vec<_> = rec.impacts.iter().filter(|i| i.material.e == 0.0).collect();
        assert_eq!(closing.len(), 1, "e {e} μ {mu}");
        assert_eq!(closing[0].cause, ImpactCause::AccumulationEnd);
        assert!(closing[0].v_a.n < 0.0 && closing[0].outcome.impulse.n > 0.0);
        assert!(closing[0].t < end.t, "e {e} μ {mu}");
        let before = rec.impacts.iter().filter(|i| i.material.e > 0.0).count();
        assert!(before > 20, "e {e} μ {mu}: {before} impacts");
        // Every impact of the law approached: none was applied to a separating contact.
        assert!(
            (rec.impacts.iter())
                .filter(|i| i.material.e > 0.0)
                .all(|i| i.v_a.n < 0.0)
        );
    }
}
