//! `[[body]]`: rigid boundary bodies of a case (issue 5) — their shape, motion and wall
//! particles; see `boundary::bodies` for the wall condition and the loads.

use super::{Case, CaseError};
use crate::boundary::bodies::Body;
use crate::boundary::geometry::Shape;
use crate::boundary::kinematics::{Motion, Pose};
use crate::eos::{Eos, EosConfig};
use crate::particles::{Particles, Vector};
use serde::{Deserialize, Serialize};

#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct BodyConfig {
    pub name: String,
    pub shape: Shape,
    #[serde(default)]
    pub motion: Motion,
    /// Reference point of the kinematics and the torque (default: the origin).
    pub reference: Option<Vec<f64>>,
    /// Rotation axis in 3D (default z).
    pub axis: Option<Vec<f64>>,
    /// Wall-particle spacing (default: the finest region spacing).
    pub spacing: Option<f64>,
    /// Reference density of the wall particles, which sets their mass (default: the Tait ρ0,
    /// else the first region's density).
    pub density: Option<f64>,
    /// No-slip wall for the laminar viscosity (`[scheme] viscosity`); default free slip (the
    /// viscous term leaves the wall out).
    #[serde(default)]
    pub no_slip: bool,
    /// How a master gives the orientation of a 3D body driven from outside (FMU inputs):
    /// "quaternion" (default, `<name>.orientation`, [w, x, y, z]) or "matrix"
    /// (`<name>.T`, Modelica MultiBody's `R.T`, row major). A 2D body takes an angle.
    #[serde(default)]
    pub orientation: OrientationInput,
}

/// `orientation` of a `[[body]]`: the form of the FMU's orientation input.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize, Default)]
#[serde(rename_all = "kebab-case")]
pub enum OrientationInput {
    #[default]
    Quaternion,
    Matrix,
}

impl BodyConfig {
    pub fn validate(&self, i: usize, case: &Case) -> Result<(), CaseError> {
        let key = format!("body[{i}]");
        let d = case.case.dimension;
        if self.name.trim().is_empty() {
            return Err(CaseError(format!("{key}.name: must not be empty")));
        }
        self.shape.validate(&key, d).map_err(CaseError)?;
        self.motion
            .validate(&format!("{key}.motion"), d)
            .map_err(CaseError)?;
        if let Some(r) = &self.reference {
            case.vec_len(&format!("{key}.reference"), r)?;
        }
        if let Some(a) = &self.axis {
            if a.len() != 3 || !a.iter().all(|x| x.is_finite()) || a.iter().all(|x| *x == 0.0) {
                return Err(CaseError(format!(
                    "{key}.axis: must be 3 finite entries, not all zero, got {a:?}"
                )));
            }
        }
        for (k, v) in [("spacing", self.spacing), ("density", self.density)] {
            if let Some(v) = v {
                if !(v.is_finite() && v > 0.0) {
                    return Err(CaseError(format!(
                        "{key}.{k}: must be a finite number > 0, got {v}"
                    )));
                }
            }
        }
        if self.orientation != OrientationInput::Quaternion
            && !(d == 3 && self.motion == Motion::External)
        {
            return Err(CaseError(format!(
                "{key}.orientation: \"matrix\" is for a 3D body with motion = {{ type = \"external\" }} (a {d}D body{} takes its orientation as {})",
                if self.motion == Motion::External { "" } else { " with a prescribed motion" },
                if d == 3 { "its motion" } else { "an angle" }
            )));
        }
        if case.bodies[..i].iter().any(|b| b.name == self.name) {
            return Err(CaseError(format!(
                "{key}.name: {:?} is used by an earlier body",
                self.name
            )));
        }
        Ok(())
    }
}

/// Add the wall particles of every body to `p` (after the fluid) and return the bodies.
/// `spacing_of` holds each fluid particle's lattice spacing; `eta` sets h = η Δx and the
/// wall thickness of one kernel support; `factor` is the wall lattice's kernel-sum factor
/// (1 + ε, or 1 without a summed density). A fluid particle inside a body is an error.
pub(super) fn add_bodies<const D: usize>(
    case: &Case,
    p: &mut Particles<D>,
    spacing_of: &[f64],
    eta: f64,
    origin: &Vector<D>,
    factor: f64,
) -> Result<Vec<Body<D>>, CaseError> {
    let fluid = p.len();
    let finest = spacing_of.iter().cloned().fold(f64::INFINITY, f64::min);
    let mut out = Vec::new();
    for (bi, b) in case.bodies.iter().enumerate() {
        let key = format!("body[{bi}]");
        if let Some(i) = (0..fluid).find(|&i| b.shape.distance(&p.pos[i]) < 0.0) {
            return Err(CaseError(format!(
                "{key}: overlaps the fluid: particle at {:?} lies inside {:?}",
                p.pos[i].as_slice(),
                b.name
            )));
        }
        let dx = b.spacing.unwrap_or(finest);
        let h = eta * dx;
        // one full support (2h) behind the surface
        let thickness = crate::kernel::SUPPORT * h;
        let rho = b.density.unwrap_or(match case.eos {
            EosConfig::Tait { rho0, .. } => rho0,
            _ => case
                .regions
                .first()
                .map(|r| case.reference_density(r))
                .unwrap_or(1.0),
        });
        let u = case
            .regions
            .first()
            .map(|r| match (r.pressure, r.internal_energy) {
                (Some(pr), _) => case.eos.internal_energy(case.reference_density(r), pr),
                (_, Some(u)) => u,
                _ => 0.0,
            })
            .unwrap_or(0.0);
        let (lattice, aligned) = b.shape.wall_lattice::<D>(dx, origin);
        let pts = b.shape.wall_points::<D>(&lattice, &aligned, thickness);
        if pts.is_empty() {
            return Err(CaseError(format!(
                "{key}.shape: no wall particle fits (spacing {dx}); the shape is thinner than the lattice"
            )));
        }
        let volume = lattice.iter().product::<f64>() / factor;
        let mass = rho * volume;
        for x in pts {
            p.push(mass, x, Vector::zeros(), u, rho, h, 1000 + bi as u16);
            let last = p.len() - 1;
            p.body[last] = bi as u16 + 1;
            p.pressure[last] = case.eos.pressure(rho, u);
        }
        let reference = b
            .reference
            .as_ref()
            .map(|r| Vector::<D>::from_iterator(r.iter().cloned()))
            .unwrap_or_else(Vector::zeros);
        let axis = b
            .axis
            .as_ref()
            .map(|a| nalgebra::Vector3::new(a[0], a[1], a[2]).normalize())
            .unwrap_or_else(nalgebra::Vector3::z);
        out.push(Body {
            name: b.name.clone(),
            motion: b.motion.clone(),
            reference,
            axis,
            pose: Pose::default(),
            force: Vector::zeros(),
            torque: [0.0; 3],
            particle_volume: volume,
            spacing: dx,
            impulse: Vector::zeros(),
            angular_impulse: [0.0; 3],
            held: Default::default(),
            no_slip: b.no_slip,
        });
    }
    Ok(out)
}
