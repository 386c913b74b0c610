//! The `contacts` stage of the loop: what happens at an event instant. In rounds, until
//! nothing changes:
//!
//! 1. **impacts**: the contact points that approach. One point alone: the one-point law
//!    of [P] (the scene's law). Several at once: Moreau's generalized Newton law over all
//!    the touching points ([`ImpactMap::apply_many`]).
//! 2. **accumulations**: an impact that leaves a touching point separating slower than its
//!    resting speed ([`super::Scales::v_rest_at`], from the point's own normal
//!    acceleration) would start a hop too small to resolve — a bouncing ball or a pendulum
//!    tip at the end of an **accumulation of impacts** (Zeno). That impact is done again,
//!    plastic: the same law with `e = 0` and the pair's friction (cause
//!    `accumulation_end`), so the infinitely many hops left are replaced by the impulse
//!    they add up to — the same normal impulse, each hop's Coulomb friction with it — and
//!    the contact stays closed. No impulse pulls. The time `t∞` the hops would end is
//!    extrapolated from their geometric decay, and the passage to persistent contact is
//!    reported then, named by the mode it enters. A rocking body, whose plastic impact on
//!    one corner lifts the other too slowly to resolve, cannot be held down by an impulse
//!    `≥ 0` at that instant: only gravity, over the hops left, brings it down. Its ledger
//!    entries (cause `rocking_end`) report the contact impulse of those hops — the jump
//!    that brings the points to rest ([`ImpactMap::close`]) plus the [`Support`] of the
//!    closed points until `t∞` — which is `≥ 0`; a point the jump would pull with no
//!    support to make up for it is released instead (see `rocking_end`).
//! 3. **modes**: the touching points that do not approach get their persistent-contact
//!    modes (open, stick, slide) from the complementarity problem at the acceleration
//!    level ([`Persistent::select`]). **Painlevé's paradox**: no consistent mode
//!    (*inconsistency*) is resolved by an impact without collision — the one-point law in
//!    its grazing limit `v_n^A → 0⁻` (Case 4 of Table 1, where it sticks with a finite
//!    impulse; Génot & Brogliato 1999) — and several consistent modes (*indeterminacy*)
//!    by the rule: the one with the most open points (the least constraint). Both are
//!    reported on the log with the time and the contact.

use std::fmt::Write as _;

use super::observer::{PairMode, Transition};
use super::persistent::{Candidate, Closed, Hold, Selection, pair_points};
use super::{
    AtTime, ImpactCause, ImpactEvent, Level, Observer, SimError, Simulation, StopReason, Support,
};
use crate::contact::{ManifoldWorkspace, PairContact};
use crate::dynamics::forward_dynamics;
use crate::events::Event;
use crate::impact::Impulse;
use crate::integrate::Stepper;
use crate::kinematics::{update_positions, update_velocities};
use crate::lcp::{self, Mode};
use crate::math::{Real, Vec2};
use crate::model::{Material, PairId};
use crate::settings::Simultaneous;

/// The slip margin of a point that starts to slide from rest, in units of the speed below
/// which a slip has no direction of its own (`v_slip`): see [`Closed::slip_margin`].
const SLIP_MARGIN: Real = 0.1;

/// The most rounds of impacts and mode changes at one instant.
const MAX_ROUNDS: usize = 100;

/// The points an event names at instant `t` (`new`), with those of the events before it at
/// the same instant (`|Δt| ≤ 1e-9 (1 + |t|)`), kept in `memo` (the instant and its points):
/// a point already there (`same`) is not added again. See `lift_offs_at`, `slip_starts_at`.
fn through_the_instant<T>(
    memo: &mut (Real, Vec<T>),
    t: Real,
    new: Option<T>,
    same: impl Fn(&T, &T) -> bool,
) {
    let same_instant = (t - memo.0).abs() <= 1e-9 * (1.0 + t.abs());
    if !same_instant {
        memo.0 = t;
        memo.1.clear();
    }
    if let Some(p) = new
        && !memo.1.iter().any(|m| same(m, &p))
    {
        memo.1.push(p);
    }
}

/// Writes the name of `pair`, `<collider a>/<collider b>` (`impact_map::pair_name`), into
/// `out` after what it holds.
fn write_pair_name(out: &mut String, model: &crate::model::Model, pair: PairId) {
    let p = &model.pair_of(pair);
    let name = |c: crate::model::ColliderId| &model.colliders()[c.index()].name;
    let _ = write!(out, "{}/{}", name(p.a), name(p.b));
}

/// How many of its caps a disarmed pair's step cap lasts (see `disarm_open_crossing`):
/// a contact separating at the speed `v` the cap `10 gap_tol / v` was made for is then
/// 100 gap_tol clear and armed again; one still within the tolerance is held, not
/// separating, and the cap would only slow the run (the 64-link rope: 31,103 of its first
/// 35,635 steps at one held pair's 3.3 µs).
const CAP_LIFETIME: Real = 10.0;

/// A touching contact point at the event instant.
#[derive(Clone, Copy, Debug)]
struct Touch {
    pair: PairId,
    contact: PairContact,
    /// The point on `a` in its body's frame.
    local: Vec2,
    /// `V_n` (m/s), with `n` from `b` to `a`.
    v_n: Real,
    /// Its speed below which it neither approaches nor separates (m/s): `v_tiny`, or
    /// `v_drift` for a point held closed in persistent contact.
    still: Real,
}

/// The events of an instant the mode selection keeps to: the points that start to slip
/// (their pair, point on `a` and slip) and the points that lift off.
type InstantEvents<'a> = (&'a [(PairId, Vec2, Real)], &'a [(PairId, Vec2)]);

impl Simulation<'_> {
    /// `f` with the kept buffer `field` of the contact stage's scratch, taken out of
    /// `self` for the call (so that `f` may borrow `self` too) and put back after it,
    /// whatever `f` returns.
    fn with_scratch<S: Default, R>(
        &mut self,
        field: fn(&mut Scratch) -> &mut S,
        f: impl FnOnce(&mut Self, &mut S) -> R,
    ) -> R {
        let mut buffer = std::mem::take(field(&mut self.scratch));
        let result = f(self, &mut buffer);
        *field(&mut self.scratch) = buffer;
        result
    }

    /// Stage `contacts` at the current time (see the module doc). Restarts the integrator
    /// when anything changed; returns a stop reason if the run cannot go on.
    pub(super) fn contacts(
        &mut self,
        event: Option<&Event>,
        observer: &mut dyn Observer,
    ) -> Result<Option<StopReason>, SimError> {
        self.contact_stages += 1;
        let t = self.stepper.t();
        self.flush_passages(t, observer)?;
        let mut y = std::mem::take(&mut self.y);
        y.copy_from_slice(self.stepper.y());
        let result = self.contacts_at(t, &mut y, event, observer);
        let outcome = match result {
            Ok((changed, stop)) => {
                if changed {
                    self.arm();
                    let reset = self.stepper.reset(&mut self.system, t, &y);
                    reset.map_err(SimError::from).map(|()| stop)
                } else {
                    Ok(stop)
                }
            }
            Err(e) => Err(e),
        };
        self.y = y;
        outcome
    }

    /// The rounds at `t` on the state `y` (updated in place): whether anything changed,
    /// and a stop reason. Works in the kept buffers of `self.scratch.rounds`.
    fn contacts_at(
        &mut self,
        t: Real,
        y: &mut [Real],
        event: Option<&Event>,
        observer: &mut dyn Observer,
    ) -> Result<(bool, Option<StopReason>), SimError> {
        self.with_scratch(
            |s| &mut s.rounds,
            |sim, r| sim.rounds(t, y, event, observer, r),
        )
    }

    /// [`Self::contacts_at`] in the buffers `r`.
    fn rounds(
        &mut self,
        t: Real,
        y: &mut [Real],
        event: Option<&Event>,
        observer: &mut dyn Observer,
        r: &mut Rounds,
    ) -> Result<(bool, Option<StopReason>), SimError> {
        let mut changed = false;
        let mut impacts_here = 0usize;
        let mut painleve_resolved = false;
        // The impacts so far at this instant, group by group (see `coupling`).
        r.groups.clear();
        let mut settled = false;
        // The instant's threshold lasts through every visit of the contact stage at `t`
        // (an event found again at once).
        if self.unresolved.0 != t {
            self.unresolved = (t, 0.0);
        }
        for _ in 0..MAX_ROUNDS {
            self.touching(t, y, &mut r.touching)?;
            if impacts_here > 0 {
                self.leave_unresolved(&mut r.touching);
            }
            let touching = &r.touching;
            let group = &mut r.group;
            (self.coupling).groups(self.model, touching.iter().map(|p| p.pair), group);
            let approaching = |i: usize| touching[i].v_n < -touching[i].still;
            // 1. Impacts, in each group of coupled points with an approaching point; the
            // groups are separate problems.
            super::coupling::distinct(
                (0..touching.len())
                    .filter(|&i| approaching(i))
                    .map(|i| group[i]),
                &mut r.ids,
            );
            if !r.ids.is_empty() {
                if impacts_here == 0 {
                    self.sample(t, y, true, observer)?;
                }
                self.map.recycle(&mut r.events);
                for &id in &r.ids {
                    r.members.clear();
                    r.members.extend(
                        (0..touching.len())
                            .filter(|&i| group[i] == id)
                            .map(|i| touching[i]),
                    );
                    let k = match r.groups.iter().position(|g| g.id == id) {
                        Some(k) => k,
                        None => {
                            r.groups.push(GroupImpacts {
                                id,
                                impacts: 0,
                                ended: false,
                            });
                            r.groups.len() - 1
                        }
                    };
                    let mut state = r.groups[k];
                    self.group_impacts(t, y, &r.members, &mut state, &mut r.events, observer)?;
                    r.groups[k] = state;
                }
                changed = true;
                // A round whose laws gave no impulse (points that approach by rounding
                // noise only) goes on to the modes; it used to repeat until the rounds ran
                // out, and the modes were not selected.
                if !r.events.is_empty() {
                    impacts_here += r.events.len();
                    if let Some(stop) = self.ledger(t, &mut r.events, observer)? {
                        return Ok((true, Some(stop)));
                    }
                    continue;
                }
            }
            // The hops that start in the groups that had impacts (unless their
            // accumulation ended).
            r.hops.clear();
            r.hops.extend(
                (0..touching.len())
                    .filter(|&i| {
                        (r.groups.iter()).any(|g| g.id == group[i] && g.impacts > 0 && !g.ended)
                    })
                    .map(|i| touching[i]),
            );
            if !r.hops.is_empty() {
                self.remember_hops(t, &r.hops);
            }
            // 3. Modes of the touching points that do not separate.
            r.resting.clear();
            r.resting
                .extend((touching.iter()).filter(|p| p.v_n <= p.still).copied());
            // The points that start to slip and those that lift off at this instant (none
            // after impacts), taken out of their memos for the selection.
            if impacts_here == 0 {
                self.slip_starts_at(t, event);
                self.lift_offs_at(t, event);
            }
            let starts_to_slip = std::mem::take(&mut self.slip_starts.1);
            let lifting = std::mem::take(&mut self.lift_offs.1);
            let events: InstantEvents<'_> = if impacts_here == 0 {
                (&starts_to_slip[..], &lifting[..])
            } else {
                (&[], &[])
            };
            let selected = self.select_modes(t, y, &r.resting, events, observer, &mut r.closed);
            self.slip_starts.1 = starts_to_slip;
            self.lift_offs.1 = lifting;
            match selected? {
                Selected::Set => {
                    let before = self.closed_on(event);
                    changed |= self.set_closed(t, &r.closed, observer)?;
                    if impacts_here == 0 && !painleve_resolved {
                        self.disarm_open_crossing(event, before, &r.touching);
                    }
                    settled = true;
                    break;
                }
                Selected::Painleve(point) => {
                    if painleve_resolved {
                        let mut name = String::new();
                        write_pair_name(&mut name, self.model, point.pair);
                        return Err(SimError::Contact {
                            t,
                            message: format!(
                                "Painlevé's paradox on {name}: no consistent contact mode even \
                                 after an impact without collision"
                            ),
                        });
                    }
                    self.impact_without_collision(point, t, y, &mut r.events, observer)?;
                    painleve_resolved = true;
                    changed = true;
                }
            }
        }
        if !settled {
            // The sequential rule's pairwise impacts among touching bodies converge without
            // end when they are (nearly) plastic (five balls of a cradle with e = 0: the
            // approach speeds shrink ~12 % per impact); Moreau's law takes the group at once.
            let hint = if self.settings.simultaneous == Simultaneous::Sequential {
                "; the sequential rule's pairwise impacts may converge without end here (as \
                 for touching bodies with e = 0): simultaneous = \"generalized-newton\" \
                 resolves the group at once"
            } else {
                ""
            };
            return Err(SimError::Contact {
                t,
                message: format!(
                    "the impacts and contact modes at this instant did not settle in \
                     {MAX_ROUNDS} rounds ({impacts_here} impacts){hint}"
                ),
            });
        }
        if impacts_here > 0 {
            self.sample(t, y, true, observer)?;
        }
        Ok((changed, None))
    }

    /// After the impacts of a round: an approach slower than `v_drift` that they left is
    /// below what the laws resolve at this instant, and no longer counts as one until the
    /// instant ends (`touching` gets the raised threshold). A law leaves such an approach
    /// where the normal rows of the points are nearly dependent (a folded chain lying on
    /// itself and on the floor): the part of the velocity along their near-null direction
    /// needs an impulse beyond the rank the solvers resolve, and repeating the law repeats
    /// it (the 32-link chain with μ = 0.1 and e = 0: 4.7e-10 m/s left at t = 1.6784 s, the
    /// same impacts 1,000 times at that instant). Closed points already tolerate `v_drift`.
    fn leave_unresolved(&mut self, touching: &mut [Touch]) {
        let left = (touching.iter())
            .filter(|p| p.v_n < -p.still && -p.v_n <= self.scales.v_drift)
            .map(|p| -p.v_n)
            .fold(0.0, Real::max);
        // Twice what is left: the next round's rounding moves it a little.
        if left > self.unresolved.1 {
            self.unresolved.1 = (2.0 * left).min(self.scales.v_drift);
        }
        for p in touching.iter_mut() {
            p.still = p.still.max(self.unresolved.1);
        }
    }

    /// The number of closed points on the pair of a gap event (slot 0), if it is one.
    fn closed_on(&self, event: Option<&Event>) -> Option<(PairId, usize)> {
        let event = event?;
        (event.index % super::gaps::SLOTS == 0).then(|| {
            let pair = PairId(event.index / super::gaps::SLOTS);
            let count = self
                .gaps
                .persistent
                .closed()
                .iter()
                .filter(|c| c.pair == pair)
                .count();
            (pair, count)
        })
    }

    /// A gap event after which no point of its pair closed, with no impact: the crossing
    /// was rounding noise (a contact that separates just after an impact) or a grazing
    /// touch that separates. The pair's gap event is disarmed until that gap is clearly
    /// open, with steps short enough to see it close again.
    fn disarm_open_crossing(
        &mut self,
        event: Option<&Event>,
        before: Option<(PairId, usize)>,
        touching: &[Touch],
    ) {
        let (Some((pair, count)), Some((_, now))) = (before, self.closed_on(event)) else {
            return;
        };
        if now > count {
            return;
        }
        // A contact separating at v is clear of the tolerance after 10 gap_tol / v: steps no
        // longer than that see it close again, while this pair stays disarmed. A grazing
        // one (v ≈ 0) separates by its acceleration; the steps are left as they are.
        let v = (touching.iter())
            .filter(|p| p.pair == pair && p.v_n > p.still)
            .map(|p| p.v_n)
            .fold(Real::INFINITY, Real::min);
        let cap = if v.is_finite() {
            10.0 * self.scales.gap_tol / v
        } else {
            Real::INFINITY
        };
        // Its event moves below the gap it has now, by the tolerance: an open point at
        // rest at a hinge drifts by ~1e-11 m and must not stop the run each time.
        let gap = self
            .gaps
            .open_gap(pair, self.stepper.t(), self.stepper.y())
            .unwrap_or(0.0);
        let floor = gap.min(0.0) - self.scales.gap_tol;
        let until = self.stepper.t() + CAP_LIFETIME * cap;
        self.disarmed[pair.index()] = Some(super::Disarm { cap, floor, until });
        self.arm();
    }

    /// The material of a pair, after the overrides.
    fn material(&self, pair: PairId) -> Material {
        self.overrides.apply(self.model.pair_of(pair).material)
    }

    /// Every contact point within the closed-contact tolerance at `(t, y)`, with its
    /// velocities, into `out`.
    fn touching(&mut self, t: Real, y: &[Real], out: &mut Vec<Touch>) -> Result<(), SimError> {
        let (n, nqu) = (self.model.nq(), self.model.nq() + self.model.nu());
        let (q, u) = (&y[..n], &y[n..nqu]);
        update_positions(self.model, &mut self.sampler, t, q).map_err(|e| e.at(t))?;
        update_velocities(self.model, &mut self.sampler, u).map_err(|e| e.at(t))?;
        out.clear();
        // The pairs within the tolerance of contact are among those whose boxes, grown by
        // it, overlap (the broad phase).
        let mut near = std::mem::take(&mut self.scratch.near);
        let mut ws = std::mem::take(&mut self.scratch.manifolds);
        let result = self
            .near_pairs(t, self.scales.gap_tol, &mut near)
            .and_then(|()| self.touching_of(t, &near, &mut ws, out));
        self.scratch.near = near;
        self.scratch.manifolds = ws;
        result?;
        // The points held closed: the touching point of its pair nearest each closed point.
        for c in self.gaps.persistent.closed() {
            let nearest = (out.iter_mut())
                .filter(|p| p.pair == c.pair)
                .min_by(|x, y| {
                    (x.local - c.local)
                        .length()
                        .total_cmp(&(y.local - c.local).length())
                });
            if let Some(p) = nearest {
                p.still = self.scales.v_drift;
            }
        }
        Ok(())
    }

    /// The contact points of the `near` pairs within the closed-contact tolerance (the
    /// positions and velocities of `self.sampler`), into `out`.
    fn touching_of(
        &mut self,
        t: Real,
        near: &[PairId],
        ws: &mut ManifoldWorkspace,
        out: &mut Vec<Touch>,
    ) -> Result<(), SimError> {
        for &pair in near {
            for (contact, local) in
                pair_points(self.model, &self.sampler, pair, self.scales.gap_tol, ws)?
            {
                let point = (pair, contact);
                let frame = (self.map).frame_perp_in(self.model, &self.sampler, point, t)?;
                out.push(Touch {
                    pair,
                    contact,
                    local,
                    v_n: frame.v_n(),
                    still: self.scales.v_tiny.max(self.unresolved.1),
                });
            }
        }
        Ok(())
    }

    /// The touching points that do not separate faster than `bound` (or than they drift),
    /// with their materials, into `out`.
    fn points_below(
        &self,
        touching: &[Touch],
        bound: Real,
        out: &mut Vec<(PairId, PairContact, Material)>,
    ) {
        out.clear();
        out.extend(
            (touching.iter())
                .filter(|p| p.v_n <= bound.max(p.still))
                .map(|p| (p.pair, p.contact, self.material(p.pair))),
        );
    }

    /// Records impacts in the ledger and the audit, and reports them (`events` is left
    /// empty). A stop reason if impacts stall.
    fn ledger(
        &mut self,
        t: Real,
        events: &mut Vec<ImpactEvent>,
        observer: &mut dyn Observer,
    ) -> Result<Option<StopReason>, SimError> {
        for ev in events.iter_mut() {
            ev.index = self.counters.impacts;
            self.counters.impacts += 1;
            self.audit.impact_delta_e += ev.outcome.delta_e;
            self.audit.impact_prescribed_work += ev.prescribed_work();
            observer.impact(self.model, ev).map_err(|e| e.at(t))?;
            if let Some(reason) = self.guard.after_impact(t) {
                let pair = ev.frame.pair;
                self.map.recycle(events);
                return Ok(Some(self.stall(t, pair, reason)));
            }
        }
        self.map.recycle(events);
        Ok(None)
    }

    /// After the impacts at `t`: the fastest separation of the touching points of each pair
    /// that had an impact, the hop that starts.
    fn remember_hops(&mut self, t: Real, touching: &[Touch]) {
        for p in touching {
            let k = p.pair.index();
            let faster = match self.last_separation[k] {
                Some((tk, v)) if tk == t => p.v_n > v,
                _ => true,
            };
            if p.v_n > p.still && faster {
                self.last_separation[k] = Some((t, p.v_n));
            }
        }
    }

    /// The impacts of one group of coupled points at `t` (`touching`: the group's touching
    /// points, some approaching), with the accumulations they end, appended to `events`;
    /// `u` (in `y`) becomes `u⁺`. `state` counts the group's impacts at this instant.
    ///
    /// Which law: a point that approaches alone, as the first impact of its group at this
    /// instant (or with no other point of the group touching), gets the scene's one-point
    /// law [P]. Otherwise — several approach at once, or an impact made another touching
    /// point approach (a rod landing on one end strikes with the other) — the scene's rule
    /// for simultaneous impacts: Moreau's generalized Newton law over the group's touching
    /// points that do not separate, or (sequential) the one-point law on the most
    /// approaching point, the rounds that follow taking the next one.
    fn group_impacts(
        &mut self,
        t: Real,
        y: &mut [Real],
        touching: &[Touch],
        state: &mut GroupImpacts,
        events: &mut Vec<ImpactEvent>,
        observer: &mut dyn Observer,
    ) -> Result<(), SimError> {
        self.with_scratch(
            |s| &mut s.group,
            |sim, g| sim.group_impacts_in(t, y, touching, state, events, observer, g),
        )
    }

    /// [`Self::group_impacts`] in the buffers `g`.
    #[allow(clippy::too_many_arguments)]
    fn group_impacts_in(
        &mut self,
        t: Real,
        y: &mut [Real],
        touching: &[Touch],
        state: &mut GroupImpacts,
        events: &mut Vec<ImpactEvent>,
        observer: &mut dyn Observer,
        g: &mut GroupScratch,
    ) -> Result<(), SimError> {
        let (n, nqu) = (self.model.nq(), self.model.nq() + self.model.nu());
        let start = events.len();
        let approaching = &mut g.approaching;
        approaching.clear();
        approaching.extend((touching.iter()).filter(|p| p.v_n < -p.still).copied());
        let sequential = self.settings.simultaneous == Simultaneous::Sequential;
        let chosen = if sequential {
            (approaching.iter())
                .min_by(|a, b| a.v_n.total_cmp(&b.v_n))
                .copied()
        } else {
            let v_tiny = self.scales.v_tiny;
            let alone = approaching.len() == 1
                && (state.impacts == 0
                    || (touching.iter())
                        .filter(|p| p.v_n <= v_tiny.max(p.still))
                        .count()
                        == 1);
            alone.then(|| approaching[0])
        };
        let approaching = approaching.len();
        g.u_before.clear();
        g.u_before.extend_from_slice(&y[n..nqu]);
        // Once an accumulation ended at this instant, the impacts in cascade that follow
        // (the other end of a rod landing flat) are plastic too.
        let ended = state.ended;
        self.impact_round(t, y, touching, approaching, chosen, ended, events, observer)?;
        // 2. Accumulations: an impact that leaves a touching point separating too slowly
        // for its hop to be resolved is made plastic.
        if !state.ended {
            self.touching_in(t, y, state.id, &mut g.after)?;
            self.slow_separations(t, y, &g.after, &mut g.slow)?;
            if !g.slow.is_empty() {
                self.note_accumulations(t, &g.slow);
                y[n..nqu].copy_from_slice(&g.u_before);
                // A slow separation elsewhere than at the struck point: the plastic impact
                // takes the whole group (the generalized law), or stays one point at a time.
                let chosen = if sequential {
                    chosen
                } else {
                    chosen.filter(|c| g.slow.iter().all(|p| p.pair == c.pair))
                };
                self.map.recycle_from(events, start);
                self.impact_round(t, y, touching, approaching, chosen, true, events, observer)?;
                state.ended = true;
                // A rocking body: the plastic impact lifts another touching point, too
                // slowly to resolve; no impulse ≥ 0 holds it down.
                self.touching_in(t, y, state.id, &mut g.after)?;
                self.slow_separations(t, y, &g.after, &mut g.slow)?;
                if !g.slow.is_empty() {
                    g.held.clear();
                    g.held.extend(
                        (g.after.iter())
                            .filter(|p| p.v_n <= self.scales.v_rest.max(p.still))
                            .copied(),
                    );
                    self.rocking_end(t, y, &mut g.held, events)?;
                }
            }
        }
        state.impacts += events.len() - start;
        Ok(())
    }

    /// The touching points at `(t, y)` of the group `id` of coupled points, into `out`.
    fn touching_in(
        &mut self,
        t: Real,
        y: &[Real],
        id: usize,
        out: &mut Vec<Touch>,
    ) -> Result<(), SimError> {
        let mut all = std::mem::take(&mut self.scratch.all);
        let mut group = std::mem::take(&mut self.scratch.all_groups);
        let result = self.touching(t, y, &mut all);
        if result.is_ok() {
            (self.coupling).groups(self.model, all.iter().map(|p| p.pair), &mut group);
            out.clear();
            out.extend(
                (all.iter().zip(&group))
                    .filter(|(_, g)| **g == id)
                    .map(|(p, _)| *p),
            );
        }
        self.scratch.all = all;
        self.scratch.all_groups = group;
        result
    }

    /// One round of impacts at `t` on the `touching` points of a group, `approaching` of
    /// them approaching, appended to `events`: the one-point law of the scene on `chosen`,
    /// else Moreau's generalized Newton law over the touching points that do not separate;
    /// `u` (in `y`) becomes `u⁺`. `plastic`: the same law with `e = 0`, reported as the end
    /// of an accumulation.
    #[allow(clippy::too_many_arguments)]
    fn impact_round(
        &mut self,
        t: Real,
        y: &mut [Real],
        touching: &[Touch],
        approaching: usize,
        chosen: Option<Touch>,
        plastic: bool,
        events: &mut Vec<ImpactEvent>,
        observer: &mut dyn Observer,
    ) -> Result<(), SimError> {
        let (n, nqu) = (self.model.nq(), self.model.nq() + self.model.nu());
        let plastic_material = |m: Material| if plastic { Material { e: 0.0, ..m } } else { m };
        let start = events.len();
        let (q, u) = y[..nqu].split_at_mut(n);
        if let Some(p) = chosen {
            let material = plastic_material(self.material(p.pair));
            let ev = self
                .map
                .apply_at(self.model, (p.pair, p.contact), material, None, t, q, u)?;
            events.extend(ev);
        } else {
            // Several points approach at once, or an impact made another touching point
            // approach (a rod landing on one end strikes with the other).
            let mut points = std::mem::take(&mut self.scratch.points);
            self.points_below(touching, self.scales.v_tiny, &mut points);
            for p in &mut points {
                p.2 = plastic_material(p.2);
            }
            let mut result = Ok(());
            if !plastic {
                let what = if approaching > 1 {
                    "simultaneous impact"
                } else {
                    "impacts in cascade at one instant"
                };
                let text = &mut self.scratch.text;
                text.clear();
                let _ = write!(
                    text,
                    "{what} of {} contact points: Moreau's generalized Newton law with \
                     Coulomb friction",
                    points.len()
                );
                result = observer
                    .message(t, Level::Warning, text)
                    .map_err(|e| e.at(t));
            }
            let result =
                result.and_then(|()| self.map.apply_many(self.model, &points, t, q, u, events));
            self.scratch.points = points;
            result?;
        }
        if plastic {
            for ev in &mut events[start..] {
                ev.cause = ImpactCause::AccumulationEnd;
            }
        }
        Ok(())
    }

    /// The touching points of `after` (at `(t, y)`, just after an impact) that separate,
    /// but slower than their resting speed ([`super::Scales::v_rest_at`] of their normal
    /// acceleration with no contact force), into `slow`: the hops they start are too small
    /// to resolve.
    fn slow_separations(
        &mut self,
        t: Real,
        y: &[Real],
        after: &[Touch],
        slow: &mut Vec<Touch>,
    ) -> Result<(), SimError> {
        // Only points slower than the resting speed of a thousand times |g| are candidates.
        let cap = 1e3_f64.sqrt() * self.scales.v_rest;
        slow.clear();
        slow.extend(
            (after.iter())
                .filter(|p| p.v_n > p.still && p.v_n <= cap)
                .copied(),
        );
        if slow.is_empty() {
            return Ok(());
        }
        let sel = self.select_filled(t, y, Real::INFINITY, |_, points| {
            points.extend(slow.iter().map(|p| Candidate {
                pair: p.pair,
                local: p.local,
                mu: 0.0,
                slip: None,
            }));
        })?;
        let mut free = sel.free.iter();
        slow.retain(|p| {
            free.next()
                .is_some_and(|a_n| p.v_n <= self.scales.v_rest_at(*a_n))
        });
        self.system.persistent.recycle_selection(sel);
        Ok(())
    }

    /// The end of a rocking accumulation at `t` (`u` in `y` just after the plastic impact
    /// that ends an accumulation): the jump that brings the `held` points to rest
    /// ([`ImpactMap::close`]), and the [`Support`] of each entry.
    ///
    /// A point whose entry would still pull (`I_n = P_n + S_n < 0`: the jump pulled it
    /// down and the contact mode that follows does not press it — the other points' forces
    /// lift it, as along a chain lying on the floor, where a link's end rises while its
    /// neighbour is pressed) is not a rocking corner: nothing brings it back, so there are
    /// no hops to sum. It is released (no impulse; it keeps its slow separation) and the
    /// jump is done again on the others, until no entry pulls or every point would be
    /// released. A released point that the new jump makes approach is held again (the
    /// jump must not leave a touching point approaching). A point that barely slipped and
    /// was stopped by an entry outside the friction cone (`|I_t| > μ I_n`: friction could
    /// not have stopped its hops' slip) slips instead, against its friction,
    /// `P_t = −μ s P_n` with `s = −sign I_t`, and the jump is done again.
    fn rocking_end(
        &mut self,
        t: Real,
        y: &mut [Real],
        held: &mut Vec<Touch>,
        events: &mut Vec<ImpactEvent>,
    ) -> Result<(), SimError> {
        self.with_scratch(
            |s| &mut s.rocking,
            |sim, r| sim.rocking_end_in(t, y, held, events, r),
        )
    }

    /// [`Self::rocking_end`] in the buffers `r`.
    fn rocking_end_in(
        &mut self,
        t: Real,
        y: &mut [Real],
        held: &mut Vec<Touch>,
        events: &mut Vec<ImpactEvent>,
        r: &mut RockingScratch,
    ) -> Result<(), SimError> {
        let (n, nqu) = (self.model.nq(), self.model.nq() + self.model.nu());
        r.u_plastic.clear();
        r.u_plastic.extend_from_slice(&y[n..nqu]);
        r.released.clear();
        // The slip each held point is made to take (`None`: the jump decides).
        let slides = &mut r.slides;
        slides.clear();
        slides.resize(held.len(), None);
        // A bound on the rounds (a point released, held again, made to slip…); the last
        // jump stands.
        let last = 3 * held.len();
        let mut round = 0;
        // The violation of the round that came closest to the conditions so far, its
        // `u` in `r.best_u` and its entries in `r.best`.
        let mut best: Option<Real> = None;
        loop {
            // Every held point, in order (`slides` is indexed like `held`).
            self.points_below(held, Real::INFINITY, &mut r.points);
            let (q, u) = y[..nqu].split_at_mut(n);
            self.map.recycle(&mut r.closing);
            let v_rest = self.scales.v_rest;
            (self.map).close(
                self.model,
                &r.points,
                slides,
                v_rest,
                t,
                q,
                u,
                &mut r.closing,
            )?;
            self.support(t, y, held, &mut r.closing)?;
            let closing = &r.closing;
            let nearest = |p: Vec2, set: &[Touch]| {
                (0..set.len()).min_by(|&i, &j| {
                    let d = |k: usize| (set[k].contact.point_a - p).length();
                    d(i).total_cmp(&d(j))
                })
            };
            // The held point of each entry.
            r.of_entry.clear();
            (r.of_entry).extend((closing.iter()).map(|ev| nearest(ev.frame.point(), held)));
            let pulled = &mut r.pulled;
            pulled.clear();
            pulled.extend(
                (closing.iter().zip(&r.of_entry))
                    .filter(|(ev, _)| ev.impulse().n < 0.0)
                    .filter_map(|(_, k)| *k),
            );
            pulled.sort_unstable();
            pulled.dedup();
            // Released points the jump made approach are held again.
            r.approaching.clear();
            if !r.released.is_empty() {
                self.touching(t, y, &mut r.now)?;
                let (now, released) = (&r.now, &r.released);
                r.approaching.extend((0..released.len()).filter(|&i| {
                    let rel = &released[i];
                    (now.iter())
                        .filter(|p| p.pair == rel.pair)
                        .min_by(|a, b| {
                            let d = |p: &Touch| (p.local - rel.local).length();
                            d(a).total_cmp(&d(b))
                        })
                        .is_some_and(|p| p.v_n < -p.still)
                }));
            }
            // Stopped points whose entry is outside the cone, and the slip they take.
            r.outside.clear();
            r.outside
                .extend((closing.iter().zip(&r.of_entry)).filter_map(|(ev, k)| {
                    let (i, mu) = (ev.impulse(), ev.material.mu);
                    let slack = 4.0 * Real::EPSILON * (i.n.abs() + i.t.abs());
                    let k = (*k)?;
                    (slides[k].is_none() && i.t.abs() > mu * i.n + slack)
                        .then(|| (k, -i.t.signum()))
                }));
            let released_all = pulled.is_empty() || pulled.len() == held.len();
            // How far the entries are from impulses ≥ 0 in the cone, and from leaving no
            // touching point approaching (N·s; m/s for those).
            let violation: Real = (closing.iter())
                .map(|ev| {
                    let i = ev.impulse();
                    (-i.n).max(0.0) + (i.t.abs() - ev.material.mu * i.n).max(0.0)
                })
                .sum::<Real>()
                + if r.approaching.is_empty() {
                    0.0
                } else {
                    Real::INFINITY
                };
            if best.is_none_or(|b| violation < b) {
                best = Some(violation);
                r.best_u.clear();
                r.best_u.extend_from_slice(&y[n..nqu]);
                self.map.recycle(&mut r.best);
                std::mem::swap(&mut r.best, &mut r.closing);
            }
            if round == last || (r.approaching.is_empty() && released_all && r.outside.is_empty()) {
                // The round that came closest to the conditions (this one, unless an
                // earlier one came closer).
                y[n..nqu].copy_from_slice(&r.best_u);
                events.append(&mut r.best);
                return Ok(());
            } else if !r.approaching.is_empty() {
                for &i in r.approaching.iter().rev() {
                    held.push(r.released.remove(i));
                    slides.push(None);
                }
            } else if !released_all {
                for &i in pulled.iter().rev() {
                    r.released.push(held.remove(i));
                    slides.remove(i);
                }
            } else {
                for &(k, s) in &r.outside {
                    slides[k] = Some(s);
                }
            }
            y[n..nqu].copy_from_slice(&r.u_plastic);
            round += 1;
        }
    }

    /// The [`Support`] of each entry of a rocking end at `t` (`y` just after its jump): the
    /// persistent contact force `λ` of the `held` points at that state, times the time
    /// `t∞ − t` the hops left would have lasted (the latest `t∞` of the pairs; at least the
    /// lifting point's own hop, `2 v_n⁻ / |a_n|` with the most negative free normal
    /// acceleration of the held points, when `t∞` could not be extrapolated). `λ` is that
    /// of the consistent set of modes the mode selection that follows takes first
    /// ([`most_open`]).
    fn support(
        &mut self,
        t: Real,
        y: &[Real],
        held: &[Touch],
        closing: &mut [ImpactEvent],
    ) -> Result<(), SimError> {
        let until = (held.iter())
            .filter_map(|p| self.accumulating[p.pair.index()].as_ref()?.t_inf)
            .fold(t, Real::max);
        // The lifting points' own hops: v_n⁻ / |a_n| up and as long down.
        let hop = (closing.iter())
            .filter(|ev| ev.v_a.n > 0.0)
            .map(|ev| ev.v_a.n)
            .fold(0.0, Real::max);
        let v_slip = 1e3 * self.scales.v_tiny;
        let sel = self.select_filled(t, y, v_slip, |sim, candidates| {
            candidates.extend(held.iter().map(|p| Candidate {
                pair: p.pair,
                local: p.local,
                mu: sim.material(p.pair).mu,
                slip: None,
            }));
        })?;
        let Some(chosen) = most_open_first(&sel.solutions) else {
            return Err(SimError::Contact {
                t,
                message: "the end of a rocking accumulation: the closed contacts have no \
                          consistent mode"
                    .to_owned(),
            });
        };
        let a_lift = (sel.free.iter().copied()).fold(0.0, |m: Real, a| m.min(a));
        let own = if a_lift < 0.0 {
            2.0 * hop / -a_lift
        } else {
            0.0
        };
        let duration = (until - t).max(own);
        for ev in closing.iter_mut() {
            let Some(i) = (0..sel.points.len()).min_by(|&i, &j| {
                let d = |k: usize| (sel.points[k].frame.point() - ev.frame.point()).length();
                d(i).total_cmp(&d(j))
            }) else {
                continue;
            };
            let f = &sel.points[i].frame;
            let force = chosen.x[2 * i] * f.n + chosen.x[2 * i + 1] * f.t;
            ev.support = Some(Support {
                impulse: Impulse::new(
                    duration * force.dot(ev.frame.n),
                    duration * force.dot(ev.frame.t),
                ),
                duration,
            });
        }
        self.system.persistent.recycle_selection(sel);
        Ok(())
    }

    /// An accumulation of impacts ends at `t` on the pairs of the `slow` points (the hop
    /// after the impact too small to resolve). Extrapolates the time `t∞` the hops would
    /// end, from the last hop of each pair: with `r = v / v_prev` the ratio of successive
    /// separation speeds and `Δt = t − t_prev` the last hop's duration, the hops left last
    /// `Σ_{k≥1} rᵏ Δt = Δt r / (1 − r)` (exact for hops of constant deceleration, the
    /// bouncing ball; the small-amplitude limit of rocking). The passage to persistent
    /// contact is reported at `t∞` ([`Self::set_closed`]).
    fn note_accumulations(&mut self, t: Real, slow: &[Touch]) {
        let mut pairs = std::mem::take(&mut self.scratch.accumulations);
        pairs.clear();
        for p in slow {
            match pairs.iter_mut().find(|(pair, _)| *pair == p.pair) {
                Some((_, v)) => *v = v.max(p.v_n),
                None => pairs.push((p.pair, p.v_n)),
            }
        }
        for &(pair, v) in &pairs {
            let k = pair.index();
            let extrapolated = match self.last_separation[k] {
                Some((t_prev, v_prev)) if t_prev < t && v < v_prev => {
                    let r = v / v_prev;
                    Some((t + (t - t_prev) * r / (1.0 - r), r))
                }
                _ => None,
            };
            self.accumulating[k] = Some(Accumulation {
                t_inf: extrapolated.map(|x| x.0),
                t,
                v,
                ratio: extrapolated.map(|x| x.1),
            });
            self.last_separation[k] = None;
        }
        self.scratch.accumulations = pairs;
    }

    /// [`Self::select_at`] of the candidates that `fill` writes into the kept candidate
    /// list (emptied first).
    fn select_filled(
        &mut self,
        t: Real,
        y: &[Real],
        v_slip: Real,
        fill: impl FnOnce(&Self, &mut Vec<Candidate>),
    ) -> Result<Selection, SimError> {
        self.with_scratch(
            |s| &mut s.candidates,
            |sim, candidates| {
                candidates.clear();
                fill(sim, candidates);
                sim.select_at(t, y, candidates, v_slip)
            },
        )
    }

    /// The mode selection of `candidates` at `(t, y)` ([`Persistent::select`] on the
    /// forward dynamics of that state), with the closed set put back in the ODE system
    /// afterwards.
    fn select_at(
        &mut self,
        t: Real,
        y: &[Real],
        candidates: &[Candidate],
        v_slip: Real,
    ) -> Result<Selection, SimError> {
        let (n, nqu) = (self.model.nq(), self.model.nq() + self.model.nu());
        let (q, u) = (&y[..n], &y[n..nqu]);
        forward_dynamics(self.model, &mut self.sampler, t, q, u).map_err(|e| e.at(t))?;
        let sel = (self.system.persistent).select(
            self.model,
            &mut self.sampler,
            (t, q, u),
            candidates,
            v_slip,
        );
        self.restore_persistent();
        sel
    }

    /// Puts the closed set back in the ODE system after a selection used its workspace.
    fn restore_persistent(&mut self) {
        let gaps = &self.gaps.persistent;
        (self.system.persistent).set_from(gaps.closed(), gaps.mus());
    }

    /// The closed point whose friction margin `μ λ_n − |λ_t|` crossed zero at `event`, if
    /// that is the event: its pair, its point on `a` and the direction in which it starts
    /// to slip, `s = −sign λ_t` (the friction opposes the slip).
    fn starts_to_slip(&self, event: Option<&Event>) -> Option<(PairId, Vec2, Real)> {
        let event = event?;
        let (pair, s) = (
            PairId(event.index / super::gaps::SLOTS),
            event.index % super::gaps::SLOTS,
        );
        if s == 0 || (s - 1) % 3 != 1 {
            return None;
        }
        let persistent = &self.gaps.persistent;
        let i = (0..persistent.closed().len())
            .filter(|&i| persistent.closed()[i].pair == pair)
            .nth((s - 1) / 3)?;
        let c = persistent.closed()[i];
        (c.hold == Hold::Stick).then(|| (pair, c.local, -persistent.force(i).1.signum()))
    }

    /// The closed point whose normal force `λ_n` crossed zero at `event`, if that is the
    /// event (a lift-off): its pair and its point on `a`.
    fn lifts_off(&self, event: Option<&Event>) -> Option<(PairId, Vec2)> {
        let event = event?;
        let (pair, s) = (
            PairId(event.index / super::gaps::SLOTS),
            event.index % super::gaps::SLOTS,
        );
        if s == 0 || (s - 1) % 3 != 0 {
            return None;
        }
        let persistent = &self.gaps.persistent;
        let c = (persistent.closed().iter())
            .filter(|c| c.pair == pair)
            .nth((s - 1) / 3)?;
        Some((pair, c.local))
    }

    /// The points that lift off at this instant, into `self.lift_offs`: the point of `event`
    /// if its normal force crossed zero, with those of the events before it at the same
    /// instant (`|Δt| ≤ 1e-9 (1 + |t|)`); see `open_lifting_points`.
    fn lift_offs_at(&mut self, t: Real, event: Option<&Event>) {
        let lift = self.lifts_off(event);
        let near = self.scales.gap_tol;
        through_the_instant(&mut self.lift_offs, t, lift, |a, b| {
            a.0 == b.0 && (a.1 - b.1).length() <= near
        })
    }

    /// The points that start to slip at this instant, into `self.slip_starts`: the point of
    /// `event` if it is a sticking point at the edge of its cone, with those of the events
    /// before it at the same instant (`|Δt| ≤ 1e-9 (1 + |t|)`). A point that started to
    /// slip keeps its slip through the instant: otherwise two points at the edge of their
    /// cones, sharing one load (a link lying on the floor, hinged to its neighbour), took
    /// turns — each selection let the other one stick at its edge, whose slip event came at
    /// once (the 8-link chain stalled at t = 4.8315 s, 1000 events).
    fn slip_starts_at(&mut self, t: Real, event: Option<&Event>) {
        let start = self.starts_to_slip(event);
        let near = self.scales.gap_tol;
        through_the_instant(&mut self.slip_starts, t, start, |a, b| {
            a.0 == b.0 && (a.1 - b.1).length() <= near
        })
    }

    /// Selects the modes of the resting points, group by group of coupled points (each a
    /// separate problem, see `coupling`); the closed points, in the order of `resting`, into
    /// `closed`.
    fn select_modes(
        &mut self,
        t: Real,
        y: &[Real],
        resting: &[Touch],
        events: InstantEvents<'_>,
        observer: &mut dyn Observer,
        closed: &mut Vec<Closed>,
    ) -> Result<Selected, SimError> {
        self.with_scratch(
            |s| &mut s.select,
            |sim, g| {
                (sim.coupling).groups(sim.model, resting.iter().map(|p| p.pair), &mut g.group);
                super::coupling::distinct(g.group.iter().copied(), &mut g.ids);
                if g.ids.len() <= 1 {
                    sim.select_group(t, y, resting, events, observer, closed)
                } else {
                    sim.select_groups(t, y, resting, events, observer, closed, g)
                }
            },
        )
    }

    /// [`Self::select_modes`] of several groups, in the buffers `g` (`g.group`: the group
    /// of each resting point, `g.ids` the groups).
    #[allow(clippy::too_many_arguments)]
    fn select_groups(
        &mut self,
        t: Real,
        y: &[Real],
        resting: &[Touch],
        events: InstantEvents<'_>,
        observer: &mut dyn Observer,
        closed: &mut Vec<Closed>,
        g: &mut SelectScratch,
    ) -> Result<Selected, SimError> {
        // Each closed point with its resting point and the order it came in (which breaks
        // the ties of the points not found, as a stable sort would).
        g.sorted.clear();
        for &id in &g.ids {
            g.index.clear();
            (g.index).extend((0..resting.len()).filter(|&i| g.group[i] == id));
            g.members.clear();
            (g.members).extend(g.index.iter().map(|&i| resting[i]));
            match self.select_group(t, y, &g.members, events, observer, &mut g.set)? {
                Selected::Set => {
                    for &c in &g.set {
                        let at = (g.index.iter().copied())
                            .find(|&i| resting[i].pair == c.pair && resting[i].local == c.local)
                            .unwrap_or(usize::MAX);
                        g.sorted.push((at, g.sorted.len(), c));
                    }
                }
                painleve => return Ok(painleve),
            }
        }
        g.sorted.sort_unstable_by_key(|c| (c.0, c.1));
        closed.clear();
        closed.extend(g.sorted.iter().map(|c| c.2));
        Ok(Selected::Set)
    }

    /// Selects the modes of the resting points of one group; the closed points into
    /// `closed`. The points of `starts_to_slip` (sticking points at the edge of their
    /// friction cones) may open or slide, not stick: at the event both are consistent to
    /// rounding, and sticking would cross the edge again at once.
    fn select_group(
        &mut self,
        t: Real,
        y: &[Real],
        resting: &[Touch],
        events: InstantEvents<'_>,
        observer: &mut dyn Observer,
        closed: &mut Vec<Closed>,
    ) -> Result<Selected, SimError> {
        closed.clear();
        if resting.is_empty() {
            return Ok(Selected::Set);
        }
        self.with_scratch(
            |s| &mut s.select_group,
            |sim, g| sim.select_group_in(t, y, resting, events, observer, closed, g),
        )
    }

    /// [`Self::select_group`] of a non-empty group, in the buffers `g`.
    #[allow(clippy::too_many_arguments)]
    fn select_group_in(
        &mut self,
        t: Real,
        y: &[Real],
        resting: &[Touch],
        (starts_to_slip, lifting): InstantEvents<'_>,
        observer: &mut dyn Observer,
        closed: &mut Vec<Closed>,
        g: &mut GroupSelectScratch,
    ) -> Result<Selected, SimError> {
        // For each point that starts to slip, the resting point nearest it, and its slip.
        let slips = &mut g.slips;
        slips.clear();
        slips.resize(resting.len(), None);
        for &(pair, local, s) in starts_to_slip {
            let nearest = (0..resting.len())
                .filter(|&i| resting[i].pair == pair)
                .min_by(|&i, &j| {
                    (resting[i].local - local)
                        .length()
                        .total_cmp(&(resting[j].local - local).length())
                });
            if let Some(i) = nearest {
                slips[i] = Some(s);
            }
        }
        let v_slip = 1e3 * self.scales.v_tiny;
        let mut sel = self.select_filled(t, y, v_slip, |sim, candidates| {
            candidates.extend(
                (resting.iter().zip(slips.iter())).map(|(p, slip)| Candidate {
                    pair: p.pair,
                    local: p.local,
                    mu: sim.material(p.pair).mu,
                    slip: *slip,
                }),
            );
        })?;
        // A point that starts to slip from rest must slip the way its acceleration goes:
        // a solution that slows it down (s ẇ_t < 0 beyond rounding) is no start of a slip —
        // its slip would stop at once, and the selection would take it again (the 8-link
        // chain stalled so at t = 5.0309 s). Forced slips of moving points are not checked.
        let scale_w = sel.free.iter().fold(0.0, |m: Real, b| m.max(b.abs()));
        let starts = &mut g.starts;
        starts.clear();
        starts.extend(
            (0..resting.len())
                .filter_map(|i| Some((i, slips[i]?)))
                .filter(|&(i, _)| sel.points[i].v_t.abs() <= v_slip),
        );
        if !starts.is_empty() {
            let consistent = |so: &lcp::Solution| {
                starts.iter().all(|&(i, s)| match so.modes[i] {
                    Mode::Slide(_) => {
                        s * so.w[2 * i + 1] >= -1e-9 * scale_w.max(Real::MIN_POSITIVE)
                    }
                    _ => true,
                })
            };
            if sel.solutions.iter().any(consistent) {
                sel.solutions.retain(consistent);
            }
        }
        let sliding_painleve = |i: usize| sel.painleve[i] <= 0.0;
        let chosen = match sel.solutions.len() {
            0 => {
                return match (0..resting.len()).find(|&i| sliding_painleve(i)) {
                    Some(i) => {
                        let text = &mut self.scratch.text;
                        text.clear();
                        text.push_str("Painlevé's paradox on ");
                        write_pair_name(text, self.model, resting[i].pair);
                        let _ = write!(
                            text,
                            " at t = {t} s: sliding is inconsistent (Painlevé coefficient \
                             {:.4e} ≤ 0, no non-negative normal force holds the contact); \
                             resolved by an impact without collision",
                            sel.painleve[i]
                        );
                        observer
                            .message(t, Level::Warning, text)
                            .map_err(|e| e.at(t))?;
                        Ok(Selected::Painleve(resting[i]))
                    }
                    None => Err(SimError::Contact {
                        t,
                        message: "the persistent contacts have no consistent mode".to_owned(),
                    }),
                };
            }
            1 => &sel.solutions[0],
            count => {
                // The least constraint: the most open points. A choice undone at once (the
                // next event at the same instant asks again) gives way to the next one in
                // that order, so the selection cannot chatter between the same sets.
                most_open(&sel.solutions, &mut g.ranked);
                let (t_prev, undone) = self.indeterminate;
                let undone = if t - t_prev <= 1e-9 * (1.0 + t.abs()) {
                    undone + 1
                } else {
                    0
                };
                self.indeterminate = (t, undone);
                // One pass through the alternatives; then the first again.
                let pick = if undone < g.ranked.len() { undone } else { 0 };
                let chosen = &sel.solutions[g.ranked[pick]];
                let text = &mut self.scratch.text;
                text.clear();
                let mut painleve = (0..resting.len()).filter(|&i| sliding_painleve(i));
                match painleve.next() {
                    None => text.push_str("the contact modes are not unique"),
                    Some(first) => {
                        text.push_str("Painlevé's paradox on ");
                        write_pair_name(text, self.model, resting[first].pair);
                        for i in painleve {
                            text.push_str(", ");
                            write_pair_name(text, self.model, resting[i].pair);
                        }
                        text.push_str(": the contact modes are indeterminate");
                    }
                }
                let _ = if pick == 0 {
                    write!(
                        text,
                        " at t = {t} s ({count} consistent sets); chose the one with the most \
                         open contacts"
                    )
                } else {
                    write!(
                        text,
                        " at t = {t} s ({count} consistent sets); the last choice was undone \
                         at once: chose the next one by open contacts (#{})",
                        pick + 1
                    )
                };
                observer
                    .message(t, Level::Warning, text)
                    .map_err(|e| e.at(t))?;
                chosen
            }
        };
        let opened = self.open_lifting_points(resting, lifting, &sel, chosen);
        let chosen = opened.as_ref().unwrap_or(chosen);
        let previous = self.gaps.persistent.closed();
        let near = 1e-6 * self.scales.length;
        closed.extend(
            (resting.iter().zip(&chosen.modes).zip(&sel.points))
                .enumerate()
                .filter_map(|(i, ((p, m), point))| {
                    let hold = match *m {
                        Mode::Open => return None,
                        Mode::Stick => Hold::Stick,
                        Mode::Slide(s) => Hold::Slide(s),
                    };
                    // A point that slid the same way keeps its margin; one that starts to
                    // slide from rest gets one — also one that slid the same way but whose
                    // slip has stopped (its slip-stop event brought it here): without a
                    // margin its event is at once again (the 32-link chain with μ = 0.1,
                    // e = 0.6 at 2.5315 s: a second point of link25/link27 sliding at
                    // v_t = 1.4e-17 m/s with margin 0, its slip-stop event 1,000 times).
                    let before = (previous.iter())
                        .find(|c| c.pair == p.pair && (c.local - p.local).length() <= near)
                        .filter(|c| c.hold == hold);
                    let fresh = |s: Real| (-s * point.v_t).max(0.0) + SLIP_MARGIN * v_slip;
                    let slip_margin = match (hold, before) {
                        (Hold::Slide(s), Some(c)) if s * point.v_t + c.slip_margin <= 0.0 => {
                            c.slip_margin.max(fresh(s))
                        }
                        (_, Some(c)) => c.slip_margin,
                        (Hold::Slide(s), None) if point.v_t.abs() <= v_slip => fresh(s),
                        _ => 0.0,
                    };
                    Some(Closed {
                        pair: p.pair,
                        local: p.local,
                        hold,
                        slip_margin,
                        reference: (chosen.x[2 * i], chosen.x[2 * i + 1]),
                    })
                }),
        );
        self.system.persistent.recycle_selection(sel);
        Ok(Selected::Set)
    }

    /// **Lift-offs stay through the instant**: the selection's modes with the points that
    /// lift off at this instant (`lifting`, see `lift_offs_at`) opened, where the chosen
    /// solution keeps one closed with a normal force that is zero to rounding
    /// (`x_n ≤ 1e-6` of the largest force) and the same forces without that point's still
    /// meet every condition with it open (`lcp::conditions_violation` ≤ `CHECK_TOL`: its
    /// `w_n ≥ 0`, the others' equations to rounding); `None` if nothing changes.
    /// At such a point both are solutions — complementarity holds with `x_n = w_n = 0` —
    /// and keeping it closed brings its lift-off event back at once: Lemke's one solution
    /// kept the end of a link of the 32-link chain closed with 1.2e-9 N, and its lift-off
    /// came back 1000 times at t = 5.8354 s. The enumeration's rule (the most open points)
    /// prefers the open point too.
    fn open_lifting_points(
        &self,
        resting: &[Touch],
        lifting: &[(PairId, Vec2)],
        sel: &Selection,
        chosen: &lcp::Solution,
    ) -> Option<lcp::Solution> {
        let scale = chosen.x.amax();
        let mut best: Option<lcp::Solution> = None;
        for &(pair, local) in lifting {
            let current = best.as_ref().unwrap_or(chosen);
            let Some(i) = (0..resting.len())
                .filter(|&i| resting[i].pair == pair)
                .min_by(|&i, &j| {
                    (resting[i].local - local)
                        .length()
                        .total_cmp(&(resting[j].local - local).length())
                })
            else {
                continue;
            };
            if current.modes[i] == Mode::Open || current.x[2 * i] > 1e-6 * scale {
                continue;
            }
            // The same forces without this point's: a change of the others' (a new split
            // of redundant points' forces) is no part of a lift-off.
            let mut open = current.clone();
            open.modes[i] = Mode::Open;
            open.x[2 * i] = 0.0;
            open.x[2 * i + 1] = 0.0;
            open.w = &sel.a * &open.x + &sel.b;
            if lcp::conditions_violation(&sel.a, &sel.b, &sel.allowed, &open) <= lcp::CHECK_TOL {
                best = Some(open);
            }
        }
        best
    }

    /// Installs a new closed set; reports the pairs whose mode changed. Whether it changed.
    fn set_closed(
        &mut self,
        t: Real,
        closed: &[Closed],
        observer: &mut dyn Observer,
    ) -> Result<bool, SimError> {
        let same = closed.len() == self.gaps.persistent.closed().len()
            && closed
                .iter()
                .zip(self.gaps.persistent.closed())
                .all(|(a, b)| {
                    a.pair == b.pair
                        && a.hold == b.hold
                        && (a.local - b.local).length() <= 1e-6 * self.scales.length
                });
        let mut mu = std::mem::take(&mut self.scratch.mu);
        mu.clear();
        mu.extend(closed.iter().map(|c| self.material(c.pair).mu));
        self.system.persistent.set_from(closed, &mu);
        self.gaps.set_closed(closed, &mu);
        self.scratch.mu = mu;
        // The pairs whose mode may change: closed now, not free before, pending or
        // accumulating (every other pair stays free).
        let mut pairs = std::mem::take(&mut self.scratch.pairs);
        pairs.clear();
        pairs.extend(
            (self.gaps.persistent.closed().iter())
                .map(|c| c.pair)
                .chain(self.modes.changed())
                .chain(self.passages.iter().map(|p| p.pair))
                .chain(self.accumulating.stored()),
        );
        pairs.sort_unstable();
        pairs.dedup();
        let result = pairs
            .iter()
            .try_for_each(|&pair| self.report_mode(t, pair, observer));
        self.scratch.pairs = pairs;
        result.map(|()| !same)
    }

    /// After a new closed set: reports the change of mode of `pair` at `t`, if it changed,
    /// or makes it pending until `t∞` at the end of an accumulation.
    fn report_mode(
        &mut self,
        t: Real,
        pair: PairId,
        observer: &mut dyn Observer,
    ) -> Result<(), SimError> {
        let k = pair.index();
        let holds = self
            .gaps
            .persistent
            .closed()
            .iter()
            .filter(|c| c.pair == pair)
            .map(|c| c.hold);
        let mut mode = PairMode::Free;
        let mut slip = 0i8;
        for h in holds {
            mode = match (mode, h) {
                (PairMode::Sliding, _) | (_, Hold::Slide(_)) => PairMode::Sliding,
                _ => PairMode::Sticking,
            };
            if let (Hold::Slide(s), 0) = (h, slip) {
                slip = if s > 0.0 { 1 } else { -1 };
            }
        }
        let (current, current_slip) = self.current_mode(pair);
        if let Some(acc) = self.accumulating[k].take() {
            // The end of an accumulation: the passage to the mode it enters is
            // reported at t∞, when the hops it replaced would have ended.
            self.flush_passages_of(pair, t, observer)?;
            self.passages.push(Passage {
                t: acc.t_inf.unwrap_or(t).max(t),
                pair,
                from: current,
                to: mode,
                slip,
                accumulation: acc,
            });
        } else if mode != current || (mode == PairMode::Sliding && slip != current_slip) {
            self.flush_passages_of(pair, t, observer)?;
            let note = if mode == current {
                Note::Reverses(slip)
            } else {
                Note::Change
            };
            self.modes[k] = mode;
            self.slips[k] = slip;
            self.report(t, pair, (current, mode), note, observer)?;
        }
        Ok(())
    }

    /// The mode and slip direction of `pair` after its pending passage, if any.
    fn current_mode(&self, pair: PairId) -> (PairMode, i8) {
        let k = pair.index();
        (self.passages.iter().rev())
            .find(|p| p.pair == pair)
            .map_or((self.modes[k], self.slips[k]), |p| (p.to, p.slip))
    }

    /// Reports the pending passages (ends of accumulations) stamped at or before `upto`,
    /// in time order.
    pub(super) fn flush_passages(
        &mut self,
        upto: Real,
        observer: &mut dyn Observer,
    ) -> Result<(), SimError> {
        while let Some(i) = (0..self.passages.len())
            .filter(|&i| self.passages[i].t <= upto)
            .min_by(|&i, &j| self.passages[i].t.total_cmp(&self.passages[j].t))
        {
            let p = self.passages.remove(i);
            self.emit_passage(p, observer)?;
        }
        Ok(())
    }

    /// Reports the pending passage of `pair` before a new change of its mode at `t`: at
    /// `t` if it was stamped later (the mode changes again before the hops would end).
    fn flush_passages_of(
        &mut self,
        pair: PairId,
        t: Real,
        observer: &mut dyn Observer,
    ) -> Result<(), SimError> {
        while let Some(i) = self.passages.iter().position(|p| p.pair == pair) {
            let mut p = self.passages.remove(i);
            p.t = p.t.min(t);
            self.emit_passage(p, observer)?;
        }
        Ok(())
    }

    /// Makes a pending passage the mode shown, and reports it at its time.
    fn emit_passage(&mut self, p: Passage, observer: &mut dyn Observer) -> Result<(), SimError> {
        self.modes[p.pair.index()] = p.to;
        self.slips[p.pair.index()] = p.slip;
        let note = Note::Passage(p.accumulation);
        self.report(p.t, p.pair, (p.from, p.to), note, observer)
    }

    /// Reports a change of mode of `pair` on the log and to the observer: the kept
    /// [`Transition`] and message text rewritten.
    fn report(
        &mut self,
        t: Real,
        pair: PairId,
        (from, to): (PairMode, PairMode),
        note: Note,
        observer: &mut dyn Observer,
    ) -> Result<(), SimError> {
        let t_accumulation = match note {
            Note::Passage(acc) => acc.t_inf,
            _ => None,
        };
        let transition = (self.scratch.transition).get_or_insert_with(|| Transition {
            t,
            pair,
            name: String::new(),
            from,
            to,
            note: String::new(),
            t_accumulation,
        });
        transition.t = t;
        transition.pair = pair;
        transition.from = from;
        transition.to = to;
        transition.t_accumulation = t_accumulation;
        transition.name.clear();
        write_pair_name(&mut transition.name, self.model, pair);
        transition.note.clear();
        note.write(&mut transition.note, (from, to));
        let text = &mut self.scratch.text;
        text.clear();
        let _ = write!(text, "{}: {}", transition.name, transition.note);
        observer
            .message(t, Level::Info, text)
            .map_err(|e| e.at(t))?;
        observer
            .transition(self.model, transition)
            .map_err(|e| e.at(t))
    }

    /// Painlevé's inconsistency at a sliding point: an impact without collision, the
    /// one-point law with the approach speed floored at `v_tiny / 2` (its grazing limit).
    /// The floor leaves the point separating at `(1 + e) v_tiny / 2 ≤ v_tiny` at most:
    /// not separating, to the resolution of the contact stage. `events`: a buffer for the
    /// ledger.
    fn impact_without_collision(
        &mut self,
        point: Touch,
        t: Real,
        y: &mut [Real],
        events: &mut Vec<ImpactEvent>,
        observer: &mut dyn Observer,
    ) -> Result<(), SimError> {
        let (n, nqu) = (self.model.nq(), self.model.nq() + self.model.nu());
        let (q, u) = y[..nqu].split_at_mut(n);
        let material = self.material(point.pair);
        let floor = Some(0.5 * self.scales.v_tiny);
        let ev = self.map.apply_at(
            self.model,
            (point.pair, point.contact),
            material,
            floor,
            t,
            q,
            u,
        )?;
        self.map.recycle(events);
        events.extend(ev);
        self.ledger(t, events, observer)?;
        Ok(())
    }
}

/// The consistent sets of modes ranked by the least constraint, into `ranked` (indices of
/// `solutions`): the most open points first, in the enumeration's order among equals (the
/// rule of the mode selection).
fn most_open(solutions: &[lcp::Solution], ranked: &mut Vec<usize>) {
    let open = |s: &lcp::Solution| s.modes.iter().filter(|m| **m == Mode::Open).count();
    ranked.clear();
    ranked.extend(0..solutions.len());
    // The index breaks the ties: the order of a stable sort, without its buffer.
    ranked.sort_unstable_by_key(|&i| (std::cmp::Reverse(open(&solutions[i])), i));
}

/// The first of [`most_open`]'s ranking: the first solution with the most open points.
fn most_open_first(solutions: &[lcp::Solution]) -> Option<&lcp::Solution> {
    let open = |s: &lcp::Solution| s.modes.iter().filter(|m| **m == Mode::Open).count();
    let mut best: Option<(&lcp::Solution, usize)> = None;
    for s in solutions {
        let k = open(s);
        if best.is_none_or(|(_, b)| k > b) {
            best = Some((s, k));
        }
    }
    best.map(|b| b.0)
}

/// The impacts of one group of coupled contact points at the current instant.
#[derive(Clone, Copy, Debug)]
struct GroupImpacts {
    /// The group's name (see [`super::coupling::Coupling::groups`]).
    id: usize,
    /// The impacts so far.
    impacts: usize,
    /// An accumulation of impacts ended in it: the impacts in cascade that follow are
    /// plastic.
    ended: bool,
}

/// An accumulation of impacts that ended on a pair at the current instant: what the
/// mode selection that follows reports (the note is written then, see [`Note`]).
#[derive(Clone, Copy, Debug)]
pub(super) struct Accumulation {
    /// When the hops would have ended, if it could be extrapolated (s).
    pub t_inf: Option<Real>,
    /// The instant of the impact that ended it (s).
    pub t: Real,
    /// The separation speed of the hop after that impact, too slow (m/s).
    pub v: Real,
    /// The ratio of the last two separation speeds, if `t_inf` was extrapolated.
    pub ratio: Option<Real>,
}

/// A change of mode reported later than it is made: the passage to persistent contact at
/// the end of an accumulation, stamped at `t∞`.
#[derive(Clone, Copy, Debug)]
pub(super) struct Passage {
    /// When it is reported (s).
    pub t: Real,
    pub pair: PairId,
    pub from: PairMode,
    pub to: PairMode,
    /// The slip direction it enters (see [`super::Sample::slips`]).
    pub slip: i8,
    /// The accumulation it ends (its `t_inf`: when the hops would have ended).
    pub accumulation: Accumulation,
}

/// What a change of mode says in words (see `report`).
#[derive(Clone, Copy, Debug)]
enum Note {
    /// `from → to`.
    Change,
    /// The slip stops and reverses, to the direction `s` (`+1` or `−1`) along `t`.
    Reverses(i8),
    /// The end of an accumulation of impacts, then `from → to`.
    Passage(Accumulation),
}

impl Note {
    /// Writes the note of a change `from → to` into `out`.
    fn write(self, out: &mut String, (from, to): (PairMode, PairMode)) {
        let _ = match self {
            Note::Change => write!(out, "{} → {}", from.name(), to.name()),
            Note::Reverses(slip) => write!(
                out,
                "the slip stops and reverses (along {} t)",
                if slip > 0 { "+" } else { "−" }
            ),
            Note::Passage(Accumulation { t, v, t_inf, ratio }) => {
                let _ = write!(
                    out,
                    "accumulation of impacts: the hop after the impact at t = {t} s ({v:.3e} \
                     m/s) is below the resting speed; the impact is made plastic (e = 0, with \
                     its friction) and the contact stays closed; "
                );
                // Without a previous hop to extrapolate from, t∞ is unknown: say so rather
                // than print NaN, and stamp the passage at t.
                let _ = match t_inf.zip(ratio) {
                    Some((t_inf, r)) => write!(
                        out,
                        "the hops would end at t∞ = {t_inf} s (extrapolated, ratio {r:.4})"
                    ),
                    None => write!(
                        out,
                        "the end of the hops is unknown (no earlier hop to extrapolate from)"
                    ),
                };
                write!(out, "; {} → {}", from.name(), to.name())
            }
        };
    }
}

/// What the mode selection found.
enum Selected {
    /// The new closed set (in the buffer given to the selection).
    Set,
    /// Painlevé's inconsistency at this sliding point.
    Painleve(Touch),
}

/// The kept buffers of the contact stage (scratch, like `Data`: nothing in them lasts from
/// one use to the next). Refilled at each event, they allocate nothing once they have
/// grown to the largest event of the run. Each is taken out (`std::mem::take`) by the
/// function that fills it and put back after; nested calls use others.
#[derive(Default)]
pub(super) struct Scratch {
    /// Of the rounds of `contacts_at`.
    rounds: Rounds,
    /// Of `group_impacts`.
    group: GroupScratch,
    /// Of `rocking_end`.
    rocking: RockingScratch,
    /// Of `select_modes`.
    select: SelectScratch,
    /// Of `select_group`.
    select_group: GroupSelectScratch,
    /// The touching points of every group, and their groups (`touching_in`).
    all: Vec<Touch>,
    all_groups: Vec<usize>,
    /// The pairs near contact (`touching`).
    near: Vec<PairId>,
    /// parry's contact manifolds (`touching`).
    manifolds: ManifoldWorkspace,
    /// The points of an impact law, with their materials (`impact_round`).
    points: Vec<(PairId, PairContact, Material)>,
    /// The candidate points of a mode selection (`select_at`'s callers).
    candidates: Vec<Candidate>,
    /// The pairs whose accumulations end, with the fastest separation of each (m/s).
    accumulations: Vec<(PairId, Real)>,
    /// The pairs whose mode may change (`set_closed`).
    pairs: Vec<PairId>,
    /// The coefficients of friction of a new closed set (`set_closed`).
    mu: Vec<Real>,
    /// The text of a message to the observer.
    pub(super) text: String,
    /// The change of mode reported to the observer (`report`; made at the first).
    transition: Option<Transition>,
}

/// The buffers of the rounds of `contacts_at`.
#[derive(Default)]
struct Rounds {
    /// The touching points of the round.
    touching: Vec<Touch>,
    /// The group of each touching point (see `coupling`).
    group: Vec<usize>,
    /// The groups with an approaching point.
    ids: Vec<usize>,
    /// The touching points of one group.
    members: Vec<Touch>,
    /// The touching points whose hops start (in the groups that had impacts).
    hops: Vec<Touch>,
    /// The impacts so far at this instant, group by group.
    groups: Vec<GroupImpacts>,
    /// The ledger entries of the round.
    events: Vec<ImpactEvent>,
    /// The touching points that do not separate.
    resting: Vec<Touch>,
    /// The closed set the mode selection found.
    closed: Vec<Closed>,
}

/// The buffers of `group_impacts`.
#[derive(Default)]
struct GroupScratch {
    /// The approaching points of the group.
    approaching: Vec<Touch>,
    /// `u` before the impacts.
    u_before: Vec<Real>,
    /// The group's touching points after an impact.
    after: Vec<Touch>,
    /// Those that separate too slowly.
    slow: Vec<Touch>,
    /// The points a rocking end holds.
    held: Vec<Touch>,
}

/// The buffers of `rocking_end`.
#[derive(Default)]
struct RockingScratch {
    /// `u` just after the plastic impact.
    u_plastic: Vec<Real>,
    /// The points released from the jump.
    released: Vec<Touch>,
    /// The slip each held point is made to take.
    slides: Vec<Option<Real>>,
    /// The held points with their materials.
    points: Vec<(PairId, PairContact, Material)>,
    /// The held point of each entry.
    of_entry: Vec<Option<usize>>,
    /// The held points whose entries pull.
    pulled: Vec<usize>,
    /// The released points the jump made approach.
    approaching: Vec<usize>,
    /// The touching points after the jump.
    now: Vec<Touch>,
    /// The stopped points whose entries are outside the cone, with the slip they take.
    outside: Vec<(usize, Real)>,
    /// `u` of the round closest to the conditions, and its entries.
    best_u: Vec<Real>,
    best: Vec<ImpactEvent>,
    /// The entries of the round's jump.
    closing: Vec<ImpactEvent>,
}

/// The buffers of `select_modes`.
#[derive(Default)]
struct SelectScratch {
    /// The group of each resting point, and the groups.
    group: Vec<usize>,
    ids: Vec<usize>,
    /// The resting points of one group: their indices, themselves.
    index: Vec<usize>,
    members: Vec<Touch>,
    /// The closed set of one group.
    set: Vec<Closed>,
    /// The closed points of every group with their resting points and order.
    sorted: Vec<(usize, usize, Closed)>,
}

/// The buffers of `select_group`.
#[derive(Default)]
struct GroupSelectScratch {
    /// The slip each resting point must take, if it starts to slip.
    slips: Vec<Option<Real>>,
    /// The points that start to slip from rest, with their slips.
    starts: Vec<(usize, Real)>,
    /// The consistent sets ranked (see [`most_open`]).
    ranked: Vec<usize>,
}
