//! Special-relativistic state of one particle (Rosswog (2015) Sec. 6, c = 1, energies per
//! baryon in units of m0 c²): the conserved variables from the primitive ones (Eqs. 54, 57,
//! 59) and back (the primitive recovery of Sec. 6.4, Eqs. 97–99), the sound speed (Eq. 63)
//! and the extreme eigenvalues of the Euler equations (Eq. 79).

/// Rest-frame primitive state of one particle for the polytrope P = (Γ − 1) n u (Eq. 62).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Primitive {
    /// Pressure.
    pub p: f64,
    /// Lorentz factor γ.
    pub lorentz: f64,
    /// Rest-frame baryon density n = N/γ (Eq. 46).
    pub n: f64,
    /// Specific internal energy u (Eq. 98).
    pub u: f64,
    /// v = S/(ε + P/N) as a factor on S (Eq. 97): v = `v_over_s` · S.
    pub v_over_s: f64,
}

impl Primitive {
    /// Specific relativistic enthalpy E = 1 + u + P/n (Eq. 59).
    pub fn enthalpy(&self) -> f64 {
        1.0 + self.u + self.p / self.n
    }
}

/// The outcome of one recovery: the state, the Newton–Raphson iterations it took, and
/// whether the thermal energy had to be floored (a fallback, counted in the run summary).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Recovered {
    pub prim: Primitive,
    pub iterations: u32,
    pub floored: bool,
}

/// Specific internal energy of the cold state a recovery falls back to when Eq. 99 has no
/// root with u ≥ 0 (the kinetic energy alone exceeds ε): S is kept, u = `U_FLOOR_ABS`.
pub const U_FLOOR_ABS: f64 = 1e-14;

/// Largest Newton–Raphson iterations before the bracket's bisection decides.
const MAX_ITERATIONS: u32 = 200;

/// The computing-frame state of a rest-frame one (n, u, |v|²) (Eqs. 46, 54, 57, 59, 62):
/// the factor γE of S = γE v, the canonical energy ε = γE − P/N, the Lorentz factor γ, the
/// pressure P and the enthalpy E.
pub fn conserved(gamma_eos: f64, n: f64, u: f64, v2: f64) -> Conserved {
    let lorentz = 1.0 / (1.0 - v2).sqrt();
    let p = (gamma_eos - 1.0) * n * u;
    let enthalpy = 1.0 + u + p / n;
    Conserved {
        s_over_v: lorentz * enthalpy,
        eps: lorentz * enthalpy - p / (lorentz * n),
        lorentz,
        p,
        enthalpy,
    }
}

/// What [`conserved`] returns.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Conserved {
    /// γE: S = γE v.
    pub s_over_v: f64,
    pub eps: f64,
    pub lorentz: f64,
    pub p: f64,
    pub enthalpy: f64,
}

/// Relativistic sound speed c_s² = (Γ − 1)(E − 1)/E (Eq. 63).
pub fn sound_speed(gamma_eos: f64, enthalpy: f64) -> f64 {
    ((gamma_eos - 1.0) * (enthalpy - 1.0) / enthalpy)
        .max(0.0)
        .sqrt()
}

/// The largest of max(0, λ⁺) and max(0, −λ⁻) (Eqs. 78–79): the extreme eigenvalues of the SR
/// Euler equations along a unit direction ê, with v∥ = v·ê and v⊥² = v² − v∥² (our reading
/// of the paper's undefined v∥, v⊥: along and across the pair axis).
pub fn signal_speed(v_par: f64, v2: f64, c: f64) -> f64 {
    let c2 = c * c;
    let v_perp2 = (v2 - v_par * v_par).max(0.0);
    let root = ((1.0 - v2) * (1.0 - v_par * v_par - v_perp2 * c2))
        .max(0.0)
        .sqrt();
    let den = 1.0 - v2 * c2;
    let plus = (v_par * (1.0 - c2) + c * root) / den;
    let minus = (v_par * (1.0 - c2) - c * root) / den;
    plus.max(0.0).max(-minus)
}

/// The longest step for which one forward-Euler step of a particle's conserved state per
/// baryon, (ε, S) → (ε + t ε̇, S + t Ṡ), keeps at least half of its margin to the edge of the
/// states a recovery can invert (our addition: the paper's step rule, Sec. 6.5, has no such
/// term; see below). ∞ when the step moves the state away from that edge.
///
/// The margin: for Γ ≤ 2 every physical state has ε² − |S|² = E(1 + (2 − Γ)u) + (P/N)² ≥ 1
/// (from Eqs. 54, 57, 59 with P = (Γ − 1) n u), and {ε ≥ √(1 + |S|²)} is convex, so
/// q = ε² − |S|² − 1 ≥ 0 is the room left before a recovery must floor u (the cold
/// fallback). A state already past it (floored) keeps the hard edge instead, ε > |S|, with
/// margin q + 1: beyond that no velocity below c exists and the run stops. SSP-RK3's stages
/// are convex combinations of forward-Euler steps of the same length, so a step that keeps
/// each Euler step inside the convex set keeps the stages inside it too (to the extent the
/// first stage's derivatives speak for the later ones).
///
/// Why it is needed, measured on the extreme Riemann II (`models/verify/sr-riemann2.toml`
/// at v = ±0.9995, 10K particles on [−1, 1], F1 with K_min = 1): a cold stream (u = 2.3e-5,
/// so q ≈ 5e-5) decelerating by ΔS ≈ 1.6 per step loses ΔS²/γ² ≈ 2.6e-3 of q to the Euler
/// step's curvature alone. With the force-step factor 0.25 the run floored u in the
/// precursor, went noisy and stopped at t = 0.19 with |S| ≥ ε; with 0.2 it ran with 3074
/// cold-state fallbacks; with 0.15 it ran clean.
///
/// Solved exactly: g(t) = m/2 + 2Bt + Ct² ≥ 0 with B = ε ε̇ − S·Ṡ and C = ε̇² − |Ṡ|²; the
/// answer is g's smallest positive root, A/(−B + √(B² − AC)) with A = m/2, in the form
/// that does not cancel.
pub fn light_cone_step(eps: f64, s2: f64, eps_dot: f64, s_dot_sdot: f64, sdot2: f64) -> f64 {
    let q = eps * eps - s2 - 1.0;
    let margin = if q > 0.0 { q } else { q + 1.0 };
    if margin.is_nan() || margin <= 0.0 || !eps.is_finite() {
        // nothing left to keep: the recovery reports the state
        return f64::INFINITY;
    }
    let a = 0.5 * margin;
    let b = eps * eps_dot - s_dot_sdot;
    let c = eps_dot * eps_dot - sdot2;
    let disc = b * b - a * c;
    if disc.is_nan() || disc < 0.0 {
        return f64::INFINITY;
    }
    let den = -b + disc.sqrt();
    if den > 0.0 {
        a / den
    } else {
        f64::INFINITY
    }
}

/// Why a state has no primitive counterpart.
#[derive(Debug, Clone, PartialEq)]
pub struct RecoveryError(pub String);

/// Solve f(P) = P − (Γ − 1) n(P) u(P) = 0 (Eq. 99) for the pressure, given |S|, ε and the
/// computing-frame density N, then back-substitute (Eqs. 97, 46, 98).
///
/// The root is bracketed: v < 1 needs ε + P/N > |S|, so P > P_lo = N(|S| − ε)⁺; and because
/// u(P) ≤ ε − 1 and n ≤ N, f(P) ≥ P − (Γ − 1) N (ε − 1) > 0 beyond P_hi = (Γ − 1) N (ε − 1).
/// Newton–Raphson steps (with the analytic f'(P) below) that leave the
/// bracket are replaced by bisection, so the iteration always converges. When f > 0 already
/// at P_lo, the state's kinetic energy exceeds ε (u would be negative): the recovery then
/// takes the cold state u = [`U_FLOOR_ABS`] at the velocity S/(ε + P/N) that keeps S and
/// reports it as floored (our decision; the paper does not say what its code does).
///
/// `guess` (the particle's pressure at its previous recovery) starts the iteration when it lies
/// inside the bracket: between density passes and RK stages P changes little, so Newton then
/// needs a few steps (measured on models/sr-riemann1d.toml: 2.0 iterations per recovery on
/// average and 5 at most, against 8.2 and 52 from the Newtonian-like start without it).
pub fn recover(
    gamma_eos: f64,
    s: f64,
    eps: f64,
    big_n: f64,
    guess: Option<f64>,
) -> Result<Recovered, RecoveryError> {
    if !(s.is_finite() && eps.is_finite() && big_n.is_finite() && big_n > 0.0 && s >= 0.0) {
        return Err(RecoveryError(format!(
            "no finite state: |S| = {s:e}, epsilon = {eps:e}, N = {big_n:e}"
        )));
    }
    if eps <= 0.0 {
        return Err(RecoveryError(format!(
            "canonical energy epsilon = {eps:e} is not positive (|S| = {s:e}, N = {big_n:e})"
        )));
    }
    let g1 = gamma_eos - 1.0;
    let prim_at = |p: f64| -> Option<Primitive> {
        let w = eps + p / big_n;
        let v = s / w;
        if v.is_nan() || v >= 1.0 {
            return None;
        }
        let lorentz = 1.0 / (1.0 - v * v).sqrt();
        let n = big_n / lorentz;
        let u = eps / lorentz + p * (1.0 - lorentz * lorentz) / (lorentz * big_n) - 1.0;
        Some(Primitive {
            p,
            lorentz,
            n,
            u,
            v_over_s: 1.0 / w,
        })
    };
    let f = |q: &Primitive| q.p - g1 * q.n * q.u;
    // f'(P): with w = ε + P/N, v = S/w, dγ/dP = −γ³ v²/(N w); n = N/γ; u as in Eq. 98.
    let df = |q: &Primitive| {
        let w = eps + q.p / big_n;
        let v = s / w;
        let g = q.lorentz;
        let dg = -g * g * g * v * v / (big_n * w);
        let dn = -big_n / (g * g) * dg;
        let du = -eps / (g * g) * dg
            + (1.0 - g * g) / (g * big_n)
            + q.p / big_n * (-(1.0 + g * g) / (g * g)) * dg;
        1.0 - g1 * (dn * q.u + q.n * du)
    };
    let mut lo = (big_n * (s - eps)).max(0.0);
    // just above the bound where v = 1 (there γ is infinite)
    if lo > 0.0 {
        lo *= 1.0 + 1e-15;
        lo += f64::MIN_POSITIVE;
    }
    let mut hi = g1 * big_n * (eps - 1.0).max(0.0) * (1.0 + 1e-12) + 1e-300;
    if hi <= lo {
        hi = lo * 2.0 + 1e-300;
    }
    let q_lo = prim_at(lo).filter(|q| q.lorentz.is_finite());
    let floored_state = |lo: f64| -> Result<Recovered, RecoveryError> {
        // the cold state: u = floor; P = (Γ − 1) n u self-consistently by a fixed point
        let mut p = lo;
        for _ in 0..100 {
            let w = eps + p / big_n;
            let v = s / w;
            if v.is_nan() || v >= 1.0 {
                break;
            }
            let lorentz = 1.0 / (1.0 - v * v).sqrt();
            let next = g1 * (big_n / lorentz) * U_FLOOR_ABS;
            if (next - p).abs() <= 1e-15 * next.max(1e-300) {
                p = next;
                break;
            }
            p = next;
        }
        let w = eps + p / big_n;
        let v = s / w;
        if v.is_nan() || v >= 1.0 {
            return Err(RecoveryError(format!(
                "|S| = {s:e} reaches or exceeds epsilon + P/N = {w:e}: no velocity below c (N = {big_n:e})"
            )));
        }
        let lorentz = 1.0 / (1.0 - v * v).sqrt();
        Ok(Recovered {
            prim: Primitive {
                p,
                lorentz,
                n: big_n / lorentz,
                u: U_FLOOR_ABS,
                v_over_s: 1.0 / w,
            },
            iterations: 0,
            floored: true,
        })
    };
    // the root found after `it` iterations (a negative u there: the cold state instead)
    let root = |q: Primitive, it: u32, lo: f64| -> Result<Recovered, RecoveryError> {
        if q.u < 0.0 {
            return floored_state(lo);
        }
        Ok(Recovered {
            prim: q,
            iterations: it,
            floored: false,
        })
    };
    match q_lo {
        Some(q) if f(&q) <= 0.0 => {}
        // no root above P_lo: the thermal energy would be negative
        _ => return floored_state(lo),
    }
    let mut p = 0.5 * (lo + hi);
    // the caller's guess, else the Newtonian-like P from u = ε/γ − 1 at P = lo
    match guess {
        Some(g) if g > lo && g < hi => p = g,
        _ => {
            if let Some(q) = q_lo {
                let start = g1 * q.n * q.u.max(0.0);
                if start > lo && start < hi {
                    p = start;
                }
            }
        }
    }
    for it in 1..=MAX_ITERATIONS {
        let Some(q) = prim_at(p) else {
            lo = p;
            p = 0.5 * (lo + hi);
            continue;
        };
        let fp = f(&q);
        // f's own round-off: γ comes from 1 − v² (relative error ~ γ² ulp), and u = ε/γ +
        // P(1 − γ²)/(γN) − 1 cancels terms of order ε/γ and 1, so |f| below a few ulps of
        // P + (Γ − 1) n ((ε/γ + |P(1 − γ²)/(γN)|)(1 + γ²) + 1) is zero
        let g = q.lorentz;
        let terms = (eps / g + (q.p * (1.0 - g * g) / (g * big_n)).abs()) * (1.0 + g * g) + 1.0;
        let noise = 8.0 * f64::EPSILON * (q.p + g1 * q.n * terms);
        if fp.abs() <= noise {
            return root(q, it, lo);
        }
        if fp > 0.0 {
            hi = p;
        } else {
            lo = p;
        }
        let d = df(&q);
        let mut next = p - fp / d;
        if !(next > lo && next < hi && d.is_finite() && d > 0.0) {
            next = 0.5 * (lo + hi);
        }
        let converged = (next - p).abs() <= (1e-14 * next.abs()).max(2.0 * noise / d.max(1e-300))
            || hi - lo <= 1e-15 * hi;
        p = next;
        if converged {
            let q = prim_at(p).ok_or_else(|| {
                RecoveryError(format!("no velocity below c at the root P = {p:e}"))
            })?;
            return root(q, it, lo);
        }
    }
    Err(RecoveryError(format!(
        "no convergence in {MAX_ITERATIONS} iterations (|S| = {s:e}, epsilon = {eps:e}, N = {big_n:e})"
    )))
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Primitive → conserved → primitive returns the state, from the Newtonian limit to
    /// γ = 70.7 (the paper's Advection I) and from cold to hot (P/n from 1e-8 to 1e3).
    #[test]
    fn recovery_inverts_the_conserved_variables() {
        let g = 5.0 / 3.0;
        for &v in &[0.0, 1e-4, 0.3, 0.9, 0.9995, 0.9999] {
            for &n in &[0.1, 1.0, 10.0] {
                for &p_over_n in &[1e-8, 1e-3, 1.0, 1e3] {
                    let u = p_over_n / (g - 1.0);
                    let c = conserved(g, n, u, v * v);
                    let (s, eps, lorentz) = (c.s_over_v * v, c.eps, c.lorentz);
                    let big_n = lorentz * n;
                    let p = (g - 1.0) * n * u;
                    let r = recover(g, s, eps, big_n, None).unwrap();
                    // a warm start 0.1 % off, as from the previous stage
                    let warm = recover(g, s, eps, big_n, Some(p * 1.001)).unwrap();
                    assert!(!r.floored, "v {v} n {n} P/n {p_over_n}");
                    let q = r.prim;
                    // u is ε/γ − 1 + …: a cold state loses the digits of 1 in that
                    // difference, so P is as exact as γ² ε_mach / (P/n) allows (the factor
                    // 8 covers the worst cold case of this grid); hot states at γ = 70.7
                    // measured 1.1e-12, under the 1e-10
                    let tol_p = 1e-10 + 8.0 * f64::EPSILON * lorentz * lorentz / p_over_n;
                    assert!(
                        (q.p - p).abs() <= tol_p * p,
                        "P {} vs {p} (v {v} n {n} P/n {p_over_n})",
                        q.p
                    );
                    assert!(
                        (warm.prim.p - p).abs() <= tol_p * p,
                        "warm P {}",
                        warm.prim.p
                    );
                    // measured at most 10 from the warm start (γ = 31.6, P/n = 1e-3), 2 on
                    // average in the 1D Riemann I run
                    assert!(
                        warm.iterations <= 16,
                        "{} warm iterations (v {v} n {n} P/n {p_over_n})",
                        warm.iterations
                    );
                    assert!((q.n - n).abs() <= 1e-10 * n, "n {} vs {n}", q.n);
                    assert!((q.lorentz - lorentz).abs() <= 1e-10 * lorentz);
                    assert!(
                        (q.v_over_s * s - v).abs() <= 1e-10,
                        "v {} vs {v}",
                        q.v_over_s * s
                    );
                    assert!(r.iterations < 60, "{} iterations", r.iterations);
                }
            }
        }
    }

    /// A state from the extreme colliding streams (v = 0.9995, γ = 31.6) met at a stage: f
    /// carries γ² ulps of round-off there, which a fixed relative stop never met (200
    /// iterations, no convergence) before the stop learnt f's noise.
    #[test]
    fn ultra_relativistic_states_converge() {
        let (s, eps, n) = (
            3.1631532738268035e1,
            3.1653936603436993e1,
            3.16508418667666e1,
        );
        for guess in [None, Some(1e-5), Some(0.1), Some(10.0), Some(1e3)] {
            let r = recover(5.0 / 3.0, s, eps, n, guess).unwrap();
            assert!((r.prim.p - 0.175526223927810).abs() < 1e-11, "{r:?}");
            // measured ≤ 12
            assert!(r.iterations <= 24, "{guess:?}: {} iterations", r.iterations);
        }
    }

    /// A state whose kinetic energy exceeds its canonical energy is floored, not NaN.
    #[test]
    fn unphysical_energy_is_floored_and_reported() {
        let g = 5.0 / 3.0;
        let c = conserved(g, 1.0, 1e-3, 0.25);
        let (s, eps, lorentz) = (c.s_over_v * 0.5, c.eps, c.lorentz);
        // take away more than the thermal energy
        let r = recover(g, s, eps - 0.01, lorentz, None).unwrap();
        assert!(r.floored);
        assert!(r.prim.p > 0.0 && r.prim.p.is_finite() && r.prim.u > 0.0);
        assert!(r.prim.v_over_s * s < 1.0);
        assert!(recover(g, 1.0, -1.0, 1.0, None).is_err());
        assert!(recover(g, f64::NAN, 1.0, 1.0, None).is_err());
        assert!(recover(g, 0.1, 1.0, 0.0, None).is_err());
    }

    /// The light-cone step: a cold stream at γ = 31.6 decelerating (the extreme Riemann II's
    /// precursor) may step until the Euler state keeps half its margin, which it then does to
    /// round-off, and recovers without the cold fallback; ten times that step floors it. A
    /// state that only heats, or that drifts without force, gets no limit.
    #[test]
    fn light_cone_step_keeps_half_the_margin() {
        let g = 5.0 / 3.0;
        let (n, u, v) = (1.0, 2.29e-5, 0.9995);
        let c = conserved(g, n, u, v * v);
        let (s, eps, big_n) = (c.s_over_v * v, c.eps, c.lorentz * n);
        let q = eps * eps - s * s - 1.0;
        // decelerating: dS/dt = −3300 (measured at that precursor), dε/dt = v dS/dt
        let (sd, ed) = (-3300.0, v * -3300.0);
        let t = light_cone_step(eps, s * s, ed, s * sd, sd * sd);
        assert!(t.is_finite() && t > 0.0);
        let margin = |k: f64| {
            let (e1, s1) = (eps + k * t * ed, s + k * t * sd);
            e1 * e1 - s1 * s1 - 1.0
        };
        assert!(
            (margin(1.0) - 0.5 * q).abs() <= 1e-6 * q,
            "{} vs {}",
            margin(1.0),
            0.5 * q
        );
        let after = |k: f64| recover(g, s + k * t * sd, eps + k * t * ed, big_n, None);
        assert!(!after(1.0).unwrap().floored);
        assert!(after(10.0).map_or(true, |r| r.floored));
        // heating at rest in S, and free drift: no limit
        assert_eq!(light_cone_step(eps, s * s, 1.0, 0.0, 0.0), f64::INFINITY);
        assert_eq!(light_cone_step(eps, s * s, 0.0, 0.0, 0.0), f64::INFINITY);
        // a floored state (q < 0) keeps the hard edge ε > |S|
        let (e0, s0) = (31.0f64, 30.99f64);
        assert!(e0 * e0 - s0 * s0 < 1.0);
        let t_hard = light_cone_step(e0, s0 * s0, 0.0, s0 * 10.0, 100.0);
        let s1 = s0 + 10.0 * t_hard;
        assert!((e0 * e0 - s1 * s1 - 0.5 * (e0 * e0 - s0 * s0)).abs() < 1e-12 * e0 * e0);
    }

    /// Eq. 63 and Eq. 79 in the Newtonian limit (c_s² → Γ(Γ − 1)u, λ± → v∥ ± c_s) and in 1D
    /// (λ± = (v ± c_s)/(1 ± v c_s)).
    #[test]
    fn sound_and_signal_speeds() {
        let g = 5.0 / 3.0;
        let u = 1e-8;
        let c = sound_speed(g, 1.0 + g * u);
        assert!((c * c / (g * (g - 1.0) * u) - 1.0).abs() < 1e-7);
        let (v, c) = (0.6, 0.5);
        let exact = (v + c) / (1.0 + v * c);
        assert!((signal_speed(v, v * v, c) - exact).abs() < 1e-14);
        assert!((signal_speed(-v, v * v, c) - exact).abs() < 1e-14);
        // transverse motion slows the signal along ê
        assert!(signal_speed(0.0, 0.36, c) < c);
    }
}
