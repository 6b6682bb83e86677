//! The Sedov–Taylor point blast (Frontiere, Raskin & Owen (2017) §4.3.2): the self-similar solution, integrated
//! from the strong-shock jump inwards.
//!
//! With r_s = β (E t²/ρ0)^{1/(ν+2)}, δ = 2/(ν+2), ξ = r/r_s and v = ṙ_s f(ξ), ρ = ρ0 g(ξ),
//! P = ρ0 ṙ_s² p(ξ), the Euler equations (planar ν = 1, cylindrical 2, spherical 3) become
//!
//!   (f−ξ) g' + g f' = −(ν−1) g f/ξ                         (mass)
//!   (f−ξ) f' + p'/g = (1−δ)/δ · f                          (momentum)
//!   (f−ξ)(p'/p − γ g'/g) = 2(1−δ)/δ                        (entropy along paths)
//!
//! with f = p = 2/(γ+1), g = (γ+1)/(γ−1) behind the shock (ξ = 1). The blast energy
//! E = ρ0 δ² r_s^{ν+2} t⁻² Ω_ν ∫₀¹ (½ g f² + p/(γ−1)) ξ^{ν−1} dξ fixes β; Ω_ν = 2, 2π, 4π
//! (the planar E counts both half-spaces).

use nalgebra::{Matrix3, Vector3};

/// The similarity profile for one γ and dimension, tabulated on ξ ∈ [0, 1].
#[derive(Debug, Clone)]
pub struct Sedov {
    pub gamma: f64,
    pub dim: usize,
    /// r_s = beta (E t²/ρ0)^{1/(ν+2)}
    pub beta: f64,
    xi: Vec<f64>,
    /// (f, g, p) at each ξ, ascending ξ.
    fgp: Vec<[f64; 3]>,
}

/// One shock state for a solution value.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct SedovState {
    pub rho: f64,
    pub v: f64,
    pub p: f64,
}

const STEPS: usize = 20_000;

impl Sedov {
    pub fn new(gamma: f64, dim: usize) -> Self {
        assert!((1..=3).contains(&dim) && gamma > 1.0);
        let nu = dim as f64;
        let delta = 2.0 / (nu + 2.0);
        let rhs = |xi: f64, y: &Vector3<f64>| -> Vector3<f64> {
            let (f, g, p) = (y[0], y[1], y[2]);
            let d = f - xi;
            let m = Matrix3::new(g, d, 0.0, d, 0.0, 1.0 / g, 0.0, -gamma * d / g, d / p);
            let b = Vector3::new(
                -(nu - 1.0) * g * f / xi,
                (1.0 - delta) / delta * f,
                2.0 * (1.0 - delta) / delta,
            );
            m.lu().solve(&b).unwrap_or_else(Vector3::zeros)
        };
        // RK4 from ξ = 1 inwards to ξ = 1e-6; the integrand of the energy is smooth.
        let xi_end = 1e-6;
        let hstep = -(1.0 - xi_end) / STEPS as f64;
        let mut y = Vector3::new(
            2.0 / (gamma + 1.0),
            (gamma + 1.0) / (gamma - 1.0),
            2.0 / (gamma + 1.0),
        );
        let mut xi = 1.0;
        let mut xs = vec![xi];
        let mut ys = vec![[y[0], y[1], y[2]]];
        for _ in 0..STEPS {
            let k1 = rhs(xi, &y);
            let k2 = rhs(xi + 0.5 * hstep, &(y + k1 * (0.5 * hstep)));
            let k3 = rhs(xi + 0.5 * hstep, &(y + k2 * (0.5 * hstep)));
            let k4 = rhs(xi + hstep, &(y + k3 * hstep));
            y += (k1 + k2 * 2.0 + k3 * 2.0 + k4) * (hstep / 6.0);
            y[1] = y[1].max(0.0);
            xi += hstep;
            xs.push(xi);
            ys.push([y[0], y[1], y[2]]);
        }
        xs.reverse();
        ys.reverse();
        // energy integral by the trapezoidal rule (the centre ξ < 1e-6 adds nothing visible)
        let integrand = |k: usize| {
            let [f, g, p] = ys[k];
            (0.5 * g * f * f + p / (gamma - 1.0)) * xs[k].powi(dim as i32 - 1)
        };
        let mut integral = 0.0;
        for k in 1..xs.len() {
            integral += 0.5 * (integrand(k) + integrand(k - 1)) * (xs[k] - xs[k - 1]);
        }
        let omega = match dim {
            1 => 2.0,
            2 => 2.0 * std::f64::consts::PI,
            _ => 4.0 * std::f64::consts::PI,
        };
        let beta = (delta * delta * omega * integral).powf(-1.0 / (nu + 2.0));
        Self {
            gamma,
            dim,
            beta,
            xi: xs,
            fgp: ys,
        }
    }

    /// Shock radius at time t for blast energy E (the whole-space energy) and density ρ0.
    pub fn shock_radius(&self, energy: f64, rho0: f64, t: f64) -> f64 {
        self.beta * (energy * t * t / rho0).powf(1.0 / (self.dim as f64 + 2.0))
    }

    /// Time at which the shock reaches radius r.
    pub fn time_of_radius(&self, energy: f64, rho0: f64, r: f64) -> f64 {
        ((r / self.beta).powf(self.dim as f64 + 2.0) * rho0 / energy).sqrt()
    }

    /// ρ, radial v and P at radius r and time t > 0 (cold, still gas ahead of the shock).
    pub fn at(&self, r: f64, energy: f64, rho0: f64, t: f64) -> SedovState {
        let rs = self.shock_radius(energy, rho0, t);
        let xi = r / rs;
        if xi >= 1.0 {
            return SedovState {
                rho: rho0,
                v: 0.0,
                p: 0.0,
            };
        }
        let k = self
            .xi
            .partition_point(|&x| x < xi)
            .clamp(1, self.xi.len() - 1);
        let (x0, x1) = (self.xi[k - 1], self.xi[k]);
        let s = ((xi - x0) / (x1 - x0)).clamp(0.0, 1.0);
        let lerp = |c: usize| self.fgp[k - 1][c] * (1.0 - s) + self.fgp[k][c] * s;
        let rs_dot = 2.0 / (self.dim as f64 + 2.0) * rs / t;
        SedovState {
            rho: rho0 * lerp(1),
            v: rs_dot * lerp(0),
            p: rho0 * rs_dot * rs_dot * lerp(2),
        }
    }
}

#[cfg(test)]
mod tests {
    use super::Sedov;

    /// Reference: ExactPack 1.7.11 (LANL) Sedov solutions, E = 1, ρ0 = 1, t = 1, sampled every
    /// 5e-4 in r (the shock lies within one sample of the value quoted).
    #[test]
    fn matches_exactpack() {
        // (dim, γ, r_s from the last shocked sample, (r, ρ, v, P) at about r_s/2). ExactPack's
        // planar energy counts one half-space: its E = 1 is our whole-line E = 2.
        let cases = [
            (
                1,
                5.0 / 3.0,
                1.4915,
                (0.74550062725, 0.64478971072, 0.30626241913, 0.28616836017),
            ),
            (
                1,
                1.4,
                1.2290,
                (0.61450069275, 0.40313356825, 0.29515581925, 0.22650757027),
            ),
            (
                2,
                5.0 / 3.0,
                1.1535,
                (0.57650071175, 0.18925166149, 0.17453224088, 0.082877641932),
            ),
            (
                3,
                5.0 / 3.0,
                1.1515,
                (0.57550071225, 0.061082122196, 0.13855616237, 0.049300745286),
            ),
            (
                2,
                1.4,
                1.0045,
                (0.502000749, 0.061706229851, 0.17954352623, 0.078826674391),
            ),
            (
                3,
                1.4,
                1.0330,
                (0.51650074175, 0.010327969195, 0.14760797071, 0.052034315928),
            ),
        ];
        for (dim, gamma, rs, (r, rho, v, p)) in cases {
            let s = Sedov::new(gamma, dim);
            let e = if dim == 1 { 2.0 } else { 1.0 };
            let mine = s.shock_radius(e, 1.0, 1.0);
            // Measured: within 5e-4 of ExactPack's last shocked sample (γ = 1.4 in 2D: our
            // β = 1.00402, ExactPack's shock lies in [1.0045, 1.0050)).
            assert!(
                (mine - rs).abs() < 1e-3 * rs,
                "dim {dim} γ {gamma}: r_s {mine} vs ExactPack {rs}"
            );
            let st = s.at(r * mine / rs, e, 1.0, 1.0);
            for (name, a, b) in [("rho", st.rho, rho), ("v", st.v, v), ("p", st.p, p)] {
                assert!(
                    (a - b).abs() < 5e-3 * b,
                    "dim {dim} γ {gamma} {name}: {a} vs {b}"
                );
            }
        }
    }
}
