//! Driven regions: particles whose state is a given function of their rest position and time,
//! imposed at every stage of every step instead of evolved. They take part in every sum like
//! fluid, so they act on the fluid as a boundary whose motion and pressure follow an analytic
//! solution: the "rind" of Frontiere, Raskin & Owen (2017) §4.0.1, the ten innermost and
//! outermost points of the Kidder implosion set to the self-similar solution every step.
//!
//! ```toml
//! [region.drive]
//! parameters = { tau = 8.15e-3 }
//! position = ["x*sqrt(1 - (t/tau)^2)"]
//! velocity = ["-x*t/(tau^2*sqrt(1 - (t/tau)^2))"]
//! density = "…"
//! pressure = "…"
//! ```
//!
//! Each expression sees the rest position `x`, `y`, `z`, `r` (where the particle was placed
//! at t = 0), the time `t` and the `parameters`. Position and velocity are set directly; the
//! specific energy is u = u(ρ, P) of the EOS from the given density and pressure. The density
//! the scheme sums (or evolves) stays the scheme's: *decision*, so that a driven particle's
//! pressure P(ρ_sum, u) is what a fluid particle in its place would have, and the boundary
//! carries no density jump of its own. Driven particles are also `frozen`: no derivative
//! moves them, and the compatible energy update drops their share of the pair work (the
//! compression work on the boundary itself, which their imposed u replaces).

use crate::case::fields::TimeFormula;
use crate::case::CaseError;
use crate::eos::Eos;
use crate::particles::Vector;
use crate::system::System;
use serde::{Deserialize, Serialize};
use std::collections::BTreeMap;

/// `[region.drive]` as written in the case file.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct DriveConfig {
    /// One expression per axis.
    pub position: Vec<String>,
    /// One expression per axis.
    pub velocity: Vec<String>,
    pub density: String,
    pub pressure: String,
    #[serde(default)]
    pub parameters: BTreeMap<String, f64>,
}

impl DriveConfig {
    /// Parse every expression for a `dim`-dimensional case; `key` (e.g. `region[0].drive`)
    /// names the field in errors.
    pub fn check(&self, key: &str, dim: usize) -> Result<(), CaseError> {
        self.parse(key, dim).map(|_| ())
    }

    /// The parsed drive of a D-dimensional case.
    pub fn build<const D: usize>(&self, key: &str) -> Result<Drive<D>, CaseError> {
        let (position, velocity, density, pressure) = self.parse(key, D)?;
        Ok(Drive {
            position,
            velocity,
            density,
            pressure,
        })
    }

    #[allow(clippy::type_complexity)]
    fn parse(
        &self,
        key: &str,
        dim: usize,
    ) -> Result<(Vec<TimeFormula>, Vec<TimeFormula>, TimeFormula, TimeFormula), CaseError> {
        let one = |name: &str, e: &str| {
            TimeFormula::compile(&format!("{key}.{name}"), e, &self.parameters, dim)
        };
        let axes = |name: &str, list: &[String]| -> Result<Vec<TimeFormula>, CaseError> {
            if list.len() != dim {
                return Err(CaseError(format!(
                    "{key}.{name}: needs {dim} expressions (one per axis), got {}",
                    list.len()
                )));
            }
            list.iter()
                .enumerate()
                .map(|(k, e)| one(&format!("{name}[{k}]"), e))
                .collect()
        };
        Ok((
            axes("position", &self.position)?,
            axes("velocity", &self.velocity)?,
            one("density", &self.density)?,
            one("pressure", &self.pressure)?,
        ))
    }
}

/// A driven region's parsed expressions.
#[derive(Debug, Clone)]
pub struct Drive<const D: usize> {
    position: Vec<TimeFormula>,
    velocity: Vec<TimeFormula>,
    density: TimeFormula,
    pressure: TimeFormula,
}

/// A driven particle's state at rest position x0, time t.
struct DrivenState<const D: usize> {
    x: Vector<D>,
    v: Vector<D>,
    /// Specific internal energy from the EOS, u(ρ, P).
    u: f64,
    /// The imposed density (rest-frame n in special-relativistic runs).
    rho: f64,
}

impl<const D: usize> Drive<D> {
    fn state(&self, x0: &Vector<D>, t: f64, eos: &dyn Eos) -> Result<DrivenState<D>, String> {
        let mut x = Vector::<D>::zeros();
        let mut v = Vector::<D>::zeros();
        for k in 0..D {
            x[k] = self.position[k].at(x0.as_slice(), t)?;
            v[k] = self.velocity[k].at(x0.as_slice(), t)?;
        }
        let rho = self.density.at(x0.as_slice(), t)?;
        let p = self.pressure.at(x0.as_slice(), t)?;
        if rho <= 0.0 {
            return Err(format!(
                "drive density is {rho} (must be > 0) at x = {x0:?}, t = {t}"
            ));
        }
        let u = eos.internal_energy(rho, p);
        Ok(DrivenState { x, v, u, rho })
    }
}

impl<const D: usize> System<D> {
    /// Set every driven particle to its region's solution at `self.time` (the time of the
    /// state the next evaluation sees). In a special-relativistic run the evolved variables
    /// are the canonical S and ε (Rosswog (2015) Eqs. 54, 57), so they are set too, from the
    /// imposed rest-frame n, P and v: S = γE v, ε = γE − P/(γn). The next evaluation
    /// recovers v, u and P from them with its own summed N, as it does for every particle
    /// (the density stays the scheme's, as in the Newtonian case above).
    pub fn apply_drives(&mut self) -> Result<(), String> {
        if self.drives.is_empty() {
            return Ok(());
        }
        let t = self.time;
        let p = &mut self.particles;
        for i in 0..p.len() {
            let k = p.drive[i];
            if k == 0 {
                continue;
            }
            let eos = crate::eos::of_material(&self.eos, &self.material_eos, p.material[i]);
            let s = self.drives[k as usize - 1].state(&p.rest[i], t, &eos)?;
            if let (Some(sr), crate::eos::EosConfig::IdealGas { gamma }) = (self.relativistic, eos)
            {
                let c = crate::scheme::rosswog::sr::recovery::conserved(
                    gamma,
                    s.rho,
                    s.u,
                    s.v.norm_squared(),
                );
                if !c.lorentz.is_finite() {
                    return Err(format!(
                        "drive velocity |v| = {} at x = {:?}, t = {t}: must be < 1 (c = 1)",
                        s.v.norm(),
                        p.rest[i].as_slice()
                    ));
                }
                p.extra_vectors[sr.momentum][i] = s.v * c.s_over_v;
                p.extra_scalars[sr.energy][i] = c.eps;
            }
            p.pos[i] = s.x;
            p.vel[i] = s.v;
            p.u[i] = s.u;
        }
        Ok(())
    }
}
