//! The Gresho–Chan vortex (Rosswog (2015) Sec. 7.4, Eqs. 104–105): a stationary solution of the
//! Euler equations with ρ = 1, used for the L1 velocity norm of Eq. 106.

use serde::{Deserialize, Serialize};

/// Vortex parameters: centre (2D), core radius R1, peak speed v0, background pressure P0.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct Gresho {
    pub center: [f64; 2],
    #[serde(default = "default_r1")]
    pub radius: f64,
    #[serde(default = "default_v0")]
    pub v0: f64,
    /// The literature's P0 = 5 (P0/ρv0² = 5); the paper's scaled numbers imply 0.5 (Rosswog (2015) Sec. 7.4).
    #[serde(default = "default_p0")]
    pub p0: f64,
}

fn default_r1() -> f64 {
    0.2
}
fn default_v0() -> f64 {
    1.0
}
fn default_p0() -> f64 {
    5.0
}

impl Gresho {
    pub fn validate(&self, key: &str) -> Result<(), String> {
        for (k, v) in [("radius", self.radius), ("v0", self.v0), ("p0", self.p0)] {
            if !(v.is_finite() && v > 0.0) {
                return Err(format!("{key}.{k}: must be a finite number > 0, got {v}"));
            }
        }
        if !self.center.iter().all(|c| c.is_finite()) {
            return Err(format!("{key}.center: must be finite"));
        }
        Ok(())
    }

    /// Azimuthal speed at radius r.
    pub fn v_phi(&self, r: f64) -> f64 {
        let u = r / self.radius;
        self.v0
            * if u <= 1.0 {
                u
            } else if u <= 2.0 {
                2.0 - u
            } else {
                0.0
            }
    }

    /// Pressure at radius r (dP/dr = ρ v_φ²/r with ρ = 1).
    pub fn pressure(&self, r: f64) -> f64 {
        let u = r / self.radius;
        let v2 = self.v0 * self.v0;
        self.p0
            + if u <= 1.0 {
                0.5 * v2 * u * u
            } else if u <= 2.0 {
                4.0 * v2 * (u * u / 8.0 - u + u.ln() + 1.0)
            } else {
                4.0 * v2 * (2f64.ln() - 0.5)
            }
    }

    /// Velocity vector at (x, y).
    pub fn velocity(&self, x: f64, y: f64) -> [f64; 2] {
        let (dx, dy) = (x - self.center[0], y - self.center[1]);
        let r = dx.hypot(dy);
        if r == 0.0 {
            return [0.0, 0.0];
        }
        let v = self.v_phi(r);
        [-v * dy / r, v * dx / r]
    }

    /// Eq. 106: L1 = (1/(N v0)) Σ_a |v_a − v(r_a)|.
    pub fn l1(&self, particles: &[([f64; 2], [f64; 2])]) -> f64 {
        let s: f64 = particles
            .iter()
            .map(|(x, v)| {
                let e = self.velocity(x[0], x[1]);
                (v[0] - e[0]).hypot(v[1] - e[1])
            })
            .sum();
        s / (particles.len().max(1) as f64 * self.v0)
    }
}
