//! The unit tests of `log::records` (`src/log/records.rs`).

// The source module's own imports.
use ricochet::impact::CollisionType;

use ricochet::log::records::*;

#[test]
fn run_mode_is_the_most_constrained() {
    use ContactMode::*;
    assert_eq!(ContactMode::of_run([]), Free);
    assert_eq!(ContactMode::of_run([Free, Sliding, Free]), Sliding);
    assert_eq!(ContactMode::of_run([Sticking, Sliding]), Sticking);
    assert_eq!(ContactMode::of_run([Sticking, Impact, Free]), Impact);
}

#[test]
fn audit_drift_closes_the_balance() {
    let a = Audit::new(
        "t_end",
        2.0,
        (10.0, 7.0),
        (-2.5, -0.25, -0.125, 0.0),
        Counters::default(),
    );
    // 7 − 10 − (−2.5 − 0.25 − 0.125 + 0) = −0.125
    assert_eq!(a.integration_drift, -0.125);
}

#[test]
fn non_finite_fields_are_named() {
    let mut s = StateRecord::new(
        0.0,
        vec![1.0, 2.0],
        vec![0.0],
        Energy::new(1.0, 2.0),
        vec![],
        0,
    );
    assert_eq!(s.first_non_finite(), None);
    s.q[1] = f64::NAN;
    assert_eq!(s.first_non_finite().as_deref(), Some("q[1]"));
    s.energy.total = f64::INFINITY;
    assert_eq!(s.first_non_finite().as_deref(), Some("energy.total"));
}

/// `StateRecord::append_json` writes the bytes serde_json writes for the record: random
/// records with numbers of every magnitude (random bit patterns, subnormals, ±0, whole
/// numbers, non-finite ones: `null`), every mode, names that need escaping.
#[test]
fn state_json_is_serde_json_s() {
    let mut rng = crate::unit::linalg::Lcg(16);
    let special = [
        0.0,
        -0.0,
        1.0,
        -2.0,
        1e16,
        1e-7,
        0.1,
        f64::MIN_POSITIVE / 3.0,
        f64::MAX,
        f64::NAN,
        f64::INFINITY,
        f64::NEG_INFINITY,
    ];
    let number = |rng: &mut crate::unit::linalg::Lcg| {
        let r = rng.next();
        if r < -0.5 {
            special[(rng.0 >> 40) as usize % special.len()]
        } else if r < 0.0 {
            rng.next() * 10f64.powi((rng.0 >> 40) as i32 % 40 - 20)
        } else {
            f64::from_bits(rng.0)
        }
    };
    let modes = [
        ContactMode::Free,
        ContactMode::Sliding,
        ContactMode::Sticking,
        ContactMode::Impact,
    ];
    let names = [
        "rodB/floor",
        "a\"b/c\\d",
        "tab\there/\u{1}x\u{7f}",
        "é/ü∞",
        "",
    ];
    let mut out = Vec::new();
    for k in 0..2000 {
        let n = k % 7;
        let contacts = (0..(k % 4))
            .map(|i| ContactState {
                pair: names[(k + i) % names.len()].to_owned(),
                mode: modes[(k + 2 * i) % 4],
                mode_code: (k % 256) as u8,
                gap: number(&mut rng),
                slip: [-1, 0, 1, i8::MIN, i8::MAX][(k + i) % 5],
            })
            .collect();
        let record = StateRecord {
            t: number(&mut rng),
            q: (0..n).map(|_| number(&mut rng)).collect(),
            u: (0..n / 2).map(|_| number(&mut rng)).collect(),
            energy: Energy {
                kinetic: number(&mut rng),
                potential: number(&mut rng),
                total: number(&mut rng),
            },
            mode: modes[k % 4],
            mode_code: (k % 5) as u8,
            contacts,
            impact_count: [0, 7, u64::MAX][k % 3],
        };
        out.clear();
        out.extend_from_slice(b"prefix");
        record.append_json(&mut out);
        let expected = serde_json::to_vec(&record).unwrap();
        assert_eq!(
            String::from_utf8_lossy(&out[6..]),
            String::from_utf8_lossy(&expected),
            "record {k}"
        );
        assert_eq!(&out[..6], b"prefix");
    }
}

#[test]
fn records_use_the_contract_names() {
    let json = serde_json::to_value(ContactState::new("a/b", ContactMode::Sticking, 0.0)).unwrap();
    assert_eq!(json["mode"], "sticking");
    assert_eq!(json["mode_code"], 2);
    assert_eq!(
        serde_json::to_value(CollisionType::ReverseSliding).unwrap(),
        "reverse_sliding"
    );
}
