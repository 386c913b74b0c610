//! Work-precision: the cost and the accuracy of each way to run a scene, measured in one
//! process on the same scenes (issue 6), and the scaling of the cost with the size of a
//! chain.
//!
//! A run is reduced to a [`Trace`] (its impacts: time, post-impact contact velocity,
//! energy after; its state at the end time), whatever produced it: the event-driven loop
//! with DOPRI5 or RK4, the Moreau–Jean time-stepping, or rapier2d (feature `rapier`,
//! `rapier`). [`metrics`] compares a trace with a reference trace (a closed form, or a
//! tight DOPRI5 run: [`reference`](mod@reference)); [`sweep`] runs the settings of each method and times
//! them; [`table`] writes and reads the CSV rows; [`chart`] draws the log–log charts;
//! [`chain`] measures the scaling with the number of links in free fall, [`chain_floor`]
//! with a floor.
//!
//! `ricochet bench` (the command line) puts them together.

pub mod chain;
pub mod chain_floor;
pub mod chart;
mod error;
pub mod metrics;
#[cfg(feature = "rapier")]
pub mod rapier;
pub mod reference;
pub mod sweep;
pub mod table;
mod trace;

pub use error::WorkprecError;
pub use trace::{ImpactRecord, Trace, TraceObserver};
