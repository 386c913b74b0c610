//! The `contacts` stage of the loop: what happens at an event instant. In rounds, until
//! nothing changes:
//!
//! 1. **impacts**: the contact points that approach. One point alone: the one-point law
//!    of [P] (the scene's law). Several at once: Moreau's generalized Newton law over all
//!    the touching points ([`ImpactMap::apply_many`]).
//! 2. **accumulations**: after the impacts, a touching point that separates slower than
//!    `v_rest` (see [`super::Scales`]) starts a hop too small to resolve — a bouncing ball
//!    or a rocking block at the end of an **accumulation of impacts** (Zeno). The hops left
//!    are replaced by one plastic normal impulse over the touching points
//!    ([`ImpactMap::close`]): they come to rest and stay closed. The time at which the
//!    infinitely many hops would end is extrapolated from their geometric decay.
//! 3. **modes**: the touching points that do not approach get their persistent-contact
//!    modes (open, stick, slide) from the complementarity problem at the acceleration
//!    level ([`Persistent::select`]). **Painlevé's paradox**: no consistent mode
//!    (*inconsistency*) is resolved by an impact without collision — the one-point law in
//!    its grazing limit `v_n^A → 0⁻` (Case 4 of Table 1, where it sticks with a finite
//!    impulse; Génot & Brogliato 1999) — and several consistent modes (*indeterminacy*)
//!    by the rule: the one with the most open points (the least constraint). Both are
//!    reported on the log with the time and the contact.

use super::impact_map::pair_name;
use super::observer::{PairMode, Transition};
use super::persistent::{Candidate, Closed, Hold, pair_points};
use super::{AtTime, ImpactEvent, Level, Observer, SimError, Simulation, StopReason};
use crate::contact::{ManifoldWorkspace, PairContact};
use crate::dynamics::forward_dynamics;
use crate::events::Event;
use crate::integrate::Stepper;
use crate::kinematics::{update_positions, update_velocities};
use crate::lcp::Mode;
use crate::math::{Real, Vec2};
use crate::model::{Material, PairId};

/// The most rounds of impacts and mode changes at one instant.
const MAX_ROUNDS: usize = 100;

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

impl Simulation<'_> {
    /// Stage `contacts` at the current time (see the module doc). Restarts the integrator
    /// when anything changed; returns a stop reason if the run cannot go on.
    pub(super) fn contacts(
        &mut self,
        event: Option<&Event>,
        observer: &mut dyn Observer,
    ) -> Result<Option<StopReason>, SimError> {
        let t = self.stepper.t();
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
    /// and a stop reason.
    fn contacts_at(
        &mut self,
        t: Real,
        y: &mut [Real],
        event: Option<&Event>,
        observer: &mut dyn Observer,
    ) -> Result<(bool, Option<StopReason>), SimError> {
        let n = self.model.nq();
        let mut changed = false;
        let mut impacts_here = 0usize;
        let mut painleve_resolved = false;
        let mut accumulation_ended = false;
        for _ in 0..MAX_ROUNDS {
            let touching = self.touching(t, y)?;
            let approaching: Vec<Touch> = (touching.iter())
                .filter(|p| p.v_n < -p.still)
                .copied()
                .collect();
            // 1. Impacts.
            if !approaching.is_empty() {
                if impacts_here == 0 {
                    self.sample(t, y, true, observer)?;
                }
                let points = self.points_below(&touching, self.scales.v_tiny);
                let (q, u) = y[..2 * n].split_at_mut(n);
                let events = if approaching.len() == 1 && (impacts_here == 0 || points.len() == 1) {
                    let p = approaching[0];
                    let material = self.material(p.pair);
                    let ev = self.map.apply_at(
                        self.model,
                        (p.pair, p.contact),
                        material,
                        None,
                        t,
                        q,
                        u,
                    )?;
                    ev.into_iter().collect()
                } else {
                    // Several points approach at once, or an impact made another touching
                    // point approach (a rod landing on one end strikes with the other).
                    let what = if approaching.len() > 1 {
                        "simultaneous impact"
                    } else {
                        "impacts in cascade at one instant"
                    };
                    observer
                        .message(
                            t,
                            Level::Warning,
                            &format!(
                                "{what} of {} contact points: Moreau's generalized Newton law \
                                 with Coulomb friction",
                                points.len()
                            ),
                        )
                        .map_err(|e| e.at(t))?;
                    self.map.apply_many(self.model, &points, t, q, u)?
                };
                impacts_here += events.len();
                if let Some(stop) = self.ledger(t, events, observer)? {
                    return Ok((true, Some(stop)));
                }
                changed = true;
                continue;
            }
            // 2. Accumulations: hops too small to resolve end.
            if impacts_here > 0 && !accumulation_ended {
                let slow: Vec<Touch> = (touching.iter())
                    .filter(|p| p.v_n > p.still && p.v_n <= self.scales.v_rest)
                    .copied()
                    .collect();
                if !slow.is_empty() {
                    self.end_accumulation(t, y, &touching, &slow, observer)?;
                    accumulation_ended = true;
                    changed = true;
                    continue;
                }
                self.remember_hops(t, &touching);
            }
            // 3. Modes of the touching points that do not separate.
            let resting: Vec<Touch> = (touching.iter())
                .filter(|p| p.v_n <= p.still)
                .copied()
                .collect();
            let starts_to_slip = if impacts_here == 0 {
                self.starts_to_slip(event)
            } else {
                None
            };
            match self.select_modes(t, y, &resting, starts_to_slip, observer)? {
                Selected::Set(closed) => {
                    let before = self.closed_on(event);
                    changed |= self.set_closed(t, closed, observer)?;
                    if impacts_here == 0 && !painleve_resolved {
                        self.disarm_open_crossing(event, before, &touching);
                    }
                    break;
                }
                Selected::Painleve(point) => {
                    if painleve_resolved {
                        return Err(SimError::Contact {
                            t,
                            message: format!(
                                "Painlevé's paradox on {}: no consistent contact mode even after \
                                 an impact without collision",
                                pair_name(self.model, point.pair)
                            ),
                        });
                    }
                    self.impact_without_collision(point, t, y, observer)?;
                    painleve_resolved = true;
                    changed = true;
                }
            }
        }
        if impacts_here > 0 {
            self.sample(t, y, true, observer)?;
        }
        Ok((changed, None))
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
        self.disarmed[pair.index()] = true;
        // A contact separating at v is clear of the tolerance after 10 gap_tol / v: steps no
        // longer than that see it close again. A grazing one (v ≈ 0) separates by its
        // acceleration; the steps are left as they are.
        let v = (touching.iter())
            .filter(|p| p.pair == pair && p.v_n > p.still)
            .map(|p| p.v_n)
            .fold(Real::INFINITY, Real::min);
        if v.is_finite() {
            let h = 10.0 * self.scales.gap_tol / v;
            self.stepper
                .set_h_max(h.min(self.settings.integrator.h_max));
        }
        self.arm();
    }

    /// The material of a pair, after the overrides.
    fn material(&self, pair: PairId) -> Material {
        self.overrides
            .apply(self.model.pairs()[pair.index()].material)
    }

    /// Every contact point within the closed-contact tolerance at `(t, y)`, with its
    /// velocities.
    fn touching(&mut self, t: Real, y: &[Real]) -> Result<Vec<Touch>, SimError> {
        let n = self.model.nq();
        let (q, u) = (&y[..n], &y[n..2 * n]);
        update_positions(self.model, &mut self.sampler, t, q).map_err(|e| e.at(t))?;
        update_velocities(self.model, &mut self.sampler, u).map_err(|e| e.at(t))?;
        let mut ws = ManifoldWorkspace::default();
        let mut out = Vec::new();
        for k in 0..self.model.pairs().len() {
            let pair = PairId(k);
            for (contact, local) in pair_points(
                self.model,
                &self.sampler,
                pair,
                self.scales.gap_tol,
                &mut ws,
            )? {
                let frame = self.map.frame_perp(self.model, (pair, contact), t, q, u)?;
                out.push(Touch {
                    pair,
                    contact,
                    local,
                    v_n: frame.v_n(),
                    still: self.scales.v_tiny,
                });
            }
        }
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
        Ok(out)
    }

    /// The touching points that do not separate faster than `bound` (or than they drift),
    /// with their materials.
    fn points_below(
        &self,
        touching: &[Touch],
        bound: Real,
    ) -> Vec<(PairId, PairContact, Material)> {
        (touching.iter())
            .filter(|p| p.v_n <= bound.max(p.still))
            .map(|p| (p.pair, p.contact, self.material(p.pair)))
            .collect()
    }

    /// Records impacts in the ledger and the audit, and reports them. A stop reason if
    /// impacts stall.
    fn ledger(
        &mut self,
        t: Real,
        events: Vec<ImpactEvent>,
        observer: &mut dyn Observer,
    ) -> Result<Option<StopReason>, SimError> {
        for mut ev in events {
            ev.index = self.counters.impacts;
            self.counters.impacts += 1;
            self.audit.impact_delta_e += ev.outcome.delta_e;
            self.audit.impact_prescribed_work += ev.prescribed_work();
            observer.impact(self.model, &ev).map_err(|e| e.at(t))?;
            if let Some(reason) = self.guard.after_impact(t) {
                return Ok(Some(self.accumulation(t, ev.frame.pair, reason)));
            }
        }
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

    /// The end of an accumulation of impacts at `t`: the `slow` points separate slower
    /// than `v_rest`. Extrapolates the time the hops would end, from the last hop of each
    /// pair: with `r = v / v_prev` the ratio of successive separation speeds and
    /// `Δt = t − t_prev` the last hop's duration, the hops left last
    /// `Σ_{k≥1} rᵏ Δt = Δt r / (1 − r)` (exact for hops of constant deceleration, the
    /// bouncing ball; the small-amplitude limit of rocking). Then closes the touching
    /// points ([`ImpactMap::close`]) and reports a transition per pair.
    fn end_accumulation(
        &mut self,
        t: Real,
        y: &mut [Real],
        touching: &[Touch],
        slow: &[Touch],
        observer: &mut dyn Observer,
    ) -> Result<(), SimError> {
        let n = self.model.nq();
        let mut pairs: Vec<(PairId, Real)> = Vec::new();
        for p in slow {
            match pairs.iter_mut().find(|(pair, _)| *pair == p.pair) {
                Some((_, v)) => *v = v.max(p.v_n),
                None => pairs.push((p.pair, p.v_n)),
            }
        }
        let mut notes = Vec::with_capacity(pairs.len());
        for &(pair, v) in &pairs {
            let (t_inf, r) = match self.last_separation[pair.index()] {
                Some((t_prev, v_prev)) if t_prev < t && v < v_prev => {
                    let r = v / v_prev;
                    (t + (t - t_prev) * r / (1.0 - r), Some(r))
                }
                _ => (Real::NAN, None),
            };
            // Without a previous hop to extrapolate from, t∞ is unknown: say so rather
            // than print NaN.
            let end = match r {
                Some(r) => {
                    format!("the hops would end at t∞ = {t_inf} s (extrapolated, ratio {r:.4})")
                }
                None => {
                    "the end of the hops is unknown (no earlier hop to extrapolate from)".to_owned()
                }
            };
            let note = format!(
                "accumulation of impacts: the last hop ({v:.3e} m/s) is below the resting speed \
                 {:.1e} m/s; the contact comes to rest (plastic normal impulses) and stays \
                 closed; {end}",
                self.scales.v_rest
            );
            notes.push((pair, note, t_inf));
            self.last_separation[pair.index()] = None;
        }
        let points = self.points_below(touching, self.scales.v_rest);
        let (q, u) = y[..2 * n].split_at_mut(n);
        let events = self
            .map
            .close(self.model, &points, self.scales.v_rest, t, q, u)?;
        self.ledger(t, events, observer)?;
        for (pair, note, t_inf) in notes {
            let from = self.modes[pair.index()];
            self.modes[pair.index()] = PairMode::Sticking;
            self.report(
                t,
                pair,
                (from, PairMode::Sticking),
                note,
                t_inf.is_finite().then_some(t_inf),
                observer,
            )?;
        }
        Ok(())
    }

    /// Puts the closed set back in the ODE system after a selection used its workspace.
    fn restore_persistent(&mut self) {
        let closed = self.gaps.persistent.closed().to_vec();
        let mu = (0..closed.len())
            .map(|i| self.gaps.persistent.mu(i))
            .collect();
        self.system.persistent.set(closed, mu);
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

    /// Selects the modes of the resting points. The point of `starts_to_slip` (a sticking
    /// point at the edge of its friction cone) may open or slide, not stick: at the event
    /// both are consistent to rounding, and sticking would cross the edge again at once.
    fn select_modes(
        &mut self,
        t: Real,
        y: &[Real],
        resting: &[Touch],
        starts_to_slip: Option<(PairId, Vec2, Real)>,
        observer: &mut dyn Observer,
    ) -> Result<Selected, SimError> {
        if resting.is_empty() {
            return Ok(Selected::Set(vec![]));
        }
        let n = self.model.nq();
        let (q, u) = (&y[..n], &y[n..2 * n]);
        forward_dynamics(self.model, &mut self.sampler, t, q, u).map_err(|e| e.at(t))?;
        // The resting point nearest the one that starts to slip.
        let slipping = starts_to_slip.and_then(|(pair, local, _)| {
            (0..resting.len())
                .filter(|&i| resting[i].pair == pair)
                .min_by(|&i, &j| {
                    (resting[i].local - local)
                        .length()
                        .total_cmp(&(resting[j].local - local).length())
                })
        });
        let candidates: Vec<Candidate> = (resting.iter().enumerate())
            .map(|(i, p)| Candidate {
                pair: p.pair,
                local: p.local,
                mu: self.material(p.pair).mu,
                slip: if Some(i) == slipping {
                    starts_to_slip.map(|s| s.2)
                } else {
                    None
                },
            })
            .collect();
        let v_slip = 1e3 * self.scales.v_tiny;
        let sel = self.system.persistent.select(
            self.model,
            &self.sampler,
            (t, q, u),
            &candidates,
            v_slip,
        )?;
        self.restore_persistent();
        let sliding_painleve = |i: usize| sel.painleve[i] <= 0.0;
        let chosen = match sel.solutions.len() {
            0 => {
                return match (0..resting.len()).find(|&i| sliding_painleve(i)) {
                    Some(i) => {
                        let name = pair_name(self.model, resting[i].pair);
                        observer
                            .message(
                                t,
                                Level::Warning,
                                &format!(
                                    "Painlevé's paradox on {name} at t = {t} s: sliding is \
                                     inconsistent (Painlevé coefficient {:.4e} ≤ 0, no \
                                     non-negative normal force holds the contact); resolved by \
                                     an impact without collision",
                                    sel.painleve[i]
                                ),
                            )
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
                // The least constraint: the most open points.
                let chosen = (sel.solutions.iter())
                    .max_by_key(|s| s.modes.iter().filter(|m| **m == Mode::Open).count())
                    .unwrap_or(&sel.solutions[0]);
                let painleve: Vec<String> = (0..resting.len())
                    .filter(|&i| sliding_painleve(i))
                    .map(|i| pair_name(self.model, resting[i].pair))
                    .collect();
                let what = if painleve.is_empty() {
                    "the contact modes are not unique".to_owned()
                } else {
                    format!(
                        "Painlevé's paradox on {}: the contact modes are indeterminate",
                        painleve.join(", ")
                    )
                };
                observer
                    .message(
                        t,
                        Level::Warning,
                        &format!("{what} at t = {t} s ({count} consistent sets); chose the one with the most open contacts"),
                    )
                    .map_err(|e| e.at(t))?;
                chosen
            }
        };
        let closed = (resting.iter().zip(&chosen.modes))
            .filter_map(|(p, m)| {
                let hold = match *m {
                    Mode::Open => return None,
                    Mode::Stick => Hold::Stick,
                    Mode::Slide(s) => Hold::Slide(s),
                };
                Some(Closed {
                    pair: p.pair,
                    local: p.local,
                    hold,
                })
            })
            .collect();
        Ok(Selected::Set(closed))
    }

    /// Installs a new closed set; reports the pairs whose mode changed. Whether it changed.
    fn set_closed(
        &mut self,
        t: Real,
        closed: Vec<Closed>,
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
        let mu: Vec<Real> = closed.iter().map(|c| self.material(c.pair).mu).collect();
        self.system.persistent.set(closed.clone(), mu.clone());
        self.gaps.persistent.set(closed, mu);
        let npairs = self.model.pairs().len();
        for k in 0..npairs {
            let pair = PairId(k);
            let holds = self
                .gaps
                .persistent
                .closed()
                .iter()
                .filter(|c| c.pair == pair)
                .map(|c| c.hold);
            let mut mode = PairMode::Free;
            for h in holds {
                mode = match (mode, h) {
                    (PairMode::Sliding, _) | (_, Hold::Slide(_)) => PairMode::Sliding,
                    _ => PairMode::Sticking,
                };
            }
            if mode != self.modes[k] {
                let from = self.modes[k];
                self.modes[k] = mode;
                let note = format!("{} → {}", from.name(), mode.name());
                self.report(t, pair, (from, mode), note, None, observer)?;
            }
        }
        Ok(!same)
    }

    /// Reports a change of mode of `pair` on the log and to the observer.
    fn report(
        &mut self,
        t: Real,
        pair: PairId,
        (from, to): (PairMode, PairMode),
        note: String,
        t_accumulation: Option<Real>,
        observer: &mut dyn Observer,
    ) -> Result<(), SimError> {
        let name = pair_name(self.model, pair);
        observer
            .message(t, Level::Info, &format!("{name}: {note}"))
            .map_err(|e| e.at(t))?;
        let transition = Transition {
            t,
            pair,
            name,
            from,
            to,
            note,
            t_accumulation,
        };
        observer
            .transition(self.model, &transition)
            .map_err(|e| e.at(t))
    }

    /// Painlevé's inconsistency at a sliding point: an impact without collision, the
    /// one-point law with the approach speed floored at `v_tiny / 2` (its grazing limit).
    /// The floor leaves the point separating at `(1 + e) v_tiny / 2 ≤ v_tiny` at most:
    /// not separating, to the resolution of the contact stage.
    fn impact_without_collision(
        &mut self,
        point: Touch,
        t: Real,
        y: &mut [Real],
        observer: &mut dyn Observer,
    ) -> Result<(), SimError> {
        let n = self.model.nq();
        let (q, u) = y[..2 * n].split_at_mut(n);
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
        self.ledger(t, ev.into_iter().collect(), observer)?;
        Ok(())
    }
}

/// What the mode selection found.
enum Selected {
    /// The new closed set.
    Set(Vec<Closed>),
    /// Painlevé's inconsistency at this sliding point.
    Painleve(Touch),
}
