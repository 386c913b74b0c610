//! The summary of a run as it goes: an [`Observer`] that keeps the ledger, the
//! checkpoints, the last sample and the energy scale, and [`run_scene`], a scene's run
//! without a log (what `golden check` does).

use serde_json::Value;

use crate::integrate::Method;
use crate::log::{Audit, Energy, ImpactRecord, LedgerNames, RunSettings};
use crate::math::Real;
use crate::model::Model;
use crate::scene::Scene;
use crate::settings::Settings;
use crate::sim::{
    ImpactEvent, Level, MaterialOverride, MoreauJean, Observer, ObserverError, RunSummary, Sample,
    Simulation,
};

use super::summary::{Parts, sample_scale};
use super::{Checkpoints, RegressError, RunOverrides, SceneId, Snapshot, Summary};

/// Keeps what a run's [`Summary`] needs while the run goes; [`Collector::finish`] makes
/// the summary. Feed it every sample and impact (it wants samples).
#[derive(Debug)]
pub struct Collector {
    names: LedgerNames,
    rule: Checkpoints,
    impacts: Vec<ImpactRecord>,
    checkpoints: Vec<Snapshot>,
    last: Option<Snapshot>,
    /// The largest `K + |V|` of the samples so far (J).
    scale: Real,
}

impl Collector {
    /// A collector for a run of `model` with `settings`, keeping about `checkpoints`
    /// checkpoints ([`Checkpoints::of`]).
    pub fn new(model: &Model, settings: &Settings, checkpoints: u64) -> Collector {
        Collector::with_rule(model, Checkpoints::of(settings, checkpoints))
    }

    /// A collector for a run of `model` keeping the checkpoints `rule` says
    /// ([`Checkpoints::Every`]: every sample, as [`Summary::from_log`] with no count keeps
    /// those of a log; the Python package's `Run` arrays).
    pub fn with_rule(model: &Model, rule: Checkpoints) -> Collector {
        Collector {
            names: LedgerNames::new(model),
            rule,
            impacts: Vec::new(),
            checkpoints: Vec::new(),
            last: None,
            scale: 0.0,
        }
    }

    /// The summary of the run of `scene` with `settings` and the material `overrides`
    /// (after the command line's overrides) that ended with `summary`.
    pub fn finish(
        self,
        scene: &Scene,
        (settings, overrides): (&Settings, &MaterialOverride),
        summary: &RunSummary,
    ) -> Summary {
        let record = RunSettings {
            settings,
            material_overrides: overrides,
        };
        let settings_map = match serde_json::to_value(record) {
            Ok(Value::Object(map)) => Some(map),
            _ => None,
        };
        let (coordinates, speeds) = super::summary::names(&scene.model);
        let parts = Parts {
            scene: Some(SceneId::new(&scene.name, &scene.text)),
            coordinates,
            speeds,
            settings: settings_map,
            audit: Some(Audit::of_run(summary)),
            max_drift: settings.max_drift,
        };
        Summary::assemble(parts, self.impacts, self.checkpoints, self.last, self.scale)
    }
}

impl Observer for Collector {
    fn sample(&mut self, _: &Model, s: &Sample<'_>) -> Result<(), ObserverError> {
        // The energies as the log's `/state` record holds them.
        let energy = Energy::new(s.energy.kinetic, s.energy.potential);
        self.scale = sample_scale(self.scale, &energy);
        let last = self.last.get_or_insert_with(|| Snapshot {
            t: s.t,
            q: Vec::new(),
            u: Vec::new(),
            energy,
        });
        last.t = s.t;
        last.q.clear();
        last.q.extend_from_slice(s.q);
        last.u.clear();
        last.u.extend_from_slice(s.u);
        last.energy = energy;
        if self.rule.keeps(s.t) {
            self.checkpoints.push(last.clone());
        }
        Ok(())
    }

    fn impact(&mut self, _: &Model, ev: &ImpactEvent) -> Result<(), ObserverError> {
        self.impacts.push(self.names.entry(ev));
        Ok(())
    }

    fn message(&mut self, _: Real, _: Level, _: &str) -> Result<(), ObserverError> {
        Ok(())
    }
}

/// Runs `scene` with `overrides`, without a log, and returns how it ended and its summary
/// with about `checkpoints` checkpoints. Errors: an override out of range, a run that
/// cannot start (its settings); a run that fails is a summary whose audit says so.
pub fn run_scene(
    scene: &Scene,
    overrides: &RunOverrides,
    checkpoints: u64,
) -> Result<(RunSummary, Summary), RegressError> {
    let mut settings = scene.settings.clone();
    let material = overrides.apply(&mut settings)?;
    let mut collector = Collector::new(&scene.model, &settings, checkpoints);
    let run = match settings.integrator.method {
        Method::MoreauJean => MoreauJean::new(&scene.model, &settings, material)
            .map(|mut mj| mj.run(&scene.initial, &mut collector, None)),
        Method::Dopri5 | Method::Dop853 | Method::Rk4 => {
            Simulation::new(&scene.model, &settings, material)
                .map(|mut sim| sim.run(&scene.initial, &mut collector, None))
        }
    }
    .map_err(|source| RegressError::Start {
        scene: scene.path.clone(),
        source: Box::new(source),
    })?;
    let summary = collector.finish(scene, (&settings, &material), &run);
    Ok((run, summary))
}
