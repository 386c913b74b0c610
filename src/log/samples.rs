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
pub(super) fn same_state_layout(a: &StateRecord, b: &StateRecord) -> bool {
    a.q.len() == b.q.len()
        && a.u.len() == b.u.len()
        && a.contacts.len() == b.contacts.len()
        && (a.contacts.iter())
            .zip(&b.contacts)
            .all(|(x, y)| x.pair == y.pair)
}

/// Appends the numbers of `state` to `words`: `t`, `q`, `u`, the energies, the run's mode
/// and mode code, the impact count, then each contact's mode, mode code, gap and slip.
pub(super) fn state_words(words: &mut Vec<u64>, state: &StateRecord) {
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
pub(super) fn apply_state_words(state: &mut StateRecord, words: &[u64]) {
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
pub(super) fn plain_transforms(tf: &FrameTransforms) -> bool {
    tf.transforms.iter().all(|t| {
        t.translation.is_some()
            && t.rotation.is_some()
            && (t.timestamp).is_some_and(|time| time.nsec() < 1_000_000_000)
    })
}

/// Whether transforms of layout `a` can be laid out on those of layout `b`: as many, with
/// the same parent and child frames.
pub(super) fn same_transforms_layout(a: &FrameTransforms, b: &FrameTransforms) -> bool {
    a.transforms.len() == b.transforms.len()
        && (a.transforms.iter()).zip(&b.transforms).all(|(x, y)| {
            x.parent_frame_id == y.parent_frame_id && x.child_frame_id == y.child_frame_id
        })
}

/// Appends the numbers of `tf` (which must be [plain](plain_transforms)) to `words`: for
/// each transform, its timestamp's seconds and nanoseconds, its translation `x, y, z` and
/// its rotation `x, y, z, w`.
pub(super) fn transforms_words(words: &mut Vec<u64>, tf: &FrameTransforms) {
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
pub(super) fn apply_transforms_words(tf: &mut FrameTransforms, words: &[u64]) {
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
pub(super) fn planar_words(
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
pub(super) fn apply_planar_words(tf: &mut FrameTransforms, words: &[u64]) {
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

#[cfg(test)]
mod tests {
    use super::*;
    use crate::log::foxglove::{FrameTransform, append_frame_transforms};
    use crate::log::records::{ContactState, Energy};
    use crate::log::{LogOptions, LogWriter, Topic};

    /// Random bits: zeros (±0.0), non-finite numbers, NaN payloads and any bit pattern.
    struct Bits(crate::linalg::tests::Lcg);
    impl Bits {
        fn next(&mut self) -> u64 {
            self.0.next();
            (self.0).0
        }
        fn number(&mut self) -> f64 {
            let b = self.next();
            match b % 7 {
                0 => 0.0,
                1 => -0.0,
                2 => f64::from_bits(0x7ff8_0000_dead_beef),
                3 => f64::NEG_INFINITY,
                _ => f64::from_bits(b.rotate_left(17)),
            }
        }
        fn finite(&mut self) -> f64 {
            let x = self.number();
            if x.is_finite() { x } else { 1.5 }
        }
    }

    const MODES: [ContactMode; 4] = [
        ContactMode::Free,
        ContactMode::Sliding,
        ContactMode::Sticking,
        ContactMode::Impact,
    ];

    /// A record of `layout` (`q` and `u` lengths, pair names) with random numbers; if
    /// `finite`, only finite ones (what the writer accepts).
    fn state(bits: &mut Bits, (n, pairs): (usize, &[&str]), finite: bool) -> StateRecord {
        let x = |bits: &mut Bits| if finite { bits.finite() } else { bits.number() };
        let contacts = (pairs.iter())
            .map(|&p| ContactState {
                pair: p.to_owned(),
                mode: MODES[bits.next() as usize % 4],
                mode_code: bits.next() as u8,
                gap: x(bits),
                slip: bits.next() as i8,
            })
            .collect();
        StateRecord {
            t: bits.finite().abs() % 1e6,
            q: (0..n).map(|_| x(bits)).collect(),
            u: (0..n + 1).map(|_| x(bits)).collect(),
            energy: Energy {
                kinetic: x(bits),
                potential: x(bits),
                total: x(bits),
            },
            mode: MODES[bits.next() as usize % 4],
            mode_code: bits.next() as u8,
            contacts,
            impact_count: bits.next(),
        }
    }

    /// Frame transforms between `frames` with random numbers and times.
    fn transforms(bits: &mut Bits, frames: &[(&str, &str)], finite: bool) -> FrameTransforms {
        let x = |bits: &mut Bits| if finite { bits.finite() } else { bits.number() };
        let transforms = (frames.iter())
            .map(|&(parent, child)| FrameTransform {
                timestamp: Some(Timestamp::new(
                    bits.next() as u32,
                    (bits.next() % 1_000_000_000) as u32,
                )),
                parent_frame_id: parent.to_owned(),
                child_frame_id: child.to_owned(),
                translation: Some(Vector3 {
                    x: x(bits),
                    y: x(bits),
                    z: x(bits),
                }),
                rotation: Some(Quaternion {
                    x: x(bits),
                    y: x(bits),
                    z: x(bits),
                    w: x(bits),
                }),
            })
            .collect();
        FrameTransforms { transforms }
    }

    const PAIRS: [&[&str]; 3] = [&[], &["rodB/floor"], &["rodA/floor", "rodB/floor"]];
    const FRAMES: [&[(&str, &str)]; 2] = [
        &[("world", "rodA")],
        &[("world", "rodA"), ("world", "rodB"), ("view", "world")],
    ];

    /// A sample's numbers laid out on a record of its layout (holding other numbers) give
    /// that record back: the same JSON and protobuf bytes as the sample's own, every bit of
    /// every number (±0.0, NaN payloads, infinities included).
    #[test]
    fn numbers_laid_out_on_the_layout_give_the_sample_back() {
        let mut bits = Bits(crate::linalg::tests::Lcg(16));
        let mut words = Vec::new();
        for k in 0..2000 {
            let layout = (k % 4, PAIRS[k % 3]);
            let sample = state(&mut bits, layout, false);
            let mut on = state(&mut bits, layout, false);
            assert!(same_state_layout(&sample, &on));
            words.clear();
            state_words(&mut words, &sample);
            apply_state_words(&mut on, &words);
            let (mut ours, mut theirs) = (Vec::new(), Vec::new());
            on.append_json(&mut ours);
            sample.append_json(&mut theirs);
            assert_eq!(ours, theirs, "{sample:?}");
            let bits_of = |s: &StateRecord| {
                let mut w = Vec::new();
                state_words(&mut w, s);
                w
            };
            assert_eq!(bits_of(&on), bits_of(&sample));

            let frames = FRAMES[k % 2];
            let tf = transforms(&mut bits, frames, false);
            let mut on = transforms(&mut bits, frames, false);
            assert!(plain_transforms(&tf) && same_transforms_layout(&tf, &on));
            words.clear();
            transforms_words(&mut words, &tf);
            apply_transforms_words(&mut on, &words);
            assert_eq!(on.transforms.len(), tf.transforms.len());
            let (mut ours, mut theirs) = (Vec::new(), Vec::new());
            append_frame_transforms(&mut ours, &on);
            append_frame_transforms(&mut theirs, &tf);
            assert_eq!(ours, theirs, "{tf:?}");
        }
    }

    /// A planar `/tf` sample (poses and view as `[x, y, cos θ, sin θ]`) laid out on the
    /// writer thread gives the bytes of the transforms the simulation's thread computed
    /// from the same poses before (`timestamp(t)`, `(x, y, 0)`, `about_z(angle())`): random
    /// positions (±0.0 included), rotations of any angle (±π, ±0) and not normalized, on
    /// layouts holding other numbers. A non-finite number, or a frame too many or too few,
    /// is refused, leaving the words as they were.
    #[test]
    fn planar_numbers_give_the_transforms_computed_from_the_poses() {
        use crate::log::foxglove::{about_z, timestamp, vector3};
        use crate::math::Pose;
        let mut bits = Bits(crate::linalg::tests::Lcg(21));
        let mut words = Vec::new();
        for k in 0..3000 {
            let frames = FRAMES[k % 2];
            let t = [0.0, 0.01 * k as f64, bits.finite().abs() % 4e9][k % 3];
            let poses: Vec<Pose> = (0..frames.len())
                .map(|j| {
                    let mut p = Pose::identity();
                    p.translation.x = bits.finite();
                    p.translation.y = bits.finite();
                    let angle = [
                        std::f64::consts::PI,
                        -std::f64::consts::PI,
                        -0.0,
                        bits.finite() % 10.0,
                    ][(k + j) % 4];
                    let (sin, cos) = angle.sin_cos();
                    let scale = if k % 5 == 0 { 1.0 + 1e-9 } else { 1.0 };
                    p.rotation.re = cos * scale;
                    p.rotation.im = sin;
                    p
                })
                .collect();
            // What `RunLogger::sample` computed on the simulation's thread.
            let mut expected = transforms(&mut bits, frames, true);
            let time = timestamp(t).unwrap();
            for (tf, p) in expected.transforms.iter_mut().zip(&poses) {
                tf.timestamp = Some(time);
                tf.translation = Some(vector3(p.translation.x, p.translation.y, 0.0));
                tf.rotation = Some(about_z(p.rotation.angle()));
            }
            let frame = |p: &Pose| {
                [
                    p.translation.x,
                    p.translation.y,
                    p.rotation.re,
                    p.rotation.im,
                ]
            };
            words.clear();
            words.push(7);
            let ns = crate::log::foxglove::nanoseconds(t).unwrap();
            assert!(planar_words(
                &mut words,
                ns,
                (poses.len(), poses.iter().map(frame))
            ));
            let mut on = transforms(&mut bits, frames, false);
            apply_planar_words(&mut on, &words[1..]);
            let (mut ours, mut theirs) = (Vec::new(), Vec::new());
            append_frame_transforms(&mut ours, &on);
            append_frame_transforms(&mut theirs, &expected);
            assert_eq!(ours, theirs, "{expected:?}");

            // Refused: a non-finite number, too many or too few frames.
            let mut bad = poses.clone();
            let j = k % bad.len();
            match k % 3 {
                0 => bad[j].translation.y = f64::NAN,
                1 => bad[j].rotation.re = f64::INFINITY,
                _ => bad[j].rotation.im = f64::NEG_INFINITY,
            }
            let before = words.clone();
            assert!(!planar_words(
                &mut words,
                ns,
                (bad.len(), bad.iter().map(frame))
            ));
            let n = poses.len();
            assert!(!planar_words(
                &mut words,
                ns,
                (n + 1, poses.iter().map(frame))
            ));
            assert!(!planar_words(
                &mut words,
                ns,
                (n - 1, poses.iter().map(frame))
            ));
            assert_eq!(words, before);
        }
    }

    #[test]
    fn layouts_differ_by_lengths_and_names() {
        let mut bits = Bits(crate::linalg::tests::Lcg(3));
        let a = state(&mut bits, (2, PAIRS[2]), true);
        assert!(same_state_layout(
            &a,
            &state(&mut bits, (2, PAIRS[2]), true)
        ));
        assert!(!same_state_layout(
            &a,
            &state(&mut bits, (3, PAIRS[2]), true)
        ));
        assert!(!same_state_layout(
            &a,
            &state(&mut bits, (2, PAIRS[1]), true)
        ));
        let renamed = state(&mut bits, (2, &["rodA/floor", "rodB/wall"]), true);
        assert!(!same_state_layout(&a, &renamed));
        let mut u_longer = state(&mut bits, (2, PAIRS[2]), true);
        u_longer.u.push(0.0);
        assert!(!same_state_layout(&a, &u_longer));

        let tf = transforms(&mut bits, FRAMES[1], true);
        assert!(!same_transforms_layout(
            &tf,
            &transforms(&mut bits, FRAMES[0], true)
        ));
        let mut other = transforms(&mut bits, FRAMES[1], true);
        other.transforms[2].child_frame_id = "floor".to_owned();
        assert!(!same_transforms_layout(&tf, &other));
        other.transforms[2].child_frame_id = "world".to_owned();
        other.transforms[1].parent_frame_id = "view".to_owned();
        assert!(!same_transforms_layout(&tf, &other));
        let mut unplain = tf.clone();
        unplain.transforms[1].rotation = None;
        assert!(!plain_transforms(&unplain));
        unplain.transforms[1] = FrameTransform::default();
        assert!(!plain_transforms(&unplain));
    }

    /// Through a whole log: samples whose layouts change (pairs listed and unlisted,
    /// frames added), going as numbers or encoded on the calling thread in turns (and as
    /// the writer thread's progress decides), interleaved with transforms that are not
    /// plain (encoded on the calling thread), in small batches and chunks: every `/state`
    /// and `/tf` message holds the bytes of the sample's own encoding.
    #[test]
    fn a_log_holds_each_samples_own_bytes() {
        let mut bits = Bits(crate::linalg::tests::Lcg(7));
        let options = LogOptions {
            chunk_size: 2048,
            ..LogOptions::default()
        };
        let mut log = LogWriter::new(std::io::Cursor::new(Vec::new()), options).unwrap();
        let (mut states, mut tfs) = (Vec::new(), Vec::new());
        for k in 0..700 {
            // Layouts in runs of a few samples, coming back to earlier ones.
            let layout = ((k / 7) % 3, PAIRS[(k / 5) % 3]);
            log.defer_samples([Some(true), Some(false), None][(k / 3) % 3]);
            let mut s = state(&mut bits, layout, true);
            s.t = k as f64 * 0.01;
            log.state(&s).unwrap();
            let mut encoded = Vec::new();
            s.append_json(&mut encoded);
            states.push(encoded);

            let mut tf = transforms(&mut bits, FRAMES[(k / 11) % 2], true);
            if k % 13 == 0 {
                tf.transforms[0].translation = None;
            }
            if k % 17 == 0 {
                tf.transforms[0].timestamp = None;
            }
            log.transforms(s.t, &tf).unwrap();
            let mut encoded = Vec::new();
            append_frame_transforms(&mut encoded, &tf);
            tfs.push(encoded);
        }
        let bytes = log.finish().unwrap().into_inner();
        let (mut got_states, mut got_tfs) = (Vec::new(), Vec::new());
        for message in mcap::MessageStream::new(&bytes).unwrap() {
            let message = message.unwrap();
            let data = message.data.into_owned();
            if message.channel.topic == Topic::State.name() {
                got_states.push(data);
            } else if message.channel.topic == Topic::Tf.name() {
                got_tfs.push(data);
            }
        }
        assert_eq!(got_states.len(), states.len());
        assert_eq!(got_tfs.len(), tfs.len());
        for (k, (got, want)) in got_states.iter().zip(&states).enumerate() {
            assert_eq!(got, want, "/state message {k}");
        }
        for (k, (got, want)) in got_tfs.iter().zip(&tfs).enumerate() {
            assert_eq!(got, want, "/tf message {k}");
        }
    }
}
