//! The Moreau–Jean time-stepping scheme [AB, ch. 10; J; M]: a fixed step `h`, the
//! contacts solved at the velocity level in every step with Newton's restitution and
//! Coulomb friction. Unlike the event-driven [`super::Simulation`] it never locates an
//! impact: impacts, accumulations of impacts and resting contacts are all the same
//! velocity jump, so it survives accumulations and many contacts, at first order.
//!
//! One step from `(t_k, q_k, u_k)`, with `θ ∈ [½, 1]`:
//!
//! ```text
//! θ-point     t_θ = t_k + θh,   q_θ = q_k + θh u_k
//! free        u_free = u_k + h M(q_θ)⁻¹ (τ − h)(t_θ, q_θ, u_k)
//! index set   I = { i : g_i(q_θ) ≤ 0 }                   (contact frames at q_θ)
//! Delassus    W = J M(q_θ)⁻¹ Jᵀ, all of I together (2m × 2m), J = (J_n; J_t) at q_θ
//! solve       v⁺ = v_free + W P,   v = J u + v_rem
//!             0 ≤ v_n⁺ + e v_nᵏ ⊥ P_n ≥ 0               (Newton's restitution)
//!             |P_t| ≤ μ P_n,  v_t⁺ ≠ 0 ⇒ P_t = −μ P_n sign(v_t⁺)   (Coulomb)
//! impulses    u_{k+1} = u_free + M⁻¹ Jᵀ P
//! positions   q_{k+1} = q_k + h ((1 − θ) u_k + θ u_{k+1})
//! ```
//!
//! Choices (documented here, as the brief of issue 5 asks):
//!
//! - **θ = ½ by default** ([`MoreauJeanSettings::theta`]): with the evaluation point below
//!   this is Moreau's midpoint rule [M; St]. With a constant mass matrix and a constant
//!   force `f` (a free body under gravity), one step satisfies exactly
//!   `E_{k+1} − E_k = Σ_i ½ P_i·(v_iᵏ + v_i^{k+1}) − (θ − ½) h fᵀ(u_{k+1} − u_k)`:
//!   the work of the contact impulses, plus a term that vanishes for θ = ½ and telescopes
//!   otherwise (`tests/all/moreau_jean.rs` checks both).
//! - **Where things are evaluated**: everything at one point, the θ-point
//!   `(t_θ, q_θ) = (t_k + θh, q_k + θh u_k)`: the mass matrix and its Cholesky factor, the
//!   forces `τ − h` (with the speeds `u_k`: explicit in `u`), the gaps, the contact frames
//!   and `J_n`, `J_t`. The scheme is linearly implicit in nothing: one forward dynamics per
//!   step, no Newton iteration (Siconos' `MoreauJeanOSI` with a single iteration is the
//!   same up to where it evaluates `M` and the forces). A step allocates nothing but the
//!   exact enumeration's scratch ([`crate::lcp::solve`]) and the ledger entries.
//! - **Index set**: `g_i(q_θ) ≤ 0`, the gap at the θ-point itself; for θ = ½ it is the
//!   exact version of Siconos' prediction `g_i(q_k) + (h/2) ġ_i(q_k, u_k) ≤ 0` (γ = ½).
//!   A contact closes while the positions overshoot by at most `θh|v_n|`: the
//!   interpenetration is `O(h v)` and never corrected (no projection).
//! - **Contacts**: every contact point of every pair ([`crate::contact::contact_points`]:
//!   the closest one, and the other ends of a flat feature lying on the other shape), so
//!   that a rod lying flat or a block on its face rests on two points.
//! - **Solver**: the exact enumeration of [`crate::lcp`] up to
//!   [`MoreauJeanSettings::exact_up_to`] contacts (2 by default; the first solution when
//!   there are several, with a warning when they differ in velocity), the nonsmooth
//!   Gauss–Seidel of [`crate::pgs`] beyond and when the enumeration finds no solution;
//!   when Gauss–Seidel stops unconverged on at most
//!   [`MoreauJeanSettings::rescue_up_to`] contacts (4), the enumeration again; else the
//!   step uses Gauss–Seidel's last iterate, with a warning.
//! - **Ledger**: a contact of the index set whose approach speed before the step exceeds
//!   [`MoreauJean::impact_speed`], `v_imp = 5 a h` with `a` the scene's acceleration scale
//!   (`|g|`, or `v_ref²/L` without gravity, as in [`super::Scales`]), is an impact: it
//!   gets an [`ImpactEvent`]. `5 a h` is the speed of a hop that lasts ten steps
//!   (`2v/a = 10h`): a resting contact approaches at most at `a h` (one step of free
//!   fall), so resting and slowly rocking contacts are not impacts, while every hop the
//!   step resolves is. The entry: `t = t_θ`; the frame at `q_θ`; the contact's 2×2 block
//!   of `W`; `v^A = vᵏ` and `v^S = v^{k+1}`; the law reported as Newton; the type from the
//!   final slip (`|v_t^{k+1}|` within the solver's tolerance: sticking; else its sign
//!   against `v_tᵏ ≥ 0`); ΔE by Eq. (29) and the works of the straight path
//!   ([`Phases::straight`]); `Δu = M⁻¹ J_iᵀ P_i` (this contact's share); the energies at the
//!   start and end of the step (the step's energy change, which the impulse dominates).
//! - **Energy audit**: `impact_delta_e` is Σ over every step and every contact of the
//!   index set (impacts and resting contacts alike) of Eq. (29) with `v^A = vᵏ`,
//!   `v^S = v^{k+1}`; `impact_prescribed_work` is Σ `−P·v_rem` (the first terms of
//!   Eq. (28); its `Σ m v_t·Δv` term is left in the drift); the works of dampers, efforts
//!   and drives are midpoint quadratures `h · power(t_θ, q_θ, ū)` with
//!   `ū = (1 − θ) u_k + θ u_{k+1}` (one more forward dynamics per step, only for models
//!   that have such elements). The drift is whatever the scheme does not conserve.
//! - **Samples** at the output rate are *interpolated* linearly between the step states:
//!   `q(t)` is then exactly the scheme's own piecewise-linear path
//!   (`q_{k+1} − q_k = h ū`), `u(t)` the linear interpolant; the contact modes are those
//!   of the step that holds the sample (free, sliding, sticking, or impact if the step has
//!   a ledger entry on that pair). There are no extra samples at impacts.
//! - **Counters**: `steps` the time steps, `rhs_evals` the forward-dynamics evaluations,
//!   `events` the times a pair entered the index set, `impacts` the ledger entries,
//!   `rejected` 0.
//!
//! References:
//! - **\[AB\]** V. Acary, B. Brogliato, *Numerical Methods for Nonsmooth Dynamical Systems:
//!   Applications in Mechanics and Electronics*, Lecture Notes in Applied and
//!   Computational Mechanics 35, Springer (2008), ch. 10 (the Moreau–Jean scheme).
//! - **\[J\]** M. Jean, *The non-smooth contact dynamics method*, Comput. Methods Appl.
//!   Mech. Engrg. 177 (1999) 235–257.
//! - **[M]** J. J. Moreau, *Unilateral contact and dry friction in finite freedom
//!   dynamics*, in *Nonsmooth Mechanics and Applications*, CISM 302, Springer (1988).
//! - **[St]** C. Studer, *Numerics of Unilateral Contacts and Friction*, Lecture Notes in
//!   Applied and Computational Mechanics 47, Springer (2009).

mod contacts;

use std::sync::atomic::{AtomicBool, Ordering};

use super::{PairMap, PairMode};
use crate::dynamics::{
    Energy, coordinate_rates, energy, forward_dynamics, forward_dynamics_with, power,
};
use crate::impact::{
    Coefficients, CollisionType, ContactVelocity, Law, Outcome, Phases, energy_change,
};
use crate::kinematics::forward_kinematics;
use crate::math::Real;
use crate::model::{Model, PairId};
use crate::pgs::{PgsSettings, PgsStatus};
use crate::settings::Settings;
use crate::state::{Data, State};

use super::{
    AtTime, EnergyAudit, ImpactCause, ImpactEvent, Level, MaterialOverride, Observer, RunCounters,
    RunSummary, Sample, Scales, SimError, StopReason,
};
use contacts::{ContactProblem, Solved};

/// Settings of the scheme beyond the run's (`dt` is the step).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct MoreauJeanSettings {
    /// θ ∈ [½, 1]: where the forces, the mass matrix and the contacts are evaluated
    /// (`t_k + θh`, `q_k + θh u_k`) and the weight of `u_{k+1}` in the positions. ½
    /// (Moreau's midpoint rule) by default; 1 is the fully implicit velocity of \[J\].
    pub theta: Real,
    /// The exact enumeration of [`crate::lcp`] solves steps with at most this many contacts
    /// in the index set (it tries up to `4^m` mode combinations); nonsmooth Gauss–Seidel
    /// the others. 0: always Gauss–Seidel.
    pub exact_up_to: usize,
    /// When Gauss–Seidel stops unconverged on at most this many contacts, the exact
    /// enumeration solves the step instead (if it finds a solution).
    pub rescue_up_to: usize,
    /// Settings of the nonsmooth Gauss–Seidel.
    pub pgs: PgsSettings,
}

impl Default for MoreauJeanSettings {
    fn default() -> Self {
        Self {
            theta: 0.5,
            exact_up_to: 2,
            rescue_up_to: 4,
            pgs: PgsSettings::default(),
        }
    }
}

/// How the contact problems of a run were solved.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct SolverReport {
    /// Steps solved by the exact enumeration.
    pub exact_steps: u64,
    /// Steps solved by Gauss–Seidel.
    pub pgs_steps: u64,
    /// Steps whose enumeration found several solutions differing in velocity (the first
    /// was used).
    pub ambiguous: u64,
    /// Steps whose enumeration found no solution (Gauss–Seidel was used).
    pub no_exact_solution: u64,
    /// Steps whose Gauss–Seidel stopped unconverged and the enumeration solved.
    pub rescued: u64,
    /// Steps whose Gauss–Seidel stopped unconverged, unrescued (its last iterate was
    /// used).
    pub unconverged: u64,
}

/// The state at both ends of the current step.
struct StepStates {
    /// `t_k` (s).
    t: Real,
    /// `q_k` (nq).
    q: Vec<Real>,
    /// `u_k` (nu).
    u: Vec<Real>,
    /// `t_{k+1}` (s).
    t_next: Real,
    /// `q_{k+1}` (nq).
    q_next: Vec<Real>,
    /// `u_{k+1}` (nu).
    u_next: Vec<Real>,
}

/// A Moreau–Jean run of one model with its settings; [`MoreauJean::run`] runs it with the
/// contracts of [`super::Simulation::run`] (samples, ledger, messages, stop reasons,
/// energy audit, counters).
///
/// ```
/// # use ricochet::sim::{MaterialOverride, MoreauJean, NullObserver, StopReason};
/// let mut scene = ricochet::scene::load(concat!(
///     env!("CARGO_MANIFEST_DIR"),
///     "/scenes/bouncing_ball.toml"
/// ))?;
/// scene.settings.integrator.dt = 1e-3;
/// let mut mj = MoreauJean::new(&scene.model, &scene.settings, MaterialOverride::default())?;
/// let summary = mj.run(&scene.initial, &mut NullObserver, None);
/// assert!(matches!(summary.stop, StopReason::EndTime));
/// // After the accumulation (t∞ = 4.06 s) the ball rests on the floor.
/// assert!(summary.state.u[0].abs() < 1e-12);
/// # Ok::<(), Box<dyn std::error::Error>>(())
/// ```
pub struct MoreauJean<'m> {
    model: &'m Model,
    settings: Settings,
    mj: MoreauJeanSettings,
    overrides: MaterialOverride,
    scales: Scales,
    /// The ledger threshold `v_imp` (m/s).
    v_impact: Real,
    /// Whether the model has dampers, efforts or drives (works to integrate).
    works: bool,
    /// Dynamics at the θ-point.
    data: Data,
    /// Scratch for samples, energies and works.
    sampler: Data,
    contacts: ContactProblem,
    states: StepStates,
    /// `q_θ` (nq).
    q_m: Vec<Real>,
    /// `u_free`, then `ū` for the works (nu).
    scratch_u: Vec<Real>,
    /// Scratch for an interpolated sample (nq, nu).
    sample_q: Vec<Real>,
    sample_u: Vec<Real>,
    /// The pairs a sample lists (see `sim::broad::listed_pairs`), their gaps, modes and
    /// slips, and every pair when the model has few.
    listed: Vec<PairId>,
    all_pairs: Option<Vec<PairId>>,
    gap_values: Vec<Real>,
    listed_modes: Vec<PairMode>,
    listed_slips: Vec<i8>,
    boxes: Vec<parry2d_f64::bounding_volume::Aabb>,
    /// The regions of the half-spaces among them.
    planes: Vec<super::broad::Plane>,
    /// Their hierarchy, kept between samples.
    finder: crate::contact::broad::PairFinder,
    /// The mode of each pair in the current step.
    modes: PairMap<PairMode>,
    /// Steps taken; the run has `n_steps`.
    k: u64,
    n_steps: u64,
    t0: Real,
    next_output: u64,
    last_sample_t: Option<Real>,
    audit: EnergyAudit,
    counters: RunCounters,
    report: SolverReport,
}

impl<'m> MoreauJean<'m> {
    /// A run of `model` with `settings` (its step is `settings.integrator.dt`), the
    /// material overrides, and the default [`MoreauJeanSettings`] (θ = ½).
    pub fn new(
        model: &'m Model,
        settings: &Settings,
        overrides: MaterialOverride,
    ) -> Result<Self, SimError> {
        Self::with_settings(model, settings, overrides, MoreauJeanSettings::default())
    }

    /// A run with explicit scheme settings. Errors: `dt` not finite and positive, θ outside
    /// [½, 1], an override out of range.
    pub fn with_settings(
        model: &'m Model,
        settings: &Settings,
        overrides: MaterialOverride,
        mj: MoreauJeanSettings,
    ) -> Result<Self, SimError> {
        overrides.validate()?;
        let dt = settings.integrator.dt;
        if !(dt.is_finite() && dt > 0.0) {
            return Err(SimError::Settings(crate::integrate::SettingsError {
                field: "dt",
                value: dt,
                reason: "the step of Moreau–Jean must be finite and > 0",
            }));
        }
        if !(0.5..=1.0).contains(&mj.theta) {
            return Err(SimError::Settings(crate::integrate::SettingsError {
                field: "theta",
                value: mj.theta,
                reason: "the θ of Moreau–Jean must lie in [0.5, 1]",
            }));
        }
        let (nq, nu) = (model.nq(), model.nu());
        let scales = Scales::of(model, &settings.integrator);
        let g = model.gravity().length();
        let accel = if g > 0.0 {
            g
        } else {
            scales.speed * scales.speed / scales.length
        };
        let works = model.has_prescribed_motion()
            || (model.joints().iter()).any(|j| j.force.damping != 0.0 || j.force.effort != 0.0);
        Ok(Self {
            model,
            settings: settings.clone(),
            mj,
            overrides,
            scales,
            v_impact: 5.0 * accel * dt,
            works,
            data: Data::new(model),
            sampler: Data::new(model),
            contacts: ContactProblem::new(model, (mj.exact_up_to, mj.rescue_up_to), mj.pgs),
            states: StepStates {
                t: 0.0,
                q: vec![0.0; nq],
                u: vec![0.0; nu],
                t_next: 0.0,
                q_next: vec![0.0; nq],
                u_next: vec![0.0; nu],
            },
            q_m: vec![0.0; nq],
            scratch_u: vec![0.0; nu],
            sample_q: vec![0.0; nq],
            sample_u: vec![0.0; nu],
            listed: Vec::new(),
            all_pairs: super::broad::all_pairs_if_few(model),
            gap_values: Vec::new(),
            listed_modes: Vec::new(),
            listed_slips: Vec::new(),
            boxes: Vec::new(),
            planes: Vec::new(),
            finder: Default::default(),
            modes: PairMap::new(PairMode::Free),
            k: 0,
            n_steps: 0,
            t0: 0.0,
            next_output: 0,
            last_sample_t: None,
            audit: EnergyAudit::default(),
            counters: RunCounters::default(),
            report: SolverReport::default(),
        })
    }

    /// The scales of the scene (its `gap_tol` is what the log draws as a closed contact).
    pub fn scales(&self) -> Scales {
        self.scales
    }

    /// The ledger threshold `v_imp = 5 a h` (m/s): a contact approaching faster at the
    /// start of a step is an impact (see the module doc).
    pub fn impact_speed(&self) -> Real {
        self.v_impact
    }

    /// How the contact problems of the last run were solved.
    pub fn solver_report(&self) -> SolverReport {
        self.report
    }

    /// Runs from `initial` to the end time with steps `dt` (the last one shortened to land
    /// on the end time), reporting to `observer`; stops early when `interrupt` becomes
    /// true. Always returns a summary: a failure is a stop reason. The run never stops at
    /// an accumulation: the scheme goes through it.
    pub fn run(
        &mut self,
        initial: &State,
        observer: &mut dyn Observer,
        interrupt: Option<&AtomicBool>,
    ) -> RunSummary {
        let stop = match self.run_stages(initial, observer, interrupt) {
            Ok(stop) => stop,
            Err(e) => StopReason::Failed(e),
        };
        self.finish(stop, observer)
    }

    /// The loop, as named stages.
    fn run_stages(
        &mut self,
        initial: &State,
        observer: &mut dyn Observer,
        interrupt: Option<&AtomicBool>,
    ) -> Result<StopReason, SimError> {
        self.start(initial, observer)?;
        loop {
            let t = self.states.t;
            if interrupt.is_some_and(|flag| flag.load(Ordering::Relaxed)) {
                return Ok(StopReason::Interrupted { t });
            }
            if self.k >= self.n_steps {
                return Ok(StopReason::EndTime);
            }
            self.step(observer)?; // one time step, its ledger and audit
            self.samples_in_step(observer)?; // the output times it passed
            self.advance(); // (t, q, u)_{k+1} becomes the current state
        }
    }

    /// Stage `start`: the state, the step grid, the initial energy and sample.
    fn start(&mut self, initial: &State, observer: &mut dyn Observer) -> Result<(), SimError> {
        let (nq, nu) = (self.model.nq(), self.model.nu());
        if initial.q.len() != nq || initial.u.len() != nu {
            return Err(SimError::InitialState {
                expected_q: nq,
                expected_u: nu,
                got_q: initial.q.len(),
                got_u: initial.u.len(),
            });
        }
        let t0 = initial.t;
        self.t0 = t0;
        self.states.t = t0;
        self.states.q.copy_from_slice(initial.q.as_slice());
        self.states.u.copy_from_slice(initial.u.as_slice());
        let span = (self.settings.t_end - t0) / self.settings.integrator.dt;
        // Steps of dt; a last fraction shorter than 1e-9 dt is merged into the last step.
        self.n_steps = if span > 0.0 {
            ((span - 1e-9).ceil().max(1.0)) as u64
        } else {
            0
        };
        self.k = 0;
        self.audit = EnergyAudit::default();
        self.counters = RunCounters::default();
        self.report = SolverReport::default();
        self.contacts.reset();
        self.modes.fill(PairMode::Free);
        self.last_sample_t = None;
        self.audit.initial = energy(
            self.model,
            &mut self.sampler,
            t0,
            initial.q.as_slice(),
            initial.u.as_slice(),
        )
        .map_err(|e| SimError::at(t0, e))?;
        let text = format!(
            "Moreau–Jean time-stepping: h = {:e} s, θ = {}, impacts above {:.3e} m/s in the \
             ledger",
            self.settings.integrator.dt, self.mj.theta, self.v_impact
        );
        observer
            .message(t0, Level::Info, &text)
            .map_err(|e| SimError::at(t0, e))?;
        self.warn_about_laws(t0, observer)?;
        let rate = self.settings.output_rate;
        self.next_output = if rate > 0.0 {
            (t0 * rate).ceil() as u64
        } else {
            u64::MAX
        };
        let (q, u) = (
            std::mem::take(&mut self.sample_q),
            std::mem::take(&mut self.sample_u),
        );
        let (mut q, mut u) = (q, u);
        q.copy_from_slice(&self.states.q);
        u.copy_from_slice(&self.states.u);
        let result = self.sample(t0, &q, &u, observer);
        (self.sample_q, self.sample_u) = (q, u);
        result?;
        if rate > 0.0 && self.next_output as Real / rate <= t0 {
            self.next_output += 1;
        }
        Ok(())
    }

    /// A warning for every pair whose law is not Newton's: the scheme applies Newton's
    /// restitution at the velocity level whatever the scene says.
    fn warn_about_laws(&mut self, t0: Real, observer: &mut dyn Observer) -> Result<(), SimError> {
        for id in self.model.pair_ids() {
            let law = self.overrides.apply(self.model.pair_of(id).material).law;
            if law != Law::Newton {
                let text = format!(
                    "pair {}: Moreau–Jean applies Newton's restitution at the velocity level; \
                     the law {law} is not used",
                    super::impact_map::pair_name(self.model, id)
                );
                observer
                    .message(t0, Level::Warning, &text)
                    .map_err(|e| SimError::at(t0, e))?;
            }
        }
        Ok(())
    }

    /// The end of step `k` (s): `t0 + (k + 1) dt`, the end time for the last step.
    fn step_end(&self) -> Real {
        if self.k + 1 >= self.n_steps {
            self.settings.t_end
        } else {
            self.t0 + (self.k + 1) as Real * self.settings.integrator.dt
        }
    }

    /// Stage `step`: one Moreau–Jean step from `(t_k, q_k, u_k)` to `(t_{k+1}, …)`.
    fn step(&mut self, observer: &mut dyn Observer) -> Result<(), SimError> {
        let t = self.states.t;
        let t_next = self.step_end();
        let h = t_next - t;
        let theta = self.mj.theta;
        let t_m = t + theta * h;
        // θ-point and free velocity: u_free = u_k + h M(q_θ)⁻¹ (τ − h)(t_θ, q_θ, u_k).
        if self.model.is_holonomic() {
            for ((qm, q), u) in self.q_m.iter_mut().zip(&self.states.q).zip(&self.states.u) {
                *qm = q + theta * h * u;
            }
        } else {
            // q_θ = q_k + θ h (A u_k + b)(t_k, q_k).
            let (q, u) = (&self.states.q, &self.states.u);
            forward_kinematics(self.model, &mut self.data, t, q, u).map_err(|e| e.at(t))?;
            coordinate_rates(self.model, &self.data, u, &mut self.q_m);
            for (qm, q) in self.q_m.iter_mut().zip(q) {
                *qm = q + theta * h * *qm;
            }
        }
        forward_dynamics(self.model, &mut self.data, t_m, &self.q_m, &self.states.u)
            .map_err(|e| SimError::at(t_m, e))?;
        self.counters.rhs_evals += 1;
        for ((uf, u), a) in (self.scratch_u.iter_mut())
            .zip(&self.states.u)
            .zip(self.data.udot.iter())
        {
            *uf = u + h * a;
        }
        // Index set, Delassus matrix, contact problem.
        self.counters.events +=
            self.contacts
                .index_set(self.model, &self.data, &self.overrides, t_m)?;
        self.contacts
            .assemble(&mut self.data, &self.scratch_u, t_m)?;
        let solved = self.contacts.solve();
        self.note_solver(t_m, solved, observer)?;
        // Impulses and positions: u_{k+1} = u_free + M⁻¹ Jᵀ P,
        // q_{k+1} = q_k + h ((1 − θ) u_k + θ u_{k+1}).
        self.states.u_next.copy_from_slice(&self.scratch_u);
        self.contacts.apply(&mut self.states.u_next);
        let s = &mut self.states;
        if self.model.is_holonomic() {
            for (((qn, q), u), un) in (s.q_next.iter_mut()).zip(&s.q).zip(&s.u).zip(&s.u_next) {
                *qn = q + h * ((1.0 - theta) * u + theta * un);
            }
        } else {
            // q_{k+1} = q_k + h (A ū + b)(t_θ, q_θ), ū = (1 − θ) u_k + θ u_{k+1}.
            for ((ub, u), un) in self.scratch_u.iter_mut().zip(&s.u).zip(&s.u_next) {
                *ub = (1.0 - theta) * u + theta * un;
            }
            forward_kinematics(
                self.model,
                &mut self.sampler,
                t_m,
                &self.q_m,
                &self.scratch_u,
            )
            .map_err(|e| e.at(t_m))?;
            coordinate_rates(self.model, &self.sampler, &self.scratch_u, &mut s.q_next);
            for (qn, q) in s.q_next.iter_mut().zip(&s.q) {
                *qn = q + h * *qn;
            }
        }
        s.t_next = t_next;
        self.contacts.end_velocities(&self.states.u_next);
        // Bookkeeping: audit, modes, ledger.
        self.audit_step(t_m, h)?;
        self.ledger(t_m, observer)?;
        self.counters.steps += 1;
        Ok(())
    }

    /// Records how the contact problem was solved, with a warning the first time it was
    /// not solved cleanly.
    fn note_solver(
        &mut self,
        t: Real,
        solved: Solved,
        observer: &mut dyn Observer,
    ) -> Result<(), SimError> {
        let r = &mut self.report;
        let warning = match solved {
            Solved::Nothing => None,
            Solved::Exact { ambiguous, rescue } => {
                r.exact_steps += 1;
                r.rescued += u64::from(rescue);
                r.ambiguous += u64::from(ambiguous);
                (ambiguous && r.ambiguous == 1).then(|| {
                    "the contact problem has several solutions with different velocities; \
                     the first (open before stick before slide) is used (reported once)"
                        .to_owned()
                })
            }
            Solved::Pgs { status, no_exact } => {
                r.pgs_steps += 1;
                r.no_exact_solution += u64::from(no_exact);
                let first_no_exact = no_exact && r.no_exact_solution == 1;
                match status {
                    PgsStatus::NonFinite => {
                        return Err(SimError::Contact {
                            t,
                            message: "the contact problem is not finite".to_owned(),
                        });
                    }
                    PgsStatus::MaxIterations {
                        iterations,
                        residual,
                    } => {
                        r.unconverged += 1;
                        (r.unconverged == 1).then(|| {
                            format!(
                                "Gauss–Seidel stopped unconverged after {iterations} sweeps \
                                 (residual {residual:.1e}); the step uses its last iterate \
                                 (reported once)"
                            )
                        })
                    }
                    PgsStatus::Converged { .. } => first_no_exact.then(|| {
                        "the exact enumeration found no solution; Gauss–Seidel solved the \
                         step (reported once)"
                            .to_owned()
                    }),
                }
            }
        };
        if let Some(text) = warning {
            observer
                .message(t, Level::Warning, &text)
                .map_err(|e| SimError::at(t, e))?;
        }
        Ok(())
    }

    /// Stage `audit`: the energy of the contact impulses (Eq. 29 with `vᵏ`, `v^{k+1}`) —
    /// of the impacts (the ledger's, approaching faster than `v_imp`) on the impacts' line,
    /// of the resting and sliding contacts on the contact forces' line —, the Eq. (28)
    /// terms, and the works of dampers, efforts and drives (midpoint quadrature).
    fn audit_step(&mut self, t_m: Real, h: Real) -> Result<(), SimError> {
        for c in &self.contacts.active {
            let delta_e = energy_change(c.impulse, c.v_k, c.v_next);
            if c.impulse.n > 0.0 && c.v_k.n < -self.v_impact {
                self.audit.impact_delta_e += delta_e;
            } else {
                self.audit.contact_work += delta_e;
            }
            let rem = c.frame.v_rem;
            self.audit.impact_prescribed_work -=
                c.impulse.n * rem.dot(c.frame.n) + c.impulse.t * rem.dot(c.frame.t);
        }
        if self.works {
            let theta = self.mj.theta;
            let s = &self.states;
            for ((ub, u), un) in self.scratch_u.iter_mut().zip(&s.u).zip(&s.u_next) {
                *ub = (1.0 - theta) * u + theta * un;
            }
            forward_dynamics_with(
                self.model,
                &mut self.sampler,
                t_m,
                &self.q_m,
                &self.scratch_u,
                None,
            )
            .map_err(|e| SimError::at(t_m, e))?;
            self.counters.rhs_evals += 1;
            let p = power(self.model, &mut self.sampler);
            self.audit.damping_work += h * p.damping;
            self.audit.applied_work += h * p.applied;
            self.audit.drive_work += h * p.drives;
        }
        Ok(())
    }

    /// Stage `ledger`: the modes of the pairs in this step, and an [`ImpactEvent`] for every
    /// contact that approached faster than `v_imp`.
    fn ledger(&mut self, t_m: Real, observer: &mut dyn Observer) -> Result<(), SimError> {
        self.modes.fill(PairMode::Free);
        let slip_tol = 1e-8 * self.contacts.velocity_scale() + self.scales.v_tiny;
        let mut energies: Option<(Energy, Energy)> = None;
        for i in 0..self.contacts.active.len() {
            let c = self.contacts.active[i];
            if c.impulse.n <= 0.0 {
                continue;
            }
            let kind = if c.v_next.t.abs() <= slip_tol {
                CollisionType::Sticking
            } else if c.v_next.t > 0.0 {
                CollisionType::ForwardSliding
            } else {
                CollisionType::ReverseSliding
            };
            let impact = c.v_k.n < -self.v_impact;
            let mode = match kind {
                _ if impact => PairMode::Impact,
                CollisionType::Sticking => PairMode::Sticking,
                _ => PairMode::Sliding,
            };
            // A pair's mode is its most constrained point's.
            let pair_mode = &mut self.modes[c.pair.index()];
            *pair_mode = (*pair_mode).max(mode);
            if !impact {
                continue;
            }
            let (before, after) = match energies {
                Some(e) => e,
                None => *energies.insert(self.step_energies()?),
            };
            let w = self.contacts.block(i);
            let coefficients = Coefficients::new(&w, c.material.mu, c.v_k);
            let phases = Phases::straight(c.v_k, kind, c.impulse, c.v_next);
            let end = *phases.end();
            let outcome = Outcome {
                law: Law::Newton,
                kind,
                case: coefficients.sign_case(),
                coefficients,
                impulse: c.impulse,
                v_s: c.v_next,
                phases,
                delta_e: energy_change(c.impulse, c.v_k, c.v_next),
                work_n: end.work_n,
                work_t: end.work_t,
                mirrored: false,
            };
            let event = ImpactEvent {
                index: self.counters.impacts,
                cause: if self.contacts.active.len() == 1 {
                    ImpactCause::Collision
                } else {
                    ImpactCause::Simultaneous
                },
                t: t_m,
                frame: c.frame,
                material: c.material,
                w,
                v_a: ContactVelocity::new(c.v_k.n, c.v_k.t),
                outcome,
                delta_u: self.contacts.delta_u(i),
                energy_before: before,
                energy_after: after,
                support: None,
            };
            self.counters.impacts += 1;
            observer
                .impact(self.model, &event)
                .map_err(|e| SimError::at(t_m, e))?;
        }
        Ok(())
    }

    /// The energies at the start and at the end of the current step.
    fn step_energies(&mut self) -> Result<(Energy, Energy), SimError> {
        let s = &self.states;
        let before = energy(self.model, &mut self.sampler, s.t, &s.q, &s.u)
            .map_err(|e| SimError::at(s.t, e))?;
        let after = energy(
            self.model,
            &mut self.sampler,
            s.t_next,
            &s.q_next,
            &s.u_next,
        )
        .map_err(|e| SimError::at(s.t_next, e))?;
        Ok((before, after))
    }

    /// Stage `samples`: every output time in `(t_k, t_{k+1}]`, interpolated linearly
    /// between the step's end states.
    fn samples_in_step(&mut self, observer: &mut dyn Observer) -> Result<(), SimError> {
        let rate = self.settings.output_rate;
        if rate.is_nan() || rate <= 0.0 {
            return Ok(());
        }
        let (mut q, mut u) = (
            std::mem::take(&mut self.sample_q),
            std::mem::take(&mut self.sample_u),
        );
        let mut result = Ok(());
        let (t_k, t_next) = (self.states.t, self.states.t_next);
        loop {
            let t = self.next_output as Real / rate;
            if t > t_next || t > self.settings.t_end {
                break;
            }
            if observer.wants_samples() {
                let s = ((t - t_k) / (t_next - t_k)).clamp(0.0, 1.0);
                let st = &self.states;
                for ((x, a), b) in q.iter_mut().zip(&st.q).zip(&st.q_next) {
                    *x = a + s * (b - a);
                }
                for ((x, a), b) in u.iter_mut().zip(&st.u).zip(&st.u_next) {
                    *x = a + s * (b - a);
                }
                result = self.sample(t, &q, &u, observer);
                if result.is_err() {
                    break;
                }
            }
            self.next_output += 1;
        }
        (self.sample_q, self.sample_u) = (q, u);
        result
    }

    /// One sample of `(t, q, u)` with the current modes.
    fn sample(
        &mut self,
        t: Real,
        q: &[Real],
        u: &[Real],
        observer: &mut dyn Observer,
    ) -> Result<(), SimError> {
        if !observer.wants_samples() {
            return Ok(());
        }
        let e = energy(self.model, &mut self.sampler, t, q, u).map_err(|e| SimError::at(t, e))?;
        super::broad::listed_pairs(
            self.model,
            &self.sampler,
            self.all_pairs.as_deref(),
            self.modes.changed(),
            (&mut self.boxes, &mut self.planes, &mut self.finder),
            &mut self.listed,
        )
        .map_err(|e| SimError::at(t, e))?;
        self.gap_values.clear();
        self.listed_modes.clear();
        self.listed_slips.clear();
        for &pair in &self.listed {
            let g = crate::contact::signed_gap(self.model, &self.sampler, pair, Real::INFINITY)
                .map_err(|e| SimError::at(t, e))?
                .unwrap_or(Real::INFINITY);
            self.gap_values.push(g);
            self.listed_modes.push(self.modes[pair.index()]);
            // Time-stepping does not report the slip direction.
            self.listed_slips.push(0);
        }
        let sample = Sample {
            t,
            q,
            u,
            energy: e,
            pairs: &self.listed,
            gaps: &self.gap_values,
            poses: &self.sampler.body_pose,
            at_impact: false,
            modes: &self.listed_modes,
            slips: &self.listed_slips,
            contact_stages: 0,
        };
        observer
            .sample(self.model, &sample)
            .map_err(|e| SimError::at(t, e))?;
        self.counters.samples += 1;
        self.last_sample_t = Some(t);
        Ok(())
    }

    /// Stage `advance`: the end of the step becomes the current state.
    fn advance(&mut self) {
        let s = &mut self.states;
        s.t = s.t_next;
        std::mem::swap(&mut s.q, &mut s.q_next);
        std::mem::swap(&mut s.u, &mut s.u_next);
        self.k += 1;
    }

    /// Stage `finish`: the final sample, the energy audit, the counters and the stop
    /// message.
    fn finish(&mut self, stop: StopReason, observer: &mut dyn Observer) -> RunSummary {
        let t = self.states.t;
        let (q, u) = (self.states.q.clone(), self.states.u.clone());
        self.audit.end = energy(self.model, &mut self.sampler, t, &q, &u).unwrap_or(Energy {
            kinetic: Real::NAN,
            potential: Real::NAN,
        });
        let level = match stop {
            StopReason::Failed(_) => Level::Error,
            StopReason::Interrupted { .. } => Level::Warning,
            StopReason::EndTime => Level::Info,
        };
        // Best effort: the run is over either way. No sample twice at the same instant.
        if self.last_sample_t != Some(t) {
            let _ = self.sample(t, &q, &u, observer);
        }
        let r = self.report;
        if r.ambiguous + r.no_exact_solution + r.unconverged > 0 {
            let _ = observer.message(
                t,
                Level::Warning,
                &format!(
                    "contact problems: {} with several solutions, {} without an exact \
                     solution, {} Gauss–Seidel unconverged ({} more rescued by the \
                     enumeration), of {} exact and {} Gauss–Seidel steps",
                    r.ambiguous,
                    r.no_exact_solution,
                    r.unconverged,
                    r.rescued,
                    r.exact_steps,
                    r.pgs_steps
                ),
            );
        }
        let _ = observer.message(t, level, &format!("run stopped at t = {t} s: {stop}"));
        RunSummary {
            stop,
            state: State::new(
                t,
                nalgebra::DVector::from_column_slice(&q),
                nalgebra::DVector::from_column_slice(&u),
            ),
            audit: self.audit,
            counters: self.counters,
        }
    }
}
