//! The MCAP log of real runs: bundled scenes (`kane_double_pendulum`, `bouncing_ball`,
//! `pendulum_wall`, `spinning_disk_particle`) simulated by [`Simulation`] with a
//! [`RunLogger`] writing to memory, next to a [`Recorder`] that sees the same run, and read
//! back with the `mcap` crate (`Summary::read`, `MessageStream`) and `ricochet::log`.
//!
//! Checked here:
//! - the six topics, their schema names and encodings, and message counts that follow
//!   from the run (`/impacts` = impacts applied, `/state` = the output grid up to the stop
//!   time + two samples per impact instant + the final one, `/tf` = `/state`, `/geometry`
//!   = one, `/scene` = one arrow per impact, `/log` = the messages the run sent + one line
//!   per impact);
//! - every JSON message validates against the schema embedded in the file, which is the
//!   shipped file under `schemas/`; every protobuf message decodes as its type;
//! - every bundled scene: every chunk holds messages, every message decodes, and at a
//!   dozen times the latest `/geometry` message draws every body and obstacle;
//! - `/state` and `/impacts` equal, value for value, what the [`Recorder`] saw; the ledger
//!   obeys Eq. (29), Newton's law and the energy balance on its own; the first impact of
//!   the double pendulum is [P] Table 2 row 1; `/tf` is the pendulum's kinematics computed
//!   here by hand;
//! - the metadata: `scene` holds the file text, `settings` the run settings, `audit` the
//!   run summary;
//! - determinism: two runs of a scene give byte-identical files, in memory and on disk;
//! - a run interrupted through its `AtomicBool`, a run whose impact law fails, and a run
//!   whose log fails each leave a complete file holding exactly what was written before,
//!   with the right stop reason in the audit;
//! - a writer that was never finished (a killed process) leaves a file that reads back up
//!   to its last flush.

use crate::common::mcap_check;
use crate::common::shared_file;

use std::collections::{BTreeMap, HashMap};
use std::io::{Cursor, Seek, Write};
use std::path::PathBuf;
use std::sync::atomic::{AtomicBool, Ordering};

use mcap::{MessageStream, Summary};
use ricochet::impact::ImpactError;
use ricochet::log::foxglove::{Decode, Encode};
use ricochet::log::{
    Ending, FrameTransforms, ImpactCause, ImpactRecord, Log, LogLevel, LogOptions, LogWriter,
    RunLogger, SceneUpdate, StateRecord, Topic,
};
use ricochet::model::Model;
use ricochet::scene::Scene;
use ricochet::settings::Settings;
use ricochet::sim::{
    ImpactEvent, Level, MaterialOverride, Observer, ObserverError, Recorder, RunSummary, Sample,
    SimError, Simulation, StopReason,
};
use serde_json::Value;
use shared_file::SharedFile;

// ---------------------------------------------------------------------------------------
// Running a scene with a log and a recorder

/// The scenes run by most tests: an accumulation that ends in persistent contact, a long
/// bouncing sequence to rest, a run to the end time, and prescribed motion.
const SCENES: [&str; 4] = [
    "kane_double_pendulum",
    "bouncing_ball",
    "pendulum_wall",
    "spinning_disk_particle",
];

fn repo_path(rel: &str) -> PathBuf {
    PathBuf::from(env!("CARGO_MANIFEST_DIR")).join(rel)
}

fn load(name: &str) -> Scene {
    ricochet::scene::load(repo_path(&format!("scenes/{name}.toml")))
        .unwrap_or_else(|e| panic!("{name}: {e}"))
}
/// Something done to the run after a number of samples.
enum Hook<'a> {
    None,
    /// Set the interrupt flag after this many samples (Ctrl-C).
    Interrupt {
        after: usize,
        flag: &'a AtomicBool,
    },
    /// Refuse every sample after this many (a full disk), without writing it.
    FailAfter(usize),
    /// Flush the log after this many samples and keep a copy of the file's bytes then,
    /// with the number of impacts recorded so far.
    Snapshot {
        after: usize,
        file: SharedFile,
        taken: Option<(Vec<u8>, usize)>,
    },
}

/// The run's observer: the log and a recorder of everything the log was given.
struct Tee<'a, W: Write + Seek + Send + 'static> {
    log: RunLogger<W>,
    seen: Recorder,
    hook: Hook<'a>,
    /// Samples written when the hook fired.
    fired_at: Option<usize>,
}

impl<W: Write + Seek + Send + 'static> Observer for Tee<'_, W> {
    fn sample(&mut self, model: &Model, s: &Sample<'_>) -> Result<(), ObserverError> {
        if let Hook::FailAfter(k) = self.hook
            && self.seen.samples.len() >= k
        {
            self.fired_at.get_or_insert(k);
            return Err("no space left on device".into());
        }
        self.log.sample(model, s)?;
        self.seen.sample(model, s)?;
        let n = self.seen.samples.len();
        match &mut self.hook {
            Hook::Interrupt { after, flag } if n == *after => {
                flag.store(true, Ordering::Relaxed);
                self.fired_at = Some(n);
            }
            Hook::Snapshot { after, file, taken } if n == *after => {
                self.log.flush()?;
                *taken = Some((file.snapshot(), self.seen.impacts.len()));
                self.fired_at = Some(n);
            }
            _ => {}
        }
        Ok(())
    }
    fn impact(&mut self, model: &Model, impact: &ImpactEvent) -> Result<(), ObserverError> {
        self.log.impact(model, impact)?;
        self.seen.impact(model, impact)
    }
    fn message(&mut self, t: f64, level: Level, text: &str) -> Result<(), ObserverError> {
        self.log.message(t, level, text)?;
        self.seen.message(t, level, text)
    }
}

/// A finished run: the log's bytes, the summary, what the observer saw.
struct Run {
    scene: Scene,
    bytes: Vec<u8>,
    summary: RunSummary,
    seen: Recorder,
    fired_at: Option<usize>,
    snapshot: Option<(Vec<u8>, usize)>,
}

fn run_with<W: Write + Seek + Send + 'static>(
    scene: Scene,
    overrides: MaterialOverride,
    writer: LogWriter<W>,
    hook: Hook<'_>,
    interrupt: Option<&AtomicBool>,
) -> (Run, W) {
    let mut sim = Simulation::new(&scene.model, &scene.settings, overrides).unwrap();
    let log = RunLogger::for_scene(writer, &scene, &overrides, sim.scales().gap_tol).unwrap();
    let mut tee = Tee {
        log,
        seen: Recorder {
            keep_samples: true,
            ..Recorder::default()
        },
        hook,
        fired_at: None,
    };
    let summary = sim.run(&scene.initial, &mut tee, interrupt);
    let Tee {
        log,
        seen,
        hook,
        fired_at,
    } = tee;
    let inner = log.finish(&summary).unwrap();
    let snapshot = match hook {
        Hook::Snapshot { taken, .. } => taken,
        _ => None,
    };
    let run = Run {
        scene,
        bytes: vec![],
        summary,
        seen,
        fired_at,
        snapshot,
    };
    (run, inner)
}

/// Runs `scene` with `overrides` and `hook`, logging to memory.
fn run_hooked(
    scene: Scene,
    overrides: MaterialOverride,
    hook: Hook<'_>,
    interrupt: Option<&AtomicBool>,
) -> Run {
    let writer = LogWriter::new(Cursor::new(Vec::new()), LogOptions::default()).unwrap();
    let (mut run, cursor) = run_with(scene, overrides, writer, hook, interrupt);
    run.bytes = cursor.into_inner();
    run
}

fn run_scene(name: &str) -> Run {
    run_hooked(load(name), MaterialOverride::default(), Hook::None, None)
}

/// Every message of a log, in file order: topic, log time (ns), data.
fn messages(bytes: &[u8]) -> Vec<(String, u64, Vec<u8>)> {
    MessageStream::new(bytes)
        .unwrap()
        .map(|m| {
            let m = m.unwrap();
            (m.channel.topic.clone(), m.log_time, m.data.into_owned())
        })
        .collect()
}

/// The messages of a JSON topic, decoded.
fn on_topic<T: serde::de::DeserializeOwned>(bytes: &[u8], topic: Topic) -> Vec<T> {
    assert!(topic.is_json(), "{}", topic.name());
    messages(bytes)
        .into_iter()
        .filter(|(name, _, _)| name == topic.name())
        .map(|(_, _, data)| serde_json::from_slice(&data).unwrap())
        .collect()
}

/// The messages of a protobuf topic, decoded.
fn on_protobuf_topic<T: Decode>(bytes: &[u8], topic: Topic) -> Vec<T>
where
    T::Error: std::fmt::Debug,
{
    assert!(!topic.is_json(), "{}", topic.name());
    messages(bytes)
        .into_iter()
        .filter(|(name, _, _)| name == topic.name())
        .map(|(_, _, data)| T::decode(&data[..]).unwrap())
        .collect()
}

/// `/state` samples the run must have written: the output grid `k / rate` up to the stop
/// time, two at each impact instant (before and after the jump), and the final one.
/// The output grid up to the stop, two samples per impact instant, and the final state
/// unless a sample was already taken at the stop time (the grid's last point, or the
/// sample after the jump when the run stops at an impact).
fn expected_samples(run: &Run) -> u64 {
    let rate = run.scene.settings.output_rate;
    let t_stop = run.summary.state.t;
    let grid = (t_stop * rate + 1e-9).floor() as u64 + 1;
    let mut instants: Vec<f64> = run.seen.impacts.iter().map(|i| i.t).collect();
    instants.dedup();
    let on_grid = (t_stop * rate - (t_stop * rate).round()).abs() < 1e-9;
    let final_sample = !(on_grid || instants.last() == Some(&t_stop));
    grid + 2 * instants.len() as u64 + u64::from(final_sample)
}

fn pair_name(model: &Model, ev: &ImpactEvent) -> String {
    let pair = model.pair_of(ev.frame.pair);
    let name = |c: ricochet::model::ColliderId| model.colliders()[c.index()].name.clone();
    format!("{}/{}", name(pair.a), name(pair.b))
}

// ---------------------------------------------------------------------------------------
// Topics, schemas, counts

#[test]
fn topics_schemas_and_counts_follow_the_run() {
    for name in SCENES {
        let run = run_scene(name);
        let c = run.summary.counters;
        let summary = Summary::read(&run.bytes)
            .unwrap()
            .expect("a summary section");
        let stats = summary.stats.as_ref().unwrap();
        let mut seen = BTreeMap::new();
        for (id, channel) in &summary.channels {
            let schema = channel.schema.as_ref().expect("every channel has a schema");
            let topic = Topic::from_name(&channel.topic).unwrap();
            assert_eq!(channel.message_encoding, topic.message_encoding(), "{name}");
            assert_eq!(schema.encoding, topic.schema_encoding(), "{name}");
            let count = stats.channel_message_counts.get(id).copied().unwrap_or(0);
            seen.insert(channel.topic.clone(), (schema.name.clone(), count));
        }
        let impacts = run.seen.impacts.len() as u64;
        let samples = expected_samples(&run);
        let expected: BTreeMap<String, (String, u64)> = [
            ("/state", "ricochet.State", samples),
            ("/impacts", "ricochet.Impact", impacts),
            ("/geometry", "foxglove.SceneUpdate", 1),
            ("/scene", "foxglove.SceneUpdate", impacts),
            ("/tf", "foxglove.FrameTransforms", samples),
            (
                "/log",
                "foxglove.Log",
                run.seen.messages.len() as u64 + impacts,
            ),
        ]
        .into_iter()
        .map(|(t, s, n)| (t.to_owned(), (s.to_owned(), n)))
        .collect();
        assert_eq!(seen, expected, "{name}");
        assert_eq!(c.impacts, impacts, "{name}");
        assert_eq!(c.samples, samples, "{name}");
        assert!(impacts > 0, "{name}: no impact");
        // At least one sample per output period of the simulated time.
        let t_stop = run.summary.state.t;
        assert!(
            samples as f64 >= t_stop * run.scene.settings.output_rate,
            "{name}"
        );
        // Simulated time stamps, from 0 to the stop time.
        assert_eq!(stats.message_start_time, 0, "{name}");
        assert_eq!(
            stats.message_end_time,
            (t_stop * 1e9).round() as u64,
            "{name}"
        );
        // The run ends with one `run stopped` message at the stop time.
        let (t, _, text) = run.seen.messages.last().unwrap();
        assert!(text.starts_with("run stopped"), "{name}: {text}");
        assert_eq!(*t, t_stop, "{name}");
        let names: Vec<&str> = (summary.metadata_indexes.iter())
            .map(|m| m.name.as_str())
            .collect();
        assert_eq!(names, ["ricochet", "scene", "settings", "audit"], "{name}");
        mcap_check::assert_every_chunk_has_messages(&run.bytes);
    }
}

#[test]
fn every_message_validates_against_the_schema_in_the_file() {
    for name in SCENES {
        let run = run_scene(name);
        let summary = Summary::read(&run.bytes).unwrap().unwrap();
        let mut validators = HashMap::new();
        for channel in summary.channels.values() {
            let schema = channel.schema.as_ref().unwrap();
            let file = match schema.name.as_str() {
                "ricochet.State" => "schemas/ricochet/State.json",
                "ricochet.Impact" => "schemas/ricochet/Impact.json",
                // Protobuf: the Foxglove SDK's descriptors (tests/all/log.rs checks them).
                _ => continue,
            };
            // The embedded schema is the shipped file, byte for byte.
            assert_eq!(
                &schema.data[..],
                std::fs::read(repo_path(file)).unwrap(),
                "{file}"
            );
            let json: Value = serde_json::from_slice(&schema.data).unwrap();
            validators.insert(
                channel.topic.clone(),
                jsonschema::validator_for(&json).unwrap(),
            );
        }
        let mut per_topic: BTreeMap<String, u64> = BTreeMap::new();
        for (topic, _, data) in messages(&run.bytes) {
            assert_decodes(&topic, &data, validators.get(&topic));
            *per_topic.entry(topic).or_default() += 1;
        }
        // Every topic had messages to check.
        assert_eq!(per_topic.len(), 6, "{name}: {per_topic:?}");
    }
}

/// A message of `topic` decodes: JSON that passes `validator`, or protobuf of the topic's
/// type that is the canonical encoding of what it decodes to.
fn assert_decodes(topic: &str, data: &[u8], validator: Option<&jsonschema::Validator>) {
    fn canonical<M: Encode>(m: M) -> Vec<u8> {
        let mut bytes = Vec::new();
        m.encode(&mut bytes).unwrap();
        bytes
    }
    if let Some(validator) = validator {
        let json: Value = serde_json::from_slice(data).unwrap();
        let errors: Vec<String> = validator
            .iter_errors(&json)
            .map(|e| format!("{e} at {}", e.instance_path()))
            .collect();
        assert!(errors.is_empty(), "{topic}: {errors:?}\n{json}");
        return;
    }
    let again = match topic {
        "/geometry" | "/scene" => canonical(SceneUpdate::decode(data).unwrap()),
        "/tf" => canonical(FrameTransforms::decode(data).unwrap()),
        "/log" => canonical(Log::decode(data).unwrap()),
        other => panic!("unexpected topic {other}"),
    };
    assert_eq!(again, data, "{topic}");
}

/// Every bundled scene, run as the scene says: every chunk of its log holds messages,
/// every message decodes, and at a dozen times spread over the run the latest `/geometry`
/// message (what a viewer that seeks there shows) draws every body and every obstacle;
/// and its audit balances (`sim_energy::assert_the_audit_balances`, on the same run).
#[test]
fn every_bundled_scene_logs_the_whole_mechanism_and_balances_its_audit() {
    let mut scenes: Vec<String> = std::fs::read_dir(repo_path("scenes"))
        .unwrap()
        .filter_map(|e| {
            let path = e.unwrap().path();
            (path.extension()? == "toml").then(|| path.file_stem()?.to_str().map(str::to_owned))?
        })
        .collect();
    scenes.sort();
    assert!(scenes.len() >= 9, "{scenes:?}");
    let mut seed = 0x2545_f491_4f6c_dd1d_u64;
    for name in &scenes {
        let run = run_scene(name);
        let model = &run.scene.model;
        crate::sim_energy::assert_the_audit_balances(
            name,
            &run.scene,
            &run.summary,
            &run.seen.impacts,
        );
        mcap_check::assert_every_chunk_has_messages(&run.bytes);
        let all = messages(&run.bytes);
        for (topic, _, data) in &all {
            // JSON topics are validated above; here they must at least parse.
            if Topic::from_name(topic).unwrap().is_json() {
                serde_json::from_slice::<Value>(data).unwrap();
            } else {
                assert_decodes(topic, data, None);
            }
        }
        let geometry: Vec<(u64, SceneUpdate)> = (all.iter())
            .filter(|(topic, _, _)| topic == Topic::Geometry.name())
            .map(|(_, ns, data)| (*ns, SceneUpdate::decode(&data[..]).unwrap()))
            .collect();
        let t_stop = (run.summary.state.t * 1e9).round() as u64;
        for _ in 0..12 {
            // xorshift64*: times spread over [0, t_stop].
            seed ^= seed >> 12;
            seed ^= seed << 25;
            seed ^= seed >> 27;
            let r = (seed.wrapping_mul(0x2545_f491_4f6c_dd1d) >> 11) as f64 / (1u64 << 53) as f64;
            let t = (r * t_stop as f64) as u64;
            let (_, latest) = (geometry.iter().rev())
                .find(|(ns, _)| *ns <= t)
                .unwrap_or_else(|| panic!("{name}: no geometry at {t} ns"));
            let drawn = |id: &str| {
                (latest.entities.iter()).any(|e| {
                    e.id == id
                        && e.cubes.len() + e.cylinders.len() + e.lines.len() + e.triangles.len() > 0
                })
            };
            for body in model.bodies() {
                assert!(
                    drawn(&format!("body/{}", body.name))
                        || drawn(&format!("visual/{}", body.name)),
                    "{name} at {t} ns: body {} is not drawn",
                    body.name
                );
            }
            for c in model.colliders().iter().filter(|c| c.body.is_none()) {
                assert!(
                    drawn(&format!("world/{}", c.name)),
                    "{name} at {t} ns: obstacle {} is not drawn",
                    c.name
                );
            }
        }
    }
}

// ---------------------------------------------------------------------------------------
// Contents against the recorder and against the physics

#[test]
fn state_samples_are_what_the_run_reported() {
    for name in SCENES {
        let run = run_scene(name);
        let all = messages(&run.bytes);
        let states: Vec<(u64, StateRecord)> = (all.iter())
            .filter(|(t, _, _)| t == Topic::State.name())
            .map(|(_, ns, data)| (*ns, serde_json::from_slice(data).unwrap()))
            .collect();
        assert_eq!(states.len(), run.seen.samples.len(), "{name}");
        let mut last_count = 0;
        for ((ns, s), (t, q, u, e)) in states.iter().zip(&run.seen.samples) {
            // Bit for bit (serde_json's float_roundtrip is on in tests).
            assert_eq!((s.t, &s.q, &s.u, s.energy.total), (*t, q, u, *e), "{name}");
            assert_eq!(*ns, (t * 1e9).round() as u64, "{name}");
            assert_eq!(s.energy.kinetic + s.energy.potential, s.energy.total);
            assert!(s.energy.kinetic >= 0.0, "{name} at {t}");
            assert_eq!(s.contacts.len(), run.scene.model.pair_count(), "{name}");
            // The impact count grows, and counts the impacts up to this instant.
            let before = run.seen.impacts.iter().filter(|i| i.t < *t).count() as u64;
            let upto = run.seen.impacts.iter().filter(|i| i.t <= *t).count() as u64;
            assert!(
                (before..=upto).contains(&s.impact_count) && s.impact_count >= last_count,
                "{name} at {t}: impact_count {}",
                s.impact_count
            );
            last_count = s.impact_count;
        }
        // Time never goes back, and the samples cover the run.
        assert!(states.windows(2).all(|w| w[0].1.t <= w[1].1.t), "{name}");
        assert_eq!(states[0].1.t, 0.0);
        assert_eq!(states.last().unwrap().1.t, run.summary.state.t, "{name}");
        assert_eq!(
            states.last().unwrap().1.q,
            run.summary.state.q.as_slice(),
            "{name}"
        );
        // Each /state message is followed by its /tf message, at the same time.
        let order: Vec<(&str, u64)> = (all.iter())
            .filter(|(t, _, _)| t == "/state" || t == "/tf")
            .map(|(t, ns, _)| (t.as_str(), *ns))
            .collect();
        for pair in order.chunks(2) {
            assert_eq!(pair[0].0, "/state", "{name}");
            assert_eq!(pair[1].0, "/tf", "{name}");
            assert_eq!(pair[0].1, pair[1].1, "{name}");
        }
    }
}

#[test]
fn impact_ledger_is_what_the_run_reported() {
    for name in SCENES {
        let run = run_scene(name);
        let model = &run.scene.model;
        let logged: Vec<ImpactRecord> = on_topic(&run.bytes, Topic::Impacts);
        assert_eq!(logged.len(), run.seen.impacts.len(), "{name}");
        assert_eq!(
            ricochet::log::read_bytes(&run.bytes).unwrap().impacts,
            logged
        );
        for (k, (r, ev)) in logged.iter().zip(&run.seen.impacts).enumerate() {
            let o = &ev.outcome;
            let c = &o.coefficients;
            let ctx = format!("{name} impact {k}");
            assert_eq!(r.index, k as u64, "{ctx}");
            assert_eq!(r.index, ev.index, "{ctx}");
            assert_eq!(r.t, ev.t, "{ctx}");
            assert_eq!(r.pair, pair_name(model, ev), "{ctx}");
            assert_eq!(
                (r.law, r.impact_type, r.case),
                (o.law, o.kind, o.case.number())
            );
            assert_eq!((r.e, r.mu), (ev.material.e, ev.material.mu), "{ctx}");
            assert_eq!(r.alpha, Some(c.alpha()).filter(|a| a.is_finite()), "{ctx}");
            assert_eq!((r.g, r.h, r.p, r.q), (c.g, c.h, c.p, c.q), "{ctx}");
            assert_eq!(r.w, ev.w, "{ctx}");
            assert_eq!(r.v_a, ev.v_a, "{ctx}");
            assert_eq!(r.v_s, o.v_s, "{ctx}");
            assert_eq!((r.i_n, r.i_t), (o.impulse.n, o.impulse.t), "{ctx}");
            assert_eq!(r.delta_u, ev.delta_u, "{ctx}");
            assert_eq!(r.energy_before, ev.energy_before.total(), "{ctx}");
            assert_eq!(r.energy_after, ev.energy_after.total(), "{ctx}");
            assert_eq!(r.delta_e, o.delta_e, "{ctx}");
            assert_eq!((r.work_n, r.work_t), (o.work_n, o.work_t), "{ctx}");
            assert_eq!(r.prescribed_work, ev.prescribed_work(), "{ctx}");
            let p = ev.frame.point();
            assert_eq!((r.point.x, r.point.y), (p.x, p.y), "{ctx}");
            assert_eq!((r.normal.x, r.normal.y), (ev.frame.n.x, ev.frame.n.y));
            assert_eq!((r.tangent.x, r.tangent.y), (ev.frame.t.x, ev.frame.t.y));

            // The ledger on its own: Eq. (29), the split of ΔE, Newton's law, the sign
            // conventions of the frame, and the energy balance of the model.
            let eq29 = 0.5 * r.i_n * (r.v_s.n + r.v_a.n) + 0.5 * r.i_t * (r.v_s.t + r.v_a.t);
            let scale = r.energy_before.abs().max(1.0);
            assert!((r.delta_e - eq29).abs() <= 1e-12 * scale, "{ctx}");
            assert!((r.work_n + r.work_t - r.delta_e).abs() <= 1e-12 * scale);
            assert_eq!(r.cause.name(), ev.cause.name(), "{ctx}");
            match r.cause {
                ImpactCause::Collision => {
                    assert!(r.v_a.n < 0.0 && r.v_s.n >= 0.0 && r.i_n > 0.0, "{ctx}");
                    assert!(r.i_t.abs() <= r.mu * r.i_n * (1.0 + 1e-12), "{ctx}");
                    if r.law == ricochet::impact::Law::Newton {
                        assert!((r.v_s.n + r.e * r.v_a.n).abs() <= 1e-12 * r.v_a.n.abs());
                    }
                }
                ImpactCause::AccumulationEnd => {
                    // The impact that ends an accumulation, made plastic with the pair's
                    // friction: an approach, a push, inside the cone, the point at rest.
                    assert!(r.v_a.n < 0.0 && r.i_n > 0.0 && r.e == 0.0, "{ctx}");
                    assert!(r.v_s.n.abs() <= 1e-12 * r.v_a.n.abs(), "{ctx}");
                    assert!(r.i_t.abs() <= r.mu * r.i_n * (1.0 + 1e-12), "{ctx}");
                    assert!(r.alpha.is_some_and(f64::is_finite), "{ctx}");
                }
                other => panic!("{ctx}: no {other:?} expected in these scenes"),
            }
            let balance = r.energy_after - r.energy_before - (r.delta_e + r.prescribed_work);
            assert!(balance.abs() <= 1e-12 * scale, "{ctx}: {balance}");
            if name != "spinning_disk_particle" {
                // No prescribed motion: the model's energy change is Eq. (29).
                assert!(r.prescribed_work.abs() <= 1e-9 * scale, "{ctx}");
            }
        }
    }
}

/// The first impact of the double pendulum is the paper's example: [P] Sect. 5, Table 2,
/// lower half, row 1 (Newton, e = 0.5, μ = 0.2), to one unit in the last printed digit
/// (`tests/golden/paper_table_2.toml`), and `ricochet impact`'s example in DESIGN.md.
#[test]
fn first_double_pendulum_impact_is_table_2_row_1() {
    let run = run_scene("kane_double_pendulum");
    let logged: Vec<ImpactRecord> = on_topic(&run.bytes, Topic::Impacts);
    let r = &logged[0];
    println!("{r:#?}");
    let close = |got: f64, printed: f64, unit: f64| (got - printed).abs() <= unit;
    assert_eq!(r.t, 0.0);
    assert_eq!(r.pair, "rodB/floor");
    assert_eq!((r.body_a.as_str(), r.body_b.as_str()), ("rodB", "world"));
    assert_eq!(r.impact_type.name(), "reverse_sliding");
    assert_eq!(r.case, 3);
    // Sect. 5: v^A = −0.2684 n + 0.5343 t, and W as corrected in ERRATA item 3:
    // m_nn = 0.3365, m_nt = −0.5071, m_tt = 0.8134.
    assert!(close(r.v_a.n, -0.2684, 1e-4) && close(r.v_a.t, 0.5343, 1e-4));
    assert!(close(r.w.nn, 0.3365, 1e-4) && close(r.w.nt, -0.5071, 1e-4));
    assert!(close(r.w.tt, 0.8134, 1e-4));
    // Table 2 row 1: Δu = (−0.12, 0.47), v^S = (0.13, −0.078), ΔE = −0.095; the printed
    // Δu₂ = 0.47 is a misprint (ERRATA item 5: the row's own v^S and ΔE give
    // Δu = (−0.1224, 0.4863)).
    assert!(close(r.delta_u[0], -0.12, 0.01));
    assert!(close(r.delta_u[0], -0.1224, 1e-4) && close(r.delta_u[1], 0.4863, 1e-4));
    assert!(close(r.v_s.n, 0.13, 0.01) && close(r.v_s.t, -0.078, 0.001));
    assert!(close(r.delta_e, -0.095, 0.001));
    // DESIGN.md: α = 1.9908, I_n = 1.0242, I_t = −0.1143, v^S = (0.1342, −0.0780),
    // ΔE = −0.0948.
    assert!(close(r.alpha.unwrap(), 1.9908, 1e-4) && close(r.i_n, 1.0242, 1e-4));
    assert!(close(r.i_t, -0.1143, 1e-4) && close(r.delta_e, -0.0948, 1e-4));
    assert!(close(r.v_s.n, 0.1342, 1e-4) && close(r.v_s.t, -0.0780, 1e-4));
}

/// `/tf` against the double pendulum's kinematics written out here: rod A turns by q1
/// about the origin, rod B by q2 (absolute) about A's end at `2 (sin q1, −cos q1)`.
#[test]
fn transforms_are_the_double_pendulum_kinematics() {
    let run = run_scene("kane_double_pendulum");
    let tfs: Vec<FrameTransforms> = on_protobuf_topic(&run.bytes, Topic::Tf);
    let states: Vec<StateRecord> = on_topic(&run.bytes, Topic::State);
    assert_eq!(tfs.len(), states.len());
    let angle = |q: &Option<ricochet::log::foxglove::Quaternion>| {
        let q = q.unwrap();
        assert_eq!((q.x, q.y), (0.0, 0.0));
        2.0 * q.z.atan2(q.w)
    };
    let same_angle = |a: f64, b: f64| {
        let d = (a - b).rem_euclid(std::f64::consts::TAU);
        d.min(std::f64::consts::TAU - d) < 1e-12
    };
    let xy = |v: &Option<ricochet::log::foxglove::Vector3>| {
        let v = v.unwrap();
        assert_eq!(v.z, 0.0);
        (v.x, v.y)
    };
    for (tf, s) in tfs.iter().zip(&states) {
        let (q1, q2) = (s.q[0], s.q[1]);
        let [a, b, view] = &tf.transforms[..] else {
            panic!("{tf:?}")
        };
        for f in [a, b, view] {
            let time = f.timestamp.unwrap();
            assert_eq!(time.total_nanos(), (s.t * 1e9).round() as u64);
        }
        assert_eq!(
            (a.child_frame_id.as_str(), b.child_frame_id.as_str()),
            ("body_rodA", "body_rodB")
        );
        assert_eq!(
            (a.parent_frame_id.as_str(), b.parent_frame_id.as_str()),
            ("world", "world")
        );
        let (ax, ay) = xy(&a.translation);
        assert!(ax.abs() < 1e-15 && ay.abs() < 1e-15);
        assert!(
            same_angle(angle(&a.rotation), q1),
            "{} vs {q1}",
            angle(&a.rotation)
        );
        let (bx, by) = xy(&b.translation);
        assert!((bx - 2.0 * q1.sin()).abs() < 1e-12);
        assert!((by + 2.0 * q1.cos()).abs() < 1e-12);
        assert!(
            same_angle(angle(&b.rotation), q2),
            "{} vs {q2}",
            angle(&b.rotation)
        );
        // The view is the root: `view → world`, a translation that keeps the mechanism
        // (the rods from the pivot to B's tip) within its dead zone.
        assert_eq!(
            (view.parent_frame_id.as_str(), view.child_frame_id.as_str()),
            ("view", "world")
        );
        assert_eq!(angle(&view.rotation), 0.0);
        let (vx, vy) = xy(&view.translation);
        let (cx, cy) = (-vx, -vy);
        let tip = (bx + 2.0 * q2.sin(), by - 2.0 * q2.cos());
        for (px, py) in [(0.0, 0.0), (bx, by), tip] {
            // Dead zone: 0.75 × the larger half-extent of the box at the start.
            assert!(
                (px - cx).abs() <= 2.5 && (py - cy).abs() <= 2.5,
                "{px}, {py} vs {cx}, {cy}"
            );
        }
    }
}

/// `/log` holds the run's messages and one line per impact, in the order they came.
#[test]
fn log_messages_are_what_the_run_reported() {
    for name in SCENES {
        let run = run_scene(name);
        let logs: Vec<Log> = on_protobuf_topic(&run.bytes, Topic::Log);
        let (lines, others): (Vec<&Log>, Vec<&Log>) =
            logs.iter().partition(|l| l.message.starts_with("impact #"));
        assert_eq!(others.len(), run.seen.messages.len(), "{name}");
        for (log, (t, level, text)) in others.iter().zip(&run.seen.messages) {
            let expected = match level {
                Level::Info => LogLevel::Info,
                Level::Warning => LogLevel::Warning,
                Level::Error => LogLevel::Error,
            };
            assert_eq!(
                (&log.message, log.level, log.name.as_str()),
                (text, expected as i32, "ricochet")
            );
            assert_eq!(
                log.timestamp.unwrap().total_nanos(),
                (t * 1e9).round() as u64
            );
        }
        // One line per impact, at its time, naming it, its pair, its type and ΔE.
        let ledger: Vec<ImpactRecord> = on_topic(&run.bytes, Topic::Impacts);
        assert_eq!(lines.len(), ledger.len(), "{name}");
        for (line, imp) in lines.iter().zip(&ledger) {
            assert_eq!(
                line.timestamp.unwrap().total_nanos(),
                (imp.t * 1e9).round() as u64
            );
            let text = &line.message;
            let head = format!(
                "impact #{} {}: {}, {} (case {})",
                imp.index,
                imp.pair,
                imp.law.name(),
                imp.impact_type.name(),
                imp.case
            );
            assert!(text.starts_with(&head), "{text} vs {head}");
            let de = ricochet::log::draw::significant(imp.delta_e);
            assert!(text.ends_with(&format!("ΔE = {de} J")), "{text}");
        }
    }
}

// ---------------------------------------------------------------------------------------
// Metadata

#[test]
fn metadata_holds_the_scene_the_settings_and_the_audit() {
    for name in SCENES {
        let run = run_scene(name);
        let log = ricochet::log::read_bytes(&run.bytes).unwrap();
        assert_eq!(log.ending, Ending::Complete, "{name}");
        assert_eq!(log.library, concat!("ricochet ", env!("CARGO_PKG_VERSION")));
        let scene = log.scene.as_ref().unwrap();
        assert_eq!(scene.name, name);
        // The scene file, verbatim, as on disk.
        let file = std::fs::read_to_string(repo_path(&format!("scenes/{name}.toml"))).unwrap();
        assert_eq!(scene.text, file, "{name}");
        let settings: Settings =
            serde_json::from_value(Value::Object(log.settings.clone().unwrap())).unwrap();
        assert_eq!(settings, run.scene.settings, "{name}");

        let s = &run.summary;
        let a = log.audit.as_ref().expect("an audit record");
        let expected_stop = match (name, &s.stop) {
            (_, StopReason::EndTime) => "t_end: reached the end time".to_owned(),
            (_, other) => panic!("{name}: unexpected stop {other}"),
        };
        assert_eq!(a.stop_reason, expected_stop, "{name}");
        assert_eq!(a.t_stop, s.state.t, "{name}");
        assert_eq!(a.energy_initial, s.audit.initial.total(), "{name}");
        assert_eq!(a.energy_final, s.audit.end.total(), "{name}");
        assert_eq!(a.impact_delta_e, s.audit.impact_delta_e, "{name}");
        assert_eq!(
            a.applied_work,
            s.audit.damping_work + s.audit.applied_work,
            "{name}"
        );
        assert_eq!(a.contact_work, s.audit.contact_work, "{name}");
        assert_eq!(
            a.prescribed_work,
            s.audit.impact_prescribed_work + s.audit.drive_work,
            "{name}"
        );
        // The same balance, summed in another order.
        let scale = a.energy_initial.abs().max(1.0);
        assert!(
            (a.integration_drift - s.audit.drift()).abs() <= 1e-12 * scale,
            "{name}: {} vs {}",
            a.integration_drift,
            s.audit.drift()
        );
        // Tight tolerances and exact impacts: the drift is tiny.
        assert!(a.integration_drift.abs() <= 1e-8 * scale, "{name}: {a:?}");
        let c = &s.counters;
        assert_eq!(
            (
                a.counters.impacts,
                a.counters.steps,
                a.counters.rejected_steps,
                a.counters.rhs_evaluations,
                a.counters.events,
                a.counters.state_samples
            ),
            (
                c.impacts,
                c.steps,
                c.rejected,
                c.rhs_evals,
                c.events,
                c.samples
            ),
            "{name}"
        );
        // The audit agrees with the log's own records: the ledger and the first and last
        // samples.
        let sum: f64 = log.impacts.iter().map(|i| i.delta_e).sum();
        assert_eq!(sum, a.impact_delta_e, "{name}");
        let states: Vec<StateRecord> = on_topic(&run.bytes, Topic::State);
        assert_eq!(states[0].energy.total, a.energy_initial, "{name}");
        assert_eq!(
            log.last_state.as_ref().unwrap().energy.total,
            a.energy_final
        );
        assert_eq!(log.last_state.as_ref(), states.last());
    }
}

// ---------------------------------------------------------------------------------------
// Determinism

#[test]
fn two_runs_of_a_scene_give_byte_identical_files() {
    for name in SCENES {
        let a = run_scene(name).bytes;
        let b = run_scene(name).bytes;
        assert!(
            a == b,
            "{name}: two runs differ ({} vs {} bytes)",
            a.len(),
            b.len()
        );
        // Through a file on disk as through memory.
        let path = PathBuf::from(env!("CARGO_TARGET_TMPDIR")).join(format!("sim_log_{name}.mcap"));
        let writer = LogWriter::create(&path, LogOptions::default()).unwrap();
        let (_, file) = run_with(
            load(name),
            MaterialOverride::default(),
            writer,
            Hook::None,
            None,
        );
        drop(file);
        assert!(
            std::fs::read(&path).unwrap() == a,
            "{name}: the file differs from the in-memory log"
        );
        std::fs::remove_file(&path).unwrap();
    }
}

// ---------------------------------------------------------------------------------------
// Runs that stop early

#[test]
fn an_interrupted_run_leaves_a_complete_log() {
    const K: usize = 50;
    let flag = AtomicBool::new(false);
    let hook = Hook::Interrupt {
        after: K,
        flag: &flag,
    };
    let run = run_hooked(
        load("pendulum_wall"),
        MaterialOverride::default(),
        hook,
        Some(&flag),
    );
    assert_eq!(run.fired_at, Some(K));
    let t = run.summary.state.t;
    assert!(
        matches!(run.summary.stop, StopReason::Interrupted { t: ti } if ti == t),
        "{:?}",
        run.summary.stop
    );
    // 100 Hz: the 50th sample is at 0.49 s (with 2 samples at the impact at 0.53 s, if
    // any before), far from the end time of 10 s.
    assert!((0.49..1.0).contains(&t), "stopped at {t}");

    // The file was finished: a summary section, and the audit says why it stopped.
    let summary = Summary::read(&run.bytes)
        .unwrap()
        .expect("a summary section");
    let log = ricochet::log::read_bytes(&run.bytes).unwrap();
    assert_eq!(log.ending, Ending::Complete);
    let audit = log.audit.as_ref().unwrap();
    assert_eq!(audit.stop_reason, "interrupted: interrupted");
    assert_eq!(audit.t_stop, t);
    // It holds exactly the samples written: those up to the flag, the rest of the step
    // that was under way, and the final sample at the stop time.
    let states: Vec<StateRecord> = on_topic(&run.bytes, Topic::State);
    assert_eq!(states.len(), run.seen.samples.len());
    assert_eq!(
        summary.stats.as_ref().unwrap().message_count,
        (messages(&run.bytes)).len() as u64
    );
    for (s, (ts, q, ..)) in states.iter().zip(&run.seen.samples) {
        assert_eq!((s.t, &s.q), (*ts, q));
    }
    assert!(
        states.len() > K && states.len() <= K + 12,
        "{}",
        states.len()
    );
    assert_eq!(states.last().unwrap().t, t);
    assert_eq!(states[K - 1].t, run.seen.samples[K - 1].0);
    assert_eq!(audit.counters.state_samples, states.len() as u64);
    assert_eq!(log.impacts.len(), run.seen.impacts.len());
    let last_log: Vec<Log> = on_protobuf_topic(&run.bytes, Topic::Log);
    let last_log = last_log.last().unwrap();
    assert_eq!(last_log.level, LogLevel::Warning as i32);
    assert_eq!(
        last_log.message,
        format!("run stopped at t = {t} s: interrupted")
    );
}

/// A run whose impact law fails: `pendulum_wall` with μ = 25 (an override). Its one
/// degree of freedom makes W singular (rank 1, `m_nt/m_tt = −20`), and with `μ ≥ 20`
/// friction holds the approaching contact: the first impact jams (`ImpactError::Jam`).
/// The run stops there with an `error: …` audit and a readable log up to that instant.
#[test]
fn a_failed_run_leaves_a_complete_log() {
    let overrides = MaterialOverride {
        mu: Some(25.0),
        ..MaterialOverride::default()
    };
    let run = run_hooked(load("pendulum_wall"), overrides, Hook::None, None);
    let t = run.summary.state.t;
    let scene = load("pendulum_wall");
    let collider = |name| scene.model.collider_by_name(name).unwrap();
    let bob_wall = (scene.model.pair_between(collider("bob"), collider("wall"))).unwrap();
    match &run.summary.stop {
        StopReason::Failed(SimError::Impact {
            t: ti,
            pair,
            name,
            source: ImpactError::Jam { law: "newton" },
        }) => {
            assert_eq!(*ti, t);
            assert_eq!((*pair, name.as_str()), (bob_wall.index(), "bob/wall"));
        }
        other => panic!("{other:?}"),
    }
    // The first impact of the pendulum released from 60°: the same time as without the
    // override (free flight does not depend on μ).
    let free = run_hooked(
        load("pendulum_wall"),
        MaterialOverride::default(),
        Hook::None,
        None,
    );
    let t1 = free.seen.impacts[0].t;
    assert_eq!(t, t1);

    let log = ricochet::log::read_bytes(&run.bytes).unwrap();
    assert_eq!(log.ending, Ending::Complete);
    assert!(Summary::read(&run.bytes).unwrap().is_some());
    let audit = log.audit.as_ref().unwrap();
    assert!(
        audit.stop_reason.starts_with(&format!(
            "error: at t = {t}: the impact on bob/wall failed: the contact jams"
        )),
        "{}",
        audit.stop_reason
    );
    assert_eq!(audit.t_stop, t);
    assert_eq!(audit.counters.impacts, 0);
    assert!(log.impacts.is_empty());
    // The grid up to t₁ (100 Hz) and the sample just before the impact.
    let grid = (t * 100.0).floor() as u64 + 1;
    assert_eq!(log.count(Topic::State), grid + 1);
    assert_eq!(log.count(Topic::State), run.seen.samples.len() as u64);
    let logs: Vec<Log> = on_protobuf_topic(&run.bytes, Topic::Log);
    let last_log = logs.last().unwrap();
    assert_eq!(last_log.level, LogLevel::Error as i32);
    assert!(last_log.message.contains("failed"), "{}", last_log.message);
}

#[test]
fn invalid_overrides_are_refused_before_the_run() {
    let scene = load("bouncing_ball");
    for (e, mu) in [
        (Some(1.5), None),
        (Some(-0.1), None),
        (None, Some(-1.0)),
        (None, Some(f64::NAN)),
    ] {
        let overrides = MaterialOverride {
            e,
            mu,
            ..MaterialOverride::default()
        };
        let err = Simulation::new(&scene.model, &scene.settings, overrides)
            .err()
            .unwrap();
        assert!(matches!(err, SimError::Override { .. }), "{err}");
    }
}

/// A run whose log fails (the observer refuses a sample: a full disk) stops with
/// `SimError::Observer`; the file still finishes, holding the samples written before.
#[test]
fn a_run_whose_log_fails_still_finishes_its_file() {
    const K: usize = 120;
    let run = run_hooked(
        load("pendulum_wall"),
        MaterialOverride::default(),
        Hook::FailAfter(K),
        None,
    );
    assert_eq!(run.fired_at, Some(K));
    let t = run.summary.state.t;
    assert!(
        matches!(&run.summary.stop, StopReason::Failed(SimError::Observer { message, .. }) if message == "no space left on device"),
        "{:?}",
        run.summary.stop
    );
    let log = ricochet::log::read_bytes(&run.bytes).unwrap();
    assert_eq!(log.ending, Ending::Complete);
    let audit = log.audit.as_ref().unwrap();
    assert!(audit.stop_reason.starts_with("error: at t = "), "{audit:?}");
    assert!(
        audit
            .stop_reason
            .ends_with("the log failed: no space left on device")
    );
    assert_eq!(log.count(Topic::State), K as u64);
    assert_eq!(log.count(Topic::Tf), K as u64);
    let states: Vec<StateRecord> = on_topic(&run.bytes, Topic::State);
    for (s, (ts, q, ..)) in states.iter().zip(&run.seen.samples) {
        assert_eq!((s.t, &s.q), (*ts, q));
    }
    // The refused sample was the next on the grid, and the run stopped at it or at the
    // end of the step that holds it.
    assert!(t > states.last().unwrap().t, "{t}");
    assert_eq!(log.impacts.len(), run.seen.impacts.len());
}

/// What a process killed after a flush leaves: the bytes of a log that was never
/// finished read back up to the flush, with `ricochet::log::read_bytes` and `mcap`.
#[test]
fn a_killed_run_leaves_a_log_readable_up_to_its_last_flush() {
    const K: usize = 300;
    let file = SharedFile::default();
    let writer = LogWriter::new(file.clone(), LogOptions::default()).unwrap();
    let hook = Hook::Snapshot {
        after: K,
        file: file.clone(),
        taken: None,
    };
    let (run, _) = run_with(
        load("pendulum_wall"),
        MaterialOverride::default(),
        writer,
        hook,
        None,
    );
    let (bytes, impacts) = run.snapshot.clone().expect("a snapshot");
    assert!(matches!(run.summary.stop, StopReason::EndTime));
    // Past the impacts at 0.53, 1.55 and 2.55 s: the 300th sample is at 2.93 s.
    assert_eq!(impacts, 3);

    assert!(Summary::read(&bytes).is_err(), "no footer, no summary");
    let read = ricochet::log::read_bytes(&bytes).unwrap();
    assert!(
        matches!(read.ending, Ending::Truncated { .. }),
        "{:?}",
        read.ending
    );
    assert_eq!(read.scene.as_ref().unwrap().name, "pendulum_wall");
    assert!(read.settings.is_some());
    assert_eq!(read.audit, None, "the run did not end");
    assert_eq!(read.count(Topic::State), K as u64);
    assert_eq!(read.count(Topic::Tf), K as u64);
    assert_eq!(read.count(Topic::Impacts), impacts as u64);
    assert_eq!(read.count(Topic::Geometry), 1);
    assert_eq!(read.count(Topic::Scene), impacts as u64);
    let (t, q, u, e) = &run.seen.samples[K - 1];
    let last = read.last_state.as_ref().unwrap();
    assert_eq!(
        (last.t, &last.q, &last.u, last.energy.total),
        (*t, q, u, *e)
    );
    // The flushed ledger is the head of the full one.
    let full = ricochet::log::read_bytes(&file.snapshot()).unwrap();
    assert_eq!(full.ending, Ending::Complete);
    assert_eq!(read.impacts[..], full.impacts[..impacts]);
    // The mcap crate reads the same messages, then reports the cut.
    let mut stream = MessageStream::new(&bytes).unwrap();
    let ok = stream.by_ref().take_while(|m| m.is_ok()).count() as u64;
    assert_eq!(ok, read.message_counts.values().sum::<u64>());
}

/// Regression (`../shared/repro/painleve_vx16.toml`): the rod of `painleve_rod` pushed
/// at 16 m/s meets, in the cascade of a simultaneous impact, an impact with a zero
/// approach speed, whose α is not a number; the log refused the ledger row ("non-finite
/// `alpha`") and the run failed. Format 2 leaves that α out, which the schema allows.
#[test]
fn an_impact_without_approach_speed_logs_no_alpha() {
    let mut scene = load("painleve_rod");
    scene.initial.u[0] = 16.0;
    let run = run_hooked(scene, MaterialOverride::default(), Hook::None, None);
    assert!(
        matches!(run.summary.stop, StopReason::EndTime),
        "{}",
        run.summary.stop
    );
    let ledger: Vec<ImpactRecord> = on_topic(&run.bytes, Topic::Impacts);
    let mut nulls = 0;
    for r in &ledger {
        match r.alpha {
            // α = v_t / |v_n| where there is an approach speed…
            Some(alpha) => {
                let expected = r.v_a.t / r.v_a.n.abs();
                assert!((alpha - expected).abs() <= 1e-12 * expected.abs(), "{r:?}");
            }
            // …and none where it vanishes (to rounding).
            None => {
                assert!(r.v_a.n.abs() <= 1e-9 * r.v_a.t.abs(), "{r:?}");
                nulls += 1;
            }
        }
    }
    assert!(nulls > 0, "no impact without approach speed");
    // The JSON has no `alpha` there, and it passes the shipped schema.
    let schema: Value =
        serde_json::from_slice(&std::fs::read(repo_path("schemas/ricochet/Impact.json")).unwrap())
            .unwrap();
    let validator = jsonschema::validator_for(&schema).unwrap();
    let mut without = 0;
    for (topic, _, data) in messages(&run.bytes) {
        if topic == Topic::Impacts.name() {
            let json: Value = serde_json::from_slice(&data).unwrap();
            assert!(validator.is_valid(&json), "{json}");
            without += usize::from(json.get("alpha").is_none());
        }
    }
    assert_eq!(without, nulls);
}
