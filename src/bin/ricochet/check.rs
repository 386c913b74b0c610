//! `ricochet check SCENE`: validates a scene and prints, as JSON, its coordinate names, the
//! initial `q` and `u`, the mass matrix at the initial state and the energies (see
//! `DESIGN.md`), with the contact pairs and their initial gaps and the run settings.

use std::io::Write;
use std::path::PathBuf;
use std::process::ExitCode;

use anyhow::Context;
use ricochet::contact::signed_gap;
use ricochet::dynamics::Energy;
use ricochet::dynamics::{energy, factor_mass_matrix, mass_matrix};
use ricochet::math::Real;
use ricochet::scene;
use ricochet::settings::Settings;
use ricochet::state::Data;
use serde::Serialize;

/// Options of `ricochet check`.
#[derive(clap::Args)]
pub struct Args {
    /// The scene file (TOML).
    scene: PathBuf,
}

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
    u: &'a [Real],
    mass_matrix: Vec<Vec<Real>>,
    energy: EnergyReport,
    bodies: Vec<&'a str>,
    pairs: Vec<PairReport<'a>>,
    settings: &'a Settings,
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
    let mut data = Data::new(model);

    let e = energy(model, &mut data, state.t, q, u)
        .with_context(|| format!("{}: energies at the initial state", args.scene.display()))?;
    mass_matrix(model, &mut data);
    factor_mass_matrix(&mut data, state.t)
        .with_context(|| format!("{}: mass matrix at the initial state", args.scene.display()))?;
    let mass: Vec<Vec<Real>> = (0..model.nu())
        .map(|r| (0..model.nu()).map(|c| data.mass[(r, c)]).collect())
        .collect();

    let mut pairs = Vec::new();
    for id in model.pair_ids() {
        let Some(p) = model.pair(id) else { continue };
        let gap = signed_gap(model, &data, id, Real::INFINITY)
            .with_context(|| format!("{}: contact pair #{}", args.scene.display(), id.index()))?;
        pairs.push(PairReport {
            a: &model.colliders()[p.a.index()].name,
            b: &model.colliders()[p.b.index()].name,
            law: p.material.law.name(),
            e: p.material.e,
            mu: p.material.mu,
            gap,
        });
    }

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
        u,
        mass_matrix: mass,
        energy: e.into(),
        bodies: model.bodies().iter().map(|b| b.name.as_str()).collect(),
        pairs,
        settings: &scene.settings,
    };
    let text = serde_json::to_string_pretty(&out)?;
    match writeln!(std::io::stdout().lock(), "{text}") {
        // A closed pipe (`ricochet check … | head`) is not an error of the scene.
        Err(e) if e.kind() != std::io::ErrorKind::BrokenPipe => Err(e.into()),
        _ => Ok(ExitCode::SUCCESS),
    }
}
