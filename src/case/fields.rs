//! `[[field]]`: initial-state fields given as expressions of position, applied after the
//! regions are filled, so a Kelvin–Helmholtz seed mode, a Rayleigh–Taylor ripple, a shear
//! profile or a smooth density step is data in the case file rather than one region per
//! lattice row.
//!
//! ```toml
//! [[field]]
//! quantity = "velocity.y"
//! expression = "A*sin(4*PI*x)*(exp(-(((y-0.25)/s)^2)) + exp(-(((y-0.75)/s)^2)))"
//! parameters = { A = 0.01, s = 0.05 }
//! ```
//!
//! The expression (parsed by the `exmex` crate: + − * / ^, sin … atanh, exp, ln, sqrt, abs,
//! min, max, atan2, floor, PI, E) sees the particle's position `x`, `y`, `z`, its distance
//! from the origin `r`, its current state `rho`, `p`, `u`, `vx`, `vy`, `vz`, and the entry's
//! `parameters`. Beware one rule of exmex's grammar: a unary minus binds tighter than `^`, so
//! `-a^2` is (−a)² = a²; write `-(a^2)` (pinned by a test below). Entries apply in file order. What each quantity changes:
//! * `velocity.x|y|z`: that component;
//! * `density`: ρ, with the particle's volume kept (its mass scales with ρ) and its pressure
//!   kept (u follows from the EOS), so a density field at uniform pressure is one entry;
//! * `pressure`: P, through u from the EOS at the particle's ρ;
//! * `internal_energy`: u;
//! * `displacement.x|y|z`: moves the particle (periodic axes wrap).

use super::CaseError;
use crate::domain::Domain;
use crate::eos::{Eos, EosConfig};
use crate::particles::{Particles, Vector};
use exmex::prelude::*;
use serde::{Deserialize, Serialize};
use std::collections::BTreeMap;

/// What a `[[field]]` entry sets.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize)]
pub enum Quantity {
    #[serde(rename = "velocity.x")]
    VelocityX,
    #[serde(rename = "velocity.y")]
    VelocityY,
    #[serde(rename = "velocity.z")]
    VelocityZ,
    #[serde(rename = "density")]
    Density,
    #[serde(rename = "pressure")]
    Pressure,
    #[serde(rename = "internal_energy")]
    InternalEnergy,
    #[serde(rename = "displacement.x")]
    DisplacementX,
    #[serde(rename = "displacement.y")]
    DisplacementY,
    #[serde(rename = "displacement.z")]
    DisplacementZ,
}

impl Quantity {
    /// The axis of a vector quantity.
    fn axis(self) -> Option<usize> {
        match self {
            Quantity::VelocityX | Quantity::DisplacementX => Some(0),
            Quantity::VelocityY | Quantity::DisplacementY => Some(1),
            Quantity::VelocityZ | Quantity::DisplacementZ => Some(2),
            _ => None,
        }
    }
}

/// How the value combines with the state the regions gave.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default, Serialize, Deserialize)]
#[serde(rename_all = "lowercase")]
pub enum Combine {
    /// Replace the value.
    #[default]
    Set,
    /// Add to the value (a perturbation on top of the regions' state).
    Add,
}

/// One `[[field]]` entry.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct FieldExpr {
    pub quantity: Quantity,
    pub expression: String,
    #[serde(default)]
    pub combine: Combine,
    /// Indices of the `[[region]]`s whose particles it applies to (default: all).
    #[serde(default)]
    pub regions: Option<Vec<usize>>,
    /// Named constants the expression may use (so `--set field.0.parameters.A=…` scans them).
    #[serde(default)]
    pub parameters: BTreeMap<String, f64>,
    /// When it applies: to the generated particles (default), or after the first density
    /// evaluation, where `rho` is the scheme's summed density (pressure and internal energy
    /// only): a pressure exactly uniform over an irregular or equal-mass particle set
    /// (Rosswog 2015 §7.1's "u from the computed density"; Abel 2011 §3.1's isobaric lattice).
    #[serde(default)]
    pub stage: Stage,
}

/// When a `[[field]]` entry applies.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default, Serialize, Deserialize)]
#[serde(rename_all = "kebab-case")]
pub enum Stage {
    /// To the particles as the regions placed them (ρ is the region's).
    #[default]
    Initial,
    /// After the first evaluation, with ρ the scheme's own density estimate.
    Density,
}

/// An expression of position alone with its constants: a region's `density_profile`.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct Formula {
    pub expression: String,
    #[serde(default)]
    pub parameters: BTreeMap<String, f64>,
}

impl Formula {
    /// Parse it for a `dim`-dimensional case; `key` names it in errors.
    pub fn compile(&self, key: &str, dim: usize) -> Result<CompiledFormula, CaseError> {
        let c = compile_expr(key, &self.expression, &self.parameters, dim, 4)?;
        Ok(CompiledFormula { c, key: key.into() })
    }
}

/// A parsed [`Formula`], evaluated at positions.
pub struct CompiledFormula {
    c: Compiled,
    key: String,
}

impl CompiledFormula {
    /// The value at x (coordinates beyond the case's dimension are 0).
    pub fn at(&self, x: &[f64]) -> Result<f64, CaseError> {
        self.c
            .eval(&position_variables(x))
            .map_err(|e| CaseError(format!("{}: at x = {x:?}: {e}", self.key)))
    }
}

/// An expression of a particle's rest position (`x`, `y`, `z`, `r`: where it was at t = 0),
/// the time `t` and named constants: one quantity of a driven region (`boundary::drive`).
#[derive(Debug, Clone)]
pub struct TimeFormula {
    c: Compiled,
    /// index of `t` among the parameters
    t_slot: usize,
    key: String,
}

impl TimeFormula {
    /// Parse `expression` for a `dim`-dimensional case; `key` names it in errors.
    pub fn compile(
        key: &str,
        expression: &str,
        parameters: &BTreeMap<String, f64>,
        dim: usize,
    ) -> Result<Self, CaseError> {
        if parameters.contains_key("t") {
            return Err(CaseError(format!(
                "{key}: `t` is the time; rename the parameter"
            )));
        }
        let mut with_t = parameters.clone();
        with_t.insert("t".into(), 0.0);
        let c = compile_expr(key, expression, &with_t, dim, 4)?;
        let t_slot = with_t.keys().position(|k| k == "t").unwrap_or(0);
        Ok(Self {
            c,
            t_slot,
            key: key.into(),
        })
    }

    /// The value for rest position x at time t (coordinates beyond the case's dimension are
    /// 0); an evaluation error or a non-finite value is an error naming the key, x and t.
    pub fn at(&self, x: &[f64], t: f64) -> Result<f64, String> {
        let mut params = self.c.params.clone();
        params[self.t_slot] = t;
        match self.c.eval_with(&position_variables(x), &params) {
            Ok(v) if v.is_finite() => Ok(v),
            Ok(v) => Err(format!("{} is {v} at x = {x:?}, t = {t}", self.key)),
            Err(e) => Err(format!("{}: at x = {x:?}, t = {t}: {e}", self.key)),
        }
    }
}

/// The own variables of a formula of position alone: x, y, z (those beyond the case's
/// dimension 0) and r; the state variables stay 0.
fn position_variables(x: &[f64]) -> [f64; 10] {
    let mut own = [0.0; 10];
    own[..x.len()].copy_from_slice(x);
    own[3] = x.iter().map(|v| v * v).sum::<f64>().sqrt();
    own
}

/// Names of the particle's own variables, in the order of [`Vars::values`].
const VARIABLES: [&str; 10] = ["x", "y", "z", "r", "rho", "p", "u", "vx", "vy", "vz"];

/// A parsed entry: the expression and, per variable it names, where its value comes from.
#[derive(Debug, Clone)]
struct Compiled {
    expr: FlatEx<f64>,
    /// index into `Vars::values` (< 10) or into the parameters (≥ 10)
    slots: Vec<usize>,
    params: Vec<f64>,
}

impl Compiled {
    /// The value with the particle's own variables `own` (in [`VARIABLES`] order).
    fn eval(&self, own: &[f64; 10]) -> Result<f64, exmex::ExError> {
        self.eval_with(own, &self.params)
    }

    /// [`Self::eval`] with other parameter values (same order as `params`).
    fn eval_with(&self, own: &[f64; 10], params: &[f64]) -> Result<f64, exmex::ExError> {
        let args: Vec<f64> = self
            .slots
            .iter()
            .map(|&s| {
                if s < own.len() {
                    own[s]
                } else {
                    params[s - own.len()]
                }
            })
            .collect();
        self.expr.eval(&args)
    }
}

fn compile(i: usize, f: &FieldExpr, dim: usize) -> Result<Compiled, CaseError> {
    compile_expr(
        &format!("field[{i}]"),
        &f.expression,
        &f.parameters,
        dim,
        VARIABLES.len(),
    )
}

/// Parse `expression` (named `key` in errors) over the first `allowed` of [`VARIABLES`] and
/// the `parameters`.
fn compile_expr(
    key: &str,
    expression: &str,
    parameters: &BTreeMap<String, f64>,
    dim: usize,
    allowed: usize,
) -> Result<Compiled, CaseError> {
    let expr = exmex::parse::<f64>(expression).map_err(|e| {
        CaseError(format!(
            "{key}.expression: cannot parse {expression:?}: {e}"
        ))
    })?;
    let params: Vec<(&String, &f64)> = parameters.iter().collect();
    let mut slots = Vec::new();
    for name in expr.var_names() {
        let slot = match VARIABLES[..allowed].iter().position(|v| v == name) {
            // a coordinate the case does not have is an error, not a silent zero
            Some(k) if k < 3 && k >= dim => {
                return Err(CaseError(format!(
                    "{key}.expression: `{name}` is not a coordinate of a {dim}D case"
                )))
            }
            Some(k) => k,
            None => match params.iter().position(|(p, _)| *p == name) {
                Some(k) => VARIABLES.len() + k,
                None => {
                    return Err(CaseError(format!(
                        "{key}.expression: unknown name `{name}` (allowed: {}, or a key of {key}.parameters)",
                        VARIABLES[..allowed].join(", ")
                    )))
                }
            },
        };
        slots.push(slot);
    }
    for (name, v) in &params {
        if !v.is_finite() {
            return Err(CaseError(format!(
                "{key}.parameters.{name}: must be finite, got {v}"
            )));
        }
    }
    Ok(Compiled {
        expr,
        slots,
        params: params.iter().map(|(_, v)| **v).collect(),
    })
}

/// Check every entry of a case: parse, names, quantity against the dimension, region indices.
pub fn validate(fields: &[FieldExpr], dim: usize, regions: usize) -> Result<(), CaseError> {
    for (i, f) in fields.iter().enumerate() {
        if let Some(k) = f.quantity.axis() {
            if k >= dim {
                return Err(CaseError(format!(
                    "field[{i}].quantity: {:?} needs axis {k}, but the case is {dim}D",
                    f.quantity
                )));
            }
        }
        if let Some(rs) = &f.regions {
            if let Some(bad) = rs.iter().find(|&&r| r >= regions) {
                return Err(CaseError(format!(
                    "field[{i}].regions: {bad} is not a region index (0 to {})",
                    regions.saturating_sub(1)
                )));
            }
        }
        if f.stage == Stage::Density {
            if f.regions.is_some() {
                return Err(CaseError(format!(
                    "field[{i}].regions: a stage = \"density\" entry applies to every fluid particle"
                )));
            }
            if !matches!(f.quantity, Quantity::Pressure | Quantity::InternalEnergy) {
                return Err(CaseError(format!(
                    "field[{i}].stage: \"density\" sets pressure or internal_energy only (from the scheme's density), not {:?}",
                    f.quantity
                )));
            }
            if f.combine == Combine::Add {
                return Err(CaseError(format!(
                    "field[{i}].combine: \"add\" is for stage = \"initial\" (a stage = \"density\" entry is re-applied until the density settles)"
                )));
            }
        }
        compile(i, f, dim)?;
    }
    Ok(())
}

/// `region_of` of a particle no region placed (a wall or port-buffer particle).
pub const NO_REGION: usize = usize::MAX;

/// Apply the density-stage entries to the fluid particles of an evaluated system (ρ the
/// scheme's); true when there are any (the caller then evaluates again: with X = P^k volume
/// elements the density depends on P).
pub fn apply_after_density<const D: usize>(
    fields: &[FieldExpr],
    sys: &mut crate::system::System<D>,
) -> Result<bool, CaseError> {
    if !fields.iter().any(|f| f.stage == Stage::Density) {
        return Ok(false);
    }
    let p = &sys.particles;
    let region_of: Vec<usize> = (0..p.len())
        .map(|a| {
            if p.body[a] == 0 && p.port[a] == 0 {
                0
            } else {
                NO_REGION
            }
        })
        .collect();
    let domain = sys.domain;
    apply(
        fields,
        Stage::Density,
        &mut sys.particles,
        &region_of,
        &|m| crate::eos::of_material(&sys.eos, &sys.material_eos, m),
        &domain,
    )?;
    Ok(true)
}

/// Apply the entries of `stage` to the particles; `region_of[a]` is the region that placed
/// particle a (entries apply to particles with a region only: not to walls or port buffers).
pub fn apply<const D: usize>(
    fields: &[FieldExpr],
    stage: Stage,
    p: &mut Particles<D>,
    region_of: &[usize],
    eos_of: &dyn Fn(u16) -> EosConfig,
    domain: &Domain<D>,
) -> Result<(), CaseError> {
    for (i, f) in fields.iter().enumerate() {
        if f.stage != stage {
            continue;
        }
        let c = compile(i, f, D)?;
        for (a, region) in region_of.iter().enumerate() {
            if *region == NO_REGION {
                continue;
            }
            if let Some(rs) = &f.regions {
                if !rs.contains(region) {
                    continue;
                }
            }
            let x = p.pos[a];
            let eos = eos_of(p.material[a]);
            let pressure = eos.pressure(p.rho[a], p.u[a]);
            let mut own = [0.0; 10];
            for k in 0..D {
                own[k] = x[k];
                own[7 + k] = p.vel[a][k];
            }
            own[3] = x.norm();
            own[4] = p.rho[a];
            own[5] = pressure;
            own[6] = p.u[a];
            let value = c.eval(&own).map_err(|e| {
                CaseError(format!(
                    "field[{i}].expression: at x = {:?}: {e}",
                    x.as_slice()
                ))
            })?;
            let old = match f.quantity {
                Quantity::Density => p.rho[a],
                Quantity::Pressure => pressure,
                Quantity::InternalEnergy => p.u[a],
                q => match q.axis() {
                    Some(k)
                        if matches!(
                            q,
                            Quantity::VelocityX | Quantity::VelocityY | Quantity::VelocityZ
                        ) =>
                    {
                        p.vel[a][k]
                    }
                    _ => 0.0,
                },
            };
            let v = match f.combine {
                Combine::Set => value,
                Combine::Add => old + value,
            };
            let positive = matches!(f.quantity, Quantity::Density);
            let non_negative = matches!(f.quantity, Quantity::Pressure | Quantity::InternalEnergy);
            if !v.is_finite() || (positive && v <= 0.0) || (non_negative && v < 0.0) {
                let range = if positive {
                    "finite and > 0"
                } else if non_negative {
                    "finite and ≥ 0"
                } else {
                    "finite"
                };
                return Err(CaseError(format!(
                    "field[{i}].expression: gives {v} for {:?} at x = {:?}; it must be {range}",
                    f.quantity,
                    x.as_slice()
                )));
            }
            match f.quantity {
                Quantity::Density => {
                    // same volume, same pressure
                    p.mass[a] *= v / p.rho[a];
                    p.rho[a] = v;
                    p.u[a] = eos.internal_energy(v, pressure);
                }
                Quantity::Pressure => p.u[a] = eos.internal_energy(p.rho[a], v),
                Quantity::InternalEnergy => p.u[a] = v,
                Quantity::VelocityX | Quantity::VelocityY | Quantity::VelocityZ => {
                    p.vel[a][f.quantity.axis().expect("vector")] = v;
                }
                Quantity::DisplacementX | Quantity::DisplacementY | Quantity::DisplacementZ => {
                    let mut x = p.pos[a];
                    x[f.quantity.axis().expect("vector")] += v;
                    let mut dummy = Vector::<D>::zeros();
                    domain.enforce(&mut x, &mut dummy);
                    p.pos[a] = x;
                }
            }
        }
    }
    Ok(())
}

#[cfg(test)]
mod tests {
    use exmex::prelude::*;

    /// The grammar rule the module documentation warns about: `-a^2` is (−a)², `-(a^2)` is −a².
    #[test]
    fn unary_minus_binds_tighter_than_power() {
        let e = |s: &str| exmex::parse::<f64>(s).unwrap().eval(&[3.0]).unwrap();
        assert_eq!(e("-a^2"), 9.0);
        assert_eq!(e("-(a^2)"), -9.0);
        assert_eq!(e("0-a^2"), -9.0);
    }
}
