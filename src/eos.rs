//! Equations of state behind one trait.

use serde::{Deserialize, Serialize};

/// P(ρ, u) and the sound speed.
pub trait Eos: Send + Sync {
    fn pressure(&self, rho: f64, u: f64) -> f64;
    fn sound_speed(&self, rho: f64, u: f64) -> f64;
    /// Specific internal energy giving pressure P at density ρ (for initial conditions).
    fn internal_energy(&self, rho: f64, p: f64) -> f64;
    /// Adiabatic index where one exists (used by entropy diagnostics), else 1.
    fn gamma(&self) -> f64;
}

/// The EOS of material `m`: its entry in `table` (indexed by material id; `[[material]]` of
/// the case file), else the case's `[eos]`.
pub fn of_material(default: &EosConfig, table: &[EosConfig], m: u16) -> EosConfig {
    table.get(m as usize).copied().unwrap_or(*default)
}

/// `[[material]]`: an equation of state of its own for the particles of regions with
/// `material = id` (e.g. the triple point's γ = 1.4 region beside γ = 1.5 gas).
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct MaterialConfig {
    /// The id regions name in `material`, 1 to 255 (0 is the `[eos]` of the case).
    pub id: u16,
    pub eos: EosConfig,
}

/// Case-file form of the equation of state (`[eos]`).
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
#[serde(tag = "type", rename_all = "kebab-case", deny_unknown_fields)]
pub enum EosConfig {
    /// P = (γ−1) ρ u.
    IdealGas { gamma: f64 },
    /// P = c² ρ (u is carried but does not enter).
    Isothermal { sound_speed: f64 },
    /// Tait / stiffened liquid: P = B[(ρ/ρ0)^γ − 1] + P_bg with B = ρ0 c0²/γ.
    Tait {
        rho0: f64,
        sound_speed: f64,
        #[serde(default = "default_tait_gamma")]
        gamma: f64,
        #[serde(default)]
        background_pressure: f64,
    },
    /// Stiffened gas: P = (γ−1) ρ u − γ P∞.
    StiffenedGas { gamma: f64, p_inf: f64 },
}

fn default_tait_gamma() -> f64 {
    7.0
}

/// x^e for the Tait law's exponents (γ in P, (γ−1)/2 in c): by multiplication when e is a
/// whole number (γ = 7 gives 7 and 3, the usual liquid), else `powf`. The library `pow` was
/// 4–5 % of the closed tank's samples (`perf`, 2026-12-07), called twice per particle and step;
/// `powi` is a handful of multiplies, within 1e-14 of it (tests/eos.rs).
#[inline]
fn tait_power(x: f64, e: f64) -> f64 {
    if e == e.trunc() && e.abs() <= 16.0 {
        x.powi(e as i32)
    } else {
        x.powf(e)
    }
}

impl EosConfig {
    /// The constant P_off that turns P into the part that scales like an ideal gas's
    /// pressure, P + P_off > 0 for every admissible state: 0 for ideal and isothermal gases,
    /// B − P_bg for Tait (P + P_off = B (ρ/ρ0)^γ), γP∞ for a stiffened gas
    /// (P + P_off = (γ−1) ρ u). Rosswog's X = P^k volume element reads it (see there).
    pub fn pressure_offset(&self) -> f64 {
        match *self {
            EosConfig::IdealGas { .. } | EosConfig::Isothermal { .. } => 0.0,
            EosConfig::Tait {
                rho0,
                sound_speed,
                gamma,
                background_pressure,
            } => rho0 * sound_speed * sound_speed / gamma - background_pressure,
            EosConfig::StiffenedGas { gamma, p_inf } => gamma * p_inf,
        }
    }

    /// Check ranges; the error names the key and the allowed range.
    pub fn validate(&self) -> Result<(), String> {
        let pos = |name: &str, v: f64| -> Result<(), String> {
            if v.is_finite() && v > 0.0 {
                Ok(())
            } else {
                Err(format!("eos.{name}: must be a finite number > 0, got {v}"))
            }
        };
        match *self {
            EosConfig::IdealGas { gamma } | EosConfig::StiffenedGas { gamma, .. } => {
                if !(gamma.is_finite() && gamma > 1.0 && gamma <= 10.0) {
                    return Err(format!("eos.gamma: must be in (1, 10], got {gamma}"));
                }
                if let EosConfig::StiffenedGas { p_inf, .. } = *self {
                    if !(p_inf.is_finite() && p_inf >= 0.0) {
                        return Err(format!(
                            "eos.p_inf: must be a finite number ≥ 0, got {p_inf}"
                        ));
                    }
                }
                Ok(())
            }
            EosConfig::Isothermal { sound_speed } => pos("sound_speed", sound_speed),
            EosConfig::Tait {
                rho0,
                sound_speed,
                gamma,
                background_pressure,
            } => {
                pos("rho0", rho0)?;
                pos("sound_speed", sound_speed)?;
                if !(gamma.is_finite() && (1.0..=10.0).contains(&gamma)) {
                    return Err(format!("eos.gamma: must be in [1, 10], got {gamma}"));
                }
                if !background_pressure.is_finite() {
                    return Err("eos.background_pressure: must be finite".into());
                }
                Ok(())
            }
        }
    }
}

impl EosConfig {
    /// The density giving pressure P at specific energy u (the inverse of `pressure`), for wall
    /// particles whose pressure comes from the wall condition; `None` if no positive density
    /// does (P below the Tait floor, or u ≤ 0 for a gas).
    pub fn density_at(&self, p: f64, u: f64) -> Option<f64> {
        let rho = match *self {
            EosConfig::IdealGas { gamma } => p / ((gamma - 1.0) * u),
            EosConfig::StiffenedGas { gamma, p_inf } => (p + gamma * p_inf) / ((gamma - 1.0) * u),
            EosConfig::Isothermal { sound_speed } => p / (sound_speed * sound_speed),
            EosConfig::Tait {
                rho0,
                sound_speed,
                gamma,
                background_pressure,
            } => {
                let b = rho0 * sound_speed * sound_speed / gamma;
                let r = (p - background_pressure) / b + 1.0;
                if r > 0.0 {
                    rho0 * r.powf(1.0 / gamma)
                } else {
                    f64::NAN
                }
            }
        };
        (rho.is_finite() && rho > 0.0).then_some(rho)
    }

    /// Entropy proxy s = (P + P∞)/ρ^γ for the compatible energy split's weights (Frontiere, Raskin
    /// & Owen (2017) §3.3, eqs 62–63); `None` for the barotropic laws, whose split is then even (f = ½).
    #[inline]
    pub fn entropy_proxy(&self, rho: f64, u: f64) -> Option<f64> {
        match *self {
            EosConfig::IdealGas { gamma } => Some((gamma - 1.0) * u * rho.powf(1.0 - gamma)),
            EosConfig::StiffenedGas { gamma, .. } => {
                Some((gamma - 1.0) * u * rho.powf(1.0 - gamma))
            }
            EosConfig::Isothermal { .. } | EosConfig::Tait { .. } => None,
        }
    }
}

impl Eos for EosConfig {
    #[inline]
    fn pressure(&self, rho: f64, u: f64) -> f64 {
        match *self {
            EosConfig::IdealGas { gamma } => (gamma - 1.0) * rho * u,
            EosConfig::Isothermal { sound_speed } => sound_speed * sound_speed * rho,
            EosConfig::Tait {
                rho0,
                sound_speed,
                gamma,
                background_pressure,
            } => {
                let b = rho0 * sound_speed * sound_speed / gamma;
                b * (tait_power(rho / rho0, gamma) - 1.0) + background_pressure
            }
            EosConfig::StiffenedGas { gamma, p_inf } => (gamma - 1.0) * rho * u - gamma * p_inf,
        }
    }
    #[inline]
    fn sound_speed(&self, rho: f64, u: f64) -> f64 {
        match *self {
            EosConfig::IdealGas { gamma } => (gamma * (gamma - 1.0) * u.max(0.0)).sqrt(),
            EosConfig::Isothermal { sound_speed } => sound_speed,
            EosConfig::Tait {
                rho0,
                sound_speed,
                gamma,
                ..
            } => sound_speed * tait_power(rho / rho0, 0.5 * (gamma - 1.0)),
            EosConfig::StiffenedGas { gamma, p_inf } => {
                let p = (gamma - 1.0) * rho * u - gamma * p_inf;
                (gamma * (p + p_inf).max(0.0) / rho).sqrt()
            }
        }
    }
    fn internal_energy(&self, rho: f64, p: f64) -> f64 {
        match *self {
            EosConfig::IdealGas { gamma } => p / ((gamma - 1.0) * rho),
            EosConfig::StiffenedGas { gamma, p_inf } => (p + gamma * p_inf) / ((gamma - 1.0) * rho),
            EosConfig::Isothermal { .. } | EosConfig::Tait { .. } => 0.0,
        }
    }
    fn gamma(&self) -> f64 {
        match *self {
            EosConfig::IdealGas { gamma } | EosConfig::StiffenedGas { gamma, .. } => gamma,
            EosConfig::Tait { gamma, .. } => gamma,
            EosConfig::Isothermal { .. } => 1.0,
        }
    }
}
