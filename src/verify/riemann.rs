//! Exact solution of the Riemann problem for an ideal gas (Toro, "Riemann Solvers and
//! Numerical Methods for Fluid Dynamics", ch. 4), including vacuum states and vacuum
//! generation (§4.6).

/// Primitive state (density, normal velocity, pressure).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Primitive {
    pub rho: f64,
    pub u: f64,
    pub p: f64,
}

#[derive(Debug, Clone, Copy)]
pub struct ExactRiemann {
    pub left: Primitive,
    pub right: Primitive,
    pub gamma: f64,
    /// Star-region pressure and velocity (0 and NaN when the solution contains vacuum).
    pub p_star: f64,
    pub u_star: f64,
    vacuum: bool,
}

impl ExactRiemann {
    pub fn new(left: Primitive, right: Primitive, gamma: f64) -> Result<Self, String> {
        if !(gamma > 1.0 && gamma.is_finite()) {
            return Err(format!("gamma: must be > 1, got {gamma}"));
        }
        for (name, s) in [("left", left), ("right", right)] {
            if !(s.rho >= 0.0
                && s.p >= 0.0
                && s.u.is_finite()
                && s.rho.is_finite()
                && s.p.is_finite())
            {
                return Err(format!(
                    "{name} state: need ρ ≥ 0, P ≥ 0 and finite values, got {s:?}"
                ));
            }
        }
        let mut rs = Self {
            left,
            right,
            gamma,
            p_star: 0.0,
            u_star: f64::NAN,
            vacuum: false,
        };
        let c = |s: Primitive| {
            if s.rho > 0.0 {
                (gamma * s.p / s.rho).sqrt()
            } else {
                0.0
            }
        };
        let (cl, cr) = (c(left), c(right));
        let g1 = gamma - 1.0;
        if left.rho == 0.0 || right.rho == 0.0 || 2.0 * (cl + cr) / g1 <= right.u - left.u {
            rs.vacuum = true;
            return Ok(rs);
        }
        // Newton–Raphson on f(p) = f_L(p) + f_R(p) + Δu (Toro §4.3), PVRS initial guess.
        let du = right.u - left.u;
        let ppv = 0.5 * (left.p + right.p) - 0.125 * du * (left.rho + right.rho) * (cl + cr);
        let mut p = ppv.max(1e-12 * (left.p + right.p)).max(1e-300);
        for _ in 0..200 {
            let (fl, dfl) = rs.f_k(p, left, cl);
            let (fr, dfr) = rs.f_k(p, right, cr);
            let f = fl + fr + du;
            let mut pn = p - f / (dfl + dfr);
            if pn <= 0.0 {
                pn = 0.1 * p;
            }
            let change = 2.0 * (pn - p).abs() / (pn + p);
            p = pn;
            if change < 1e-15 {
                break;
            }
        }
        let (fl, _) = rs.f_k(p, left, cl);
        let (fr, _) = rs.f_k(p, right, cr);
        rs.p_star = p;
        rs.u_star = 0.5 * (left.u + right.u) + 0.5 * (fr - fl);
        Ok(rs)
    }

    /// Toro eq. 4.6–4.7: f_K and its derivative.
    fn f_k(&self, p: f64, s: Primitive, c: f64) -> (f64, f64) {
        let g = self.gamma;
        if p > s.p {
            let a = 2.0 / ((g + 1.0) * s.rho);
            let b = (g - 1.0) / (g + 1.0) * s.p;
            let q = (a / (p + b)).sqrt();
            ((p - s.p) * q, q * (1.0 - 0.5 * (p - s.p) / (b + p)))
        } else {
            let e = (g - 1.0) / (2.0 * g);
            let r = (p / s.p).powf(e);
            // f' = (1/(ρ c)) (p/p_K)^{−(γ+1)/(2γ)} = r/(ρ c)·(p_K/p)
            (2.0 * c / (g - 1.0) * (r - 1.0), r / (s.rho * c) * (s.p / p))
        }
    }

    /// The solution at similarity coordinate ξ = (x − x0)/t.
    pub fn sample(&self, xi: f64) -> Primitive {
        let g = self.gamma;
        let (l, r) = (self.left, self.right);
        let c = |s: Primitive| {
            if s.rho > 0.0 {
                (g * s.p / s.rho).sqrt()
            } else {
                0.0
            }
        };
        let (cl, cr) = (c(l), c(r));
        let g1 = g - 1.0;
        let gp = g + 1.0;
        // Left rarefaction fan state at ξ (Toro 4.56).
        let fan_l = |xi: f64| {
            let f = 2.0 / gp + g1 / (gp * cl) * (l.u - xi);
            Primitive {
                rho: l.rho * f.powf(2.0 / g1),
                u: 2.0 / gp * (cl + 0.5 * g1 * l.u + xi),
                p: l.p * f.powf(2.0 * g / g1),
            }
        };
        let fan_r = |xi: f64| {
            let f = 2.0 / gp - g1 / (gp * cr) * (r.u - xi);
            Primitive {
                rho: r.rho * f.powf(2.0 / g1),
                u: 2.0 / gp * (-cr + 0.5 * g1 * r.u + xi),
                p: r.p * f.powf(2.0 * g / g1),
            }
        };
        let vac = Primitive {
            rho: 0.0,
            u: 0.0,
            p: 0.0,
        };
        if self.vacuum {
            // Toro §4.6: right vacuum, left vacuum, or generated vacuum.
            if r.rho == 0.0 && l.rho == 0.0 {
                return vac;
            }
            if r.rho == 0.0 {
                let s_head = l.u - cl;
                let s_tail = l.u + 2.0 * cl / g1;
                return if xi <= s_head {
                    l
                } else if xi < s_tail {
                    fan_l(xi)
                } else {
                    vac
                };
            }
            if l.rho == 0.0 {
                let s_head = r.u + cr;
                let s_tail = r.u - 2.0 * cr / g1;
                return if xi >= s_head {
                    r
                } else if xi > s_tail {
                    fan_r(xi)
                } else {
                    vac
                };
            }
            let sl_tail = l.u + 2.0 * cl / g1;
            let sr_tail = r.u - 2.0 * cr / g1;
            return if xi <= l.u - cl {
                l
            } else if xi < sl_tail {
                fan_l(xi)
            } else if xi <= sr_tail {
                vac
            } else if xi < r.u + cr {
                fan_r(xi)
            } else {
                r
            };
        }
        let (ps, us) = (self.p_star, self.u_star);
        if xi <= us {
            if ps > l.p {
                let s = l.u - cl * ((gp / (2.0 * g)) * ps / l.p + g1 / (2.0 * g)).sqrt();
                if xi <= s {
                    l
                } else {
                    let rho = l.rho * (ps / l.p + g1 / gp) / (g1 / gp * ps / l.p + 1.0);
                    Primitive { rho, u: us, p: ps }
                }
            } else {
                let head = l.u - cl;
                let cs = cl * (ps / l.p).powf(g1 / (2.0 * g));
                let tail = us - cs;
                if xi <= head {
                    l
                } else if xi >= tail {
                    Primitive {
                        rho: l.rho * (ps / l.p).powf(1.0 / g),
                        u: us,
                        p: ps,
                    }
                } else {
                    fan_l(xi)
                }
            }
        } else if ps > r.p {
            let s = r.u + cr * ((gp / (2.0 * g)) * ps / r.p + g1 / (2.0 * g)).sqrt();
            if xi >= s {
                r
            } else {
                let rho = r.rho * (ps / r.p + g1 / gp) / (g1 / gp * ps / r.p + 1.0);
                Primitive { rho, u: us, p: ps }
            }
        } else {
            let head = r.u + cr;
            let cs = cr * (ps / r.p).powf(g1 / (2.0 * g));
            let tail = us + cs;
            if xi >= head {
                r
            } else if xi <= tail {
                Primitive {
                    rho: r.rho * (ps / r.p).powf(1.0 / g),
                    u: us,
                    p: ps,
                }
            } else {
                fan_r(xi)
            }
        }
    }

    /// Solution at position x and time t for an interface initially at x0.
    pub fn at(&self, x: f64, x0: f64, t: f64) -> Primitive {
        if t <= 0.0 {
            return if x < x0 { self.left } else { self.right };
        }
        self.sample((x - x0) / t)
    }
}
