//! `ricochet bench`: the work-precision charts (error against wall time, one curve per
//! method, one chart per scene and error kind) and the scaling of the event-driven loop
//! with the number of links of a chain, in free fall and (`--floor`) falling onto a floor,
//! measured in one process; CSV, SVG and a description of the machine go to `--out`
//! (default `docs/charts`).
//!
//! A subcommand rather than a criterion bench: it must run several methods on the same
//! scenes with their accuracy, write tables and charts, and take options; criterion
//! measures one closure at a time and owns the command line. rapier2d is compiled only
//! with `--features rapier`; without it the bench runs ricochet's methods and says so.

use std::fmt::Write as _;
use std::path::{Path, PathBuf};
use std::process::ExitCode;

use anyhow::{Context, bail};
use ricochet::math::Real;
use ricochet::scene::Scene;
use ricochet::workprec::chain_floor::{self, FloorSettings};
use ricochet::workprec::chart::{self, Labels, Series};
use ricochet::workprec::metrics::{Errors, errors};
use ricochet::workprec::reference::{self, Ball, TIGHT_RTOL};
use ricochet::workprec::sweep::{self, Method};
use ricochet::workprec::table::{self, ChainRow, FloorRow, Row};
use ricochet::workprec::{Trace, chain};

use crate::output::say;

/// Options of `ricochet bench`.
#[derive(clap::Args)]
pub struct Args {
    /// Folder of the CSV tables, the SVG charts and MACHINE.txt.
    #[arg(short, long, default_value = "docs/charts")]
    out: PathBuf,
    /// Timed runs per setting (the median is reported).
    #[arg(long, default_value_t = 5)]
    repeats: usize,
    /// Scenes of the work-precision part (comma-separated; default: all four).
    #[arg(long, value_delimiter = ',')]
    scenes: Option<Vec<String>>,
    /// Skip the work-precision part.
    #[arg(long)]
    no_workprec: bool,
    /// Skip the chain scaling part.
    #[arg(long)]
    no_chain: bool,
    /// Largest chain (links; the chains are 1, 2, 4, ... up to it).
    #[arg(long, default_value_t = 16)]
    max_links: usize,
    /// Simulated time of each chain run (s): the free fall before any contact.
    #[arg(long, default_value_t = 0.05)]
    chain_t_end: Real,
    /// Run the scaling of the rope falling onto the floor (`scenes/chain_floor.toml`
    /// cut into 1, 2, 4, ... links; long: up to the budget per size).
    #[arg(long)]
    floor: bool,
    /// Largest rope of the floor part (links).
    #[arg(long, default_value_t = 256)]
    floor_max_links: usize,
    /// The floor part's sizes instead of the powers of two (comma-separated links).
    #[arg(long, value_delimiter = ',')]
    floor_links: Option<Vec<usize>>,
    /// The window measured after the rope's first impact (s of simulated time).
    #[arg(long, default_value_t = 0.5)]
    floor_window: Real,
    /// Wall-time budget of each size's run through the window (s): a run that exhausts it
    /// stops there and its row says how far it got.
    #[arg(long, default_value_t = 1200.0)]
    floor_budget: Real,
    /// Redraw `chain_floor_scaling.svg` and print the fits from the floor part's CSV in
    /// `--out`, without measuring (MACHINE.txt unchanged).
    #[arg(long)]
    floor_redraw: bool,
}

/// A scene of the work-precision part: its file, end time, the impacts compared, and how
/// its reference is made.
struct Case {
    name: &'static str,
    t_end: Real,
    impacts: usize,
}

const CASES: [Case; 4] = [
    // Before the accumulation point (4.06 s): 7 impacts.
    Case {
        name: "bouncing_ball",
        t_end: 3.0,
        impacts: 5,
    },
    // The lower end strikes, then the other; to before the accumulation.
    Case {
        name: "falling_rod",
        t_end: 0.8,
        impacts: 3,
    },
    // From the paper's impact at t = 0 through the bounces of the tip.
    Case {
        name: "kane_double_pendulum",
        t_end: 0.5,
        impacts: 3,
    },
    Case {
        name: "pendulum_wall",
        t_end: 5.0,
        impacts: 5,
    },
];

const KINDS: [(&str, &str); 4] = [
    (
        "impact_time",
        "impact-time error, max over the first n impacts (s)",
    ),
    ("velocity", "post-impact velocity error, max relative"),
    (
        "energy",
        "energy error after n impacts, relative to the loss",
    ),
    ("end_state", "end-state error |y − y_ref|/|y_ref|"),
];

fn kind_value(e: &Row, kind: &str) -> Real {
    match kind {
        "impact_time" => e.err_impact_time,
        "velocity" => e.err_velocity,
        "energy" => e.err_energy,
        _ => e.err_end_state,
    }
}

pub fn run(args: Args) -> anyhow::Result<ExitCode> {
    if args.repeats == 0 {
        bail!("--repeats must be at least 1");
    }
    if !(args.chain_t_end.is_finite() && args.chain_t_end > 0.0) {
        bail!("--chain-t-end must be a positive number of seconds");
    }
    if args.max_links == 0 {
        bail!("--max-links must be at least 1");
    }
    if !(args.floor_window.is_finite() && args.floor_window > 0.0) {
        bail!("--floor-window must be a positive number of seconds");
    }
    if args.floor_budget.is_nan() || args.floor_budget <= 0.0 {
        bail!("--floor-budget must be a positive number of seconds");
    }
    if args.floor_max_links == 0 || args.floor_links.as_ref().is_some_and(|l| l.contains(&0)) {
        bail!("a rope has at least 1 link");
    }
    let scenes_dir = Path::new(env!("CARGO_MANIFEST_DIR")).join("scenes");
    let cases: Vec<&Case> = match &args.scenes {
        None => CASES.iter().collect(),
        Some(names) => names
            .iter()
            .map(|n| {
                CASES.iter().find(|c| c.name == n).with_context(|| {
                    format!(
                        "unknown scene {n:?}; the work-precision scenes are {}",
                        CASES.map(|c| c.name).join(", ")
                    )
                })
            })
            .collect::<anyhow::Result<_>>()?,
    };
    std::fs::create_dir_all(&args.out)
        .with_context(|| format!("cannot create {}", args.out.display()))?;
    let mut notes = String::new();
    if !cfg!(feature = "rapier") {
        say!(
            "rapier2d is not compiled in (build with --features rapier): ricochet's methods only"
        )?;
    }
    if !args.no_workprec {
        let mut rows = Vec::new();
        for case in &cases {
            rows.extend(workprec(
                &scenes_dir,
                case,
                args.repeats,
                &args.out,
                &mut notes,
            )?);
        }
        let path = args.out.join("workprec.csv");
        table::write(&path, &rows)?;
        say!("wrote {}", path.display())?;
    }
    if !args.no_chain {
        chain_scaling(&scenes_dir, &args, &mut notes)?;
    }
    let mut floor_notes = None;
    if args.floor_redraw {
        let csv = args.out.join("chain_floor.csv");
        let rows: Vec<FloorRow> = table::read(&csv)?;
        for line in floor_summary(&rows) {
            say!("  {line}")?;
        }
        floor_chart(&args.out.join("chain_floor_scaling.svg"), &rows)?;
        say!(
            "redrew chain_floor_scaling.svg and chain_floor_per_step.svg from {}",
            csv.display()
        )?;
    } else if args.floor {
        let mut lines = String::new();
        floor_scaling(&args, &mut lines)?;
        floor_notes = Some(lines);
    }
    let main_notes = (!(args.no_workprec && args.no_chain)).then_some(notes.as_str());
    if main_notes.is_some() || floor_notes.is_some() {
        machine(&args.out, main_notes, floor_notes.as_deref())?;
    }
    Ok(ExitCode::SUCCESS)
}

/// The work-precision part on one scene.
fn workprec(
    dir: &Path,
    case: &Case,
    repeats: usize,
    out: &Path,
    notes: &mut String,
) -> anyhow::Result<Vec<Row>> {
    let mut scene = ricochet::scene::load(dir.join(format!("{}.toml", case.name)))?;
    scene.settings.t_end = case.t_end;
    let (reference, ref_name) = reference_of(&scene, notes)?;
    say!(
        "\n{} to {} s, {} impacts compared, reference {ref_name}: impacts at {}",
        case.name,
        case.t_end,
        case.impacts,
        reference
            .impacts
            .iter()
            .map(|i| format!("{:.6}", i.t))
            .collect::<Vec<_>>()
            .join(", ")
    )?;
    if reference.impacts.len() < case.impacts {
        bail!(
            "{}: the reference has {} impacts, fewer than the {} compared",
            case.name,
            reference.impacts.len(),
            case.impacts
        );
    }
    let mut rows = Vec::new();
    for method in Method::ALL {
        for setting in method.default_sweep() {
            let Some(row) = measure(
                &scene, case, method, setting, repeats, &reference, &ref_name,
            )?
            else {
                continue;
            };
            say!(
                "  {:<12} {}={:<8.0e} wall {:>10.3e} s  steps {:>8}  rhs {:>8}  impacts {:>3}  \
                 err t {:.2e}  v {:.2e}  E {:.2e}  end {:.2e}  {}",
                row.method,
                row.parameter,
                row.value,
                row.wall_median_s,
                row.steps,
                row.rhs_evals.map_or("-".into(), |r| r.to_string()),
                row.impacts,
                row.err_impact_time,
                row.err_velocity,
                row.err_energy,
                row.err_end_state,
                row.stop
            )?;
            rows.push(row);
        }
    }
    for (kind, label) in KINDS {
        let series: Vec<Series> = Method::ALL
            .iter()
            .filter_map(|m| {
                let points: Vec<(Real, Real)> = (rows.iter())
                    .filter(|r| r.method == m.name())
                    .map(|r| (r.wall_median_s, kind_value(r, kind)))
                    .collect();
                (!points.is_empty()).then(|| Series {
                    name: m.name().to_owned(),
                    points,
                })
            })
            .collect();
        let path = out.join(format!("{}_{kind}.svg", case.name));
        let title = format!("{} ({}; × off scale)", case.name, ref_name);
        chart::loglog(
            &path,
            Labels {
                title: &title,
                x: "wall time (s), median",
                y: label,
            },
            &series,
        )?;
    }
    for other in [
        Method::MoreauJean,
        Method::Rapier,
        Method::Rk4,
        Method::Dop853,
    ] {
        if let Some(line) = equal_wall_ratio(&rows, other, "velocity") {
            say!("  {}: {line}", case.name)?;
            let _ = writeln!(notes, "{}: {line}", case.name);
        }
    }
    if case.name == "kane_double_pendulum" {
        let mut s = scene.clone();
        s.settings.t_end = 2.0;
        for method in [Method::Dopri5, Method::Dop853] {
            let (wall, lo, hi) = sweep::time_ricochet(&s, method, 1e-10, repeats.max(5))?;
            let line = format!(
                "kane_double_pendulum to 2 s with {} at rtol 1e-10 (atol 1e-12), no log: wall \
                 {wall:.3e} s (runs {lo:.3e}–{hi:.3e}), {:.3e} simulated s per wall s (target \
                 ≥ 1e4)",
                method.name(),
                2.0 / wall
            );
            say!("  {line}")?;
            let _ = writeln!(notes, "{line}");
        }
    }
    Ok(rows)
}

/// The reference of a scene and its name.
fn reference_of(scene: &Scene, notes: &mut String) -> anyhow::Result<(Trace, String)> {
    let material = (scene.model.pairs().next())
        .with_context(|| format!("{}: no contact pair", scene.name))?
        .material;
    if scene.name == "bouncing_ball" {
        let radius = scene.model.colliders()[0]
            .shape
            .as_ball()
            .context("bouncing_ball: the ball's shape")?
            .radius;
        let ball = Ball {
            g: -scene.model.gravity().y,
            y0: scene.initial.q[0],
            r: radius,
            m: scene.model.bodies()[0].mass,
            e: material.e,
        };
        return Ok((ball.closed_form(scene.settings.t_end), "closed form".into()));
    }
    let tight = reference::tight(scene)?;
    if scene.name == "falling_rod" {
        // The tight run against the analytic first impact (the scene's constants).
        let first = reference::falling_rod_first_impact(
            1.0,
            1.0,
            0.01,
            30f64.to_radians(),
            1.0,
            9.81,
            material.e,
            material.mu,
        )?;
        let got = tight.impacts.first().context("falling_rod: no impact")?;
        let line = format!(
            "falling_rod: the reference's first impact against the analytic one: |Δt| = {:.1e} s, \
             |Δv_n^S| = {:.1e} m/s, ||Δv_t^S|| = {:.1e} m/s, |ΔE| = {:.1e} J",
            (got.t - first.t).abs(),
            (got.v_s[0] - first.v_s[0]).abs(),
            (got.v_s[1].abs() - first.v_s[1].abs()).abs(),
            (got.energy_after - first.energy_after).abs()
        );
        say!("{line}")?;
        let _ = writeln!(notes, "{line}");
    }
    Ok((tight, format!("dopri5 rtol {TIGHT_RTOL:.0e}")))
}

/// One method at one setting: the errors from one observed run, the wall time from
/// `repeats` runs without observer. `None` if the method is not available (rapier
/// without the feature) or cannot run the scene (said on the terminal).
fn measure(
    scene: &Scene,
    case: &Case,
    method: Method,
    setting: Real,
    repeats: usize,
    reference: &Trace,
    ref_name: &str,
) -> anyhow::Result<Option<Row>> {
    let (trace, steps, rhs, stop, walls) = match method {
        Method::Rapier => match rapier_run(scene, setting, repeats)? {
            Some(r) => r,
            None => return Ok(None),
        },
        _ => {
            let (trace, c, stop) = sweep::trace_of(scene, method, setting)?;
            let walls = sweep::time_ricochet(scene, method, setting, repeats)?;
            (
                trace,
                c.steps,
                Some(c.rhs_evals),
                stop.name().to_owned(),
                walls,
            )
        }
    };
    let Errors {
        impact_time,
        velocity,
        energy,
        end_state,
    } = errors(&trace, reference, case.impacts);
    Ok(Some(Row {
        scene: case.name.into(),
        method: method.name().into(),
        parameter: method.parameter().into(),
        value: setting,
        wall_median_s: walls.0,
        wall_min_s: walls.1,
        wall_max_s: walls.2,
        repeats: repeats as u32,
        steps,
        rhs_evals: rhs,
        impacts: trace.impacts.len() as u64,
        compared: case.impacts as u32,
        stop,
        reference: ref_name.into(),
        err_impact_time: impact_time,
        err_velocity: velocity,
        err_energy: energy,
        err_end_state: end_state,
    }))
}

type Measured = (Trace, u64, Option<u64>, String, (Real, Real, Real));

#[cfg(feature = "rapier")]
fn rapier_run(scene: &Scene, dt: Real, repeats: usize) -> anyhow::Result<Option<Measured>> {
    use ricochet::workprec::rapier::RapierWorld;
    let t_end = scene.settings.t_end;
    let mut world = match RapierWorld::new(scene, dt) {
        Ok(w) => w,
        Err(e) => {
            say!("  rapier: {e}")?;
            return Ok(None);
        }
    };
    let trace = world.trace(t_end)?;
    let steps = (t_end / dt).round() as u64;
    let walls = sweep::wall_times(repeats, || {
        if let Ok(mut w) = RapierWorld::new(scene, dt) {
            for _ in 0..steps {
                w.step();
            }
            std::hint::black_box(w.t());
        }
    });
    Ok(Some((trace, steps, None, "t_end".into(), walls)))
}

#[cfg(not(feature = "rapier"))]
fn rapier_run(_: &Scene, _: Real, _: usize) -> anyhow::Result<Option<Measured>> {
    Ok(None)
}

/// At equal wall time, `other`'s error over DOPRI5's, for every setting of `other` whose
/// wall time DOPRI5 can match: DOPRI5's error at that wall time is interpolated on its
/// log–log curve (or, beyond its slowest setting, its most accurate one). Returns a line
/// with the smallest and the largest ratio.
fn equal_wall_ratio(rows: &[Row], other: Method, kind: &str) -> Option<String> {
    let mut dopri: Vec<(Real, Real)> = (rows.iter())
        .filter(|r| r.method == "dopri5")
        .map(|r| (r.wall_median_s, kind_value(r, kind)))
        .filter(|p| p.1.is_finite() && p.1 > 0.0)
        .collect();
    dopri.sort_by(|a, b| a.0.total_cmp(&b.0));
    let (first, last) = (dopri.first()?.0, dopri.last()?.0);
    let ratios: Vec<(Real, Real)> = (rows.iter())
        .filter(|r| r.method == other.name() && r.wall_median_s >= first)
        .map(|r| {
            let w = r.wall_median_s;
            let e = if w >= last {
                dopri.iter().map(|p| p.1).fold(Real::INFINITY, Real::min)
            } else {
                let k = dopri.iter().position(|p| p.0 > w).unwrap_or(1).max(1);
                let (a, b) = (dopri[k - 1], dopri[k]);
                let s = (w.ln() - a.0.ln()) / (b.0.ln() - a.0.ln());
                (a.1.ln() + s * (b.1.ln() - a.1.ln())).exp()
            };
            (r.value, kind_value(r, kind) / e)
        })
        .collect();
    if ratios.is_empty() {
        return Some(format!(
            "{} is faster than DOPRI5's fastest setting at every step: no equal-wall comparison",
            other.name()
        ));
    }
    let p = other.parameter();
    let min = ratios
        .iter()
        .fold(ratios[0], |m, p| if p.1 < m.1 { *p } else { m });
    let max = ratios
        .iter()
        .fold(ratios[0], |m, p| if p.1 > m.1 { *p } else { m });
    Some(format!(
        "{kind} error of {} / DOPRI5's at equal wall time: from {:.2e} ({p} {:.0e}) to {:.2e} \
         ({p} {:.0e}) over {} settings",
        other.name(),
        min.1,
        min.0,
        max.1,
        max.0,
        ratios.len()
    ))
}

/// The chain scaling part.
fn chain_scaling(dir: &Path, args: &Args, notes: &mut String) -> anyhow::Result<()> {
    let path = dir.join("chain.toml");
    let mut rows: Vec<ChainRow> = Vec::new();
    let mut links = 1;
    say!(
        "\nchain, DOPRI5 at the scene's tolerances, to {} s:",
        args.chain_t_end
    )?;
    while links <= args.max_links {
        let repeats = if links >= 16 { 3 } else { args.repeats };
        let r = chain::measure(&path, links, args.chain_t_end, repeats)?;
        say!(
            "  {:>2} links, {:>3} pairs: {:.3e} wall s per simulated s ({}), {} steps \
             ({} rejected), {} rhs, {} events, {} impacts; rhs {:.2e} s each = {:.0} % of \
             the run; all gaps {:.2e} s",
            r.links,
            r.pairs,
            r.wall_per_sim_s,
            r.stop,
            r.steps,
            r.rejected,
            r.rhs_evals,
            r.events,
            r.impacts,
            r.rhs_eval_s,
            100.0 * r.rhs_share,
            r.gaps_eval_s
        )?;
        rows.push(r);
        links *= 2;
    }
    let points: Vec<(Real, Real)> = rows
        .iter()
        .map(|r| (Real::from(r.links), r.wall_per_sim_s))
        .collect();
    let p_all = chain::power_law_exponent(&points);
    let p_big = chain::power_law_exponent(&points[points.len().saturating_sub(3)..]);
    let line = format!(
        "chain: wall time per simulated second ∝ links^{p_all:.2} over all, \
         ^{p_big:.2} over the three largest"
    );
    say!("  {line}")?;
    let _ = writeln!(notes, "{line}");
    let csv = args.out.join("chain.csv");
    table::write(&csv, &rows)?;
    let series = [
        Series {
            name: "wall s per simulated s".into(),
            points,
        },
        Series {
            name: "rhs evaluations × rhs time, per simulated s".into(),
            points: rows
                .iter()
                .map(|r| {
                    (
                        Real::from(r.links),
                        r.rhs_evals as Real * r.rhs_eval_s / r.t_end,
                    )
                })
                .collect(),
        },
    ];
    chart::loglog(
        &args.out.join("chain_scaling.svg"),
        Labels {
            title: &format!("chain: event-driven DOPRI5 (slope {p_all:.2})"),
            x: "links",
            y: "wall time per simulated second",
        },
        &series,
    )?;
    say!("wrote {} and chain_scaling.svg", csv.display())?;
    Ok(())
}

/// The scaling of the rope falling onto the floor (`workprec::chain_floor`).
fn floor_scaling(args: &Args, notes: &mut String) -> anyhow::Result<()> {
    let sizes: Vec<usize> = match &args.floor_links {
        Some(links) => links.clone(),
        None => std::iter::successors(Some(1usize), |n| n.checked_mul(2))
            .take_while(|&n| n <= args.floor_max_links)
            .collect(),
    };
    let settings = FloorSettings {
        window: args.floor_window,
        budget: args.floor_budget,
    };
    say!(
        "\nrope on the floor, DOPRI5 at the scene's tolerances, {} s after the first impact, \
         budget {} s of wall time per size:",
        settings.window,
        settings.budget
    )?;
    let mut rows: Vec<FloorRow> = Vec::new();
    let mut readings: Vec<Vec<(Real, Real)>> = Vec::new();
    for &links in &sizes {
        let mut r = Vec::new();
        let row = chain_floor::measure(links, settings, &mut r)?;
        say!(
            "  {:>3} links: first impact at {} s after {:.3e} s of wall ({} steps); window \
             reached {:.4} s of {} in {:.3e} s of wall: {:.3e} wall s ({} CPU s) per \
             simulated s{}; {} steps ({} rejected), {} rhs, {} events, {} impacts at {} \
             instants; closed at the end {} pairs, {} points (most pairs at once {}); {}; load \
             before {}",
            row.links,
            row.t_first_impact
                .map_or("(none)".into(), |t| format!("{t:.4}")),
            row.free_fall_wall_s,
            row.free_fall_steps,
            row.window_reached_s,
            row.window_s,
            row.window_wall_s,
            row.wall_per_sim_s,
            row.cpu_per_sim_s.map_or("?".into(), |c| format!("{c:.3e}")),
            if row.budget_limited {
                " (budget-limited)"
            } else {
                ""
            },
            row.steps,
            row.rejected,
            row.rhs_evals,
            row.events,
            row.impacts,
            row.impact_instants,
            row.closed_pairs_end,
            row.closed_points_end,
            row.max_closed_pairs,
            row.stop,
            row.load_before.map_or("?".into(), |l| l.to_string())
        )?;
        rows.push(row);
        readings.push(r);
    }
    chain_floor::common_window(&mut rows, &readings);
    let csv = args.out.join("chain_floor.csv");
    table::write(&csv, &rows)?;
    let lines = floor_summary(&rows);
    for line in &lines {
        say!("  {line}")?;
        let _ = writeln!(notes, "{line}");
    }
    floor_chart(&args.out.join("chain_floor_scaling.svg"), &rows)?;
    say!(
        "wrote {}, chain_floor_scaling.svg and chain_floor_per_step.svg",
        csv.display()
    )?;
    Ok(())
}

/// The complete rows' points `(links, cost per simulated second)` of the window.
fn complete_points(rows: &[FloorRow]) -> Vec<(Real, Real)> {
    (rows.iter())
        .filter(|r| !r.budget_limited && r.stop == "t_end" && r.wall_per_sim_s.is_finite())
        .map(|r| (Real::from(r.links), r.wall_per_sim_s))
        .collect()
}

/// One size's figures in a line: the window's cost, its steps, the cost of a step.
fn floor_line(r: &FloorRow) -> String {
    format!(
        "chain_floor {:>3} links: {:.4} s of the {} s window{} in {:.3e} s wall, {} CPU s: \
         {:.3e} wall s per simulated s, {:.3e} steps per simulated s, {:.3e} wall s per \
         step; {} impacts; {} closed points at the end",
        r.links,
        r.window_reached_s,
        r.window_s,
        if r.budget_limited {
            " (budget-limited)"
        } else {
            ""
        },
        r.window_wall_s,
        r.window_cpu_s.map_or("?".into(), |c| format!("{c:.3e}")),
        r.wall_per_sim_s,
        r.steps as Real / r.window_reached_s,
        r.window_wall_s / r.steps as Real,
        r.impacts,
        r.closed_points_end
    )
}

/// The fitted exponents of the floor part, as lines for the terminal and MACHINE.txt.
fn floor_summary(rows: &[FloorRow]) -> Vec<String> {
    let mut lines: Vec<String> = rows.iter().map(floor_line).collect();
    let fit = |points: &[(Real, Real)], what: &str, lines: &mut Vec<String>| {
        if points.len() >= 2 {
            let (a, b) = (points[0].0, points[points.len() - 1].0);
            lines.push(format!(
                "chain_floor: {what} ∝ links^{:.2} over {a}–{b} links ({} sizes)",
                chain::power_law_exponent(points),
                points.len()
            ));
        }
    };
    let complete = complete_points(rows);
    fit(
        &complete,
        "wall time per simulated second of the window",
        &mut lines,
    );
    let big: Vec<(Real, Real)> = complete.iter().copied().filter(|p| p.0 >= 8.0).collect();
    if big.len() < complete.len() {
        fit(
            &big,
            "wall time per simulated second of the window",
            &mut lines,
        );
    }
    let common: Vec<(Real, Real)> = (rows.iter())
        .filter_map(|r| Some((Real::from(r.links), r.common_wall_per_sim_s?)))
        .collect();
    if let Some(tau) = rows.iter().find_map(|r| r.common_window_s) {
        let big: Vec<(Real, Real)> = common.iter().copied().filter(|p| p.0 >= 8.0).collect();
        fit(
            &big,
            &format!("wall time per simulated second of the first {tau:.4} s after the impact"),
            &mut lines,
        );
    }
    let fall: Vec<(Real, Real)> = (rows.iter())
        .filter(|r| r.t_first_impact.is_some() && r.links >= 8)
        .map(|r| (Real::from(r.links), r.free_fall_wall_per_sim_s))
        .collect();
    fit(
        &fall,
        "wall time per simulated second of the free fall",
        &mut lines,
    );
    for r in rows
        .iter()
        .filter(|r| r.budget_limited || r.stop != "t_end")
    {
        lines.push(format!(
            "chain_floor: {} links stopped ({}) {:.4} s into the {} s window after {:.0} s of \
             wall: {:.3e} wall s per simulated s reached",
            r.links, r.stop, r.window_reached_s, r.window_s, r.wall_s, r.wall_per_sim_s
        ));
    }
    lines
}

/// The exponent fitted to the points from 8 links on (all of them if fewer than two), and
/// the sizes it spans.
fn slope_from_8(points: &[(Real, Real)]) -> Option<(Real, Real, Real)> {
    let big: Vec<(Real, Real)> = points.iter().copied().filter(|p| p.0 >= 8.0).collect();
    let fitted = if big.len() >= 2 { &big[..] } else { points };
    (fitted.len() >= 2).then(|| {
        (
            chain::power_law_exponent(fitted),
            fitted[0].0,
            fitted[fitted.len() - 1].0,
        )
    })
}

/// `chain_floor_scaling.svg`: the window's cost per simulated second against links, in
/// wall and CPU time (the complete rows; the budget-limited ones apart), over the common
/// window, and the free fall's.
fn floor_chart(path: &Path, rows: &[FloorRow]) -> anyhow::Result<()> {
    let Some(first) = rows.first() else {
        return Ok(());
    };
    let (window, budget) = (first.window_s, first.budget_s);
    let complete = complete_points(rows);
    let cpu: Vec<(Real, Real)> = (rows.iter())
        .filter(|r| !r.budget_limited && r.stop == "t_end")
        .filter_map(|r| Some((Real::from(r.links), r.cpu_per_sim_s?)))
        .collect();
    let slope = |points: &[(Real, Real)]| {
        slope_from_8(points).map_or(String::new(), |(p, a, b)| {
            format!(" (links^{p:.2} over {a}–{b})")
        })
    };
    let mut series = vec![Series {
        name: format!(
            "wall, the {window} s after the first impact{}",
            slope(&complete)
        ),
        points: complete,
    }];
    if !cpu.is_empty() {
        series.push(Series {
            name: format!("CPU, the {window} s after the first impact{}", slope(&cpu)),
            points: cpu,
        });
    }
    let limited: Vec<(Real, Real)> = (rows.iter())
        .filter(|r| (r.budget_limited || r.stop != "t_end") && r.wall_per_sim_s.is_finite())
        .map(|r| (Real::from(r.links), r.wall_per_sim_s))
        .collect();
    if !limited.is_empty() {
        series.push(Series {
            name: format!(
                "wall, stopped by the budget ({budget} s): wall / simulated time reached"
            ),
            points: limited,
        });
    }
    if let Some(tau) = rows.iter().find_map(|r| r.common_window_s) {
        let common: Vec<(Real, Real)> = (rows.iter())
            .filter_map(|r| Some((Real::from(r.links), r.common_wall_per_sim_s?)))
            .collect();
        series.push(Series {
            name: format!(
                "wall, the first {tau:.3} s after the first impact (every size){}",
                slope(&common)
            ),
            points: common,
        });
    }
    series.push(Series {
        name: "wall, free fall before the first impact".into(),
        points: (rows.iter())
            .filter(|r| r.t_first_impact.is_some())
            .map(|r| (Real::from(r.links), r.free_fall_wall_per_sim_s))
            .collect(),
    });
    chart::loglog(
        path,
        Labels {
            title: "rope falling onto the floor: event-driven DOPRI5",
            x: "links",
            y: "time per simulated second (s)",
        },
        &series,
    )?;
    floor_step_chart(&path.with_file_name("chain_floor_per_step.svg"), rows)
}

/// `chain_floor_per_step.svg`: the time of a step against links, in the window (CPU: the
/// complete rows and the budget-limited ones; wall: the complete rows) and in the free fall
/// (CPU). The window's cost per simulated second is this times the steps per simulated
/// second, which a step cap can multiply whatever a step costs.
fn floor_step_chart(path: &Path, rows: &[FloorRow]) -> anyhow::Result<()> {
    let limited = |r: &FloorRow| r.budget_limited || r.stop != "t_end";
    let per_step = |keep: &dyn Fn(&FloorRow) -> bool, time: &dyn Fn(&FloorRow) -> Option<Real>| {
        (rows.iter())
            .filter(|r| r.steps > 0 && keep(r))
            .filter_map(|r| Some((Real::from(r.links), time(r)? / r.steps as Real)))
            .collect::<Vec<_>>()
    };
    let fitted = |name: &str, points: Vec<(Real, Real)>| Series {
        name: format!(
            "{name}{}",
            slope_from_8(&points).map_or(String::new(), |(p, a, b)| format!(
                " (links^{p:.2} over {a}–{b})"
            ))
        ),
        points,
    };
    let mut series = vec![
        fitted(
            "CPU, the window after the first impact",
            per_step(&|r| !limited(r), &|r| r.window_cpu_s),
        ),
        fitted(
            "wall, the window after the first impact",
            per_step(&|r| !limited(r), &|r| Some(r.window_wall_s)),
        ),
    ];
    let cut = per_step(&limited, &|r| r.window_cpu_s);
    if !cut.is_empty() {
        series.push(Series {
            name: "CPU, the window stopped by the budget".into(),
            points: cut,
        });
    }
    series.push(Series {
        name: "CPU, free fall before the first impact".into(),
        points: (rows.iter())
            .filter(|r| r.t_first_impact.is_some() && r.free_fall_steps > 0)
            .filter_map(|r| {
                Some((
                    Real::from(r.links),
                    r.free_fall_cpu_s? / r.free_fall_steps as Real,
                ))
            })
            .collect(),
    });
    series.retain(|s| !s.points.is_empty());
    chart::loglog(
        path,
        Labels {
            title: "rope falling onto the floor: time per accepted step",
            x: "links",
            y: "time per step (s)",
        },
        &series,
    )?;
    Ok(())
}

/// The heading of the floor part's section of `MACHINE.txt`.
const FLOOR_SECTION: &str = "## chain_floor (`ricochet bench --floor`)";

/// `MACHINE.txt`: the CPU, cores, load, date, rustc, commit, and the figures printed; one
/// section for the work-precision and chain parts (`main`), one for the floor part
/// (`floor`), each with its own machine lines. A part that did not run (`None`) keeps its
/// section of the file as it was.
fn machine(out: &Path, main: Option<&str>, floor: Option<&str>) -> anyhow::Result<()> {
    let path = out.join("MACHINE.txt");
    let old = std::fs::read_to_string(&path).unwrap_or_default();
    let (old_main, old_floor) = match old.find(FLOOR_SECTION) {
        Some(k) => (&old[..k], &old[k..]),
        None => (old.as_str(), ""),
    };
    let mut text = match main {
        Some(notes) => machine_lines(notes),
        None => old_main.to_owned(),
    };
    let floor = match floor {
        Some(notes) => format!("{FLOOR_SECTION}\n\n{}", machine_lines(notes)),
        None => old_floor.to_owned(),
    };
    if !floor.is_empty() {
        if !text.is_empty() && !text.ends_with("\n\n") {
            text.push_str(if text.ends_with('\n') { "\n" } else { "\n\n" });
        }
        text.push_str(&floor);
    }
    std::fs::write(&path, text).with_context(|| format!("cannot write {}", path.display()))?;
    say!("wrote {}", path.display())?;
    Ok(())
}

/// The machine's lines and `notes` after them.
fn machine_lines(notes: &str) -> String {
    let cpu = std::fs::read_to_string("/proc/cpuinfo")
        .ok()
        .and_then(|s| {
            s.lines()
                .find(|l| l.starts_with("model name"))
                .and_then(|l| l.split(':').nth(1))
                .map(|m| m.trim().to_owned())
        })
        .unwrap_or_else(|| "unknown".into());
    let cores = std::thread::available_parallelism().map_or(0, |n| n.get());
    let load = std::fs::read_to_string("/proc/loadavg").unwrap_or_default();
    let cmd = |c: &str, a: &[&str]| {
        std::process::Command::new(c)
            .args(a)
            .output()
            .ok()
            .map(|o| String::from_utf8_lossy(&o.stdout).trim().to_owned())
            .unwrap_or_else(|| "unknown".into())
    };
    format!(
        "cpu: {cpu}\ncores: {cores}\nload average (1, 5, 15 min) at the end: {}\ndate: {}\n\
         rustc: {}\ncommit: {}\nfeatures: {}\n\n{notes}",
        load.split_whitespace()
            .take(3)
            .collect::<Vec<_>>()
            .join(" "),
        cmd("date", &["-u", "+%Y-%m-%dT%H:%M:%SZ"]),
        cmd("rustc", &["--version"]),
        cmd("git", &["rev-parse", "--short", "HEAD"]),
        if cfg!(feature = "rapier") {
            "rapier"
        } else {
            "(none)"
        },
    )
}
