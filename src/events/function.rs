//! The event functions: `m` scalar functions `gᵢ(t, y)` whose closing crossings
//! (from `g > 0` to `g ≤ 0`) are events, and optionally their time derivatives.

use crate::math::Real;

/// `m` event functions `gᵢ(t, y)`, evaluated together (the simulation loop computes the
/// signed gaps of all contact pairs from `y`). `gᵢ > 0` means separated.
///
/// [`rates`](EventFunctions::rates) may supply `ġᵢ = ∂gᵢ/∂t + ∇gᵢ · ẏ`; for a gap this is
/// the normal velocity, cheap to compute from `y` alone. Without it the locator
/// differentiates `g` along the dense output numerically (one more evaluation of
/// [`values`](EventFunctions::values) per sample).
///
/// Closures `FnMut(t, y, g) -> Result<(), E>` implement this trait (values only); see
/// also [`FnEvents`].
pub trait EventFunctions {
    /// The error of a failing evaluation (e.g. an unsupported shape pair).
    type Error: std::error::Error + 'static;

    /// Writes `gᵢ(t, y)`, `i = 0 … m−1`, into `g`.
    fn values(&mut self, t: Real, y: &[Real], g: &mut [Real]) -> Result<(), Self::Error>;

    /// Writes `gᵢ(t, y)` at an interior sample of a step's regular sampling (not at its
    /// ends, not in a root search): a function that the caller can show not to reach zero
    /// anywhere in the step may get a positive stand-in instead of its value, since the
    /// locator reads only the signs of such samples. The default computes every value.
    fn interior_values(&mut self, t: Real, y: &[Real], g: &mut [Real]) -> Result<(), Self::Error> {
        self.values(t, y, g)
    }

    /// [`interior_values`](EventFunctions::interior_values) at `t` when every function
    /// has a stand-in there, so that no state is needed: writes them into `g` and returns
    /// `true` (the locator then skips the dense output at `t`, and asks
    /// [`interior_rates_without_state`](EventFunctions::interior_rates_without_state) for
    /// the rates). `false`, with nothing written, when a value needs the state. The
    /// default: `false`.
    fn interior_values_without_state(
        &mut self,
        _t: Real,
        _g: &mut [Real],
    ) -> Result<bool, Self::Error> {
        Ok(false)
    }

    /// The rates after [`interior_values_without_state`] gave the values at `t` (every
    /// function a stand-in; see [`interior_rates`](EventFunctions::interior_rates)):
    /// written into `g_dot` with `true`, or `false`, with nothing written, when they need
    /// the state. The default: `false`.
    ///
    /// [`interior_values_without_state`]: EventFunctions::interior_values_without_state
    fn interior_rates_without_state(
        &mut self,
        _t: Real,
        _g_dot: &mut [Real],
    ) -> Result<bool, Self::Error> {
        Ok(false)
    }

    /// Whether every function has a stand-in at each of the `samples` interior samples of
    /// the step being located, asked once after the values and rates at the step's start:
    /// if so, writes them into `g` and returns `true` — they must be what
    /// [`interior_values_without_state`] writes at each of those samples, the same numbers
    /// at all of them (a stand-in is one number for the step), with the zero rates of
    /// [`interior_rates_without_state`] — and counts them as sampled. The locator then
    /// takes no interior sample: with every armed function positive at both ends of the
    /// step and at the stand-ins, whose rates are zero, no interval of the step has an
    /// event to classify (no sign change; no minimum to search, which needs a rate `< 0`
    /// followed by one `> 0`), and the step has none without the rates at its end.
    /// `false`, with nothing written, when some function needs a sample (the default).
    ///
    /// [`interior_values_without_state`]: EventFunctions::interior_values_without_state
    /// [`interior_rates_without_state`]: EventFunctions::interior_rates_without_state
    fn interior_stand_ins(&mut self, samples: usize, g: &mut [Real]) -> Result<bool, Self::Error> {
        let _ = (samples, g);
        Ok(false)
    }

    /// Writes `ġᵢ(t, y)` at an interior sample of a step's regular sampling, after
    /// [`interior_values`](EventFunctions::interior_values) at the same `t`, like
    /// [`rates`](EventFunctions::rates). A function that got a positive stand-in there
    /// (it cannot reach zero anywhere in the step) may get any rate `ġᵢ ≥ 0`: the
    /// locator searches a dip between two samples only where `ġ` goes from `< 0` to
    /// `> 0`, and a function without event in the step needs none, so a zero rate there
    /// changes no result. A caller with stand-ins should supply rates (the numerical
    /// difference of the default would mix a stand-in with a value). The default is
    /// [`rates`](EventFunctions::rates).
    fn interior_rates(
        &mut self,
        t: Real,
        y: &[Real],
        dy: &[Real],
        g_dot: &mut [Real],
    ) -> Result<bool, Self::Error> {
        self.rates(t, y, dy, g_dot)
    }

    /// `gᵢ(t, y)` of the one function `i` (a root or extremum search follows one
    /// function): the same number as [`values`](EventFunctions::values) gives it. The
    /// default computes them all into `g` (of length `m`) and returns `g[i]`.
    fn value(
        &mut self,
        t: Real,
        y: &[Real],
        i: usize,
        g: &mut [Real],
    ) -> Result<Real, Self::Error> {
        self.values(t, y, g)?;
        Ok(g[i])
    }

    /// `ġᵢ(t, y)` of the one function `i`, if the rates are available: the same number as
    /// [`rates`](EventFunctions::rates) gives it. The default computes them all into
    /// `g_dot` (of length `m`).
    fn rate(
        &mut self,
        t: Real,
        y: &[Real],
        dy: &[Real],
        i: usize,
        g_dot: &mut [Real],
    ) -> Result<Option<Real>, Self::Error> {
        Ok(self.rates(t, y, dy, g_dot)?.then(|| g_dot[i]))
    }

    /// Writes `ġᵢ(t, y)` into `g_dot` given `ẏ = dy` and returns `Ok(true)`, or returns
    /// `Ok(false)` if the rates are not available (the default).
    fn rates(
        &mut self,
        t: Real,
        y: &[Real],
        dy: &[Real],
        g_dot: &mut [Real],
    ) -> Result<bool, Self::Error> {
        let _ = (t, y, dy, g_dot);
        Ok(false)
    }
}

impl<F, E> EventFunctions for F
where
    F: FnMut(Real, &[Real], &mut [Real]) -> Result<(), E>,
    E: std::error::Error + 'static,
{
    type Error = E;

    fn values(&mut self, t: Real, y: &[Real], g: &mut [Real]) -> Result<(), E> {
        self(t, y, g)
    }
}

/// The signature of an infallible rates closure `ġ(t, y, ẏ, out)`.
pub type RatesFn = fn(Real, &[Real], &[Real], &mut [Real]);

/// [`EventFunctions`] from infallible closures: `values(t, y, g)` and, optionally,
/// `rates(t, y, ẏ, ġ)`.
///
/// ```
/// use ricochet::events::{EventFunctions, FnEvents};
/// // A ball's height above the floor y = (height, velocity), and its rate.
/// let mut gap = FnEvents::with_rates(
///     |_t, y: &[f64], g: &mut [f64]| g[0] = y[0],
///     |_t, y: &[f64], _dy: &[f64], g_dot: &mut [f64]| g_dot[0] = y[1],
/// );
/// let (mut g, mut g_dot) = ([0.0], [0.0]);
/// gap.values(0.0, &[2.0, -1.0], &mut g).unwrap();
/// assert!(gap.rates(0.0, &[2.0, -1.0], &[-1.0, -9.81], &mut g_dot).unwrap());
/// assert_eq!((g, g_dot), ([2.0], [-1.0]));
/// ```
#[derive(Clone, Debug)]
pub struct FnEvents<G, R = RatesFn> {
    values: G,
    rates: Option<R>,
}

impl<G> FnEvents<G>
where
    G: FnMut(Real, &[Real], &mut [Real]),
{
    /// Values only: the locator differentiates numerically where it needs `ġ`.
    pub fn new(values: G) -> Self {
        Self {
            values,
            rates: None,
        }
    }
}

impl<G, R> FnEvents<G, R>
where
    G: FnMut(Real, &[Real], &mut [Real]),
    R: FnMut(Real, &[Real], &[Real], &mut [Real]),
{
    /// Values and rates.
    pub fn with_rates(values: G, rates: R) -> Self {
        Self {
            values,
            rates: Some(rates),
        }
    }
}

impl<G, R> EventFunctions for FnEvents<G, R>
where
    G: FnMut(Real, &[Real], &mut [Real]),
    R: FnMut(Real, &[Real], &[Real], &mut [Real]),
{
    type Error = std::convert::Infallible;

    fn values(&mut self, t: Real, y: &[Real], g: &mut [Real]) -> Result<(), Self::Error> {
        (self.values)(t, y, g);
        Ok(())
    }

    fn rates(
        &mut self,
        t: Real,
        y: &[Real],
        dy: &[Real],
        g_dot: &mut [Real],
    ) -> Result<bool, Self::Error> {
        match &mut self.rates {
            Some(r) => {
                r(t, y, dy, g_dot);
                Ok(true)
            }
            None => Ok(false),
        }
    }
}
