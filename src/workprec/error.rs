//! Errors of the work-precision module.

use std::path::PathBuf;

use crate::math::Real;

/// What can go wrong while measuring, writing or drawing.
#[derive(Debug, thiserror::Error)]
pub enum WorkprecError {
    /// A scene could not be loaded.
    #[error(transparent)]
    Scene(Box<crate::scene::SceneError>),
    /// A simulation could not be set up (bad settings).
    #[error("{method}: {error}")]
    Setup {
        /// The method.
        method: &'static str,
        /// Why.
        error: Box<crate::sim::SimError>,
    },
    /// A kinematics or contact query failed while reading a trajectory.
    #[error("at t = {t} s: {what}")]
    Query {
        /// Time (s).
        t: Real,
        /// What failed.
        what: String,
    },
    /// A scene that a method cannot represent faithfully.
    #[error("{method} cannot run scene {scene}: {reason}")]
    Unsupported {
        /// The method.
        method: &'static str,
        /// The scene.
        scene: String,
        /// Why.
        reason: String,
    },
    /// A CSV table could not be written or read.
    #[error("{path}: {error}")]
    Csv {
        /// The file.
        path: PathBuf,
        /// The error.
        error: csv::Error,
    },
    /// A chart could not be drawn.
    #[error("{path}: {reason}")]
    Chart {
        /// The file.
        path: PathBuf,
        /// Why.
        reason: String,
    },
}

impl From<crate::scene::SceneError> for WorkprecError {
    fn from(e: crate::scene::SceneError) -> Self {
        WorkprecError::Scene(Box::new(e))
    }
}
