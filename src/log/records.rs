//! ricochet's own records: what is logged on `/state` and `/impacts`, and the energy audit
//! written as metadata at the end of a run. Their JSON schemas are
//! `schemas/ricochet/State.json` and `schemas/ricochet/Impact.json`; a field added here must
//! be added there (the tests validate every record against its schema, and the schemas
//! forbid unknown fields).

use std::fmt;

use serde::{Deserialize, Serialize};

use crate::impact::{CollisionType, ContactVelocity, ImpactMatrix, Law};

/// Energies of the system at one instant (J).
#[derive(Clone, Copy, Debug, Default, PartialEq, Serialize, Deserialize)]
pub struct Energy {
    /// Kinetic energy `½ uᵀ M(q) u` (J).
    pub kinetic: f64,
    /// Potential energy of gravity and springs (J), relative to the scene's datum.
    pub potential: f64,
    /// Total mechanical energy `kinetic + potential` (J).
    pub total: f64,
}

impl Energy {
    /// The energies with `total = kinetic + potential` (J).
    pub fn new(kinetic: f64, potential: f64) -> Energy {
        Energy {
            kinetic,
            potential,
            total: kinetic + potential,
        }
    }
}

/// The state of one contact pair, or of the whole run.
///
/// Ordered from the least to the most constrained: `Free < Sliding < Sticking`, and
/// `Impact` above them all, because at an impact instant the impact is what matters.
#[derive(
    Clone, Copy, Debug, Default, PartialEq, Eq, PartialOrd, Ord, Hash, Serialize, Deserialize,
)]
#[serde(rename_all = "snake_case")]
pub enum ContactMode {
    /// Open: the gap is positive or the bodies separate (code 0).
    #[default]
    Free,
    /// Closed and slipping: Coulomb friction at `μ λ_n` opposes the slip (code 1).
    Sliding,
    /// Closed and not slipping: the friction force is inside the cone (code 2).
    Sticking,
    /// An impact at this instant (code 3).
    Impact,
}

impl ContactMode {
    /// The name used in logs: `free`, `sliding`, `sticking`, `impact`.
    pub fn name(self) -> &'static str {
        match self {
            ContactMode::Free => "free",
            ContactMode::Sliding => "sliding",
            ContactMode::Sticking => "sticking",
            ContactMode::Impact => "impact",
        }
    }

    /// A number for the Plot panel: free 0, sliding 1, sticking 2, impact 3.
    pub fn code(self) -> u8 {
        match self {
            ContactMode::Free => 0,
            ContactMode::Sliding => 1,
            ContactMode::Sticking => 2,
            ContactMode::Impact => 3,
        }
    }

    /// The mode of a run from the modes of its contacts: the most constrained one, or
    /// `Free` when there are none.
    pub fn of_run(contacts: impl IntoIterator<Item = ContactMode>) -> ContactMode {
        contacts.into_iter().max().unwrap_or_default()
    }
}

impl fmt::Display for ContactMode {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.write_str(self.name())
    }
}

/// The state of one contact pair in a [`StateRecord`].
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct ContactState {
    /// Name of the pair, `<body_a>/<body_b>` (the world is `world`).
    pub pair: String,
    /// Mode of the pair.
    pub mode: ContactMode,
    /// `mode` as a number for the Plot panel (see [`ContactMode::code`]).
    pub mode_code: u8,
    /// Signed gap `g` (m): positive when apart, negative when penetrating.
    pub gap: f64,
    /// Direction of the slip along the contact tangent `t = perp(n)` when sliding: `1` or
    /// `−1`; `0` otherwise (a slip that stops and reverses flips it).
    #[serde(default)]
    pub slip: i8,
}

impl ContactState {
    /// The state of `pair` in `mode` with the signed gap `gap` (m); fills `mode_code`.
    pub fn new(pair: impl Into<String>, mode: ContactMode, gap: f64) -> ContactState {
        ContactState {
            pair: pair.into(),
            mode,
            mode_code: mode.code(),
            gap,
            slip: 0,
        }
    }
}

/// One sample of the run (`ricochet.State` on `/state`).
///
/// Plot panel paths: `/state.energy.total`, `/state.q[0]`, `/state.u[1]`,
/// `/state.mode_code`, `/state.contacts[0].gap`.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct StateRecord {
    /// Simulated time (s), `≥ 0`; also the message's log time.
    pub t: f64,
    /// Generalized coordinates `q`, n_q entries (m for translations, rad for angles).
    pub q: Vec<f64>,
    /// Generalized speeds `u`, n_u entries (m/s, rad/s).
    pub u: Vec<f64>,
    /// Energies at this instant (J).
    pub energy: Energy,
    /// Mode of the run: the most constrained of the contacts' modes
    /// ([`ContactMode::of_run`]).
    pub mode: ContactMode,
    /// `mode` as a number for the Plot panel.
    pub mode_code: u8,
    /// Every contact pair that the scene watches, in a fixed order.
    pub contacts: Vec<ContactState>,
    /// Number of impacts since the start of the run, up to this sample: at an impact
    /// instant, the sample before the jump excludes that instant's impacts and the one
    /// after includes them.
    pub impact_count: u64,
}

impl StateRecord {
    /// A sample at time `t` (s); the run's `mode` and the mode codes are derived from
    /// `contacts`.
    pub fn new(
        t: f64,
        q: Vec<f64>,
        u: Vec<f64>,
        energy: Energy,
        contacts: Vec<ContactState>,
        impact_count: u64,
    ) -> StateRecord {
        let mode = ContactMode::of_run(contacts.iter().map(|c| c.mode));
        StateRecord {
            t,
            q,
            u,
            energy,
            mode,
            mode_code: mode.code(),
            contacts,
            impact_count,
        }
    }

    /// The name of the first non-finite number, if any, `t` aside (the writer checks times
    /// on their own).
    #[doc(hidden)]
    pub fn first_non_finite(&self) -> Option<String> {
        let scalars = [
            ("energy.kinetic", self.energy.kinetic),
            ("energy.potential", self.energy.potential),
            ("energy.total", self.energy.total),
        ];
        first_bad(&scalars)
            .or_else(|| first_bad_in("q", &self.q))
            .or_else(|| first_bad_in("u", &self.u))
            .or_else(|| {
                (self.contacts.iter().enumerate())
                    .find(|(_, c)| !c.gap.is_finite())
                    .map(|(i, _)| format!("contacts[{i}].gap"))
            })
    }
}

impl StateRecord {
    /// Appends the record's JSON text to `out`: byte for byte what `serde_json::to_writer`
    /// writes for it (its derived `Serialize`: the fields in declaration order, compact),
    /// without serde's per-field machinery — the writer thread encodes ~100 of these per
    /// simulated second (issue 16). Numbers go through serde_json's own `CompactFormatter`
    /// (the same shortest round-trip float text, `null` for a non-finite one), the names
    /// through [`json_string`]. The test `state_json_is_serde_json_s`
    /// (`tests/all/unit/log_records.rs`) holds it to `serde_json::to_vec` over random
    /// records.
    #[doc(hidden)]
    pub fn append_json(&self, out: &mut Vec<u8>) {
        use serde_json::ser::Formatter;
        out.extend_from_slice(b"{\"t\":");
        json_f64(out, self.t);
        out.extend_from_slice(b",\"q\":");
        json_f64s(out, &self.q);
        out.extend_from_slice(b",\"u\":");
        json_f64s(out, &self.u);
        out.extend_from_slice(b",\"energy\":{\"kinetic\":");
        json_f64(out, self.energy.kinetic);
        out.extend_from_slice(b",\"potential\":");
        json_f64(out, self.energy.potential);
        out.extend_from_slice(b",\"total\":");
        json_f64(out, self.energy.total);
        out.extend_from_slice(b"},\"mode\":");
        json_mode(out, self.mode);
        out.extend_from_slice(b",\"mode_code\":");
        json_u64(out, u64::from(self.mode_code));
        out.extend_from_slice(b",\"contacts\":[");
        for (k, c) in self.contacts.iter().enumerate() {
            // Every field, by name: a field added to the record must be written here.
            let ContactState {
                pair,
                mode,
                mode_code,
                gap,
                slip,
            } = c;
            if k > 0 {
                out.push(b',');
            }
            out.extend_from_slice(b"{\"pair\":");
            json_string(out, pair);
            out.extend_from_slice(b",\"mode\":");
            json_mode(out, *mode);
            out.extend_from_slice(b",\"mode_code\":");
            json_u64(out, u64::from(*mode_code));
            out.extend_from_slice(b",\"gap\":");
            json_f64(out, *gap);
            out.extend_from_slice(b",\"slip\":");
            let _ = serde_json::ser::CompactFormatter.write_i8(out, *slip);
            out.push(b'}');
        }
        out.extend_from_slice(b"],\"impact_count\":");
        json_u64(out, self.impact_count);
        out.push(b'}');
    }
}

/// `x` as serde_json writes an `f64`: its shortest round-trip text, `null` if not finite.
/// (Writing into a `Vec` cannot fail.)
fn json_f64(out: &mut Vec<u8>, x: f64) {
    use serde_json::ser::Formatter;
    if x.is_finite() {
        let _ = serde_json::ser::CompactFormatter.write_f64(out, x);
    } else {
        out.extend_from_slice(b"null");
    }
}

/// `xs` as a JSON array of numbers (as serde_json writes a `Vec<f64>`).
fn json_f64s(out: &mut Vec<u8>, xs: &[f64]) {
    out.push(b'[');
    for (k, &x) in xs.iter().enumerate() {
        if k > 0 {
            out.push(b',');
        }
        json_f64(out, x);
    }
    out.push(b']');
}

/// `n` as serde_json writes an unsigned integer.
fn json_u64(out: &mut Vec<u8>, n: u64) {
    use serde_json::ser::Formatter;
    let _ = serde_json::ser::CompactFormatter.write_u64(out, n);
}

/// A contact mode as its serialized name (`snake_case`, [`ContactMode::name`]).
fn json_mode(out: &mut Vec<u8>, mode: ContactMode) {
    out.push(b'"');
    out.extend_from_slice(mode.name().as_bytes());
    out.push(b'"');
}

/// `s` as a JSON string, as serde_json writes it: quoted, with `"`, `\\` and the control
/// characters below U+0020 escaped (serde_json's own escaping for those, which are rare in
/// a pair's name), everything else verbatim.
fn json_string(out: &mut Vec<u8>, s: &str) {
    if s.bytes().any(|b| b < 0x20 || b == b'"' || b == b'\\') {
        let _ = serde_json::to_writer(&mut *out, s);
        return;
    }
    out.push(b'"');
    out.extend_from_slice(s.as_bytes());
    out.push(b'"');
}

/// A planar vector in the world frame (m, or dimensionless for a direction).
#[derive(Clone, Copy, Debug, Default, PartialEq, Serialize, Deserialize)]
pub struct Planar {
    /// x component in the world frame.
    pub x: f64,
    /// y component in the world frame.
    pub y: f64,
}

/// The support of a `rocking_end` entry: the impulse of the persistent contact force at its
/// point over the hops left (see `ricochet::sim::Support`).
#[derive(Clone, Copy, Debug, Default, PartialEq, Serialize, Deserialize)]
pub struct SupportRecord {
    /// Normal part (N·s).
    pub i_n: f64,
    /// Tangential part (N·s).
    pub i_t: f64,
    /// `t∞ − t`, how long the hops left would have lasted (s).
    pub duration: f64,
}

/// Why an impulse was applied (the `cause` of an impact record).
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum ImpactCause {
    /// One contact point approaching: the scene's one-point law.
    #[default]
    Collision,
    /// Several points at once: Moreau's generalized Newton law.
    Simultaneous,
    /// Painlevé's inconsistency resolved by an impact without collision.
    WithoutCollision,
    /// The end of an accumulation of impacts: the impact after which the hop would be too
    /// small to resolve, made plastic (`e = 0`, with the pair's friction).
    AccumulationEnd,
    /// The end of a rocking accumulation: the projection of the velocity onto the closed
    /// contacts, whose normal impulse on the lifting point is negative.
    RockingEnd,
}

impl ImpactCause {
    /// The name used in logs: `collision`, `simultaneous`, `without_collision`,
    /// `accumulation_end`, `rocking_end`.
    pub fn name(self) -> &'static str {
        match self {
            ImpactCause::Collision => "collision",
            ImpactCause::Simultaneous => "simultaneous",
            ImpactCause::WithoutCollision => "without_collision",
            ImpactCause::AccumulationEnd => "accumulation_end",
            ImpactCause::RockingEnd => "rocking_end",
        }
    }
}

/// One entry of the impact ledger (`ricochet.Impact` on `/impacts`).
///
/// The fields up to `work_t` are the contract of `DESIGN.md`; the rest are additions.
/// Sign conventions as in the crate doc: `n` is oriented so that `v_a.n ≤ 0`, `t` so
/// that `v_a.t ≥ 0` [P, Eq. (10)].
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct ImpactRecord {
    /// Simulated time of the impact (s), `≥ 0`; also the message's log time.
    pub t: f64,
    /// Name of the contact pair, `<body_a>/<body_b>`.
    pub pair: String,
    /// Name of the first body of the pair (`world` for a static obstacle).
    pub body_a: String,
    /// Name of the second body of the pair (`world` for a static obstacle).
    pub body_b: String,
    /// The impact law that solved the impact.
    pub law: Law,
    /// Sticking, reverse or forward sliding [P, Table 1].
    #[serde(rename = "type")]
    pub impact_type: CollisionType,
    /// The sign case 1–5 of `(g, h, p, q)` [P, Table 1].
    pub case: u8,
    /// `α = v_t^A / |v_n^A|` [P, Eq. (34)] (dimensionless); `None` (absent from the JSON)
    /// when it is not a finite number: an impact without approach speed (`v_n^A = 0`) has
    /// no α. (Absent, not `null`: Foxglove Studio 1.48 refuses a JSON schema whose field
    /// may be a number or null.)
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub alpha: Option<f64>,
    /// `W = J M⁻¹ Jᵀ` in the contact frame [P, Eq. (20)].
    pub w: ImpactMatrix,
    /// `g = μ m_tt − m_nt` [P, Eq. (35)].
    pub g: f64,
    /// `h = m_nn − μ m_nt` [P, Eq. (35)].
    pub h: f64,
    /// `p = μ m_tt + m_nt` [P, Eq. (35)].
    pub p: f64,
    /// `q = m_nn + μ m_nt` [P, Eq. (35)].
    pub q: f64,
    /// Velocity of approach `v^A` in the contact frame (m/s) [P, Eq. (21)].
    pub v_a: ContactVelocity,
    /// Velocity of separation `v^S` in the contact frame (m/s) [P, Eq. (21)].
    pub v_s: ContactVelocity,
    /// Normal impulse `I_n` (N·s) [P, Eq. (13)], `≥ 0`. For a `rocking_end`, the contact
    /// impulse of the hops left: the jump's plus the [`SupportRecord`].
    pub i_n: f64,
    /// Tangential impulse `I_t` (N·s) [P, Eq. (13)]; for a `rocking_end`, that of the hops
    /// left.
    pub i_t: f64,
    /// Only on a `rocking_end`: the part of `i_n`, `i_t` the persistent contact force
    /// delivers over the hops left (absent otherwise).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub support: Option<SupportRecord>,
    /// Jump of the generalized speeds `Δu = M⁻¹ Jᵀ I`, n_u entries (m/s, rad/s) [P, Eq. (16)];
    /// for a `rocking_end`, of the jump `I − support`.
    pub delta_u: Vec<f64>,
    /// Mechanical energy just before the impact (J).
    pub energy_before: f64,
    /// Mechanical energy just after the impact (J).
    pub energy_after: f64,
    /// `ΔE = ½ I_n (v_n^S + v_n^A) + ½ I_t (v_t^S + v_t^A)` (J) [P, Eq. (29)].
    pub delta_e: f64,
    /// Work of the normal impulse along the law's path in the impulse plane,
    /// `∫ v_n dI_n` (J); `work_n + work_t = delta_e`.
    pub work_n: f64,
    /// Work of the tangential impulse along the law's path, `∫ v_t dI_t` (J).
    pub work_t: f64,
    /// Index of the impact in the run, from 0.
    pub index: u64,
    /// Why the impulse was applied (absent from logs written before it existed, whose
    /// impacts were all collisions).
    #[serde(default)]
    pub cause: ImpactCause,
    /// Coefficient of restitution used by the law (dimensionless).
    pub e: f64,
    /// Coefficient of friction `μ` used by the law (dimensionless).
    pub mu: f64,
    /// The left-hand side of [P, Eq. (28)], the energy change due to prescribed motion
    /// (J); zero without prescribed motion. `energy_after − energy_before = delta_e +
    /// prescribed_work`.
    pub prescribed_work: f64,
    /// Contact point in the world frame (m).
    pub point: Planar,
    /// Unit contact normal `n` in the world frame.
    pub normal: Planar,
    /// Unit contact tangent `t` in the world frame.
    pub tangent: Planar,
}

impl ImpactRecord {
    /// The impulse `I_n n + I_t t` in the world frame (N·s).
    pub fn impulse(&self) -> Planar {
        Planar {
            x: self.i_n * self.normal.x + self.i_t * self.tangent.x,
            y: self.i_n * self.normal.y + self.i_t * self.tangent.y,
        }
    }

    /// The name of the first non-finite number, if any, `t` aside (the writer checks times
    /// on their own).
    pub(crate) fn first_non_finite(&self) -> Option<String> {
        let scalars = [
            ("alpha", self.alpha.unwrap_or(0.0)),
            ("w.mnn", self.w.nn),
            ("w.mnt", self.w.nt),
            ("w.mtt", self.w.tt),
            ("g", self.g),
            ("h", self.h),
            ("p", self.p),
            ("q", self.q),
            ("v_a.n", self.v_a.n),
            ("v_a.t", self.v_a.t),
            ("v_s.n", self.v_s.n),
            ("v_s.t", self.v_s.t),
            ("i_n", self.i_n),
            ("i_t", self.i_t),
            ("energy_before", self.energy_before),
            ("energy_after", self.energy_after),
            ("delta_e", self.delta_e),
            ("work_n", self.work_n),
            ("work_t", self.work_t),
            ("e", self.e),
            ("mu", self.mu),
            ("prescribed_work", self.prescribed_work),
            ("point.x", self.point.x),
            ("point.y", self.point.y),
            ("normal.x", self.normal.x),
            ("normal.y", self.normal.y),
            ("tangent.x", self.tangent.x),
            ("tangent.y", self.tangent.y),
        ];
        first_bad(&scalars).or_else(|| first_bad_in("delta_u", &self.delta_u))
    }
}

/// Work counters of a run, for the audit.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Serialize, Deserialize)]
pub struct Counters {
    /// Impacts solved.
    pub impacts: u64,
    /// Accepted integration steps.
    pub steps: u64,
    /// Rejected integration steps.
    pub rejected_steps: u64,
    /// Evaluations of the right-hand side `u̇ = M⁻¹(τ − h)`.
    pub rhs_evaluations: u64,
    /// Events located (impacts, lift-offs, stick–slip transitions).
    pub events: u64,
    /// `/state` samples written.
    pub state_samples: u64,
}

/// The energy audit of a run, written as the `audit` metadata record when the run ends.
///
/// The balance is `E_end − E_0 = impact_delta_e + applied_work + contact_work +
/// prescribed_work + integration_drift`: whatever the bookkeeping does not explain is drift
/// of the integrator (or a bug).
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct Audit {
    /// Why the run stopped: `t_end` when it reached its end time, `interrupted` on Ctrl-C,
    /// otherwise the error or the event that stopped it.
    pub stop_reason: String,
    /// Simulated time at which the run stopped (s).
    pub t_stop: f64,
    /// Mechanical energy at `t = 0`, `E_0` (J).
    pub energy_initial: f64,
    /// Mechanical energy at `t_stop`, `E_end` (J).
    pub energy_final: f64,
    /// Sum of `delta_e` over the impacts (J), `≤ 0` unless [P, Eq. (28)] is violated.
    pub impact_delta_e: f64,
    /// Work of dampers and applied non-conservative forces between impacts (J).
    pub applied_work: f64,
    /// Work of the forces of contacts in persistent contact (J): friction of sliding
    /// contacts. Absent from logs written before persistent contact existed (zero).
    #[serde(default)]
    pub contact_work: f64,
    /// Work of prescribed (rheonomic) motion, including its share at impacts (J).
    pub prescribed_work: f64,
    /// `E_end − E_0 − (impact_delta_e + applied_work + contact_work + prescribed_work)`
    /// (J): the energy the bookkeeping does not explain. Set by [`Audit::new`].
    pub integration_drift: f64,
    /// Work counters.
    pub counters: Counters,
}

impl Audit {
    /// The audit with `integration_drift` computed from the balance.
    pub fn new(
        stop_reason: impl Into<String>,
        t_stop: f64,
        (energy_initial, energy_final): (f64, f64),
        (impact_delta_e, applied_work, contact_work, prescribed_work): (f64, f64, f64, f64),
        counters: Counters,
    ) -> Audit {
        let explained = impact_delta_e + applied_work + contact_work + prescribed_work;
        Audit {
            stop_reason: stop_reason.into(),
            t_stop,
            energy_initial,
            energy_final,
            impact_delta_e,
            applied_work,
            contact_work,
            prescribed_work,
            integration_drift: energy_final - energy_initial - explained,
            counters,
        }
    }

    /// The name of the first non-finite number, if any.
    pub(crate) fn first_non_finite(&self) -> Option<String> {
        first_bad(&[
            ("t_stop", self.t_stop),
            ("energy_initial", self.energy_initial),
            ("energy_final", self.energy_final),
            ("impact_delta_e", self.impact_delta_e),
            ("applied_work", self.applied_work),
            ("contact_work", self.contact_work),
            ("prescribed_work", self.prescribed_work),
            ("integration_drift", self.integration_drift),
        ])
    }
}

fn first_bad(values: &[(&str, f64)]) -> Option<String> {
    (values.iter())
        .find(|(_, v)| !v.is_finite())
        .map(|(name, _)| (*name).to_owned())
}

fn first_bad_in(name: &str, values: &[f64]) -> Option<String> {
    (values.iter())
        .position(|v| !v.is_finite())
        .map(|i| format!("{name}[{i}]"))
}
