//! Golden runs: one small JSON file per scene, `<scene file stem>.golden.json`, holding
//! the scene's path (relative to the golden file's folder), the overrides of its settings,
//! the number of checkpoints, the tolerances and the run's [`Summary`]. `golden check`
//! re-runs each scene as recorded and compares with [`compare`](fn@compare), as `ricochet compare`
//! does; the tolerances are the file's own, so that one scene can be loosened alone.
//!
//! JSON rather than TOML: the golden file *is* a summary with a header, read by the same
//! reader and by any script (`json.load`); numbers round-trip bit-exact through
//! `serde_json` (and Python's `json`), and the layout (one impact, one checkpoint per line)
//! keeps `git diff` of a moved run to the lines that moved.

use std::path::{Component, Path, PathBuf};

use serde::{Deserialize, Serialize};
use serde_json::Value;

use super::summary::check_format;
use super::{
    Comparison, DriftCheck, RegressError, RunOverrides, SUMMARY_FORMAT, SUMMARY_VERSION, Summary,
    Tolerances, compare, run_scene,
};

/// The `format` of a golden file.
pub const GOLDEN_FORMAT: &str = "ricochet.golden";
/// The version of the golden file's fields.
pub const GOLDEN_VERSION: u32 = 1;
/// How golden files are named: `<scene file stem>.golden.json`.
pub const GOLDEN_SUFFIX: &str = ".golden.json";

/// A golden file.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct Golden {
    /// Always [`GOLDEN_FORMAT`].
    pub format: String,
    /// [`GOLDEN_VERSION`] when written.
    pub version: u32,
    /// The scene file, relative to the golden file's folder, with `/` separators (or
    /// absolute, when it is on another drive).
    pub scene: String,
    /// The overrides of the scene's settings the run was recorded with.
    #[serde(default)]
    pub overrides: RunOverrides,
    /// The number of checkpoints asked for ([`super::Checkpoints::of`]).
    pub checkpoints: u64,
    /// The tolerances of `golden check` for this scene.
    pub tolerances: Tolerances,
    /// The recorded run.
    pub summary: Summary,
}

impl Golden {
    /// Reads the golden file at `path`: its format, version, tolerances and summary.
    pub fn read(path: &Path) -> Result<Golden, RegressError> {
        let text = super::read_text(path)?;
        Golden::from_text(&text, path)
    }

    /// Reads a golden file's `text` (from `path`, named in errors).
    pub fn from_text(text: &str, path: &Path) -> Result<Golden, RegressError> {
        let value: Value = super::parse_json(text, path)?;
        check_format(&value, path, GOLDEN_FORMAT, GOLDEN_VERSION)?;
        let summary = value.get("summary").cloned().unwrap_or(Value::Null);
        check_format(&summary, path, SUMMARY_FORMAT, SUMMARY_VERSION)?;
        let golden: Golden =
            serde_json::from_str(text).map_err(|source| RegressError::Document {
                path: path.to_owned(),
                what: GOLDEN_FORMAT,
                source,
            })?;
        golden
            .tolerances
            .validate()
            .map_err(|e| RegressError::Invalid {
                path: path.to_owned(),
                message: e.to_string(),
            })?;
        Ok(golden)
    }

    /// Writes the file to `path`.
    pub fn write(&self, path: &Path) -> Result<(), RegressError> {
        if let Some(field) = self.summary.first_non_finite() {
            return Err(RegressError::NonFinite {
                field: format!("summary.{field}"),
            });
        }
        let text = super::layout::to_string(self).map_err(RegressError::Encode)?;
        std::fs::write(path, text).map_err(|source| RegressError::Write {
            path: path.to_owned(),
            source,
        })
    }

    /// The scene file of the golden file at `path`.
    pub fn scene_path(&self, path: &Path) -> PathBuf {
        let dir = path.parent().unwrap_or(Path::new("."));
        dir.join(&self.scene)
    }
}

/// The golden file of the scene file `scene` in `dir`: `<dir>/<stem>.golden.json`.
pub fn golden_path(dir: &Path, scene: &Path) -> PathBuf {
    let stem = scene
        .file_stem()
        .map_or_else(|| "scene".to_owned(), |s| s.to_string_lossy().into_owned());
    dir.join(format!("{stem}{GOLDEN_SUFFIX}"))
}

/// The golden files in `dir`, in name order.
pub fn golden_files(dir: &Path) -> Result<Vec<PathBuf>, RegressError> {
    let entries = std::fs::read_dir(dir).map_err(|source| RegressError::Read {
        path: dir.to_owned(),
        source,
    })?;
    let mut files = Vec::new();
    for entry in entries {
        let entry = entry.map_err(|source| RegressError::Read {
            path: dir.to_owned(),
            source,
        })?;
        let name = entry.file_name().to_string_lossy().into_owned();
        if name.ends_with(GOLDEN_SUFFIX) {
            files.push(entry.path());
        }
    }
    files.sort();
    Ok(files)
}

/// Runs the scene file `scene` with `overrides` and writes its golden file in `dir` (which
/// must exist) with `tolerances` and about `checkpoints` checkpoints. Returns the file's
/// path and what it holds.
pub fn record(
    scene: &Path,
    dir: &Path,
    overrides: &RunOverrides,
    (tolerances, checkpoints): (&Tolerances, u64),
) -> Result<(PathBuf, Golden), RegressError> {
    tolerances.validate()?;
    let loaded = crate::scene::load(scene)?;
    let (_, summary) = run_scene(&loaded, overrides, checkpoints)?;
    let path = golden_path(dir, scene);
    let golden = Golden {
        format: GOLDEN_FORMAT.to_owned(),
        version: GOLDEN_VERSION,
        scene: relative_path(dir, scene),
        overrides: *overrides,
        checkpoints,
        tolerances: *tolerances,
        summary,
    };
    golden.write(&path)?;
    Ok((path, golden))
}

/// A golden file checked against a fresh run of its scene.
#[derive(Clone, Debug)]
pub struct Checked {
    /// The golden file.
    pub path: PathBuf,
    /// What it holds.
    pub golden: Golden,
    /// The fresh run's summary.
    pub fresh: Summary,
    /// The recorded run (A) against the fresh one (B), with the file's tolerances.
    pub comparison: Comparison,
}

impl Checked {
    /// Whether the run moved beyond the file's tolerances.
    pub fn moved(&self) -> bool {
        !self.comparison.within
    }

    /// The fresh run's drift check.
    pub fn drift(&self) -> Option<DriftCheck> {
        self.fresh.drift
    }

    /// Whether the fresh run breaks its drift budget.
    pub fn drift_broken(&self) -> bool {
        self.drift().is_some_and(|d| d.broken())
    }

    /// Whether the scene file changed since the recording (its checksum).
    pub fn scene_changed(&self) -> bool {
        let crc = |s: &Summary| s.scene.as_ref().map(|x| x.crc32.clone());
        crc(&self.golden.summary) != crc(&self.fresh)
    }

    /// Writes the fresh run into the golden file, keeping its scene, overrides,
    /// checkpoints and tolerances.
    pub fn update(&self) -> Result<(), RegressError> {
        let golden = Golden {
            summary: self.fresh.clone(),
            ..self.golden.clone()
        };
        golden.write(&self.path)
    }
}

/// Re-runs the scene of the golden file at `path` with its overrides and compares the run
/// with the recorded one, within the file's tolerances.
pub fn check(path: &Path) -> Result<Checked, RegressError> {
    let golden = Golden::read(path)?;
    let scene = crate::scene::load(golden.scene_path(path))?;
    let (_, fresh) = run_scene(&scene, &golden.overrides, golden.checkpoints)?;
    let comparison = compare(&golden.summary, &fresh, &golden.tolerances);
    Ok(Checked {
        path: path.to_owned(),
        golden,
        fresh,
        comparison,
    })
}

/// `target` relative to the folder `from`, with `/` separators: both made absolute
/// (canonical when they exist), the common prefix dropped, `..` for the rest of `from`.
/// Absolute when they share no root (another drive).
pub fn relative_path(from: &Path, target: &Path) -> String {
    let absolute = |p: &Path| {
        std::fs::canonicalize(p).unwrap_or_else(|_| {
            std::env::current_dir()
                .map(|d| d.join(p))
                .unwrap_or_else(|_| p.to_owned())
        })
    };
    let (from, target) = (absolute(from), absolute(target));
    let a: Vec<Component> = from.components().collect();
    let b: Vec<Component> = target.components().collect();
    if a.first() != b.first() {
        return slashes(&target);
    }
    let common = a.iter().zip(&b).take_while(|(x, y)| x == y).count();
    let mut parts: Vec<String> = vec!["..".to_owned(); a.len() - common];
    parts.extend(
        b[common..]
            .iter()
            .map(|c| c.as_os_str().to_string_lossy().into_owned()),
    );
    parts.join("/")
}

fn slashes(p: &Path) -> String {
    p.to_string_lossy().replace('\\', "/")
}
