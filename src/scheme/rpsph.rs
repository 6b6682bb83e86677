//! Relative-pressure SPH (Abel 2011, "rpSPH"; spec `rpsph.md` §1.3): standard SPH with the
//! pressure force replaced by a_a = −Σ_b m_b (P_b − P_a)/ρ_b² ∇W. Density, h, viscosity,
//! conductivity and time stepping are the standard scheme's. A uniform pressure exerts no
//! force for any particle arrangement (Newton's first law), at the price of exact momentum
//! and energy conservation: the runner reports the momentum drift.

use super::standard::{check_range, force_pass, velocity_gradients, PressureForm, StandardParams};
use super::{smoothing, Scheme, SchemeError};
use crate::system::System;
use serde::{Deserialize, Serialize};

/// Which kernel gradient the relative-pressure force uses.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "kebab-case")]
pub enum RpsphGradient {
    /// ∇_a W_ab(h_a): eq. 4 of the paper, a pure gather.
    OwnH,
    /// ½[∇_a W_ab(h_a) + ∇_a W_ab(h_b)]: the Appendix B variant for large density contrasts.
    Symmetric,
}

/// Parameters of `[scheme] name = "rpsph"`.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields, default)]
pub struct RpsphParams {
    pub alpha: f64,
    pub beta: f64,
    pub balsara: bool,
    pub conductivity: f64,
    pub epsilon: f64,
    pub gradient: RpsphGradient,
    /// Fall back to standard SPH where −h ∇·v > 3 c_s (the paper's hybrid shock switch).
    pub shock_switch: bool,
}

impl Default for RpsphParams {
    fn default() -> Self {
        let s = StandardParams::default();
        Self {
            alpha: s.alpha,
            beta: s.beta,
            balsara: s.balsara,
            conductivity: s.conductivity,
            epsilon: s.epsilon,
            gradient: RpsphGradient::OwnH,
            shock_switch: false,
        }
    }
}

impl RpsphParams {
    fn viscosity(&self) -> StandardParams {
        StandardParams {
            alpha: self.alpha,
            beta: self.beta,
            balsara: self.balsara,
            conductivity: self.conductivity,
            epsilon: self.epsilon,
        }
    }
    pub fn validate(&self) -> Result<(), String> {
        check_range("scheme.alpha", self.alpha, 0.0, 10.0)?;
        self.viscosity().validate()
    }
}

pub struct Rpsph {
    params: RpsphParams,
    balsara_slot: usize,
}

impl Rpsph {
    pub fn new(params: RpsphParams) -> Self {
        Self {
            params,
            balsara_slot: usize::MAX,
        }
    }
}

impl<const D: usize> Scheme<D> for Rpsph {
    fn name(&self) -> &'static str {
        "rpsph"
    }

    fn init(&mut self, sys: &mut System<D>) {
        self.balsara_slot = sys.particles.add_scalar_field(1.0);
        let alpha = self.params.alpha;
        sys.particles.alpha.iter_mut().for_each(|a| *a = alpha);
    }

    fn evaluate(&mut self, sys: &mut System<D>) -> Result<(), SchemeError> {
        smoothing::solve_density_and_h(sys);
        sys.update_eos();
        velocity_gradients(sys, self.balsara_slot, self.params.balsara);
        let form = PressureForm::Relative {
            symmetric: self.params.gradient == RpsphGradient::Symmetric,
            shock_switch: self.params.shock_switch,
        };
        force_pass(sys, &self.params.viscosity(), self.balsara_slot, form);
        Ok(())
    }
}
