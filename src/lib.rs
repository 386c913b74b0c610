//! # ricochet
//!
//! A planar multibody simulator with event-driven rigid impacts. An ODE integrator
//! advances the generalized coordinates between impacts; parry2d finds the first contact
//! and supplies the normal; the impact law of \[P\] turns the velocity of approach into
//! impulses; [P, Eq. (16)] updates the generalized speeds; trajectories and a per-impact
//! energy ledger go to an MCAP file that Foxglove opens.
//!
//! ```text
//! scene file ──► Model (constant) ──► Simulation loop ──────────────────────► MCAP log
//!                                      │ integrate (free flight, or a contact mode)
//!                                      │ locate the first event on dense output
//!                                      │ event: impact → contact frame (parry2d)
//!                                      │        → W = J M⁻¹ Jᵀ            [P, Eq. (20)]
//!                                      │        → impact law → (I_n, I_t)
//!                                      │        → Δu = M⁻¹ Jᵀ I           [P, Eq. (16)]
//!                                      └ repeat until t_end
//! ```
//!
//! ## Conventions
//!
//! The mass matrix `M` is the usual positive definite one; the paper's is its negative
//! (`M = −M_paper`, see `paper/ERRATA.md`). Hence `Δu = M⁻¹ (J_nᵀ I_n + J_tᵀ I_t)` and
//! `W = J M⁻¹ Jᵀ` is symmetric positive definite. The contact normal `n` is oriented so
//! that the normal velocity of approach is `v_n^A = v^A·n ≤ 0`, and the tangent `t` so
//! that `v_t^A = v^A·t ≥ 0` [P, Eq. (10)].
//!
//! ## Notation
//!
//! | paper | code | meaning |
//! |---|---|---|
//! | `q`, `u` | `q`, `u` | generalized coordinates and speeds (`u = q̇`) |
//! | `M` | `mass` | positive definite mass matrix (`−M_paper`) |
//! | `m_nn, m_nt, m_tt` | `w.nn, w.nt, w.tt` | entries of `W = J M⁻¹ Jᵀ` [P, Eq. (20)] |
//! | `Δ` | `det` | `m_nn m_tt − m_nt²` [P, Eq. (24)] |
//! | `v_n^A, v_t^A` | `v_a.n, v_a.t` | velocity of approach [P, Eq. (21)] |
//! | `v_n^S, v_t^S` | `v_s.n, v_s.t` | velocity of separation [P, Eq. (21)] |
//! | `I_n, I_t` | `i_n, i_t` | normal and tangential impulses [P, Eq. (13)] |
//! | `e`, `μ` | `e`, `mu` | coefficient of restitution, Coulomb's coefficient of friction |
//! | `α` | `alpha` | `v_t^A / |v_n^A|` [P, Eq. (34)] |
//! | `g, h, p, q` | `g, h, p, q` | `μ m_tt ∓ m_nt`, `m_nn ∓ μ m_nt` [P, Eq. (35)] |
//! | `r_m, r_p` | `r_m, r_p` | `g/h`, `p/q` [P, Eq. (36)] |
//! | `ΔE` | `delta_e` | change of mechanical energy at an impact [P, Eq. (29)] |
//!
//! ## References
//!
//! - **\[P\]** H. Djerassi, *Collision with friction; Part A: Newton's hypothesis*,
//!   Multibody System Dynamics 21, 37–54 (2009). The text in `../shared/paper/` with its
//!   `ERRATA.md`.
//! - **\[KL\]** T. R. Kane, D. A. Levinson, *Dynamics: Theory and Applications*, McGraw-Hill
//!   (1985), the double pendulum of Sect. 5 of \[P\].
//! - **\[S\]** W. J. Stronge, *Impact Mechanics*, Cambridge University Press (2000): the
//!   energetic coefficient of restitution.
//! - **\[HNW\]** E. Hairer, S. P. Nørsett, G. Wanner, *Solving Ordinary Differential
//!   Equations I*, 2nd ed., Springer (1993): DOPRI5 and its dense output (II.5–6).
//! - **\[F\]** R. Featherstone, *Rigid Body Dynamics Algorithms*, Springer (2008): the
//!   composite rigid body algorithm.
#![warn(missing_docs)]
#![forbid(unsafe_code)]

pub mod articulated;
pub mod constraints;
pub mod contact;
pub mod dynamics;
pub mod events;
pub mod impact;
pub mod integrate;
pub mod kinematics;
pub mod lcp;
pub mod linalg;
pub mod log;
pub mod math;
pub mod model;
pub mod pgs;
pub mod regions;
pub mod regress;
pub mod scene;
pub mod settings;
pub mod sim;
pub mod state;
pub mod sweep;
pub mod tree_matrix;
pub mod workprec;
