//! Contact geometry through parry2d: the signed gap of a contact pair (the event function
//! of an impact), and the contact frame with the Jacobians of the relative velocity (the
//! input of the impact map).
//!
//! Sign convention: the gap `g` is positive when the shapes are apart, zero when they
//! touch and negative (minus the penetration depth) when they overlap. parry's normal
//! ([`PairContact::normal`]) points from the pair's collider `a` towards `b`; the impact
//! frame ([`ContactFrame::n`]) points the other way, from `b` towards `a`, so that the
//! impulse it reports acts on `a` (always a body).

pub mod broad;
mod frame;
#[doc(hidden)]
pub mod gap;
#[doc(hidden)]
pub mod manifold;
#[doc(hidden)]
pub mod penetration;
pub mod query;

pub use frame::{
    ContactFrame, FrameWorkspace, Tangent, contact_frame, frame_at, frame_of, relative_velocity,
    relative_velocity_of,
};
pub use gap::{ContactError, PairContact, pair_contact, pair_contact_of, signed_gap};
pub use manifold::{
    ClosedVertex, ContactPoints, MAX_CONTACT_POINTS, ManifoldWorkspace, contact_points,
    contact_points_of, is_plane_pair,
};
