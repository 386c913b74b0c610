//! Contact geometry through parry2d: the signed gap of a contact pair (the event function
//! of an impact), the contact frame with the Jacobians of the relative velocity (the
//! input of the impact map), and the contact points of a pair lying on a flat feature
//! ([`contact_points`], for time-stepping).
//!
//! Sign convention: the gap `g` is positive when the shapes are apart, zero when they
//! touch and negative (minus the penetration depth) when they overlap. parry's normal
//! ([`PairContact::normal`]) points from the pair's collider `a` towards `b`; the impact
//! frame ([`ContactFrame::n`]) points the other way, from `b` towards `a`, so that the
//! impulse it reports acts on `a` (always a body).

mod frame;
mod gap;
mod manifold;
mod penetration;

pub use frame::{ContactFrame, FrameWorkspace, contact_frame, frame_of_contact};
pub use gap::{ContactError, PairContact, pair_contact, signed_gap};
pub use manifold::{MAX_CONTACT_POINTS, contact_points};
