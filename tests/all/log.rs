//! The MCAP log (`src/log/`): a synthetic run written with `LogWriter`, read back with the
//! `mcap` crate (`Summary::read`, `MessageStream`) and with `ricochet::log::read`.
//!
//! The run: scene and settings metadata, a geometry update drawing every shape kind, 100
//! `/state` samples with their `/tf` transforms, 3 impacts with their impulse arrows, `/log`
//! messages, a deletion, and the audit. Checked here: topics, schema names and encodings,
//! message counts, every chunk holding messages, exact round trip of every value (JSON and
//! protobuf), validation of every JSON message against its shipped JSON schema and of the
//! embedded protobuf schemas, byte-identical output of two writes, reading a file cut short
//! (a killed process), finishing on drop, rejection of invalid times, the committed
//! fixtures `tests/data/fixture.mcap` (format 2) and `tests/data/fixture_v1.mcap` (format 1,
//! still read), and `ricochet inspect`.
//!
//! Regenerate the fixture with `bash tests/data/regenerate.sh`.

use crate::common::mcap_check;
use crate::common::shared_file;

use std::collections::{BTreeMap, HashMap};
use std::io::{Cursor, Seek, SeekFrom, Write};
use std::path::PathBuf;

use mcap::{MessageStream, Summary};
use parry2d_f64::math::{Pose as Pose2, Vector};
use parry2d_f64::shape::{
    Ball, Capsule, ConvexPolygon, Cuboid, HalfSpace, Polyline, Segment, Shape, Triangle,
};
use ricochet::impact::{CollisionType, ContactVelocity, ImpactMatrix, Law};
use ricochet::log::draw::{self, ArrowStyle, DrawStyle, ShapeDrawing};
use ricochet::log::foxglove::{
    Color, Decode, Encode, SceneEntityDeletion, Timestamp, rgba, timestamp,
};
use ricochet::log::{
    Audit, ContactMode, ContactState, Counters, Ending, Energy, FrameTransforms, ImpactRecord, Log,
    LogError, LogLevel, LogOptions, LogWriter, Planar, SceneUpdate, StateRecord, Topic,
};
use ricochet::settings::Settings;
use serde_json::Value;
use shared_file::SharedFile;

// ---------------------------------------------------------------------------------------
// The synthetic run

/// One message of the run, in the order written.
#[derive(Clone, Debug, PartialEq)]
enum Event {
    Geometry(f64, SceneUpdate),
    Scene(f64, SceneUpdate),
    Tf(f64, FrameTransforms),
    State(StateRecord),
    Impact(Box<ImpactRecord>),
    Log(f64, LogLevel, String),
}

struct Run {
    scene_name: &'static str,
    scene_text: &'static str,
    settings: Settings,
    events: Vec<Event>,
    audit: Audit,
}

const N_STATES: usize = 100;
const IMPACT_TIMES: [f64; 3] = [0.123, 0.456, 0.789];
const SCENE_TEXT: &str = "version = 1\nname = \"synthetic\"\n\n[[body]]\nname = \"ball\"\nshape = { ball = { radius = 0.1 } }\n";

const BLUE: Color = rgba(0.2, 0.4, 0.9, 1.0);
const GREY: Color = rgba(0.5, 0.5, 0.5, 0.6);

/// A geometry update drawing every shape kind: bodies (ball, capsule, cuboid, convex
/// polygon, triangle) in their frames, a skeleton, obstacles (half-space, segment,
/// polyline) in `world`.
fn scene_at_start() -> SceneUpdate {
    let style = DrawStyle::default();
    let ball = Ball::new(0.1);
    let rod = Capsule::new_x(0.4, 0.03);
    let block = Cuboid::new(Vector::new(0.2, 0.1));
    let wedge = ConvexPolygon::from_convex_polyline(vec![
        Vector::new(0.0, 0.0),
        Vector::new(0.3, 0.0),
        Vector::new(0.0, 0.2),
    ])
    .unwrap();
    let fin = Triangle::new(
        Vector::new(0.0, 0.0),
        Vector::new(0.1, 0.0),
        Vector::new(0.0, 0.1),
    );
    let ground = HalfSpace::new(Vector::Y);
    let wall = Segment::new(Vector::new(2.0, 0.0), Vector::new(2.0, 1.0));
    let steps = Polyline::new(
        vec![
            Vector::new(-2.0, 0.3),
            Vector::new(-1.5, 0.3),
            Vector::new(-1.5, 0.0),
        ],
        None,
    );
    let id = Pose2::IDENTITY;
    let entities = vec![
        draw::body_entity(0.0, "ball", &[d(&ball, id, BLUE)], &style).unwrap(),
        draw::body_entity(
            0.0,
            "rod",
            &[d(&rod, Pose2::translation(0.4, 0.0), BLUE)],
            &style,
        )
        .unwrap(),
        draw::body_entity(
            0.0,
            "block",
            &[
                d(&block, id, BLUE),
                d(&wedge, Pose2::new(Vector::new(0.2, 0.1), 0.5), BLUE),
            ],
            &style,
        )
        .unwrap(),
        draw::body_entity(0.0, "fin", &[d(&fin, id, BLUE)], &style).unwrap(),
        draw::obstacle_entity(0.0, "ground", &[d(&ground, id, GREY)], &style).unwrap(),
        draw::obstacle_entity(0.0, "wall", &[d(&wall, id, GREY)], &style).unwrap(),
        draw::obstacle_entity(0.0, "steps", &[d(&steps, id, GREY)], &style).unwrap(),
        draw::skeleton_entity(
            0.0,
            "fin",
            &[Vector::new(0.3, 0.0)],
            (Vector::new(0.1, 0.05), true),
            BLUE,
            &style,
        )
        .unwrap(),
    ];
    SceneUpdate {
        deletions: vec![],
        entities,
    }
}

fn d(shape: &dyn Shape, pose: Pose2, color: Color) -> ShapeDrawing<'_> {
    ShapeDrawing { shape, pose, color }
}

/// Sample `i` of a ball bouncing on the ground: awkward binary fractions on purpose.
fn state(i: usize) -> StateRecord {
    let t = i as f64 * 0.01;
    let y = 0.5 + 0.25 * (7.0 * t).cos();
    let q = vec![0.1 * i as f64, y, t / 3.0];
    let u = vec![0.1, -1.75 * (7.0 * t).sin(), 1.0 / 3.0];
    let energy = Energy::new(0.5 * (u[0] * u[0] + u[1] * u[1]), 9.81 * y);
    let mode = if i.is_multiple_of(10) {
        ContactMode::Sliding
    } else {
        ContactMode::Free
    };
    let contacts = vec![
        ContactState::new("ball/ground", mode, y - 0.1),
        ContactState::new("ball/wall", ContactMode::Free, 2.0 - q[0] - 0.1),
    ];
    let impacts = IMPACT_TIMES.iter().filter(|&&ti| ti <= t).count() as u64;
    StateRecord::new(t, q, u, energy, contacts, impacts)
}

/// Impact `k`, with the ledger fields consistent with each other.
fn impact(k: usize) -> ImpactRecord {
    let (mnn, mnt, mtt, mu, e) = (1.0, 0.2, 3.5, 0.3, 0.5);
    let v_a = ContactVelocity {
        n: -2.0 - k as f64,
        t: 0.7,
    };
    let i_n = 1.0242 + 0.1 * k as f64;
    let i_t = -0.1143;
    let v_s = ContactVelocity {
        n: -e * v_a.n,
        t: 0.2 - 0.05 * k as f64,
    };
    let work_n = 0.5 * i_n * (v_s.n + v_a.n);
    let work_t = 0.5 * i_t * (v_s.t + v_a.t);
    let energy_before = 10.0 - k as f64;
    ImpactRecord {
        t: IMPACT_TIMES[k],
        pair: "ball/ground".to_owned(),
        body_a: "ball".to_owned(),
        body_b: "world".to_owned(),
        law: [Law::Newton, Law::KaneLevinson, Law::Stronge][k],
        impact_type: [
            CollisionType::Sticking,
            CollisionType::ReverseSliding,
            CollisionType::ForwardSliding,
        ][k],
        case: [1, 3, 5][k],
        alpha: Some(v_a.t / v_a.n.abs()),
        w: ImpactMatrix::new(mnn, mnt, mtt),
        g: mu * mtt - mnt,
        h: mnn - mu * mnt,
        p: mu * mtt + mnt,
        q: mnn + mu * mnt,
        v_a,
        v_s,
        i_n,
        i_t,
        support: None,
        delta_u: vec![i_t, i_n, 0.1 * i_t],
        energy_before,
        energy_after: energy_before + work_n + work_t,
        delta_e: work_n + work_t,
        work_n,
        work_t,
        index: k as u64,
        cause: ricochet::log::ImpactCause::Collision,
        e,
        mu,
        prescribed_work: 0.0,
        point: Planar {
            x: 0.1 * k as f64,
            y: 0.0,
        },
        normal: Planar { x: 0.0, y: 1.0 },
        tangent: Planar { x: 1.0, y: 0.0 },
    }
}

fn synthetic() -> Run {
    let mut events = vec![
        Event::Geometry(0.0, scene_at_start()),
        Event::Log(0.0, LogLevel::Info, "run started".to_owned()),
    ];
    let mut next_impact = 0;
    for i in 0..N_STATES {
        let s = state(i);
        while next_impact < IMPACT_TIMES.len() && IMPACT_TIMES[next_impact] <= s.t {
            let imp = impact(next_impact);
            let arrow = draw::impulse_arrow(&imp, 0.4, &ArrowStyle::default()).unwrap();
            events.push(Event::Impact(Box::new(imp.clone())));
            events.push(Event::Scene(
                imp.t,
                SceneUpdate {
                    deletions: vec![],
                    entities: vec![arrow],
                },
            ));
            events.push(Event::Log(
                imp.t,
                LogLevel::Info,
                format!("impact {next_impact}: {}", imp.impact_type),
            ));
            next_impact += 1;
        }
        let (x, y, theta) = (s.q[0], s.q[1], s.q[2]);
        let tf =
            draw::body_transforms(s.t, [("ball", Pose2::new(Vector::new(x, y), theta))]).unwrap();
        events.push(Event::Tf(s.t, tf));
        events.push(Event::State(s));
    }
    events.push(Event::Log(
        0.5,
        LogLevel::Warning,
        "energy drift above 1e-6 J".to_owned(),
    ));
    let deletion = SceneEntityDeletion {
        timestamp: Some(timestamp(0.99).unwrap()),
        // MATCHING_ID
        r#type: 0,
        id: "impulse/ball/ground".to_owned(),
    };
    events.push(Event::Scene(
        0.99,
        SceneUpdate {
            deletions: vec![deletion],
            entities: vec![],
        },
    ));
    let audit = Audit::new(
        "t_end",
        0.99,
        (state(0).energy.total, state(N_STATES - 1).energy.total),
        (
            (0..3).map(|k| impact(k).delta_e).sum(),
            -1.25e-3,
            -0.5e-3,
            0.0,
        ),
        Counters {
            impacts: 3,
            steps: 1234,
            rejected_steps: 7,
            rhs_evaluations: 7446,
            events: 5,
            state_samples: N_STATES as u64,
        },
    );
    Run {
        scene_name: "synthetic",
        scene_text: SCENE_TEXT,
        settings: Settings::default(),
        events,
        audit,
    }
}

/// Writes the metadata and the first `n` events of `run`; the audit too when `n` is all.
fn write_prefix<W: Write + Seek + Send + 'static>(run: &Run, log: &mut LogWriter<W>, n: usize) {
    log.scene(run.scene_name, run.scene_text).unwrap();
    log.settings(&run.settings).unwrap();
    for event in &run.events[..n] {
        match event {
            Event::Geometry(t, update) => log.geometry(*t, update).unwrap(),
            Event::Scene(t, update) => log.scene_update(*t, update).unwrap(),
            Event::Tf(t, tf) => log.transforms(*t, tf).unwrap(),
            Event::State(s) => log.state(s).unwrap(),
            Event::Impact(i) => log.impact(i).unwrap(),
            Event::Log(t, level, msg) => log.log(*t, *level, msg).unwrap(),
        }
    }
    if n == run.events.len() {
        log.audit(&run.audit).unwrap();
    }
}

fn write_run(run: &Run, options: LogOptions) -> Vec<u8> {
    let mut log = LogWriter::new(Cursor::new(Vec::new()), options).unwrap();
    write_prefix(run, &mut log, run.events.len());
    log.finish().unwrap().into_inner()
}

/// What a message holds: JSON (ricochet's topics) or protobuf bytes (Foxglove's).
#[derive(Clone, Debug, PartialEq)]
enum Payload {
    Json(Value),
    Protobuf(Vec<u8>),
}

/// The protobuf encoding of a Foxglove message, by the SDK.
fn protobuf<M: Encode>(m: &M) -> Payload {
    let mut bytes = Vec::new();
    m.encode(&mut bytes).unwrap();
    Payload::Protobuf(bytes)
}

/// The topic and time (s) of an event, and its message.
fn expected_message(event: &Event) -> (Topic, f64, Payload) {
    let json = |v: &dyn erased::Json| Payload::Json(v.to_json());
    match event {
        Event::Geometry(t, u) => (Topic::Geometry, *t, protobuf(u)),
        Event::Scene(t, u) => (Topic::Scene, *t, protobuf(u)),
        Event::Tf(t, tf) => (Topic::Tf, *t, protobuf(tf)),
        Event::State(s) => (Topic::State, s.t, json(s)),
        Event::Impact(i) => (Topic::Impacts, i.t, json(i)),
        Event::Log(t, level, message) => (
            Topic::Log,
            *t,
            protobuf(&Log {
                timestamp: Some(timestamp(*t).unwrap()),
                level: *level as i32,
                message: message.clone(),
                name: "ricochet".to_owned(),
                file: String::new(),
                line: 0,
            }),
        ),
    }
}

mod erased {
    pub trait Json {
        fn to_json(&self) -> serde_json::Value;
    }
    impl<T: serde::Serialize> Json for T {
        fn to_json(&self) -> serde_json::Value {
            serde_json::to_value(self).unwrap()
        }
    }
}

/// Exact nanoseconds of an event time: every time of the run is a whole number of
/// milliseconds, computed here in integers, independently of the writer's rounding.
fn exact_ns(t: f64) -> u64 {
    let ms = (t * 1000.0).round() as u64;
    assert!(
        (ms as f64 / 1000.0 - t).abs() < 1e-12,
        "{t} is not whole ms"
    );
    ms * 1_000_000
}

fn repo_path(rel: &str) -> PathBuf {
    PathBuf::from(env!("CARGO_MANIFEST_DIR")).join(rel)
}

fn tmp_path(name: &str) -> PathBuf {
    PathBuf::from(env!("CARGO_TARGET_TMPDIR")).join(name)
}
fn count_events(events: &[Event], topic: Topic) -> u64 {
    events
        .iter()
        .filter(|e| expected_message(e).0 == topic)
        .count() as u64
}

// ---------------------------------------------------------------------------------------
// Tests

#[test]
fn topics_schemas_and_counts_read_back_with_the_mcap_crate() {
    let run = synthetic();
    let bytes = write_run(&run, LogOptions::default());
    let summary = Summary::read(&bytes).unwrap().expect("a summary section");

    // topic → (schema, encoding, count)
    let expected: BTreeMap<&str, (&str, &str, u64)> = BTreeMap::from([
        ("/state", ("ricochet.State", "json", N_STATES as u64)),
        ("/impacts", ("ricochet.Impact", "json", 3)),
        ("/geometry", ("foxglove.SceneUpdate", "protobuf", 1)),
        ("/scene", ("foxglove.SceneUpdate", "protobuf", 3 + 1)),
        (
            "/tf",
            ("foxglove.FrameTransforms", "protobuf", N_STATES as u64),
        ),
        ("/log", ("foxglove.Log", "protobuf", 1 + 3 + 1)),
    ]);
    let stats = summary.stats.as_ref().unwrap();
    let mut seen = BTreeMap::new();
    for (id, channel) in &summary.channels {
        let schema = channel.schema.as_ref().expect("every channel has a schema");
        let schema_encoding = match channel.message_encoding.as_str() {
            "json" => "jsonschema",
            other => other,
        };
        assert_eq!(schema.encoding, schema_encoding, "{}", channel.topic);
        let count = stats.channel_message_counts.get(id).copied().unwrap_or(0);
        let encoding = channel.message_encoding.as_str();
        seen.insert(
            channel.topic.as_str(),
            (schema.name.as_str(), encoding, count),
        );
    }
    assert_eq!(seen, expected);
    // `/geometry` and `/scene` share one schema record.
    assert_eq!(summary.schemas.len(), 5);
    assert_eq!(stats.message_count, 2 * N_STATES as u64 + 3 + 1 + 4 + 5);
    assert_eq!(stats.message_start_time, 0);
    assert_eq!(stats.message_end_time, 990_000_000);
    let names: Vec<&str> = summary
        .metadata_indexes
        .iter()
        .map(|m| m.name.as_str())
        .collect();
    assert_eq!(names, ["ricochet", "scene", "settings", "audit"]);
    // Metadata records read through the summary's index.
    let format = mcap::read::metadata(&bytes, &summary.metadata_indexes[0]).unwrap();
    assert_eq!(format.metadata["format_version"], "2");
    let scene = mcap::read::metadata(&bytes, &summary.metadata_indexes[1]).unwrap();
    assert_eq!(scene.metadata["name"], "synthetic");
    assert_eq!(scene.metadata["text"], SCENE_TEXT);
}

/// Readers that bundle `@mcap/core` before 2025 (Foxglove Studio 1.48) refuse a chunk
/// without a message index; format 1 began every log with one (its schemas and channels).
#[test]
fn every_chunk_holds_messages() {
    let run = synthetic();
    for chunk_size in [64 * 1024, 2048, 1] {
        let options = LogOptions {
            chunk_size,
            ..LogOptions::default()
        };
        let bytes = write_run(&run, options);
        mcap_check::assert_every_chunk_has_messages(&bytes);
        let chunks = Summary::read(&bytes).unwrap().unwrap().chunk_indexes.len();
        assert!(chunks >= 1, "{chunk_size}: {chunks} chunks");
    }
    // The check can fail: the format 1 fixture has such a chunk.
    let v1 = std::fs::read(repo_path(FIXTURE_V1)).unwrap();
    let caught = std::panic::catch_unwind(|| mcap_check::assert_every_chunk_has_messages(&v1));
    assert!(caught.is_err(), "the format 1 fixture passed the check");
}

/// Every LZ4 chunk is the LZ4 frame of its records as mcap 0.26.0 as published made it,
/// but for the content checksum: its records fed to liblz4's frame encoder (level 0, no
/// block checksum, no content checksum: the chunk's CRC covers the same bytes) field by
/// field. vendor/mcap gathers them in 64 KiB first (PATCHES.md); the frame must not change. Re-encoded here from the decompressed records in pieces of 1 to
/// 40 bytes and in one write, chunks of one LZ4 block and of several (1 MiB), both must
/// give the chunk's bytes; the records' CRC and size are the chunk header's.
#[test]
fn lz4_chunks_are_one_frame_of_their_records() {
    use lz4::liblz4::{BlockChecksum, ContentChecksum};
    use mcap::records::Record;
    use std::io::Read;

    fn encode(records: &[u8], piece: impl Fn(usize) -> usize) -> Vec<u8> {
        let mut enc = lz4::EncoderBuilder::new()
            .level(0)
            .block_checksum(BlockChecksum::NoBlockChecksum)
            .checksum(ContentChecksum::NoChecksum)
            .build(Vec::new())
            .unwrap();
        let mut at = 0;
        let mut k = 0;
        while at < records.len() {
            let n = piece(k).min(records.len() - at);
            enc.write_all(&records[at..at + n]).unwrap();
            at += n;
            k += 1;
        }
        let (out, result) = enc.finish();
        result.unwrap();
        out
    }

    let run = synthetic();
    let mut several_blocks = 0;
    for chunk_size in [64 * 1024, 1024 * 1024] {
        let options = LogOptions {
            chunk_size,
            ..LogOptions::default()
        };
        let bytes = write_run(&run, options);
        let mut chunks = 0;
        for record in mcap::read::LinearReader::new(&bytes).unwrap() {
            let Record::Chunk { header, data } = record.unwrap() else {
                continue;
            };
            chunks += 1;
            assert_eq!(header.compression, "lz4");
            let mut records = Vec::new();
            lz4::Decoder::new(&data[..])
                .unwrap()
                .read_to_end(&mut records)
                .unwrap();
            assert_eq!(records.len() as u64, header.uncompressed_size);
            assert_eq!(crc32fast::hash(&records), header.uncompressed_crc);
            if records.len() > 64 * 1024 {
                several_blocks += 1;
            }
            // Pieces of 1, 8, 2, 4, 8, 8, 40, … bytes: an opcode, a length, a header, data.
            let small = encode(&records, |k| [1, 8, 2, 4, 8, 8, 40, 3, 17][k % 9]);
            assert!(
                small == data[..],
                "chunk {chunks}: not the frame of small writes"
            );
            let whole = encode(&records, |_| usize::MAX);
            assert!(
                whole == data[..],
                "chunk {chunks}: not the frame of one write"
            );
        }
        assert!(chunks >= 1);
    }
    assert!(several_blocks >= 1, "no chunk of more than one LZ4 block");
}

/// `mcap::Writer::into_inner` on an open LZ4 chunk ends its frame with every message given
/// so far in it, as mcap 0.26.0 as published did (its encoder's buffered block went into
/// the frame): vendor/mcap's gathered bytes are not dropped. The frame is found by its
/// magic number after the chunk's header and decoded with liblz4.
#[test]
fn an_lz4_chunk_given_up_still_holds_its_messages() {
    use std::io::Read;
    let mut w = mcap::WriteOptions::new()
        .compression(Some(mcap::Compression::Lz4))
        .chunk_size(None)
        .create(Cursor::new(Vec::new()))
        .unwrap();
    let schema = w.add_schema("S", "jsonschema", b"{}").unwrap();
    let channel = w
        .add_channel(schema, "/a", "json", &BTreeMap::new())
        .unwrap();
    let payloads: Vec<String> = (0..50).map(|i| format!("{{\"i\":{i}}}")).collect();
    for (i, p) in payloads.iter().enumerate() {
        let header = mcap::records::MessageHeader {
            channel_id: channel,
            sequence: i as u32,
            log_time: i as u64,
            publish_time: i as u64,
        };
        w.write_to_known_channel(&header, p.as_bytes()).unwrap();
    }
    let bytes = w.into_inner().into_inner();
    let magic = 0x184D_2204_u32.to_le_bytes();
    let at = (bytes.windows(4).position(|x| x == magic)).expect("an LZ4 frame");
    let mut records = Vec::new();
    lz4::Decoder::new(&bytes[at..])
        .unwrap()
        .read_to_end(&mut records)
        .unwrap();
    let text = String::from_utf8_lossy(&records);
    for p in &payloads {
        assert!(text.contains(p.as_str()), "{p} is not in the frame");
    }
}

/// Exact (bit-for-bit) decoding needs `serde_json/float_roundtrip`, which the
/// `jsonschema` dev-dependency turns on for test builds; protobuf doubles are their bits.
#[test]
fn every_value_round_trips_exactly() {
    let run = synthetic();
    let bytes = write_run(&run, LogOptions::default());
    let mut sequences: HashMap<String, u32> = HashMap::new();
    let mut n = 0;
    for (msg, event) in MessageStream::new(&bytes).unwrap().zip(&run.events) {
        let msg = msg.unwrap();
        let (topic, t, expected) = expected_message(event);
        assert_eq!(msg.channel.topic, topic.name());
        assert_eq!(msg.log_time, exact_ns(t), "log time of {event:?}");
        assert_eq!(msg.publish_time, msg.log_time);
        // Sequence numbers count up from 0 per channel.
        let seq = sequences.entry(msg.channel.topic.clone()).or_default();
        assert_eq!(msg.sequence, *seq);
        *seq += 1;
        let got = match &expected {
            Payload::Json(_) => Payload::Json(serde_json::from_slice(&msg.data).unwrap()),
            Payload::Protobuf(_) => Payload::Protobuf(msg.data.to_vec()),
        };
        assert_eq!(got, expected);
        // Typed round trip, compared with the written value bit for bit (==).
        match event {
            Event::State(s) => assert_eq!(
                &serde_json::from_slice::<StateRecord>(&msg.data).unwrap(),
                s
            ),
            Event::Impact(i) => assert_eq!(
                &serde_json::from_slice::<ImpactRecord>(&msg.data).unwrap(),
                &**i
            ),
            Event::Geometry(_, u) | Event::Scene(_, u) => {
                assert_eq!(&SceneUpdate::decode(&msg.data[..]).unwrap(), u)
            }
            Event::Tf(_, tf) => assert_eq!(&FrameTransforms::decode(&msg.data[..]).unwrap(), tf),
            Event::Log(..) => {
                let log = Log::decode(&msg.data[..]).unwrap();
                assert_eq!(log.timestamp.unwrap().total_nanos(), msg.log_time);
            }
        }
        n += 1;
    }
    assert_eq!(n, run.events.len());
    // A few values by hand, independent of the encoders: t = 0.37 s is sec 0, nsec
    // 370 000 000.
    let tf = run.events.iter().find_map(|e| match e {
        Event::Tf(t, tf) if (*t - 0.37).abs() < 1e-12 => Some(tf),
        _ => None,
    });
    assert_eq!(
        tf.unwrap().transforms[0].timestamp,
        Some(Timestamp::new(0, 370_000_000))
    );
}

#[test]
fn every_message_validates_against_its_schema() {
    use prost_types::FileDescriptorSet;
    let run = synthetic();
    let bytes = write_run(&run, LogOptions::default());
    let summary = Summary::read(&bytes).unwrap().unwrap();
    let mut validators = HashMap::new();
    for channel in summary.channels.values() {
        let schema = channel.schema.as_ref().unwrap();
        if channel.message_encoding == "protobuf" {
            // The embedded schema is the SDK's descriptor set, and it defines the type.
            let sdk = match schema.name.as_str() {
                "foxglove.SceneUpdate" => SceneUpdate::get_schema(),
                "foxglove.FrameTransforms" => FrameTransforms::get_schema(),
                "foxglove.Log" => Log::get_schema(),
                other => panic!("unexpected schema {other}"),
            };
            assert_eq!(&schema.data[..], &sdk.unwrap().data[..], "{}", schema.name);
            let set = <FileDescriptorSet as prost::Message>::decode(&schema.data[..]).unwrap();
            let (package, name) = schema.name.split_once('.').unwrap();
            let defined = (set.file.iter())
                .filter(|f| f.package() == package)
                .flat_map(|f| &f.message_type)
                .any(|m| m.name() == name);
            assert!(defined, "{} not defined by its descriptor set", schema.name);
            continue;
        }
        // The embedded JSON schema is the shipped file, byte for byte.
        let file = match schema.name.as_str() {
            "ricochet.State" => "schemas/ricochet/State.json",
            "ricochet.Impact" => "schemas/ricochet/Impact.json",
            other => panic!("unexpected schema {other}"),
        };
        assert_eq!(
            &schema.data[..],
            std::fs::read(repo_path(file)).unwrap(),
            "{file}"
        );
        let json: Value = serde_json::from_slice(&schema.data).unwrap();
        jsonschema::meta::validate(&json)
            .unwrap_or_else(|e| panic!("{file} is not a valid schema: {e}"));
        validators.insert(
            channel.topic.clone(),
            jsonschema::validator_for(&json).unwrap(),
        );
    }
    let mut n = 0;
    for msg in MessageStream::new(&bytes).unwrap() {
        let msg = msg.unwrap();
        n += 1;
        let Some(validator) = validators.get(&msg.channel.topic) else {
            // Protobuf: decodes as its type, and is the canonical encoding of what it
            // decodes to (nothing unknown or left over).
            let data = &msg.data[..];
            let again = match msg.channel.topic.as_str() {
                "/geometry" | "/scene" => reencode(SceneUpdate::decode(data).unwrap()),
                "/tf" => reencode(FrameTransforms::decode(data).unwrap()),
                "/log" => reencode(Log::decode(data).unwrap()),
                other => panic!("unexpected topic {other}"),
            };
            assert_eq!(
                again, data,
                "{} message {}",
                msg.channel.topic, msg.sequence
            );
            continue;
        };
        let json: Value = serde_json::from_slice(&msg.data).unwrap();
        let errors: Vec<String> = validator
            .iter_errors(&json)
            .map(|e| format!("{} at {}", e, e.instance_path()))
            .collect();
        assert!(
            errors.is_empty(),
            "{} message {}: {errors:?}",
            msg.channel.topic,
            msg.sequence
        );
    }
    assert_eq!(n, run.events.len());
}

fn reencode<M: Encode>(m: M) -> Vec<u8> {
    let mut bytes = Vec::new();
    m.encode(&mut bytes).unwrap();
    bytes
}

#[test]
fn schemas_reject_what_they_should() {
    // The validation above is only worth something if the validators can fail.
    let schema = |file: &str| -> jsonschema::Validator {
        let json: Value = serde_json::from_slice(&std::fs::read(repo_path(file)).unwrap()).unwrap();
        jsonschema::validator_for(&json).unwrap()
    };
    let state = serde_json::to_value(state(3)).unwrap();
    let v = schema("schemas/ricochet/State.json");
    assert!(v.is_valid(&state));
    let mut missing = state.clone();
    missing.as_object_mut().unwrap().remove("energy");
    assert!(!v.is_valid(&missing), "a missing field");
    let mut extra = state.clone();
    extra["velocity"] = Value::from(1.0);
    assert!(!v.is_valid(&extra), "an unknown field");
    let mut bad_mode = state.clone();
    bad_mode["contacts"][0]["mode"] = Value::from("rolling");
    assert!(!v.is_valid(&bad_mode), "an unknown mode");
    let mut negative_t = state;
    negative_t["t"] = Value::from(-0.5);
    assert!(!v.is_valid(&negative_t), "a negative time");

    let v = schema("schemas/ricochet/Impact.json");
    let imp = serde_json::to_value(impact(1)).unwrap();
    assert!(v.is_valid(&imp));
    let mut bad_case = imp.clone();
    bad_case["case"] = Value::from(6);
    assert!(!v.is_valid(&bad_case), "case 6");
    let mut bad_law = imp;
    bad_law["law"] = Value::from("hertz");
    assert!(!v.is_valid(&bad_law), "an unknown law");
}

#[test]
fn two_writes_are_byte_identical() {
    let run = synthetic();
    let a = write_run(&run, LogOptions::default());
    let b = write_run(&synthetic(), LogOptions::default());
    assert!(a == b, "two writes of the same run differ");
    // Through a file as through memory.
    let path = tmp_path("two_writes.mcap");
    let mut log = LogWriter::create(&path, LogOptions::default()).unwrap();
    write_prefix(&run, &mut log, run.events.len());
    log.finish().unwrap();
    assert!(
        std::fs::read(&path).unwrap() == a,
        "the file differs from the in-memory log"
    );
}

/// With the `zstd` feature: zstd chunks (single-threaded) are deterministic and readable.
#[cfg(feature = "zstd")]
#[test]
fn zstd_writes_are_byte_identical_and_readable() {
    use ricochet::log::Compression;
    let options = LogOptions {
        compression: Compression::Zstd,
        ..LogOptions::default()
    };
    let a = write_run(&synthetic(), options);
    assert!(
        a == write_run(&synthetic(), options),
        "two zstd writes differ"
    );
    let read = ricochet::log::read_bytes(&a).unwrap();
    assert_eq!(read.ending, Ending::Complete);
    assert_eq!(read.count(Topic::State), N_STATES as u64);
}

#[test]
fn reader_returns_metadata_impacts_and_counts() {
    let run = synthetic();
    let log = ricochet::log::read_bytes(&write_run(&run, LogOptions::default())).unwrap();
    assert_eq!(log.ending, Ending::Complete);
    assert_eq!(log.library, concat!("ricochet ", env!("CARGO_PKG_VERSION")));
    let scene = log.scene.as_ref().unwrap();
    assert_eq!(
        (scene.name.as_str(), scene.text.as_str()),
        ("synthetic", SCENE_TEXT)
    );
    let settings = Value::Object(log.settings.clone().unwrap());
    assert_eq!(
        serde_json::from_value::<Settings>(settings).unwrap(),
        run.settings
    );
    assert_eq!(log.audit.as_ref(), Some(&run.audit));
    assert_eq!(log.impacts, (0..3).map(impact).collect::<Vec<_>>());
    assert_eq!(log.last_state, Some(state(N_STATES - 1)));
    for topic in Topic::ALL {
        assert_eq!(
            log.count(topic),
            count_events(&run.events, topic),
            "{}",
            topic.name()
        );
    }
    assert_eq!(log.time_range, Some((0.0, 0.99)));

    // `read_bytes_with` gives the same, and every `/state` sample in order.
    let mut states = Vec::new();
    let bytes = write_run(&run, LogOptions::default());
    let with = ricochet::log::read_bytes_with(&bytes, &mut |s| states.push(s)).unwrap();
    assert_eq!(with, log);
    assert_eq!(states, (0..N_STATES).map(state).collect::<Vec<_>>());
}

#[test]
fn a_killed_writer_leaves_a_file_readable_up_to_its_last_flush() {
    let run = synthetic();
    // Kill the "process" after the 50th state sample and a flush, then write on without
    // flushing: what is on disk holds exactly the flushed part.
    let n_flushed = (run.events.iter())
        .position(|e| matches!(e, Event::State(s) if (s.t - 0.49).abs() < 1e-12))
        .unwrap()
        + 1;
    let file = SharedFile::default();
    let mut log = LogWriter::new(file.clone(), LogOptions::default()).unwrap();
    write_prefix(&run, &mut log, n_flushed);
    log.flush().unwrap();
    for event in &run.events[n_flushed..n_flushed + 20] {
        if let Event::State(s) = event {
            log.state(s).unwrap();
        }
    }
    let on_disk = file.snapshot();
    std::mem::forget(log); // killed: no drop, no finish

    assert!(Summary::read(&on_disk).is_err(), "no footer, no summary");
    let read = ricochet::log::read_bytes(&on_disk).unwrap();
    assert!(
        matches!(read.ending, Ending::Truncated { .. }),
        "{:?}",
        read.ending
    );
    assert_eq!(read.scene.as_ref().unwrap().name, "synthetic");
    assert!(read.settings.is_some());
    assert_eq!(read.audit, None, "the run did not end");
    let flushed = &run.events[..n_flushed];
    for topic in Topic::ALL {
        assert_eq!(
            read.count(topic),
            count_events(flushed, topic),
            "{}",
            topic.name()
        );
    }
    assert_eq!(read.count(Topic::State), 50);
    assert_eq!(read.impacts, (0..2).map(impact).collect::<Vec<_>>());
    assert_eq!(read.last_state, Some(state(49)));

    // The mcap crate's MessageStream reads the same messages, then reports the cut.
    let mut stream = MessageStream::new(&on_disk).unwrap();
    let ok = stream.by_ref().take_while(|m| m.is_ok()).count();
    assert_eq!(ok, n_flushed);
}

#[test]
fn a_file_cut_anywhere_is_read_as_far_as_it_goes() {
    let run = synthetic();
    // Small chunks, so that a cut keeps many of them.
    let options = LogOptions {
        chunk_size: 2048,
        ..LogOptions::default()
    };
    let bytes = write_run(&run, options);
    let full = ricochet::log::read_bytes(&bytes).unwrap();
    // The magic (8), the header record's opcode and length (9), its empty profile string
    // (a u32 length) and its library string: the shortest prefix that is an MCAP file.
    let header_end = 8 + 9 + 4 + 4 + full.library.len();
    let mut totals = vec![];
    for cut in (header_end..bytes.len()).step_by(97) {
        let read = ricochet::log::read_bytes(&bytes[..cut])
            .unwrap_or_else(|e| panic!("cut at {cut} of {}: {e}", bytes.len()));
        assert!(
            matches!(read.ending, Ending::Truncated { .. }),
            "cut at {cut}"
        );
        let total: u64 = read.message_counts.values().sum();
        assert!(
            totals.last().is_none_or(|&p| total >= p),
            "cut at {cut}: fewer messages than a shorter cut"
        );
        totals.push(total);
        // What was read is a prefix of the run.
        assert_eq!(read.impacts[..], full.impacts[..read.impacts.len()]);
    }
    // From nothing, through many partial reads, to everything once the cut is past the
    // data section (in the summary section, which the reader does not need).
    let all = run.events.len() as u64;
    assert_eq!(totals.first(), Some(&0));
    assert_eq!(totals.last(), Some(&all));
    let partial: std::collections::BTreeSet<u64> = totals
        .iter()
        .copied()
        .filter(|&n| 0 < n && n < all)
        .collect();
    assert!(
        partial.len() > 10,
        "only {} distinct partial reads",
        partial.len()
    );
    // Not an MCAP file at all: an error.
    assert!(ricochet::log::read_bytes(b"not an mcap file").is_err());
}

#[test]
fn a_dropped_writer_still_finishes_the_file() {
    let run = synthetic();
    let file = SharedFile::default();
    {
        let mut log = LogWriter::new(file.clone(), LogOptions::default()).unwrap();
        write_prefix(&run, &mut log, 30);
        // Dropped here, as on an early return or a panic: mcap's Drop finishes the file.
    }
    let bytes = file.snapshot();
    let summary = Summary::read(&bytes).unwrap().expect("a summary section");
    assert_eq!(summary.stats.unwrap().message_count, 30);
    let read = ricochet::log::read_bytes(&bytes).unwrap();
    assert_eq!(read.ending, Ending::Complete);
    assert_eq!(read.audit, None, "no audit: the run stopped early");
}

/// A file on a disk that fills up: writes beyond `capacity` bytes fail.
struct FullDisk {
    file: Cursor<Vec<u8>>,
    capacity: u64,
}

impl Write for FullDisk {
    fn write(&mut self, buf: &[u8]) -> std::io::Result<usize> {
        if self.file.position() + buf.len() as u64 > self.capacity {
            return Err(std::io::Error::new(
                std::io::ErrorKind::StorageFull,
                "disk full",
            ));
        }
        self.file.write(buf)
    }
    fn flush(&mut self) -> std::io::Result<()> {
        Ok(())
    }
}

impl Seek for FullDisk {
    fn seek(&mut self, pos: SeekFrom) -> std::io::Result<u64> {
        self.file.seek(pos)
    }
}

/// The writer thread meets an I/O error: a later call (a write, `flush` or `finish`)
/// reports it as an MCAP error, once; after it the writer refuses everything with
/// `SinkFailed`, which repeats the error's text; nothing hangs or panics.
#[test]
fn an_io_error_of_the_writer_thread_is_reported_by_a_later_call() {
    let run = synthetic();
    // Room for the first half of the run's messages, as written out (small chunks, so
    // that the messages reach the disk while the run goes on).
    let options = LogOptions {
        chunk_size: 1024,
        ..LogOptions::default()
    };
    let half = {
        let file = SharedFile::default();
        let mut log = LogWriter::new(file.clone(), options).unwrap();
        write_prefix(&run, &mut log, run.events.len() / 2);
        log.flush().unwrap();
        file.snapshot().len() as u64
    };
    let disk = FullDisk {
        file: Cursor::new(Vec::new()),
        capacity: half,
    };
    let mut log = LogWriter::new(disk, options).unwrap();
    let mut first = None;
    for (k, event) in run.events.iter().enumerate() {
        let result = match event {
            Event::Geometry(t, update) => log.geometry(*t, update),
            Event::Scene(t, update) => log.scene_update(*t, update),
            Event::Tf(t, tf) => log.transforms(*t, tf),
            Event::State(s) => log.state(s),
            Event::Impact(i) => log.impact(i),
            Event::Log(t, level, msg) => log.log(*t, *level, msg),
        };
        if let Err(e) = result {
            first = Some((k, e));
            break;
        }
    }
    // The error reaches the calling side at the latest at `flush`.
    let (k, error) = match first {
        Some(found) => found,
        None => (run.events.len(), log.flush().unwrap_err()),
    };
    assert!(
        k >= run.events.len() / 2,
        "the first half fits on the disk, yet call {k} failed"
    );
    let LogError::Mcap(mcap::McapError::Io(io)) = &error else {
        panic!("expected the disk's I/O error, got {error:?}");
    };
    assert_eq!(io.kind(), std::io::ErrorKind::StorageFull);
    // Reported once; afterwards the writer has stopped, and says after which error.
    let disk_error = io.to_string();
    for after in [log.state(&state(0)), log.finish().map(|_| ())] {
        match after {
            Err(LogError::SinkFailed { cause }) => assert!(cause.contains(&disk_error), "{cause}"),
            other => panic!("expected SinkFailed, got {other:?}"),
        }
    }
}

#[test]
fn invalid_times_and_non_finite_values_are_errors() {
    let mut log = LogWriter::new(Cursor::new(Vec::new()), LogOptions::default()).unwrap();
    for t in [-1e-9, -1.0, f64::NAN, f64::INFINITY, 5e9] {
        let mut s = state(1);
        s.t = t;
        assert!(
            matches!(log.state(&s), Err(LogError::InvalidTime { .. })),
            "state at {t}"
        );
        assert!(matches!(
            log.log(t, LogLevel::Info, "x"),
            Err(LogError::InvalidTime { .. })
        ));
        assert!(matches!(
            log.scene_update(t, &SceneUpdate::default()),
            Err(LogError::InvalidTime { .. })
        ));
        assert!(matches!(
            log.geometry(t, &SceneUpdate::default()),
            Err(LogError::InvalidTime { .. })
        ));
        assert!(matches!(
            log.transforms(t, &FrameTransforms::default()),
            Err(LogError::InvalidTime { .. })
        ));
        let mut i = impact(0);
        i.t = t;
        assert!(log.impact(&i).is_err(), "impact at {t}");
    }
    let mut s = state(2);
    s.u[1] = f64::NAN;
    match log.state(&s) {
        Err(LogError::NonFinite { field, .. }) => assert_eq!(field, "u[1]"),
        other => panic!("{other:?}"),
    }
    let mut i = impact(1);
    i.delta_u[2] = f64::NEG_INFINITY;
    assert!(matches!(log.impact(&i), Err(LogError::NonFinite { .. })));
    let mut scene = scene_at_start();
    scene.entities[2].cubes[0].size.as_mut().unwrap().y = f64::NAN;
    match log.geometry(0.0, &scene) {
        Err(LogError::NonFinite { field, what, .. }) => {
            assert_eq!(
                (what, field.as_str()),
                ("/geometry", "entities[2].cubes[0].size.y")
            )
        }
        other => panic!("{other:?}"),
    }
    let imp = impact(0);
    let mut arrow = draw::impulse_arrow(&imp, f64::INFINITY, &ArrowStyle::default()).unwrap();
    arrow.id = "x".to_owned();
    let update = SceneUpdate {
        deletions: vec![],
        entities: vec![arrow],
    };
    match log.scene_update(0.0, &update) {
        Err(LogError::NonFinite { field, what, .. }) => {
            assert_eq!(
                (what, field.as_str()),
                ("/scene", "entities[0].arrows[0].shaft_length")
            )
        }
        other => panic!("{other:?}"),
    }
    let mut tf = draw::body_transforms(0.0, [("ball", Pose2::IDENTITY)]).unwrap();
    tf.transforms[0].rotation.as_mut().unwrap().z = f64::INFINITY;
    match log.transforms(0.0, &tf) {
        Err(LogError::NonFinite { field, .. }) => assert_eq!(field, "transforms[0].rotation.z"),
        other => panic!("{other:?}"),
    }
    // The writer is still usable, and nothing rejected was written.
    log.state(&state(3)).unwrap();
    let bytes = log.finish().unwrap().into_inner();
    let read = ricochet::log::read_bytes(&bytes).unwrap();
    assert_eq!(read.message_counts.values().sum::<u64>(), 1);
    assert_eq!(read.last_state, Some(state(3)));
}

/// The committed fixture, which older and newer readers alike must keep reading.
const FIXTURE: &str = "tests/data/fixture.mcap";

/// The same synthetic run written by format 1 (JSON Foxglove topics, the bodies on
/// `/scene`, a first chunk without messages), committed before format 2.
const FIXTURE_V1: &str = "tests/data/fixture_v1.mcap";

#[test]
fn fixture_reads_back_and_matches_the_writer() {
    let committed = std::fs::read(repo_path(FIXTURE)).unwrap();
    let run = synthetic();
    let read = ricochet::log::read_bytes(&committed).unwrap();
    assert_eq!(read.ending, Ending::Complete);
    assert_eq!(read.format_version, 2);
    assert_eq!(read.audit.as_ref(), Some(&run.audit));
    assert_eq!(read.impacts.len(), 3);
    assert_eq!(read.count(Topic::State), N_STATES as u64);
    // Golden check of determinism across builds and machines.
    let fresh = write_run(&run, LogOptions::default());
    assert!(
        committed == fresh,
        "{FIXTURE} differs from a fresh write ({} vs {} bytes). If the log format changed on \
         purpose, regenerate it: bash tests/data/regenerate.sh",
        committed.len(),
        fresh.len()
    );
}

/// A format 1 log is still read: its metadata, ledger and samples are unchanged in
/// format 2 (only Foxglove's topics changed).
#[test]
fn a_format_1_log_is_still_read() {
    let run = synthetic();
    let read = ricochet::log::read_bytes(&std::fs::read(repo_path(FIXTURE_V1)).unwrap()).unwrap();
    assert_eq!(read.ending, Ending::Complete);
    assert_eq!(read.format_version, 1);
    assert_eq!(read.scene.as_ref().unwrap().text, SCENE_TEXT);
    assert_eq!(read.audit.as_ref(), Some(&run.audit));
    assert_eq!(read.impacts, (0..3).map(impact).collect::<Vec<_>>());
    assert_eq!(read.last_state, Some(state(N_STATES - 1)));
    assert_eq!(read.count(Topic::Geometry), 0);
    assert_eq!(read.count(Topic::Scene), 1 + 3 + 1);
}

/// Rewrites the fixture: `bash tests/data/regenerate.sh` (`cargo test --test all --
/// --ignored --exact log::regenerate_fixture`).
#[test]
#[ignore = "writes tests/data/fixture.mcap"]
fn regenerate_fixture() {
    let bytes = write_run(&synthetic(), LogOptions::default());
    std::fs::create_dir_all(repo_path("tests/data")).unwrap();
    std::fs::write(repo_path(FIXTURE), &bytes).unwrap();
    println!("wrote {FIXTURE} ({} bytes)", bytes.len());
}

/// The shipped Foxglove layout refers to topics, fields and frames that the log has.
#[test]
fn foxglove_layout_refers_to_what_is_logged() {
    let text = std::fs::read_to_string(repo_path("foxglove/ricochet-layout.json")).unwrap();
    let layout: Value = serde_json::from_str(&text).unwrap();
    let panels = layout["configById"].as_object().unwrap();
    let topic_names: Vec<&str> = Topic::ALL.iter().map(|t| t.name()).collect();
    let mut kinds = vec![];
    for (id, config) in panels {
        let kind = id.split('!').next().unwrap();
        kinds.push(kind);
        match kind {
            "3D" => {
                // The camera follows the view frame; frame labels (which hide the bodies)
                // are off, under `scene.transforms`, where Studio reads them.
                assert_eq!(config["followTf"], draw::VIEW_FRAME);
                assert_eq!(config["followMode"], "follow-position");
                assert_eq!(config["scene"]["transforms"]["showLabel"], false);
                assert!(
                    config
                        .get("transforms")
                        .is_none_or(|t| t.get("showLabel").is_none())
                );
                let mut shown: Vec<&str> = (config["topics"].as_object().unwrap().iter())
                    .filter(|(_, c)| c["visible"] == true)
                    .map(|(topic, _)| topic.as_str())
                    .collect();
                shown.sort();
                assert_eq!(shown, [Topic::Geometry.name(), Topic::Scene.name()]);
                for topic in &shown {
                    assert!(topic_names.contains(topic), "3D panel topic {topic}");
                }
            }
            "Plot" => {
                for path in config["paths"].as_array().unwrap() {
                    let path = path["value"].as_str().unwrap();
                    let (topic, fields) = path.split_once('.').unwrap();
                    let topic = Topic::from_name(topic).unwrap_or_else(|| panic!("{path}"));
                    // Follow the fields through the topic's JSON schema.
                    assert!(topic.is_json(), "plot path {path} on a protobuf topic");
                    let mut schema: Value = serde_json::from_slice(&topic.schema()).unwrap();
                    for field in fields.split('.') {
                        schema = schema["properties"][field].clone();
                        assert!(!schema.is_null(), "plot path {path}: no field {field}");
                    }
                    assert_eq!(schema["type"], "number", "plot path {path}");
                }
            }
            "RawMessages" => {
                assert!(topic_names.contains(&config["topicPath"].as_str().unwrap()))
            }
            "RosOut" => assert_eq!(config["topicToRender"], Topic::Log.name()),
            other => panic!("unexpected panel {other}"),
        }
    }
    kinds.sort();
    assert_eq!(kinds, ["3D", "Plot", "Plot", "RawMessages", "RosOut"]);
    // Every panel of the layout tree is configured, and every configured panel is placed.
    fn leaves(node: &Value, out: &mut Vec<String>) {
        match node {
            Value::String(id) => out.push(id.clone()),
            Value::Object(split) => {
                leaves(&split["first"], out);
                leaves(&split["second"], out);
            }
            other => panic!("bad layout node {other}"),
        }
    }
    let mut placed = vec![];
    leaves(&layout["layout"], &mut placed);
    placed.sort();
    let mut configured: Vec<String> = panels.keys().cloned().collect();
    configured.sort();
    assert_eq!(placed, configured);
}

#[test]
fn inspect_prints_the_summary_of_a_run() {
    let bin = env!("CARGO_BIN_EXE_ricochet");
    let out = std::process::Command::new(bin)
        .args(["inspect", FIXTURE])
        .current_dir(env!("CARGO_MANIFEST_DIR"))
        .output()
        .unwrap();
    let stdout = String::from_utf8(out.stdout).unwrap();
    assert!(
        out.status.success(),
        "{stdout}\n{}",
        String::from_utf8_lossy(&out.stderr)
    );
    for needle in [
        "scene: synthetic",
        "log format 2",
        "complete",
        "output_rate",
        "impacts: 3",
        "reverse_sliding",
        "kane-levinson",
        "stop reason",
        "t_end",
        "integration drift",
        "/state",
    ] {
        assert!(
            stdout.contains(needle),
            "`{needle}` missing from:\n{stdout}"
        );
    }
    // One table row per impact, each starting with its time.
    for t in ["0.123", "0.456", "0.789"] {
        assert_eq!(
            stdout
                .lines()
                .filter(|l| l.trim_start().starts_with(t))
                .count(),
            1,
            "{t}:\n{stdout}"
        );
    }

    // A file cut short in its data section: still a summary, and it says so.
    let bytes = std::fs::read(repo_path(FIXTURE)).unwrap();
    let data_end = mcap::read::footer(&bytes).unwrap().summary_start as usize;
    let cut = tmp_path("inspect_cut.mcap");
    std::fs::write(&cut, &bytes[..data_end / 2]).unwrap();
    let out = std::process::Command::new(bin)
        .arg("inspect")
        .arg(&cut)
        .output()
        .unwrap();
    let stdout = String::from_utf8(out.stdout).unwrap();
    assert!(out.status.success(), "{stdout}");
    assert!(stdout.contains("truncated"), "{stdout}");
    assert!(stdout.contains("no audit"), "{stdout}");
}

/// The JSON schemas of ricochet's topics use only what Foxglove Studio 1.48 parses into
/// its datatypes (`parseJsonSchema` of `@foxglove/studio-base` 1.48, transcribed): every
/// property has one `type`, a string among boolean, string, number, integer, object
/// (itself parsed the same way) and array (whose items have one such type). A field that
/// may be a number or null (`"type": ["number", "null"]`) makes Studio drop the whole topic
/// ("Unsupported type"), which a first draft of format 2 did to `/impacts`.
#[test]
fn ricochet_schemas_are_what_foxglove_studio_parses() {
    fn object(schema: &Value, path: &str) {
        assert_eq!(schema["type"], "object", "{path}: not an object");
        for (name, field) in schema["properties"].as_object().unwrap() {
            let path = format!("{path}.{name}");
            if let Some(one_of) = field.get("oneOf") {
                let constants = one_of.as_array().unwrap();
                assert!(constants.iter().all(|c| c["const"].is_number()), "{path}");
                continue;
            }
            match field["type"].as_str() {
                Some("boolean" | "number" | "integer") => {}
                Some("string") => assert!(
                    field.get("contentEncoding").is_none_or(|e| e == "base64"),
                    "{path}"
                ),
                Some("object") => object(field, &path),
                Some("array") => match field["items"]["type"].as_str() {
                    Some("boolean" | "string" | "number" | "integer") => {}
                    Some("object") => object(&field["items"], &format!("{path}[]")),
                    other => panic!("{path}: array items of type {other:?}"),
                },
                _ => panic!("{path}: type {} is not one Studio parses", field["type"]),
            }
        }
    }
    for topic in Topic::ALL.into_iter().filter(|t| t.is_json()) {
        let schema: Value = serde_json::from_slice(&topic.schema()).unwrap();
        object(&schema, topic.name());
    }
    // The check fails where Studio fails.
    let nullable: Value = serde_json::json!({
        "type": "object",
        "properties": {"alpha": {"type": ["number", "null"]}}
    });
    assert!(std::panic::catch_unwind(|| object(&nullable, "/impacts")).is_err());
}

/// Forwards to a [`RunLogger`](ricochet::log::RunLogger), counting the allocations its
/// `sample` makes on the simulation's thread after the first `warm_up` samples.
struct CountingLogger<W: Write + Seek + Send + 'static> {
    inner: ricochet::log::RunLogger<W>,
    warm_up: usize,
    samples: usize,
    allocations: u64,
}

impl<W: Write + Seek + Send + 'static> ricochet::sim::Observer for CountingLogger<W> {
    fn sample(
        &mut self,
        model: &ricochet::model::Model,
        s: &ricochet::sim::Sample<'_>,
    ) -> Result<(), ricochet::sim::ObserverError> {
        let mut result = Ok(());
        let n = crate::common::alloc::allocations_in(|| result = self.inner.sample(model, s));
        self.samples += 1;
        if self.samples > self.warm_up {
            self.allocations += n;
        }
        result
    }
    fn impact(
        &mut self,
        model: &ricochet::model::Model,
        impact: &ricochet::sim::ImpactEvent,
    ) -> Result<(), ricochet::sim::ObserverError> {
        self.inner.impact(model, impact)
    }
    fn message(
        &mut self,
        t: f64,
        level: ricochet::sim::Level,
        text: &str,
    ) -> Result<(), ricochet::sim::ObserverError> {
        self.inner.message(t, level, text)
    }
}

/// Logging a sample does not allocate on the simulation's thread once the log is under way
/// (issue 16): Kane's pendulum, 5 s at 100 Hz (its impacts and accumulation in the first
/// 0.2 s, then sliding), past its first 100 samples. A sample is handed over as numbers
/// (or encoded) into a batch whose buffers are reused. What may allocate depends on the
/// writer thread's progress, not on the samples: a new batch (three buffers) when the
/// writer thread holds every spare one, at most once per 32 samples, and a reused batch's
/// bytes growing (by doubling) once the simulation's thread starts encoding samples into
/// it. An allocation per sample would be 400 here; a few dozen at most are allowed.
#[test]
fn a_logged_sample_allocates_nothing_after_warm_up() {
    use ricochet::sim::{MaterialOverride, Simulation};
    let mut s =
        ricochet::scene::load(repo_path("scenes/kane_double_pendulum.toml")).expect("the scene");
    s.settings.t_end = 5.0;
    s.settings.output_rate = 100.0;
    let over = MaterialOverride::default();
    let mut sim = Simulation::new(&s.model, &s.settings, over).expect("a simulation");
    let writer = LogWriter::new(Cursor::new(Vec::new()), LogOptions::default()).expect("a log");
    let inner = ricochet::log::RunLogger::for_scene(writer, &s, &over, sim.scales().gap_tol)
        .expect("a logger");
    let mut log = CountingLogger {
        inner,
        warm_up: 100,
        samples: 0,
        allocations: 0,
    };
    let summary = sim.run(&s.initial, &mut log, None);
    assert!(log.samples > 500, "{} samples", log.samples);
    let counted = (log.samples - log.warm_up) as u64;
    assert!(
        log.allocations * 8 <= counted,
        "{} allocations in {counted} samples",
        log.allocations
    );
    eprintln!("{} allocations in {counted} samples", log.allocations);
    log.inner.finish(&summary).expect("finished");
}
