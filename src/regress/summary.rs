//! The run summary: one JSON document that holds what a regression test compares — the
//! scene's name and checksum, the settings, the energy audit with the stop reason and the
//! counters, the drift check, every ledger row, the final state and the state at a few
//! checkpoints. `ricochet run --summary` writes it from a run, `ricochet inspect --json`
//! from a log; both give the same document for the same run (the same records, built by
//! the same functions: [`LedgerNames::entry`], [`Audit::of_run`], [`RunSettings`]).
//!
//! The document is a versioned contract (`ARCHITECTURE.md`, "The run summary"):
//! `format = "ricochet.summary"`, `version` = [`SUMMARY_VERSION`]. Fields are added, never
//! renamed or re-typed without a version bump.
//!
//! [`LedgerNames::entry`]: crate::log::LedgerNames::entry
//! [`RunSettings`]: crate::log::RunSettings

use std::path::Path;

use serde::{Deserialize, Serialize};
use serde_json::{Map, Value};

use crate::log::{Audit, Energy, ImpactRecord, LogError, RunLog, StateRecord};
use crate::math::Real;
use crate::settings::Settings;

use super::{DriftCheck, RegressError};

/// The `format` of a run summary.
pub const SUMMARY_FORMAT: &str = "ricochet.summary";

/// The version of the run summary's fields.
pub const SUMMARY_VERSION: u32 = 1;

/// How many checkpoints a summary keeps by default.
pub const DEFAULT_CHECKPOINTS: u64 = 10;

/// The scene a run is of.
#[derive(Clone, Debug, PartialEq, Eq, Serialize, Deserialize)]
pub struct SceneId {
    /// The scene's `name`.
    pub name: String,
    /// CRC-32 (IEEE) of the scene file's text, 8 lower-case hex digits, as in a sweep's
    /// table header: a changed scene file has another.
    pub crc32: String,
}

impl SceneId {
    /// The id of the scene `name` whose file reads `text`.
    pub fn new(name: &str, text: &str) -> SceneId {
        SceneId {
            name: name.to_owned(),
            crc32: format!("{:08x}", crc32fast::hash(text.as_bytes())),
        }
    }
}

/// The state at one instant.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct Snapshot {
    /// Time (s).
    pub t: Real,
    /// Generalized coordinates (m, rad).
    pub q: Vec<Real>,
    /// Generalized speeds (m/s, rad/s).
    pub u: Vec<Real>,
    /// Energies (J).
    pub energy: Energy,
}

impl From<&StateRecord> for Snapshot {
    fn from(s: &StateRecord) -> Snapshot {
        Snapshot {
            t: s.t,
            q: s.q.clone(),
            u: s.u.clone(),
            energy: s.energy,
        }
    }
}

/// Which samples of a run are its checkpoints.
///
/// The output samples of a run are at `t = k / output_rate` (and two more at each impact
/// instant). With `n` checkpoints asked for, the stride is `s = max(1, ⌈t_end ·
/// output_rate / n⌉)` and the checkpoints are the samples on the output grid whose `k` is a
/// multiple of `s` (`t = 0` included), so about `n + 1` of them, at the same times in two
/// runs with the same `t_end` and `output_rate` whatever their impacts. The rule reads the
/// samples alone, so a run and its log give the same checkpoints.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum Checkpoints {
    /// Every sample (a log compared with `ricochet compare`).
    Every,
    /// The samples on the output grid at multiples of `stride` (none if `rate` is not
    /// positive or `stride` is 0).
    Grid {
        /// Output rate (Hz).
        rate: Real,
        /// Samples between checkpoints.
        stride: u64,
    },
}

impl Checkpoints {
    /// About `count` checkpoints over a run with `settings` (none when `count = 0`).
    pub fn of(settings: &Settings, count: u64) -> Checkpoints {
        let rate = settings.output_rate;
        let intervals = settings.t_end * rate;
        let stride = if count == 0 || !(intervals.is_finite() && rate > 0.0) {
            0
        } else {
            ((intervals / count as Real).ceil() as u64).max(1)
        };
        Checkpoints::Grid { rate, stride }
    }

    /// Whether the sample at `t` is a checkpoint.
    pub fn keeps(&self, t: Real) -> bool {
        match *self {
            Checkpoints::Every => true,
            Checkpoints::Grid { rate, stride } => {
                let grid = stride > 0 && rate > 0.0 && t >= 0.0;
                if !grid {
                    return false;
                }
                // The output times are `k as f64 / rate` (src/sim): a sample on the grid
                // has exactly that time.
                let k = (t * rate).round();
                k < 2f64.powi(53) && k / rate == t && (k as u64).is_multiple_of(stride)
            }
        }
    }
}

/// The run summary (see the module doc).
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct Summary {
    /// Always [`SUMMARY_FORMAT`].
    pub format: String,
    /// [`SUMMARY_VERSION`] when written.
    pub version: u32,
    /// The version of the ricochet that wrote it (not compared).
    pub ricochet: String,
    /// The scene, if known (a log without its `scene` record has none).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub scene: Option<SceneId>,
    /// The names of the generalized coordinates, in the order of `q` and `u` (empty when
    /// unknown: a log whose scene text no longer loads).
    #[serde(default)]
    pub coordinates: Vec<String>,
    /// The names of the generalized speeds, in the order of `u`, when they are not the
    /// coordinates' (a nonholonomic scene); absent otherwise.
    #[serde(default, skip_serializing_if = "Vec::is_empty")]
    pub speeds: Vec<String>,
    /// The run settings as the log's `settings` record holds them: `t_end`,
    /// `output_rate`, `integrator {method, rtol, atol, dt, h_max}`, `max_drift` (if any)
    /// and `material_overrides {law, e, mu}`.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub settings: Option<Map<String, Value>>,
    /// The energy audit, the stop reason and the counters, as the log's `audit` record;
    /// absent for a log of a run that did not finish.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub audit: Option<Audit>,
    /// The drift against the energy scale and the budget; absent without an audit.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub drift: Option<DriftCheck>,
    /// Every ledger row (`ricochet.Impact`, as on `/impacts`), in order.
    pub impacts: Vec<ImpactRecord>,
    /// The last sample of the run: the state where it stopped.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub final_state: Option<Snapshot>,
    /// The state at the checkpoints ([`Checkpoints`]), in time order.
    #[serde(default)]
    pub checkpoints: Vec<Snapshot>,
}

/// What a summary is built from, besides the ledger and the samples.
#[derive(Clone, Debug)]
pub(crate) struct Parts {
    pub scene: Option<SceneId>,
    pub coordinates: Vec<String>,
    pub speeds: Vec<String>,
    pub settings: Option<Map<String, Value>>,
    pub audit: Option<Audit>,
    pub max_drift: Option<Real>,
}

/// The names of a model's coordinates, and of its speeds when they are not the
/// coordinates' (a nonholonomic model; empty otherwise).
pub(crate) fn names(model: &crate::model::Model) -> (Vec<String>, Vec<String>) {
    let coordinates = (model.coordinates().iter())
        .map(|c| c.name.clone())
        .collect();
    let speeds = if model.is_holonomic() {
        Vec::new()
    } else {
        (model.speeds().iter()).map(|s| s.name.clone()).collect()
    };
    (coordinates, speeds)
}

/// The largest `K + |V|` of the samples seen, for the energy scale (J).
pub(crate) fn sample_scale(scale: Real, e: &Energy) -> Real {
    scale.max(e.kinetic + e.potential.abs())
}

impl Summary {
    /// The summary from its parts, the ledger, the checkpoints, the last sample and the
    /// largest `K + |V|` over the samples (J).
    pub(crate) fn assemble(
        parts: Parts,
        impacts: Vec<ImpactRecord>,
        checkpoints: Vec<Snapshot>,
        final_state: Option<Snapshot>,
        sampled_scale: Real,
    ) -> Summary {
        let drift = parts.audit.as_ref().map(|a| {
            let scale = (a.energy_initial.abs())
                .max(a.energy_final.abs())
                .max(sampled_scale);
            DriftCheck::new(a.integration_drift, scale, parts.max_drift)
        });
        Summary {
            format: SUMMARY_FORMAT.to_owned(),
            version: SUMMARY_VERSION,
            ricochet: env!("CARGO_PKG_VERSION").to_owned(),
            scene: parts.scene,
            coordinates: parts.coordinates,
            speeds: parts.speeds,
            settings: parts.settings,
            audit: parts.audit,
            drift,
            impacts,
            final_state,
            checkpoints,
        }
    }

    /// The summary of the run in the log `bytes`; the checkpoints follow `count` (see
    /// [`Checkpoints::of`], with the log's settings), or are every sample when `count` is
    /// `None`. The coordinates' names come from the scene text in the log, when it still
    /// loads.
    pub fn from_log(bytes: &[u8], count: Option<u64>) -> Result<Summary, LogError> {
        Summary::from_log_read(bytes, count).map(|(summary, _)| summary)
    }

    /// [`Summary::from_log`], and the log as read (its [`RunLog::ending`]: complete, cut
    /// short or damaged, the summary holding what was read before; its scene text).
    pub fn from_log_read(bytes: &[u8], count: Option<u64>) -> Result<(Summary, RunLog), LogError> {
        // Every sample as a snapshot (a few numbers each, not the whole `/state` record).
        let mut samples: Vec<Snapshot> = Vec::new();
        let mut scale = 0.0;
        let log = crate::log::read_bytes_with(bytes, &mut |s| {
            scale = sample_scale(scale, &s.energy);
            samples.push(Snapshot::from(&s));
        })?;
        let settings: Option<Settings> = (log.settings.as_ref())
            .and_then(|m| serde_json::from_value(Value::Object(m.clone())).ok());
        let rule = match (count, &settings) {
            (None, _) => Checkpoints::Every,
            (Some(n), Some(s)) => Checkpoints::of(s, n),
            (Some(_), None) => Checkpoints::Grid {
                rate: 0.0,
                stride: 0,
            },
        };
        let model = (log.scene.as_ref())
            .and_then(|s| crate::scene::load_str(&s.text, format!("{}.toml", s.name)).ok())
            .map(|s| s.model);
        let (coordinates, speeds) = model.as_ref().map(names).unwrap_or_default();
        let parts = Parts {
            scene: (log.scene.as_ref()).map(|s| SceneId::new(&s.name, &s.text)),
            coordinates,
            speeds,
            settings: log.settings.clone(),
            audit: log.audit.clone(),
            max_drift: settings.and_then(|s| s.max_drift),
        };
        let last = samples.last().cloned();
        samples.retain(|s| rule.keeps(s.t));
        let summary = Summary::assemble(parts, log.impacts.clone(), samples, last, scale);
        Ok((summary, log))
    }

    /// The name of the first number that is not finite, if any. JSON has no NaN nor
    /// infinity; ricochet's log refuses them (naming the field), and so does the summary.
    pub fn first_non_finite(&self) -> Option<String> {
        if let Some(a) = &self.audit
            && let Some(f) = a.first_non_finite()
        {
            return Some(format!("audit.{f}"));
        }
        if let Some(d) = &self.drift {
            let values = [
                ("integration_drift", Some(d.integration_drift)),
                ("energy_scale", Some(d.energy_scale)),
                ("relative", d.relative),
                ("max_drift", d.max_drift),
            ];
            if let Some((name, _)) = values
                .iter()
                .find(|(_, v)| v.is_some_and(|v| !v.is_finite()))
            {
                return Some(format!("drift.{name}"));
            }
        }
        for (k, i) in self.impacts.iter().enumerate() {
            if !i.t.is_finite() {
                return Some(format!("impacts[{k}].t"));
            }
            if let Some(f) = i.first_non_finite() {
                return Some(format!("impacts[{k}].{f}"));
            }
            if let Some(s) = &i.support {
                let values = [("i_n", s.i_n), ("i_t", s.i_t), ("duration", s.duration)];
                if let Some((name, _)) = values.iter().find(|(_, v)| !v.is_finite()) {
                    return Some(format!("impacts[{k}].support.{name}"));
                }
            }
        }
        let snapshots = (self
            .final_state
            .iter()
            .map(|s| ("final_state".to_owned(), s)))
        .chain(
            (self.checkpoints.iter().enumerate()).map(|(k, s)| (format!("checkpoints[{k}]"), s)),
        );
        for (name, s) in snapshots {
            if let Some(f) = snapshot_non_finite(s) {
                return Some(format!("{name}.{f}"));
            }
        }
        None
    }

    /// The document as JSON text (see `layout.rs`: one impact per line). Errors: a number
    /// that is not finite, named.
    pub fn to_json(&self) -> Result<String, RegressError> {
        if let Some(field) = self.first_non_finite() {
            return Err(RegressError::NonFinite { field });
        }
        super::layout::to_string(self).map_err(RegressError::Encode)
    }

    /// Writes the document to `path`.
    pub fn write(&self, path: &Path) -> Result<(), RegressError> {
        let text = self.to_json()?;
        std::fs::write(path, text).map_err(|source| RegressError::Write {
            path: path.to_owned(),
            source,
        })
    }

    /// Reads a summary from its JSON `value` (read from `path`, named in errors): checks
    /// the format and the version.
    pub fn from_value(value: Value, path: &Path) -> Result<Summary, RegressError> {
        check_format(&value, path, SUMMARY_FORMAT, SUMMARY_VERSION)?;
        serde_json::from_value(value).map_err(|source| RegressError::Document {
            path: path.to_owned(),
            what: SUMMARY_FORMAT,
            source,
        })
    }
}

/// Checks the `format` and `version` fields of a document read from `path`.
#[doc(hidden)]
pub fn check_format(
    value: &Value,
    path: &Path,
    format: &'static str,
    supported: u32,
) -> Result<(), RegressError> {
    let found = value.get("format").and_then(Value::as_str).unwrap_or("");
    if found != format {
        return Err(RegressError::NotADocument {
            path: path.to_owned(),
            expected: format,
            found: found.to_owned(),
        });
    }
    let version = value.get("version").and_then(Value::as_u64);
    match version {
        Some(v) if v >= 1 && v <= u64::from(supported) => Ok(()),
        _ => Err(RegressError::Version {
            path: path.to_owned(),
            what: format,
            found: value
                .get("version")
                .map(Value::to_string)
                .unwrap_or_default(),
            supported,
        }),
    }
}

fn snapshot_non_finite(s: &Snapshot) -> Option<String> {
    let scalars = [
        ("t", s.t),
        ("energy.kinetic", s.energy.kinetic),
        ("energy.potential", s.energy.potential),
        ("energy.total", s.energy.total),
    ];
    if let Some((name, _)) = scalars.iter().find(|(_, v)| !v.is_finite()) {
        return Some((*name).to_owned());
    }
    for (name, xs) in [("q", &s.q), ("u", &s.u)] {
        if let Some(k) = xs.iter().position(|v| !v.is_finite()) {
            return Some(format!("{name}[{k}]"));
        }
    }
    None
}
