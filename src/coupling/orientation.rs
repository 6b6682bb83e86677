//! Orientations as a master gives them (issue 22): a unit quaternion, a rotation matrix in
//! Modelica MultiBody's convention, or a 2D angle, each checked and turned into the one form
//! the solver keeps (a unit quaternion [w, x, y, z], scalar first, that turns body offsets
//! into world offsets: r_world = q r_body q*).
//!
//! Tolerances, decided once here:
//! * A quaternion whose length is within [`UNIT_TOLERANCE`] of 1 is renormalised; beyond that
//!   it is refused. Masters that integrate q̇ = ½ ω ⊗ q drift from unit length by round-off
//!   (1e-16 per step) and truncation of their integrator (1e-9 … 1e-7 over long runs with
//!   error control at 1e-6); a drift past 1e-6 means the master is not passing a rotation.
//! * A rotation matrix T (Modelica.Mechanics.MultiBody.Frames.Orientation `R.T`: the matrix that
//!   maps world components to body components, v_body = T v_world, so its rows are the body
//!   axes in world coordinates) is accepted when max |T Tᵀ − I| ≤ [`UNIT_TOLERANCE`] and
//!   det T > 0, then turned into the nearest quaternion of R = Tᵀ (nalgebra's
//!   `UnitQuaternion::from_rotation_matrix`, Shepperd's branch choice) and renormalised.

use nalgebra::{Matrix3, Quaternion, Rotation3, UnitQuaternion};

/// How far from unit length a quaternion, and from orthonormal a matrix, may be.
pub const UNIT_TOLERANCE: f64 = 1e-6;

/// The identity orientation [w, x, y, z].
pub const IDENTITY: [f64; 4] = [1.0, 0.0, 0.0, 0.0];

/// The identity orientation as Modelica's `R.T`, row major.
pub const IDENTITY_T: [f64; 9] = [1.0, 0.0, 0.0, 0.0, 1.0, 0.0, 0.0, 0.0, 1.0];

fn finite(key: &str, v: &[f64]) -> Result<(), String> {
    match v.iter().find(|x| !x.is_finite()) {
        Some(x) => Err(format!("{key}: entries must be finite, got {x}")),
        None => Ok(()),
    }
}

/// `q` renormalised, or why it is not a rotation.
pub fn unit_quaternion(key: &str, q: &[f64; 4]) -> Result<[f64; 4], String> {
    finite(key, q)?;
    let n = q.iter().map(|x| x * x).sum::<f64>().sqrt();
    if (n - 1.0).abs() > UNIT_TOLERANCE {
        return Err(format!(
            "{key}: a unit quaternion [w, x, y, z] must have length within {UNIT_TOLERANCE:e} of 1, got length {n} ({q:?})"
        ));
    }
    Ok(q.map(|x| x / n))
}

/// The solver's quaternion of a checked [w, x, y, z].
pub fn to_unit(q: &[f64; 4]) -> UnitQuaternion<f64> {
    UnitQuaternion::new_unchecked(Quaternion::new(q[0], q[1], q[2], q[3]))
}

/// [w, x, y, z] of a solver quaternion.
pub fn to_array(q: &UnitQuaternion<f64>) -> [f64; 4] {
    let q = q.quaternion();
    [q.w, q.i, q.j, q.k]
}

/// The quaternion of a rotation by `angle` about z (a 2D body's angle).
pub fn planar(angle: f64) -> [f64; 4] {
    let (s, c) = (0.5 * angle).sin_cos();
    [c, 0.0, 0.0, s]
}

/// The quaternion of Modelica's `R.T` (9 entries, row major), or why it is not a rotation.
pub fn from_matrix_t(key: &str, t: &[f64; 9]) -> Result<[f64; 4], String> {
    finite(key, t)?;
    let m = Matrix3::from_row_slice(t);
    let off = (m * m.transpose() - Matrix3::identity()).abs().max();
    if off > UNIT_TOLERANCE {
        return Err(format!(
            "{key}: must be orthonormal (max |T Tᵀ − I| ≤ {UNIT_TOLERANCE:e}), got {off:.3e}"
        ));
    }
    let det = m.determinant();
    if det <= 0.0 {
        return Err(format!(
            "{key}: must be a rotation (det T = +1), got det {det:.6} (a reflection)"
        ));
    }
    let q = UnitQuaternion::from_rotation_matrix(&Rotation3::from_matrix_unchecked(m.transpose()));
    unit_quaternion(key, &to_array(&q))
}

/// Modelica's `R.T` (row major) of a solver quaternion.
pub fn matrix_t(q: &UnitQuaternion<f64>) -> [f64; 9] {
    let r = q.to_rotation_matrix();
    let t = r.matrix().transpose();
    let mut out = [0.0; 9];
    for i in 0..3 {
        for j in 0..3 {
            out[3 * i + j] = t[(i, j)];
        }
    }
    out
}

#[cfg(test)]
mod tests {
    use super::*;
    use nalgebra::Vector3;

    #[test]
    fn a_matrix_and_its_quaternion_are_one_rotation() {
        let q = UnitQuaternion::from_euler_angles(0.3, -0.4, 1.2);
        let back = from_matrix_t("t", &matrix_t(&q)).unwrap();
        assert!((to_unit(&back).angle_to(&q)).abs() < 1e-15);
        // Modelica's T maps world components to body components
        let t = Matrix3::from_row_slice(&matrix_t(&q));
        let v = Vector3::new(0.1, 0.2, 0.3);
        assert!((t * (q * v) - v).norm() < 1e-15);
        // 120° about the diagonal: exact in both forms, so the same bits
        let diag = [0.5, 0.5, 0.5, 0.5];
        let t = [0.0, 1.0, 0.0, 0.0, 0.0, 1.0, 1.0, 0.0, 0.0];
        assert_eq!(from_matrix_t("t", &t).unwrap(), diag);
        assert_eq!(matrix_t(&to_unit(&diag)), t);
    }

    #[test]
    fn near_unit_is_renormalised_and_beyond_is_refused() {
        let q = unit_quaternion("q", &[1.0 + 5e-7, 0.0, 0.0, 0.0]).unwrap();
        assert_eq!(q, IDENTITY);
        for bad in [
            [1.0 + 2e-6, 0.0, 0.0, 0.0],
            [0.0; 4],
            [f64::NAN, 0.0, 0.0, 1.0],
        ] {
            let e = unit_quaternion("tank.orientation", &bad).unwrap_err();
            assert!(e.starts_with("tank.orientation: "), "{e}");
        }
        let mut skew = [1.0, 0.0, 0.0, 0.0, 1.0, 0.0, 0.0, 0.0, 1.0];
        skew[1] = 1e-3;
        assert!(from_matrix_t("m", &skew)
            .unwrap_err()
            .contains("orthonormal"));
        let mirror = [-1.0, 0.0, 0.0, 0.0, 1.0, 0.0, 0.0, 0.0, 1.0];
        assert!(from_matrix_t("m", &mirror)
            .unwrap_err()
            .contains("reflection"));
        assert_eq!(planar(0.0), IDENTITY);
    }
}
