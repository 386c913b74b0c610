//! Locating the earliest closing event of the last step on its dense output.

use std::convert::Infallible;

use super::illinois::{Probe, Solved, illinois};
use super::{EventError, EventFunctions};
use crate::integrate::{IntegrateError, OdeSystem, Stepper};
use crate::math::Real;

/// Settings of the [`EventLocator`].
#[derive(Clone, Debug, PartialEq)]
pub struct LocatorSettings {
    /// Interior sample points per step, `k`: the step is split into `k + 1` equal parts
    /// whose ends bracket sign changes (default 4).
    pub samples: usize,
    /// Absolute time tolerance of a root (s), added to `4 ε |t|` (default 0: the root is
    /// bracketed to 4 ulp).
    pub t_tol: Real,
    /// Events of different functions within this time of the earliest are reported
    /// together (s, default 1e-9).
    pub simultaneity: Real,
    /// Search the extremum of `g` between two samples when `ġ` changes sign there, to
    /// find dips below zero between positive samples (grazing, thin or fast obstacles)
    /// and bounces between non-positive samples (default true). Off: only sign changes at
    /// the samples are seen.
    pub extremum_search: bool,
    /// Iteration budget of one root or extremum search (default 200).
    pub max_iter: usize,
}

impl Default for LocatorSettings {
    fn default() -> Self {
        Self {
            samples: 4,
            t_tol: 0.0,
            simultaneity: 1e-9,
            extremum_search: true,
            max_iter: 200,
        }
    }
}

/// How an event was found; the kinds differ in what `[t_lo, t_hi]` means.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
pub enum EventKind {
    /// `g > 0` at a sample and `g ≤ 0` at the next: the root is bracketed,
    /// `g(t_lo) > 0 ≥ g(t_hi)` on the dense output, `t = t_hi`.
    Crossing,
    /// `g > 0` at two consecutive samples, but the minimum of `g` between them (where `ġ`
    /// changes sign from − to +) is `≤ 0`: grazing, or a thin or fast obstacle. Bracket
    /// as for `Crossing`.
    Grazing,
    /// `g ≤ 0` at two consecutive samples (the function started the step at contact,
    /// opening), but its maximum between them is `> 0`: a bounce shorter than a sample
    /// interval, ending in a closing crossing. Bracket as for `Crossing`.
    Bounce,
    /// `g(t_prev) ≤ 0` and closing there (`ġ < 0`, or `ġ = 0` and `g` decreasing): a
    /// root exactly at the step's start, or a contact that does not open.
    /// `t = t_lo = t_hi = t_prev`. The loop decides what it means.
    AtStart,
    /// `g ≤ 0` at the start and opening, but `g` turns to closing again without becoming
    /// positive (a separation below the resolution of `g`). `t = t_hi` is just after
    /// the maximum of `g`, `[t_lo, t_hi]` brackets the maximum, and `g(t) ≤ 0`.
    Reclosing,
}

/// One event: the function, how it was found, its time and bracket (s).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Event {
    /// Index `i` of the event function.
    pub index: usize,
    /// How it was found.
    pub kind: EventKind,
    /// The event time: the post-event end of the bracket, `t_hi` (s).
    pub t: Real,
    /// Lower end of the bracket (s).
    pub t_lo: Real,
    /// Upper end of the bracket (s).
    pub t_hi: Real,
}

/// Work of the locator since it was built.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Hash)]
pub struct LocatorCounters {
    /// Calls of [`EventLocator::locate`] on non-empty steps.
    pub calls: u64,
    /// Evaluations of all `m` event functions (`values`), samples and iterations.
    pub value_evals: u64,
    /// Evaluations of the rates supplied by the caller.
    pub rate_evals: u64,
}

/// The samples of one step: times, values and rates of all functions.
#[derive(Clone, Debug)]
struct Samples {
    /// `k + 2` times, `t_prev` … `t` (s).
    ts: Vec<Real>,
    /// `g[j m + i]`: function `i` at sample `j`.
    gs: Vec<Real>,
    /// `ġ[j m + i]`, valid where `known[j]`.
    gds: Vec<Real>,
    known: Vec<bool>,
}

/// Scratch vectors for one evaluation.
#[derive(Clone, Debug)]
pub(crate) struct Scratch {
    y: Vec<Real>,
    dy: Vec<Real>,
    y2: Vec<Real>,
    pub(crate) g: Vec<Real>,
    pub(crate) gd: Vec<Real>,
    g2: Vec<Real>,
}

/// Finds the earliest closing event of any armed function inside the last step of a
/// [`Stepper`], on its dense output; see the [module](super) docs for the semantics and
/// the limits. All vectors are allocated in [`new`](EventLocator::new).
#[derive(Clone, Debug)]
pub struct EventLocator {
    pub(crate) settings: LocatorSettings,
    n: usize,
    m: usize,
    samples: Samples,
    pub(crate) scratch: Scratch,
    done: Vec<bool>,
    found: Vec<Event>,
    pub(crate) counters: LocatorCounters,
}

/// The last step of a stepper as the locator reads it: its ends, and its dense output,
/// completed ([`Stepper::complete_dense`]) the first time it is read inside the step.
pub(crate) trait LastStep {
    /// The stepper.
    type Stepper: Stepper;
    /// The error of the system's right-hand side ([`Infallible`] for a stepper that is
    /// only read).
    type Error: std::error::Error + 'static;
    /// The stepper, to read.
    fn stepper(&self) -> &Self::Stepper;
    /// The dense output at `t` inside the last step into `out`, completed first if it can
    /// be ([`Stepper::dense_completing`]).
    fn dense(&mut self, t: Real, out: &mut [Real]) -> Result<(), IntegrateError<Self::Error>>;
    /// Its derivative likewise ([`Stepper::dense_derivative_completing`]).
    fn dense_derivative(
        &mut self,
        t: Real,
        out: &mut [Real],
    ) -> Result<(), IntegrateError<Self::Error>>;
}

/// A stepper only read: its dense output must be complete where it is read
/// ([`DenseIncomplete`](crate::integrate::DenseIncomplete) otherwise).
impl<St: Stepper> LastStep for &St {
    type Stepper = St;
    type Error = Infallible;
    fn stepper(&self) -> &St {
        self
    }
    fn dense(&mut self, t: Real, out: &mut [Real]) -> Result<(), IntegrateError<Infallible>> {
        Ok(Stepper::dense(*self, t, out)?)
    }
    fn dense_derivative(
        &mut self,
        t: Real,
        out: &mut [Real],
    ) -> Result<(), IntegrateError<Infallible>> {
        Ok(Stepper::dense_derivative(*self, t, out)?)
    }
}

/// A stepper with its system: the dense output is completed on demand.
pub(crate) struct Completing<'a, St, Sys> {
    pub(crate) stepper: &'a mut St,
    pub(crate) sys: &'a mut Sys,
}

impl<St: Stepper, Sys: OdeSystem> LastStep for Completing<'_, St, Sys> {
    type Stepper = St;
    type Error = Sys::Error;
    fn stepper(&self) -> &St {
        self.stepper
    }
    #[inline]
    fn dense(&mut self, t: Real, out: &mut [Real]) -> Result<(), IntegrateError<Sys::Error>> {
        self.stepper.dense_completing(self.sys, t, out)
    }
    #[inline]
    fn dense_derivative(
        &mut self,
        t: Real,
        out: &mut [Real],
    ) -> Result<(), IntegrateError<Sys::Error>> {
        self.stepper.dense_derivative_completing(self.sys, t, out)
    }
}

/// The error of the event location of a [`LastStep`] whose system fails with `E`.
type LocateError<G, E> = EventError<<G as EventFunctions>::Error, E>;

impl<G, E> EventError<G, E>
where
    G: std::error::Error + 'static,
    E: std::error::Error + 'static,
{
    /// The failure of the location itself, or (`Err`) of the integration it made: the
    /// dense output completed by
    /// [`locate_completing_dense`](EventLocator::locate_completing_dense) (a failing
    /// right-hand side), to be reported as a failure of the step it belongs to.
    pub fn or_integration(self) -> Result<EventError<G>, IntegrateError<E>> {
        Ok(match self {
            EventError::Integrate(e) => return Err(e),
            EventError::Function { t, source } => EventError::Function { t, source },
            EventError::NonFinite { t, index } => EventError::NonFinite { t, index },
            EventError::Dimension {
                what,
                expected,
                got,
            } => EventError::Dimension {
                what,
                expected,
                got,
            },
            EventError::NotConverged {
                index,
                t_lo,
                t_hi,
                iters,
            } => EventError::NotConverged {
                index,
                t_lo,
                t_hi,
                iters,
            },
        })
    }
}

/// Evaluates the event functions on the dense output of the last step.
pub(crate) struct Sampler<'a, L, G> {
    pub(crate) step: L,
    pub(crate) funcs: &'a mut G,
    pub(crate) s: &'a mut Scratch,
    pub(crate) counters: &'a mut LocatorCounters,
}

impl<L: LastStep, G: EventFunctions> Sampler<'_, L, G> {
    /// The stepper.
    fn stepper(&self) -> &L::Stepper {
        self.step.stepper()
    }

    /// The state at `t` into `y`: the stored ends of the step exactly, the dense output
    /// inside (completed first).
    fn state_at(&mut self, t: Real) -> Result<(), LocateError<G, L::Error>> {
        let st = self.step.stepper();
        if t == st.t() {
            self.s.y.copy_from_slice(st.y());
        } else if t == st.t_prev() {
            self.s.y.copy_from_slice(st.y_prev());
        } else {
            self.step.dense(t, &mut self.s.y)?;
        }
        Ok(())
    }

    /// The derivative `ẏ(t)` into `dy`: the stored ends of the step exactly, the dense
    /// output's derivative inside (completed first).
    fn derivative_at(&mut self, t: Real) -> Result<(), LocateError<G, L::Error>> {
        let st = self.step.stepper();
        if t == st.t() {
            self.s.dy.copy_from_slice(st.dy());
        } else if t == st.t_prev() {
            self.s.dy.copy_from_slice(st.dy_prev());
        } else {
            self.step.dense_derivative(t, &mut self.s.dy)?;
        }
        Ok(())
    }

    /// `g(t)` into `scratch.g`.
    pub(crate) fn values(&mut self, t: Real) -> Result<(), LocateError<G, L::Error>> {
        self.state_at(t)?;
        self.counters.value_evals += 1;
        self.funcs
            .values(t, &self.s.y, &mut self.s.g)
            .map_err(|source| EventError::Function { t, source })
    }

    /// `g(t)` into `scratch.g` at an interior sample of the step: stand-ins allowed (see
    /// [`EventFunctions::interior_values`]).
    fn interior_values(&mut self, t: Real) -> Result<(), LocateError<G, L::Error>> {
        self.counters.value_evals += 1;
        let stateless = (self.funcs)
            .interior_values_without_state(t, &mut self.s.g)
            .map_err(|source| EventError::Function { t, source })?;
        if stateless {
            return Ok(());
        }
        self.state_at(t)?;
        self.funcs
            .interior_values(t, &self.s.y, &mut self.s.g)
            .map_err(|source| EventError::Function { t, source })
    }

    /// The stand-ins of every interior sample into `scratch.g`, if the functions have them
    /// for all `samples` of them (see [`EventFunctions::interior_stand_ins`]); `t` is the
    /// first one's time, for an error.
    fn interior_stand_ins(
        &mut self,
        t: Real,
        samples: usize,
    ) -> Result<bool, LocateError<G, L::Error>> {
        let given = (self.funcs)
            .interior_stand_ins(samples, &mut self.s.g)
            .map_err(|source| EventError::Function { t, source })?;
        if given {
            self.counters.value_evals += samples as u64;
            self.counters.rate_evals += samples as u64;
        }
        Ok(given)
    }

    /// `gᵢ(t)` of the one function `i` (see [`EventFunctions::value`]).
    fn value(&mut self, t: Real, i: usize) -> Result<Real, LocateError<G, L::Error>> {
        self.state_at(t)?;
        self.counters.value_evals += 1;
        self.funcs
            .value(t, &self.s.y, i, &mut self.s.g)
            .map_err(|source| EventError::Function { t, source })
    }

    /// `ġᵢ(t)` of the one function `i`; [`value`](Self::value) at the same `t` must come
    /// just before. The caller's rate if it has rates, else the one-sided difference of
    /// [`rates`](Self::rates).
    fn rate(&mut self, t: Real, i: usize) -> Result<Real, LocateError<G, L::Error>> {
        self.derivative_at(t)?;
        let given = self
            .funcs
            .rate(t, &self.s.y, &self.s.dy, i, &mut self.s.gd)
            .map_err(|source| EventError::Function { t, source })?;
        match given {
            Some(gd) => {
                self.counters.rate_evals += 1;
                Ok(gd)
            }
            None => {
                self.values(t)?;
                self.rates(t)?;
                Ok(self.s.gd[i])
            }
        }
    }

    /// The caller's `ġ(t)` into `scratch.gd`, if it has rates; `y` must hold the state
    /// at `t` ([`values`](Self::values) at the same `t` just before).
    pub(crate) fn caller_rates(&mut self, t: Real) -> Result<bool, LocateError<G, L::Error>> {
        self.derivative_at(t)?;
        let given = self
            .funcs
            .rates(t, &self.s.y, &self.s.dy, &mut self.s.gd)
            .map_err(|source| EventError::Function { t, source })?;
        if given {
            self.counters.rate_evals += 1;
        }
        Ok(given)
    }

    /// `ġ(t)` into `scratch.gd`; [`values`](Self::values) at the same `t` must come
    /// just before. Uses the caller's rates if it has them, else a one-sided difference
    /// of `g` along the dense output with `δ = √ε h` (the step must not be empty).
    pub(crate) fn rates(&mut self, t: Real) -> Result<(), LocateError<G, L::Error>> {
        if self.caller_rates(t)? {
            return Ok(());
        }
        self.difference_rates(t)
    }

    /// [`rates`](Self::rates) at an interior sample, after
    /// [`interior_values`](Self::interior_values) at the same `t`: the caller's
    /// [`EventFunctions::interior_rates`] (stand-ins allowed), else the difference.
    fn interior_rates(&mut self, t: Real) -> Result<(), LocateError<G, L::Error>> {
        let stateless = (self.funcs)
            .interior_rates_without_state(t, &mut self.s.gd)
            .map_err(|source| EventError::Function { t, source })?;
        if stateless {
            self.counters.rate_evals += 1;
            return Ok(());
        }
        self.derivative_at(t)?;
        let given = self
            .funcs
            .interior_rates(t, &self.s.y, &self.s.dy, &mut self.s.gd)
            .map_err(|source| EventError::Function { t, source })?;
        if given {
            self.counters.rate_evals += 1;
            return Ok(());
        }
        self.difference_rates(t)
    }

    /// `ġ(t)` into `scratch.gd` by a one-sided difference of `g` along the dense output
    /// (see [`rates`](Self::rates)).
    fn difference_rates(&mut self, t: Real) -> Result<(), LocateError<G, L::Error>> {
        let st = self.step.stepper();
        let (t0, t1) = (st.t_prev(), st.t());
        let delta = (Real::EPSILON.sqrt() * (t1 - t0)).max(16.0 * Real::EPSILON * t.abs());
        let t2 = if t + delta <= t1 {
            t + delta
        } else {
            t - delta
        };
        if t2 == t1 {
            self.s.y2.copy_from_slice(st.y());
        } else {
            self.step.dense(t2, &mut self.s.y2)?;
        }
        self.counters.value_evals += 1;
        self.funcs
            .values(t2, &self.s.y2, &mut self.s.g2)
            .map_err(|source| EventError::Function { t: t2, source })?;
        let inv = 1.0 / (t2 - t);
        for ((gd, g2), g) in self.s.gd.iter_mut().zip(&self.s.g2).zip(&self.s.g) {
            *gd = (g2 - g) * inv;
        }
        Ok(())
    }
}

/// The time tolerance of a bracket `[a, b]` in a step of length `h`:
/// `4 ε max(|a|, |b|) + t_tol`, i.e. 4 ulp of the time, with a floor of `10⁻³ ε h` so
/// that a root at `t = 0` is bracketed in a bounded number of iterations.
pub(crate) fn time_tol(a: Real, b: Real, h: Real, t_tol: Real) -> Real {
    4.0 * Real::EPSILON * a.abs().max(b.abs()).max(1e-3 * h) + t_tol
}

impl EventLocator {
    /// A locator for states of dimension `n` and `m` event functions.
    pub fn new(n: usize, m: usize, settings: LocatorSettings) -> Self {
        let k2 = settings.samples + 2;
        Self {
            n,
            m,
            samples: Samples {
                ts: vec![0.0; k2],
                gs: vec![0.0; k2 * m],
                gds: vec![0.0; k2 * m],
                known: vec![false; k2],
            },
            scratch: Scratch {
                y: vec![0.0; n],
                dy: vec![0.0; n],
                y2: vec![0.0; n],
                g: vec![0.0; m],
                gd: vec![0.0; m],
                g2: vec![0.0; m],
            },
            done: vec![false; m],
            found: Vec::with_capacity(m),
            counters: LocatorCounters::default(),
            settings,
        }
    }

    /// Changes the number of event functions to `m` (a broad phase samples a different set
    /// of functions each step). The vectors keep their allocations as `m` shrinks.
    pub fn set_len(&mut self, m: usize) {
        if m == self.m {
            return;
        }
        let k2 = self.settings.samples + 2;
        self.m = m;
        self.samples.gs.resize(k2 * m, 0.0);
        self.samples.gds.resize(k2 * m, 0.0);
        for v in [
            &mut self.scratch.g,
            &mut self.scratch.gd,
            &mut self.scratch.g2,
        ] {
            v.resize(m, 0.0);
        }
        self.done.resize(m, false);
    }

    /// Reserves room for `m` event functions, so that [`Self::set_len`] up to `m` does not
    /// allocate.
    pub fn reserve(&mut self, m: usize) {
        let k2 = self.settings.samples + 2;
        let more = |len: usize, want: usize| want.saturating_sub(len);
        self.samples.gs.reserve(more(self.samples.gs.len(), k2 * m));
        self.samples
            .gds
            .reserve(more(self.samples.gds.len(), k2 * m));
        for v in [
            &mut self.scratch.g,
            &mut self.scratch.gd,
            &mut self.scratch.g2,
        ] {
            v.reserve(more(v.len(), m));
        }
        self.done.reserve(more(self.done.len(), m));
        self.found.reserve(more(self.found.len(), m));
    }

    /// The settings.
    pub fn settings(&self) -> &LocatorSettings {
        &self.settings
    }

    /// The number `m` of event functions.
    pub fn len(&self) -> usize {
        self.m
    }

    /// Whether there are no event functions.
    pub fn is_empty(&self) -> bool {
        self.m == 0
    }

    /// Work since the locator was built.
    pub fn counters(&self) -> LocatorCounters {
        self.counters
    }

    /// The events of the last [`locate`](Self::locate): the earliest and every other
    /// function's event within `simultaneity` of it, sorted by time (then index).
    pub fn events(&self) -> &[Event] {
        &self.found
    }

    pub(crate) fn check_dims<St: Stepper, E: std::error::Error + 'static, I>(
        &self,
        stepper: &St,
        armed: &[bool],
    ) -> Result<(), EventError<E, I>>
    where
        I: std::error::Error + 'static,
    {
        if stepper.dim() != self.n {
            return Err(EventError::Dimension {
                what: "state",
                expected: self.n,
                got: stepper.dim(),
            });
        }
        if armed.len() != self.m {
            return Err(EventError::Dimension {
                what: "armed flags",
                expected: self.m,
                got: armed.len(),
            });
        }
        Ok(())
    }

    /// Finds the earliest closing event of any armed function in the last step
    /// `[t_prev, t]` of `stepper` (a function whose flag in `armed` is false is
    /// ignored). Returns it, or `None`; [`events`](Self::events) then lists the
    /// simultaneous ones. Nothing is changed in the stepper: call
    /// [`settle`](Self::settle) to move it to the event at full order.
    ///
    /// Stages: (1) sample `g` (and `ġ`) at `k + 2` equally spaced points; (2) walk the
    /// sample intervals in time order, classifying each armed function (start, sign
    /// change, dip, bounce); (3) refine each candidate with the Illinois method on the
    /// dense output; (4) keep the earliest and those within `simultaneity` of it.
    ///
    /// The stepper is only read: where the location reads its dense output, that must be
    /// complete ([`Stepper::complete_dense`]; DOP853's is not after a step), else the
    /// error is `EventError::Integrate(IntegrateError::DenseIncomplete)`. With the system
    /// at hand, [`locate_completing_dense`](Self::locate_completing_dense) completes it
    /// when it is first needed.
    pub fn locate<St: Stepper, G: EventFunctions>(
        &mut self,
        stepper: &St,
        funcs: &mut G,
        armed: &[bool],
    ) -> Result<Option<Event>, EventError<G::Error>> {
        self.locate_step(stepper, funcs, armed)
    }

    /// [`locate`](Self::locate), completing the dense output of the last step
    /// ([`Stepper::complete_dense`] with `sys`) the first time it is read inside the step:
    /// a step located from its ends and stand-ins alone does not pay for it. A failure of
    /// `sys` there is `EventError::Integrate(IntegrateError::Rhs)`.
    pub fn locate_completing_dense<St: Stepper, Sys: OdeSystem, G: EventFunctions>(
        &mut self,
        stepper: &mut St,
        sys: &mut Sys,
        funcs: &mut G,
        armed: &[bool],
    ) -> Result<Option<Event>, EventError<G::Error, Sys::Error>> {
        self.locate_step(Completing { stepper, sys }, funcs, armed)
    }

    /// [`locate`](Self::locate) on `step`.
    fn locate_step<L: LastStep, G: EventFunctions>(
        &mut self,
        step: L,
        funcs: &mut G,
        armed: &[bool],
    ) -> Result<Option<Event>, LocateError<G, L::Error>> {
        self.found.clear();
        let stepper = step.stepper();
        self.check_dims(stepper, armed)?;
        let (t0, t1) = (stepper.t_prev(), stepper.t());
        if t1 <= t0 || !armed.iter().any(|&a| a) {
            return Ok(None);
        }
        self.counters.calls += 1;
        let mut sp = Sampler {
            step,
            funcs,
            s: &mut self.scratch,
            counters: &mut self.counters,
        };
        if sample(&mut sp, &mut self.samples, &self.settings, armed)? {
            // Positive everywhere the step was sampled, with stand-ins inside: no event.
            return Ok(None);
        }

        let (m, parts) = (self.m, self.settings.samples + 1);
        let sim = self.settings.simultaneity;
        self.done.fill(false);
        let mut t_first = Real::INFINITY;
        let extremum_search = self.settings.extremum_search;
        for j in 0..parts {
            if self.samples.ts[j] > t_first + sim {
                break;
            }
            // The samples at both ends of the interval, of every function.
            let (ends, rates) = (&self.samples.gs, &self.samples.gds);
            let (g_a, g_b) = (&ends[j * m..(j + 1) * m], &ends[(j + 1) * m..(j + 2) * m]);
            let (gd_a, gd_b) = (&rates[j * m..(j + 1) * m], &rates[(j + 1) * m..(j + 2) * m]);
            for (i, &is_armed) in armed.iter().enumerate() {
                if !is_armed || self.done[i] {
                    continue;
                }
                // Positive at both ends and no minimum between them to search: `classify`
                // has nothing to find (the common case, its tests in its order).
                if g_a[i] > 0.0
                    && g_b[i] > 0.0
                    && !(extremum_search && gd_a[i] < 0.0 && gd_b[i] > 0.0)
                {
                    continue;
                }
                if let Some(ev) = classify(&mut sp, &self.samples, &self.settings, m, i, j)? {
                    self.done[i] = true;
                    t_first = t_first.min(ev.t);
                    self.found.push(ev);
                }
            }
        }
        self.found.retain(|e| e.t <= t_first + sim);
        self.found
            .sort_unstable_by(|a, b| a.t.total_cmp(&b.t).then(a.index.cmp(&b.index)));
        Ok(self.found.first().copied())
    }
}

/// Stage 1: `g` at the `k + 2` sample times (the interior ones through
/// [`EventFunctions::interior_values`] and [`EventFunctions::interior_rates`]), and `ġ` where it is needed (everywhere with the
/// extremum search; else at the start, if an armed function is not positive there).
///
/// When the functions give stand-ins for every interior sample
/// ([`EventFunctions::interior_stand_ins`], asked after the start's sample), those are
/// written for all of them, with zero rates; if then every armed function is positive
/// at the start, at the stand-ins and at the end, no interval can have an event (a sign
/// change needs a value `≤ 0`; a minimum to search, a rate `< 0` at an interval's start
/// and `> 0` at its end, and every interval has a zero rate at one end; a maximum, values
/// `≤ 0`): the rates at the end are not sampled, and `true` says the step has no event.
fn sample<L: LastStep, G: EventFunctions>(
    sp: &mut Sampler<'_, L, G>,
    smp: &mut Samples,
    settings: &LocatorSettings,
    armed: &[bool],
) -> Result<bool, LocateError<G, L::Error>> {
    let (t0, t1) = (sp.stepper().t_prev(), sp.stepper().t());
    let parts = settings.samples + 1;
    let m = armed.len();
    let time = |j: usize| {
        if j == parts {
            t1
        } else {
            t0 + (t1 - t0) * (j as Real / parts as Real)
        }
    };
    let mut stand_ins = false;
    for j in 0..=parts {
        if stand_ins && j < parts {
            // Written with the start's sample.
            continue;
        }
        let t = time(j);
        smp.ts[j] = t;
        if j == 0 || j == parts {
            sp.values(t)?;
        } else {
            sp.interior_values(t)?;
        }
        check_finite(&sp.s.g, armed, t)?;
        smp.gs[j * m..(j + 1) * m].copy_from_slice(&sp.s.g);
        if stand_ins {
            if all_positive(smp, armed, [0, 1, parts]) {
                return Ok(true);
            }
            // Every interval is classified: the other interior samples are the first's.
            for k in 2..parts {
                smp.gs.copy_within(m..2 * m, k * m);
                smp.ts[k] = time(k);
                smp.known[k] = smp.known[1];
                if smp.known[k] {
                    smp.gds[k * m..(k + 1) * m].fill(0.0);
                }
            }
        }
        let at_contact = j == 0 && sp.s.g.iter().zip(armed).any(|(g, &a)| a && *g <= 0.0);
        smp.known[j] = settings.extremum_search || at_contact;
        if smp.known[j] {
            if j == 0 || j == parts {
                sp.rates(t)?;
            } else {
                sp.interior_rates(t)?;
            }
            check_finite(&sp.s.gd, armed, t)?;
            smp.gds[j * m..(j + 1) * m].copy_from_slice(&sp.s.gd);
        }
        if j == 0 && parts > 1 && sp.interior_stand_ins(time(1), parts - 1)? {
            // The first interior sample; the others, the same, are written only if the
            // step needs its intervals classified (above, at the step's end).
            check_finite(&sp.s.g, armed, time(1))?;
            smp.ts[1] = time(1);
            smp.gs[m..2 * m].copy_from_slice(&sp.s.g);
            smp.known[1] = settings.extremum_search;
            if smp.known[1] {
                smp.gds[m..2 * m].fill(0.0);
            }
            stand_ins = true;
        }
    }
    Ok(false)
}

/// Whether every armed function is positive at the samples `js`.
fn all_positive<const K: usize>(smp: &Samples, armed: &[bool], js: [usize; K]) -> bool {
    let m = armed.len();
    js.iter().all(|&j| {
        let g = &smp.gs[j * m..(j + 1) * m];
        g.iter().zip(armed).all(|(&g, &a)| !a || g > 0.0)
    })
}

fn check_finite<E: std::error::Error + 'static, I: std::error::Error + 'static>(
    v: &[Real],
    armed: &[bool],
    t: Real,
) -> Result<(), EventError<E, I>> {
    // Every value finite (unarmed ones too, as a rule): one pass without branches.
    if v.iter().fold(true, |ok, x| ok & x.is_finite()) {
        return Ok(());
    }
    match v.iter().zip(armed).position(|(x, &a)| a && !x.is_finite()) {
        Some(index) => Err(EventError::NonFinite { t, index }),
        None => Ok(()),
    }
}

/// Stages 2–3 for function `i` on the sample interval `j`: the event it has there, if any.
fn classify<L: LastStep, G: EventFunctions>(
    sp: &mut Sampler<'_, L, G>,
    smp: &Samples,
    settings: &LocatorSettings,
    m: usize,
    i: usize,
    j: usize,
) -> Result<Option<Event>, LocateError<G, L::Error>> {
    let (a, b) = (smp.ts[j], smp.ts[j + 1]);
    let (ga, gb) = (smp.gs[j * m + i], smp.gs[(j + 1) * m + i]);
    let event = |kind, t_lo, t_hi| Event {
        index: i,
        kind,
        t: t_hi,
        t_lo,
        t_hi,
    };
    // At the step's start, not separated: closing is an event, opening is not.
    if j == 0 && ga <= 0.0 {
        let gda = smp.gds[i];
        if gda < 0.0 || (gda == 0.0 && gb < ga) {
            return Ok(Some(event(EventKind::AtStart, a, a)));
        }
    }
    // A sign change between the samples.
    if ga > 0.0 && gb <= 0.0 {
        let (lo, hi) = root(sp, settings, i, (a, ga), (b, gb))?;
        return Ok(Some(event(EventKind::Crossing, lo, hi)));
    }
    if !settings.extremum_search {
        return Ok(None);
    }
    let (gda, gdb) = (smp.gds[j * m + i], smp.gds[(j + 1) * m + i]);
    if ga > 0.0 && gb > 0.0 && gda < 0.0 && gdb > 0.0 {
        // A minimum between two positive samples: does it dip to g ≤ 0? Not if it
        // clearly cannot (most pairs of a many-body scene, far apart, at every step).
        if cannot_dip(ga, gda, gb, gdb, b - a) {
            return Ok(None);
        }
        let found = extremum(sp, settings, i, (a, -gda), (b, -gdb), Extremum::Min)?;
        if let Found::Crossed(t, g_t) = found {
            let (lo, hi) = root(sp, settings, i, (a, ga), (t, g_t))?;
            return Ok(Some(event(EventKind::Grazing, lo, hi)));
        }
    } else if ga <= 0.0 && gb <= 0.0 && gda >= 0.0 && gdb < 0.0 {
        // A maximum between two non-positive samples: does it rise to g > 0?
        if gda == 0.0 {
            return Ok(Some(event(EventKind::Reclosing, a, a)));
        }
        match extremum(sp, settings, i, (a, gda), (b, gdb), Extremum::Max)? {
            Found::Crossed(t, g_t) => {
                let (lo, hi) = root(sp, settings, i, (t, g_t), (b, gb))?;
                return Ok(Some(event(EventKind::Bounce, lo, hi)));
            }
            Found::Extremum(lo, hi) => {
                return Ok(Some(event(EventKind::Reclosing, lo, hi)));
            }
        }
    }
    Ok(None)
}

/// Whether a function that is positive at both ends of `[a, a + h]` (`g_a`, `g_b`),
/// falling at `a` (`ġ_a < 0`) and rising at `a + h` (`ġ_b > 0`), clearly stays positive
/// in between, so that the extremum search can be skipped.
///
/// For `g` convex on the interval (`ġ` increasing from `ġ_a` to `ġ_b`, one minimum), the
/// tangents at the ends are lower bounds: `g(t) ≥ g_a + ġ_a (t − a) ≥ g_a + ġ_a h` and
/// `g(t) ≥ g_b − ġ_b h`. The test asks the larger of the two bounds to stay positive with
/// the end slopes doubled, `max(g_a + 2 ġ_a h, g_b − 2 ġ_b h) > 0`: a margin for a
/// non-convex `g` whose slope steepens inside the interval to up to twice its values at
/// the ends. (The search itself assumes one extremum between two samples, the resolution
/// of the sampling.) Without it, every pair of a many-body scene with a minimum of its
/// gap inside a sample interval, however far apart, was searched to the time tolerance
/// at every step: a cost of ~N⁴ per step for N bodies.
#[doc(hidden)]
pub fn cannot_dip(g_a: Real, gd_a: Real, g_b: Real, gd_b: Real, h: Real) -> bool {
    (g_a + 2.0 * gd_a * h).max(g_b - 2.0 * gd_b * h) > 0.0
}

/// The root of `gᵢ` in `[lo, hi]`, `gᵢ(lo) > 0 ≥ gᵢ(hi)`, as a bracket to the time
/// tolerance (Illinois on the dense output).
pub(crate) fn root<L: LastStep, G: EventFunctions>(
    sp: &mut Sampler<'_, L, G>,
    settings: &LocatorSettings,
    i: usize,
    lo: (Real, Real),
    hi: (Real, Real),
) -> Result<(Real, Real), LocateError<G, L::Error>> {
    let h = sp.stepper().t() - sp.stepper().t_prev();
    let solved = illinois(
        |t| {
            let g = sp.value(t, i)?;
            if g.is_finite() {
                Ok(Probe::Value(g))
            } else {
                Err(EventError::NonFinite { t, index: i })
            }
        },
        lo,
        hi,
        |a, b| time_tol(a, b, h, settings.t_tol),
        settings.max_iter,
    )?;
    match solved {
        Solved::Bracket { lo, hi, .. } => Ok((lo, hi)),
        Solved::Stopped { t, .. } => Ok((t, t)),
        Solved::NotConverged { lo, hi, iters } => Err(EventError::NotConverged {
            index: i,
            t_lo: lo,
            t_hi: hi,
            iters,
        }),
    }
}

#[derive(Clone, Copy, PartialEq)]
enum Extremum {
    Min,
    Max,
}

/// What an extremum search found.
enum Found {
    /// A point `(t, g(t))` on the other side of zero (`g ≤ 0` for a minimum, `g > 0` for
    /// a maximum).
    Crossed(Real, Real),
    /// The extremum, bracketed, without reaching the other side.
    Extremum(Real, Real),
}

/// Searches the extremum of `gᵢ` in `[a, b]` by Illinois on `±ġᵢ` (`+ġ` for a maximum,
/// `−ġ` for a minimum; positive at `a`, negative at `b`), stopping as soon as a point
/// on the other side of zero is met.
fn extremum<L: LastStep, G: EventFunctions>(
    sp: &mut Sampler<'_, L, G>,
    settings: &LocatorSettings,
    i: usize,
    a: (Real, Real),
    b: (Real, Real),
    kind: Extremum,
) -> Result<Found, LocateError<G, L::Error>> {
    let h = sp.stepper().t() - sp.stepper().t_prev();
    let mut crossed = Real::NAN;
    let solved = illinois(
        |t| {
            let g = sp.value(t, i)?;
            let other_side = match kind {
                Extremum::Min => g <= 0.0,
                Extremum::Max => g > 0.0,
            };
            if other_side {
                crossed = g;
                return Ok(Probe::Stop);
            }
            let gd = sp.rate(t, i)?;
            if !gd.is_finite() {
                return Err(EventError::NonFinite { t, index: i });
            }
            Ok(Probe::Value(if kind == Extremum::Min { -gd } else { gd }))
        },
        a,
        b,
        |a, b| time_tol(a, b, h, settings.t_tol),
        settings.max_iter,
    )?;
    Ok(match solved {
        Solved::Stopped { t, .. } => Found::Crossed(t, crossed),
        Solved::Bracket { lo, hi, .. } | Solved::NotConverged { lo, hi, .. } => {
            Found::Extremum(lo, hi)
        }
    })
}
