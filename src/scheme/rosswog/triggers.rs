//! The dissipation parameter K_a (Rosswog (2015) Eqs. 80–96, Eqs. 80–96): raised at once to
//! K_des = max(K_shock, K_noise), otherwise decaying with τ = χ h / c_s.
//!
//! Decisions the paper leaves open (Rosswog (2015) Eqs. 80–96 (a)–(d), made here in one place):
//! (a) the noise sums include b = a; (b) d(∇·v)/dt = [(∇·v)ⁿ − (∇·v)ⁿ⁻¹]/Δt between full
//! steps, A = 0 on the first step; (c) K is updated once per full step, outside the RK stages:
//! Kⁿ⁺¹ = max(K_des, K_min + (Kⁿ − K_min) e^{−Δt/τ}); (d) the noise sums run over all
//! neighbours within the support. ∇·v is the fIA estimate of the latest evaluation.

use super::{RosswogParams, TriggerLevels};
use crate::system::System;
use rayon::prelude::*;

/// What the triggers carry from step to step for a Rosswog scheme (Newtonian or SR): the slot
/// of the previous ∇·v, whether a step has been seen yet (the first has no previous ∇·v) and
/// the levels of the latest update.
#[derive(Debug, Clone, Copy)]
pub struct TriggerState {
    prev_div_slot: usize,
    pub first_step: bool,
    pub levels: Option<TriggerLevels>,
}

impl TriggerState {
    pub fn new() -> Self {
        Self {
            prev_div_slot: usize::MAX,
            first_step: true,
            levels: None,
        }
    }

    /// Register the previous-∇·v slot (at the scheme's `init`).
    pub fn register<const D: usize>(&mut self, sys: &mut System<D>) {
        self.prev_div_slot = sys.particles.add_scalar_field(0.0);
    }

    /// After a step: update K when the triggers run (`lorentz`: the γ_b weights of SR runs).
    pub fn end_step<const D: usize>(
        &mut self,
        sys: &mut System<D>,
        prm: &RosswogParams,
        dt: f64,
        lorentz: Option<&[f64]>,
    ) {
        if prm.triggers {
            // the noise triggers read the neighbours' ∇·v (Eqs. 87–88); their γ_b (SR) come
            // from the recovery, which ran on the halo copies from their owners' bits
            let (sync, p) = (sys.halo_sync(), &mut sys.particles);
            sync.refresh(vec![crate::parallel::rows(&mut p.div_v)]);
            self.levels = Some(update(
                sys,
                prm,
                self.prev_div_slot,
                dt,
                self.first_step,
                lorentz,
            ));
        }
        self.first_step = false;
    }

    /// The carried state as one 0/1 value (whether the first step is still to come).
    pub fn carried(&self) -> Vec<f64> {
        vec![if self.first_step { 1.0 } else { 0.0 }]
    }

    /// Put back what [`Self::carried`] returned, for scheme `name`.
    pub fn set_carried(&mut self, name: &str, state: &[f64]) -> Result<(), String> {
        match state {
            [f] if *f == 0.0 || *f == 1.0 => {
                self.first_step = *f == 1.0;
                Ok(())
            }
            _ => Err(format!("{name}: expected one 0/1 flag, got {state:?}")),
        }
    }
}

impl Default for TriggerState {
    fn default() -> Self {
        Self::new()
    }
}

#[derive(Clone, Copy, Default)]
struct NoiseSums {
    s1: f64,
    s2: f64,
    pos_sum: f64,
    pos_n: u32,
    neg_sum: f64,
    neg_n: u32,
}

impl NoiseSums {
    /// A neighbour's ∇·v `d` and its Lorentz factor `g` (1 in Newtonian runs): noise 1 sums
    /// ∇·v (Eqs. 87–88), noise 2 sums γ_b ∇·v_b (Eqs. 90–91).
    fn add(&mut self, d: f64, g: f64) {
        self.s1 += d;
        self.s2 += d.abs();
        if d > 0.0 {
            self.pos_sum += g * d;
            self.pos_n += 1;
        } else if d < 0.0 {
            self.neg_sum += g * d;
            self.neg_n += 1;
        }
    }
}

pub fn update<const D: usize>(
    sys: &mut System<D>,
    prm: &RosswogParams,
    prev_slot: usize,
    dt: f64,
    first: bool,
    lorentz: Option<&[f64]>,
) -> TriggerLevels {
    let gamma = |i: usize| lorentz.map_or(1.0, |l| l[i]);
    let n = sys.particles.len();
    let mut sums = vec![NoiseSums::default(); n];
    {
        let p = &sys.particles;
        let k = &sys.kernel;
        sys.gather(&mut sums, |a, s, pr| {
            if pr.r < k.radius(p.h[a]) {
                s.add(p.div_v[pr.b], gamma(pr.b));
            }
        });
    }
    let p = &mut sys.particles;
    let (div, cs, h) = (&p.div_v, &p.sound_speed, &p.h);
    let prev = &p.extra_scalars[prev_slot];
    let targets: Vec<(f64, f64, f64, f64)> = (0..n)
        .into_par_iter()
        .map(|a| {
            let mut s = sums[a];
            s.add(div[a], gamma(a)); // (a) self included
            let c_over_h = cs[a] / h[a];
            // shock (Eqs. 85–86)
            let ddiv = if first || dt <= 0.0 {
                0.0
            } else {
                (div[a] - prev[a]) / dt
            };
            let big_a = (-ddiv).max(0.0);
            let k_shock = if big_a > 0.0 {
                prm.k_max * big_a / (big_a + c_over_h * c_over_h)
            } else {
                0.0
            };
            // noise 1 (Eqs. 87–89, 94)
            let s1 = if div[a] < 0.0 { -s.s1 } else { s.s1 };
            let n1 = if s.s2 > 0.0 {
                (s1 / s.s2 - 1.0).abs()
            } else {
                0.0
            };
            let kappa1 = n1 / (n1 + prm.n_noise);
            // noise 2 (Eqs. 90–92, 95)
            let n2 = if s.pos_n > 0 && s.neg_n > 0 {
                let sp = s.pos_sum / s.pos_n as f64;
                let sm = -s.neg_sum / s.neg_n as f64;
                (sp * sm).sqrt()
            } else {
                0.0
            };
            let kappa2 = if n2 > 0.0 {
                n2 / (n2 + 0.2 * c_over_h)
            } else {
                0.0
            };
            (k_shock, prm.k_max * kappa1, prm.k_max * kappa2, c_over_h)
        })
        .collect();
    let mut levels = TriggerLevels::default();
    for t in &targets {
        levels.shock = levels.shock.max(t.0);
        levels.noise1 = levels.noise1.max(t.1);
        levels.noise2 = levels.noise2.max(t.2);
        levels.mean_shock += t.0 / n as f64;
        levels.mean_noise1 += t.1 / n as f64;
        levels.mean_noise2 += t.2 / n as f64;
    }
    let new_k: Vec<f64> = targets
        .par_iter()
        .map(|&(k_shock, k_n1, k_n2, c_over_h)| (k_shock.max(k_n1).max(k_n2), c_over_h))
        .zip(p.alpha.par_iter())
        .map(|((k_des, c_over_h), &k_old)| {
            let tau = prm.chi / c_over_h.max(1e-300);
            let decayed = prm.k_min + (k_old - prm.k_min) * (-dt / tau).exp();
            k_des.max(decayed).max(prm.k_min)
        })
        .collect();
    // before `k_constant_until` the triggers watch (∇·v history) but K stays constant
    p.alpha = if sys.time < prm.k_constant_until {
        vec![prm.k_constant; n]
    } else {
        new_k
    };
    let d = p.div_v.clone();
    p.extra_scalars[prev_slot] = d;
    levels.k = p.alpha.iter().cloned().fold(0.0, f64::max);
    levels
}
