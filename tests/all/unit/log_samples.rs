//! The unit tests of `log::samples` (`src/log/samples.rs`).

// The source module's own imports.
use ricochet::log::foxglove::{FrameTransforms, Quaternion, Timestamp, Vector3};
use ricochet::log::records::{ContactMode, StateRecord};

use ricochet::log::foxglove::{FrameTransform, append_frame_transforms};
use ricochet::log::records::{ContactState, Energy};
use ricochet::log::samples::*;
use ricochet::log::{LogOptions, LogWriter, Topic};

/// Random bits: zeros (±0.0), non-finite numbers, NaN payloads and any bit pattern.
struct Bits(crate::unit::linalg::Lcg);
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
    let mut bits = Bits(crate::unit::linalg::Lcg(16));
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
    use ricochet::log::foxglove::{about_z, timestamp, vector3};
    use ricochet::math::Pose;
    let mut bits = Bits(crate::unit::linalg::Lcg(21));
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
        let ns = ricochet::log::foxglove::nanoseconds(t).unwrap();
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
    let mut bits = Bits(crate::unit::linalg::Lcg(3));
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
    let mut bits = Bits(crate::unit::linalg::Lcg(7));
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
