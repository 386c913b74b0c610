//! The event functions of the loop: the gaps of open contacts, and the forces and slips of
//! closed ones.

use super::persistent::{Evaluation, Hold, Persistent, PointScratch, nearest_velocities};
use super::{AtTime, Nested, Scales};
use crate::contact::{PairContact, pair_contact, pair_contact_of};
use crate::dynamics::forward_dynamics;
use crate::events::EventFunctions;
use crate::kinematics::{point_velocity, update_positions, update_velocities};
use crate::math::{Real, Vec2};
use crate::model::{ContactPair, Model, PairId};
use crate::state::Data;

/// Event functions per contact pair.
pub const SLOTS: usize = 7;

/// The slot of an event function among every pair's: for pair `k`, slot `SLOTS·k + s`
/// (the index of the events the contact stage receives). The locator samples the
/// functions of the candidate pairs alone (the broad phase, `sim::broad`): the pair of
/// rank `r` among them has the slots `SLOTS·r + s` there ([`GapFunctions::slot_of`]).
///
/// | s | function | armed when | its event |
/// |---|---|---|---|
/// | 0 | the signed gap (m) | no point of the pair is closed | an impact |
/// | 0 | the gap at the pair's other point (m) | one point is closed | an impact there |
/// | 0 | the gap (or the other point's) `− floor` | the gap event is disarmed | it sinks |
/// | 1 + 3j | `λ_n` of closed point j (N) | point j is closed | lift-off |
/// | 2 + 3j | `μ λ_n − |λ_t|` (N) | point j sticks | it starts to slip |
/// | 2 + 3j | `s V_t` (m/s) | point j slides with slip s | the slip stops |
/// | 3 + 3j | the Painlevé coefficient (1/kg) | point j slides | sliding cannot be held |
///
/// Every event is a closing crossing (`> 0` to `≤ 0`). `j` is the rank of the point among
/// the closed points of its pair, in the order of `Persistent::closed`.
pub fn slot(pair: PairId, s: usize) -> usize {
    SLOTS * pair.index() + s
}

/// The rank of closed point `i` among the closed points of its pair.
pub fn rank(persistent: &Persistent, i: usize) -> usize {
    let closed = persistent.closed();
    closed[..i]
        .iter()
        .filter(|c| c.pair == closed[i].pair)
        .count()
}

/// The event functions `gᵢ(t, y)` of a model: see [`slot`].
pub struct GapFunctions<'m> {
    model: &'m Model,
    /// Boxed, to trade places with `end_kinematics.data` by a pointer swap.
    data: Box<Data>,
    /// The closed contact points, in sync with the ODE system's.
    pub persistent: Persistent,
    scratch: PointScratch,
    scales: Scales,
    /// The candidate pairs of the step, in pair order: the pairs whose functions are
    /// evaluated (see [`slot`]).
    pub candidates: Vec<PairId>,
    /// The pairs whose gap event is disarmed (in pair order), with the floor of each: their
    /// slot 0 is `gap − floor`, an event only when the gap sinks below `floor ≤ −gap_tol`
    /// (see `Simulation::arm`).
    pub disarmed: Vec<(PairId, Real)>,
    /// The last values computed, with what they depend on (see [`Memo`]).
    memo: Memo,
    /// The force functions that cannot reach zero in the current step (see
    /// [`StandIns`]).
    stand_ins: StandIns,
    /// The right-hand side's evaluation of the closed points at the end of the step, if
    /// it has one (see [`Self::take_end_evaluation`]).
    end: Evaluation,
    /// What `self.data` holds, with the gaps' contacts found there (see [`Here`]).
    here: Here,
    /// The kinematics of the step's end from the right-hand side (see
    /// [`Self::take_end_kinematics`]).
    end_kinematics: EndKinematics,
    /// The last pair looked up, with its id ([`Self::pair`]).
    last_pair: std::cell::Cell<Option<(PairId, ContactPair)>>,
}

/// The kinematics of the step's end, copied from the right-hand side's scratch, whose last
/// stage (DOPRI5's, first same as last) evaluated that very state: the exact samples there
/// (the values and rates at the step's end) copy them instead of computing them again.
struct EndKinematics {
    /// Whether `data` holds the positions and velocities at `(t, qu)`.
    valid: bool,
    t: Real,
    /// `[q; u]`.
    qu: Vec<Real>,
    data: Box<Data>,
}

/// The state whose kinematics `GapFunctions::data` holds after the values of a sample, with
/// the contact of each candidate's slot 0 there: the locator asks for the rates at the
/// same sample (every sample, with the extremum search), which then take the positions,
/// velocities and contacts as they are instead of computing them again (two kinematics
/// passes and a contact query per candidate). The same numbers. Every other change of
/// `data` forgets it.
#[derive(Default)]
struct Here {
    /// Whether it describes `data`.
    valid: bool,
    t: Real,
    /// `[q; u]`: `data` holds the positions of `q`, and the velocities of `u` if
    /// `velocities`.
    qu: Vec<Real>,
    velocities: bool,
    /// The candidates and closed points the contacts were found for.
    candidates: Vec<PairId>,
    closed: Vec<super::persistent::Closed>,
    /// The contact of slot 0 of each candidate (`GapFunctions::gap_contact`).
    contacts: Vec<Option<PairContact>>,
    /// The contact points of each candidate with one closed point, with their points on
    /// `a` in its body's frame (`PointScratch::candidates`; empty for the others): the
    /// slip velocity of the closed point is the nearest's.
    candidate_points: Vec<arrayvec::ArrayVec<(PairContact, Vec2), 2>>,
    /// The contact points of the last `GapFunctions::other_point`.
    points: arrayvec::ArrayVec<(PairContact, Vec2), 2>,
}

impl Here {
    /// Whether `data` holds the positions of `(t, q)` (`q = qu[..n]`), with these contacts.
    fn holds(&self, fns: &GapFunctions<'_>, t: Real, q: &[Real]) -> bool {
        self.valid
            && self.t == t
            && self.qu.get(..q.len()) == Some(q)
            && self.candidates == fns.candidates
            && self.closed == fns.persistent.closed()
    }
}

/// Stand-ins for the force functions of the closed points at the interior samples of a
/// step, when none of them can reach zero in it.
///
/// Those functions (`λ_n`, the friction margin, the Painlevé coefficient) have no rate, and
/// each sample of them costs the constrained dynamics (the forces of every closed point).
/// The right-hand side computed them at every stage of the step (the integrator's own
/// samples of it, [`Persistent::bounds`]), and the locator's first sample at the step's
/// start. With `lo`, `hi` the least and largest of these values of a function, the
/// function cannot reach zero in the step when [`stays_positive`]:
///
/// ```text
/// lo > 4 (hi − lo)
/// ```
///
/// The forces are part of the right-hand side (`u̇` holds `M⁻¹ Jᵀ λ`), so along an accepted
/// step they vary as smoothly as the stages resolve: like a polynomial of the method's
/// degree through the stage values. A polynomial of degree ≤ 5 through DOPRI5's nodes
/// `0, 1/5, 3/10, 4/5, 8/9, 1` stays within `(Λ − 1)/2 · (hi − lo)` below `lo`, with `Λ`
/// = 5.64 the Lebesgue constant of those nodes (largest at `t = 0.56 h`, in the wide gap
/// between 3/10 and 4/5): above `lo − 2.32 (hi − lo) > 0.42 lo` under the rule (the test
/// in this module). When every force function is so, the interior samples compute only the
/// kinematic functions (the gaps, the slips) and write `lo` for the others: the locator
/// reads only the signs of the samples of functions without rates. The exact evaluations
/// (the step's end, root searches, the settling) check the bound, `g ≥ lo / 2`; if one
/// fails, [`GapFunctions::stand_ins_failed`] tells the loop to locate again without
/// stand-ins.
///
/// The slip velocity `s V_t + margin` of a sliding point gets a stand-in by the same rule:
/// the right-hand side computes `V_t` at every stage too ([`Persistent::bounds`]).
///
/// The gap of a candidate pair (slot 0) gets one from its value `g₀` at the step's start
/// and the speed bound `V₀ = V_a + V_b` there, the rotation bound of the broad phase
/// (`broad::reach`: `|v_G| + |ω| (|c − G| + r)` of each collider, which holds as a body
/// turns): a gap changes no faster than the relative speed of the shapes' points, so
/// `g(t) ≥ g₀ − V̄ (t − t₀)` while that speed stays below `V̄`. With
///
/// ```text
/// V̄ = 2 (V₀ + |g| h),    g₀ > 2 V̄ h
/// ```
///
/// (`h` the step, `|g|` gravity: twice what the start's speed and a free fall give), the
/// gap stays above `g₀ / 2` for speeds up to `2 V̄` everywhere in the step. The exact
/// evaluations check it a posteriori like the forces' bound: the gap `g ≥ g₀ / 2` and the
/// speed bound `V ≤ V̄` (the step's end is one: every step checks it). A pair with two
/// closed points has no gap function (a constant). When every function of the candidates
/// has a stand-in, an interior sample computes nothing, no kinematics, and its rates are
/// zero ([`EventFunctions::interior_rates`]): the far end of Kane's pendulum and its
/// sliding tip, most of its run.
/// Whether a function whose values at a step's start and stages lie in `[lo, hi]` stays
/// positive over the step (see [`StandIns`]): `lo > 4 (hi − lo)`.
#[doc(hidden)]
pub fn stays_positive(lo: Real, hi: Real) -> bool {
    lo > 0.0 && lo > 4.0 * (hi - lo)
}

/// The speed bound `V̄ = 2 (V₀ + |g| h)` over a step of length `h` of a pair whose speed
/// bound is `v0` at its start, under gravity `grav`, if its gap `g0` at the start cannot
/// close in the step by it, `g₀ > 2 V̄ h` (see [`StandIns`]).
#[doc(hidden)]
pub fn gap_stays_positive(g0: Real, v0: Real, grav: Real, h: Real) -> Option<Real> {
    let v_bar = 2.0 * (v0 + grav * h);
    (v0 >= 0.0 && v_bar.is_finite() && g0 > 2.0 * v_bar * h).then_some(v_bar)
}

/// What the stand-ins of the force functions did in a run (see `StandIns`).
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct StandInCounts {
    /// Interior samples of the event location with closed points.
    pub samples: u64,
    /// Those that used the stand-ins (no constrained dynamics solved).
    pub used: u64,
    /// Steps located again because an exact value broke a stand-in's bound.
    pub relocated: u64,
    /// Exact samples that took the right-hand side's evaluation of the step's end (see
    /// [`GapFunctions::take_end_evaluation`]) instead of solving the forces again.
    pub taken: u64,
    /// Interior samples (with closed points or not) whose every function had a stand-in:
    /// nothing computed, no kinematics.
    pub skipped: u64,
    /// Steps in which a candidate's gap got no stand-in because it could close in the
    /// step by its bound (its speed known).
    pub gaps_refused: u64,
}

/// What the interior samples of a step compute (see [`StandIns`]).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
enum Interior {
    /// Every function.
    Exact,
    /// The gaps and slips, with stand-ins for the force functions.
    Kinematic,
    /// Nothing: a stand-in for every function.
    Nothing,
}

/// The speed bounds `V_a + V_b` of the candidates ([`GapFunctions::pair_speed`]) at the
/// state whose kinematics `GapFunctions::data` held when they were computed: the check at
/// a step's end, whose state is the next step's start, where `V₀` is the same numbers.
#[derive(Default)]
struct EndSpeeds {
    t: Real,
    /// `[q; u]` of that state.
    qu: Vec<Real>,
    /// Each candidate and its speed bound.
    speeds: Vec<(PairId, Real)>,
}

#[derive(Default)]
struct StandIns {
    /// `(lo, hi)` of each closed point's force functions over the step's stages.
    stages: Vec<[(Real, Real); 3]>,
    /// Decided for this step: what the interior samples compute.
    decided: Option<Interior>,
    /// `lo` of each force function, with the start's value (NaN for a slip function
    /// without a stand-in).
    lo: Vec<[Real; 3]>,
    /// The step `[t0, t1]` being located.
    t0: Real,
    t1: Real,
    /// The speed bound `V₀` of each candidate pair at the step's start (NaN: unknown), from
    /// the rates there.
    v0: Vec<Real>,
    /// For each candidate, `(g₀, V̄)` if its gap has a stand-in (NaN: none).
    gap: Vec<(Real, Real)>,
    /// The time of the last interior sample that computed nothing (NaN: none), for its
    /// rates.
    nothing_at: Real,
    /// The values of the interior samples that compute nothing, once the first of the
    /// step wrote them (empty: not yet).
    nothing: Vec<Real>,
    /// Whether an interior sample of this step used them.
    used: bool,
    /// Whether an interior sample of this step used the gaps' stand-ins.
    gaps_used: bool,
    /// The time of the last check of the gaps' speed bounds (NaN: none): the values and
    /// the rates of a sample check them once.
    checked_at: Real,
    /// The speed bounds of the candidates found by the last check at a step's end, with
    /// the state `[q; u]` of `GapFunctions::data` then (see `GapFunctions::speeds_at`).
    end_speeds: EndSpeeds,
    /// Whether an exact value broke the bound after they were used.
    failed: bool,
    /// Never use them (the oracle of the tests: `Simulation::set_stand_ins(false)`).
    off: bool,
    /// Interior samples with closed points, those that used the stand-ins, and the steps
    /// located again after one failed.
    counts: StandInCounts,
}

/// The values of the last [`EventFunctions::values`] call, with everything they depend on:
/// the state, the candidates, the floors of the disarmed pairs and the closed points
/// (their modes, slip margins and reference forces). The locator samples each step at
/// both ends, and a step starts where the last one ended: its first sample is the last
/// one's final sample, a constrained dynamics solve saved per step when nothing changed
/// in between (an event, a new mode, a released margin, a new candidate all do).
#[derive(Default)]
struct Memo {
    t: Real,
    y: Vec<Real>,
    candidates: Vec<PairId>,
    disarmed: Vec<(PairId, Real)>,
    closed: Vec<super::persistent::Closed>,
    g: Vec<Real>,
}

impl Memo {
    fn holds(&self, fns: &GapFunctions<'_>, t: Real, y: &[Real], m: usize) -> bool {
        self.t == t
            && self.g.len() == m
            && self.y == y
            && self.candidates == fns.candidates
            && self.disarmed == fns.disarmed
            && self.closed == fns.persistent.closed()
    }

    /// Keeps `g` at `(t, y)` with the candidates, disarmed pairs and closed points of the
    /// functions.
    fn keep(
        &mut self,
        (t, y, g): (Real, &[Real], &[Real]),
        candidates: &[PairId],
        disarmed: &[(PairId, Real)],
        closed: &[super::persistent::Closed],
    ) {
        self.t = t;
        self.y.clear();
        self.y.extend_from_slice(y);
        self.candidates.clear();
        self.candidates.extend_from_slice(candidates);
        self.disarmed.clear();
        self.disarmed.extend_from_slice(disarmed);
        self.closed.clear();
        self.closed.extend_from_slice(closed);
        self.g.clear();
        self.g.extend_from_slice(g);
    }
}

impl<'m> GapFunctions<'m> {
    /// The event functions of `model`, with no closed contact point.
    pub fn new(model: &'m Model, scales: Scales) -> Self {
        Self {
            model,
            data: Box::new(Data::new(model)),
            persistent: Persistent::new(model, scales),
            scratch: PointScratch::new(model),
            scales,
            candidates: Vec::new(),
            disarmed: Vec::new(),
            memo: Memo::default(),
            stand_ins: StandIns::default(),
            end: Evaluation::default(),
            here: Here::default(),
            end_kinematics: EndKinematics {
                valid: false,
                t: Real::NAN,
                qu: vec![0.0; model.nq() + model.nu()],
                data: Box::new(Data::new(model)),
            },
            last_pair: std::cell::Cell::new(None),
        }
    }

    /// Takes the kinematics of the right-hand side's last evaluation if it was at the
    /// step's end `(t, y)` (the last stage of a DOPRI5 step): the values and rates there
    /// copy them ([`Data::copy_kinematics_from`], the same numbers) instead of one
    /// positions and one velocities pass each. Call before the location of a step; what
    /// was taken is used only at that very state. Not when the stand-ins are off (the
    /// oracle computes everything).
    pub fn take_end_kinematics(&mut self, system: &super::MotionSystem<'_>, t: Real, y: &[Real]) {
        let (n, nqu) = (self.model.nq(), self.model.nq() + self.model.nu());
        let end = &mut self.end_kinematics;
        end.valid = false;
        if self.stand_ins.off {
            return;
        }
        if let Some(data) = system.kinematics_at(t, &y[..n], &y[n..nqu]) {
            end.data.copy_kinematics_from(data);
            end.t = t;
            end.qu.copy_from_slice(&y[..nqu]);
            end.valid = true;
        }
    }

    /// Whether the kinematics of the right-hand side may be shared with other consumers of
    /// the same state (not when the stand-ins are off: the oracle computes everything).
    pub fn shares_kinematics(&self) -> bool {
        !self.stand_ins.off
    }

    /// Moves the kinematics taken by [`Self::take_end_kinematics`] into `self.data` if they
    /// are those of `(t, q, u)` (once: a second call computes them); whether it did.
    fn end_kinematics_at(&mut self, t: Real, q: &[Real], u: &[Real]) -> bool {
        let end = &self.end_kinematics;
        let n = q.len();
        let at = end.valid
            && end.t == t
            && end.qu.len() == n + u.len()
            && end.qu[..n] == *q
            && end.qu[n..] == *u;
        if at {
            // Taken, not copied: `data` and the taken scratch trade places (both full
            // scratches of the model; every other consumer of `data` computes what it
            // reads), and what was taken is spent.
            std::mem::swap(&mut self.data, &mut self.end_kinematics.data);
            self.end_kinematics.valid = false;
        }
        at
    }

    /// Takes the last evaluation of the ODE system's closed points (the same closed
    /// points as these), to be used if the event functions are asked for that state: the
    /// last stage of a DOPRI5 step is its end state, where the locator samples them too.
    /// The same numbers, without solving the same forces twice. Call before the location
    /// of a step, and [`Self::drop_end_evaluation`] after it.
    pub fn take_end_evaluation(&mut self, system: &mut Persistent) {
        if self.stand_ins.off {
            return;
        }
        system.trade_evaluation(&mut self.end);
        // What the system got back is stale: it computes its own at its next evaluation.
        system.forget_evaluation();
    }

    /// Replaces the closed points (`mu` from their pairs, after overrides), with room for
    /// their evaluations (`Persistent::set_from`: copied into kept buffers).
    pub fn set_closed(&mut self, closed: &[super::Closed], mu: &[Real]) {
        let k = closed.len();
        (self.here.closed).reserve(k.saturating_sub(self.here.closed.len()));
        self.persistent.set_from(closed, mu);
        self.stand_ins.nothing.clear();
        self.end.fit(k, self.model.nq() + self.model.nu());
    }

    /// Forgets the evaluation taken by [`Self::take_end_evaluation`].
    pub fn drop_end_evaluation(&mut self) {
        self.end.forget();
    }

    /// Starts the event location of the step `[t0, t1]` whose right-hand sides gave the
    /// force functions the bounds `stages` (`Persistent::bounds` of the ODE system, whose
    /// closed points are these). `stand_ins` false: none in this step.
    pub fn begin_step(
        &mut self,
        stages: &[[(Real, Real); 3]],
        (t0, t1): (Real, Real),
        stand_ins: bool,
    ) {
        let s = &mut self.stand_ins;
        s.stages.clear();
        s.stages.extend_from_slice(stages);
        s.decided = (!stand_ins).then_some(Interior::Exact);
        if s.failed {
            s.counts.relocated += 1;
        }
        (s.t0, s.t1) = (t0, t1);
        s.v0.clear();
        s.v0.resize(self.candidates.len(), Real::NAN);
        s.gap.clear();
        s.nothing_at = Real::NAN;
        s.nothing.clear();
        s.checked_at = Real::NAN;
        s.used = false;
        s.gaps_used = false;
        s.failed = false;
    }

    /// Whether an exact evaluation in this step broke the bound of a stand-in used at an
    /// interior sample: the step must be located again without them
    /// (`begin_step` with `stand_ins` false).
    pub fn stand_ins_failed(&self) -> bool {
        self.stand_ins.failed
    }

    /// Allows the stand-ins and the taking of the right-hand side's evaluation of a step's
    /// end (the default), or forbids both: every sample then solves the forces.
    pub fn set_stand_ins(&mut self, on: bool) {
        self.stand_ins.off = !on;
    }

    /// What the stand-ins did so far.
    pub fn stand_in_counts(&self) -> StandInCounts {
        self.stand_ins.counts
    }

    /// Reserves room for `pairs` candidate pairs, so that the event location does not
    /// allocate as the candidates grow up to that many.
    pub fn reserve(&mut self, pairs: usize) {
        self.candidates
            .reserve(pairs.saturating_sub(self.candidates.len()));
        let dim = self.model.nq() + self.model.nu() + super::system::WORKS;
        let memo = &mut self.memo;
        memo.y.reserve(dim.saturating_sub(memo.y.len()));
        memo.candidates
            .reserve(pairs.saturating_sub(memo.candidates.len()));
        memo.g.reserve((SLOTS * pairs).saturating_sub(memo.g.len()));
        let here = &mut self.here;
        let nqu = self.model.nq() + self.model.nu();
        here.qu.reserve(nqu.saturating_sub(here.qu.len()));
        (here.candidates).reserve(pairs.saturating_sub(here.candidates.len()));
        (here.contacts).reserve(pairs.saturating_sub(here.contacts.len()));
        (here.candidate_points).reserve(pairs.saturating_sub(here.candidate_points.len()));
        let s = &mut self.stand_ins;
        s.v0.reserve(pairs.saturating_sub(s.v0.len()));
        s.gap.reserve(pairs.saturating_sub(s.gap.len()));
        (s.nothing).reserve((SLOTS * pairs).saturating_sub(s.nothing.len()));
        let end = &mut s.end_speeds;
        end.qu.reserve(nqu.saturating_sub(end.qu.len()));
        (end.speeds).reserve(pairs.saturating_sub(end.speeds.len()));
    }

    /// The slot `s` of `pair` among the candidates' functions, if it is a candidate.
    pub fn slot_of(&self, pair: PairId, s: usize) -> Option<usize> {
        let r = self.candidates.binary_search(&pair).ok()?;
        Some(SLOTS * r + s)
    }

    /// The slot among every pair's ([`slot`]) of the candidates' slot `i`.
    pub fn global_slot(&self, i: usize) -> usize {
        slot(self.candidates[i / SLOTS], i % SLOTS)
    }

    /// Adds `pairs` to the candidates (kept in pair order, once each).
    pub fn add_candidates(&mut self, pairs: impl Iterator<Item = PairId>) {
        let before = self.candidates.len();
        for pair in pairs {
            if self.candidates.binary_search(&pair).is_err() {
                self.candidates.push(pair);
            }
        }
        if self.candidates.len() > before {
            self.stand_ins.nothing.clear();
            self.candidates.sort_unstable();
            self.candidates.dedup();
        }
    }
}

impl GapFunctions<'_> {
    /// The function of slot 0 of `pair` at `(t, y)`: the gap, or with one closed point
    /// the gap at the pair's other point (m); see [`slot`].
    pub fn open_gap(&mut self, pair: PairId, t: Real, y: &[Real]) -> Result<Real, Nested> {
        let n = self.model.nq();
        self.here.valid = false;
        update_positions(self.model, &mut self.data, t, &y[..n])
            .map_err(|e| Nested::from(e.at(t)))?;
        self.open_gap_here(pair, t)
    }

    /// The positions at `(t, y)`, for [`Self::open_gap_at_positions`] (one kinematics pass
    /// for the gaps of many pairs).
    pub fn set_positions(&mut self, t: Real, y: &[Real]) -> Result<(), Nested> {
        let n = self.model.nq();
        self.here.valid = false;
        update_positions(self.model, &mut self.data, t, &y[..n]).map_err(|e| Nested::from(e.at(t)))
    }

    /// [`Self::open_gap`] at the positions of the last [`Self::set_positions`] (at `t`).
    pub fn open_gap_at_positions(&mut self, pair: PairId, t: Real) -> Result<Real, Nested> {
        self.open_gap_here(pair, t)
    }

    /// The other point of the pair of closed point `i`, its only one: of its (at most two)
    /// candidates, the one farther from the closed point (which moves on `a` as it slides
    /// or rolls). At the positions of `self.data`.
    fn other_point(&mut self, i: usize) -> Result<Option<PairContact>, Nested> {
        let (model, c) = (self.model, self.persistent.closed()[i]);
        let (pair, local) = (c.pair, c.local);
        // The pair as the closed points looked it up (once per set of them).
        let p = self.persistent.closed_pair(model, &self.data, i)?;
        let candidates =
            (self.scratch).candidates_of(model, &self.data, (pair, &p), self.scales.length)?;
        self.here.points = candidates;
        Ok(match self.here.points.as_slice() {
            [x, y] if (x.1 - local).length() <= (y.1 - local).length() => Some(y.0),
            [x, _] => Some(x.0),
            _ => None,
        })
    }

    /// `model.pair(pair)`, looked up once while the pair asked for stays the same (the
    /// model does not change; the contact of a candidate, its rate and its speed bound ask
    /// for the same pair in turn).
    fn pair(&self, pair: PairId) -> Option<ContactPair> {
        match self.last_pair.get() {
            Some((id, p)) if id == pair => Some(p),
            _ => {
                let p = self.model.pair(pair)?;
                self.last_pair.set(Some((pair, p)));
                Some(p)
            }
        }
    }

    /// `model.pair_of(pair)` ([`Self::pair`] when the model has the pair, the same pair).
    pub(super) fn pair_of(&self, pair: PairId) -> ContactPair {
        self.pair(pair).unwrap_or_else(|| self.model.pair_of(pair))
    }

    /// [`Self::open_gap`] at the positions of `self.data`.
    fn open_gap_here(&mut self, pair: PairId, t: Real) -> Result<Real, Nested> {
        Ok(self
            .gap_contact(pair, t)?
            .map_or(self.scales.length, |c| c.gap))
    }

    /// The contact whose gap is slot 0 of `pair`, at the positions of `self.data`: the
    /// pair's closest features with no closed point, its other point with one, none with
    /// two (or when it has no such point).
    fn gap_contact(&mut self, pair: PairId, t: Real) -> Result<Option<PairContact>, Nested> {
        let model = self.model;
        let closed = self.persistent.closed();
        let mut on_pair = (closed.iter().enumerate()).filter(|(_, c)| c.pair == pair);
        let (first, second) = (on_pair.next().map(|(i, _)| i), on_pair.next());
        match (first, second) {
            (None, _) => match self.pair(pair) {
                // `pair_contact` without its lookup: the same numbers.
                Some(p) => pair_contact_of(model, &self.data, &p, Real::INFINITY)
                    .map_err(|e| Nested::from(e.at(t))),
                None => pair_contact(model, &self.data, pair, Real::INFINITY)
                    .map_err(|e| Nested::from(e.at(t))),
            },
            (Some(i), None) => self.other_point(i),
            (Some(_), Some(_)) => Ok(None),
        }
    }
}

impl GapFunctions<'_> {
    /// Slot 0 of every candidate (the gaps), at the positions of `self.data`; their
    /// contacts into `self.here`, for the rates of the same sample: the caller describes
    /// the state with [`Self::keep_here`].
    fn gap_slots(&mut self, t: Real, g: &mut [Real]) -> Result<(), Nested> {
        self.here.valid = false;
        let mut contacts = std::mem::take(&mut self.here.contacts);
        contacts.clear();
        self.here.candidate_points.clear();
        for r in 0..self.candidates.len() {
            let pair = self.candidates[r];
            let floor = match self.disarmed.binary_search_by_key(&pair, |d| d.0) {
                Ok(k) => self.disarmed[k].1,
                Err(_) => 0.0,
            };
            self.here.points.clear();
            let contact = self.gap_contact(pair, t)?;
            contacts.push(contact);
            // Moved, not copied: `other_point` writes them afresh at each use.
            let points = std::mem::take(&mut self.here.points);
            self.here.candidate_points.push(points);
            g[SLOTS * r] = contact.map_or(self.scales.length, |c| c.gap) - floor;
        }
        self.here.contacts = contacts;
        Ok(())
    }

    /// Marks `self.data` as holding the positions at `(t, y)`, and the velocities if
    /// `velocities`, with the contacts of the last [`Self::gap_slots`] (see [`Here`]).
    fn keep_here(&mut self, t: Real, y: &[Real], velocities: bool) {
        let nqu = self.model.nq() + self.model.nu();
        let here = &mut self.here;
        here.t = t;
        here.qu.clear();
        here.qu.extend_from_slice(&y[..nqu]);
        here.velocities = velocities;
        here.candidates.clear();
        here.candidates.extend_from_slice(&self.candidates);
        here.closed.clear();
        here.closed.extend_from_slice(self.persistent.closed());
        here.valid = true;
    }

    /// [`EventFunctions::values`], computed.
    fn values_here(&mut self, t: Real, y: &[Real], g: &mut [Real]) -> Result<(), Nested> {
        let model = self.model;
        let (n, nqu) = (model.nq(), model.nq() + model.nu());
        let (q, u) = (&y[..n], &y[n..nqu]);
        // Unarmed functions hold a positive value.
        g.fill(self.scales.length);
        let taken = self.persistent.can_take(&self.end, (t, q, u));
        // Positions alone, or the forward dynamics (positions and velocities).
        let positions_only = self.persistent.closed().is_empty() || taken;
        self.here.valid = false;
        // The velocities too, if the right-hand side's kinematics of this state are copied.
        let mut velocities = !positions_only;
        if positions_only {
            if self.end_kinematics_at(t, q, u) {
                velocities = true;
            } else {
                update_positions(model, &mut self.data, t, q).map_err(|e| Nested::from(e.at(t)))?;
            }
            if taken {
                // The right-hand side's evaluation of this very state (see
                // `take_end_evaluation`).
                self.persistent.trade_evaluation(&mut self.end);
                self.end.forget();
                self.stand_ins.counts.taken += 1;
            }
        } else {
            forward_dynamics(model, &mut self.data, t, q, u).map_err(|e| Nested::from(e.at(t)))?;
            self.persistent
                .accelerate(model, &mut self.data, (t, q, u))?;
        }
        self.gap_slots(t, g)?;
        self.keep_here(t, y, velocities);
        for i in 0..self.persistent.closed().len() {
            let c = self.persistent.closed()[i];
            let j = rank(&self.persistent, i);
            let Some(at) = self.slot_of(c.pair, 0) else {
                continue;
            };
            let f = self.persistent.force_functions(i);
            g[at + 1 + 3 * j] = f[0];
            g[at + 2 + 3 * j] = match c.hold {
                Hold::Stick => f[1],
                Hold::Slide(s) => s * self.persistent.points()[i].v_t + c.slip_margin,
            };
            g[at + 3 + 3 * j] = f[2];
        }
        Ok(())
    }

    /// What the interior samples of this step compute (see [`StandIns`]); decided once per
    /// step, from the stages' bounds, the exact values at the step's start (the last
    /// exact evaluation, `self.memo`) and the speed bounds there (from its rates).
    fn interior(&mut self) -> Interior {
        if let Some(decided) = self.stand_ins.decided {
            return decided;
        }
        let closed = self.persistent.closed();
        let s = &mut self.stand_ins;
        let start_known = !s.off
            && self.memo.t == s.t0
            && self.memo.g.len() == SLOTS * self.candidates.len()
            && self.memo.candidates == self.candidates
            && self.memo.closed == closed;
        // The force functions (all or none: one of them costs the constrained dynamics),
        // and the slips.
        let mut forces = start_known && s.stages.len() == closed.len();
        let mut slips = forces;
        s.lo.clear();
        for (i, (c, stages)) in closed.iter().zip(&s.stages).enumerate() {
            if !forces {
                break;
            }
            let Some(at) = self.candidates.binary_search(&c.pair).ok() else {
                forces = false;
                break;
            };
            let j = rank(&self.persistent, i);
            let mut lo = [Real::NAN; 3];
            for (f, (&(a, b), l)) in stages.iter().zip(&mut lo).enumerate() {
                let start = self.memo.g[SLOTS * at + 1 + f + 3 * j];
                let ok = a <= b && stays_positive(a.min(start), b.max(start));
                if f == 1 && matches!(c.hold, Hold::Slide(_)) {
                    // The slip velocity: a stand-in of its own, else computed.
                    slips &= ok;
                    if !ok {
                        continue;
                    }
                }
                *l = a.min(start);
                forces &= ok;
            }
            s.lo.push(lo);
        }
        // The gaps.
        let mut gaps = start_known && s.v0.len() == self.candidates.len();
        s.gap.clear();
        if gaps {
            let (h, grav) = (s.t1 - s.t0, self.model.gravity().length());
            for (r, &pair) in self.candidates.iter().enumerate() {
                let g0 = self.memo.g[SLOTS * r];
                let both_closed = closed.iter().filter(|c| c.pair == pair).count() >= 2;
                let bound = if both_closed {
                    // No gap function: the constant `scales.length`.
                    Some(Real::INFINITY)
                } else {
                    gap_stays_positive(g0, s.v0[r], grav, h)
                };
                match bound {
                    Some(v_bar) => s.gap.push((g0, v_bar)),
                    None => {
                        s.gap.push((Real::NAN, Real::NAN));
                        gaps = false;
                    }
                }
            }
            if !gaps {
                s.counts.gaps_refused += 1;
            }
        }
        let decided = match (closed.is_empty() || forces, gaps && slips) {
            (true, true) => Interior::Nothing,
            (true, false) if !closed.is_empty() => Interior::Kinematic,
            _ => Interior::Exact,
        };
        s.decided = Some(decided);
        decided
    }

    /// The values at `samples` interior samples where every function has a stand-in (see
    /// [`StandIns`]), the same at each: nothing computed. `t` is the sample's time, for
    /// its rates (NaN: none asked).
    fn values_of_nothing(&mut self, t: Real, samples: u64, g: &mut [Real]) {
        let s = &mut self.stand_ins;
        let closed = self.persistent.closed();
        if s.nothing.len() == g.len() {
            // The same stand-ins at every interior sample of the step: written once.
            g.copy_from_slice(&s.nothing);
        } else {
            g.fill(self.scales.length);
            for (r, &(g0, _)) in s.gap.iter().enumerate() {
                if g0.is_finite() {
                    g[SLOTS * r] = g0;
                }
            }
            for (i, c) in closed.iter().enumerate() {
                let j = rank(&self.persistent, i);
                let at = SLOTS * self.candidates.binary_search(&c.pair).unwrap_or(0);
                for (f, &l) in s.lo[i].iter().enumerate() {
                    g[at + 1 + f + 3 * j] = l;
                }
            }
            s.nothing.clear();
            s.nothing.extend_from_slice(g);
        }
        if !closed.is_empty() {
            s.used = true;
            s.counts.samples += samples;
            s.counts.used += samples;
        }
        s.gaps_used = true;
        s.nothing_at = t;
        s.counts.skipped += samples;
    }

    /// The values at an interior sample with the force functions' stand-ins: the gaps
    /// and the slip velocities computed, `lo` for the rest (see [`StandIns`]).
    fn values_with_stand_ins(&mut self, t: Real, y: &[Real], g: &mut [Real]) -> Result<(), Nested> {
        let model = self.model;
        let (n, nqu) = (model.nq(), model.nq() + model.nu());
        g.fill(self.scales.length);
        self.here.valid = false;
        update_positions(model, &mut self.data, t, &y[..n]).map_err(|e| Nested::from(e.at(t)))?;
        update_velocities(model, &mut self.data, &y[n..nqu]).map_err(|e| Nested::from(e.at(t)))?;
        self.gap_slots(t, g)?;
        self.keep_here(t, y, true);
        for i in 0..self.persistent.closed().len() {
            let c = self.persistent.closed()[i];
            let j = rank(&self.persistent, i);
            let at = SLOTS * self.candidates.binary_search(&c.pair).unwrap_or(0);
            let lo = self.stand_ins.lo[i];
            g[at + 1 + 3 * j] = lo[0];
            g[at + 2 + 3 * j] = match c.hold {
                Hold::Stick => lo[1],
                Hold::Slide(_) if !lo[1].is_nan() => lo[1],
                Hold::Slide(s) => {
                    // The pair's contact points found for its gap (its only closed
                    // point), or a query.
                    let points = (self.candidates.binary_search(&c.pair).ok())
                        .map(|r| &self.here.candidate_points[r])
                        .filter(|points| !points.is_empty());
                    let v = if let Some(points) = points {
                        let p = self.pair_of(c.pair);
                        nearest_velocities(model, &self.data, &p, points, c.local)?
                    } else {
                        self.scratch.velocities(
                            model,
                            &self.data,
                            c.pair,
                            c.local,
                            self.scales.length,
                        )?
                    };
                    let (_, v_t) = v.ok_or_else(|| {
                        Nested::from(super::SimError::Contact {
                            t,
                            message: format!(
                                "closed contact point of pair #{} lost",
                                c.pair.index()
                            ),
                        })
                    })?;
                    s * v_t + c.slip_margin
                }
            };
            g[at + 3 + 3 * j] = lo[2];
        }
        self.stand_ins.used = true;
        self.stand_ins.counts.used += 1;
        Ok(())
    }

    /// The speed bound `V_a + V_b` of the points of `pair` (`broad::reach`), at the
    /// positions and velocities of `self.data`.
    fn pair_speed(&self, pair: PairId) -> Real {
        let p = self.pair_of(pair);
        let reach = |c| super::broad::reach(self.model, &self.data, c).0;
        reach(p.a) + reach(p.b)
    }

    /// At the positions and velocities of `self.data` at `t`, an exact state of the step:
    /// the speed bounds `V₀` of the candidates at the step's start, or elsewhere in it
    /// whether a gap that had a stand-in broke its speed bound `V ≤ V̄` (see
    /// [`StandIns`]).
    fn speeds_at(&mut self, t: Real) {
        let s = &self.stand_ins;
        if s.off || s.failed {
            return;
        }
        if t == s.t0 {
            if s.decided.is_none()
                && s.v0.len() == self.candidates.len()
                && s.v0.iter().any(|v| v.is_nan())
            {
                if self.end_speeds_hold(t) {
                    // The check at the last step's end computed them at this very state.
                    let speeds = &self.stand_ins.end_speeds.speeds;
                    for (v0, &(_, v)) in self.stand_ins.v0.iter_mut().zip(speeds) {
                        *v0 = v;
                    }
                } else {
                    for r in 0..self.candidates.len() {
                        let v = self.pair_speed(self.candidates[r]);
                        self.stand_ins.v0[r] = v;
                    }
                }
            }
        } else if s.gaps_used && t > s.t0 && t <= s.t1 && t != s.checked_at {
            self.stand_ins.checked_at = t;
            // Every candidate's bound, kept for the next step's start when `data` is
            // described by `self.here` (its state known).
            let mut end = std::mem::take(&mut self.stand_ins.end_speeds);
            end.speeds.clear();
            for &pair in &self.candidates {
                end.speeds.push((pair, self.pair_speed(pair)));
            }
            let s = &self.stand_ins;
            let failed = (s.gap.iter().zip(&end.speeds))
                .any(|(&(_, v_bar), &(_, v))| v_bar.is_finite() && !v.le(&v_bar));
            let here = &self.here;
            let n = self.model.nq();
            let known = here.valid && here.velocities && here.t == t && here.qu.len() > n;
            end.t = if known { t } else { Real::NAN };
            end.qu.clear();
            if known {
                end.qu.extend_from_slice(&here.qu);
            }
            self.stand_ins.end_speeds = end;
            self.stand_ins.failed |= failed;
        }
    }

    /// Whether the speed bounds of the last check at a step's end are those of the
    /// kinematics in `self.data` at `t` (the same state, described by `self.here`, with
    /// its velocities) for the current candidates.
    fn end_speeds_hold(&self, t: Real) -> bool {
        let (end, here) = (&self.stand_ins.end_speeds, &self.here);
        end.t == t
            && here.valid
            && here.velocities
            && here.t == t
            && here.qu == end.qu
            && end.speeds.len() == self.candidates.len()
            && (end.speeds.iter().zip(&self.candidates)).all(|(&(pair, _), &c)| pair == c)
    }

    /// After an exact evaluation: whether a function that had a stand-in in this step
    /// broke its bound, `g ≥ lo / 2` of a force or slip function, `g ≥ g₀ / 2` of a gap
    /// (see [`StandIns`]).
    fn check_stand_ins(&mut self, g: &[Real]) {
        let s = &mut self.stand_ins;
        if s.gaps_used && !s.failed {
            for (r, &(g0, _)) in s.gap.iter().enumerate() {
                if g0.is_finite() && !(g.get(SLOTS * r).is_some_and(|&x| x >= 0.5 * g0)) {
                    s.failed = true;
                }
            }
        }
        if !s.used || s.failed {
            return;
        }
        let closed = self.persistent.closed();
        for (i, lo) in s.lo.iter().enumerate() {
            let Some(at) = self.candidates.binary_search(&closed[i].pair).ok() else {
                continue;
            };
            let j = rank(&self.persistent, i);
            for (f, l) in lo.iter().enumerate() {
                if !(l.is_nan() || g[SLOTS * at + 1 + f + 3 * j] >= 0.5 * l) {
                    s.failed = true;
                }
            }
        }
    }
}

impl EventFunctions for GapFunctions<'_> {
    type Error = Nested;

    fn values(&mut self, t: Real, y: &[Real], g: &mut [Real]) -> Result<(), Nested> {
        if self.memo.holds(self, t, y, g.len()) {
            g.copy_from_slice(&self.memo.g);
            return Ok(());
        }
        self.values_here(t, y, g)?;
        self.check_stand_ins(g);
        if self.stand_ins.gaps_used && !self.stand_ins.failed {
            // The speed bounds of the gaps' stand-ins: the velocities, if the values did
            // not need them (the rates at the same sample take them).
            let model = self.model;
            let (n, nqu) = (model.nq(), model.nq() + model.nu());
            if !self.here.velocities {
                update_velocities(model, &mut self.data, &y[n..nqu])
                    .map_err(|e| Nested::from(e.at(t)))?;
                self.here.velocities = true;
                self.here.qu.truncate(n);
                self.here.qu.extend_from_slice(&y[n..nqu]);
            }
            self.speeds_at(t);
        }
        (self.memo).keep(
            (t, y, g),
            &self.candidates,
            &self.disarmed,
            self.persistent.closed(),
        );
        Ok(())
    }

    /// A gap alone (slot 0: a root search of an impact evaluates one pair's gap, not every
    /// candidate's — the cost of a search in a scene of many bodies); a force, slip or
    /// Painlevé function with all of them (they share the constrained dynamics). The same
    /// numbers as [`EventFunctions::values`].
    fn value(&mut self, t: Real, y: &[Real], i: usize, g: &mut [Real]) -> Result<Real, Nested> {
        if !i.is_multiple_of(SLOTS) {
            self.values(t, y, g)?;
            return Ok(g[i]);
        }
        let (n, nqu) = (self.model.nq(), self.model.nq() + self.model.nu());
        self.here.valid = false;
        if !self.end_kinematics_at(t, &y[..n], &y[n..nqu]) {
            update_positions(self.model, &mut self.data, t, &y[..n])
                .map_err(|e| Nested::from(e.at(t)))?;
        }
        let pair = self.candidates[i / SLOTS];
        let floor = match self.disarmed.binary_search_by_key(&pair, |d| d.0) {
            Ok(k) => self.disarmed[k].1,
            Err(_) => 0.0,
        };
        Ok(self.open_gap_here(pair, t)? - floor)
    }

    /// The rate of one function (see [`EventFunctions::rates`]): a gap's alone.
    fn rate(
        &mut self,
        t: Real,
        y: &[Real],
        _dy: &[Real],
        i: usize,
        _g_dot: &mut [Real],
    ) -> Result<Option<Real>, Nested> {
        if !i.is_multiple_of(SLOTS) {
            return Ok(Some(0.0));
        }
        let model = self.model;
        let (n, nqu) = (model.nq(), model.nq() + model.nu());
        self.here.valid = false;
        if !self.end_kinematics_at(t, &y[..n], &y[n..nqu]) {
            update_positions(model, &mut self.data, t, &y[..n])
                .map_err(|e| Nested::from(e.at(t)))?;
            update_velocities(model, &mut self.data, &y[n..nqu])
                .map_err(|e| Nested::from(e.at(t)))?;
        }
        let contact = self.gap_contact(self.candidates[i / SLOTS], t)?;
        self.gap_rate(self.candidates[i / SLOTS], contact, t)
            .map(Some)
    }

    /// The values of [`Self::values_of_nothing`] when every function has a stand-in (no
    /// state needed), the same as [`EventFunctions::interior_values`] gives them.
    fn interior_values_without_state(&mut self, t: Real, g: &mut [Real]) -> Result<bool, Nested> {
        if self.interior() != Interior::Nothing {
            return Ok(false);
        }
        self.values_of_nothing(t, 1, g);
        Ok(true)
    }

    /// [`Self::interior_values_without_state`] for all the interior samples of the step at
    /// once (the same stand-ins at each, zero rates), when every function has one: the
    /// exact values that follow (the step's end first) check their bounds, as they do
    /// after the samples one by one.
    fn interior_stand_ins(&mut self, samples: usize, g: &mut [Real]) -> Result<bool, Nested> {
        if self.interior() != Interior::Nothing {
            return Ok(false);
        }
        self.values_of_nothing(Real::NAN, samples as u64, g);
        Ok(true)
    }

    /// Zero rates after [`Self::interior_values_without_state`] at `t`.
    fn interior_rates_without_state(
        &mut self,
        t: Real,
        g_dot: &mut [Real],
    ) -> Result<bool, Nested> {
        if t != self.stand_ins.nothing_at {
            return Ok(false);
        }
        g_dot.fill(0.0);
        Ok(true)
    }

    fn interior_values(&mut self, t: Real, y: &[Real], g: &mut [Real]) -> Result<(), Nested> {
        let interior = self.interior();
        if interior != Interior::Nothing && !self.persistent.closed().is_empty() {
            self.stand_ins.counts.samples += 1;
        }
        match interior {
            Interior::Nothing => {
                self.values_of_nothing(t, 1, g);
                Ok(())
            }
            Interior::Kinematic => self.values_with_stand_ins(t, y, g),
            Interior::Exact => self.values(t, y, g),
        }
    }

    /// Zero rates after an interior sample that computed nothing (every function has a
    /// positive stand-in, see `StandIns`), else [`EventFunctions::rates`].
    fn interior_rates(
        &mut self,
        t: Real,
        y: &[Real],
        dy: &[Real],
        g_dot: &mut [Real],
    ) -> Result<bool, Nested> {
        if t == self.stand_ins.nothing_at {
            g_dot.fill(0.0);
            return Ok(true);
        }
        self.rates(t, y, dy, g_dot)
    }

    fn rates(
        &mut self,
        t: Real,
        y: &[Real],
        _dy: &[Real],
        g_dot: &mut [Real],
    ) -> Result<bool, Nested> {
        // The rates of the gaps: the normal relative velocity of their points. The force,
        // slip and Painlevé functions get a zero rate: the locator finds their sign changes
        // at its samples, not a dip below zero and back between two of them (which would
        // take a difference of the constrained dynamics at every search iteration).
        let model = self.model;
        let (n, nqu) = (model.nq(), model.nq() + model.nu());
        // The kinematics and contacts of the values at this sample, if `data` holds them.
        let here = self.here.holds(self, t, &y[..n]);
        let mut velocities = here && self.here.velocities && self.here.qu[n..] == y[n..nqu];
        if !here {
            self.here.valid = false;
            if self.end_kinematics_at(t, &y[..n], &y[n..nqu]) {
                velocities = true;
            } else {
                update_positions(model, &mut self.data, t, &y[..n])
                    .map_err(|e| Nested::from(e.at(t)))?;
            }
        }
        if !velocities {
            update_velocities(model, &mut self.data, &y[n..nqu])
                .map_err(|e| Nested::from(e.at(t)))?;
            if here {
                self.here.velocities = true;
                self.here.qu.truncate(n);
                self.here.qu.extend_from_slice(&y[n..nqu]);
            }
        }
        self.speeds_at(t);
        g_dot.fill(0.0);
        for r in 0..self.candidates.len() {
            let pair = self.candidates[r];
            let contact = if here {
                self.here.contacts[r]
            } else {
                self.gap_contact(pair, t)?
            };
            g_dot[SLOTS * r] = self.gap_rate(pair, contact, t)?;
        }
        Ok(true)
    }
}

impl GapFunctions<'_> {
    /// The rate of the gap of `pair` (slot 0): the normal relative velocity of the points
    /// of its `contact` ([`Self::gap_contact`]), at the velocities of `self.data`.
    fn gap_rate(
        &self,
        pair: PairId,
        contact: Option<PairContact>,
        t: Real,
    ) -> Result<Real, Nested> {
        let model = self.model;
        Ok(match contact {
            Some(c) => {
                let p = self.pair_of(pair);
                let v = |collider: crate::model::ColliderId, at: Vec2| match model.colliders()
                    [collider.index()]
                .body
                {
                    Some(body) => point_velocity(model, &self.data, body, at)
                        .map(|v| v.total)
                        .map_err(|e| Nested::from(e.at(t))),
                    None => Ok(Vec2::ZERO),
                };
                (v(p.b, c.point_b)? - v(p.a, c.point_a)?).dot(c.normal)
            }
            None => 0.0,
        })
    }
}
