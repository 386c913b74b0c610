//! Contact geometry through parry2d: for now the signed gap of a contact pair at the current
//! poses (used to validate scenes and, later, as the event function of an impact).
//!
//! Sign convention: the gap `g` is positive when the shapes are apart, zero when they
//! touch and negative (minus the penetration depth) when they overlap; parry's contact
//! normal points from the pair's collider `a` towards `b`.

mod gap;

pub use gap::{ContactError, signed_gap};
