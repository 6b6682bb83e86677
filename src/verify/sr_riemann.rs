//! The exact Riemann solution of special-relativistic hydrodynamics (c = 1) for an ideal gas
//! P = (Γ − 1) n u, with tangential velocity: Martí & Müller (1994, J. Fluid Mech. 258, 317)
//! for the normal flow, Pons, Martí & Müller (2000, J. Fluid Mech. 422, 125) for the
//! tangential velocity. Notation: n rest-frame density, h = 1 + u + P/n the specific
//! enthalpy, W the Lorentz factor of the whole velocity, v^x normal and v^t tangential.
//!
//! Across every wave h W v^t is invariant (Pons et al. 2000), so v^t follows from v^x:
//! (v^t)² = A² (1 − (v^x)²)/(h² + A²) with A = h W v^t.
//! * Shock (state a ahead, pressure P_b behind): the Taub adiabat
//!   h_b² − h_a² = (h_b/n_b + h_a/n_a)(P_b − P_a), the mass flux j² = −[P]/[h/n], the shock
//!   speed V_s = (n_a² W_a² v_a ± |j| √(j² + n_a² W_a² (1 − v_a²)))/(n_a² W_a² + j²) and the
//!   post-shock normal velocity
//!   v_b = (h_a W_a v_a + W_s (P_b − P_a)/j)/(h_a W_a + (P_b − P_a)(W_s v_a/j + 1/(n_a W_a))).
//! * Rarefaction: isentropic (P/n^Γ constant) with dv^x/dP = ± 1/(n h W² c_s √(1 + g)),
//!   g = (v^t)²(ξ² − 1)/(1 − ξ v^x)², ξ = λ± of the state (Eq. 79 of Rosswog (2015)); "+" for
//!   the right wave, "−" for the left.
//!
//! P* is found by bisection on the monotone v^x_L*(P) − v^x_R*(P); a rarefaction is integrated
//! with fourth-order Runge–Kutta in ln P and tabulated for sampling its fan.

/// A rest-frame state.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct SrPrimitive {
    /// Rest-frame density n.
    pub n: f64,
    /// Normal (x) velocity.
    pub vx: f64,
    /// Tangential velocity.
    pub vt: f64,
    pub p: f64,
}

impl SrPrimitive {
    pub fn lorentz(&self) -> f64 {
        1.0 / (1.0 - self.vx * self.vx - self.vt * self.vt).sqrt()
    }
}

/// Steps of a rarefaction's integration (fourth-order: the table's error is far below the
/// particle errors it is compared with).
const FAN_STEPS: usize = 4000;

#[derive(Debug, Clone)]
enum Wave {
    Shock {
        speed: f64,
    },
    /// (ξ, state) along the fan from the outer state to the star state.
    Fan {
        table: Vec<(f64, SrPrimitive)>,
    },
}

#[derive(Debug, Clone)]
pub struct SrRiemann {
    gamma: f64,
    left: SrPrimitive,
    right: SrPrimitive,
    /// The star states left and right of the contact.
    pub star_left: SrPrimitive,
    pub star_right: SrPrimitive,
    left_wave: Wave,
    right_wave: Wave,
}

struct Side {
    gamma: f64,
    /// −1 for the left wave, +1 for the right.
    sign: f64,
}

impl Side {
    fn enthalpy(&self, n: f64, p: f64) -> f64 {
        1.0 + self.gamma / (self.gamma - 1.0) * p / n
    }
    fn sound(&self, n: f64, p: f64) -> f64 {
        let h = self.enthalpy(n, p);
        (self.gamma * p / (n * h)).sqrt()
    }
    /// v^t behind a wave with normal velocity vx, from A = h W v^t of the state ahead.
    fn tangential(&self, a: f64, h: f64, vx: f64) -> f64 {
        if a == 0.0 {
            return 0.0;
        }
        a.signum() * (a * a * (1.0 - vx * vx) / (h * h + a * a)).sqrt()
    }
    /// λ± of a state along x (Rosswog (2015) Eq. 79 with v∥ = v^x, v⊥ = v^t).
    fn eigen(&self, s: &SrPrimitive) -> f64 {
        let c = self.sound(s.n, s.p);
        let (c2, v2) = (c * c, s.vx * s.vx + s.vt * s.vt);
        let root = ((1.0 - v2) * (1.0 - s.vx * s.vx - s.vt * s.vt * c2))
            .max(0.0)
            .sqrt();
        (s.vx * (1.0 - c2) + self.sign * c * root) / (1.0 - v2 * c2)
    }

    /// The state behind a shock of pressure `p` running into `a`, and the shock speed.
    fn shock(&self, a: &SrPrimitive, p: f64) -> (SrPrimitive, f64) {
        let g = self.gamma;
        let ha = self.enthalpy(a.n, a.p);
        let wa = a.lorentz();
        let dp = p - a.p;
        // Taub adiabat as a quadratic in h_b (n_b = Γ P /((Γ − 1)(h_b − 1)))
        let k = (g - 1.0) / (g * p);
        let qa = 1.0 - dp * k;
        let qb = dp * k;
        let qc = -ha * ha - dp * ha / a.n;
        let hb = (-qb + (qb * qb - 4.0 * qa * qc).sqrt()) / (2.0 * qa);
        let nb = g * p / ((g - 1.0) * (hb - 1.0));
        let j2 = -dp / (hb / nb - ha / a.n);
        let j = self.sign * j2.max(0.0).sqrt();
        let m = a.n * a.n * wa * wa;
        let vs =
            (m * a.vx + self.sign * j.abs() * (j2 + m * (1.0 - a.vx * a.vx)).sqrt()) / (m + j2);
        let ws = 1.0 / (1.0 - vs * vs).sqrt();
        let vb =
            (ha * wa * a.vx + ws * dp / j) / (ha * wa + dp * (ws * a.vx / j + 1.0 / (a.n * wa)));
        let vt = self.tangential(ha * wa * a.vt, hb, vb);
        (
            SrPrimitive {
                n: nb,
                vx: vb,
                vt,
                p,
            },
            vs,
        )
    }

    /// dv^x/d ln P along the isentrope through `s0`'s entropy at pressure p.
    fn fan_slope(&self, k_entropy: f64, a: f64, p: f64, vx: f64) -> f64 {
        let n = (p / k_entropy).powf(1.0 / self.gamma);
        let h = self.enthalpy(n, p);
        let c = self.sound(n, p);
        let vt = self.tangential(a, h, vx);
        let w2 = 1.0 / (1.0 - vx * vx - vt * vt);
        let s = SrPrimitive { n, vx, vt, p };
        let xi = self.eigen(&s);
        let gterm = vt * vt * (xi * xi - 1.0) / (1.0 - xi * vx).powi(2);
        // "+" (right wave) with sign = +1, "−" (left) with −1; times P for d/d ln P
        self.sign * p / (n * h * w2 * c * (1.0 + gterm).max(1e-300).sqrt())
    }

    /// The rarefaction from `a` down to pressure `p`: the table of (ξ, state) from a.
    fn fan(&self, a: &SrPrimitive, p: f64, steps: usize) -> Vec<(f64, SrPrimitive)> {
        let k_entropy = a.p / a.n.powf(self.gamma);
        let big_a = self.enthalpy(a.n, a.p) * a.lorentz() * a.vt;
        let state = |lp: f64, vx: f64| {
            let pp = lp.exp();
            let n = (pp / k_entropy).powf(1.0 / self.gamma);
            let vt = self.tangential(big_a, self.enthalpy(n, pp), vx);
            SrPrimitive { n, vx, vt, p: pp }
        };
        let (l0, l1) = (a.p.ln(), p.ln());
        let dl = (l1 - l0) / steps as f64;
        let f = |lp: f64, vx: f64| self.fan_slope(k_entropy, big_a, lp.exp(), vx);
        let mut table = Vec::with_capacity(steps + 1);
        let mut vx = a.vx;
        let mut lp = l0;
        let first = state(lp, vx);
        table.push((self.eigen(&first), first));
        for _ in 0..steps {
            let k1 = f(lp, vx);
            let k2 = f(lp + 0.5 * dl, vx + 0.5 * dl * k1);
            let k3 = f(lp + 0.5 * dl, vx + 0.5 * dl * k2);
            let k4 = f(lp + dl, vx + dl * k3);
            vx += dl * (k1 + 2.0 * k2 + 2.0 * k3 + k4) / 6.0;
            lp += dl;
            let s = state(lp, vx);
            table.push((self.eigen(&s), s));
        }
        table
    }

    /// The state behind the wave (shock if p > P_a, else rarefaction) at pressure p.
    fn behind(&self, a: &SrPrimitive, p: f64, steps: usize) -> (SrPrimitive, Wave) {
        if p > a.p {
            let (s, speed) = self.shock(a, p);
            (s, Wave::Shock { speed })
        } else {
            let table = self.fan(a, p, steps);
            let s = table.last().expect("a fan has a last state").1;
            (s, Wave::Fan { table })
        }
    }
}

impl SrRiemann {
    pub fn new(left: SrPrimitive, right: SrPrimitive, gamma: f64) -> Result<Self, String> {
        for (name, s) in [("left", left), ("right", right)] {
            let v2 = s.vx * s.vx + s.vt * s.vt;
            if !(s.n > 0.0 && s.p > 0.0 && v2 < 1.0 && s.n.is_finite() && s.p.is_finite()) {
                return Err(format!(
                    "{name}: the SR Riemann problem needs n > 0, P > 0 and |v| < 1, got {s:?}"
                ));
            }
        }
        if !(gamma > 1.0 && gamma <= 2.0) {
            return Err(format!(
                "the SR Riemann solver needs 1 < Γ ≤ 2, got {gamma}"
            ));
        }
        let (l, r) = (Side { gamma, sign: -1.0 }, Side { gamma, sign: 1.0 });
        // coarse fans while bracketing P*; the final waves are tabulated finely
        let mismatch = |p: f64| l.behind(&left, p, 400).0.vx - r.behind(&right, p, 400).0.vx;
        // v_L*(P) falls and v_R*(P) rises with P: the difference falls through zero
        let (mut lo, mut hi) = (left.p.min(right.p), left.p.max(right.p));
        while mismatch(lo) < 0.0 {
            lo *= 0.5;
            if lo < 1e-300 {
                return Err("no star pressure above zero (vacuum forms)".into());
            }
        }
        while mismatch(hi) > 0.0 {
            hi *= 2.0;
            if hi > 1e300 {
                return Err("no finite star pressure".into());
            }
        }
        for _ in 0..200 {
            let mid = (lo * hi).sqrt();
            if mismatch(mid) > 0.0 {
                lo = mid;
            } else {
                hi = mid;
            }
            if hi / lo - 1.0 < 1e-15 {
                break;
            }
        }
        let p_star = (lo * hi).sqrt();
        let (star_left, left_wave) = l.behind(&left, p_star, FAN_STEPS);
        let (star_right, right_wave) = r.behind(&right, p_star, FAN_STEPS);
        Ok(Self {
            gamma,
            left,
            right,
            star_left,
            star_right,
            left_wave,
            right_wave,
        })
    }

    /// The speed of the shock on each side, if that wave is a shock.
    pub fn shock_speeds(&self) -> (Option<f64>, Option<f64>) {
        let s = |w: &Wave| match w {
            Wave::Shock { speed } => Some(*speed),
            Wave::Fan { .. } => None,
        };
        (s(&self.left_wave), s(&self.right_wave))
    }

    /// The state at ξ = (x − x0)/t.
    pub fn sample(&self, xi: f64) -> SrPrimitive {
        let contact = 0.5 * (self.star_left.vx + self.star_right.vx);
        let (outer, star, wave, sign) = if xi < contact {
            (&self.left, &self.star_left, &self.left_wave, -1.0)
        } else {
            (&self.right, &self.star_right, &self.right_wave, 1.0)
        };
        // distance from the outer state, positive towards the contact
        let toward = |x: f64| -sign * x;
        match wave {
            Wave::Shock { speed } => {
                if toward(xi) < toward(*speed) {
                    *outer
                } else {
                    *star
                }
            }
            Wave::Fan { table } => {
                let (head, tail) = (table[0].0, table[table.len() - 1].0);
                if toward(xi) <= toward(head) {
                    *outer
                } else if toward(xi) >= toward(tail) {
                    *star
                } else {
                    // ξ runs monotonically through the table: bisect, then interpolate
                    let (mut a, mut b) = (0usize, table.len() - 1);
                    while b - a > 1 {
                        let m = (a + b) / 2;
                        if toward(table[m].0) <= toward(xi) {
                            a = m;
                        } else {
                            b = m;
                        }
                    }
                    let (xa, sa) = table[a];
                    let (xb, sb) = table[b];
                    let w = if xb != xa { (xi - xa) / (xb - xa) } else { 0.0 };
                    let lerp = |u: f64, v: f64| u + (v - u) * w;
                    SrPrimitive {
                        n: lerp(sa.n, sb.n),
                        vx: lerp(sa.vx, sb.vx),
                        vt: lerp(sa.vt, sb.vt),
                        p: lerp(sa.p, sb.p),
                    }
                }
            }
        }
    }

    /// The state at x and time t for an interface at x0.
    pub fn at(&self, x: f64, x0: f64, t: f64) -> SrPrimitive {
        if t <= 0.0 {
            return if x < x0 { self.left } else { self.right };
        }
        self.sample((x - x0) / t)
    }

    pub fn gamma(&self) -> f64 {
        self.gamma
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn state(n: f64, vx: f64, vt: f64, p: f64) -> SrPrimitive {
        SrPrimitive { n, vx, vt, p }
    }

    /// Martí & Müller's Problem 1 (Living Rev. Relativity 6 (2003) 7, Sec. 6.2; also
    /// Rosswog (2015) Riemann I): n 10 / 1, P 13.33 / ~0, Γ = 5/3. Published star state
    /// P* = 1.448, v* = 0.714, n*_L = 2.639, n*_R = 5.070, shock speed 0.828.
    #[test]
    fn marti_mueller_problem_1() {
        let rs = SrRiemann::new(
            state(10.0, 0.0, 0.0, 40.0 / 3.0),
            state(1.0, 0.0, 0.0, 1e-6),
            5.0 / 3.0,
        )
        .unwrap();
        let (sl, sr) = (rs.star_left, rs.star_right);
        println!(
            "Riemann I star state: P* {:.6}, v* {:.6}, n*_L {:.6}, n*_R {:.6} (N*_R = {:.6}), shock {:.6}",
            sl.p,
            sl.vx,
            sl.n,
            sr.n,
            sr.n * sr.lorentz(),
            rs.shock_speeds().1.unwrap()
        );
        assert!((sl.p - 1.448).abs() < 1e-3, "P* {}", sl.p);
        assert!((sl.vx - 0.714).abs() < 1e-3, "v* {}", sl.vx);
        assert!((sl.vx - sr.vx).abs() < 1e-12 && (sl.p - sr.p).abs() < 1e-10 * sl.p);
        assert!((sl.n - 2.639).abs() < 2e-3, "n*_L {}", sl.n);
        assert!((sr.n - 5.070).abs() < 2e-3, "n*_R {}", sr.n);
        let vs = rs.shock_speeds().1.unwrap();
        assert!((vs - 0.828).abs() < 1e-3, "shock {vs}");
    }

    /// Martí & Müller's Problem 2 (same source): n 1 / 1, P 1000 / 0.01, Γ = 5/3. Published
    /// P* = 18.6, v* = 0.960, n*_L = 0.0912, shock speed 0.986. (n*_R = 10.42 here is checked
    /// by the jump conditions below; a strong shock would compress (ΓW* + 1)/(Γ − 1) = 10.43.)
    #[test]
    fn marti_mueller_problem_2() {
        let rs = SrRiemann::new(
            state(1.0, 0.0, 0.0, 1000.0),
            state(1.0, 0.0, 0.0, 0.01),
            5.0 / 3.0,
        )
        .unwrap();
        let (sl, sr) = (rs.star_left, rs.star_right);
        assert!((sl.p - 18.6).abs() < 0.05, "P* {}", sl.p);
        assert!((sl.vx - 0.960).abs() < 1e-3, "v* {}", sl.vx);
        assert!((sl.n - 0.0912).abs() < 5e-4, "n*_L {}", sl.n);
        let w = 1.0 / (1.0 - sr.vx * sr.vx).sqrt();
        let strong = (5.0 / 3.0 * w + 1.0) / (2.0 / 3.0);
        assert!(
            sr.n < strong && sr.n > 0.99 * strong,
            "n*_R {} vs {strong}",
            sr.n
        );
        let vs = rs.shock_speeds().1.unwrap();
        assert!((vs - 0.986).abs() < 1e-3, "shock {vs}");
    }

    /// The shock state satisfies the jump conditions of the SR Euler equations in the
    /// shock's frame, with tangential velocity: [D(v^x − V)] = [S^x(v^x − V) + P] =
    /// [S^t(v^x − V)] = [τ(v^x − V) + P v^x] = 0, D = nW, S = n h W² v, τ = n h W² − P − D.
    #[test]
    fn shocks_conserve_across_the_jump_with_tangential_velocity() {
        let g = 5.0 / 3.0;
        let side = Side {
            gamma: g,
            sign: 1.0,
        };
        for &(vx, vt) in &[(0.0, 0.0), (-0.3, 0.5), (0.5, 0.7), (-0.9, 0.3)] {
            let a = state(1.0, vx, vt, 0.1);
            let (b, vs) = side.shock(&a, 3.0);
            let flux = |s: &SrPrimitive| {
                let w = s.lorentz();
                let h = side.enthalpy(s.n, s.p);
                let d = s.n * w;
                let (sx, st) = (s.n * h * w * w * s.vx, s.n * h * w * w * s.vt);
                let tau = s.n * h * w * w - s.p - d;
                let rel = s.vx - vs;
                [d * rel, sx * rel + s.p, st * rel, tau * rel + s.p * s.vx]
            };
            let (fa, fb) = (flux(&a), flux(&b));
            for k in 0..4 {
                let scale = fa[k].abs().max(fb[k].abs()).max(1.0);
                assert!(
                    (fa[k] - fb[k]).abs() < 1e-10 * scale,
                    "v {vx},{vt}: flux {k} {} vs {}",
                    fa[k],
                    fb[k]
                );
            }
        }
    }

    /// Without tangential velocity a rarefaction keeps the Riemann invariant
    /// ½ ln((1 + v)/(1 − v)) ∓ (2/√(Γ − 1)) artanh(c_s/√(Γ − 1)) (Martí & Müller 1994; the
    /// upper sign for the right wave).
    #[test]
    fn rarefactions_keep_the_riemann_invariant() {
        let g = 5.0 / 3.0;
        let side = Side {
            gamma: g,
            sign: -1.0,
        };
        let a = state(10.0, 0.1, 0.0, 40.0 / 3.0);
        let inv = |s: &SrPrimitive| {
            let c = side.sound(s.n, s.p);
            0.5 * ((1.0 + s.vx) / (1.0 - s.vx)).ln()
                - side.sign * 2.0 / (g - 1.0).sqrt() * (c / (g - 1.0).sqrt()).atanh()
        };
        let table = side.fan(&a, 1.0, 4000);
        let end = table.last().unwrap().1;
        assert!(
            (inv(&end) - inv(&a)).abs() < 1e-12,
            "{} vs {}",
            inv(&end),
            inv(&a)
        );
        // the fan widens: ξ grows from head to tail for a left wave
        assert!(table.windows(2).all(|w| w[1].0 > w[0].0));
    }

    /// Rosswog (2015) Riemann II (colliding streams at ±0.9, n = 1, u = 2.29e-5): two shocks,
    /// the gas at rest between them.
    #[test]
    fn colliding_streams_stop_between_two_shocks() {
        let g = 5.0 / 3.0;
        let p = (g - 1.0) * 2.29e-5;
        let rs = SrRiemann::new(state(1.0, 0.9, 0.0, p), state(1.0, -0.9, 0.0, p), g).unwrap();
        let extreme =
            SrRiemann::new(state(1.0, 0.9995, 0.0, p), state(1.0, -0.9995, 0.0, p), g).unwrap();
        for (v, r) in [(0.9, &rs), (0.9995, &extreme)] {
            let s = r.star_right;
            println!(
                "Riemann II at v = ±{v}: n* = N* = {:.6}, P* {:.6e}, u* {:.6e}, shock speed {:.6}",
                s.n,
                s.p,
                s.p / ((g - 1.0) * s.n),
                r.shock_speeds().1.unwrap()
            );
        }
        assert!(rs.star_left.vx.abs() < 1e-10);
        let (l, r) = rs.shock_speeds();
        assert!((l.unwrap() + r.unwrap()).abs() < 1e-10 && r.unwrap() > 0.0);
        // a strong relativistic shock: compression (Γ W + 1)/(Γ − 1) ≈ 7.2 in the rest frame
        let w = 1.0 / (1.0 - 0.81f64).sqrt();
        let expect = (g * w + 1.0) / (g - 1.0);
        assert!(
            (rs.star_left.n / expect - 1.0).abs() < 1e-3,
            "{} vs {expect}",
            rs.star_left.n
        );
    }
}
