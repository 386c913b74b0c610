//! Moving the stepper to a located event at full order: re-take the last step to the
//! event time, and correct the time by Newton's method on the full-order `g`.

use super::locate::{Completing, Sampler, time_tol};
use super::{Event, EventError, EventFunctions, EventKind, EventLocator};
use crate::integrate::{OdeSystem, Stepper};
use crate::math::Real;

/// The result of [`EventLocator::settle`]: the stepper now stands at `t` with the
/// full-order state.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Settled {
    /// The event time (s); `stepper.t() == t`.
    pub t: Real,
    /// The event function at the full-order state, `gᵢ(t, y(t))` (≈ 0 for a crossing).
    pub g: Real,
    /// Its rate `ġᵢ` there (from the caller's rates or a difference quotient).
    pub g_dot: Real,
    /// Steps re-taken (each costs one step's evaluations of `f`).
    pub resteps: u32,
    /// Whether the Newton correction converged to the time tolerance (always true for
    /// events that are not crossings).
    pub converged: bool,
}

/// Newton corrections of the event time at most (each one re-takes the step).
const MAX_NEWTON: u32 = 3;

impl EventLocator {
    /// Moves `stepper` to `event` (from the last [`locate`](Self::locate) on the same
    /// step) with the state at full order: the last step is re-taken from
    /// `(t_prev, y_prev)` to the event time ([`Stepper::restep_to`]), so the state is
    /// the method's own solution and not the order-4 continuous extension
    /// (`notes/crates.md` §3d: this removes the interpolant's error floor).
    ///
    /// For a crossing (`Crossing`, `Grazing`, `Bounce`) the time is then corrected by
    /// Newton's method on the full-order `gᵢ`, each iterate re-taking the step:
    ///
    /// ```text
    ///   t ← t − gᵢ(t, y(t)) / ġᵢ(t, y(t)),   until |Δt| ≤ 4 ε |t| + t_tol
    /// ```
    ///
    /// at most 3 times, staying inside the step and stopping if `ġᵢ ≥ 0`. Typically 2
    /// re-steps. `AtStart` rewinds to `t_prev` (free); `Reclosing` re-steps once.
    /// The stepper then continues from the event time; the loop applies its reset map
    /// with [`Stepper::reset`].
    pub fn settle<St, Sys, G>(
        &mut self,
        stepper: &mut St,
        sys: &mut Sys,
        funcs: &mut G,
        event: &Event,
    ) -> Result<Settled, EventError<G::Error, Sys::Error>>
    where
        St: Stepper,
        Sys: OdeSystem,
        G: EventFunctions,
    {
        let i = event.index;
        if i >= self.len() {
            return Err(EventError::Dimension {
                what: "event index",
                expected: self.len(),
                got: i,
            });
        }
        let (t_prev, t_end) = (stepper.t_prev(), stepper.t());
        let h = t_end - t_prev;
        let newton = matches!(
            event.kind,
            EventKind::Crossing | EventKind::Grazing | EventKind::Bounce
        );
        let mut t = event.t;
        let mut resteps = 0;
        let mut converged = !newton;
        loop {
            stepper.restep_to(sys, t)?;
            if t > t_prev {
                resteps += 1;
            }
            let (g, g_dot) = self.full_order_g(stepper, sys, funcs, i, t)?;
            let dt = -g / g_dot;
            let tol = time_tol(t, t, h, self.settings.t_tol);
            if newton && g_dot < 0.0 && dt.abs() <= tol {
                converged = true;
            }
            let t_new = t + dt;
            let inside = t_new > t_prev && t_new <= t_end;
            let closing = g_dot < 0.0;
            if converged || !closing || !inside || resteps >= MAX_NEWTON {
                return Ok(Settled {
                    t,
                    g,
                    g_dot,
                    resteps,
                    converged,
                });
            }
            t = t_new;
        }
    }

    /// `gᵢ` and `ġᵢ` at the stepper's current (full-order) state `t = stepper.t()` (a
    /// difference of `gᵢ` reads the re-taken step's dense output, completed then).
    fn full_order_g<St: Stepper, Sys: OdeSystem, G: EventFunctions>(
        &mut self,
        stepper: &mut St,
        sys: &mut Sys,
        funcs: &mut G,
        i: usize,
        t: Real,
    ) -> Result<(Real, Real), EventError<G::Error, Sys::Error>> {
        let inside = stepper.t() > stepper.t_prev();
        let mut sp = Sampler {
            step: Completing { stepper, sys },
            funcs,
            s: &mut self.scratch,
            counters: &mut self.counters,
        };
        sp.values(t)?;
        let g = sp.s.g[i];
        let g_dot = if inside {
            sp.rates(t)?;
            sp.s.gd[i]
        } else if sp.caller_rates(t)? {
            // An empty step (rewound to its start): only the caller's rates can say.
            sp.s.gd[i]
        } else {
            Real::NAN
        };
        Ok((g, g_dot))
    }
}
