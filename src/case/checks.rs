//! `[verify]` (the exact solution a run is compared with) and `[blast]` (a point energy
//! deposit) of a case file.

use super::{Case, CaseError};
use crate::eos::EosConfig;
use serde::{Deserialize, Serialize};

/// `[verify]`: the exact solution to compare with after the run.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(tag = "type", rename_all = "kebab-case", deny_unknown_fields)]
pub enum Verify {
    /// A 1D Riemann problem along x (shock tubes), states as [ρ, v, P]; L1 of ρ, v, P and a
    /// profile plot.
    Riemann {
        x0: f64,
        left: [f64; 3],
        right: [f64; 3],
        /// Only particles with x in [x_min, x_max] enter the norms.
        x_min: Option<f64>,
        x_max: Option<f64>,
    },
    /// The Gresho–Chan vortex: L1 of the velocity (Rosswog Eq. 106).
    Gresho(crate::verify::vortex::Gresho),
    /// Sedov–Taylor blast of whole-space energy `energy` (a quadrant holding E/4 in 2D)
    /// centred at `center` in gas of density `rho0`: shock radius, L1(ρ), radial plot.
    Sedov {
        energy: f64,
        #[serde(default = "one")]
        rho0: f64,
        center: Vec<f64>,
        /// Only particles with r < r_max enter L1(ρ) (default: everywhere).
        r_max: Option<f64>,
    },
    /// Noh implosion: gas of density `rho0` falling in at `speed` towards `center`.
    Noh {
        #[serde(default = "one")]
        rho0: f64,
        #[serde(default = "one")]
        speed: f64,
        center: Vec<f64>,
        r_max: Option<f64>,
    },
}

fn one() -> f64 {
    1.0
}

/// `[blast]`: energy added to the particle nearest `center` (u += E/m), the single-particle
/// spike of the CRKSPH paper's Sedov test (Rosswog (2015), a point the paper leaves open (decided here)).
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct Blast {
    pub energy: f64,
    pub center: Vec<f64>,
}

fn ideal_gas(case: &Case, what: &str) -> Result<(), CaseError> {
    if matches!(case.eos, EosConfig::IdealGas { .. }) {
        Ok(())
    } else {
        Err(CaseError(format!(
            "verify: the {what} solution needs eos.type = \"ideal-gas\""
        )))
    }
}

fn positive(key: &str, v: f64) -> Result<(), CaseError> {
    if v.is_finite() && v > 0.0 {
        Ok(())
    } else {
        Err(CaseError(format!(
            "{key}: must be a finite number > 0, got {v}"
        )))
    }
}

impl Verify {
    pub fn validate(&self, case: &Case) -> Result<(), CaseError> {
        let d = case.case.dimension;
        match self {
            Verify::Gresho(g) => {
                if d != 2 {
                    return Err(CaseError(
                        "verify: the Gresho vortex needs case.dimension = 2".into(),
                    ));
                }
                g.validate("verify")?;
            }
            Verify::Riemann { left, right, .. } => {
                ideal_gas(case, "Riemann")?;
                for (k, s) in [("left", *left), ("right", *right)] {
                    if !(s.iter().all(|x| x.is_finite()) && s[0] >= 0.0 && s[2] >= 0.0) {
                        return Err(CaseError(format!(
                            "verify.{k}: must be [ρ ≥ 0, v, P ≥ 0], finite, got {s:?}"
                        )));
                    }
                }
            }
            Verify::Sedov {
                energy,
                rho0,
                center,
                r_max,
            } => {
                ideal_gas(case, "Sedov")?;
                positive("verify.energy", *energy)?;
                positive("verify.rho0", *rho0)?;
                case.vec_len("verify.center", center)?;
                if let Some(r) = r_max {
                    positive("verify.r_max", *r)?;
                }
            }
            Verify::Noh {
                rho0,
                speed,
                center,
                r_max,
            } => {
                ideal_gas(case, "Noh")?;
                positive("verify.rho0", *rho0)?;
                positive("verify.speed", *speed)?;
                case.vec_len("verify.center", center)?;
                if let Some(r) = r_max {
                    positive("verify.r_max", *r)?;
                }
            }
        }
        Ok(())
    }
}

impl Blast {
    pub fn validate(&self, case: &Case) -> Result<(), CaseError> {
        positive("blast.energy", self.energy)?;
        case.vec_len("blast.center", &self.center)
    }
}
