//! The log of a simulation run: the [`Observer`] that writes a run's samples, impacts and
//! messages to an MCAP file, with the scene drawn for Foxglove's 3D panel.

use std::io::{Seek, Write};

use parry2d_f64::bounding_volume::{Aabb, BoundingVolume};
use serde::Serialize;

use super::draw::{self, ArrowScale, ArrowStyle, DrawStyle, ShapeDrawing, ViewTracker};
use super::foxglove::{Color, about_z, rgba, timestamp, vector3};
use super::writer::log_message;
use super::{
    Audit, ContactMode, ContactState, Counters, Energy, FrameTransforms, ImpactCause, ImpactRecord,
    Log, LogError, LogLevel, LogWriter, Planar, SceneUpdate, StateRecord, SupportRecord,
};
use crate::math::{Pose, Real, Vec2};
use crate::model::{Model, PairId};
use crate::scene::Scene;
use crate::settings::Settings;
use crate::sim::{
    ImpactEvent, Level, MaterialOverride, Observer, ObserverError, PairMode, RunSummary, Sample,
    StopReason,
};
use crate::state::{Data, State};

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
const OBSTACLE: Color = rgba(0.6, 0.6, 0.6, 1.0);

/// Receives what a [`RunLogger`] writes, message by message, as it writes it: a second
/// destination of the run, such as the live view (`ricochet run --live`, feature `live`).
/// Publishing cannot fail the run; a tap reports its own trouble.
pub trait Tap: Send {
    /// The drawing of every body and obstacle (`/geometry`), at the start of the run, or at
    /// once when the tap is attached later.
    fn geometry(&mut self, t: Real, update: &SceneUpdate);
    /// A sample: its `/state` record and its `/tf` transforms.
    fn sample(&mut self, state: &StateRecord, transforms: &FrameTransforms);
    /// An impact: its ledger entry and its drawing (`/scene`).
    fn impact(&mut self, impact: &ImpactRecord, drawing: &SceneUpdate);
    /// A `/log` message.
    fn log(&mut self, log: &Log);
    /// The run has ended and its log is finished.
    fn finish(&mut self) {}
}

/// Writes a run to an MCAP log as it goes: the bodies and obstacles on `/geometry` at the
/// start; `/state` and `/tf` at each sample; `/impacts`, an impulse arrow on `/scene` and a
/// line on `/log` at each impact; `/log` for messages; the scene text, the settings and,
/// at the end, the energy audit as metadata.
pub struct RunLogger<W: Write + Seek + Send + 'static> {
    #[doc(hidden)]
    pub writer: LogWriter<W>,
    /// The names that ledger entries carry.
    names: LedgerNames,
    /// A contact is drawn as closed when its gap is at most this (m).
    gap_tol: Real,
    impacts: u64,
    arrow: ArrowStyle,
    arrow_scale: ArrowScale,
    /// Bounding box of each body in its own frame: its shapes and its skeleton (m).
    local_boxes: Vec<Aabb>,
    /// The `view` frame that keeps the mechanism in view.
    view: ViewTracker,
    /// The `/state` record, updated in place at each sample (no allocation while the
    /// sample lists the same pairs).
    state: StateRecord,
    /// The pairs of `state.contacts`.
    listed: Vec<PairId>,
    /// The `/tf` message, updated in place at each sample: a transform per body, then
    /// `view → world`.
    tf: FrameTransforms,
    /// The `/geometry` message, kept for a tap attached later.
    geometry: (Real, SceneUpdate),
    /// A second destination of what is written.
    tap: Option<Box<dyn Tap>>,
}

impl<W: Write + Seek + Send + 'static> RunLogger<W> {
    /// [`RunLogger::new`] for a run of `scene` as it stands (its model, name, file text,
    /// settings and initial state) with the material `overrides`; `gap_tol` is the run's
    /// ([`Simulation::scales`](crate::sim::Simulation::scales)).
    pub fn for_scene(
        writer: LogWriter<W>,
        scene: &Scene,
        overrides: &MaterialOverride,
        gap_tol: Real,
    ) -> Result<Self, LogError> {
        Self::new(
            writer,
            &scene.model,
            (&scene.name, &scene.text),
            (&scene.settings, overrides),
            &scene.initial,
            gap_tol,
        )
    }

    /// Starts the log of a run of `model` from the state `initial`: writes the scene
    /// (`name`, file `text`), the `settings` with the material `overrides` (so that the
    /// log describes the run it holds), and the bodies and obstacles on `/geometry`.
    pub fn new(
        mut writer: LogWriter<W>,
        model: &Model,
        (name, text): (&str, &str),
        (settings, overrides): (&Settings, &MaterialOverride),
        initial: &State,
        gap_tol: Real,
    ) -> Result<Self, LogError> {
        let t0 = initial.t;
        writer.scene(name, text)?;
        writer.settings(&RunSettings {
            settings,
            material_overrides: overrides,
        })?;
        let bodies: Vec<String> = model.bodies().iter().map(|b| b.name.clone()).collect();
        let names = LedgerNames::new(model);
        let drawing = geometry(model, t0)?;
        writer.geometry(t0, &drawing)?;

        // The mechanism at the start: its size scales the arrows, its box starts the view.
        let local_boxes: Vec<Aabb> = (0..model.nbody()).map(|k| local_box(model, k)).collect();
        let mut data = Data::new(model);
        let q: Vec<Real> = initial.q.iter().copied().collect();
        crate::kinematics::update_positions(model, &mut data, t0, &q)
            .map_err(LogError::Kinematics)?;
        let start = mechanism_box(&local_boxes, &data.body_pose);
        let extent = start.maxs - start.mins;
        let view = ViewTracker::new(&start);

        let state = StateRecord::new(t0, vec![], vec![], Energy::new(0.0, 0.0), vec![], 0);
        let identity = crate::math::Pose::identity();
        let mut tf = draw::body_transforms(t0, bodies.iter().map(|b| (b.as_str(), identity)))?;
        tf.transforms.push(view.transform(t0)?);
        Ok(Self {
            writer,
            names,
            listed: Vec::new(),
            gap_tol,
            impacts: 0,
            arrow: ArrowStyle::for_size(extent.x.max(extent.y)),
            arrow_scale: ArrowScale::default(),
            local_boxes,
            view,
            state,
            tf,
            geometry: (t0, drawing),
            tap: None,
        })
    }

    /// Sends everything written from now on to `tap` as well, starting with the geometry.
    pub fn with_tap(mut self, mut tap: Box<dyn Tap>) -> Self {
        let (t0, drawing) = &self.geometry;
        tap.geometry(*t0, drawing);
        self.tap = Some(tap);
        self
    }

    /// Ends the log: writes the energy audit of `summary` and finishes the file.
    pub fn finish(mut self, summary: &RunSummary) -> Result<W, LogError> {
        self.writer.audit(&Audit::of_run(summary))?;
        let inner = self.writer.finish()?;
        if let Some(tap) = &mut self.tap {
            tap.finish();
        }
        Ok(inner)
    }

    /// Flushes what is written so far (the log stays readable if the process dies).
    pub fn flush(&mut self) -> Result<(), LogError> {
        self.writer.flush()
    }
}

/// The `settings` metadata record of a run: the run settings, with the material overrides
/// of the command line, so that the log describes the run it holds. Each top-level field
/// is a key of the record.
#[derive(Clone, Copy, Debug, Serialize)]
pub struct RunSettings<'a> {
    /// The scene's settings, after the command line's overrides.
    #[serde(flatten)]
    pub settings: &'a Settings,
    /// The law, `e` and `μ` that replace every pair's (`null` where not overridden).
    pub material_overrides: &'a MaterialOverride,
}

impl Audit {
    /// The audit record of a run that ended with `summary`: the stop reason as
    /// `<name>: <what>` (`error: <the error>` for a failure), the balance with the dampers'
    /// and efforts' works as `applied_work` and the prescribed motions' (at the impacts
    /// and between them) as `prescribed_work`.
    pub fn of_run(summary: &RunSummary) -> Audit {
        let a = &summary.audit;
        let c = &summary.counters;
        let stop = match &summary.stop {
            StopReason::Failed(e) => format!("error: {e}"),
            other => format!("{}: {other}", other.name()),
        };
        Audit::new(
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
        )
    }
}

/// The names that a model's ledger entries carry: each contact pair's name and the bodies
/// of its two sides, made on demand from the colliders' (a model lists no pairs).
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct LedgerNames {
    /// The name of each collider.
    colliders: Vec<String>,
    /// The body of each collider (`world` for an obstacle), and whether it is on a body.
    sides: Vec<(String, bool)>,
}

impl LedgerNames {
    /// The names of `model`'s pairs.
    pub fn new(model: &Model) -> LedgerNames {
        let colliders = model.colliders().iter().map(|c| c.name.clone()).collect();
        let sides = (model.colliders().iter())
            .map(|c| match c.body {
                Some(b) => (model.bodies()[b.index()].name.clone(), true),
                None => ("world".to_owned(), false),
            })
            .collect();
        LedgerNames { colliders, sides }
    }

    /// The colliders `(a, b)` of `pair`: `a` on a body, as in [`Model::pair`].
    fn sides_of(&self, pair: PairId) -> (usize, usize) {
        let (i, j) = pair
            .colliders(self.colliders.len())
            .map_or((0, 0), |(i, j)| (i.index(), j.index()));
        if self.sides.get(i).is_some_and(|s| s.1) {
            (i, j)
        } else {
            (j, i)
        }
    }

    /// The name `<collider a>/<collider b>` of `pair`.
    pub fn pair(&self, pair: PairId) -> String {
        let (a, b) = self.sides_of(pair);
        let name = |c: usize| self.colliders.get(c).map_or("?", String::as_str);
        format!("{}/{}", name(a), name(b))
    }

    /// The bodies of the two sides of `pair` (`world` for an obstacle).
    pub fn bodies(&self, pair: PairId) -> (String, String) {
        let (a, b) = self.sides_of(pair);
        let side = |c: usize| self.sides.get(c).map_or("?", |s| s.0.as_str()).to_owned();
        (side(a), side(b))
    }

    /// The ledger entry (`/impacts` record) of the impact `ev`: the law's outcome, the
    /// frame, the energies; `alpha` absent when it is not finite (no approach speed).
    pub fn entry(&self, ev: &ImpactEvent) -> ImpactRecord {
        let (out, c) = (&ev.outcome, &ev.outcome.coefficients);
        let (body_a, body_b) = self.bodies(ev.frame.pair);
        ImpactRecord {
            t: ev.t,
            pair: self.pair(ev.frame.pair),
            body_a,
            body_b,
            law: out.law,
            impact_type: out.kind,
            case: out.case.number(),
            alpha: Some(c.alpha()).filter(|a| a.is_finite()),
            w: ev.w,
            g: c.g,
            h: c.h,
            p: c.p,
            q: c.q,
            v_a: ev.v_a,
            v_s: out.v_s,
            i_n: ev.impulse().n,
            i_t: ev.impulse().t,
            support: ev.support.map(|s| SupportRecord {
                i_n: s.impulse.n,
                i_t: s.impulse.t,
                duration: s.duration,
            }),
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
                crate::sim::ImpactCause::RockingEnd => ImpactCause::RockingEnd,
            },
            e: ev.material.e,
            mu: ev.material.mu,
            prescribed_work: ev.prescribed_work(),
            point: planar(ev.frame.point()),
            normal: planar(ev.frame.n),
            tangent: planar(ev.frame.t),
        }
    }
}

/// The drawing of the whole scene for `/geometry`: each body (frame-locked to its frame)
/// with its shapes, or its skeleton if it has none, and the obstacles (in `world`).
fn geometry(model: &Model, t: Real) -> Result<SceneUpdate, LogError> {
    let style = DrawStyle::default();
    let mut entities = Vec::new();
    for (k, body) in model.bodies().iter().enumerate() {
        let (r, g, b) = PALETTE[k % PALETTE.len()];
        let color = rgba(r, g, b, 1.0);
        let shapes: Vec<ShapeDrawing<'_>> = model
            .colliders()
            .iter()
            .filter(|c| c.body.is_some_and(|b| b.index() == k))
            .map(|c| ShapeDrawing {
                shape: &*c.shape.0,
                pose: c.pose,
                color,
            })
            .collect();
        entities.push(draw::body_entity(t, &body.name, &shapes, &style)?);
        // The skeleton: the visual of a body without shapes; the link of a body hinged
        // away from its centre of mass or its children (a pendulum's rod).
        let anchors = child_joints(model, k);
        let reach = (anchors.iter().chain([&body.com])).any(|p| p.length() > 0.0);
        if shapes.is_empty() || reach {
            let skeleton = (body.com, shapes.is_empty());
            entities.push(draw::skeleton_entity(
                t, &body.name, &anchors, skeleton, color, &style,
            )?);
        }
    }
    // The blades and wheels: a third of their body's size, a tenth of a metre without
    // shapes.
    for c in model.constraints() {
        let body = &model.bodies()[c.body.index()];
        let size = (model.colliders().iter())
            .filter(|s| s.body == Some(c.body))
            .map(|s| 2.0 * s.shape.0.compute_aabb(&s.pose).half_extents().max_element())
            .fold(0.0, Real::max);
        let length = if size > 0.0 { size / 3.0 } else { 0.1 };
        let wheel = c.kind == crate::model::ConstraintKind::Wheel;
        entities.push(draw::constraint_entity(
            t,
            (&c.name, &body.name),
            (c.point, c.direction),
            wheel,
            length,
            &style,
        )?);
    }
    for c in model.colliders().iter().filter(|c| c.body.is_none()) {
        let shape = ShapeDrawing {
            shape: &*c.shape.0,
            pose: c.pose,
            color: OBSTACLE,
        };
        entities.push(draw::obstacle_entity(t, &c.name, &[shape], &style)?);
    }
    Ok(SceneUpdate {
        deletions: vec![],
        entities,
    })
}

/// Where the children of body `k` are jointed to it, in its frame (m).
fn child_joints(model: &Model, k: usize) -> Vec<Vec2> {
    (model.joints().iter())
        .filter(|j| j.parent.is_some_and(|p| p.index() == k))
        .map(|j| j.placement.translation)
        .collect()
}

/// The bounding box of body `k` in its own frame: its shapes (half-spaces excepted), its
/// origin, its centre of mass and its children's joints (m).
fn local_box(model: &Model, k: usize) -> Aabb {
    let body = &model.bodies()[k];
    let mut aabb = Aabb::new(Vec2::ZERO, Vec2::ZERO);
    for p in child_joints(model, k).into_iter().chain([body.com]) {
        aabb.take_point(p);
    }
    for c in (model.colliders().iter()).filter(|c| c.body.is_some_and(|b| b.index() == k)) {
        let shape_box = c.shape.0.compute_aabb(&c.pose);
        if shape_box.mins.is_finite() && shape_box.maxs.is_finite() {
            aabb.merge(&shape_box);
        }
    }
    aabb
}

/// The bounding box in the world of the bodies at `poses`, from their boxes `local` in
/// their own frames (m).
fn mechanism_box(local: &[Aabb], poses: &[Pose]) -> Aabb {
    let mut aabb = Aabb::new_invalid();
    for (b, pose) in local.iter().zip(poses) {
        aabb.merge(&b.transform_by(pose));
    }
    if aabb.mins.x > aabb.maxs.x {
        // No bodies.
        return Aabb::new(Vec2::ZERO, Vec2::ZERO);
    }
    aabb
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
        if self.listed != s.pairs {
            self.listed.clear();
            self.listed.extend_from_slice(s.pairs);
            rec.contacts = (s.pairs.iter())
                .map(|&p| ContactState::new(self.names.pair(p), ContactMode::Free, 0.0))
                .collect();
        }
        for (((c, &gap), mode), &slip) in (rec.contacts.iter_mut())
            .zip(s.gaps)
            .zip(s.modes)
            .zip(s.slips)
        {
            c.slip = if *mode == PairMode::Sliding { slip } else { 0 };
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
        // `/tf`: the poses and the view handed to the writer thread as numbers (it computes
        // the rotations and encodes the message), unless a tap needs the message here, the
        // writer thread is behind or a number is not finite; then the cached transforms
        // with this sample's poses, and the view, written from here.
        let center = self.view.follow(&mechanism_box(&self.local_boxes, s.poses));
        if self.tap.is_none() {
            let frames = (s.poses.iter())
                .map(|p| {
                    [
                        p.translation.x,
                        p.translation.y,
                        p.rotation.re,
                        p.rotation.im,
                    ]
                })
                .chain([[-center.x, -center.y, 1.0, 0.0]]);
            if self.writer.planar_transforms(s.t, &self.tf, frames)? {
                return Ok(());
            }
        }
        let time = timestamp(s.t)?;
        let poses = (s.poses.iter())
            .map(|p| (p.translation, p.rotation.angle()))
            .chain([(-center, 0.0)]);
        for (tf, (position, angle)) in self.tf.transforms.iter_mut().zip(poses) {
            tf.timestamp = Some(time);
            tf.translation = Some(vector3(position.x, position.y, 0.0));
            tf.rotation = Some(about_z(angle));
        }
        self.writer.transforms(s.t, &self.tf)?;
        if let Some(tap) = &mut self.tap {
            tap.sample(&self.state, &self.tf);
        }
        Ok(())
    }

    fn impact(&mut self, _model: &Model, ev: &ImpactEvent) -> Result<(), ObserverError> {
        let record = self.names.entry(ev);
        let impulse = record.impulse();
        let length = (self.arrow_scale).length(impulse.x.hypot(impulse.y), &self.arrow);
        self.writer.impact_drawn(&record, (length, self.arrow))?;
        if let Some(tap) = &mut self.tap {
            let drawing = super::sink::arrow_update(&record, (length, self.arrow))?;
            let line = log_message(ev.t, LogLevel::Info, &impact_line(&record))?;
            tap.impact(&record, &drawing);
            tap.log(&line);
        }
        self.impacts += 1;
        Ok(())
    }

    fn message(&mut self, t: Real, level: Level, text: &str) -> Result<(), ObserverError> {
        let level = match level {
            Level::Info => LogLevel::Info,
            Level::Warning => LogLevel::Warning,
            Level::Error => LogLevel::Error,
        };
        let log = log_message(t, level, text)?;
        self.writer.log_message(&log)?;
        if let Some(tap) = &mut self.tap {
            tap.log(&log);
        }
        Ok(())
    }
}

/// The `/log` line of an impact: `impact #3 rodB/floor: newton, forward_sliding (case 3),
/// I_n = 0.455 N·s, I_t = -0.0911 N·s, v_s = (0.0714, 0.197) m/s, ΔE = -0.0481 J`.
#[doc(hidden)]
pub fn impact_line(r: &ImpactRecord) -> String {
    let s = draw::significant;
    let cause = match r.cause {
        ImpactCause::Collision => String::new(),
        other => format!(" [{}]", other.name()),
    };
    format!(
        "impact #{} {}: {}, {} (case {}){cause}, I_n = {} N·s, I_t = {} N·s, \
         v_s = ({}, {}) m/s, ΔE = {} J",
        r.index,
        r.pair,
        r.law.name(),
        r.impact_type.name(),
        r.case,
        s(r.i_n),
        s(r.i_t),
        s(r.v_s.n),
        s(r.v_s.t),
        s(r.delta_e),
    )
}
