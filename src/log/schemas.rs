//! The topics of a ricochet log, and the JSON schemas embedded in every file.
//!
//! Every channel is JSON-encoded (`message_encoding = "json"`) with a `jsonschema` schema.
//! The Foxglove schemas are the official ones (`schemas/foxglove/`, MIT, see its README);
//! ricochet's own are `schemas/ricochet/`.

/// Schema encoding of every channel.
pub const SCHEMA_ENCODING: &str = "jsonschema";
/// Message encoding of every channel.
pub const MESSAGE_ENCODING: &str = "json";

/// A channel of the log: its topic and the name and text of its schema.
#[derive(Clone, Copy, Debug, PartialEq, Eq, PartialOrd, Ord, Hash)]
pub enum Topic {
    /// `/state`: [`StateRecord`](super::StateRecord), one per output sample.
    State,
    /// `/impacts`: [`ImpactRecord`](super::ImpactRecord), one per impact.
    Impacts,
    /// `/scene`: [`SceneUpdate`](super::SceneUpdate): bodies, obstacles, impulse arrows.
    Scene,
    /// `/tf`: [`FrameTransforms`](super::FrameTransforms), `world → body_<name>`.
    Tf,
    /// `/log`: [`Log`](super::Log): warnings and mode changes.
    Log,
}

impl Topic {
    /// Every topic, in the order their channels are registered (channel ids 1..=5).
    pub const ALL: [Topic; 5] = [
        Topic::State,
        Topic::Impacts,
        Topic::Scene,
        Topic::Tf,
        Topic::Log,
    ];

    /// The topic name, e.g. `/state`.
    pub fn name(self) -> &'static str {
        match self {
            Topic::State => "/state",
            Topic::Impacts => "/impacts",
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
            Topic::Scene => "foxglove.SceneUpdate",
            Topic::Tf => "foxglove.FrameTransforms",
            Topic::Log => "foxglove.Log",
        }
    }

    /// The JSON schema text embedded in the file for this topic.
    pub fn schema(self) -> &'static str {
        match self {
            Topic::State => STATE,
            Topic::Impacts => IMPACT,
            Topic::Scene => SCENE_UPDATE,
            Topic::Tf => FRAME_TRANSFORMS,
            Topic::Log => LOG,
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
/// `foxglove.SceneUpdate`.
pub const SCENE_UPDATE: &str = include_str!("../../schemas/foxglove/SceneUpdate.json");
/// `foxglove.FrameTransforms`.
pub const FRAME_TRANSFORMS: &str = include_str!("../../schemas/foxglove/FrameTransforms.json");
/// `foxglove.Log`.
pub const LOG: &str = include_str!("../../schemas/foxglove/Log.json");

/// Names of the metadata records.
pub mod metadata {
    /// The scene: keys `name` (the scene's name) and `text` (the scene file, verbatim).
    pub const SCENE: &str = "scene";
    /// The run settings: one key per top-level field, each value a JSON text.
    pub const SETTINGS: &str = "settings";
    /// The energy audit, written when the run ends: one key per field of
    /// [`Audit`](crate::log::Audit), each value a JSON text.
    pub const AUDIT: &str = "audit";
}
