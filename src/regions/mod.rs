//! Maps of the classification of \[P\]: for a given `W` and `e`, the collision type and the
//! sign of `ΔE` over the `(α, μ)` plane under each impact law — [P, Table 1] and
//! [P, Sect. 4.3] as pictures — with the boundaries `α = (1+e) r_m(μ)` and
//! `α = −(1+e) r_p(μ)` [P, Eq. (36)].
//!
//! Every cell is the answer of the real law ([`crate::impact::solve`]) at the velocity of
//! approach `v^A = (−1, α)` m/s: nothing of the classification is re-implemented here. The
//! laws are homogeneous of degree one in `v^A`, so the type and the sign of `ΔE` depend on
//! `α` alone; `ΔE` itself is reported per `|v_n^A|² = 1 m²/s²`.
//!
//! ## Why `α` takes both signs
//!
//! [P, Eq. (34)] defines `α ≥ 0` by orienting `t` along the slip (Eq. 10). A scene fixes
//! the tangent once (`t = perp(n)`), and the slip can go either way: `v_t^A < 0` is the
//! mirrored problem (`m_nt → −m_nt`), whose `r_m` is the original `r_p`. So the map spans
//! `α ∈ [−a, a]`: the right half is Table 1 for `W`, the left half Table 1 for the mirrored
//! `W`, and the forward-sliding boundary of the left half is `α = −(1+e) r_p` — the second
//! curve of the issue. The same curve, where it falls on the right half (`r_p < 0`, Case 3),
//! is Kane–Levinson's boundary between sticking and reverse sliding [P, Appendix C,
//! Ineqs. (74), (77)].
//!
//! ```
//! use ricochet::impact::{CollisionType, ImpactMatrix, Law};
//! use ricochet::regions::{Axis, MapSpec, RegionMap};
//!
//! // The double pendulum of [P, Sect. 5] (ERRATA item 3), e = 0.5.
//! let spec = MapSpec {
//!     w: ImpactMatrix::new(0.3365, -0.5071, 0.8134),
//!     e: 0.5,
//!     law: Law::Newton,
//!     alpha: Axis::new(-4.0, 4.0, 81),
//!     mu: Axis::new(0.0, 1.0, 11),
//! };
//! let map = RegionMap::compute(&spec)?;
//! // Table 2, lower half, row 1: α = 1.99, μ = 0.2 is reverse sliding.
//! let cell = map.cell_at(1.99, 0.2).unwrap();
//! assert_eq!(cell.kind(), Some(CollisionType::ReverseSliding));
//! # Ok::<(), ricochet::regions::RegionsError>(())
//! ```

mod draw;
mod scene;

pub use draw::{DrawError, Marker, render_svg, style, write_svg};
pub use scene::{SceneContact, pair_name, scene_contact};

use crate::impact::{
    self, CollisionType, ContactVelocity, ImpactError, ImpactMatrix, ImpactProblem, Law, SignCase,
};
use crate::math::Real;

/// Why a map cannot be computed.
#[derive(Debug, thiserror::Error)]
pub enum RegionsError {
    /// An axis is not a finite increasing range with at least two nodes.
    #[error(
        "the {axis} axis [{min}, {max}] with {n} nodes is invalid: it needs finite bounds \
         min < max{extra} and at least 2 nodes"
    )]
    InvalidAxis {
        /// `α` or `μ`.
        axis: &'static str,
        /// Lower bound.
        min: Real,
        /// Upper bound.
        max: Real,
        /// Number of nodes.
        n: usize,
        /// A further condition on the bounds (`μ ≥ 0`).
        extra: &'static str,
    },
    /// `W` or `e` cannot be given to the laws (not positive semidefinite with `m_nn > 0`,
    /// `e ∉ [0, 1]`, not finite).
    #[error("{0}")]
    Problem(ImpactError),
    /// The law failed at one point in a way that is not a jam (a bug of the law).
    #[error("{law} failed at α = {alpha}, μ = {mu}: {source}")]
    Cell {
        /// The law.
        law: Law,
        /// `α` of the point.
        alpha: Real,
        /// `μ` of the point.
        mu: Real,
        /// The law's error.
        source: ImpactError,
    },
}

/// Nodes evenly spaced over `[min, max]`, both ends included: `x_i = min + i (max − min)/(n − 1)`.
/// A map samples each law at the nodes and draws each node as the cell around it.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Axis {
    /// First node.
    pub min: Real,
    /// Last node.
    pub max: Real,
    /// Number of nodes (≥ 2).
    pub n: usize,
}

impl Axis {
    /// The axis of `n` nodes from `min` to `max` (checked by [`RegionMap::compute`]).
    pub fn new(min: Real, max: Real, n: usize) -> Self {
        Self { min, max, n }
    }

    /// The distance between two nodes.
    pub fn step(&self) -> Real {
        (self.max - self.min) / (self.n - 1) as Real
    }

    /// Node `i` (the last one is exactly `max`).
    pub fn value(&self, i: usize) -> Real {
        if i + 1 == self.n {
            self.max
        } else {
            self.min + i as Real * self.step()
        }
    }

    /// The cell of node `i`: `[x_i − step/2, x_i + step/2]` clipped to `[min, max]`.
    pub fn cell(&self, i: usize) -> (Real, Real) {
        let (x, h) = (self.value(i), 0.5 * self.step());
        ((x - h).max(self.min), (x + h).min(self.max))
    }

    /// The node nearest to `x`, or `None` outside `[min, max]`.
    pub fn nearest(&self, x: Real) -> Option<usize> {
        if !(self.min..=self.max).contains(&x) {
            return None;
        }
        let i = ((x - self.min) / self.step()).round() as usize;
        Some(i.min(self.n - 1))
    }

    fn check(&self, axis: &'static str, nonnegative: bool) -> Result<(), RegionsError> {
        let ok = self.min.is_finite()
            && self.max.is_finite()
            && self.min < self.max
            && self.n >= 2
            && (!nonnegative || self.min >= 0.0);
        if ok {
            Ok(())
        } else {
            Err(RegionsError::InvalidAxis {
                axis,
                min: self.min,
                max: self.max,
                n: self.n,
                extra: if nonnegative { ", min ≥ 0" } else { "" },
            })
        }
    }
}

/// What to map: `W`, `e`, the law, and the nodes of `α` and `μ`.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct MapSpec {
    /// `W = J M⁻¹ Jᵀ` in the contact frame [P, Eq. (20)].
    pub w: ImpactMatrix,
    /// Coefficient of restitution `e ∈ [0, 1]`.
    pub e: Real,
    /// The impact law.
    pub law: Law,
    /// Nodes of `α = v_t^A / |v_n^A|` [P, Eq. (34)]; negative for `v_t^A < 0`.
    pub alpha: Axis,
    /// Nodes of `μ ≥ 0`.
    pub mu: Axis,
}

/// The sign of `ΔE` [P, Eq. (29)] at a point.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
pub enum EnergySign {
    /// `ΔE < 0`: the impact dissipates.
    Loss,
    /// `ΔE = 0` to rounding (e.g. `e = 1`, `μ = 0`).
    Conserved,
    /// `ΔE > 0`: the calculated energy grows [P, Sect. 4.3].
    Gain,
}

/// Relative size of `ΔE`, against `|I_n| (|v_n^A| + |v_t^A|) + |I_t| (|v_n^A| + |v_t^A|)`
/// (a bound on the terms of Eq. 29), at or below which it counts as zero: the closed forms
/// are exact to rounding (~1e-15), so only a structural zero is this small.
const ENERGY_ZERO: Real = 1e-9;

/// One node of a map.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum Cell {
    /// The law's answer.
    Solved {
        /// The collision type.
        kind: CollisionType,
        /// The sign case of (g, h, p, q) [P, Table 1], in the frame with `v_t^A ≥ 0`.
        case: SignCase,
        /// `ΔE` [P, Eq. (29)] for `|v_n^A| = 1 m/s` (J).
        delta_e: Real,
        /// The sign of `ΔE`.
        energy: EnergySign,
    },
    /// `W` is singular and friction holds the approaching contact: no finite impulse
    /// ends the collision ([`ImpactError::Jam`]).
    Jam,
}

impl Cell {
    /// The collision type, `None` for a jam.
    pub fn kind(&self) -> Option<CollisionType> {
        match *self {
            Cell::Solved { kind, .. } => Some(kind),
            Cell::Jam => None,
        }
    }

    /// Whether the energy grows, `ΔE > 0`.
    pub fn gains_energy(&self) -> bool {
        matches!(
            self,
            Cell::Solved {
                energy: EnergySign::Gain,
                ..
            }
        )
    }
}

/// The class of the point `(α, μ)` under `law`: the real law solved at `v^A = (−1, α)` m/s.
pub fn classify(
    law: Law,
    w: ImpactMatrix,
    e: Real,
    alpha: Real,
    mu: Real,
) -> Result<Cell, ImpactError> {
    let v_a = ContactVelocity::new(-1.0, alpha);
    match impact::solve(law, &ImpactProblem::new(w, v_a, e, mu)) {
        Ok(out) => {
            let speed = v_a.n.abs() + v_a.t.abs();
            let scale = (out.impulse.n.abs() + out.impulse.t.abs()) * speed;
            let energy = if out.delta_e > ENERGY_ZERO * scale {
                EnergySign::Gain
            } else if out.delta_e < -ENERGY_ZERO * scale {
                EnergySign::Loss
            } else {
                EnergySign::Conserved
            };
            Ok(Cell::Solved {
                kind: out.kind,
                case: out.case,
                delta_e: out.delta_e,
                energy,
            })
        }
        Err(ImpactError::Jam { .. }) => Ok(Cell::Jam),
        Err(err) => Err(err),
    }
}

/// The classification of one law over a grid of `(α, μ)`.
#[derive(Clone, Debug, PartialEq)]
pub struct RegionMap {
    /// What was mapped.
    pub spec: MapSpec,
    /// The nodes, `μ` rows of `α` columns: node `(i, j)` at `i + j · alpha.n`.
    cells: Vec<Cell>,
}

impl RegionMap {
    /// Solves the law at every node of the grid.
    ///
    /// Errors: an invalid axis (`μ` must stay ≥ 0); `W` or `e` the laws refuse (checked
    /// once, at `α = 0`, `μ = 0`); a law failing at a node other than by a jam.
    pub fn compute(spec: &MapSpec) -> Result<Self, RegionsError> {
        spec.alpha.check("α", false)?;
        spec.mu.check("μ", true)?;
        ImpactProblem::new(spec.w, ContactVelocity::new(-1.0, 0.0), spec.e, 0.0)
            .validate()
            .map_err(RegionsError::Problem)?;
        let mut cells = Vec::with_capacity(spec.alpha.n * spec.mu.n);
        for j in 0..spec.mu.n {
            let mu = spec.mu.value(j);
            for i in 0..spec.alpha.n {
                let alpha = spec.alpha.value(i);
                let cell = classify(spec.law, spec.w, spec.e, alpha, mu).map_err(|source| {
                    RegionsError::Cell {
                        law: spec.law,
                        alpha,
                        mu,
                        source,
                    }
                })?;
                cells.push(cell);
            }
        }
        Ok(Self { spec: *spec, cells })
    }

    /// The node `i` of `α`, `j` of `μ`.
    pub fn cell(&self, i: usize, j: usize) -> Cell {
        self.cells[i + j * self.spec.alpha.n]
    }

    /// The node nearest to `(α, μ)`, `None` outside the map.
    pub fn cell_at(&self, alpha: Real, mu: Real) -> Option<Cell> {
        let i = self.spec.alpha.nearest(alpha)?;
        let j = self.spec.mu.nearest(mu)?;
        Some(self.cell(i, j))
    }

    /// Every node as `(α, μ, cell)`, row by row (increasing `μ`), each row by increasing `α`.
    pub fn nodes(&self) -> impl Iterator<Item = (Real, Real, Cell)> + '_ {
        let (a, m) = (self.spec.alpha, self.spec.mu);
        self.cells
            .iter()
            .enumerate()
            .map(move |(k, c)| (a.value(k % a.n), m.value(k / a.n), *c))
    }

    /// The two boundary curves clipped to the map ([`boundary`]): `α = (1+e) r_m(μ)`, then
    /// `α = −(1+e) r_p(μ)`, with up to `2 samples` points per piece.
    pub fn boundaries(&self, samples: usize) -> [Boundary; 2] {
        let s = &self.spec;
        [BoundaryKind::ForwardSliding, BoundaryKind::Mirrored].map(|kind| {
            boundary(
                kind,
                s.w,
                s.e,
                (s.alpha.min, s.alpha.max),
                (s.mu.min, s.mu.max),
                samples,
            )
        })
    }
}

/// Which boundary of [P, Table 1].
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
pub enum BoundaryKind {
    /// `α = (1+e) r_m(μ)`: forward sliding to the end above it (Cases 1–3), for every law
    /// on Routh's path and for Kane–Levinson [P, Table 1, Ineq. (64)].
    ForwardSliding,
    /// `α = −(1+e) r_p(μ)`: the same boundary for `v_t^A < 0` (the mirrored problem, whose
    /// `r_m` is `r_p`); on `α > 0` (`r_p < 0`), Kane–Levinson's boundary between sticking
    /// and reverse sliding [P, Appendix C, Ineqs. (74), (77)].
    Mirrored,
}

impl BoundaryKind {
    /// The curve's equation as a label.
    pub fn label(self) -> &'static str {
        match self {
            BoundaryKind::ForwardSliding => "α = (1+e) r_m(μ)",
            BoundaryKind::Mirrored => "α = −(1+e) r_p(μ)",
        }
    }
}

/// A boundary curve clipped to a window: polylines of `(α, μ)` points, increasing in `μ`,
/// broken at the pole of `r_m` (`h = 0`) or `r_p` (`q = 0`).
#[derive(Clone, Debug, PartialEq)]
pub struct Boundary {
    /// Which curve.
    pub kind: BoundaryKind,
    /// The pieces inside the window.
    pub pieces: Vec<Vec<(Real, Real)>>,
}

/// The curve `α(μ) = k (a μ + b) / (c μ + d)`, a Möbius map of `μ`: monotone on each side
/// of its pole `μ = −d/c` (`dα/dμ = k (ad − bc) / (cμ + d)²`, and `ad − bc = Δ ≥ 0`), with
/// the exact inverse `μ(α) = (k b − α d) / (α c − k a)`.
#[derive(Clone, Copy, Debug)]
struct Moebius {
    k: Real,
    a: Real,
    b: Real,
    c: Real,
    d: Real,
}

impl Moebius {
    fn alpha(&self, mu: Real) -> Real {
        self.k * (self.a * mu + self.b) / (self.c * mu + self.d)
    }

    fn mu(&self, alpha: Real) -> Real {
        (self.k * self.b - alpha * self.d) / (alpha * self.c - self.k * self.a)
    }
}

/// The boundary curve `kind` for `W` and `e`, clipped to `α ∈ alpha`, `μ ∈ mu`.
///
/// Implements [P, Eqs. (35)–(36)] and the boundaries of [P, Table 1]:
///
/// ```text
/// (1+e) r_m(μ)  = (1+e) (μ m_tt − m_nt) / (m_nn − μ m_nt)     pole where h = 0
/// −(1+e) r_p(μ) = −(1+e) (μ m_tt + m_nt) / (m_nn + μ m_nt)    pole where q = 0
/// ```
///
/// Each is monotone in `μ` on either side of its pole (`∂r_m/∂μ = Δ/h² ≥ 0`, [P, Sect. 4.2,
/// last paragraph]), so the part inside the window is one interval per side, whose ends
/// come from the exact inverse. Each piece is sampled at `samples` points evenly in `μ`
/// and `samples` points evenly in `α` (so that it stays smooth where it is steep), all on
/// the curve.
pub fn boundary(
    kind: BoundaryKind,
    w: ImpactMatrix,
    e: Real,
    alpha: (Real, Real),
    mu: (Real, Real),
    samples: usize,
) -> Boundary {
    let curve = match kind {
        BoundaryKind::ForwardSliding => Moebius {
            k: 1.0 + e,
            a: w.tt,
            b: -w.nt,
            c: -w.nt,
            d: w.nn,
        },
        BoundaryKind::Mirrored => Moebius {
            k: -(1.0 + e),
            a: w.tt,
            b: w.nt,
            c: w.nt,
            d: w.nn,
        },
    };
    let pole = -curve.d / curve.c;
    let mut branches = vec![mu];
    if pole > mu.0 && pole < mu.1 {
        branches = vec![(mu.0, pole), (pole, mu.1)];
    }
    let tol = 1e-9 * (alpha.1 - alpha.0);
    let inside = |m: Real| {
        let a = curve.alpha(m);
        m.is_finite() && m != pole && a.is_finite() && a >= alpha.0 - tol && a <= alpha.1 + tol
    };
    let mut pieces = Vec::new();
    for (lo, hi) in branches {
        let ends: Vec<Real> = [lo, hi, curve.mu(alpha.0), curve.mu(alpha.1)]
            .into_iter()
            .filter(|&m| m >= lo && m <= hi && inside(m))
            .collect();
        let (Some(m0), Some(m1)) = (
            ends.iter().copied().reduce(Real::min),
            ends.iter().copied().reduce(Real::max),
        ) else {
            continue;
        };
        if m1 <= m0 {
            continue;
        }
        let n = samples.max(2);
        let (a0, a1) = (curve.alpha(m0), curve.alpha(m1));
        let mut mus: Vec<Real> = (0..n)
            .map(|s| m0 + (m1 - m0) * s as Real / (n - 1) as Real)
            .chain((1..n - 1).map(|s| curve.mu(a0 + (a1 - a0) * s as Real / (n - 1) as Real)))
            .filter(|&m| m >= m0 && m <= m1 && inside(m))
            .collect();
        mus.sort_by(Real::total_cmp);
        mus.dedup();
        let piece = mus
            .into_iter()
            .map(|m| (curve.alpha(m).clamp(alpha.0, alpha.1), m))
            .collect();
        pieces.push(piece);
    }
    Boundary { kind, pieces }
}
