//! CRKSPH artificial viscosity with the RK-gradient limiter (Frontiere, Raskin & Owen (2017) §3.2; eqs 45–55; 69–74, eqs 45–55, 69–74).
//!
//! The velocity gradient is the RK gradient of eq 54, ∂β v_i^α = −Σ_j V_j v_ij^α G_ij^β. Per
//! pair the velocity jump is extrapolated to the midpoint with the van Leer limiter
//! φ_ij = max(0, min(1, 4r/(1+r)²))·E_ij, r = (x·∇v_i·x)/(x·∇v_j·x), so a linear field
//! (shear included) gives v̂_ij = 0 and Q = 0. Lengths in the paper are in units of its h,
//! whose kernel support is η_max·h; ours is 2h, so its η = |x_ij| η_max / (2 h_ours).

pub use super::gradient::velocity_gradients;
use crate::particles::Vector;
use nalgebra::SMatrix;

/// Limiter and viscosity constants (Frontiere, Raskin & Owen (2017) §3.2; eqs 45–55; 69–74; defaults for W7 with n_h = 1).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct ViscosityParams {
    pub c_l: f64,
    pub c_q: f64,
    pub eps2: f64,
    pub eta_crit: f64,
    pub eta_fold: f64,
    /// The kernel's native support in the paper's h units (W7: 4), converting our h.
    pub native_support: f64,
    pub limiter: bool,
}

impl Default for ViscosityParams {
    fn default() -> Self {
        Self {
            c_l: 2.0,
            c_q: 1.0,
            eps2: 1e-2,
            eta_crit: 1.0,
            eta_fold: 0.2,
            native_support: 4.0,
            limiter: true,
        }
    }
}

/// Viscous pressures (Q_i, Q_j) of the pair (i, j): x_ij = x_i − x_j, v_ij, gradients of i and
/// j (j's reflected for a mirror image), and each side's h, ρ, c.
#[allow(clippy::too_many_arguments)]
pub fn pair_q<const D: usize>(
    prm: &ViscosityParams,
    xij: &Vector<D>,
    vij: &Vector<D>,
    grad_i: &SMatrix<f64, D, D>,
    grad_j: &SMatrix<f64, D, D>,
    (hi, rhoi, ci): (f64, f64, f64),
    (hj, rhoj, cj): (f64, f64, f64),
) -> (f64, f64) {
    let to_paper = prm.native_support / crate::kernel::SUPPORT;
    let r = xij.norm();
    let (eta_i, eta_j) = (xij * (to_paper / hi), xij * (to_paper / hj));
    let phi = if prm.limiter {
        let num = xij.dot(&(grad_i * xij));
        let mut den = xij.dot(&(grad_j * xij));
        den = den.signum() * den.abs().max(1e-30);
        let ratio = num / den;
        let van_leer = if ratio > 0.0 {
            (4.0 * ratio / ((1.0 + ratio) * (1.0 + ratio))).min(1.0)
        } else {
            0.0
        };
        let eta_ij = (r * to_paper / hi).min(r * to_paper / hj);
        let closeness = if eta_ij < prm.eta_crit {
            (-((eta_ij - prm.eta_crit) / prm.eta_fold).powi(2)).exp()
        } else {
            1.0
        };
        van_leer * closeness
    } else {
        0.0
    };
    // v̂_ij = v_ij − (φ/2)(∇v_i + ∇v_j)·x_ij
    let vhat = vij - (grad_i + grad_j) * xij * (0.5 * phi);
    let q = |eta: &Vector<D>, rho: f64, c: f64| {
        let mu = (vhat.dot(eta) / (eta.dot(eta) + prm.eps2)).min(0.0);
        rho * (-prm.c_l * c * mu + prm.c_q * mu * mu)
    };
    (q(&eta_i, rhoi, ci), q(&eta_j, rhoj, cj))
}
