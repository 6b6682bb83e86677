//! Relative-pressure SPH (Abel 2011, "rpSPH"; Abel (2011)): standard SPH with the
//! pressure force replaced by a_a = −Σ_b m_b (P_b − P_a)/ρ_b² ∇W. Density, h, viscosity,
//! conductivity and time stepping are the standard scheme's. A uniform pressure exerts no
//! force for any particle arrangement (Newton's first law), at the price of exact momentum
//! and energy conservation: the runner reports the momentum drift.

use super::standard::{check_range, PressureForm, StandardParams, StandardSph};
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
            cullen_dehnen: false,
            density: super::standard::DensityMode::Summation,
            viscosity: 0.0,
            delta: 0.0,
        }
    }
    pub fn validate(&self) -> Result<(), String> {
        check_range("scheme.alpha", self.alpha, 0.0, 10.0)?;
        self.viscosity().validate()
    }
}

/// rpSPH is the standard scheme with the relative-pressure force (one pair loop for both).
pub fn build(params: RpsphParams) -> StandardSph {
    let form = PressureForm::Relative {
        symmetric: params.gradient == RpsphGradient::Symmetric,
        shock_switch: params.shock_switch,
    };
    StandardSph::with_form(params.viscosity(), form, "rpsph")
}
