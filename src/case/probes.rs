//! `[[probe]]` and `[[marker]]` of a case (issue 5): named points where the Coupling API
//! reports the fluid state. A probe is a fixed point in the fluid (ρ, P, v); a marker is a
//! point on a body's surface that moves with the body (the wall pressure there, for mapping
//! onto another model's mesh). Sampling is in `coupling::sampling`.

use super::{Case, CaseError};
use serde::{Deserialize, Serialize};

#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct ProbeConfig {
    pub name: String,
    /// Fixed point in the fluid (length = dimension).
    pub point: Vec<f64>,
}

#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct MarkerConfig {
    pub name: String,
    /// Name of the body whose surface carries the marker.
    pub body: String,
    /// Point on that surface at t = 0 (length = dimension); it moves with the body.
    pub point: Vec<f64>,
}

/// A named part of a body's surface: the body's wall particles whose t = 0 position lies in
/// the box (all layers, for the force) and, of those, the first layer (for the pressures and
/// the area).
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct PatchConfig {
    pub name: String,
    pub body: String,
    /// Box corners in the body's position at t = 0 (length = dimension).
    pub min: Vec<f64>,
    pub max: Vec<f64>,
}

fn check_name(key: &str, name: &str, earlier: &[&str]) -> Result<(), CaseError> {
    if name.trim().is_empty() {
        return Err(CaseError(format!("{key}.name: must not be empty")));
    }
    if earlier.contains(&name) {
        return Err(CaseError(format!(
            "{key}.name: {name:?} is used by an earlier entry"
        )));
    }
    Ok(())
}

impl Case {
    /// Probes: named, a point of the right length; markers: on the surface of a named body,
    /// within one wall spacing of it.
    pub(super) fn validate_probes(&self) -> Result<(), CaseError> {
        for (i, p) in self.probes.iter().enumerate() {
            let key = format!("probe[{i}]");
            let earlier: Vec<&str> = self.probes[..i].iter().map(|q| q.name.as_str()).collect();
            check_name(&key, &p.name, &earlier)?;
            self.vec_len(&format!("{key}.point"), &p.point)?;
        }
        for (i, m) in self.markers.iter().enumerate() {
            let key = format!("marker[{i}]");
            let earlier: Vec<&str> = self.markers[..i].iter().map(|q| q.name.as_str()).collect();
            check_name(&key, &m.name, &earlier)?;
            self.vec_len(&format!("{key}.point"), &m.point)?;
            let Some(b) = self.bodies.iter().find(|b| b.name == m.body) else {
                let names: Vec<&str> = self.bodies.iter().map(|b| b.name.as_str()).collect();
                return Err(CaseError(format!(
                    "{key}.body: no body named {:?} (bodies: {names:?})",
                    m.body
                )));
            };
            let spacing = b.spacing.unwrap_or_else(|| self.finest_spacing());
            let phi = match self.case.dimension {
                1 => b
                    .shape
                    .distance(&nalgebra::SVector::<f64, 1>::from_column_slice(&m.point)),
                2 => b
                    .shape
                    .distance(&nalgebra::SVector::<f64, 2>::from_column_slice(&m.point)),
                _ => b
                    .shape
                    .distance(&nalgebra::SVector::<f64, 3>::from_column_slice(&m.point)),
            };
            if phi.is_nan() || phi.abs() > spacing {
                return Err(CaseError(format!(
                    "{key}.point: {:?} is {phi:.4} from the surface of body {:?}; a marker must lie within one wall spacing ({spacing}) of it",
                    m.point, m.body
                )));
            }
        }
        for (i, pa) in self.patches.iter().enumerate() {
            let key = format!("patch[{i}]");
            let earlier: Vec<&str> = self.patches[..i].iter().map(|q| q.name.as_str()).collect();
            check_name(&key, &pa.name, &earlier)?;
            self.vec_len(&format!("{key}.min"), &pa.min)?;
            self.vec_len(&format!("{key}.max"), &pa.max)?;
            if let Some(k) = (0..pa.min.len()).find(|&k| pa.max[k] <= pa.min[k]) {
                return Err(CaseError(format!(
                    "{key}.max: must exceed min on every axis, axis {k}: {} ≤ {}",
                    pa.max[k], pa.min[k]
                )));
            }
            if !self.bodies.iter().any(|b| b.name == pa.body) {
                let names: Vec<&str> = self.bodies.iter().map(|b| b.name.as_str()).collect();
                return Err(CaseError(format!(
                    "{key}.body: no body named {:?} (bodies: {names:?})",
                    pa.body
                )));
            }
        }
        Ok(())
    }

    /// The finest region spacing (the default wall spacing).
    pub(crate) fn finest_spacing(&self) -> f64 {
        self.regions
            .iter()
            .map(|r| {
                r.spacing.unwrap_or_else(|| {
                    (r.particle_mass.unwrap_or(0.0) / self.reference_density(r))
                        .powf(1.0 / self.case.dimension as f64)
                })
            })
            .fold(f64::INFINITY, f64::min)
    }
}
