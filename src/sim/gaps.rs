//! The event functions of the loop: the gaps of open contacts, and the forces and slips of
//! closed ones.

use super::persistent::{Hold, Persistent, PointScratch};
use super::{AtTime, Nested, Scales};
use crate::contact::{PairContact, pair_contact, signed_gap};
use crate::dynamics::forward_dynamics;
use crate::events::EventFunctions;
use crate::kinematics::{point_velocity, update_positions, update_velocities};
use crate::math::{Real, Vec2};
use crate::model::{Model, PairId};
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
/// the closed points of its pair, in the order of [`Persistent::closed`].
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
    data: Data,
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

    fn keep(&mut self, fns: &GapFunctions<'_>, t: Real, y: &[Real], g: &[Real]) {
        self.t = t;
        self.y.clear();
        self.y.extend_from_slice(y);
        self.candidates.clear();
        self.candidates.extend_from_slice(&fns.candidates);
        self.disarmed.clear();
        self.disarmed.extend_from_slice(&fns.disarmed);
        self.closed.clear();
        self.closed.extend_from_slice(fns.persistent.closed());
        self.g.clear();
        self.g.extend_from_slice(g);
    }
}

impl<'m> GapFunctions<'m> {
    /// The event functions of `model`, with no closed contact point.
    pub fn new(model: &'m Model, scales: Scales) -> Self {
        Self {
            model,
            data: Data::new(model),
            persistent: Persistent::new(model, scales),
            scratch: PointScratch::new(model),
            scales,
            candidates: Vec::new(),
            disarmed: Vec::new(),
            memo: Memo::default(),
        }
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
        update_positions(self.model, &mut self.data, t, &y[..n])
            .map_err(|e| Nested::from(e.at(t)))?;
        self.open_gap_here(pair, t)
    }

    /// The positions at `(t, y)`, for [`Self::open_gap_at_positions`] (one kinematics pass
    /// for the gaps of many pairs).
    pub fn set_positions(&mut self, t: Real, y: &[Real]) -> Result<(), Nested> {
        let n = self.model.nq();
        update_positions(self.model, &mut self.data, t, &y[..n]).map_err(|e| Nested::from(e.at(t)))
    }

    /// [`Self::open_gap`] at the positions of the last [`Self::set_positions`] (at `t`).
    pub fn open_gap_at_positions(&mut self, pair: PairId, t: Real) -> Result<Real, Nested> {
        self.open_gap_here(pair, t)
    }

    /// The other point of a pair with one closed point at `local`: of its (at most two)
    /// candidates, the one farther from the closed point (which moves on `a` as it slides
    /// or rolls). At the positions of `self.data`.
    fn other_point(&mut self, pair: PairId, local: Vec2) -> Result<Option<PairContact>, Nested> {
        let candidates =
            self.scratch
                .candidates(self.model, &self.data, pair, self.scales.length)?;
        Ok(match candidates.as_slice() {
            [x, y] if (x.1 - local).length() <= (y.1 - local).length() => Some(y.0),
            [x, _] => Some(x.0),
            _ => None,
        })
    }

    /// [`Self::open_gap`] at the positions of `self.data`.
    fn open_gap_here(&mut self, pair: PairId, t: Real) -> Result<Real, Nested> {
        let model = self.model;
        let closed = self.persistent.closed();
        let mut on_pair = closed.iter().filter(|c| c.pair == pair);
        let (first, second) = (on_pair.next().map(|c| c.local), on_pair.next());
        Ok(match (first, second) {
            (None, _) => signed_gap(model, &self.data, pair, Real::INFINITY)
                .map_err(|e| Nested::from(e.at(t)))?
                .unwrap_or(self.scales.length),
            (Some(local), None) => match self.other_point(pair, local)? {
                Some(c) => c.gap,
                None => self.scales.length,
            },
            (Some(_), Some(_)) => self.scales.length,
        })
    }
}

impl GapFunctions<'_> {
    /// [`EventFunctions::values`], computed.
    fn values_here(&mut self, t: Real, y: &[Real], g: &mut [Real]) -> Result<(), Nested> {
        let model = self.model;
        let (n, nqu) = (model.nq(), model.nq() + model.nu());
        let (q, u) = (&y[..n], &y[n..nqu]);
        // Unarmed functions hold a positive value.
        g.fill(self.scales.length);
        if self.persistent.closed().is_empty() {
            update_positions(model, &mut self.data, t, q).map_err(|e| Nested::from(e.at(t)))?;
        } else {
            forward_dynamics(model, &mut self.data, t, q, u).map_err(|e| Nested::from(e.at(t)))?;
            self.persistent
                .accelerate(model, &mut self.data, (t, q, u))?;
        }
        for r in 0..self.candidates.len() {
            let pair = self.candidates[r];
            let floor = match self.disarmed.binary_search_by_key(&pair, |d| d.0) {
                Ok(k) => self.disarmed[k].1,
                Err(_) => 0.0,
            };
            g[SLOTS * r] = self.open_gap_here(pair, t)? - floor;
        }
        for i in 0..self.persistent.closed().len() {
            let c = self.persistent.closed()[i];
            let j = rank(&self.persistent, i);
            let Some(at) = self.slot_of(c.pair, 0) else {
                continue;
            };
            let (lambda_n, lambda_t) = self.persistent.force(i);
            let mu = self.persistent.mu(i);
            g[at + 1 + 3 * j] = lambda_n;
            g[at + 2 + 3 * j] = match c.hold {
                Hold::Stick => mu * lambda_n - lambda_t.abs(),
                Hold::Slide(s) => s * self.persistent.points()[i].v_t + c.slip_margin,
            };
            g[at + 3 + 3 * j] = self.persistent.painleve(i).min(self.scales.length);
        }
        Ok(())
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
        let mut memo = std::mem::take(&mut self.memo);
        memo.keep(self, t, y, g);
        self.memo = memo;
        Ok(())
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
        update_positions(model, &mut self.data, t, &y[..n]).map_err(|e| Nested::from(e.at(t)))?;
        update_velocities(model, &mut self.data, &y[n..nqu]).map_err(|e| Nested::from(e.at(t)))?;
        g_dot.fill(0.0);
        for r in 0..self.candidates.len() {
            let pair = self.candidates[r];
            let closed = self.persistent.closed();
            let mut on_pair = closed.iter().filter(|c| c.pair == pair);
            let contact = match (on_pair.next().map(|c| c.local), on_pair.next()) {
                (None, _) => pair_contact(model, &self.data, pair, Real::INFINITY)
                    .map_err(|e| Nested::from(e.at(t)))?,
                (Some(local), None) => self.other_point(pair, local)?,
                (Some(_), Some(_)) => None,
            };
            g_dot[SLOTS * r] = match contact {
                Some(c) => {
                    let p = model.pair_of(pair);
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
            };
        }
        Ok(true)
    }
}
