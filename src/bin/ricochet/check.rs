//! `ricochet check SCENE`: validates a scene and prints, as JSON, its coordinate names, the
//! initial `q` and `u` (with the speeds' names), the mass matrix at the initial state and
//! the energies (see `DESIGN.md`), with the contact pairs and their initial gaps and the
//! run settings; for a nonholonomic scene, its constraints and the kinematic equations
//! `q̇ = A u + b` at the initial state.
//!
//! Big models: the mass matrix is printed (and computed) for at most
//! [`MASS_MATRIX_MAX_SPEEDS`] speeds, and every pair with its gap for at most
//! [`PAIRS_MAX`] pairs; beyond, `mass_matrix` is absent (`omitted` says why) and `pairs`
//! lists the pairs whose bounding boxes overlap at the initial state (the broad phase),
//! with `pairs_total`. `--full` prints everything (a 4,000-link chain: 16 million numbers
//! and 8 million pairs).

use std::io::Write;
use std::path::PathBuf;
use std::process::ExitCode;

use anyhow::Context;
use ricochet::contact::broad::{collider_boxes, overlapping_pairs};
use ricochet::contact::signed_gap;
use ricochet::dynamics::Energy;
use ricochet::dynamics::{energy, factor_mass, kinematic_equations, mass_matrix};
use ricochet::math::Real;
use ricochet::model::{Model, PairId};
use ricochet::scene;
use ricochet::settings::Settings;
use ricochet::state::Data;
use serde::Serialize;

/// Options of `ricochet check`.
#[derive(clap::Args)]
pub struct Args {
    /// The scene file (TOML).
    scene: PathBuf,
    /// Print the mass matrix and every pair whatever the size of the model.
    #[arg(long)]
    full: bool,
}

/// The most speeds whose mass matrix `check` prints without `--full`.
pub const MASS_MATRIX_MAX_SPEEDS: usize = 100;
/// The most pairs `check` lists without `--full`.
pub const PAIRS_MAX: usize = 1000;

/// What `check` prints, in this order.
#[derive(Serialize)]
struct Report<'a> {
    scene: &'a str,
    file: String,
    description: &'a str,
    coordinates: Vec<&'a str>,
    units: Vec<&'static str>,
    t: Real,
    q: &'a [Real],
    /// The generalized speeds' names (the coordinates' for a holonomic model).
    speeds: Vec<&'a str>,
    speed_units: Vec<&'static str>,
    u: &'a [Real],
    /// Nonholonomic models: the constraints and the kinematic equations `q̇ = A u + b`.
    #[serde(skip_serializing_if = "Option::is_none")]
    constraints: Option<Vec<ConstraintReport<'a>>>,
    #[serde(skip_serializing_if = "Option::is_none")]
    kinematic_equations: Option<KinematicReport>,
    #[serde(skip_serializing_if = "Option::is_none")]
    mass_matrix: Option<Vec<Vec<Real>>>,
    energy: EnergyReport,
    bodies: Vec<&'a str>,
    pairs: Vec<PairReport<'a>>,
    /// The number of pairs, when `pairs` lists only some of them.
    #[serde(skip_serializing_if = "Option::is_none")]
    pairs_total: Option<usize>,
    /// What a big model's report leaves out, and why.
    #[serde(skip_serializing_if = "Vec::is_empty")]
    omitted: Vec<String>,
    settings: &'a Settings,
}

#[derive(Serialize)]
struct ConstraintReport<'a> {
    name: &'a str,
    #[serde(rename = "type")]
    kind: &'static str,
    body: &'a str,
    /// The blade's point (m, body frame).
    at: [Real; 2],
    /// The blade's direction (unit, body frame).
    direction: [Real; 2],
    /// The speed it removes.
    removes: &'a str,
}

/// `q̇ = A(q, t) u + b(q, t)` at the initial state: `a` row by row (one row per
/// coordinate, one column per speed).
#[derive(Serialize)]
struct KinematicReport {
    a: Vec<Vec<Real>>,
    b: Vec<Real>,
}

#[derive(Serialize)]
struct EnergyReport {
    kinetic: Real,
    potential: Real,
    total: Real,
}

impl From<Energy> for EnergyReport {
    fn from(e: Energy) -> Self {
        EnergyReport {
            kinetic: e.kinetic,
            potential: e.potential,
            total: e.total(),
        }
    }
}

#[derive(Serialize)]
struct PairReport<'a> {
    a: &'a str,
    b: &'a str,
    law: &'static str,
    e: Real,
    mu: Real,
    /// Signed gap at the initial state (m).
    gap: Option<Real>,
}

pub fn run(args: Args) -> anyhow::Result<ExitCode> {
    let scene = scene::load(&args.scene)?;
    let model = &scene.model;
    let state = &scene.initial;
    let (q, u) = (state.q.as_slice(), state.u.as_slice());
    // The mass matrix's storage only if it is printed.
    let mut data = Data::for_kinematics(model);

    let e = energy(model, &mut data, state.t, q, u)
        .with_context(|| format!("{}: energies at the initial state", args.scene.display()))?;
    let mut omitted = Vec::new();
    let nu = model.nu();
    let mass = if args.full || nu <= MASS_MATRIX_MAX_SPEEDS {
        factor_mass(model, &mut data, state.t).with_context(|| {
            format!("{}: mass matrix at the initial state", args.scene.display())
        })?;
        if data.mass_factor.is_articulated() {
            // Factored without forming M.
            mass_matrix(model, &mut data);
        }
        Some(
            (0..nu)
                .map(|r| (0..nu).map(|c| data.mass[(r, c)]).collect())
                .collect(),
        )
    } else {
        omitted.push(format!(
            "mass_matrix: {nu} speeds, more than {MASS_MATRIX_MAX_SPEEDS} (--full prints it)"
        ));
        None
    };

    let npairs = model.pair_count();
    let listed: Vec<PairId> = if args.full || npairs <= PAIRS_MAX {
        model.pair_ids().collect()
    } else {
        let boxes = collider_boxes(model, &data, |_| 0.0)
            .with_context(|| format!("{}: bounding boxes", args.scene.display()))?;
        omitted.push(format!(
            "pairs: {npairs} pairs, more than {PAIRS_MAX}: only those whose bounding boxes \
             overlap at the initial state (--full lists them all)"
        ));
        overlapping_pairs(model, &boxes)
    };
    let pairs = pair_reports(model, &data, &listed, &args.scene.display().to_string())?;

    let (constraints, kinematics) = if model.is_holonomic() {
        (None, None)
    } else {
        let (a, b) = kinematic_equations(model, &mut data, state.t, q).with_context(|| {
            format!(
                "{}: kinematic equations at the initial state",
                args.scene.display()
            )
        })?;
        let report = (model.constraints().iter())
            .enumerate()
            .map(|(k, c)| ConstraintReport {
                name: &c.name,
                kind: c.kind.name(),
                body: &model.bodies()[c.body.index()].name,
                at: [c.point.x, c.point.y],
                direction: [c.direction.x, c.direction.y],
                removes: &model.tree_speeds()[model.dependent_speeds()[k]].name,
            })
            .collect();
        let rows = (0..model.nq())
            .map(|r| (0..model.nu()).map(|c| a[(r, c)]).collect())
            .collect();
        (
            Some(report),
            Some(KinematicReport {
                a: rows,
                b: b.iter().copied().collect(),
            }),
        )
    };
    let coordinates = model.coordinates();
    let out = Report {
        scene: &scene.name,
        file: args.scene.display().to_string(),
        description: &scene.description,
        coordinates: coordinates.iter().map(|c| c.name.as_str()).collect(),
        units: coordinates
            .iter()
            .map(|c| if c.is_angle { "rad" } else { "m" })
            .collect(),
        t: state.t,
        q,
        speeds: model.speeds().iter().map(|s| s.name.as_str()).collect(),
        speed_units: (model.speeds().iter())
            .map(|s| if s.is_angle { "rad/s" } else { "m/s" })
            .collect(),
        u,
        constraints,
        kinematic_equations: kinematics,
        mass_matrix: mass,
        energy: e.into(),
        bodies: model.bodies().iter().map(|b| b.name.as_str()).collect(),
        pairs_total: (pairs.len() != npairs).then_some(npairs),
        pairs,
        omitted,
        settings: &scene.settings,
    };
    let text = serde_json::to_string_pretty(&out)?;
    match writeln!(std::io::stdout().lock(), "{text}") {
        // A closed pipe (`ricochet check … | head`) is not an error of the scene.
        Err(e) if e.kind() != std::io::ErrorKind::BrokenPipe => Err(e.into()),
        _ => Ok(ExitCode::SUCCESS),
    }
}

/// The pairs `ids` with their material and their gap at the positions of `data`.
fn pair_reports<'a>(
    model: &'a Model,
    data: &Data,
    ids: &[PairId],
    file: &str,
) -> anyhow::Result<Vec<PairReport<'a>>> {
    let mut pairs = Vec::with_capacity(ids.len());
    for &id in ids {
        let Some(p) = model.pair(id) else { continue };
        let gap = signed_gap(model, data, id, Real::INFINITY)
            .with_context(|| format!("{file}: contact pair #{}", id.index()))?;
        pairs.push(PairReport {
            a: &model.colliders()[p.a.index()].name,
            b: &model.colliders()[p.b.index()].name,
            law: p.material.law.name(),
            e: p.material.e,
            mu: p.material.mu,
            gap,
        });
    }
    Ok(pairs)
}
