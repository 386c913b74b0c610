//! The scaling of the event-driven loop (DOPRI5 at the scene's tolerances) with the
//! number of links of `scenes/chain.toml`, and where the time goes.

use std::hint::black_box;
use std::path::Path;
use std::time::Instant;

use super::WorkprecError;
use super::sweep::{Method, run_ricochet, wall_times};
use super::table::ChainRow;
use crate::contact::signed_gap;
use crate::dynamics::forward_dynamics;
use crate::kinematics::update_positions;
use crate::math::Real;
use crate::model::PairId;
use crate::sim::NullObserver;
use crate::state::Data;

/// Runs the chain of `links` links to `t_end` (s) `repeats` times without an observer,
/// and measures one right-hand-side evaluation and one evaluation of all the gaps alone
/// (the median of many, at the initial state bent by a few degrees per link).
pub fn measure(
    path: &Path,
    links: usize,
    t_end: Real,
    repeats: usize,
) -> Result<ChainRow, WorkprecError> {
    let mut scene = crate::scene::load_chain(path, links)?;
    scene.settings.t_end = t_end;
    let rtol = scene.settings.integrator.rtol;
    // Counters from one run (they do not depend on timing).
    let summary = run_ricochet(&scene, Method::Dopri5, rtol, &mut NullObserver)?;
    let (wall, lo, hi) = wall_times(repeats, || {
        let _ = black_box(run_ricochet(
            &scene,
            Method::Dopri5,
            rtol,
            &mut NullObserver,
        ));
    });
    // The right-hand side alone, and the gaps alone.
    let model = &scene.model;
    let q: Vec<Real> = (0..model.nq())
        .map(|i| scene.initial.q[i] + 0.05 * i as Real)
        .collect();
    let u: Vec<Real> = (0..model.nu()).map(|i| 0.5 - 0.07 * i as Real).collect();
    let mut data = Data::new(model);
    let query = |what: String| WorkprecError::Query { t: 0.0, what };
    let evals = (20_000 / links.max(1)).max(200);
    let rhs_eval_s = per_call(evals, || {
        forward_dynamics(model, &mut data, 0.0, black_box(&q), black_box(&u))
            .map(|_| ())
            .map_err(|e| query(e.to_string()))
    })?;
    let pairs: Vec<PairId> = model.pair_ids().collect();
    let npairs = pairs.len();
    let gaps_eval_s = per_call((evals / npairs.max(1)).max(50), || {
        update_positions(model, &mut data, 0.0, black_box(&q)).map_err(|e| query(e.to_string()))?;
        for &pair in &pairs {
            black_box(
                signed_gap(model, &data, pair, Real::INFINITY).map_err(|e| query(e.to_string()))?,
            );
        }
        Ok(())
    })?;
    let c = summary.counters;
    Ok(ChainRow {
        links: links as u32,
        pairs: npairs as u32,
        t_end: summary.state.t,
        wall_median_s: wall,
        wall_min_s: lo,
        wall_max_s: hi,
        wall_per_sim_s: wall / summary.state.t,
        steps: c.steps,
        rejected: c.rejected,
        rhs_evals: c.rhs_evals,
        events: c.events,
        impacts: c.impacts,
        rhs_eval_s,
        rhs_share: c.rhs_evals as Real * rhs_eval_s / wall,
        gaps_eval_s,
        stop: summary.stop.name().to_owned(),
    })
}

/// The mean wall time of `n` calls of `f` (s), the median of 5 such batches.
fn per_call(
    n: usize,
    mut f: impl FnMut() -> Result<(), WorkprecError>,
) -> Result<Real, WorkprecError> {
    let mut batches = Vec::with_capacity(5);
    for _ in 0..5 {
        let start = Instant::now();
        for _ in 0..n {
            f()?;
        }
        batches.push(start.elapsed().as_secs_f64() / n as Real);
    }
    batches.sort_by(Real::total_cmp);
    Ok(batches[2])
}

/// The least-squares slope `p` of `log y = p log x + c`: the exponent of a power law
/// `y ∝ x^p` through the points (at least two, positive).
pub fn power_law_exponent(points: &[(Real, Real)]) -> Real {
    let logs: Vec<(Real, Real)> = points
        .iter()
        .filter(|(x, y)| *x > 0.0 && *y > 0.0)
        .map(|(x, y)| (x.ln(), y.ln()))
        .collect();
    let n = logs.len() as Real;
    let (mx, my) = (
        logs.iter().map(|p| p.0).sum::<Real>() / n,
        logs.iter().map(|p| p.1).sum::<Real>() / n,
    );
    let sxy: Real = logs.iter().map(|p| (p.0 - mx) * (p.1 - my)).sum();
    let sxx: Real = logs.iter().map(|p| (p.0 - mx).powi(2)).sum();
    sxy / sxx
}
