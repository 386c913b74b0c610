//! The CSV tables of `ricochet bench`: one row per scene × method × setting
//! ([`Row`]), one row per chain length ([`ChainRow`]), one row per rope length on the
//! floor ([`FloorRow`]). Written and read back with the
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

/// The cost of the rope on the floor with `links` links over the window after its first
/// impact (`workprec::chain_floor`). The counters `steps` … `events` and `impacts` are the
/// window's (from the first impact on).
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct FloorRow {
    /// Number of links.
    pub links: u32,
    /// Number of contact pairs (link–link two or more apart, link–floor).
    pub pairs: u32,
    /// The window asked for after the first impact (s of simulated time).
    pub window_s: Real,
    /// The wall-time budget of the run through the window (s).
    pub budget_s: Real,
    /// Time of the first impact `t₁` (s); empty if the first run found none.
    pub t_first_impact: Option<Real>,
    /// Wall time of the free fall, release to first impact (s).
    pub free_fall_wall_s: Real,
    /// Its wall time per simulated second.
    pub free_fall_wall_per_sim_s: Real,
    /// Its CPU time (s; the simulating thread's, empty where it cannot be read).
    pub free_fall_cpu_s: Option<Real>,
    /// Accepted steps of the free fall.
    pub free_fall_steps: u64,
    /// Simulated time reached by the run through the window (s).
    pub t_reached: Real,
    /// How much of the window it reached, `t_reached − t₁` (s).
    pub window_reached_s: Real,
    /// Wall time of the run through the window, free fall included (s).
    pub wall_s: Real,
    /// Wall time spent in the window, after the first impact (s).
    pub window_wall_s: Real,
    /// Cost per simulated second: `window_wall_s / window_reached_s`.
    pub wall_per_sim_s: Real,
    /// CPU time spent in the window (s; empty where it cannot be read).
    pub window_cpu_s: Option<Real>,
    /// CPU time per simulated second: `window_cpu_s / window_reached_s`.
    pub cpu_per_sim_s: Option<Real>,
    /// The shortest window reached by any row of the table (s; empty if none).
    pub common_window_s: Option<Real>,
    /// The cost per simulated second over that shortest window.
    pub common_wall_per_sim_s: Option<Real>,
    /// Accepted steps in the window.
    pub steps: u64,
    /// Rejected steps in the window.
    pub rejected: u64,
    /// Right-hand-side evaluations of the integrator in the window.
    pub rhs_evals: u64,
    /// Events located in the window.
    pub events: u64,
    /// Impacts in the window (contact points struck; the first impact's included).
    pub impacts: u64,
    /// Distinct instants of those impacts.
    pub impact_instants: u64,
    /// Pairs closed (sticking or sliding) at the end of the run.
    pub closed_pairs_end: u32,
    /// Contact points of those pairs within the closed-contact tolerance at the end.
    pub closed_points_end: u32,
    /// The most pairs closed at once during the run.
    pub max_closed_pairs: u32,
    /// Whether the budget stopped the run before the end of the window.
    pub budget_limited: bool,
    /// Why the run stopped: `t_end`, `budget` or `error`.
    pub stop: String,
    /// The machine's load average (1 min) before the size's runs (empty where it cannot be
    /// read): the wall times grow with it on a shared machine, the CPU times much less.
    pub load_before: Option<Real>,
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

/// Reads the rows of a CSV file written by [`write`](fn@write).
pub fn read<T: DeserializeOwned>(path: &Path) -> Result<Vec<T>, WorkprecError> {
    let err = |error| WorkprecError::Csv {
        path: path.to_owned(),
        error,
    };
    let mut r = csv::Reader::from_path(path).map_err(err)?;
    r.deserialize().map(|row| row.map_err(err)).collect()
}
