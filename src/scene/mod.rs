//! Scene files: a versioned TOML format that a person writes by hand, read into a
//! [`Model`], its initial [`State`] and the run [`Settings`]. `scenes/README.md` documents
//! the format; `scenes/*.toml` are the scenes shared by tests, benches and examples.
//!
//! ```toml
//! version = 1
//! name = "pendulum"
//! gravity = [0.0, -9.81]            # m/s²
//!
//! [run]
//! t_end = 2.0                       # s
//!
//! [[body]]
//! name = "rod"
//! mass = 1.0                        # kg
//! com = [0.0, -0.5]                 # m, body frame
//! inertia = 0.0833                  # kg·m², about the centre of mass
//! joint = { type = "revolute", angle = "30 deg" }
//! ```
//!
//! Loading checks the syntax, rejects unknown fields, and validates the physics (positive
//! masses and inertias, finite numbers, existing parents and no cycles, `0 ≤ e ≤ 1`,
//! `μ ≥ 0`, no overlapping shapes at the start beyond a tolerance). Every error names the
//! file, the line, the column and the field:
//!
//! ```text
//! scenes/bad.toml:12:9: body["rod"].joint.angle: an angle needs its unit: write e.g. "20 deg" or "0.35 rad"
//! ```

mod build;
mod chain;
mod error;
mod format;
mod joint;
#[doc(hidden)]
pub mod ranges;
mod shape;
#[doc(hidden)]
pub mod units;

use std::path::{Path, PathBuf};

pub use build::{DEFAULT_OVERLAP_TOLERANCE, VERSION};
pub use error::SceneError;

use crate::model::Model;
use crate::settings::Settings;
use crate::state::State;

use build::Overrides;
use error::Locator;

/// A loaded scene.
#[derive(Clone, Debug)]
pub struct Scene {
    /// The scene's name (its `name` field).
    pub name: String,
    /// Its description (the `description` field; may be empty).
    pub description: String,
    /// The file it was read from.
    pub path: PathBuf,
    /// The text of the file, as read (the log stores it).
    pub text: String,
    /// The mechanical model.
    pub model: Model,
    /// The initial state, at `t = 0`.
    pub initial: State,
    /// The run settings.
    pub settings: Settings,
    /// How far shapes may overlap at the start (m): `[contact] overlap_tolerance`.
    pub overlap_tolerance: crate::math::Real,
}

impl Scene {
    /// Checks another initial state of the scene as its own is checked when it loads (a
    /// sweep's `q0.…` values): no two shapes overlapping by more than the scene's
    /// tolerance. The message names the two shapes and the overlap.
    pub fn check_initial(&self, initial: &State) -> Result<(), String> {
        build::first_overlap(&self.model, initial, self.overlap_tolerance)
    }
}

/// Reads and validates the scene file at `path`.
pub fn load(path: impl AsRef<Path>) -> Result<Scene, SceneError> {
    load_with(path.as_ref(), Overrides::default())
}

/// Reads the scene file at `path` (which must have a `[chain]` table) with its number of
/// links set to `links`: the benches build chains of 1 to 32 links from `scenes/chain.toml`.
pub fn load_chain(path: impl AsRef<Path>, links: usize) -> Result<Scene, SceneError> {
    load_with(
        path.as_ref(),
        Overrides {
            chain_links: Some(links),
        },
    )
}

/// Validates the scene `text`; `path` is only used in messages and kept in the result.
pub fn load_str(text: &str, path: impl AsRef<Path>) -> Result<Scene, SceneError> {
    parse(text.to_owned(), path.as_ref(), Overrides::default())
}

fn load_with(path: &Path, overrides: Overrides) -> Result<Scene, SceneError> {
    let text = std::fs::read_to_string(path).map_err(|error| SceneError::Io {
        path: path.to_owned(),
        error,
    })?;
    parse(text, path, overrides)
}

fn parse(text: String, path: &Path, overrides: Overrides) -> Result<Scene, SceneError> {
    let loc = Locator { path, text: &text };
    let file: format::SceneFile = toml::from_str(&text).map_err(|e| loc.toml(&e))?;
    let built = build::build(file, &loc, &overrides)?;
    Ok(Scene {
        name: built.name,
        description: built.description,
        path: path.to_owned(),
        model: built.model,
        initial: built.initial,
        settings: built.settings,
        overlap_tolerance: built.overlap_tolerance,
        text,
    })
}
