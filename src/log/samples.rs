//! The `/state` and `/tf` samples handed to the sink thread as numbers, encoded there.
//!
//! A run's samples are most of its log (Kane's pendulum, 5 s at 100 Hz: 1,046 of its 1,083
//! messages) and their encoding (JSON for `/state`, protobuf for `/tf`) was about half of
//! what logging costs the simulation thread (issue 16): 4,400 of its 8,600 instructions per
//! sample. The simulation thread now checks a sample (a bad number is still reported at
//! once, naming the field) and copies its numbers — the bits of each `f64` and the small
//! integers, as `u64` words — into the batch; the sink thread lays them out on its own copy
//! of the record and encodes it with the same encoders
//! ([`StateRecord::append_json`](super::records::StateRecord::append_json),
//! [`append_frame_transforms`](super::foxglove::append_frame_transforms)), so the bytes are
//! those the calling thread wrote.
//!
//! What is not a number — the lengths of `q` and `u`, the names of the contact pairs, the
//! frame names — is the *layout* of a sample. The sink thread keeps the last layout it was
//! given (a whole record, cloned); the calling side sends a new one with the first sample
//! and whenever a sample's layout differs from the last one sent (a pair starts or stops
//! being listed): a run in its steady state copies numbers only and allocates nothing.
//!
//! The `/tf` samples of a run ([`RunLogger`](super::RunLogger)) go as *planar* numbers:
//! the time, then each body's position and rotation as they are in its pose (`x, y, cos θ,
//! sin θ`) and the view's; the sink thread computes each rotation's angle and quaternion
//! (`atan2`, `sin_cos`: ~670 instructions a sample, which the simulation's thread no longer
//! spends) with the same functions, so the bytes are those the calling thread wrote
//! ([`apply_planar_words`]).
//!
//! Samples go this way while the sink thread keeps up
//! ([`Sink::defers_samples`](super::sink::Sink::defers_samples)); otherwise the calling
//! thread encodes them. Only frame transforms whose timestamp, translation and rotation are all present, with a
//! normalized timestamp (what [`RunLogger`](super::RunLogger) writes), go this way; others
//! are encoded on the calling thread as before.

use super::foxglove::{FrameTransforms, Quaternion, Timestamp, Vector3, about_z, vector3};
use super::records::{ContactMode, StateRecord};

/// Whether a sample of layout `a` can be laid out on a record of layout `b`: the same
/// numbers of coordinates, speeds and contacts, the same pair names.
#[doc(hidden)]
pub fn same_state_layout(a: &StateRecord, b: &StateRecord) -> bool {
    a.q.len() == b.q.len()
        && a.u.len() == b.u.len()
        && a.contacts.len() == b.contacts.len()
        && (a.contacts.iter())
            .zip(&b.contacts)
            .all(|(x, y)| x.pair == y.pair)
}

/// Appends the numbers of `state` to `words`: `t`, `q`, `u`, the energies, the run's mode
/// and mode code, the impact count, then each contact's mode, mode code, gap and slip.
#[doc(hidden)]
pub fn state_words(words: &mut Vec<u64>, state: &StateRecord) {
    words.push(state.t.to_bits());
    words.extend(state.q.iter().map(|x| x.to_bits()));
    words.extend(state.u.iter().map(|x| x.to_bits()));
    let e = &state.energy;
    words.extend([
        e.kinetic.to_bits(),
        e.potential.to_bits(),
        e.total.to_bits(),
        u64::from(state.mode.code()),
        u64::from(state.mode_code),
        state.impact_count,
    ]);
    for c in &state.contacts {
        words.extend([
            u64::from(c.mode.code()),
            u64::from(c.mode_code),
            c.gap.to_bits(),
            u64::from(c.slip as u8),
        ]);
    }
}

/// Lays the numbers `words` (from [`state_words`] of a record of `state`'s layout) out on
/// `state`.
#[doc(hidden)]
pub fn apply_state_words(state: &mut StateRecord, words: &[u64]) {
    let mut w = words.iter().copied();
    let mut word = || w.next().unwrap_or_default();
    state.t = f64::from_bits(word());
    for x in &mut state.q {
        *x = f64::from_bits(word());
    }
    for x in &mut state.u {
        *x = f64::from_bits(word());
    }
    state.energy.kinetic = f64::from_bits(word());
    state.energy.potential = f64::from_bits(word());
    state.energy.total = f64::from_bits(word());
    state.mode = mode_of_code(word());
    state.mode_code = word() as u8;
    state.impact_count = word();
    for c in &mut state.contacts {
        c.mode = mode_of_code(word());
        c.mode_code = word() as u8;
        c.gap = f64::from_bits(word());
        c.slip = word() as u8 as i8;
    }
}

/// The mode whose [`ContactMode::code`] is `code`.
fn mode_of_code(code: u64) -> ContactMode {
    match code {
        1 => ContactMode::Sliding,
        2 => ContactMode::Sticking,
        3 => ContactMode::Impact,
        _ => ContactMode::Free,
    }
}

/// Whether `tf` can go as numbers: every transform with a timestamp (normalized), a
/// translation and a rotation.
#[doc(hidden)]
pub fn plain_transforms(tf: &FrameTransforms) -> bool {
    tf.transforms.iter().all(|t| {
        t.translation.is_some()
            && t.rotation.is_some()
            && (t.timestamp).is_some_and(|time| time.nsec() < 1_000_000_000)
    })
}

/// Whether transforms of layout `a` can be laid out on those of layout `b`: as many, with
/// the same parent and child frames.
#[doc(hidden)]
pub fn same_transforms_layout(a: &FrameTransforms, b: &FrameTransforms) -> bool {
    a.transforms.len() == b.transforms.len()
        && (a.transforms.iter()).zip(&b.transforms).all(|(x, y)| {
            x.parent_frame_id == y.parent_frame_id && x.child_frame_id == y.child_frame_id
        })
}

/// Appends the numbers of `tf` (which must be [plain](plain_transforms)) to `words`: for
/// each transform, its timestamp's seconds and nanoseconds, its translation `x, y, z` and
/// its rotation `x, y, z, w`.
#[doc(hidden)]
pub fn transforms_words(words: &mut Vec<u64>, tf: &FrameTransforms) {
    for t in &tf.transforms {
        let (sec, nsec) = t.timestamp.map_or((0, 0), |s| (s.sec(), s.nsec()));
        let v = t.translation.as_ref().map_or([0.0; 3], |v| [v.x, v.y, v.z]);
        let r = t
            .rotation
            .as_ref()
            .map_or([0.0; 4], |r| [r.x, r.y, r.z, r.w]);
        words.extend([u64::from(sec), u64::from(nsec)]);
        words.extend(v.iter().chain(&r).map(|x| x.to_bits()));
    }
}

/// Lays the numbers `words` (from [`transforms_words`] of transforms of `tf`'s layout) out
/// on `tf`.
#[doc(hidden)]
pub fn apply_transforms_words(tf: &mut FrameTransforms, words: &[u64]) {
    let mut w = words.iter().copied();
    let mut word = || w.next().unwrap_or_default();
    for t in &mut tf.transforms {
        let (sec, nsec) = (word() as u32, word() as u32);
        // `nsec` is below 10⁹ (plain transforms): `new` keeps it as it is.
        t.timestamp = Some(Timestamp::new(sec, nsec));
        let mut f = || f64::from_bits(word());
        t.translation = Some(Vector3 {
            x: f(),
            y: f(),
            z: f(),
        });
        t.rotation = Some(Quaternion {
            x: f(),
            y: f(),
            z: f(),
            w: f(),
        });
    }
}

/// Appends the numbers of a planar `/tf` sample (see [`apply_planar_words`]) to `words`:
/// the time `time` (ns) as its seconds and nanoseconds, then each frame's `[x, y, cos θ,
/// sin θ]`. Returns `false`, leaving `words` as it was, if a number is not finite (the
/// caller then writes the sample the slow way, which names the field) or there are not
/// `n` frames.
#[doc(hidden)]
pub fn planar_words(
    words: &mut Vec<u64>,
    time: u64,
    (n, frames): (usize, impl Iterator<Item = [f64; 4]>),
) -> bool {
    let start = words.len();
    words.extend([time / 1_000_000_000, time % 1_000_000_000]);
    let (mut finite, mut count) = (true, 0);
    for frame in frames {
        finite &= frame.iter().all(|x| x.is_finite());
        words.extend(frame.map(f64::to_bits));
        count += 1;
    }
    let taken = finite && count == n;
    if !taken {
        words.truncate(start);
    }
    taken
}

/// Lays the numbers `words` of a planar sample ([`planar_words`], as many frames as `tf`
/// has transforms) out on `tf`: each transform at the time, its translation `(x, y, 0)`,
/// its rotation [`about_z`] of the angle of `(cos θ, sin θ)` — the numbers, bit for bit,
/// that [`RunLogger`](super::RunLogger) computes from a body's pose (`Pose::rotation`'s
/// `angle()`, `atan2(sin, cos)`), here on the writer thread rather than the simulation's.
#[doc(hidden)]
pub fn apply_planar_words(tf: &mut FrameTransforms, words: &[u64]) {
    let mut w = words.iter().copied();
    let mut word = || w.next().unwrap_or_default();
    // Whole seconds below 2³² and nanoseconds below 10⁹ (`nanoseconds` checked the time).
    let time = Timestamp::new(word() as u32, word() as u32);
    for t in &mut tf.transforms {
        let mut f = || f64::from_bits(word());
        let (x, y, cos, sin) = (f(), f(), f(), f());
        let mut rotation = crate::math::Pose::identity().rotation;
        rotation.re = cos;
        rotation.im = sin;
        t.timestamp = Some(time);
        t.translation = Some(vector3(x, y, 0.0));
        t.rotation = Some(about_z(rotation.angle()));
    }
}
