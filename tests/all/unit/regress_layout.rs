//! The unit tests of `regress::layout` (`src/regress/layout.rs`).

// The source module's own imports.
use serde::Serialize;

use std::collections::BTreeMap;

#[derive(Serialize)]
struct Point {
    t: f64,
    q: Vec<f64>,
}

#[derive(Serialize)]
struct Inner {
    x: Vec<f64>,
    e: BTreeMap<String, f64>,
}

#[derive(Serialize)]
struct Doc {
    a: f64,
    o: Inner,
    list: Vec<Point>,
    empty: Vec<Point>,
}

#[test]
fn members_on_lines_array_elements_compact() {
    let doc = Doc {
        a: 1.5,
        o: Inner {
            x: vec![1.0, 2.0],
            e: BTreeMap::new(),
        },
        list: vec![
            Point {
                t: 0.1,
                q: vec![1.0, -0.0],
            },
            Point { t: 0.2, q: vec![] },
        ],
        empty: vec![],
    };
    let text = ricochet::regress::layout::to_string(&doc).unwrap();
    let expected = "{\n  \"a\": 1.5,\n  \"o\": {\n    \"x\": [\n      1.0,\n      2.0\n    ],\n    \
        \"e\": {}\n  },\n  \"list\": [\n    {\"t\": 0.1, \"q\": [1.0, -0.0]},\n    \
        {\"t\": 0.2, \"q\": []}\n  ],\n  \"empty\": []\n}\n";
    assert_eq!(text, expected, "{text}");
    // It is JSON: it reads back to the same value as serde_json's own text.
    let back: serde_json::Value = serde_json::from_str(&text).unwrap();
    assert_eq!(back, serde_json::to_value(&doc).unwrap());
}

#[test]
fn numbers_read_back_bit_exact() {
    let xs = [
        0.1,
        1.0 / 3.0,
        -2.5e-300,
        f64::MIN_POSITIVE,
        5e-324,
        f64::MAX,
        -0.0,
        std::f64::consts::PI * 1e17,
    ];
    let text = ricochet::regress::layout::to_string(&xs.to_vec()).unwrap();
    let back: Vec<f64> = serde_json::from_str(&text).unwrap();
    for (x, y) in xs.iter().zip(&back) {
        assert_eq!(x.to_bits(), y.to_bits(), "{x} → {text}");
    }
}
