//! The CSV tables of `ricochet bench`: one row per scene × method × setting
//! ([`Row`]), one row per chain length ([`ChainRow`]). Written and read back with the
//! `csv` crate; non-finite errors are written as `inf` / `NaN` and read back as such.

use std::path::Path;

use serde::{Deserialize, Serialize, de::DeserializeOwned};

use super::WorkprecError;
use crate::math::Real;

/// One measured setting of one method on one scene.
#[derive(Clone, Debug, Default, PartialEq, Serialize, Deserialize)]
pub struct Row {
    /// The scene's name.
    pub scene: String,
    /// The method (`dopri5`, `rk4`, `moreau-jean`, `rapier`).
    pub method: String,
    /// The swept setting (`rtol` or `dt`).
    pub parameter: String,
    /// Its value (dimensionless, or s).
    pub value: Real,
    /// Median wall time of the timed runs (s).
    pub wall_median_s: Real,
    /// Fastest timed run (s).
    pub wall_min_s: Real,
    /// Slowest timed run (s).
    pub wall_max_s: Real,
    /// Number of timed runs.
    pub repeats: u32,
    /// Accepted steps.
    pub steps: u64,
    /// Right-hand-side (forward-dynamics) evaluations; empty for rapier.
    pub rhs_evals: Option<u64>,
    /// Impacts found in the run.
    pub impacts: u64,
    /// Impacts compared (the first n of the reference).
    pub compared: u32,
    /// Why the run stopped (`end_time`, `accumulation`, `failed`, ...).
    pub stop: String,
    /// The reference of the impact errors (`closed_form`, `dopri5_rtol_1e-13`).
    pub reference: String,
    /// Impact-time error, max over the compared impacts (s).
    pub err_impact_time: Real,
    /// Post-impact velocity error, max relative over the compared impacts.
    pub err_velocity: Real,
    /// Energy after the n-th impact, relative to the reference's loss.
    pub err_energy: Real,
    /// State at the end time, relative.
    pub err_end_state: Real,
}

/// The scaling of the event-driven loop (DOPRI5) with the number of links of `chain`.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct ChainRow {
    /// Number of links.
    pub links: u32,
    /// Number of contact pairs.
    pub pairs: u32,
    /// Simulated time (s).
    pub t_end: Real,
    /// Median wall time (s).
    pub wall_median_s: Real,
    /// Fastest run (s).
    pub wall_min_s: Real,
    /// Slowest run (s).
    pub wall_max_s: Real,
    /// Median wall time per simulated second.
    pub wall_per_sim_s: Real,
    /// Accepted steps.
    pub steps: u64,
    /// Rejected steps.
    pub rejected: u64,
    /// Right-hand-side evaluations.
    pub rhs_evals: u64,
    /// Events located.
    pub events: u64,
    /// Impacts.
    pub impacts: u64,
    /// Wall time of one right-hand-side evaluation, measured alone (s).
    pub rhs_eval_s: Real,
    /// Estimated share of the run spent in the integrator's right-hand-side evaluations:
    /// `rhs_evals · rhs_eval_s / wall` (the event locator's rates run the forward
    /// dynamics too, outside this counter).
    pub rhs_share: Real,
    /// Wall time of one evaluation of every pair's signed gap, measured alone (s).
    pub gaps_eval_s: Real,
    /// Why the run stopped.
    pub stop: String,
}

/// Writes `rows` to `path` as CSV with a header.
pub fn write<T: Serialize>(path: &Path, rows: &[T]) -> Result<(), WorkprecError> {
    let err = |error| WorkprecError::Csv {
        path: path.to_owned(),
        error,
    };
    let mut w = csv::Writer::from_path(path).map_err(err)?;
    for row in rows {
        w.serialize(row).map_err(err)?;
    }
    w.flush().map_err(|e| err(e.into()))
}

/// Reads the rows of a CSV file written by [`write`].
pub fn read<T: DeserializeOwned>(path: &Path) -> Result<Vec<T>, WorkprecError> {
    let err = |error| WorkprecError::Csv {
        path: path.to_owned(),
        error,
    };
    let mut r = csv::Reader::from_path(path).map_err(err)?;
    r.deserialize().map(|row| row.map_err(err)).collect()
}
