//! Rigid-body kinematics of a boundary body (issue 5): a body moves as a translation d(t) of its
//! reference point plus a rotation by θ(t) about a fixed axis through that point (2D: the z
//! axis; 3D: `axis`). A body point p (at t = 0) is at x(t) = r0 + d(t) + R(θ)(p − r0) with
//! velocity ḋ + ω × (x − r0 − d) and acceleration d̈ + ω̇ × r + ω × (ω × r), r = x − r0 − d.
//!
//! Motions: fixed; sinusoidal (translation amplitude and/or rotation amplitude, one frequency);
//! a ramp to a constant velocity; a table of displacements (piecewise linear, so the velocity
//! is piecewise constant and the acceleration zero inside a segment); or set from outside
//! (the Coupling API: pose and velocities at an instant, constant velocity until the next).

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
    /// Displacements of the reference point at increasing times, linear in between; held
    /// before the first and after the last entry.
    Table {
        time: Vec<f64>,
        displacement: Vec<Vec<f64>>,
    },
    /// Pose and velocities set by the master through the Coupling API.
    External,
}

/// Translation and rotation of a body at one instant (rotation about the body axis).
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
pub struct Pose<const D: usize> {
    pub displacement: crate::particles::Vector<D>,
    pub velocity: crate::particles::Vector<D>,
    pub acceleration: crate::particles::Vector<D>,
    pub angle: f64,
    pub angular_velocity: f64,
    pub angular_acceleration: f64,
}

impl<const D: usize> Default for Pose<D> {
    fn default() -> Self {
        let z = crate::particles::Vector::<D>::zeros();
        Self {
            displacement: z,
            velocity: z,
            acceleration: z,
            angle: 0.0,
            angular_velocity: 0.0,
            angular_acceleration: 0.0,
        }
    }
}

/// The pose last set from outside (`Motion::External`, the Coupling API) and when: between
/// two updates the body moves on at the velocities it was given (so its acceleration is zero
/// and the wall condition sees none).
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize, Default)]
pub struct HeldPose<const D: usize> {
    pub time: f64,
    pub pose: Pose<D>,
}

impl<const D: usize> HeldPose<D> {
    /// The pose at t ≥ `time`: displacement and angle carried on at constant velocity.
    pub fn at(&self, t: f64) -> Pose<D> {
        let dt = t - self.time;
        Pose {
            displacement: self.pose.displacement + self.pose.velocity * dt,
            velocity: self.pose.velocity,
            acceleration: crate::particles::Vector::<D>::zeros(),
            angle: self.pose.angle + self.pose.angular_velocity * dt,
            angular_velocity: self.pose.angular_velocity,
            angular_acceleration: 0.0,
        }
    }
}

/// R(θ)·r: rotation by θ about the unit `axis` (Rodrigues; 2D always about z, 1D none).
pub fn rotate_about<const D: usize>(
    axis: &nalgebra::Vector3<f64>,
    r: &crate::particles::Vector<D>,
    theta: f64,
) -> crate::particles::Vector<D> {
    if D < 2 || theta == 0.0 {
        return *r;
    }
    let r3 = nalgebra::Vector3::from_fn(|k, _| if k < D { r[k] } else { 0.0 });
    let k = if D == 2 {
        nalgebra::Vector3::z()
    } else {
        *axis
    };
    let (s, c) = theta.sin_cos();
    let o = r3 * c + k.cross(&r3) * s + k * (k.dot(&r3) * (1.0 - c));
    crate::particles::Vector::<D>::from_fn(|i, _| o[i])
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
            Motion::Table { time, displacement } => {
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

    /// The pose at time t (for `External`: the rest pose; the coupling layer moves it).
    pub fn pose<const D: usize>(&self, t: f64) -> Pose<D> {
        let mut p = Pose::<D>::default();
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
                    p.angle = angle_amplitude * s;
                    p.angular_velocity = angle_amplitude * w * c;
                    p.angular_acceleration = -angle_amplitude * w * w * s;
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
                        p.angular_acceleration = al;
                        p.angular_velocity = al * tau;
                        p.angle = 0.5 * al * tau * tau;
                    } else {
                        let moved = 0.5 * ramp_time + (tau - ramp_time);
                        p.velocity = v;
                        p.displacement = v * moved;
                        p.angular_velocity = *w;
                        p.angle = w * moved;
                    }
                }
            }
            Motion::Table { time, displacement } => {
                let k = time.partition_point(|&x| x <= t);
                if k == 0 {
                    p.displacement = vector::<D>(&displacement[0]);
                } else if k == time.len() {
                    p.displacement = vector::<D>(&displacement[k - 1]);
                } else {
                    let (t0, t1) = (time[k - 1], time[k]);
                    let (d0, d1) = (
                        vector::<D>(&displacement[k - 1]),
                        vector::<D>(&displacement[k]),
                    );
                    let s = (t - t0) / (t1 - t0);
                    p.displacement = d0 + (d1 - d0) * s;
                    p.velocity = (d1 - d0) / (t1 - t0);
                }
            }
        }
        p
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn fd_check(m: &Motion, times: &[f64]) {
        let e = 1e-6;
        for &t in times {
            let (a, b, c) = (m.pose::<2>(t - e), m.pose::<2>(t), m.pose::<2>(t + e));
            let v = (c.displacement - a.displacement) / (2.0 * e);
            let acc = (c.velocity - a.velocity) / (2.0 * e);
            let w = (c.angle - a.angle) / (2.0 * e);
            let al = (c.angular_velocity - a.angular_velocity) / (2.0 * e);
            assert!((v - b.velocity).norm() < 1e-6, "{m:?} v at {t}");
            assert!((acc - b.acceleration).norm() < 1e-5, "{m:?} a at {t}");
            assert!((w - b.angular_velocity).abs() < 1e-6, "{m:?} ω at {t}");
            assert!((al - b.angular_acceleration).abs() < 1e-5, "{m:?} α at {t}");
        }
    }

    #[test]
    fn velocities_and_accelerations_are_the_derivatives_of_the_pose() {
        fd_check(
            &Motion::Sinusoid {
                amplitude: Some(vec![0.01, -0.02]),
                angle_amplitude: 0.05,
                frequency: 1.3,
                phase: 0.4,
                start: 0.0,
            },
            &[0.1, 0.37, 2.0],
        );
        fd_check(
            &Motion::Ramp {
                velocity: vec![1.0, 0.5],
                angular_velocity: 0.7,
                ramp_time: 0.2,
                start: 0.1,
            },
            &[0.05, 0.2, 0.25, 1.0],
        );
        let table = Motion::Table {
            time: vec![0.0, 1.0, 3.0],
            displacement: vec![vec![0.0, 0.0], vec![1.0, 0.0], vec![1.0, 2.0]],
        };
        fd_check(&table, &[0.5, 2.0]);
        assert_eq!(table.pose::<2>(-1.0).displacement[0], 0.0);
        assert_eq!(table.pose::<2>(9.0).displacement[1], 2.0);
        assert_eq!(table.pose::<2>(2.0).displacement[1], 1.0);
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
                },
                "body[0].motion.time",
            ),
        ];
        for (m, key) in bad {
            let e = m.validate("body[0].motion", 2).unwrap_err();
            assert!(e.starts_with(key), "{e}");
        }
    }
}
