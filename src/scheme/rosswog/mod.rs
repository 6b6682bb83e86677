//! Rosswog (2015), "Boosting the accuracy of SPH" — the Newtonian formulations F1–F4
//! (its Secs. 5–6). Four ingredients, each switchable:
//!
//! * gradient: kernel gradients with grad-h terms (Eqs. 55/61) or the antisymmetric
//!   integral approximation G_a = C_a (r_b − r_a) W_ab(h_a) (Eqs. 64/65, 66/67), Ω ≡ 1;
//! * volume element X = 1, m or P^k (Eqs. 36–41) with the ρ–P–h iteration of §7.2;
//! * dissipation (§6.4, Newtonian limit of Chow & Monaghan) on momentum and energy with the
//!   gradient factor D_ab = ½(g_a + g_b) of the same family as the hydro terms (Eq. 72/76);
//! * the per-particle dissipation parameter K: constant, or the shock and noise triggers of
//!   §7.1 ([`triggers`]).
//!
//! The specific internal energy is evolved instead of e: the hydro part in the paper's
//! pairwise u-form, the dissipation's heating split pairwise (see [`dissipative_heating`]), so
//! total energy is conserved in continuous time and pairwise antisymmetry keeps momentum
//! exact. Angular momentum is not exact with IA (G_a is not along r_ab; Rosswog (2015) Eqs. 16–25).

mod force;
pub mod gradients;
mod ia_sums;
pub mod sr;
pub mod triggers;

use super::smoothing::{refresh_halo_after_solve, solve_density_and_h_weighted};
use super::standard::check_range;
use super::{Scheme, SchemeError};
use crate::kernel::KernelName;
use crate::particles::Vector;
use crate::system::System;
use rayon::prelude::*;
use serde::{Deserialize, Serialize};

/// Relative approach speed (in units of the sound speed) below which a pair counts as at rest.
///
/// Our decision (the paper is silent): Rosswog (2015) Sec. 6.3 dissipates "approaching" pairs,
/// v_ab·r_ab < 0. Without a margin, a static state's ±1e-16 velocities switch on the e*
/// conduction term, which does not scale with the approach speed, across every density jump.
pub const APPROACH_TOLERANCE: f64 = 1e-9;

/// Volume weight X of V_a = X_a / Σ_b X_b W_ab(h_a).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "kebab-case")]
pub enum VolumeElement {
    /// X = 1 (number density).
    One,
    /// X = m (standard SPH).
    Mass,
    /// X = P^k.
    Pressure,
}

#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "kebab-case")]
pub enum GradientOperator {
    /// Kernel gradients with grad-h factors.
    Kernel,
    /// Antisymmetric integral approximation (IA).
    IntegralApproximation,
}

#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "kebab-case")]
pub enum SignalVelocity {
    /// max(c_a, c_b) + max(0, −v_ab·ê): Galilean invariant (Rosswog (2015) Eqs. 77–79 [MINE]).
    Galilean,
    /// max(c_a + |v_a·ê|, c_b + |v_b·ê|): the literal Newtonian limit of Eq. 79.
    Literal,
}

/// Fully resolved parameters of one formulation.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
pub struct RosswogParams {
    pub volume: VolumeElement,
    /// Exponent k of X = P^k.
    pub k: f64,
    pub gradient: GradientOperator,
    /// Triggered dissipation (true) or constant K = `k_constant`.
    pub triggers: bool,
    pub k_constant: f64,
    pub k_max: f64,
    pub n_noise: f64,
    /// Decay time τ = χ h / c_s.
    pub chi: f64,
    /// Floor of K (Eq. 82), 0 by default.
    pub k_min: f64,
    pub signal_velocity: SignalVelocity,
    /// Until this time K = `k_constant` everywhere and the triggers only watch (Rosswog
    /// (2015) §7.7.1 starts the KH runs with "K_a = 1 for t < 0.5"); 0: triggered from the
    /// start.
    pub k_constant_until: f64,
    /// Keep the conduction part of the Chow–Monaghan dissipation (Rosswog (2015) Eqs. 70–75:
    /// the jumps in e* (Newtonian: u) and, in SR, in S* and ε* through the enthalpy);
    /// false dissipates only the velocity jump. Our option, for hot contacts moving at high
    /// γ, where the paper's form is unstable (see `sr::pair_dissipation`).
    pub conduction: bool,
}

impl RosswogParams {
    /// K at the start: K_min when the triggers run from t = 0, else the constant K (constant
    /// dissipation, or the triggers' start-up phase before `k_constant_until`).
    pub fn initial_k(&self) -> f64 {
        if self.triggers && self.k_constant_until <= 0.0 {
            self.k_min
        } else {
            self.k_constant
        }
    }
}

/// The four formulations F1–F4 the paper compares.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Preset {
    F1,
    F2,
    F3,
    F4,
}

impl Preset {
    pub fn params(self) -> RosswogParams {
        let base = RosswogParams {
            volume: VolumeElement::Pressure,
            k: 0.05,
            gradient: GradientOperator::IntegralApproximation,
            triggers: true,
            k_constant: 1.0,
            k_max: 1.5,
            n_noise: 50.0,
            chi: 2.0,
            k_min: 0.0,
            signal_velocity: SignalVelocity::Galilean,
            k_constant_until: 0.0,
            conduction: true,
        };
        match self {
            Preset::F1 => base,
            Preset::F2 => RosswogParams {
                gradient: GradientOperator::Kernel,
                ..base
            },
            Preset::F3 => RosswogParams {
                volume: VolumeElement::Mass,
                ..base
            },
            Preset::F4 => RosswogParams {
                volume: VolumeElement::Mass,
                gradient: GradientOperator::Kernel,
                triggers: false,
                ..base
            },
        }
    }

    /// Kernel and η of the table: W3,3 (Wendland C6 at 2h) η = 2.2 for F1–F3, M4 η = 1.2 for F4.
    pub fn kernel(self) -> (KernelName, f64) {
        match self {
            Preset::F4 => (KernelName::CubicSpline, 1.2),
            _ => (KernelName::WendlandC6, 2.2),
        }
    }
}

/// `[scheme]` keys of a preset; any key given overrides the preset's value.
#[derive(Debug, Clone, Copy, PartialEq, Default, Serialize, Deserialize)]
#[serde(deny_unknown_fields, default)]
pub struct RosswogOverrides {
    pub volume: Option<VolumeElement>,
    pub k: Option<f64>,
    pub gradient: Option<GradientOperator>,
    pub triggers: Option<bool>,
    pub k_constant: Option<f64>,
    pub k_max: Option<f64>,
    pub n_noise: Option<f64>,
    pub chi: Option<f64>,
    pub k_min: Option<f64>,
    pub signal_velocity: Option<SignalVelocity>,
    pub k_constant_until: Option<f64>,
    pub conduction: Option<bool>,
}

impl RosswogOverrides {
    pub fn resolve(&self, preset: Preset) -> RosswogParams {
        let b = preset.params();
        RosswogParams {
            volume: self.volume.unwrap_or(b.volume),
            k: self.k.unwrap_or(b.k),
            gradient: self.gradient.unwrap_or(b.gradient),
            triggers: self.triggers.unwrap_or(b.triggers),
            k_constant: self.k_constant.unwrap_or(b.k_constant),
            k_max: self.k_max.unwrap_or(b.k_max),
            n_noise: self.n_noise.unwrap_or(b.n_noise),
            chi: self.chi.unwrap_or(b.chi),
            k_min: self.k_min.unwrap_or(b.k_min),
            signal_velocity: self.signal_velocity.unwrap_or(b.signal_velocity),
            k_constant_until: self.k_constant_until.unwrap_or(b.k_constant_until),
            conduction: self.conduction.unwrap_or(b.conduction),
        }
    }

    pub fn validate(&self, preset: Preset) -> Result<(), String> {
        let p = self.resolve(preset);
        check_range("scheme.k", p.k, 0.0, 1.0)?;
        check_range("scheme.k_constant", p.k_constant, 0.0, 10.0)?;
        check_range("scheme.k_max", p.k_max, 0.0, 10.0)?;
        if !(p.n_noise.is_finite() && p.n_noise > 0.0) {
            return Err(format!(
                "scheme.n_noise: must be a finite number > 0, got {}",
                p.n_noise
            ));
        }
        if !(p.chi.is_finite() && p.chi > 0.0) {
            return Err(format!(
                "scheme.chi: must be a finite number > 0, got {}",
                p.chi
            ));
        }
        check_range("scheme.k_min", p.k_min, 0.0, p.k_max)?;
        if !(p.k_constant_until.is_finite() && p.k_constant_until >= 0.0) {
            return Err(format!(
                "scheme.k_constant_until: must be a finite time ≥ 0, got {}",
                p.k_constant_until
            ));
        }
        Ok(())
    }
}

pub struct Rosswog {
    pub params: RosswogParams,
    preset: Preset,
    /// The triggers' carried state (previous ∇·v, first step, levels).
    trig: triggers::TriggerState,
}

/// The largest dissipation parameter and trigger targets over the particles after a step
/// (Rosswog (2015) Eqs. 85–95; the paper reports them for the Gresho vortex, §7.4).
#[derive(Debug, Clone, Copy, Default, PartialEq)]
pub struct TriggerLevels {
    /// max K_a.
    pub k: f64,
    /// max K_max A/(A + (c/h)²), the shock trigger's target.
    pub shock: f64,
    /// max K_max κ1 (noise trigger N1).
    pub noise1: f64,
    /// max K_max κ2 (noise trigger N2).
    pub noise2: f64,
    /// The means over the particles of the shock, noise-1 and noise-2 targets.
    pub mean_shock: f64,
    pub mean_noise1: f64,
    pub mean_noise2: f64,
}

impl Rosswog {
    pub fn new(preset: Preset, params: RosswogParams) -> Self {
        Self {
            params,
            preset,
            trig: triggers::TriggerState::new(),
        }
    }

    /// Density, h and pressure (Newtonian: P from the EOS), see [`density_and_pressure`].
    fn density<const D: usize>(&self, sys: &mut System<D>) -> Vec<f64> {
        density_and_pressure(sys, &self.params, self.trig.first_step, &mut |s| {
            s.update_eos();
            Ok(())
        })
        .expect("the Newtonian EOS update cannot fail")
    }
}

/// X for the current pressures (X = P^k with P floored at a tiny positive value).
///
/// Our decision for liquids (the paper's X = P^k, its Eq. 12 family, is written for
/// ideal gases): X = (P + P_off)^k with the EOS's offset (`EosConfig::pressure_offset`,
/// B for Tait, γP∞ for a stiffened gas), the part of P that behaves like a gas pressure.
/// A liquid's P passes through zero at a free surface and sits near it in a tank, where
/// P^k would swing by orders of magnitude and the ρ–P loop run away (measured: the closed
/// tank's first evaluation diverged to P ~ 1e109); (P + P_off)^k = B^k (ρ/ρ0)^{γk} stays
/// smooth. For ideal gases P_off = 0: the paper's X unchanged.
fn weights<const D: usize>(sys: &System<D>, params: &RosswogParams) -> Option<Vec<f64>> {
    let p = &sys.particles;
    match params.volume {
        VolumeElement::Mass => None,
        VolumeElement::One => Some(vec![1.0; p.len()]),
        VolumeElement::Pressure => {
            let k = params.k;
            let off = sys.eos.pressure_offset();
            Some(
                p.pressure
                    .par_iter()
                    .map(|&pr| (pr + off).max(1e-300).powf(k))
                    .collect(),
            )
        }
    }
}

/// Density, h and pressure; for X = P^k the ρ–P loop of Rosswog (2015) Sec. 6.1.3 (steps
/// a–e): one more density pass with the X of the new pressures. `pressures` turns the new
/// densities into pressures: the EOS (Newtonian) or the primitive recovery (SR, Sec. 6.4).
/// Our decision for bodies: in the first step the wall particles' X starts from the pressure
/// they were generated with (not yet the wall condition's), so the loop repeats until X
/// settles (max relative change ≤ 1e-10, at most `FIRST_STEP_PASSES`); afterwards X carries
/// over and two passes suffice. Returns X (the masses for X = m).
pub(crate) fn density_and_pressure<const D: usize>(
    sys: &mut System<D>,
    params: &RosswogParams,
    first_step: bool,
    pressures: &mut dyn FnMut(&mut System<D>) -> Result<(), SchemeError>,
) -> Result<Vec<f64>, SchemeError> {
    const FIRST_STEP_PASSES: usize = 30;
    let x = weights(sys, params);
    let again = params.volume == VolumeElement::Pressure;
    // the wall condition reads the working list, so with bodies every pass compacts it
    let walls = !sys.bodies.is_empty();
    solve_density_and_h_weighted(sys, x.as_deref(), !again || walls);
    // the next passes read the neighbours' h, ρ and Ω (and X from their P)
    refresh_halo_after_solve(sys, !again || walls);
    pressures(sys)?;
    if !again {
        return Ok(x.unwrap_or_else(|| sys.particles.mass.clone()));
    }
    let passes = if first_step && walls {
        FIRST_STEP_PASSES
    } else {
        1
    };
    let mut prev = x.expect("X = P^k");
    for _ in 0..passes {
        let x = weights(sys, params).expect("X = P^k");
        solve_density_and_h_weighted(sys, Some(&x), true);
        refresh_halo_after_solve(sys, true);
        pressures(sys)?;
        // over the owned particles and every rank: all ranks take the same passes (each
        // refresh is a collective), as many as one process would
        let own = sys.owned();
        let mut change = [x[..own]
            .iter()
            .zip(&prev[..own])
            .map(|(a, b)| ((a - b) / a).abs())
            .fold(0.0, f64::max)];
        if let Some(ranks) = &sys.ranks {
            ranks.max_in_place(&mut change);
        }
        let change = change[0];
        prev = x;
        if change <= 1e-10 {
            break;
        }
    }
    Ok(prev)
}

/// Particle a's internal-energy change per unit m_b from the Chow–Monaghan dissipation of
/// the approaching pair (a, b) (Rosswog (2015) Eqs. 68–76 in their Newtonian limit):
/// conduction `kv (u_a − u_b) ê·D` (kv = K v_sig/ρ̄) plus half the pair's viscous work
/// `½ Π v_ab·D`.
///
/// Our decision. The paper dissipates the total energy e with e* = u + ½(v·ê)² (Eq. 75), and
/// u then follows from de − v·dv. Where D_ab lies along ê (kernel gradients, F2 and F4) that
/// is exactly this split: −v_a·dv_diss + de_diss = kv[(u_a − u_b) F − ½ w² F] with D = F ê.
/// With IA gradients (F1, F3) D_ab has a part D⊥ across ê, and the e-form adds
/// −kv w (v_a·D⊥): a term in the lab-frame velocity, not Galilean invariant and of either
/// sign. In a cold fast flow it is far larger than u (Noh: u = 1.5e-6 at |v| = 1) and drove u
/// negative at the free edge within ten steps (F1 stopped with a collapsed time step at step
/// 3 of the 2D Noh problem). Here the kinetic energy the pair loses,
/// m_a m_b Π v_ab·D_ab, heats both particles equally, so energy is conserved pair by pair and
/// only relative velocities enter.
/// Here `e_dot_d` = ê·D_ab and `v_dot_d` = v_ab·D_ab.
#[inline(always)]
fn dissipative_heating(kv: f64, pi: f64, du_ab: f64, e_dot_d: f64, v_dot_d: f64) -> f64 {
    kv * du_ab * e_dot_d + 0.5 * pi * v_dot_d
}

/// The IA matrices of every particle (and the fIA ∇·v the triggers read), with their time
/// and the kernel-gradient fallbacks in the run statistics.
pub(crate) fn ia_matrices<const D: usize>(sys: &mut System<D>) -> Vec<gradients::IaMatrix<D>> {
    let t0 = std::time::Instant::now();
    let (mut mats, _grads, fallbacks) = gradients::ia_pass(sys);
    // the forces read the neighbours' matrices (g_b, Eqs. 66/67)
    sys.halo_sync()
        .refresh(vec![crate::parallel::rows(&mut mats)]);
    sys.stats.ia_fallbacks = fallbacks;
    sys.stats.ia_fallbacks_total += fallbacks;
    sys.stats.seconds_gradients += t0.elapsed().as_secs_f64();
    mats
}

/// g_a (or g_b) of the pair (a, b), standing in for ∇_a W (Eqs. 66/67) with particle i's
/// smoothing length h: IA, C_i (r_b − r_a) W(h), or, on fallback and in the kernel
/// formulations, dW/dr · r̂_ab. `dx` = r_a − r_b; a mirror image (`code` ≠ 0) carries the
/// reflected matrix R C R.
#[inline(always)]
pub(crate) fn pair_gradient<const D: usize>(
    k: &crate::kernel::DimKernel<D>,
    ia: bool,
    mat: &gradients::IaMatrix<D>,
    h: f64,
    dx: &Vector<D>,
    dist: f64,
    code: u8,
) -> Vector<D> {
    if ia && !mat.fallback {
        let c = if code == 0 {
            mat.c
        } else {
            gradients::reflect(&mat.c, code)
        };
        c * (-dx) * k.w(dist, h)
    } else {
        *dx * (k.dwdr(dist, h) / dist)
    }
}

impl<const D: usize> Scheme<D> for Rosswog {
    fn name(&self) -> &'static str {
        match self.preset {
            Preset::F1 => "rosswog-f1",
            Preset::F2 => "rosswog-f2",
            Preset::F3 => "rosswog-f3",
            Preset::F4 => "rosswog-f4",
        }
    }

    fn init(&mut self, sys: &mut System<D>) {
        // wall particles need full neighbourhoods for their IA matrices (Eq. 17)
        sys.wall_pairs = true;
        self.trig.register(sys);
        // Pressures of the initial condition seed X = P^k.
        sys.update_eos();
        let k0 = self.params.initial_k();
        sys.particles.alpha.iter_mut().for_each(|a| *a = k0);
    }

    fn evaluate(&mut self, sys: &mut System<D>) -> Result<(), SchemeError> {
        let xw = self.density(sys);
        let mats = ia_matrices(sys);
        let t0 = std::time::Instant::now();
        // the pass's per-particle arrays, kept between steps (`crate::scratch`)
        let mut recs: Vec<force::Rec<D>> = sys.scratch.take();
        let mut out: Vec<force::Acc<D>> = sys.scratch.take();
        force::RosswogForce {
            sys,
            xw: &xw,
            mats: &mats,
            ia: self.params.gradient == GradientOperator::IntegralApproximation,
            literal: self.params.signal_velocity == SignalVelocity::Literal,
            conduction: if self.params.conduction { 1.0 } else { 0.0 },
        }
        .run(&mut recs, &mut out);
        sys.store_derivatives(t0, |a| force::derivatives(&recs[a], &out[a]));
        sys.scratch.keep(recs);
        sys.scratch.keep(out);
        Ok(())
    }

    /// After a predictor-corrector's final update: the same volume elements as `evaluate`.
    fn refresh(&mut self, sys: &mut System<D>) {
        self.density(sys);
    }

    fn end_step(&mut self, sys: &mut System<D>, dt: f64) {
        self.trig.end_step(sys, &self.params, dt, None);
    }

    /// One support: the h–ρ–P loop, the IA matrices and the triggers refresh the halo's
    /// fields between passes (`density_and_pressure`, `ia_matrices`, `end_step`).
    fn halo_depth(&self) -> usize {
        1
    }

    fn trigger_levels(&self) -> Option<TriggerLevels> {
        self.trig.levels
    }

    /// Whether the trigger has seen a step yet (its first step has no previous ∇·v).
    fn carried_state(&self) -> Vec<f64> {
        self.trig.carried()
    }

    fn set_carried_state(&mut self, state: &[f64]) -> Result<(), String> {
        self.trig
            .set_carried(<Self as Scheme<D>>::name(self), state)
    }
}
