//! What the test modules share: fixtures, helpers and the crate's counting allocator.
#![allow(dead_code)]

pub mod alloc;
pub mod cli;
pub mod mcap_check;
pub mod model_fixtures;
pub mod paper;
pub mod rng;
pub mod shared_file;

/// The energy scale of a run's audit, against which its drift is judged: the largest of
/// |T₀|, |V₀|, |T_end|, |V_end| and `floor` (J).
pub fn energy_scale(a: &ricochet::sim::EnergyAudit, floor: f64) -> f64 {
    [
        a.initial.kinetic,
        a.initial.potential,
        a.end.kinetic,
        a.end.potential,
    ]
    .iter()
    .fold(floor, |m, x| m.max(x.abs()))
}
