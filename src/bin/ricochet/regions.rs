//! `ricochet regions`: maps of the classification of [P] (Table 1 and Sect. 4.3 as
//! pictures): for a given `W` and `e`, the collision type and the sign of `ΔE` over the
//! `(α, μ)` plane under each law, one SVG per law.

use std::path::PathBuf;
use std::process::ExitCode;

use anyhow::{Context, bail};
use ricochet::impact::{ImpactMatrix, Law};
use ricochet::regions::{self, Axis, MapSpec, Marker, RegionMap};
use ricochet::scene;

use crate::output::tell;

/// Options of `ricochet regions`.
#[derive(clap::Args)]
#[command(group = clap::ArgGroup::new("source").required(true).args(["w", "scene"]))]
pub struct Args {
    /// W = J M⁻¹ Jᵀ as `MNN,MNT,MTT` (positive semidefinite, m_nn > 0).
    #[arg(
        long,
        value_name = "MNN,MNT,MTT",
        value_delimiter = ',',
        allow_negative_numbers = true
    )]
    w: Option<Vec<f64>>,
    /// Take W from this scene at its initial state (the pair with the smallest gap, or
    /// `--pair`); its point (α, μ) is marked if the contact approaches.
    #[arg(long, value_name = "SCENE")]
    scene: Option<PathBuf>,
    /// The contact pair of `--scene`: `a/b` (collider names) or its index from 0.
    #[arg(long, requires = "scene")]
    pair: Option<String>,
    /// Coefficient of restitution (default with `--scene`: the pair's).
    #[arg(long, allow_negative_numbers = true)]
    e: Option<f64>,
    /// The laws to map, comma-separated: newton, kane-levinson, poisson, stronge (default:
    /// all four).
    #[arg(long, value_delimiter = ',')]
    law: Vec<Law>,
    /// The map spans α ∈ [−ALPHA_MAX, ALPHA_MAX].
    #[arg(long, default_value_t = 4.0, allow_negative_numbers = true)]
    alpha_max: f64,
    /// The map spans μ ∈ [0, MU_MAX].
    #[arg(long, default_value_t = 1.0, allow_negative_numbers = true)]
    mu_max: f64,
    /// Nodes along each axis (each node is one cell of the picture).
    #[arg(long, default_value_t = 201)]
    resolution: usize,
    /// The folder the SVG files go to (created if missing).
    #[arg(short = 'o', long = "out-dir", value_name = "DIR", default_value = ".")]
    out_dir: PathBuf,
}

/// Largest number of nodes along an axis: beyond it the SVG grows to many megabytes
/// without showing more.
const MAX_RESOLUTION: usize = 2001;

pub fn run(args: Args) -> anyhow::Result<ExitCode> {
    if !(2..=MAX_RESOLUTION).contains(&args.resolution) {
        bail!(
            "--resolution {} is outside [2, {MAX_RESOLUTION}]",
            args.resolution
        );
    }
    if !(args.alpha_max.is_finite() && args.alpha_max > 0.0) {
        bail!("--alpha-max {} must be positive and finite", args.alpha_max);
    }
    if !(args.mu_max.is_finite() && args.mu_max > 0.0) {
        bail!("--mu-max {} must be positive and finite", args.mu_max);
    }
    let (stem, w, e, markers) = source(&args)?;
    let laws = if args.law.is_empty() {
        Law::ALL.to_vec()
    } else {
        args.law.clone()
    };
    std::fs::create_dir_all(&args.out_dir)
        .with_context(|| format!("cannot create {}", args.out_dir.display()))?;
    for law in laws {
        let spec = MapSpec {
            w,
            e,
            law,
            alpha: Axis::new(-args.alpha_max, args.alpha_max, args.resolution),
            mu: Axis::new(0.0, args.mu_max, args.resolution),
        };
        let map = RegionMap::compute(&spec)?;
        let path = args.out_dir.join(format!("{stem}_{law}.svg"));
        regions::write_svg(&path, &map, &markers)?;
        crate::output::print(&format!("{}\n", path.display()))?;
    }
    Ok(ExitCode::SUCCESS)
}

/// The file stem, `W`, `e` and the markers, from `--w` or `--scene`.
fn source(args: &Args) -> anyhow::Result<(String, ImpactMatrix, f64, Vec<Marker>)> {
    if let Some(w) = &args.w {
        let [nn, nt, tt] = w[..] else {
            bail!("--w takes three numbers MNN,MNT,MTT, got {}", w.len());
        };
        let Some(e) = args.e else {
            bail!("--e is required with --w");
        };
        return Ok((
            "regions".to_owned(),
            ImpactMatrix::new(nn, nt, tt),
            e,
            Vec::new(),
        ));
    }
    let Some(path) = &args.scene else {
        bail!("give --w MNN,MNT,MTT or --scene SCENE");
    };
    let scene = scene::load(path)?;
    let c = regions::scene_contact(&scene.model, &scene.initial, args.pair.as_deref())
        .with_context(|| format!("{}: the contact at the initial state", path.display()))?;
    let e = args.e.unwrap_or(c.material.e);
    tell!(
        "{}: pair {} (gap {:.3e} m), W = [{}, {}, {}], v = ({}, {}) m/s, e = {e}, μ = {}",
        scene.name,
        c.name,
        c.gap,
        c.w.nn,
        c.w.nt,
        c.w.tt,
        c.v.n,
        c.v.t,
        c.material.mu
    );
    let markers = match c.alpha() {
        Some(alpha) => vec![Marker {
            label: format!("{}: α = {alpha:.4}, μ = {}", scene.name, c.material.mu),
            alpha,
            mu: c.material.mu,
        }],
        None => Vec::new(),
    };
    Ok((scene.name.clone(), c.w, e, markers))
}
