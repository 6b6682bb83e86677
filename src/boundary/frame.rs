//! The body-fixed (non-inertial) frame of a case (issues 5 and 22, `[frame]`): instead of
//! moving a tank's walls through the box, the whole computation stays in the tank's frame,
//! which moves with a prescribed motion or one a master sets (`motion = external`: any 3D
//! pose, with the accelerations held over a step), a translation d(t) of its reference point
//! and a rotation R(t) (`boundary::kinematics`). Every particle then feels, besides the
//! inertial gravity g, the fictitious accelerations of a frame with origin acceleration
//! A = d̈ and angular velocity Ω (e.g. Landau & Lifshitz, Mechanics §39):
//!
//!   a = −∇P/ρ + Rᵀ(g − A) − Ω̇ × r − 2 Ω × v − Ω × (Ω × r),
//!
//! with r = x − reference and v the velocity in the frame, Rᵀ turning inertial vectors into
//! frame coordinates, and Ω = Rᵀω, Ω̇ = Rᵀω̇ the world angular velocity and acceleration in
//! frame coordinates (d/dt (Rᵀω) = Rᵀω̇, since Ṙᵀω = −Rᵀ(ω × ω) = 0). The terms hold for
//! any 3D pose; a prescribed motion turns about one axis, where Rᵀω = ω. Positions,
//! velocities, forces and torques on bodies are all reported in frame coordinates. The wall
//! condition's hydrostatic term (Adami et al. 2012, eq. 27) uses the same effective body
//! force at the wall particle.
use super::kinematics::{from3, to3, HeldPose, Motion, Pose};
use crate::case::bodies::OrientationInput;
use crate::particles::Vector;
use nalgebra::Vector3;
use serde::{Deserialize, Serialize};

/// `[frame]` of a case file.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct FrameConfig {
    /// The frame's motion: fixed, sinusoid or ramp (about `axis`), or external (set by a
    /// master: the Coupling API's `set_frame_kinematics`, the FMU's `frame.*` inputs, any 3D
    /// pose with its angular velocity and the accelerations held over a step).
    pub motion: Motion,
    /// Point the rotation is about, in frame coordinates (default: the origin).
    #[serde(default)]
    pub reference: Option<Vec<f64>>,
    /// Rotation axis (3D; default z). 2D frames rotate about z.
    #[serde(default)]
    pub axis: Option<Vec<f64>>,
    /// The FMU's orientation input of an external 3D frame: "quaternion" (`frame.orientation`,
    /// default) or "matrix" (`frame.T`, Modelica's R.T).
    #[serde(default)]
    pub orientation: OrientationInput,
}

impl FrameConfig {
    pub fn validate(&self, dim: usize) -> Result<(), String> {
        if self.orientation != OrientationInput::Quaternion
            && !(dim == 3 && self.motion == Motion::External)
        {
            return Err(format!(
                "frame.orientation: \"matrix\" is for a 3D frame with motion = {{ type = \"external\" }} (this is a {dim}D frame{})",
                if self.motion == Motion::External { "" } else { " with a prescribed motion" }
            ));
        }
        if let Motion::Table { .. } = self.motion {
            return Err(
                "frame.motion: a table is piecewise linear, so its acceleration (the frame force) is zero between entries; use a sinusoid or ramp".into(),
            );
        }
        self.motion.validate("frame.motion", dim)?;
        if let Some(r) = &self.reference {
            if r.len() != dim || r.iter().any(|x| !x.is_finite()) {
                return Err(format!(
                    "frame.reference: must have {dim} finite entries (case.dimension), got {r:?}"
                ));
            }
        }
        if let Some(a) = &self.axis {
            if dim != 3 {
                return Err(format!(
                    "frame.axis: only in 3D (a {dim}D frame rotates about z)"
                ));
            }
            let n = a.iter().map(|x| x * x).sum::<f64>().sqrt();
            if a.len() != 3 || !(n.is_finite() && n > 0.0) {
                return Err(format!(
                    "frame.axis: must be 3 finite entries, not all zero, got {a:?}"
                ));
            }
        }
        Ok(())
    }

    pub fn build<const D: usize>(&self) -> Frame<D> {
        let axis = match &self.axis {
            Some(a) => Vector3::new(a[0], a[1], a[2]).normalize(),
            None => Vector3::z(),
        };
        Frame {
            motion: self.motion.clone(),
            reference: self
                .reference
                .as_ref()
                .map(|r| Vector::<D>::from_iterator(r.iter().cloned()))
                .unwrap_or_else(Vector::<D>::zeros),
            axis,
            pose: Pose::default(),
            held: HeldPose::default(),
        }
    }
}

/// The frame at run time: its motion and the pose at the current time.
#[derive(Debug, Clone, Serialize, Deserialize)]
pub struct Frame<const D: usize> {
    /// From the case, so not part of a saved state (`coupling::state` puts it back).
    #[serde(skip)]
    pub motion: Motion,
    pub reference: Vector<D>,
    pub axis: Vector3<f64>,
    pub pose: Pose<D>,
    /// The pose a master set (`Motion::External`), carried on at its accelerations.
    pub held: HeldPose<D>,
}

/// Body force per unit mass at x moving at v: `uniform` without a frame, else the frame's
/// [`Frame::body_force`]. A free function for passes that hold the particles mutably.
#[inline]
pub fn body_force_in<const D: usize>(
    frame: Option<&Frame<D>>,
    uniform: &Vector<D>,
    x: &Vector<D>,
    v: &Vector<D>,
) -> Vector<D> {
    match frame {
        Some(f) => f.body_force(uniform, x, v),
        None => *uniform,
    }
}

impl<const D: usize> Frame<D> {
    /// The frame's pose at time t.
    pub fn place(&mut self, t: f64) {
        self.pose = match self.motion {
            Motion::External => self.held.at(t),
            _ => self
                .motion
                .pose::<D>(t, &nalgebra::Unit::new_normalize(self.axis)),
        };
    }

    /// The uniform part of the body force in frame coordinates, Rᵀ(g − A).
    pub fn uniform(&self, g: &Vector<D>) -> Vector<D> {
        self.pose.to_body(&(g - self.pose.acceleration))
    }

    /// Body force per unit mass at frame position x moving at frame velocity v: the uniform
    /// part and the Euler, Coriolis and centrifugal terms (module docs).
    pub fn body_force(&self, uniform: &Vector<D>, x: &Vector<D>, v: &Vector<D>) -> Vector<D> {
        let p = &self.pose;
        if p.angular_velocity == Vector3::zeros() && p.angular_acceleration == Vector3::zeros() {
            return *uniform;
        }
        let r = to3(&(x - self.reference));
        let w = p.rotation.inverse_transform_vector(&p.angular_velocity);
        let wdot = p.rotation.inverse_transform_vector(&p.angular_acceleration);
        let f = -wdot.cross(&r) - 2.0 * w.cross(&to3(v)) - w.cross(&w.cross(&r));
        uniform + from3::<D>(&f)
    }
}
