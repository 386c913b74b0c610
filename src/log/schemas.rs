//! The topics of a ricochet log, their encodings, and the schemas embedded in every file.
//!
//! ricochet's own topics (`/state`, `/impacts`) are JSON with a `jsonschema` schema
//! (`schemas/ricochet/`), because scripts read them. Foxglove's well-known types
//! (`/geometry`, `/scene`, `/tf`, `/log`) are protobuf-encoded by Foxglove's SDK (the
//! `foxglove` crate), with the schema it gives: a protobuf `FileDescriptorSet`.

use std::borrow::Cow;

use foxglove::Encode;

use super::foxglove::{FrameTransforms, Log, SceneUpdate};

/// The version of the log format: the topics, their schemas and encodings, and the
/// metadata records. Version 1 (before 2026-11) wrote every topic as JSON, the bodies on
/// `/scene` once at the start; version 2 writes Foxglove's types as protobuf and the
/// bodies on `/geometry`. Written in the `ricochet` metadata record.
pub const FORMAT_VERSION: u32 = 2;

/// Schema encoding of ricochet's own topics.
pub const JSON_SCHEMA: &str = "jsonschema";
/// Message encoding of ricochet's own topics.
pub const JSON: &str = "json";

/// A channel of the log: its topic, encoding and schema.
#[derive(Clone, Copy, Debug, PartialEq, Eq, PartialOrd, Ord, Hash)]
pub enum Topic {
    /// `/state`: [`StateRecord`](super::StateRecord), one per output sample (JSON).
    State,
    /// `/impacts`: [`ImpactRecord`](super::ImpactRecord), one per impact (JSON).
    Impacts,
    /// `/geometry`: [`SceneUpdate`] drawing every body and obstacle; its latest message at
    /// any time describes them all (protobuf).
    Geometry,
    /// `/scene`: [`SceneUpdate`] with the transient drawings: the impulse of each impact
    /// (protobuf).
    Scene,
    /// `/tf`: [`FrameTransforms`], `world → body_<name>` and `world → view` (protobuf).
    Tf,
    /// `/log`: [`Log`]: one line per impact, warnings and mode changes (protobuf).
    Log,
}

impl Topic {
    /// Every topic, in the order their channels are registered (channel ids 1..=6).
    pub const ALL: [Topic; 6] = [
        Topic::State,
        Topic::Impacts,
        Topic::Geometry,
        Topic::Scene,
        Topic::Tf,
        Topic::Log,
    ];

    /// The topic name, e.g. `/state`.
    pub fn name(self) -> &'static str {
        match self {
            Topic::State => "/state",
            Topic::Impacts => "/impacts",
            Topic::Geometry => "/geometry",
            Topic::Scene => "/scene",
            Topic::Tf => "/tf",
            Topic::Log => "/log",
        }
    }

    /// The schema name, e.g. `ricochet.State` or `foxglove.SceneUpdate`.
    pub fn schema_name(self) -> &'static str {
        match self {
            Topic::State => "ricochet.State",
            Topic::Impacts => "ricochet.Impact",
            Topic::Geometry | Topic::Scene => "foxglove.SceneUpdate",
            Topic::Tf => "foxglove.FrameTransforms",
            Topic::Log => "foxglove.Log",
        }
    }

    /// The message encoding: `json` or `protobuf`.
    pub fn message_encoding(self) -> &'static str {
        if self.is_json() { JSON } else { "protobuf" }
    }

    /// The schema encoding: `jsonschema` or `protobuf`.
    pub fn schema_encoding(self) -> &'static str {
        if self.is_json() {
            JSON_SCHEMA
        } else {
            "protobuf"
        }
    }

    /// `true` for ricochet's own JSON topics.
    pub fn is_json(self) -> bool {
        matches!(self, Topic::State | Topic::Impacts)
    }

    /// The schema embedded in the file for this topic: a JSON schema, or the Foxglove
    /// SDK's `FileDescriptorSet`.
    pub fn schema(self) -> Cow<'static, [u8]> {
        let sdk = |schema: Option<foxglove::Schema>| schema.map(|s| s.data).unwrap_or_default();
        match self {
            Topic::State => Cow::Borrowed(STATE.as_bytes()),
            Topic::Impacts => Cow::Borrowed(IMPACT.as_bytes()),
            Topic::Geometry | Topic::Scene => sdk(SceneUpdate::get_schema()),
            Topic::Tf => sdk(FrameTransforms::get_schema()),
            Topic::Log => sdk(Log::get_schema()),
        }
    }

    /// The topic named `name`, if it is one of ricochet's.
    pub fn from_name(name: &str) -> Option<Topic> {
        Topic::ALL.into_iter().find(|t| t.name() == name)
    }

    /// Position in [`Topic::ALL`].
    pub(crate) fn index(self) -> usize {
        self as usize
    }
}

/// `ricochet.State` (draft 2020-12).
pub const STATE: &str = include_str!("../../schemas/ricochet/State.json");
/// `ricochet.Impact` (draft 2020-12).
pub const IMPACT: &str = include_str!("../../schemas/ricochet/Impact.json");

/// Names of the metadata records.
pub mod metadata {
    /// The log format: keys `format_version` (e.g. `2`) and `version` (ricochet's). Absent
    /// from logs of format version 1.
    pub const RICOCHET: &str = "ricochet";
    /// The scene: keys `name` (the scene's name) and `text` (the scene file, verbatim).
    pub const SCENE: &str = "scene";
    /// The run settings: one key per top-level field, each value a JSON text.
    pub const SETTINGS: &str = "settings";
    /// The energy audit, written when the run ends: one key per field of
    /// [`Audit`](crate::log::Audit), each value a JSON text.
    pub const AUDIT: &str = "audit";
}
