//! Two runs side by side: the impacts matched in order and by contact pair, then for each
//! quantity the largest absolute and relative difference and the first place where the
//! runs part beyond the tolerances.
//!
//! Rules (the contract of `ricochet compare` and `golden check`, in `ARCHITECTURE.md`):
//!
//! - **Matching.** The impacts of each contact pair are matched in their order on that
//!   pair (so that two impacts of one instant logged in another order still match); an
//!   impact without a partner is a difference (`count`). Samples are matched by time: two
//!   samples are the same instant when their times differ by at most `time_tol`, walking
//!   both lists in order (an impact instant's two samples match the other run's two).
//! - **The impact frame.** Where the tangential approach speed vanishes the paper lets
//!   either tangent be `t` (Eq. 10), and the choice follows the sign of rounding noise: a
//!   rod landing flat, a rocking block. When B's tangent is opposite to A's, B's row is
//!   mirrored into A's frame before the comparison (`m_nt`, `v_t`, `I_t` and its support's,
//!   `t`, α change sign, `g ↔ p`, `h ↔ q`, forward ↔ reverse sliding, the sign case of the
//!   mirrored coefficients): the same impact, written in the other frame. A note counts
//!   them.
//! - **Tolerances, per kind of quantity.** Times (impact times, sample and final times,
//!   the stop time): `|a − b| ≤ time_tol`. Energies (the audit's terms and drift, the
//!   ledger's energies, ΔE and its split, the samples' energies): `|a − b| ≤ atol + rtol ·
//!   max(|a|, |b|, E_ref)`, with `E_ref` the runs' energy scale ([`super::DriftCheck`]).
//!   Every other number: `|a − b| ≤ atol + rtol · max(|a|, |b|, S)`, with `S` the largest
//!   magnitude of the same field in either run (`i_n` over every impact, `q[2]` over every
//!   sample and the final state, …). A value is measured against the size of its kind in
//!   the run, not against itself alone: the impulses at the end of an accumulation, a
//!   coordinate crossing zero, the drift, a small impact's ΔE are small differences of
//!   large numbers, whose relative rounding is large. `α = v_t^A / |v_n^A|` is not
//!   compared as a number (it is the ratio of two compared ones, and unbounded as the
//!   approach speed vanishes), only whether it exists. A law, collision type, sign case,
//!   cause or stop reason that differs, a different number of impacts or of coordinates,
//!   or a part that one side lacks, is always a difference.
//! - **Reported.** For each quantity: the values compared, how many are beyond, the
//!   largest `|a − b|` and the largest relative difference (`|a − b|` over the scale of
//!   its rule, `max(|a|, |b|)` for times), and the first difference. The first difference
//!   of all is the earliest in simulated time (impacts before samples of the same instant;
//!   the audit last).
//! - **Not compared.** The scene's checksum and the settings (reported as notes: a changed
//!   scene is what a regression test is for), the work counters (steps, right-hand sides,
//!   events: cost, not motion; reported as a note when they differ).

use std::collections::{BTreeMap, HashMap};
use std::fmt::Write as _;

use serde::{Deserialize, Serialize};
use serde_json::{Value, json};

use crate::log::{Energy, ImpactRecord};
use crate::math::Real;

use super::{RegressError, Snapshot, Summary};

/// Default relative tolerance of `compare` and golden files.
pub const DEFAULT_RTOL: Real = 1e-9;
/// Default absolute tolerance (units of each quantity).
pub const DEFAULT_ATOL: Real = 1e-12;
/// Default tolerance on times (s).
pub const DEFAULT_TIME_TOL: Real = 1e-9;

/// The tolerances of a comparison.
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct Tolerances {
    /// Relative tolerance (dimensionless).
    pub rtol: Real,
    /// Absolute tolerance (in the unit of each quantity).
    pub atol: Real,
    /// Tolerance on times (s).
    pub time_tol: Real,
}

impl Default for Tolerances {
    fn default() -> Self {
        Tolerances {
            rtol: DEFAULT_RTOL,
            atol: DEFAULT_ATOL,
            time_tol: DEFAULT_TIME_TOL,
        }
    }
}

impl Tolerances {
    /// Checks that every tolerance is a finite number `≥ 0`.
    pub fn validate(&self) -> Result<(), RegressError> {
        for (field, value) in [
            ("rtol", self.rtol),
            ("atol", self.atol),
            ("time_tol", self.time_tol),
        ] {
            if !(value.is_finite() && value >= 0.0) {
                return Err(RegressError::Tolerance { field, value });
            }
        }
        Ok(())
    }
}

/// The kind of a quantity, which says which tolerance applies.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize)]
#[serde(rename_all = "snake_case")]
pub enum Kind {
    /// A time (s): `time_tol`.
    Time,
    /// An energy or work (J): `atol + rtol · max(|a|, |b|, E_ref)`.
    Energy,
    /// Any other number: `atol + rtol · max(|a|, |b|, S)`, `S` the field's largest
    /// magnitude in either run.
    Value,
    /// A name, a type, a count: equal or not.
    Exact,
}

/// Where two runs differ.
#[derive(Clone, Debug, PartialEq, Serialize)]
#[serde(tag = "at", rename_all = "snake_case")]
pub enum Place {
    /// A ledger row: its index in each run (absent on the side that has no such impact)
    /// and its contact pair.
    Impact {
        /// Index in run A.
        a: Option<u64>,
        /// Index in run B.
        b: Option<u64>,
        /// The contact pair.
        pair: String,
    },
    /// A sample (a checkpoint of a summary, any sample of a log).
    Sample,
    /// The final state.
    FinalState,
    /// The energy audit.
    Audit,
}

/// One difference.
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct Difference {
    /// Where.
    #[serde(flatten)]
    pub place: Place,
    /// The time of the place in run A (run B's when A has none) (s).
    #[serde(skip_serializing_if = "Option::is_none")]
    pub t: Option<Real>,
    /// The field, e.g. `v_s.n`, `q[2] (rod.theta)`, `type`.
    pub field: String,
    /// The value in A (a number, a name, or `null` when A has none).
    pub a: Value,
    /// The value in B.
    pub b: Value,
    /// `|a − b|`, for numbers.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub abs: Option<Real>,
    /// The relative difference, for numbers (see the module doc).
    #[serde(skip_serializing_if = "Option::is_none")]
    pub rel: Option<Real>,
}

/// The differences of one quantity over the whole run.
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct Quantity {
    /// Its name, e.g. `impacts.i_n`, `samples.q`, `audit.integration_drift`.
    pub name: String,
    /// Which tolerance applies.
    pub kind: Kind,
    /// How many values were compared.
    pub compared: u64,
    /// How many are beyond the tolerances.
    pub beyond: u64,
    /// The largest `|a − b|` (numbers).
    pub max_abs: Real,
    /// The largest relative difference (numbers).
    pub max_rel: Real,
    /// The first difference beyond the tolerances, in the order of the runs.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub first: Option<Difference>,
}

/// What one side of a comparison holds.
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct Side {
    /// The scene's name.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub scene: Option<String>,
    /// The scene file's CRC-32.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub crc32: Option<String>,
    /// Number of ledger rows.
    pub impacts: usize,
    /// Number of samples (checkpoints).
    pub samples: usize,
    /// The stop reason and time, from the audit.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub stop_reason: Option<String>,
    /// When the run stopped (s).
    #[serde(skip_serializing_if = "Option::is_none")]
    pub t_stop: Option<Real>,
}

impl Side {
    fn of(s: &Summary) -> Side {
        Side {
            scene: s.scene.as_ref().map(|x| x.name.clone()),
            crc32: s.scene.as_ref().map(|x| x.crc32.clone()),
            impacts: s.impacts.len(),
            samples: s.checkpoints.len(),
            stop_reason: s.audit.as_ref().map(|a| a.stop_reason.clone()),
            t_stop: s.audit.as_ref().map(|a| a.t_stop),
        }
    }
}

/// The comparison of two runs.
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct Comparison {
    /// Whether every quantity is within the tolerances.
    pub within: bool,
    /// The tolerances used.
    pub tolerances: Tolerances,
    /// The energy scale `E_ref` of the energies' tolerance (J): the larger of the two
    /// runs'.
    pub energy_scale: Real,
    /// Run A.
    pub a: Side,
    /// Run B.
    pub b: Side,
    /// What differs and is not compared (scene, settings, counters).
    pub notes: Vec<String>,
    /// Number of values compared.
    pub compared: u64,
    /// Number of values beyond the tolerances.
    pub beyond: u64,
    /// Each quantity.
    pub quantities: Vec<Quantity>,
    /// The first difference, in simulated time.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub first: Option<Difference>,
}

/// Compares run `a` with run `b` within `tol` (see the module doc).
pub fn compare(a: &Summary, b: &Summary, tol: &Tolerances) -> Comparison {
    let scale = |s: &Summary| {
        s.drift
            .map(|d| d.energy_scale)
            .or_else(|| s.final_state.as_ref().map(|f| energy_magnitude(&f.energy)))
            .unwrap_or(0.0)
    };
    let mut c = Comparer {
        tol: *tol,
        energy_scale: scale(a).max(scale(b)),
        scales: HashMap::new(),
        measuring: true,
        mirrored: 0,
        boundary_cases: 0,
        quantities: Vec::new(),
        firsts: Vec::new(),
        seq: 0,
        coordinates: if a.coordinates.is_empty() {
            b.coordinates.clone()
        } else {
            a.coordinates.clone()
        },
        speeds: if a.speeds.is_empty() {
            b.speeds.clone()
        } else {
            a.speeds.clone()
        },
    };
    // Two passes over the same pairs of values: the fields' scales, then the comparison.
    for measuring in [true, false] {
        c.measuring = measuring;
        c.mirrored = 0;
        c.boundary_cases = 0;
        c.impacts(&a.impacts, &b.impacts);
        c.samples(&a.checkpoints, &b.checkpoints);
        c.final_state(a.final_state.as_ref(), b.final_state.as_ref());
        c.audit(a, b);
    }
    let mut notes = notes(a, b);
    if c.mirrored > 0 {
        notes.push(format!(
            "{} impacts of B have the tangent opposite to A's (no tangential approach speed: \
             either tangent is the paper's); compared in A's frame",
            c.mirrored
        ));
    }
    if c.boundary_cases > 0 {
        notes.push(format!(
            "{} impacts have another sign case of Table 1 in B only because a coefficient \
             within the tolerances of zero changed sign (the same solution either side, \
             Comment g); compared as A's",
            c.boundary_cases
        ));
    }
    let first = (c.firsts.iter())
        .min_by(|x, y| x.0.total_cmp(&y.0).then(x.1.cmp(&y.1)))
        .map(|x| x.2.clone());
    let compared = c.quantities.iter().map(|q| q.compared).sum();
    let beyond = c.quantities.iter().map(|q| q.beyond).sum();
    Comparison {
        within: beyond == 0,
        tolerances: *tol,
        energy_scale: c.energy_scale,
        a: Side::of(a),
        b: Side::of(b),
        notes,
        compared,
        beyond,
        quantities: c.quantities,
        first,
    }
}

fn energy_magnitude(e: &Energy) -> Real {
    e.kinetic + e.potential.abs()
}

/// Fields of two ledger rows: name, value in A, value in B.
type Fields<'a> = Vec<(&'a str, Real, Real)>;

/// The comparison as it is being made.
struct Comparer {
    tol: Tolerances,
    energy_scale: Real,
    /// The largest magnitude of each field (by its name) in either run.
    scales: HashMap<String, Real>,
    /// Whether this pass only measures the scales.
    measuring: bool,
    /// Number of B's ledger rows mirrored into A's frame.
    mirrored: u64,
    /// Number of B's ledger rows whose sign case differs from A's only at a boundary of
    /// Table 1 (see [`Comparer::case_of`]).
    boundary_cases: u64,
    quantities: Vec<Quantity>,
    /// Each quantity's first difference with its sort key (time, order found).
    firsts: Vec<(Real, u64, Difference)>,
    seq: u64,
    coordinates: Vec<String>,
    /// The speeds' names when they are not the coordinates' (a nonholonomic scene).
    speeds: Vec<String>,
}

impl Comparer {
    fn quantity(&mut self, name: &str, kind: Kind) -> usize {
        if let Some(k) = self.quantities.iter().position(|q| q.name == name) {
            return k;
        }
        self.quantities.push(Quantity {
            name: name.to_owned(),
            kind,
            compared: 0,
            beyond: 0,
            max_abs: 0.0,
            max_rel: 0.0,
            first: None,
        });
        self.quantities.len() - 1
    }

    /// Records a difference beyond the tolerances of quantity `k`.
    fn beyond(&mut self, k: usize, d: Difference) {
        let q = &mut self.quantities[k];
        q.beyond += 1;
        self.seq += 1;
        if q.first.is_none() {
            let key = match d.place {
                Place::Audit => Real::INFINITY,
                _ => d.t.unwrap_or(Real::INFINITY),
            };
            self.firsts.push((key, self.seq, d.clone()));
            q.first = Some(d);
        }
    }

    /// Compares two numbers of quantity `name`.
    fn number(
        &mut self,
        (name, kind): (&str, Kind),
        at: (&Place, Option<Real>),
        field: &str,
        a: Real,
        b: Real,
    ) {
        let size = a.abs().max(b.abs());
        if self.measuring {
            let s = self.scales.entry(field.to_owned()).or_insert(0.0);
            if size.is_finite() {
                *s = s.max(size);
            }
            return;
        }
        let k = self.quantity(name, kind);
        let abs = (a - b).abs();
        let (scale, allowed) = match kind {
            Kind::Time => (size, self.tol.time_tol),
            Kind::Energy => {
                let s = size.max(self.energy_scale);
                (s, self.tol.atol + self.tol.rtol * s)
            }
            Kind::Value | Kind::Exact => {
                let s = size.max(self.scales.get(field).copied().unwrap_or(0.0));
                (s, self.tol.atol + self.tol.rtol * s)
            }
        };
        let rel = if abs == 0.0 { 0.0 } else { abs / scale };
        let q = &mut self.quantities[k];
        q.compared += 1;
        // Bit-equal numbers agree whatever they are; anything else must be within.
        let same = a.to_bits() == b.to_bits() || abs <= allowed;
        if abs.is_finite() {
            q.max_abs = q.max_abs.max(abs);
            q.max_rel = q.max_rel.max(rel);
        }
        if !same {
            self.beyond(
                k,
                Difference {
                    place: at.0.clone(),
                    t: at.1,
                    field: field.to_owned(),
                    a: json!(a),
                    b: json!(b),
                    abs: Some(abs).filter(|x| x.is_finite()),
                    rel: Some(rel).filter(|x| x.is_finite()),
                },
            );
        }
    }

    /// Whether `a` and `b` of field `field` (a quantity of kind [`Kind::Value`]) are within
    /// the tolerances (in the comparing pass; the scales are known then).
    fn close(&self, field: &str, a: Real, b: Real) -> bool {
        let s = (a.abs().max(b.abs())).max(self.scales.get(field).copied().unwrap_or(0.0));
        a.to_bits() == b.to_bits() || (a - b).abs() <= self.tol.atol + self.tol.rtol * s
    }

    /// B's sign case, or A's when they differ only at a boundary of Table 1: some
    /// coefficient g, h, p, q changes sign, and each that does is within the tolerances of
    /// A's, so both
    /// are within rounding of zero — where, by [P, Comment g], the equal sign may go with
    /// either inequality and the solution is the same (two equal pendulums striking
    /// head-on have `m_nt = 0`, and with μ = 0 the case follows the sign of its rounding).
    /// The numbers themselves are compared with the other fields.
    fn case_of(&mut self, a: &ImpactRecord, b: &ImpactRecord) -> u8 {
        if a.case == b.case {
            return b.case;
        }
        let coefficients = [
            ("g", a.g, b.g),
            ("h", a.h, b.h),
            ("p", a.p, b.p),
            ("q", a.q, b.q),
        ];
        let flips = |&(_, x, y): &(&str, Real, Real)| (x < 0.0) != (y < 0.0);
        let boundary = coefficients.iter().any(flips)
            && (coefficients.iter())
                .filter(|c| flips(c))
                .all(|&(f, x, y)| self.close(f, x, y));
        if boundary {
            self.boundary_cases += 1;
            a.case
        } else {
            b.case
        }
    }

    /// Compares two names, types or counts: equal or a difference.
    fn exact(&mut self, name: &str, at: (&Place, Option<Real>), field: &str, a: Value, b: Value) {
        if self.measuring {
            return;
        }
        let k = self.quantity(name, Kind::Exact);
        self.quantities[k].compared += 1;
        if a != b {
            self.beyond(
                k,
                Difference {
                    place: at.0.clone(),
                    t: at.1,
                    field: field.to_owned(),
                    a,
                    b,
                    abs: None,
                    rel: None,
                },
            );
        }
    }

    /// The ledgers: matched per pair, in order.
    fn impacts(&mut self, a: &[ImpactRecord], b: &[ImpactRecord]) {
        let mut pairs: BTreeMap<&str, (Vec<&ImpactRecord>, Vec<&ImpactRecord>)> = BTreeMap::new();
        for i in a {
            pairs.entry(&i.pair).or_default().0.push(i);
        }
        for i in b {
            pairs.entry(&i.pair).or_default().1.push(i);
        }
        if !self.measuring {
            self.quantity("impacts.count", Kind::Exact);
        }
        // In A's order, so that the quantities' first differences come in time order.
        let mut rows: Vec<(Option<&ImpactRecord>, Option<&ImpactRecord>)> = Vec::new();
        for (ra, rb) in pairs.values() {
            for k in 0..ra.len().max(rb.len()) {
                rows.push((ra.get(k).copied(), rb.get(k).copied()));
            }
        }
        rows.sort_by(|x, y| {
            let key = |r: &(Option<&ImpactRecord>, Option<&ImpactRecord>)| match r {
                (Some(i), _) | (None, Some(i)) => (i.t, i.index),
                (None, None) => (Real::INFINITY, u64::MAX),
            };
            let (kx, ky) = (key(x), key(y));
            kx.0.total_cmp(&ky.0).then(kx.1.cmp(&ky.1))
        });
        for row in rows {
            match row {
                (Some(ia), Some(ib)) => self.impact(ia, ib),
                (ia, ib) => {
                    let i = ia.or(ib);
                    let Some(i) = i.filter(|_| !self.measuring) else {
                        continue;
                    };
                    let place = Place::Impact {
                        a: ia.map(|i| i.index),
                        b: ib.map(|i| i.index),
                        pair: i.pair.clone(),
                    };
                    let describe = |x: Option<&ImpactRecord>| {
                        x.map_or(Value::Null, |i| {
                            json!(format!("impact #{} at t = {} s", i.index, i.t))
                        })
                    };
                    let k = self.quantity("impacts.count", Kind::Exact);
                    self.quantities[k].compared += 1;
                    self.beyond(
                        k,
                        Difference {
                            place,
                            t: Some(i.t),
                            field: "impact".to_owned(),
                            a: describe(ia),
                            b: describe(ib),
                            abs: None,
                            rel: None,
                        },
                    );
                }
            }
        }
        // After the rows: an impact without a partner is the first difference, at its time.
        self.exact(
            "impacts.count",
            (&Place::Audit, None),
            "impacts",
            json!(a.len()),
            json!(b.len()),
        );
    }

    /// Two matched ledger rows, field by field in the ledger's order (B's in A's frame).
    fn impact(&mut self, a: &ImpactRecord, b: &ImpactRecord) {
        let opposite = a.tangent.x * b.tangent.x + a.tangent.y * b.tangent.y < 0.0;
        let mirror;
        let b = if opposite {
            self.mirrored += 1;
            mirror = mirrored(b);
            &mirror
        } else {
            b
        };
        let place = Place::Impact {
            a: Some(a.index),
            b: Some(b.index),
            pair: a.pair.clone(),
        };
        let at = (&place, Some(a.t));
        use Kind::{Energy, Time, Value as V};
        self.number(("impacts.t", Time), at, "t", a.t, b.t);
        let case_b = if self.measuring {
            b.case
        } else {
            self.case_of(a, b)
        };
        let names = [
            ("law", json!(a.law.name()), json!(b.law.name())),
            (
                "type",
                json!(a.impact_type.name()),
                json!(b.impact_type.name()),
            ),
            ("case", json!(a.case), json!(case_b)),
            ("cause", json!(a.cause.name()), json!(b.cause.name())),
        ];
        for (field, x, y) in names {
            self.exact("impacts.type", at, field, x, y);
        }
        // α only as present or absent (see the module doc).
        if a.alpha.is_some() != b.alpha.is_some() {
            self.exact("impacts.type", at, "alpha", json!(a.alpha), json!(b.alpha));
        }
        let groups: [(&str, Kind, Fields<'_>); 14] = [
            (
                "impacts.w",
                V,
                vec![
                    ("w.mnn", a.w.nn, b.w.nn),
                    ("w.mnt", a.w.nt, b.w.nt),
                    ("w.mtt", a.w.tt, b.w.tt),
                    ("g", a.g, b.g),
                    ("h", a.h, b.h),
                    ("p", a.p, b.p),
                    ("q", a.q, b.q),
                ],
            ),
            (
                "impacts.v_a",
                V,
                vec![("v_a.n", a.v_a.n, b.v_a.n), ("v_a.t", a.v_a.t, b.v_a.t)],
            ),
            (
                "impacts.v_s",
                V,
                vec![("v_s.n", a.v_s.n, b.v_s.n), ("v_s.t", a.v_s.t, b.v_s.t)],
            ),
            ("impacts.i_n", V, vec![("i_n", a.i_n, b.i_n)]),
            ("impacts.i_t", V, vec![("i_t", a.i_t, b.i_t)]),
            ("impacts.delta_u", V, vec![]),
            (
                "impacts.energy",
                Energy,
                vec![
                    ("energy_before", a.energy_before, b.energy_before),
                    ("energy_after", a.energy_after, b.energy_after),
                ],
            ),
            (
                "impacts.delta_e",
                Energy,
                vec![("delta_e", a.delta_e, b.delta_e)],
            ),
            (
                "impacts.work_n",
                Energy,
                vec![("work_n", a.work_n, b.work_n)],
            ),
            (
                "impacts.work_t",
                Energy,
                vec![("work_t", a.work_t, b.work_t)],
            ),
            (
                "impacts.material",
                V,
                vec![("e", a.e, b.e), ("mu", a.mu, b.mu)],
            ),
            (
                "impacts.prescribed_work",
                Energy,
                vec![("prescribed_work", a.prescribed_work, b.prescribed_work)],
            ),
            (
                "impacts.point",
                V,
                vec![
                    ("point.x", a.point.x, b.point.x),
                    ("point.y", a.point.y, b.point.y),
                ],
            ),
            (
                "impacts.frame",
                V,
                vec![
                    ("normal.x", a.normal.x, b.normal.x),
                    ("normal.y", a.normal.y, b.normal.y),
                    ("tangent.x", a.tangent.x, b.tangent.x),
                    ("tangent.y", a.tangent.y, b.tangent.y),
                ],
            ),
        ];
        for (name, kind, fields) in groups {
            if name == "impacts.delta_u" {
                self.vector((name, V), at, "delta_u", &a.delta_u, &b.delta_u);
                continue;
            }
            for (field, x, y) in fields {
                self.number((name, kind), at, field, x, y);
            }
        }
        // The support of a rocking end: present on both sides or on neither.
        match (&a.support, &b.support) {
            (Some(x), Some(y)) => {
                self.number(("impacts.support", V), at, "support.i_n", x.i_n, y.i_n);
                self.number(("impacts.support", V), at, "support.i_t", x.i_t, y.i_t);
                let duration = ("impacts.support_duration", Time);
                self.number(duration, at, "support.duration", x.duration, y.duration);
            }
            (None, None) => {}
            (x, y) => {
                let present = |s: &Option<_>| json!(if s.is_some() { "present" } else { "absent" });
                self.exact("impacts.type", at, "support", present(x), present(y));
            }
        }
    }

    /// Two vectors of generalized coordinates or speeds, entry by entry.
    fn vector(
        &mut self,
        q: (&str, Kind),
        at: (&Place, Option<Real>),
        name: &str,
        a: &[Real],
        b: &[Real],
    ) {
        if a.len() != b.len() {
            let field = format!("{name} (length)");
            self.exact(q.0, at, &field, json!(a.len()), json!(b.len()));
            return;
        }
        let speeds = name == "u" && !self.speeds.is_empty();
        for (k, (x, y)) in a.iter().zip(b).enumerate() {
            let names = if speeds {
                &self.speeds
            } else {
                &self.coordinates
            };
            let field = match names.get(k) {
                Some(c) if a.len() == names.len() => format!("{name}[{k}] ({c})"),
                _ => format!("{name}[{k}]"),
            };
            self.number(q, at, &field, *x, *y);
        }
    }

    /// One state against another: `q`, `u`, energies.
    fn snapshot(&mut self, prefix: &str, place: &Place, a: &Snapshot, b: &Snapshot) {
        let at = (place, Some(a.t));
        self.vector((&format!("{prefix}.q"), Kind::Value), at, "q", &a.q, &b.q);
        self.vector((&format!("{prefix}.u"), Kind::Value), at, "u", &a.u, &b.u);
        let energy = (&*format!("{prefix}.energy"), Kind::Energy);
        self.number(
            energy,
            at,
            "energy.kinetic",
            a.energy.kinetic,
            b.energy.kinetic,
        );
        self.number(
            energy,
            at,
            "energy.potential",
            a.energy.potential,
            b.energy.potential,
        );
        self.number(energy, at, "energy.total", a.energy.total, b.energy.total);
    }

    /// The samples at common times: both lists walked in time order.
    /// A sample pairs with the other run's sample within `time_tol`, unless the next
    /// sample of either run is a closer partner (a loose `time_tol` must not pair a sample
    /// with its neighbour when the other run has it too).
    fn samples(&mut self, a: &[Snapshot], b: &[Snapshot]) {
        let (mut i, mut j) = (0, 0);
        while i < a.len() && j < b.len() {
            let (ta, tb) = (a[i].t, b[j].t);
            let gap = (ta - tb).abs();
            let closer = |x: Option<&Snapshot>, t: Real| x.is_some_and(|s| (s.t - t).abs() < gap);
            if gap <= self.tol.time_tol && closer(a.get(i + 1), tb) {
                i += 1;
            } else if gap <= self.tol.time_tol && closer(b.get(j + 1), ta) {
                j += 1;
            } else if gap <= self.tol.time_tol {
                self.snapshot("samples", &Place::Sample, &a[i], &b[j]);
                i += 1;
                j += 1;
            } else if ta < tb {
                i += 1;
            } else {
                j += 1;
            }
        }
    }

    fn final_state(&mut self, a: Option<&Snapshot>, b: Option<&Snapshot>) {
        match (a, b) {
            (Some(a), Some(b)) => {
                let at = (&Place::FinalState, Some(a.t));
                self.number(("final_state.t", Kind::Time), at, "t", a.t, b.t);
                self.snapshot("final_state", &Place::FinalState, a, b);
            }
            (None, None) => {}
            (a, b) => {
                let t = a.or(b).map(|s| s.t);
                let present =
                    |x: Option<&Snapshot>| json!(if x.is_some() { "present" } else { "absent" });
                self.exact(
                    "final_state.t",
                    (&Place::FinalState, t),
                    "final state",
                    present(a),
                    present(b),
                );
            }
        }
    }

    fn audit(&mut self, a: &Summary, b: &Summary) {
        let at = (&Place::Audit, None);
        let (Some(x), Some(y)) = (&a.audit, &b.audit) else {
            if a.audit.is_some() != b.audit.is_some() {
                let present = |s: &Summary| {
                    json!(if s.audit.is_some() {
                        "present"
                    } else {
                        "absent: the run did not finish"
                    })
                };
                self.exact("audit.stop_reason", at, "audit", present(a), present(b));
            }
            return;
        };
        // The reason's name (`t_end`, `interrupted`, `error`); the details are words.
        let reason = |s: &str| s.split(':').next().unwrap_or(s).to_owned();
        self.exact(
            "audit.stop_reason",
            at,
            "stop_reason",
            json!(reason(&x.stop_reason)),
            json!(reason(&y.stop_reason)),
        );
        self.number(
            ("audit.t_stop", Kind::Time),
            at,
            "t_stop",
            x.t_stop,
            y.t_stop,
        );
        let energies = [
            (
                "audit.energy",
                "energy_initial",
                x.energy_initial,
                y.energy_initial,
            ),
            (
                "audit.energy",
                "energy_final",
                x.energy_final,
                y.energy_final,
            ),
            (
                "audit.impact_delta_e",
                "impact_delta_e",
                x.impact_delta_e,
                y.impact_delta_e,
            ),
            (
                "audit.works",
                "applied_work",
                x.applied_work,
                y.applied_work,
            ),
            (
                "audit.works",
                "contact_work",
                x.contact_work,
                y.contact_work,
            ),
            (
                "audit.works",
                "prescribed_work",
                x.prescribed_work,
                y.prescribed_work,
            ),
            (
                "audit.integration_drift",
                "integration_drift",
                x.integration_drift,
                y.integration_drift,
            ),
        ];
        for (name, field, u, v) in energies {
            self.number((name, Kind::Energy), at, field, u, v);
        }
    }
}

/// The ledger row `r` written with the opposite tangent `−t`: the same impact in the other
/// frame that Eq. (10) allows when `v_t^A = 0`. `m_nt`, `v_t`, `I_t` (and its support's),
/// `t` and α change sign; `g = μ m_tt − m_nt` and `p = μ m_tt + m_nt` swap, as do `h` and `q`; forward and
/// reverse sliding swap (they are the sign of `v_t^S` along `t`); the sign case is that of
/// the swapped coefficients [P, Table 1].
fn mirrored(r: &ImpactRecord) -> ImpactRecord {
    use crate::impact::{Coefficients, CollisionType, ContactVelocity, ImpactMatrix};
    let w = ImpactMatrix { nt: -r.w.nt, ..r.w };
    let v_a = ContactVelocity {
        n: r.v_a.n,
        t: -r.v_a.t,
    };
    let case = Coefficients::new(&w, r.mu, v_a).sign_case().number();
    ImpactRecord {
        alpha: r.alpha.map(|x| -x),
        w,
        g: r.p,
        h: r.q,
        p: r.g,
        q: r.h,
        case,
        impact_type: match r.impact_type {
            CollisionType::ForwardSliding => CollisionType::ReverseSliding,
            CollisionType::ReverseSliding => CollisionType::ForwardSliding,
            CollisionType::Sticking => CollisionType::Sticking,
        },
        v_a,
        v_s: ContactVelocity {
            n: r.v_s.n,
            t: -r.v_s.t,
        },
        i_t: -r.i_t,
        support: r
            .support
            .map(|s| crate::log::SupportRecord { i_t: -s.i_t, ..s }),
        tangent: crate::log::Planar {
            x: -r.tangent.x,
            y: -r.tangent.y,
        },
        ..r.clone()
    }
}

/// What differs and is not compared: the scenes, the settings, the coordinates, the work
/// counters; and samples without a common time.
fn notes(a: &Summary, b: &Summary) -> Vec<String> {
    let mut notes = Vec::new();
    match (&a.scene, &b.scene) {
        (Some(x), Some(y)) if x.name != y.name => {
            notes.push(format!("the scenes differ: `{}` and `{}`", x.name, y.name));
        }
        (Some(x), Some(y)) if x.crc32 != y.crc32 => notes.push(format!(
            "the scene files differ: crc32 {} and {}",
            x.crc32, y.crc32
        )),
        _ => {}
    }
    if let (Some(x), Some(y)) = (&a.settings, &b.settings) {
        let mut fields = Vec::new();
        settings_diff(
            "",
            &Value::Object(x.clone()),
            &Value::Object(y.clone()),
            &mut fields,
        );
        if !fields.is_empty() {
            notes.push(format!("the settings differ: {}", fields.join(", ")));
        }
    }
    if !a.coordinates.is_empty() && !b.coordinates.is_empty() && a.coordinates != b.coordinates {
        notes.push(format!(
            "the coordinates differ: [{}] and [{}]",
            a.coordinates.join(", "),
            b.coordinates.join(", ")
        ));
    }
    if let (Some(x), Some(y)) = (&a.audit, &b.audit)
        && x.counters != y.counters
    {
        let (c, d) = (&x.counters, &y.counters);
        notes.push(format!(
            "the work counters differ (not compared): steps {} and {}, rejected {} and {}, \
             rhs evaluations {} and {}, events {} and {}, samples {} and {}",
            c.steps,
            d.steps,
            c.rejected_steps,
            d.rejected_steps,
            c.rhs_evaluations,
            d.rhs_evaluations,
            c.events,
            d.events,
            c.state_samples,
            d.state_samples
        ));
    }
    let common = (a.checkpoints.iter()).any(|s| b.checkpoints.iter().any(|r| r.t == s.t));
    if !common && !a.checkpoints.is_empty() && !b.checkpoints.is_empty() {
        notes.push("no sample time is common to both runs: no samples compared".to_owned());
    }
    notes
}

/// The paths of the settings whose values differ, as `path a → b`.
fn settings_diff(path: &str, a: &Value, b: &Value, out: &mut Vec<String>) {
    match (a, b) {
        (Value::Object(x), Value::Object(y)) => {
            let keys: std::collections::BTreeSet<&String> = x.keys().chain(y.keys()).collect();
            for key in keys {
                let sub = if path.is_empty() {
                    key.clone()
                } else {
                    format!("{path}.{key}")
                };
                let null = Value::Null;
                settings_diff(
                    &sub,
                    x.get(key).unwrap_or(&null),
                    y.get(key).unwrap_or(&null),
                    out,
                );
            }
        }
        _ if a != b => out.push(format!("{path} {a} and {b}")),
        _ => {}
    }
}

impl Comparison {
    /// The comparison as a table for a terminal; `labels` name the two runs (their files).
    pub fn to_text(&self, labels: (&str, &str)) -> String {
        let mut out = String::new();
        for (tag, label, side) in [("A", labels.0, &self.a), ("B", labels.1, &self.b)] {
            let scene = side.scene.as_deref().unwrap_or("(no scene record)");
            let crc = side
                .crc32
                .as_deref()
                .map(|c| format!(" (crc32 {c})"))
                .unwrap_or_default();
            let stop = match (&side.stop_reason, side.t_stop) {
                (Some(r), Some(t)) => format!("stopped at t = {t} s, {r}"),
                _ => "no audit: the run did not finish".to_owned(),
            };
            let _ = writeln!(
                out,
                "{tag}  {label}: {scene}{crc}, {} impacts, {} samples, {stop}",
                side.impacts, side.samples
            );
        }
        let t = &self.tolerances;
        let _ = writeln!(
            out,
            "tolerances: rtol {:e}, atol {:e}, time_tol {:e} s; energies against E_ref = {} J",
            t.rtol,
            t.atol,
            t.time_tol,
            short(self.energy_scale)
        );
        for note in &self.notes {
            let _ = writeln!(out, "note: {note}");
        }
        let _ = writeln!(out);
        let head = [
            "quantity",
            "compared",
            "beyond",
            "max |Δ|",
            "max rel",
            "first beyond the tolerances",
        ];
        let rows: Vec<[String; 6]> = (self.quantities.iter())
            .map(|q| {
                let numbers = q.kind != Kind::Exact;
                [
                    q.name.clone(),
                    q.compared.to_string(),
                    q.beyond.to_string(),
                    if numbers {
                        short(q.max_abs)
                    } else {
                        "—".to_owned()
                    },
                    if numbers {
                        short(q.max_rel)
                    } else {
                        "—".to_owned()
                    },
                    q.first
                        .as_ref()
                        .map(Difference::place_text)
                        .unwrap_or_default(),
                ]
            })
            .collect();
        let widths: Vec<usize> = (0..6)
            .map(|c| {
                (rows.iter().map(|r| r[c].chars().count()))
                    .chain([head[c].chars().count()])
                    .max()
                    .unwrap_or(0)
            })
            .collect();
        let line = |cells: [&str; 6]| {
            let mut s = String::new();
            for (c, cell) in cells.iter().enumerate() {
                let pad = widths[c] - cell.chars().count();
                if c == 0 || c == 5 {
                    let _ = write!(s, "{cell}{}  ", " ".repeat(pad));
                } else {
                    let _ = write!(s, "{}{cell}  ", " ".repeat(pad));
                }
            }
            s.trim_end().to_owned()
        };
        let _ = writeln!(out, "{}", line(head));
        for r in &rows {
            let _ = writeln!(out, "{}", line([&r[0], &r[1], &r[2], &r[3], &r[4], &r[5]]));
        }
        let _ = writeln!(out);
        match &self.first {
            Some(d) => {
                let _ = writeln!(out, "first difference: {}", d.to_text());
                let _ = writeln!(
                    out,
                    "BEYOND the tolerances: {} of {} values",
                    self.beyond, self.compared
                );
            }
            None => {
                let _ = writeln!(
                    out,
                    "within the tolerances: {} values compared",
                    self.compared
                );
            }
        }
        out
    }

    /// The comparison as a JSON document (`format = "ricochet.comparison"`, version 1).
    pub fn to_json(&self) -> Result<String, RegressError> {
        #[derive(Serialize)]
        struct Doc<'a> {
            format: &'static str,
            version: u32,
            #[serde(flatten)]
            comparison: &'a Comparison,
        }
        super::layout::to_string(&Doc {
            format: "ricochet.comparison",
            version: 1,
            comparison: self,
        })
        .map_err(RegressError::Encode)
    }
}

impl Difference {
    /// Where, in words: `impact #3 ball/floor at t = 1.2 s`, `sample at t = 0.5 s`.
    pub fn place_text(&self) -> String {
        let t = self.t.map(|t| format!(" at t = {t} s")).unwrap_or_default();
        match &self.place {
            Place::Impact { a, b, pair } => {
                let which = match (a, b) {
                    (Some(a), Some(b)) if a == b => format!("#{a}"),
                    (Some(a), Some(b)) => format!("#{a} (B #{b})"),
                    (Some(a), None) => format!("#{a} (none in B)"),
                    (None, Some(b)) => format!("B #{b} (none in A)"),
                    (None, None) => String::new(),
                };
                format!("impact {which} {pair}{t}: {}", self.field)
            }
            Place::Sample => format!("sample{t}: {}", self.field),
            Place::FinalState => format!("final state{t}: {}", self.field),
            Place::Audit => format!("audit: {}", self.field),
        }
    }

    /// The difference in words, with both values.
    pub fn to_text(&self) -> String {
        let value = |v: &Value| match v {
            Value::Null => "none".to_owned(),
            Value::String(s) => s.clone(),
            other => other.to_string(),
        };
        let mut s = format!(
            "{}: A {}, B {}",
            self.place_text(),
            value(&self.a),
            value(&self.b)
        );
        if let (Some(abs), Some(rel)) = (self.abs, self.rel) {
            let _ = write!(s, " (|Δ| = {}, relative {})", short(abs), short(rel));
        }
        s
    }
}

/// A number in a table: 3 significant digits.
fn short(x: Real) -> String {
    if x == 0.0 {
        "0".to_owned()
    } else {
        format!("{x:.2e}")
    }
}
