//! Event location on the dense output of an integrator step. Generic: the functions
//! `gᵢ(t, y)` are supplied by the caller (the simulation loop computes signed gaps); this
//! module knows nothing about contacts.
//!
//! # Semantics
//!
//! An **event** of function `i` is a *closing* crossing: from `gᵢ > 0` (separated) to
//! `gᵢ ≤ 0`. Opening crossings (`≤ 0` to `> 0`) are never events. Per step `[t_prev, t]`
//! the [`EventLocator`] returns the **earliest** event of any armed function, and lists
//! the other functions' events within a simultaneity tolerance of it. The kinds
//! ([`EventKind`]):
//!
//! | situation in the step | result |
//! |---|---|
//! | `g > 0` at one sample, `≤ 0` at the next | `Crossing`, root bracketed to a few ulp by Illinois on the dense output |
//! | `g > 0` at both samples, `ġ` from − to + between them, minimum `≤ 0` | `Grazing`, bracketed the same way |
//! | `g(t_prev) ≤ 0` and closing (`ġ < 0`, or `ġ = 0` and `g` falling) | `AtStart` at `t_prev`: a root exactly at the step's start; the loop decides |
//! | `g(t_prev) ≈ 0` and opening (just after an impact) | no event at the start (**no re-detection**), but a later closing crossing in the same step is found: |
//! |   … `g ≤ 0` at both samples, `ġ` from + to −, maximum `> 0` | `Bounce` (a bounce shorter than a sample interval) |
//! |   … maximum `≤ 0` | `Reclosing` (the function closes again without separating) |
//!
//! The time `t` of an event is the post-event end `t_hi` of its bracket
//! (`g(t_lo) > 0 ≥ g(t_hi)` on the dense output), as users of event-driven solvers expect
//! (SciML DifferentialEquations.jl #551). After locating, [`EventLocator::settle`]
//! re-takes the step to the event time so that the state is at the method's full
//! order, with a Newton correction of the time on the full-order `g`.
//!
//! # Driving it from a loop
//!
//! ```
//! use ricochet::events::{EventLocator, FnEvents, LocatorSettings};
//! use ricochet::integrate::{Dopri5, Dopri5Settings, FnSystem, StepOutcome, Stepper};
//! // A ball y = (height, velocity) under gravity, bouncing with restitution e.
//! let (grav, e) = (9.81, 0.8);
//! let mut sys = FnSystem::new(2, move |_t, y: &[f64], dy: &mut [f64]| {
//!     dy[0] = y[1];
//!     dy[1] = -grav;
//! });
//! let mut gap = FnEvents::with_rates(
//!     |_t, y: &[f64], g: &mut [f64]| g[0] = y[0],
//!     |_t, y: &[f64], _dy: &[f64], g_dot: &mut [f64]| g_dot[0] = y[1],
//! );
//! let settings = Dopri5Settings { rtol: 1e-12, atol: 1e-12, h_max: 1.0, ..Default::default() };
//! let mut stepper = Dopri5::new(2, settings)?;
//! let mut locator = EventLocator::new(2, 1, LocatorSettings::default());
//! stepper.start(&mut sys, 0.0, &[1.0, 0.0])?;
//! let mut impacts = Vec::new();
//! while impacts.len() < 3 {
//!     stepper.step(&mut sys, f64::INFINITY)?;                        // step
//!     if let Some(event) = locator.locate(&stepper, &mut gap, &[true])? { // locate
//!         let settled = locator.settle(&mut stepper, &mut sys, &mut gap, &event)?; // restep
//!         let y = [stepper.y()[0], -e * stepper.y()[1]];              // the reset map
//!         stepper.reset(&mut sys, settled.t, &y)?;                    // reset
//!         impacts.push(settled.t);
//!     }
//! }
//! let t1 = (2.0 / grav).sqrt();
//! assert!((impacts[0] - t1).abs() < 1e-12);
//! assert!((impacts[1] - (t1 + 2.0 * e * grav * t1 / grav)).abs() < 1e-12);
//! # Ok::<(), Box<dyn std::error::Error>>(())
//! ```
//!
//! # Limits (what can be missed)
//!
//! - Between two consecutive samples, `g` is assumed to have **at most one extremum**
//!   (`ġ` changes sign at most once). A dip below zero *and back* between two positive
//!   samples is found through `ġ` (its sign change locates the minimum), so grazing
//!   contacts and obstacles crossed in much less than a step are found, however short
//!   the crossing. Two or more extrema between samples (`g` oscillating faster than the
//!   sample spacing `h/(k+1)`) can hide a crossing: raise `samples`, or cap the step.
//! - The search sees `g` through the dense output (order 4 for DOPRI5, 3 for RK4) and `ġ`
//!   through its derivative (one order lower) or a difference quotient: a dip shallower
//!   than the interpolation error (≈ the tolerance) may be found or not. A tangency with
//!   minimum exactly 0 counts as an event only if a point with `g ≤ 0` is evaluated.
//! - With `extremum_search = false`, only sign changes at the samples are seen, and a dip
//!   between samples is missed (tested).
//! - The guaranteed alternative is a step bound from the closing speed,
//!   [`closing_time_bound`], given to [`Stepper::set_h_max`](crate::integrate::Stepper::set_h_max).

use std::convert::Infallible;

use crate::integrate::IntegrateError;
use crate::math::Real;

#[doc(hidden)]
pub mod bound;
mod function;
#[doc(hidden)]
pub mod illinois;
#[doc(hidden)]
pub mod locate;
mod settle;

pub use bound::closing_time_bound;
pub use function::{EventFunctions, FnEvents, RatesFn};
pub use locate::{Event, EventKind, EventLocator, LocatorCounters, LocatorSettings};
pub use settle::Settled;

/// A failure of event location. `G` is the error of the event functions, `E` that of the
/// system's right-hand side (only [`EventLocator::settle`] and
/// [`EventLocator::locate_completing_dense`] integrate).
#[derive(Debug, thiserror::Error)]
pub enum EventError<G, E = Infallible>
where
    G: std::error::Error + 'static,
    E: std::error::Error + 'static,
{
    /// An event function failed.
    #[error("event function failed at t = {t}")]
    Function {
        /// Time of the failing evaluation (s).
        t: Real,
        /// The caller's error.
        #[source]
        source: G,
    },
    /// An armed event function (or its rate) is not finite.
    #[error("event function {index} is not finite at t = {t}")]
    NonFinite {
        /// Time of the evaluation (s).
        t: Real,
        /// Index of the function.
        index: usize,
    },
    /// A length does not match the locator's dimensions.
    #[error("dimension mismatch ({what}): expected {expected}, got {got}")]
    Dimension {
        /// What has the wrong length.
        what: &'static str,
        /// The locator's dimension.
        expected: usize,
        /// What was passed.
        got: usize,
    },
    /// A root search did not converge within `max_iter` iterations.
    #[error("event {index} not localized after {iters} iterations: bracket [{t_lo}, {t_hi}]")]
    NotConverged {
        /// Index of the function.
        index: usize,
        /// Last lower end (s).
        t_lo: Real,
        /// Last upper end (s).
        t_hi: Real,
        /// Iterations used.
        iters: usize,
    },
    /// Re-taking the step failed.
    #[error(transparent)]
    Integrate(#[from] IntegrateError<E>),
}
