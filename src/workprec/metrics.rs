//! The errors of a run against a reference, from their [`Trace`]s.
//!
//! Impacts are matched by rank: the k-th impact of the run against the k-th of the
//! reference, for the first `n` of the reference. A run with fewer than `n` impacts (a
//! missed impact) gets infinite impact, velocity and energy errors; an extra impact
//! shifts every later rank, which shows as a large error (that is what it is).

use super::Trace;
use crate::math::Real;

/// The four errors of a run (all non-negative; `INFINITY` when the run has fewer
/// impacts than compared, `NaN` when a reference value makes a ratio undefined).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Errors {
    /// `max_k≤n |t_k − t_k^ref|` (s): impact-time error.
    pub impact_time: Real,
    /// `max_k≤n |v_k^S − v_k^S,ref| / |v_k^S,ref|` (dimensionless, Euclidean norms of
    /// `(v_n^S, v_t^S)`): post-impact velocity error.
    pub velocity: Real,
    /// `|E_n − E_n^ref| / |E_0^ref − E_n^ref|`: the energy after the n-th impact, relative
    /// to the energy the reference loses in those n impacts (and the flights between).
    pub energy: Real,
    /// `|y − y^ref| / |y^ref|` with `y = (q, u)` at the end time (Euclidean norms, SI
    /// units mixed: m, rad, m/s, rad/s).
    pub end_state: Real,
}

/// The errors of `run` against `reference` over the first `n` impacts (`n ≥ 1`; the
/// reference must have them).
pub fn errors(run: &Trace, reference: &Trace, n: usize) -> Errors {
    let n = n.max(1);
    let (mut impact_time, mut velocity) = (0.0 as Real, 0.0 as Real);
    if run.impacts.len() < n || reference.impacts.len() < n {
        impact_time = Real::INFINITY;
        velocity = Real::INFINITY;
    } else {
        for (a, b) in run.impacts.iter().zip(&reference.impacts).take(n) {
            impact_time = impact_time.max((a.t - b.t).abs());
            let diff = (a.v_s[0] - b.v_s[0]).hypot(a.v_s[1] - b.v_s[1]);
            velocity = velocity.max(diff / b.v_s[0].hypot(b.v_s[1]));
        }
    }
    let energy = match (run.impacts.get(n - 1), reference.impacts.get(n - 1)) {
        (Some(a), Some(b)) => {
            (a.energy_after - b.energy_after).abs()
                / (reference.energy_initial - b.energy_after).abs()
        }
        _ => Real::INFINITY,
    };
    let end_state = if run.q.len() != reference.q.len() || run.u.len() != reference.u.len() {
        Real::NAN
    } else {
        let diff = run
            .q
            .iter()
            .zip(&reference.q)
            .chain(run.u.iter().zip(&reference.u));
        let num: Real = diff.map(|(a, b)| (a - b).powi(2)).sum::<Real>().sqrt();
        let den: Real = (reference.q.iter().chain(&reference.u))
            .map(|x| x * x)
            .sum::<Real>()
            .sqrt();
        // A run that stopped early (a failure) has not reached the end time.
        if (run.t_end - reference.t_end).abs() <= 1e-9 * reference.t_end.abs().max(1.0) {
            num / den
        } else {
            Real::INFINITY
        }
    };
    Errors {
        impact_time,
        velocity,
        energy,
        end_state,
    }
}
