//! The unit tests of `log::foxglove` (`src/log/foxglove.rs`).

// The source module's own imports.
use foxglove::Decode;
use foxglove::messages::{
    Duration, FrameTransform, FrameTransforms, LinePrimitive, Quaternion, SceneEntity, SceneUpdate,
    Timestamp,
};
use ricochet::log::LogError;

use ricochet::log::foxglove::*;

/// `append_frame_transforms` writes prost's bytes: random transforms with every
/// sub-message absent or present, numbers zero (±0.0), non-finite or random bit
/// patterns, names empty, short or beyond 127 bytes (a two-byte length), times with
/// zero and large parts.
#[test]
fn frame_transforms_encode_as_prost_does() {
    let mut rng = crate::unit::linalg::Lcg(5);
    let mut bits = || {
        rng.next();
        rng.0
    };
    let number = |b: u64| match b % 6 {
        0 => 0.0,
        1 => -0.0,
        2 => f64::NAN,
        3 => f64::NEG_INFINITY,
        _ => f64::from_bits(b.rotate_left(17)),
    };
    let long = "frame/".repeat(30);
    let names = ["", "world", "body_rodB", long.as_str()];
    let (mut ours, mut theirs) = (Vec::new(), Vec::new());
    for k in 0..3000 {
        let transforms = (0..k % 5)
            .map(|_| {
                let b = bits();
                FrameTransform {
                    timestamp: (b & 1 == 0).then(|| {
                        Timestamp::new([0, 1, 200, u32::MAX][(b >> 1) as usize % 4], {
                            [0, 999_999_999, 5][(b >> 3) as usize % 3]
                        })
                    }),
                    parent_frame_id: names[(b >> 5) as usize % 4].to_owned(),
                    child_frame_id: names[(b >> 7) as usize % 4].to_owned(),
                    translation: (b & 512 == 0)
                        .then(|| vector3(number(bits()), number(bits()), number(bits()))),
                    rotation: (b & 1024 == 0).then(|| Quaternion {
                        x: number(bits()),
                        y: number(bits()),
                        z: number(bits()),
                        w: number(bits()),
                    }),
                }
            })
            .collect();
        let tf = FrameTransforms { transforms };
        ours.clear();
        theirs.clear();
        append_frame_transforms(&mut ours, &tf);
        append_protobuf(&mut theirs, "/tf", &tf).unwrap();
        assert_eq!(ours, theirs, "case {k}: {tf:?}");
    }
}

#[test]
fn time_splits_seconds_and_nanoseconds() {
    let t = timestamp(1.25).unwrap();
    assert_eq!((t.sec(), t.nsec()), (1, 250_000_000));
    assert_eq!(t.total_nanos(), 1_250_000_000);
    assert_eq!(seconds(&t), 1.25);
    assert_eq!(timestamp(-0.0).unwrap(), Timestamp::new(0, 0));
    // 0.1 s is 100 000 000.000000006 ns in binary; rounding gives the decimal value.
    assert_eq!(nanoseconds(0.1).unwrap(), 100_000_000);
    // Rounding to the nearest ns carries into the next second.
    assert_eq!(timestamp(2.999_999_999_6).unwrap(), Timestamp::new(3, 0));
    assert_eq!(lifetime(0.25).unwrap(), Duration::new(0, 250_000_000));
}

#[test]
fn invalid_times_are_rejected() {
    for t in [
        -1e-9,
        -1.0,
        f64::NAN,
        f64::INFINITY,
        f64::NEG_INFINITY,
        4_294_967_296.0,
    ] {
        assert!(
            matches!(nanoseconds(t), Err(LogError::InvalidTime { .. })),
            "{t} accepted"
        );
        assert!(
            timestamp(t).is_err() && lifetime(t).is_err(),
            "{t} accepted"
        );
    }
    // The last representable second is accepted.
    assert_eq!(timestamp(4_294_967_295.5).unwrap().sec(), u32::MAX);
}

#[test]
fn quaternion_about_z_rotates_x_to_the_angle() {
    // Rotating (1, 0, 0) by q = (0, 0, s, c): x' = c² − s² = cos θ, y' = 2sc = sin θ.
    let theta = 0.7;
    let q = about_z(theta);
    assert!((q.w * q.w - q.z * q.z - theta.cos()).abs() < 1e-15);
    assert!((2.0 * q.w * q.z - theta.sin()).abs() < 1e-15);
    assert!((q.w * q.w + q.z * q.z - 1.0).abs() < 1e-15);
}

#[test]
fn non_finite_numbers_are_found_with_their_path() {
    let mut line = LinePrimitive {
        points: vec![point3(0.0, 0.0, 0.0), point3(1.0, 0.0, 0.0)],
        pose: Some(planar_pose(0.0, 0.0, 0.0, 0.0)),
        ..LinePrimitive::default()
    };
    let clean = |line: &LinePrimitive| SceneUpdate {
        deletions: vec![],
        entities: vec![
            SceneEntity::default(),
            SceneEntity {
                lines: vec![line.clone()],
                ..SceneEntity::default()
            },
        ],
    };
    assert_eq!(first_non_finite_scene(&clean(&line)), None);
    line.points[1].y = f64::NAN;
    assert_eq!(
        first_non_finite_scene(&clean(&line)).as_deref(),
        Some("entities[1].lines[0].points[1].y")
    );
    line.points[1].y = 0.0;
    line.pose = Some(planar_pose(0.0, f64::INFINITY, 0.0, 0.0));
    assert_eq!(
        first_non_finite_scene(&clean(&line)).as_deref(),
        Some("entities[1].lines[0].pose.position.y")
    );
    let mut tf = FrameTransforms {
        transforms: vec![
            planar_transform(0.0, "world", "a", (0.0, 0.0, 0.0)).unwrap(),
            planar_transform(0.0, "world", "b", (0.0, 0.0, 0.0)).unwrap(),
        ],
    };
    assert_eq!(first_non_finite_transforms(&tf), None);
    tf.transforms[1].rotation.as_mut().unwrap().w = f64::NAN;
    assert_eq!(
        first_non_finite_transforms(&tf).as_deref(),
        Some("transforms[1].rotation.w")
    );
}

#[test]
fn protobuf_encoding_round_trips() {
    let tf = FrameTransforms {
        transforms: vec![planar_transform(1.5, "world", "body_rod", (1.0, -2.0, 0.3)).unwrap()],
    };
    let mut buffer = b"prefix".to_vec();
    append_protobuf(&mut buffer, "/tf", &tf).unwrap();
    let back = FrameTransforms::decode(&buffer[6..]).unwrap();
    assert_eq!(back, tf);
}
