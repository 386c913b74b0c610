//! The log of a simulation run: the [`Observer`] that writes a run's samples, impacts and
//! messages to an MCAP file, with the scene drawn for Foxglove's 3D panel.

use std::io::{Seek, Write};

use serde::Serialize;

use super::draw::{self, ArrowStyle, DrawStyle, ShapeDrawing};
use super::foxglove::{Color, Pose as FoxglovePose, Time};
use super::{
    Audit, ContactMode, ContactState, Counters, Energy, FrameTransforms, ImpactCause, ImpactRecord,
    LogError, LogLevel, LogWriter, Planar, SceneUpdate, StateRecord,
};
use crate::math::{Real, Vec2};
use crate::model::Model;
use crate::settings::Settings;
use crate::sim::{
    ImpactEvent, Level, MaterialOverride, Observer, ObserverError, PairMode, RunSummary, Sample,
    StopReason,
};

/// Colours of the bodies, in body order (cycled).
const PALETTE: [(f64, f64, f64); 6] = [
    (0.27, 0.51, 0.71),
    (0.87, 0.56, 0.20),
    (0.35, 0.65, 0.35),
    (0.75, 0.30, 0.35),
    (0.55, 0.45, 0.70),
    (0.55, 0.40, 0.30),
];

/// Colour of the obstacles.
const OBSTACLE: (f64, f64, f64) = (0.6, 0.6, 0.6);

/// Writes a run to an MCAP log as it goes: `/state` and `/tf` at each sample, `/impacts`
/// and an impulse arrow on `/scene` at each impact, `/log` for messages; the scene text,
/// the settings and, at the end, the energy audit as metadata.
pub struct RunLogger<W: Write + Seek + Send + 'static> {
    writer: LogWriter<W>,
    /// Pair names `<collider a>/<collider b>`, in pair order.
    pairs: Vec<String>,
    /// Body names of each pair's two sides (`world` for an obstacle).
    sides: Vec<(String, String)>,
    /// A contact is drawn as closed when its gap is at most this (m).
    gap_tol: Real,
    impacts: u64,
    arrow: ArrowStyle,
    /// The `/state` record, updated in place at each sample (no allocation).
    state: StateRecord,
    /// The `/tf` message, updated in place at each sample.
    tf: FrameTransforms,
}

impl<W: Write + Seek + Send + 'static> RunLogger<W> {
    /// Starts the log of a run of `model`: writes the scene (`name`, file `text`), the
    /// `settings` with the material `overrides` (so that the log describes the run it
    /// holds), and the bodies and obstacles on `/scene` at `t0`.
    pub fn new(
        mut writer: LogWriter<W>,
        model: &Model,
        (name, text): (&str, &str),
        (settings, overrides): (&Settings, &MaterialOverride),
        t0: Real,
        gap_tol: Real,
    ) -> Result<Self, LogError> {
        #[derive(Serialize)]
        struct AsRun<'a> {
            #[serde(flatten)]
            settings: &'a Settings,
            material_overrides: &'a MaterialOverride,
        }
        writer.scene(name, text)?;
        writer.settings(&AsRun {
            settings,
            material_overrides: overrides,
        })?;
        let bodies: Vec<String> = model.bodies().iter().map(|b| b.name.clone()).collect();
        let side = |c: crate::model::ColliderId| -> String {
            model.colliders()[c.index()]
                .body
                .map_or_else(|| "world".to_owned(), |b| bodies[b.index()].clone())
        };
        let pairs: Vec<String> = model
            .pairs()
            .iter()
            .map(|p| {
                let (a, b) = (
                    &model.colliders()[p.a.index()],
                    &model.colliders()[p.b.index()],
                );
                format!("{}/{}", a.name, b.name)
            })
            .collect();
        let sides = model
            .pairs()
            .iter()
            .map(|p| (side(p.a), side(p.b)))
            .collect();
        writer.scene_update(t0, &scene_entities(model, &bodies, t0)?)?;
        let contacts = (pairs.iter())
            .map(|name| ContactState::new(name.clone(), ContactMode::Free, 0.0))
            .collect();
        let state = StateRecord::new(t0, vec![], vec![], Energy::new(0.0, 0.0), contacts, 0);
        let identity = crate::math::Pose::identity();
        let tf = draw::body_transforms(t0, bodies.iter().map(|b| (b.as_str(), identity)))?;
        Ok(Self {
            writer,
            pairs,
            sides,
            gap_tol,
            impacts: 0,
            arrow: ArrowStyle::default(),
            state,
            tf,
        })
    }

    /// Ends the log: writes the energy audit of `summary` and finishes the file.
    pub fn finish(mut self, summary: &RunSummary) -> Result<W, LogError> {
        let a = &summary.audit;
        let c = &summary.counters;
        let stop = match &summary.stop {
            StopReason::Failed(e) => format!("error: {e}"),
            other => format!("{}: {other}", other.name()),
        };
        let audit = Audit::new(
            stop,
            summary.state.t,
            (a.initial.total(), a.end.total()),
            (
                a.impact_delta_e,
                a.damping_work + a.applied_work,
                a.contact_work,
                a.impact_prescribed_work + a.drive_work,
            ),
            Counters {
                impacts: c.impacts,
                steps: c.steps,
                rejected_steps: c.rejected,
                rhs_evaluations: c.rhs_evals,
                events: c.events,
                state_samples: c.samples,
            },
        );
        self.writer.audit(&audit)?;
        self.writer.finish()
    }

    /// Flushes what is written so far (the log stays readable if the process dies).
    pub fn flush(&mut self) -> Result<(), LogError> {
        self.writer.flush()
    }
}

/// The bodies (frame-locked to their frames) and the obstacles (in `world`).
fn scene_entities(model: &Model, bodies: &[String], t: Real) -> Result<SceneUpdate, LogError> {
    let style = DrawStyle::default();
    let mut entities = Vec::new();
    for (k, name) in bodies.iter().enumerate() {
        let (r, g, b) = PALETTE[k % PALETTE.len()];
        let shapes: Vec<ShapeDrawing<'_>> = model
            .colliders()
            .iter()
            .filter(|c| c.body.is_some_and(|b| b.index() == k))
            .map(|c| ShapeDrawing {
                shape: &*c.shape.0,
                pose: c.pose,
                color: Color::rgba(r, g, b, 1.0),
            })
            .collect();
        entities.push(draw::body_entity(t, name, &shapes, &style)?);
    }
    for c in model.colliders().iter().filter(|c| c.body.is_none()) {
        let (r, g, b) = OBSTACLE;
        let shape = ShapeDrawing {
            shape: &*c.shape.0,
            pose: c.pose,
            color: Color::rgba(r, g, b, 1.0),
        };
        entities.push(draw::obstacle_entity(t, &c.name, &[shape], &style)?);
    }
    Ok(SceneUpdate {
        deletions: vec![],
        entities,
    })
}

fn planar(v: Vec2) -> Planar {
    Planar { x: v.x, y: v.y }
}

impl<W: Write + Seek + Send + 'static> Observer for RunLogger<W> {
    fn sample(&mut self, _model: &Model, s: &Sample<'_>) -> Result<(), ObserverError> {
        // `/state`: the cached record with this sample's numbers.
        let rec = &mut self.state;
        rec.t = s.t;
        rec.q.clear();
        rec.q.extend_from_slice(s.q);
        rec.u.clear();
        rec.u.extend_from_slice(s.u);
        rec.energy = Energy::new(s.energy.kinetic, s.energy.potential);
        for ((c, &gap), mode) in rec.contacts.iter_mut().zip(s.gaps).zip(s.modes) {
            c.mode = if s.at_impact && gap <= self.gap_tol {
                ContactMode::Impact
            } else {
                match mode {
                    PairMode::Free => ContactMode::Free,
                    PairMode::Sticking => ContactMode::Sticking,
                    PairMode::Sliding => ContactMode::Sliding,
                    PairMode::Impact => ContactMode::Impact,
                }
            };
            c.mode_code = c.mode.code();
            c.gap = gap;
        }
        rec.mode = ContactMode::of_run(rec.contacts.iter().map(|c| c.mode));
        rec.mode_code = rec.mode.code();
        rec.impact_count = self.impacts;
        self.writer.state(&self.state)?;
        // `/tf`: the cached transforms with this sample's poses.
        let time = Time::from_seconds(s.t)?;
        for (tf, pose) in self.tf.transforms.iter_mut().zip(s.poses) {
            let p = FoxglovePose::planar(
                pose.translation.x,
                pose.translation.y,
                pose.rotation.angle(),
            );
            tf.timestamp = time;
            tf.translation = p.position;
            tf.rotation = p.orientation;
        }
        self.writer.transforms(s.t, &self.tf)?;
        Ok(())
    }

    fn impact(&mut self, _model: &Model, ev: &ImpactEvent) -> Result<(), ObserverError> {
        let k = ev.frame.pair.index();
        let (out, c) = (&ev.outcome, &ev.outcome.coefficients);
        let record = ImpactRecord {
            t: ev.t,
            pair: self.pairs[k].clone(),
            body_a: self.sides[k].0.clone(),
            body_b: self.sides[k].1.clone(),
            law: out.law,
            impact_type: out.kind,
            case: out.case.number(),
            alpha: c.alpha(),
            w: ev.w,
            g: c.g,
            h: c.h,
            p: c.p,
            q: c.q,
            v_a: ev.v_a,
            v_s: out.v_s,
            i_n: out.impulse.n,
            i_t: out.impulse.t,
            delta_u: ev.delta_u.clone(),
            energy_before: ev.energy_before.total(),
            energy_after: ev.energy_after.total(),
            delta_e: out.delta_e,
            work_n: out.work_n,
            work_t: out.work_t,
            index: ev.index,
            cause: match ev.cause {
                crate::sim::ImpactCause::Collision => ImpactCause::Collision,
                crate::sim::ImpactCause::Simultaneous => ImpactCause::Simultaneous,
                crate::sim::ImpactCause::WithoutCollision => ImpactCause::WithoutCollision,
                crate::sim::ImpactCause::AccumulationEnd => ImpactCause::AccumulationEnd,
            },
            e: ev.material.e,
            mu: ev.material.mu,
            prescribed_work: ev.prescribed_work(),
            point: planar(ev.frame.point()),
            normal: planar(ev.frame.n),
            tangent: planar(ev.frame.t),
        };
        self.writer.impact(&record)?;
        let arrow = draw::impulse_arrow(&record, &self.arrow)?;
        self.writer.scene_update(
            ev.t,
            &SceneUpdate {
                deletions: vec![],
                entities: vec![arrow],
            },
        )?;
        self.impacts += 1;
        Ok(())
    }

    fn message(&mut self, t: Real, level: Level, text: &str) -> Result<(), ObserverError> {
        let level = match level {
            Level::Info => LogLevel::Info,
            Level::Warning => LogLevel::Warning,
            Level::Error => LogLevel::Error,
        };
        self.writer.log(t, level, text)?;
        Ok(())
    }
}
