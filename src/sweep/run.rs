//! Running the points of a grid: the overrides of one point, one run without a log, the
//! row it gives, and the parallel map over a shard.

use std::num::NonZeroUsize;
use std::panic::{AssertUnwindSafe, catch_unwind};
use std::sync::atomic::{AtomicBool, Ordering};

use rayon::prelude::*;

use crate::integrate::Method;
use crate::scene::Scene;
use crate::sim::{
    EnergyAudit, MaterialOverride, MoreauJean, NullObserver, RunCounters, RunSummary, Simulation,
};
use crate::state::State;

use super::grid::{Grid, Shard};
use super::spec::{Param, Value, format_real};
use super::table::{Header, write_table};
use super::{SpecError, SweepError};

/// Where a parameter's value goes.
#[derive(Clone, Copy, Debug)]
enum Target {
    E,
    Mu,
    Law,
    Method,
    Simultaneous,
    TEnd,
    Rtol,
    Atol,
    Dt,
    HMax,
    /// `q[i]` of the initial state.
    Q(usize),
    /// `u[i]` of the initial state.
    U(usize),
}

/// A sweep: a scene and a grid of overrides of it.
#[derive(Debug)]
pub struct Sweep<'s> {
    scene: &'s Scene,
    grid: Grid,
    targets: Vec<Target>,
}

impl<'s> Sweep<'s> {
    /// The sweep of `grid` over `scene`. Errors: a `q0.`/`u0.` parameter that names no
    /// coordinate of the scene's model.
    pub fn new(scene: &'s Scene, grid: Grid) -> Result<Sweep<'s>, SpecError> {
        // `q0.` names a coordinate, `u0.` a generalized speed (the same names for a
        // holonomic scene; a nonholonomic one has its own, see `Model::speeds`).
        let names = |speeds: bool| -> Vec<String> {
            if speeds {
                speed_names(scene)
            } else {
                coordinate_names(scene)
            }
        };
        let coordinate = |param: &Param, name: &str| {
            let known = names(matches!(param, Param::U0(_)));
            known
                .iter()
                .position(|c| c == name)
                .ok_or_else(|| SpecError::UnknownCoordinate {
                    param: param.to_string(),
                    name: name.to_owned(),
                    scene: scene.name.clone(),
                    known: known.join(", "),
                })
        };
        let targets = grid
            .params()
            .iter()
            .map(|p| {
                Ok(match &p.param {
                    Param::E => Target::E,
                    Param::Mu => Target::Mu,
                    Param::Law => Target::Law,
                    Param::Method => Target::Method,
                    Param::Simultaneous => Target::Simultaneous,
                    Param::TEnd => Target::TEnd,
                    Param::Rtol => Target::Rtol,
                    Param::Atol => Target::Atol,
                    Param::Dt => Target::Dt,
                    Param::HMax => Target::HMax,
                    Param::Q0(c) => Target::Q(coordinate(&p.param, c)?),
                    Param::U0(c) => Target::U(coordinate(&p.param, c)?),
                })
            })
            .collect::<Result<_, SpecError>>()?;
        Ok(Sweep {
            scene,
            grid,
            targets,
        })
    }

    /// The grid.
    pub fn grid(&self) -> &Grid {
        &self.grid
    }

    /// The scene.
    pub fn scene(&self) -> &Scene {
        self.scene
    }

    /// The header of the table of `shard` of this sweep.
    pub fn header(&self, shard: Shard) -> Header {
        Header::new(self.scene, &self.grid, shard)
    }

    /// The columns of the table: `run`, the parameters in the order given, then
    /// [`RESULT_COLUMNS`], then the final state `t`, `q.<coordinate>`…, `u.<speed>`… (the
    /// coordinates' names for a holonomic scene, the speeds' own for a nonholonomic one:
    /// `Model::speeds`), and last `stop_detail`.
    pub fn columns(&self) -> Vec<String> {
        let (names, speeds) = (coordinate_names(self.scene), speed_names(self.scene));
        std::iter::once("run".to_owned())
            .chain(self.grid.params().iter().map(|p| p.param.to_string()))
            .chain(RESULT_COLUMNS.iter().map(|c| (*c).to_owned()))
            .chain(std::iter::once("t".to_owned()))
            .chain(names.iter().map(|c| format!("q.{c}")))
            .chain(speeds.iter().map(|c| format!("u.{c}")))
            .chain(std::iter::once("stop_detail".to_owned()))
            .collect()
    }

    /// Writes the table of `shard` with `rows` (as [`Sweep::run`] returns them) to `out`.
    pub fn write_table(
        &self,
        out: impl std::io::Write,
        shard: Shard,
        rows: &[Row],
    ) -> Result<(), SweepError> {
        self.write_table_under(out, &self.header(shard), rows)
    }

    /// [`Sweep::write_table`] under `header` (e.g. [`Sweep::header`] marked
    /// [`incomplete`](Header::incomplete)).
    pub fn write_table_under(
        &self,
        out: impl std::io::Write,
        header: &Header,
        rows: &[Row],
    ) -> Result<(), SweepError> {
        let (nq, nu) = (self.scene.model.nq(), self.scene.model.nu());
        write_table(
            out,
            header,
            &self.columns(),
            rows.iter().map(|r| r.fields(nq, nu)),
        )
    }

    /// Runs the point `index` of the grid: the scene's settings, materials and initial
    /// state with the point's overrides, by the event-driven loop or Moreau–Jean (as the
    /// `method` says), with no log ([`NullObserver`]). A run that cannot start, fails or
    /// panics is a row with that stop reason, never an error of the sweep.
    pub fn run_point(&self, index: usize) -> Row {
        let values = self.values(index);
        let outcome = caught(|| self.simulate(&values, None));
        Row {
            index,
            values,
            outcome,
        }
    }

    /// [`Sweep::run_point`] under the interrupt flag `interrupt`: `None` if the flag is set
    /// before the run starts, or while it runs (the run stops at its next step: it did not
    /// finish, and gives no row).
    pub fn run_point_until(&self, index: usize, interrupt: Option<&AtomicBool>) -> Option<Row> {
        let stopped = || interrupt.is_some_and(|flag| flag.load(Ordering::SeqCst));
        if stopped() {
            return None;
        }
        let values = self.values(index);
        let outcome = caught(|| self.simulate(&values, interrupt));
        let interrupted = matches!(&outcome, Ok(r) if r.stop == INTERRUPTED);
        (!interrupted).then_some(Row {
            index,
            values,
            outcome,
        })
    }

    /// The values of the parameters at the point `index`, in the grid's order.
    fn values(&self, index: usize) -> Vec<Value> {
        (0..self.targets.len())
            .map(|j| self.grid.value(index, j))
            .collect()
    }

    /// One run with the overrides `values`, stopped by `interrupt` when it is set.
    fn simulate(
        &self,
        values: &[Value],
        interrupt: Option<&AtomicBool>,
    ) -> Result<RunResult, NotRun> {
        let mut settings = self.scene.settings.clone();
        let mut initial = self.scene.initial.clone();
        let mut overrides = MaterialOverride::default();
        for (target, value) in self.targets.iter().zip(values) {
            match (*target, *value) {
                (Target::E, Value::Real(x)) => overrides.e = Some(x),
                (Target::Mu, Value::Real(x)) => overrides.mu = Some(x),
                (Target::Law, Value::Law(l)) => overrides.law = Some(l),
                (Target::Method, Value::Method(m)) => settings.integrator.method = m,
                (Target::Simultaneous, Value::Simultaneous(r)) => settings.simultaneous = r,
                (Target::TEnd, Value::Real(x)) => settings.t_end = x,
                (Target::Rtol, Value::Real(x)) => settings.integrator.rtol = x,
                (Target::Atol, Value::Real(x)) => settings.integrator.atol = x,
                (Target::Dt, Value::Real(x)) => settings.integrator.dt = x,
                (Target::HMax, Value::Real(x)) => settings.integrator.h_max = x,
                (Target::Q(i), Value::Real(x)) => initial.q[i] = x,
                (Target::U(i), Value::Real(x)) => initial.u[i] = x,
                // The parser gives each parameter values of its own kind.
                (target, value) => {
                    return Err(NotRun {
                        stop: "error",
                        detail: format!("the value {value} does not fit {target:?}"),
                    });
                }
            }
        }
        // A swept initial state is checked as the scene's own is when it loads (a ball
        // put 5 m inside the floor "reached the end time").
        if (self.targets.iter()).any(|t| matches!(t, Target::Q(_))) {
            self.scene
                .check_initial(&initial)
                .map_err(|detail| NotRun {
                    stop: "error",
                    detail: format!("the initial state: {detail}"),
                })?;
        }
        let model = &self.scene.model;
        let summary = match settings.integrator.method {
            Method::MoreauJean => MoreauJean::new(model, &settings, overrides)
                .map(|mut mj| mj.run(&initial, &mut NullObserver, interrupt)),
            Method::Dopri5 | Method::Dop853 | Method::Rk4 => {
                Simulation::new(model, &settings, overrides)
                    .map(|mut sim| sim.run(&initial, &mut NullObserver, interrupt))
            }
        }
        .map_err(|e| NotRun {
            stop: "error",
            detail: format!("cannot simulate: {e}"),
        })?;
        Ok(RunResult::from(summary))
    }

    /// Runs the points of `shard` in parallel on `threads` threads (see [`thread_pool`]),
    /// calling `done` after each run (from any thread): [`Sweep::run_in`] a new pool.
    pub fn run(
        &self,
        shard: Shard,
        threads: Option<NonZeroUsize>,
        done: &(dyn Fn(&Row) + Sync),
    ) -> Result<Vec<Row>, SweepError> {
        Ok(self.run_in(&thread_pool(threads)?, shard, done))
    }

    /// Runs the points of `shard` in parallel in `pool`, calling `done` after each run
    /// (from any thread). The rows come back in increasing run index whatever the threads
    /// and the order in which the runs finish (rayon's indexed `collect`), and each run is
    /// independent of the others, so the rows do not depend on the number of threads.
    pub fn run_in(
        &self,
        pool: &rayon::ThreadPool,
        shard: Shard,
        done: &(dyn Fn(&Row) + Sync),
    ) -> Vec<Row> {
        self.run_until(pool, shard, done, None)
    }

    /// [`Sweep::run_in`] under the interrupt flag `interrupt` (Ctrl-C): once it is set, the
    /// runs under way stop at their next step and no other run starts. The rows are those
    /// of the runs that finished (all of them when the flag stays clear), in increasing
    /// run index.
    pub fn run_until(
        &self,
        pool: &rayon::ThreadPool,
        shard: Shard,
        done: &(dyn Fn(&Row) + Sync),
        interrupt: Option<&AtomicBool>,
    ) -> Vec<Row> {
        let runs: Vec<usize> = shard.runs(self.grid.len()).collect();
        let rows: Vec<Option<Row>> = pool.install(|| {
            runs.par_iter()
                .map(|&index| {
                    let row = self.run_point_until(index, interrupt)?;
                    done(&row);
                    Some(row)
                })
                .collect()
        });
        rows.into_iter().flatten().collect()
    }
}

/// The [`StopReason::name`](crate::sim::StopReason::name) of an interrupted run.
const INTERRUPTED: &str = "interrupted";

/// The outcome of `run`, or a `panic` row with the panic's message if it panics (a bug:
/// the sweep goes on with the other runs).
#[doc(hidden)]
pub fn caught(run: impl FnOnce() -> Result<RunResult, NotRun>) -> Result<RunResult, NotRun> {
    catch_unwind(AssertUnwindSafe(run)).unwrap_or_else(|payload| {
        let what = payload
            .downcast_ref::<&str>()
            .map(|s| (*s).to_owned())
            .or_else(|| payload.downcast_ref::<String>().cloned())
            .unwrap_or_else(|| "unknown".to_owned());
        Err(NotRun {
            stop: "panic",
            detail: format!("the run panicked: {what}"),
        })
    })
}

/// A rayon pool of `threads` threads (`None`: one per core, or `RAYON_NUM_THREADS`).
pub fn thread_pool(threads: Option<NonZeroUsize>) -> Result<rayon::ThreadPool, SweepError> {
    Ok(rayon::ThreadPoolBuilder::new()
        .num_threads(threads.map_or(0, NonZeroUsize::get))
        .build()?)
}

/// The names of the generalized speeds, in the order of `u`: the coordinates' names for a
/// holonomic scene (`u = q̇`), their own for a nonholonomic one (`Model::speeds`).
fn speed_names(scene: &Scene) -> Vec<String> {
    (scene.model.speeds().iter())
        .map(|s| s.name.clone())
        .collect()
}

/// The names of the model's coordinates, in the order of `q`.
fn coordinate_names(scene: &Scene) -> Vec<String> {
    scene
        .model
        .coordinates()
        .iter()
        .map(|c| c.name.clone())
        .collect()
}

/// The result columns between the parameters and the final state:
///
/// - `stop`: `t_end`, `accumulation`, `interrupted`, `error` (the run failed; it may also
///   not have started, then the numbers are empty), `panic` (a bug; the row says where);
/// - `impacts`: the impacts applied;
/// - `delta_e`: ΔE total, the sum of ΔE of Eq. (29) over the impacts (J);
/// - `energy_0`, `energy_end`: the total energy at the start and at the end (J);
/// - `impact_prescribed_work`, `damping_work`, `applied_work`, `drive_work`,
///   `contact_work`: the other terms of the energy audit (J), and `drift`, what it leaves
///   unexplained (J);
/// - `steps`, `rejected`, `rhs_evals`, `events`: the work counters.
///
/// No wall time: the table is a function of the scene and the grid alone (identical
/// whatever the sharding and the threads), and the command prints the time instead.
pub const RESULT_COLUMNS: [&str; 15] = [
    "stop",
    "impacts",
    "delta_e",
    "energy_0",
    "energy_end",
    "impact_prescribed_work",
    "damping_work",
    "applied_work",
    "drive_work",
    "contact_work",
    "drift",
    "steps",
    "rejected",
    "rhs_evals",
    "events",
];

/// What one run gave.
#[derive(Clone, Debug, PartialEq)]
pub struct RunResult {
    /// [`crate::sim::StopReason::name`].
    pub stop: &'static str,
    /// The stop reason in words.
    pub detail: String,
    /// The energy audit.
    pub audit: EnergyAudit,
    /// The work counters (the impacts among them).
    pub counters: RunCounters,
    /// The final state.
    pub state: State,
}

impl From<RunSummary> for RunResult {
    fn from(s: RunSummary) -> Self {
        RunResult {
            stop: s.stop.name(),
            detail: s.stop.to_string(),
            audit: s.audit,
            counters: s.counters,
            state: s.state,
        }
    }
}

/// A run that did not start (its settings are refused) or panicked.
#[derive(Clone, Debug, PartialEq)]
pub struct NotRun {
    /// `error` or `panic`.
    pub stop: &'static str,
    /// Why.
    pub detail: String,
}

/// One row of the table: a run of the grid.
#[derive(Clone, Debug, PartialEq)]
pub struct Row {
    /// The run index in the grid.
    pub index: usize,
    /// The values of the parameters, in the grid's order.
    pub values: Vec<Value>,
    /// What the run gave.
    pub outcome: Result<RunResult, NotRun>,
}

impl Row {
    /// The stop reason's short name.
    pub fn stop(&self) -> &'static str {
        match &self.outcome {
            Ok(r) => r.stop,
            Err(n) => n.stop,
        }
    }

    /// The fields of the row, in the order of [`Sweep::columns`] (`nq` and `nu` the sizes
    /// of the model's state, for the empty fields of a run that did not start). Numbers
    /// in [`format_real`], the shortest decimal that reads back to the same `f64`.
    pub fn fields(&self, nq: usize, nu: usize) -> Vec<String> {
        let mut f = Vec::with_capacity(1 + self.values.len() + RESULT_COLUMNS.len() + nq + nu + 2);
        f.push(self.index.to_string());
        f.extend(self.values.iter().map(Value::to_string));
        match &self.outcome {
            Ok(r) => {
                let a = &r.audit;
                let c = &r.counters;
                f.push(r.stop.to_owned());
                f.push(c.impacts.to_string());
                f.extend(
                    [
                        a.impact_delta_e,
                        a.initial.total(),
                        a.end.total(),
                        a.impact_prescribed_work,
                        a.damping_work,
                        a.applied_work,
                        a.drive_work,
                        a.contact_work,
                        a.drift(),
                    ]
                    .map(format_real),
                );
                f.extend([c.steps, c.rejected, c.rhs_evals, c.events].map(|n| n.to_string()));
                f.push(format_real(r.state.t));
                f.extend(r.state.q.iter().map(|&x| format_real(x)));
                f.extend(r.state.u.iter().map(|&x| format_real(x)));
                f.push(r.detail.clone());
            }
            Err(n) => {
                f.push(n.stop.to_owned());
                f.extend(std::iter::repeat_n(
                    String::new(),
                    RESULT_COLUMNS.len() - 1 + 1 + nq + nu,
                ));
                f.push(n.detail.clone());
            }
        }
        f
    }
}
