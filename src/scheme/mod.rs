//! Hydrodynamic formulations. A scheme turns the current (x, v, u) into dv/dt and du/dt; the
//! driver and the integrators never know which scheme runs. Each formulation lives in its own
//! module behind [`Scheme`]; all of them loop over pairs through [`System::gather`].

pub mod rpsph;
pub mod smoothing;
pub mod standard;

use crate::system::System;
use serde::{Deserialize, Serialize};

/// Failure inside an evaluation (reported with the step and time by the driver).
#[derive(Debug, Clone, PartialEq)]
pub struct SchemeError(pub String);

pub trait Scheme<const D: usize>: Send + Sync {
    /// Preset name as written in case files.
    fn name(&self) -> &'static str;
    /// Register per-particle fields and set initial switch values.
    fn init(&mut self, sys: &mut System<D>);
    /// Full derivative evaluation: neighbours, density and h, EOS, gradients, forces.
    /// Leaves `acc`, `dudt`, `v_sig` (and the derived fields) in the particles.
    fn evaluate(&mut self, sys: &mut System<D>) -> Result<(), SchemeError>;
    /// Recompute the state (neighbours, ρ, h, P, c) without forces, as after a
    /// predictor-corrector's final update.
    fn refresh(&mut self, sys: &mut System<D>) {
        smoothing::solve_density_and_h(sys);
        sys.update_eos();
    }
    /// Hook after each completed step (switch evolution).
    fn end_step(&mut self, _sys: &mut System<D>, _dt: f64) {}
}

/// `[scheme]` table of a case file.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
#[serde(tag = "name", rename_all = "kebab-case", deny_unknown_fields)]
pub enum SchemeConfig {
    /// Traditional grad-h SPH with Monaghan–Gingold viscosity (see [`standard`]).
    Standard(standard::StandardParams),
    /// Relative-pressure SPH (Abel 2011), see [`rpsph`].
    Rpsph(rpsph::RpsphParams),
}

/// Scheme names accepted in `scheme.name`.
pub const SCHEME_NAMES: &str = "standard, rpsph";

impl SchemeConfig {
    pub fn validate(&self) -> Result<(), String> {
        match self {
            SchemeConfig::Standard(p) => p.validate(),
            SchemeConfig::Rpsph(p) => p.validate(),
        }
    }
    pub fn build<const D: usize>(&self) -> Box<dyn Scheme<D>> {
        match *self {
            SchemeConfig::Standard(p) => Box::new(standard::StandardSph::new(p)),
            SchemeConfig::Rpsph(p) => Box::new(rpsph::Rpsph::new(p)),
        }
    }
}

impl Default for SchemeConfig {
    fn default() -> Self {
        SchemeConfig::Standard(standard::StandardParams::default())
    }
}
