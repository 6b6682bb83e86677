//! Rigid-body kinematics of a boundary body (issues 5 and 22): a body moves as a translation
//! d(t) of its reference point r0 plus a rotation R(t) about that point. A body point p (at
//! t = 0) is at x(t) = r0 + d(t) + R(t)(p − r0), with velocity ḋ + ω × r and acceleration
//! d̈ + ω̇ × r + ω × (ω × r), r = x − r0 − d, where ω is the angular velocity in world
//! coordinates (Ṙ = [ω]× R).
//!
//! R is a unit quaternion (nalgebra's `UnitQuaternion`, which turns body offsets into world
//! offsets); a 2D body turns about z only, a 1D body not at all. Prescribed motions rotate
//! about one fixed axis (the body's `axis`, 2D: z), so R = exp(θ(t) k), ω = θ̇ k, ω̇ = θ̈ k:
//! fixed; sinusoidal (translation amplitude and/or rotation amplitude, one frequency); a ramp
//! to a constant velocity; a table of displacements and angles (piecewise linear, so the
//! velocity is piecewise constant and the acceleration zero inside a segment). A body driven
//! from outside (the Coupling API, e.g. a multibody master through the FMU) takes any pose
//! and moves on at constant velocity and angular velocity until the next update.

use nalgebra::{Unit, UnitQuaternion, Vector3};
use serde::{Deserialize, Serialize};
use std::f64::consts::PI;

/// `motion` of a `[[body]]` in case files.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize, Default)]
#[serde(tag = "type", rename_all = "kebab-case", deny_unknown_fields)]
pub enum Motion {
    #[default]
    Fixed,
    /// d(t) = A sin(2π f (t − t0) + φ), θ(t) = Θ sin(2π f (t − t0) + φ) for t ≥ t0, else 0.
    Sinusoid {
        #[serde(default)]
        amplitude: Option<Vec<f64>>,
        /// Rotation amplitude Θ in radians.
        #[serde(default)]
        angle_amplitude: f64,
        frequency: f64,
        #[serde(default)]
        phase: f64,
        #[serde(default)]
        start: f64,
    },
    /// Velocity (and angular velocity) rising linearly from 0 at `start` to `velocity` at
    /// `start + ramp_time`, then constant (ramp_time = 0: a step at `start`).
    Ramp {
        velocity: Vec<f64>,
        #[serde(default)]
        angular_velocity: f64,
        ramp_time: f64,
        #[serde(default)]
        start: f64,
    },
    /// Displacements of the reference point (and, optionally, rotation angles about the axis,
    /// radians) at increasing times, linear in between; held before the first and after the
    /// last entry.
    Table {
        time: Vec<f64>,
        displacement: Vec<Vec<f64>>,
        #[serde(default)]
        angle: Option<Vec<f64>>,
    },
    /// Pose and velocities set by the master through the Coupling API.
    External,
}

/// Translation and rotation of a body at one instant. `rotation` turns body offsets (from the
/// reference point, as they were at t = 0) into world offsets; `angular_velocity` and
/// `angular_acceleration` are world vectors (2D: z only; 1D: zero).
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
pub struct Pose<const D: usize> {
    pub displacement: crate::particles::Vector<D>,
    pub velocity: crate::particles::Vector<D>,
    pub acceleration: crate::particles::Vector<D>,
    pub rotation: UnitQuaternion<f64>,
    pub angular_velocity: Vector3<f64>,
    pub angular_acceleration: Vector3<f64>,
}

impl<const D: usize> Default for Pose<D> {
    fn default() -> Self {
        let z = crate::particles::Vector::<D>::zeros();
        Self {
            displacement: z,
            velocity: z,
            acceleration: z,
            rotation: UnitQuaternion::identity(),
            angular_velocity: Vector3::zeros(),
            angular_acceleration: Vector3::zeros(),
        }
    }
}

impl<const D: usize> Pose<D> {
    /// R·r: a body offset turned into world coordinates.
    pub fn to_world(&self, r: &crate::particles::Vector<D>) -> crate::particles::Vector<D> {
        if D < 2 {
            return *r;
        }
        from3(&(self.rotation * to3(r)))
    }

    /// Rᵀ·r: a world vector in body coordinates.
    pub fn to_body(&self, r: &crate::particles::Vector<D>) -> crate::particles::Vector<D> {
        if D < 2 {
            return *r;
        }
        from3(&self.rotation.inverse_transform_vector(&to3(r)))
    }

    /// The rotation angle about z of a 2D pose (radians, in (−π, π]).
    pub fn planar_angle(&self) -> f64 {
        let q = self.rotation.quaternion();
        2.0 * q.k.atan2(q.w)
    }

    /// The pose of a rotation by θ (with rates θ̇, θ̈) about the unit `axis` (2D: z).
    fn set_rotation(&mut self, axis: &Unit<Vector3<f64>>, theta: f64, rate: f64, accel: f64) {
        if D < 2 {
            return;
        }
        let k = if D == 2 { Vector3::z_axis() } else { *axis };
        self.rotation = UnitQuaternion::from_axis_angle(&k, theta);
        self.angular_velocity = k.into_inner() * rate;
        self.angular_acceleration = k.into_inner() * accel;
    }
}

/// The pose last set from outside (`Motion::External`, the Coupling API) and when: between
/// two updates the body moves on at the acceleration and angular acceleration it was given
/// (zero unless the master gives them: then at constant velocities).
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize, Default)]
pub struct HeldPose<const D: usize> {
    pub time: f64,
    pub pose: Pose<D>,
}

impl<const D: usize> HeldPose<D> {
    /// The pose at t ≥ `time`: the reference point on a parabola, d0 + v0 τ + a τ²/2
    /// (τ = t − time), and the rotation R(t) = exp([φ(τ)]×) R0 with the rotation vector
    /// φ = ω0 τ + α τ²/2 and ω(t) = ω0 + α τ. That is exact for a rotation about a fixed axis
    /// (α ∥ ω0, every 2D motion) and second-order accurate otherwise, the order of the
    /// master's own integrator across a communication step. With a = α = 0 the body moves
    /// on at constant velocity and world angular velocity.
    pub fn at(&self, t: f64) -> Pose<D> {
        let dt = t - self.time;
        let p = &self.pose;
        let (w, al) = (p.angular_velocity, p.angular_acceleration);
        let phi = w * dt + al * (0.5 * dt * dt);
        let rotation = if dt == 0.0 || phi == Vector3::zeros() {
            p.rotation
        } else {
            UnitQuaternion::from_scaled_axis(phi) * p.rotation
        };
        Pose {
            displacement: p.displacement + p.velocity * dt + p.acceleration * (0.5 * dt * dt),
            velocity: p.velocity + p.acceleration * dt,
            acceleration: p.acceleration,
            rotation,
            angular_velocity: w + al * dt,
            angular_acceleration: al,
        }
    }
}

/// A D-vector as a 3-vector (missing entries 0).
pub fn to3<const D: usize>(v: &crate::particles::Vector<D>) -> Vector3<f64> {
    Vector3::from_fn(|k, _| if k < D { v[k] } else { 0.0 })
}

/// The first D entries of a 3-vector.
pub fn from3<const D: usize>(v: &Vector3<f64>) -> crate::particles::Vector<D> {
    crate::particles::Vector::<D>::from_fn(|k, _| v[k])
}

fn vector<const D: usize>(v: &[f64]) -> crate::particles::Vector<D> {
    crate::particles::Vector::<D>::from_iterator(v.iter().cloned())
}

impl Motion {
    /// Check ranges; `key` names the table (e.g. `body[0].motion`), `dim` the case dimension.
    pub fn validate(&self, key: &str, dim: usize) -> Result<(), String> {
        let finite_vec = |k: &str, v: &[f64]| -> Result<(), String> {
            if v.len() != dim {
                return Err(format!(
                    "{key}.{k}: must have {dim} entries (case.dimension), got {}",
                    v.len()
                ));
            }
            if let Some(x) = v.iter().find(|x| !x.is_finite()) {
                return Err(format!("{key}.{k}: entries must be finite, got {x}"));
            }
            Ok(())
        };
        let finite = |k: &str, v: f64| -> Result<(), String> {
            if v.is_finite() {
                Ok(())
            } else {
                Err(format!("{key}.{k}: must be finite, got {v}"))
            }
        };
        match self {
            Motion::Fixed | Motion::External => Ok(()),
            Motion::Sinusoid {
                amplitude,
                angle_amplitude,
                frequency,
                phase,
                start,
            } => {
                if let Some(a) = amplitude {
                    finite_vec("amplitude", a)?;
                }
                finite("angle_amplitude", *angle_amplitude)?;
                finite("phase", *phase)?;
                finite("start", *start)?;
                if !(frequency.is_finite() && *frequency > 0.0) {
                    return Err(format!(
                        "{key}.frequency: must be a finite number > 0, got {frequency}"
                    ));
                }
                Ok(())
            }
            Motion::Ramp {
                velocity,
                angular_velocity,
                ramp_time,
                start,
            } => {
                finite_vec("velocity", velocity)?;
                finite("angular_velocity", *angular_velocity)?;
                finite("start", *start)?;
                if !(ramp_time.is_finite() && *ramp_time >= 0.0) {
                    return Err(format!(
                        "{key}.ramp_time: must be a finite number ≥ 0, got {ramp_time}"
                    ));
                }
                Ok(())
            }
            Motion::Table {
                time,
                displacement,
                angle,
            } => {
                if let Some(a) = angle {
                    if a.len() != time.len() {
                        return Err(format!(
                            "{key}.angle: must have one entry per time ({}), got {}",
                            time.len(),
                            a.len()
                        ));
                    }
                    if let Some(x) = a.iter().find(|x| !x.is_finite()) {
                        return Err(format!("{key}.angle: entries must be finite, got {x}"));
                    }
                    if dim < 2 && a.iter().any(|x| *x != 0.0) {
                        return Err(format!("{key}.angle: a 1D body cannot rotate"));
                    }
                }
                if time.is_empty() || time.len() != displacement.len() {
                    return Err(format!(
                        "{key}: `time` and `displacement` must be non-empty and of equal length, got {} and {}",
                        time.len(),
                        displacement.len()
                    ));
                }
                for (i, d) in displacement.iter().enumerate() {
                    finite_vec(&format!("displacement[{i}]"), d)?;
                }
                for (i, w) in time.windows(2).enumerate() {
                    if !(w[0].is_finite() && w[1].is_finite() && w[1] > w[0]) {
                        return Err(format!(
                            "{key}.time: must be finite and strictly increasing, entry {} ({}) ≤ entry {i} ({})",
                            i + 1,
                            w[1],
                            w[0]
                        ));
                    }
                }
                finite("time[0]", time[0])
            }
        }
    }

    /// The pose at time t, rotating about the unit `axis` (2D: z; for `External`: the rest
    /// pose, the coupling layer moves it).
    pub fn pose<const D: usize>(&self, t: f64, axis: &Unit<Vector3<f64>>) -> Pose<D> {
        let mut p = Pose::<D>::default();
        // the rotation angle about the axis and its two rates
        let (mut theta, mut rate, mut accel) = (0.0, 0.0, 0.0);
        match self {
            Motion::Fixed | Motion::External => {}
            Motion::Sinusoid {
                amplitude,
                angle_amplitude,
                frequency,
                phase,
                start,
            } => {
                if t >= *start {
                    let w = 2.0 * PI * frequency;
                    let arg = w * (t - start) + phase;
                    let (s, c) = arg.sin_cos();
                    if let Some(a) = amplitude {
                        let a = vector::<D>(a);
                        p.displacement = a * s;
                        p.velocity = a * (w * c);
                        p.acceleration = a * (-w * w * s);
                    }
                    theta = angle_amplitude * s;
                    rate = angle_amplitude * w * c;
                    accel = -angle_amplitude * w * w * s;
                }
            }
            Motion::Ramp {
                velocity,
                angular_velocity: w,
                ramp_time,
                start,
            } => {
                let v = vector::<D>(velocity);
                let tau = t - start;
                if tau > 0.0 {
                    if tau < *ramp_time {
                        let (a, al) = (v / *ramp_time, w / ramp_time);
                        p.acceleration = a;
                        p.velocity = a * tau;
                        p.displacement = a * (0.5 * tau * tau);
                        accel = al;
                        rate = al * tau;
                        theta = 0.5 * al * tau * tau;
                    } else {
                        let moved = 0.5 * ramp_time + (tau - ramp_time);
                        p.velocity = v;
                        p.displacement = v * moved;
                        rate = *w;
                        theta = w * moved;
                    }
                }
            }
            Motion::Table {
                time,
                displacement,
                angle,
            } => {
                let k = time.partition_point(|&x| x <= t);
                let angle_at = |j: usize| angle.as_ref().map_or(0.0, |a| a[j]);
                if k == 0 || k == time.len() {
                    let j = k.saturating_sub(1);
                    p.displacement = vector::<D>(&displacement[j]);
                    theta = angle_at(j);
                } else {
                    let (t0, t1) = (time[k - 1], time[k]);
                    let (d0, d1) = (
                        vector::<D>(&displacement[k - 1]),
                        vector::<D>(&displacement[k]),
                    );
                    let s = (t - t0) / (t1 - t0);
                    p.displacement = d0 + (d1 - d0) * s;
                    p.velocity = (d1 - d0) / (t1 - t0);
                    let (a0, a1) = (angle_at(k - 1), angle_at(k));
                    theta = a0 + (a1 - a0) * s;
                    rate = (a1 - a0) / (t1 - t0);
                }
            }
        }
        if theta != 0.0 || rate != 0.0 || accel != 0.0 {
            p.set_rotation(axis, theta, rate, accel);
        }
        p
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The world angular velocity that turns R(t − e) into R(t + e): Ṙ Rᵀ = [ω]×.
    fn fd_omega<const D: usize>(a: &Pose<D>, c: &Pose<D>, e: f64) -> Vector3<f64> {
        (c.rotation * a.rotation.inverse()).scaled_axis() / (2.0 * e)
    }

    fn fd_check<const D: usize>(m: &Motion, axis: &Unit<Vector3<f64>>, times: &[f64]) {
        let e = 1e-6;
        for &t in times {
            let (a, b, c) = (
                m.pose::<D>(t - e, axis),
                m.pose::<D>(t, axis),
                m.pose::<D>(t + e, axis),
            );
            let v = (c.displacement - a.displacement) / (2.0 * e);
            let acc = (c.velocity - a.velocity) / (2.0 * e);
            let w = fd_omega(&a, &c, e);
            let al = (c.angular_velocity - a.angular_velocity) / (2.0 * e);
            assert!((v - b.velocity).norm() < 1e-6, "{m:?} v at {t}");
            assert!((acc - b.acceleration).norm() < 1e-5, "{m:?} a at {t}");
            assert!((w - b.angular_velocity).norm() < 1e-6, "{m:?} ω at {t}");
            assert!(
                (al - b.angular_acceleration).norm() < 1e-5,
                "{m:?} α at {t}"
            );
        }
    }

    #[test]
    fn velocities_and_accelerations_are_the_derivatives_of_the_pose() {
        let z = Vector3::z_axis();
        let oblique = Unit::new_normalize(Vector3::new(1.0, -2.0, 0.5));
        let sinusoid = |a: Vec<f64>| Motion::Sinusoid {
            amplitude: Some(a),
            angle_amplitude: 0.05,
            frequency: 1.3,
            phase: 0.4,
            start: 0.0,
        };
        fd_check::<2>(&sinusoid(vec![0.01, -0.02]), &z, &[0.1, 0.37, 2.0]);
        fd_check::<3>(&sinusoid(vec![0.01, -0.02, 0.03]), &oblique, &[0.1, 0.37]);
        let ramp = |v: Vec<f64>| Motion::Ramp {
            velocity: v,
            angular_velocity: 0.7,
            ramp_time: 0.2,
            start: 0.1,
        };
        fd_check::<2>(&ramp(vec![1.0, 0.5]), &z, &[0.05, 0.2, 0.25, 1.0]);
        fd_check::<3>(&ramp(vec![1.0, 0.5, 0.0]), &oblique, &[0.2, 1.0]);
        let table = Motion::Table {
            time: vec![0.0, 1.0, 3.0],
            displacement: vec![vec![0.0, 0.0], vec![1.0, 0.0], vec![1.0, 2.0]],
            angle: Some(vec![0.0, 0.3, -0.1]),
        };
        fd_check::<2>(&table, &z, &[0.5, 2.0]);
        assert_eq!(table.pose::<2>(-1.0, &z).displacement[0], 0.0);
        assert_eq!(table.pose::<2>(9.0, &z).displacement[1], 2.0);
        assert_eq!(table.pose::<2>(2.0, &z).displacement[1], 1.0);
        assert!((table.pose::<2>(2.0, &z).planar_angle() - 0.1).abs() < 1e-15);
        assert!((table.pose::<2>(9.0, &z).planar_angle() + 0.1).abs() < 1e-15);
    }

    #[test]
    fn a_held_pose_turns_at_its_world_angular_velocity() {
        let pose = Pose::<3> {
            rotation: UnitQuaternion::from_euler_angles(0.3, -0.2, 1.1),
            angular_velocity: Vector3::new(0.4, -1.0, 0.25),
            velocity: crate::particles::Vector::<3>::new(1.0, 2.0, 3.0),
            ..Default::default()
        };
        let held = HeldPose { time: 2.0, pose };
        assert_eq!(held.at(2.0), pose);
        let e = 1e-6;
        let w = fd_omega(&held.at(2.5 - e), &held.at(2.5 + e), e);
        assert!((w - pose.angular_velocity).norm() < 1e-8, "{w}");
        // a body point turns like ω × r: x(t) − x(t0) ≈ (ω × r) dt for small dt
        let r = crate::particles::Vector::<3>::new(0.2, -0.1, 0.3);
        let dt = 1e-7;
        let moved = held.at(2.0 + dt).to_world(&r) - pose.to_world(&r);
        let expected = pose.angular_velocity.cross(&pose.to_world(&r)) * dt;
        assert!((moved - expected).norm() < 1e-13, "{moved} {expected}");
        assert!((pose.to_body(&pose.to_world(&r)) - r).norm() < 1e-15);
    }

    #[test]
    fn bad_motions_name_the_key() {
        let bad = [
            (
                Motion::Sinusoid {
                    amplitude: Some(vec![0.1]),
                    angle_amplitude: 0.0,
                    frequency: 1.0,
                    phase: 0.0,
                    start: 0.0,
                },
                "body[0].motion.amplitude",
            ),
            (
                Motion::Sinusoid {
                    amplitude: None,
                    angle_amplitude: f64::NAN,
                    frequency: 1.0,
                    phase: 0.0,
                    start: 0.0,
                },
                "body[0].motion.angle_amplitude",
            ),
            (
                Motion::Ramp {
                    velocity: vec![1.0, 0.0],
                    angular_velocity: 0.0,
                    ramp_time: -1.0,
                    start: 0.0,
                },
                "body[0].motion.ramp_time",
            ),
            (
                Motion::Ramp {
                    velocity: vec![1.0, 0.0],
                    angular_velocity: f64::INFINITY,
                    ramp_time: 1.0,
                    start: 0.0,
                },
                "body[0].motion.angular_velocity",
            ),
            (
                Motion::Table {
                    time: vec![0.0, 0.0],
                    displacement: vec![vec![0.0, 0.0], vec![1.0, 0.0]],
                    angle: None,
                },
                "body[0].motion.time",
            ),
            (
                Motion::Table {
                    time: vec![0.0, 1.0],
                    displacement: vec![vec![0.0, 0.0], vec![1.0, 0.0]],
                    angle: Some(vec![0.0]),
                },
                "body[0].motion.angle",
            ),
        ];
        for (m, key) in bad {
            let e = m.validate("body[0].motion", 2).unwrap_err();
            assert!(e.starts_with(key), "{e}");
        }
    }
}
