//! The system `ẏ = f(t, y)` that the integrators advance.

use std::convert::Infallible;

use crate::math::Real;

/// A first-order system `ẏ = f(t, y)` of fixed dimension `n`.
///
/// The right-hand side may fail (for a multibody model, a mass matrix that is not
/// positive definite); the integrators then stop and return
/// [`IntegrateError::Rhs`](super::IntegrateError::Rhs) with the time of the failing
/// evaluation. `rhs` takes `&mut self` so that an implementation can keep its scratch
/// (a `Data` workspace) inside.
pub trait OdeSystem {
    /// The error of a failing right-hand side.
    type Error: std::error::Error + 'static;

    /// The dimension `n` of the state `y`.
    fn dim(&self) -> usize;

    /// Writes `f(t, y)` into `dy` (both of length `n`).
    fn rhs(&mut self, t: Real, y: &[Real], dy: &mut [Real]) -> Result<(), Self::Error>;

    /// How many leading components of `y` the step-size control weighs (default: all).
    /// Quadratures appended after them — running integrals of functions of the others,
    /// such as the works of an energy audit — may be left out: their accuracy follows from
    /// the others', and zero components would only dilute the RMS error norm.
    fn controlled(&self) -> usize {
        self.dim()
    }
}

/// An [`OdeSystem`] made of a closure `f(t, y, dy)` that cannot fail (tests, benches,
/// small examples).
///
/// ```
/// use ricochet::integrate::{FnSystem, OdeSystem};
/// // The harmonic oscillator ẍ = −x as y = (x, ẋ).
/// let mut sys = FnSystem::new(2, |_t, y: &[f64], dy: &mut [f64]| {
///     dy[0] = y[1];
///     dy[1] = -y[0];
/// });
/// let mut dy = [0.0; 2];
/// sys.rhs(0.0, &[1.0, 0.0], &mut dy).unwrap();
/// assert_eq!(dy, [0.0, -1.0]);
/// ```
#[derive(Clone, Debug)]
pub struct FnSystem<F> {
    dim: usize,
    f: F,
}

impl<F> FnSystem<F>
where
    F: FnMut(Real, &[Real], &mut [Real]),
{
    /// A system of dimension `dim` with right-hand side `f(t, y, dy)`.
    pub fn new(dim: usize, f: F) -> Self {
        Self { dim, f }
    }
}

impl<F> OdeSystem for FnSystem<F>
where
    F: FnMut(Real, &[Real], &mut [Real]),
{
    type Error = Infallible;

    fn dim(&self) -> usize {
        self.dim
    }

    fn rhs(&mut self, t: Real, y: &[Real], dy: &mut [Real]) -> Result<(), Infallible> {
        (self.f)(t, y, dy);
        Ok(())
    }
}
