//! Shared by the tests that reproduce [P]: the golden values of Table 2 and the double
//! pendulum of Sect. 5 from its closed form (independent of the simulator's model).
#![allow(dead_code)]

use nalgebra::{Matrix2, RowVector2, Vector2};
use ricochet::impact::{ContactVelocity, ImpactMatrix};
use serde::Deserialize;

#[derive(Deserialize)]
pub struct Golden {
    pub source: String,
    pub row: Vec<Row>,
    pub exception: Vec<Exception>,
}

#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
pub struct Row {
    pub law: String,
    pub row: u32,
    pub e: f64,
    pub mu: f64,
    pub r_m: String,
    pub one_plus_e_r_m: String,
    pub minus_one_plus_e_r_p: String,
    #[serde(rename = "type")]
    pub kind: Option<u8>,
    pub delta_u: Option<[String; 2]>,
    pub v_n_s: Option<String>,
    pub v_t_s: Option<String>,
    pub delta_e: Option<String>,
}

#[derive(Deserialize)]
pub struct Exception {
    pub law: String,
    pub row: u32,
    pub column: String,
    pub reason: String,
}

/// A printed number and one unit in its last printed place.
#[derive(Clone, Copy, Debug)]
pub struct Printed {
    pub value: f64,
    pub unit: f64,
}

pub fn printed(s: &str) -> Printed {
    let decimals = s.split('.').nth(1).map_or(0, str::len);
    Printed {
        value: s.parse().expect("a number"),
        unit: 10f64.powi(-(decimals as i32)),
    }
}

/// The double pendulum at the instant of impact, from its closed form.
pub struct Pendulum {
    /// Positive definite mass matrix, M = m l² [[4/3, ½ cos(q1−q2)], [½ cos(q1−q2), 1/3]]
    /// (the negative of the paper's, whose equations of motion in Sect. 5 carry −⅓ m l²
    /// times [[4, 3/2 cos], [3/2 cos, 1]]).
    pub mass: Matrix2<f64>,
    /// Rows J_n, J_t: tip velocity components along n = +y and t = −x.
    pub jac: Matrix2<f64>,
    /// Generalized speeds before the impact.
    pub u: Vector2<f64>,
}

pub fn pendulum() -> Pendulum {
    let (m, l) = (3.0, 2.0);
    let (q1, q2) = (20f64.to_radians(), 30f64.to_radians());
    let c12 = (q1 - q2).cos();
    let mass = m * l * l * Matrix2::new(4.0 / 3.0, 0.5 * c12, 0.5 * c12, 1.0 / 3.0);
    // Tip position l (sin q1 + sin q2, −cos q1 − cos q2): ∂y/∂q = l (sin q1, sin q2),
    // ∂x/∂q = l (cos q1, cos q2); n = +y, t = −x (so that v_t^A ≥ 0).
    let j_n = RowVector2::new(l * q1.sin(), l * q2.sin());
    let j_t = -RowVector2::new(l * q1.cos(), l * q2.cos());
    Pendulum {
        mass,
        jac: Matrix2::from_rows(&[j_n, j_t]),
        u: Vector2::new(-0.1, -0.2),
    }
}

impl Pendulum {
    pub fn w(&self) -> ImpactMatrix {
        let w = self.jac * self.mass.try_inverse().unwrap() * self.jac.transpose();
        ImpactMatrix::new(w[(0, 0)], w[(0, 1)], w[(1, 1)])
    }
    pub fn v_a(&self) -> ContactVelocity {
        let v = self.jac * self.u;
        ContactVelocity::new(v[0], v[1])
    }
    /// Eq. (16) with the positive definite M: Δu = M⁻¹ (J_nᵀ I_n + J_tᵀ I_t).
    pub fn delta_u(&self, i_n: f64, i_t: f64) -> Vector2<f64> {
        self.mass.try_inverse().unwrap() * self.jac.transpose() * Vector2::new(i_n, i_t)
    }
}

/// The golden values of Table 2 (`tests/golden/paper_table_2.toml`).
pub fn golden() -> Golden {
    let text = std::fs::read_to_string(concat!(
        env!("CARGO_MANIFEST_DIR"),
        "/tests/golden/paper_table_2.toml"
    ))
    .unwrap();
    toml::from_str(&text).unwrap()
}
