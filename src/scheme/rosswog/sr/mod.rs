//! Special-relativistic SPH of Rosswog (2015) Sec. 6 (c = 1, energies per baryon in units of
//! m0 c²): the formulations F1–F4 with the same gradient, kernel and volume-element choices
//! as the Newtonian presets ([`super::Preset`]), evolving the canonical momentum per baryon
//! S = γ E v (Eq. 54) and the canonical energy per baryon ε = γ E − P/N (Eq. 57).
//!
//! Where the Newtonian machinery has the same form it is reused, not copied: the density
//! N = γ n is the X-weighted kernel sum of baryon numbers ν (Eqs. 36–41, [`super::density_and_pressure`]
//! with the primitive recovery in place of the EOS), the IA matrices and fIA ∇·v
//! ([`super::gradients`]), the pair gradients g_a, g_b ([`super::pair_gradient`]) and the
//! dissipation triggers ([`super::triggers`], with the γ_b weights of Eqs. 90/91).
//!
//! What is SR only: the momentum and energy equations 55/61 (kernel gradients) and 64/65
//! (IA); the primitive recovery (Eqs. 97–99, [`recovery`]); the sound speed (Eq. 63); the
//! eigenvalue signal speeds (Eq. 79); and the dissipation on S and ε with the γ* projections
//! (Eqs. 68–76). The particles keep ν in `mass`, N in `rho`, the recovered v, u, P and c_s in
//! `vel`, `u`, `pressure` and `sound_speed`, and S, ε, γ in slots ([`SrSlots`]) the
//! integrator advances in place of v and u (`acc` holds dS/dt, `dudt` dε/dt).
//!
//! Case files give rest-frame states (n, P, v), as the paper quotes them. [`RosswogSr::init`]
//! turns them into ν = γ m and N = γ n, so a region's lattice keeps its spacing and its
//! summed density is the computing-frame N (Eq. 46).

pub mod recovery;

use super::triggers;
use super::{
    density_and_pressure, ia_matrices, pair_gradient, GradientOperator, Preset, RosswogOverrides,
    RosswogParams, SignalVelocity, TriggerLevels, APPROACH_TOLERANCE,
};
use crate::particles::Vector;
use crate::scheme::{Scheme, SchemeError};
use crate::system::System;
use rayon::prelude::*;
use serde::{Deserialize, Serialize};

/// Where the particles keep the SR state the integrator evolves.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize)]
pub struct SrSlots {
    /// `extra_vectors` slot of the canonical momentum per baryon S.
    pub momentum: usize,
    /// `extra_scalars` slot of the canonical energy per baryon ε.
    pub energy: usize,
    /// `extra_scalars` slot of the Lorentz factor γ of the latest recovery.
    pub lorentz: usize,
}

/// The override keys of an SR preset: those of the Newtonian presets, except the signal
/// velocity, which is the relativistic eigenvalue bound of Eq. 79 (Lorentz-, not
/// Galilean-, invariant physics).
pub fn validate_overrides(preset: Preset, o: &RosswogOverrides) -> Result<(), String> {
    if o.signal_velocity.is_some() {
        return Err("scheme.signal_velocity: the rosswog-sr presets take their signal speed from the relativistic eigenvalues (Rosswog (2015) Eq. 79); remove the key".into());
    }
    o.validate(preset)
}

pub struct RosswogSr {
    pub params: RosswogParams,
    preset: Preset,
    /// The triggers' carried state (previous ∇·v, first step, levels).
    trig: triggers::TriggerState,
    slots: SrSlots,
    /// Γ of P = (Γ − 1) n u (Eq. 62).
    gamma_eos: f64,
    /// A particle whose initial state has no SR counterpart (|v| ≥ 1 from a `[[field]]`,
    /// which the case validation cannot see), reported by the first evaluation.
    bad_state: Option<String>,
}

impl RosswogSr {
    pub fn new(preset: Preset, params: RosswogParams) -> Self {
        Self {
            params: RosswogParams {
                signal_velocity: SignalVelocity::Literal,
                ..params
            },
            preset,
            trig: triggers::TriggerState::new(),
            slots: SrSlots {
                momentum: usize::MAX,
                energy: usize::MAX,
                lorentz: usize::MAX,
            },
            gamma_eos: 5.0 / 3.0,
            bad_state: None,
        }
    }
}

/// v, u, P, c_s and γ of every particle from its S, ε and the summed N (Rosswog (2015)
/// Sec. 6.4), with the iteration counts in the run statistics. A state with no velocity
/// below c stops the run with the particle named, never a NaN; under the paper's conduction
/// (`conduction`) the message also names the option that runs the measured cases on
/// ([`pair_dissipation`]), so the user sees the way out where the run stops.
pub fn recover_all<const D: usize>(
    sys: &mut System<D>,
    slots: SrSlots,
    gamma_eos: f64,
    conduction: bool,
) -> Result<(), SchemeError> {
    let p = &sys.particles;
    let s = &p.extra_vectors[slots.momentum];
    let eps = &p.extra_scalars[slots.energy];
    let out: Vec<Result<recovery::Recovered, String>> = (0..p.len())
        .into_par_iter()
        .map(|i| {
            recovery::recover(
                gamma_eos,
                s[i].norm(),
                eps[i],
                p.rho[i],
                Some(p.pressure[i]),
            )
            .map_err(|e| {
                let hint = if conduction {
                    "; if the run has a hot contact or shear at high Lorentz factor, try scheme.conduction = false (the paper's dissipation conducts heat without its momentum there)"
                } else {
                    ""
                };
                format!(
                    "primitive recovery failed on particle {} at x = {:?}: {}{hint}",
                    p.id[i],
                    p.pos[i].as_slice(),
                    e.0
                )
            })
        })
        .collect();
    let mut iterations = 0u64;
    let mut max_it = 0u64;
    let mut fallbacks = 0u64;
    for r in &out {
        match r {
            Ok(r) => {
                iterations += r.iterations as u64;
                max_it = max_it.max(r.iterations as u64);
                fallbacks += r.floored as u64;
            }
            Err(e) => return Err(SchemeError(e.clone())),
        }
    }
    let st = &mut sys.stats;
    st.sr_recoveries += out.len() as u64;
    st.sr_recovery_iterations += iterations;
    st.sr_recovery_max_iterations = st.sr_recovery_max_iterations.max(max_it);
    st.sr_recovery_fallbacks += fallbacks;
    let p = &mut sys.particles;
    let s = std::mem::take(&mut p.extra_vectors[slots.momentum]);
    let mut lorentz = std::mem::take(&mut p.extra_scalars[slots.lorentz]);
    p.vel
        .par_iter_mut()
        .zip(p.u.par_iter_mut())
        .zip(p.pressure.par_iter_mut().zip(p.sound_speed.par_iter_mut()))
        .zip(lorentz.par_iter_mut())
        .enumerate()
        .for_each(|(i, (((v, u), (pr, cs)), g))| {
            let q = out[i].as_ref().expect("checked above").prim;
            *v = s[i] * q.v_over_s;
            *u = q.u;
            *pr = q.p;
            *cs = recovery::sound_speed(gamma_eos, q.enthalpy());
            *g = q.lorentz;
        });
    p.extra_vectors[slots.momentum] = s;
    p.extra_scalars[slots.lorentz] = lorentz;
    Ok(())
}

/// What the SR pair loop reads of one particle.
#[derive(Clone, Copy)]
struct Rec<const D: usize> {
    x: Vector<D>,
    v: Vector<D>,
    nu: f64,
    h: f64,
    /// X_a
    xw: f64,
    /// A_a = P_a V_a² / (Ω_a X_a)
    a: f64,
    /// N_a
    big_n: f64,
    c: f64,
    /// E_a = 1 + u + P/n (Eq. 59)
    enthalpy: f64,
    /// P_a / N_a
    p_over_n: f64,
    k: f64,
}

#[derive(Clone, Copy)]
struct Acc<const D: usize> {
    ds: Vector<D>,
    deps: f64,
    ds_diss: Vector<D>,
    deps_diss: f64,
    vsig: f64,
}

impl<const D: usize> Default for Acc<D> {
    fn default() -> Self {
        Self {
            ds: Vector::zeros(),
            deps: 0.0,
            ds_diss: Vector::zeros(),
            deps_diss: 0.0,
            vsig: 0.0,
        }
    }
}

/// γ*_k E_k and ε*_k of Eqs. 73–75 for particle k with velocity `v` along the pair axis ê:
/// S*_k·ê = γ*_k E_k (v·ê), ε*_k = γ*_k E_k − P_k/N_k.
#[inline(always)]
fn projected(v_par: f64, enthalpy: f64, p_over_n: f64) -> (f64, f64) {
    let gs = 1.0 / (1.0 - v_par * v_par).sqrt();
    (gs * enthalpy * v_par, gs * enthalpy - p_over_n)
}

/// Particle a's dS/dt and dε/dt per unit ν_b from the dissipation of the approaching pair
/// (a, b) (Rosswog (2015) Eqs. 68–76), given kv = K̄ v_sig / N̄, each particle's velocity
/// along ê, b's (image) velocity, ê and D_ab.
///
/// With `conduction` (the default) this is the paper's form: S*_k and ε*_k (Eqs. 73–75)
/// carry each particle's own enthalpy E_k and P_k/N_k, Π = −kv (S*_a − S*_b)·ê and
/// dε/dt = kv (ε*_a − ε*_b) ê·D. A pair moving at one velocity still exchanges energy and
/// momentum in proportion to its enthalpy jump: a conduction.
///
/// Without it (`scheme.conduction = false`, our option): Π from the pair-mean Ē, so
/// only γ*_k and v_k·ê differ (a relativistic viscosity: Π ∝ the approach speed in the
/// Newtonian limit), and the energy it dissipates goes as the pair's work, dε/dt = −Π v̄·D
/// with v̄ = ½(v_a + v_b): exactly the Newtonian presets' pairwise split of the viscous heating
/// ([`super::dissipative_heating`]), which the Newtonian presets keep without their
/// kv (u_a − u_b) term under the same key. Then a's rest-frame heating,
/// γ_a(dε − v_a·dS) = ½ Π v_ab·D per ν_b, holds only relative velocities.
///
/// Why the option (our decision; the paper has only the first form). Advection I (§7.5) with
/// X = ν (F3, F4): a hot contact (E = 443 inside the triangle, 222 outside) moving at
/// γ = 70.7, where X = ν's pressure blip sets pairs approaching. Measured on
/// `models/verify/sr-advection1.toml` with F3 (7K particles):
/// * the paper's form: across the flow (v·ê ≈ 0, γ* ≈ 1) the conduction moves kv ΔE of ε and
///   no momentum, and at fixed S a particle's rest-frame enthalpy changes by γ times the ε it
///   receives (E² = (ε + P/N)² − S²); a Lorentz-covariant heat flux q would carry the
///   momentum γ v q with its energy γ q. The Lorentz factors spread from 70.7 to
///   [51.9, 115.9] by t = 0.1 and the run stopped at t = 0.86 with |S| ≥ ε. With K = 0 they
///   stay in [70.3, 71.8] at t = 1.
/// * a covariant conduction (γ̄ q of energy, γ̄ v̄ q of momentum) still spread them to
///   [61.7, 99.4] by t = 1: the eigenvalue signal speed (Eq. 79) holds the bulk motion, ≈ 1
///   for pairs oblique to the flow, so a conduction with it runs up to γ times faster than
///   the fluid's proper time allows.
/// * the pair-mean jumps with the paper's ε*-form energy: clean to t = 1, but IA's D_ab has a
///   part D⊥ across ê, and that energy form then heats a by −γ kv ΔS* (v_a·D⊥): the lab
///   velocity, γ times over (the SR twin of the Newtonian presets' finding). The run stopped
///   (time step below 1e-10) at t = 18.2 with the triggers, at t = 1.4 with K = 1; F4's
///   kernel gradients (D ∥ ê) ran all ten crossings.
#[inline(always)]
fn pair_dissipation<const D: usize>(
    conduction: bool,
    kv: f64,
    (va_par, ra): (f64, &Rec<D>),
    (vb_par, rb, vb): (f64, &Rec<D>, &Vector<D>),
    e: &Vector<D>,
    dab: &Vector<D>,
) -> (Vector<D>, f64) {
    if conduction {
        let (sa, epsa) = projected(va_par, ra.enthalpy, ra.p_over_n);
        let (sb, epsb) = projected(vb_par, rb.enthalpy, rb.p_over_n);
        // −Π D and −Ω·D with Ω = −kv (ε*_a − ε*_b) ê (Eqs. 68–71)
        (dab * (kv * (sa - sb)), kv * (epsa - epsb) * e.dot(dab))
    } else {
        // S*·ê at the pair-mean enthalpy (P/N enters only ε*, which this form does not use)
        let e_bar = 0.5 * (ra.enthalpy + rb.enthalpy);
        let pi = -kv * (projected(va_par, e_bar, 0.0).0 - projected(vb_par, e_bar, 0.0).0);
        let v_bar = (ra.v + vb) * 0.5;
        (dab * -pi, -pi * v_bar.dot(dab))
    }
}

impl<const D: usize> Scheme<D> for RosswogSr {
    fn name(&self) -> &'static str {
        match self.preset {
            Preset::F1 => "rosswog-sr-f1",
            Preset::F2 => "rosswog-sr-f2",
            Preset::F3 => "rosswog-sr-f3",
            Preset::F4 => "rosswog-sr-f4",
        }
    }

    /// Register S, ε and γ, and turn the case's rest-frame states (n in `rho`, u from P,
    /// v) into the computing frame: γ = 1/√(1 − v²), ν = γ m, N = γ n, S = γ E v,
    /// ε = γ E − P/N (Eqs. 46, 54, 57). The case validation has checked |v| < 1 and the
    /// ideal-gas EOS.
    fn init(&mut self, sys: &mut System<D>) {
        sys.wall_pairs = true;
        if let crate::eos::EosConfig::IdealGas { gamma } = sys.eos {
            self.gamma_eos = gamma;
        }
        let g = self.gamma_eos;
        self.trig.register(sys);
        let slots = SrSlots {
            momentum: sys.particles.add_vector_field(),
            energy: sys.particles.add_scalar_field(0.0),
            lorentz: sys.particles.add_scalar_field(1.0),
        };
        self.slots = slots;
        sys.relativistic = Some(slots);
        let p = &mut sys.particles;
        for i in 0..p.len() {
            let v = p.vel[i];
            let (n, u) = (p.rho[i], p.u[i]);
            let c = recovery::conserved(g, n, u, v.norm_squared());
            if !(c.lorentz.is_finite() && n > 0.0 && u > 0.0) && self.bad_state.is_none() {
                self.bad_state = Some(format!(
                    "particle {} at x = {:?}: the initial state needs |v| < 1 (c = 1), n > 0 and P > 0, got |v| = {}, n = {n}, u = {u}",
                    p.id[i],
                    p.pos[i].as_slice(),
                    v.norm()
                ));
            }
            p.mass[i] *= c.lorentz;
            p.rho[i] = c.lorentz * n;
            p.pressure[i] = c.p;
            p.sound_speed[i] = recovery::sound_speed(g, c.enthalpy);
            p.extra_vectors[slots.momentum][i] = v * c.s_over_v;
            p.extra_scalars[slots.energy][i] = c.eps;
            p.extra_scalars[slots.lorentz][i] = c.lorentz;
        }
        let k0 = self.params.initial_k();
        p.alpha.iter_mut().for_each(|a| *a = k0);
    }

    fn evaluate(&mut self, sys: &mut System<D>) -> Result<(), SchemeError> {
        if let Some(e) = &self.bad_state {
            return Err(SchemeError(e.clone()));
        }
        let (slots, g) = (self.slots, self.gamma_eos);
        let conduction = self.params.conduction;
        let xw = density_and_pressure(sys, &self.params, self.trig.first_step, &mut |s| {
            recover_all(s, slots, g, conduction)
        })?;
        let mats = ia_matrices(sys);
        let t0 = std::time::Instant::now();
        let n = sys.particles.len();
        let ia = self.params.gradient == GradientOperator::IntegralApproximation;
        let p = &sys.particles;
        let recs: Vec<Rec<D>> = (0..n)
            .into_par_iter()
            .map(|a| {
                let vol = p.mass[a] / p.rho[a];
                let om = if ia { 1.0 } else { p.omega[a] };
                let lorentz = p.extra_scalars[slots.lorentz][a];
                let rest_n = p.rho[a] / lorentz;
                Rec {
                    x: p.pos[a],
                    v: p.vel[a],
                    nu: p.mass[a],
                    h: p.h[a],
                    xw: xw[a],
                    a: p.pressure[a] * vol * vol / (om * xw[a]),
                    big_n: p.rho[a],
                    c: p.sound_speed[a],
                    enthalpy: 1.0 + p.u[a] + p.pressure[a] / rest_n,
                    p_over_n: p.pressure[a] / p.rho[a],
                    k: p.alpha[a],
                }
            })
            .collect();
        let mut out = vec![Acc::<D>::default(); n];
        let k = &sys.kernel;
        sys.gather_with(
            |i| (recs[i].x, recs[i].v),
            &mut out,
            |a, o, pr| {
                if pr.r <= 0.0 || sys.wall_pair(a, pr.b) {
                    return;
                }
                let (ra, rb) = (&recs[a], &recs[pr.b]);
                let ga = pair_gradient(k, ia, &mats[a], ra.h, &pr.dx, pr.r, 0);
                let gb = pair_gradient(k, ia, &mats[pr.b], rb.h, &pr.dx, pr.r, pr.code);
                // Eqs. 55/64 and 61/65 without the 1/ν_a factor; b's image velocity
                o.ds -= ga * (ra.a * rb.xw) + gb * (rb.a * ra.xw);
                o.deps -= ra.a * rb.xw * pr.vb.dot(&ga) + rb.a * ra.xw * ra.v.dot(&gb);
                let e = pr.dx / pr.r;
                let (va_par, vb_par) = (ra.v.dot(&e), pr.vb.dot(&e));
                // Eqs. 77–79
                let vsig = recovery::signal_speed(va_par, ra.v.norm_squared(), ra.c)
                    .max(recovery::signal_speed(vb_par, pr.vb.norm_squared(), rb.c));
                o.vsig = o.vsig.max(vsig);
                let w = va_par - vb_par;
                // approaching (v_ab·r_ab < 0) beyond round-off, as in the Newtonian loop
                if w < -APPROACH_TOLERANCE * ra.c.max(rb.c) {
                    // Eqs. 68–76 with D_ab = ½(g_a + g_b) (Eq. 72 or 76) and N̄_ab the
                    // arithmetic mean (the paper leaves it undefined)
                    let dab = (ga + gb) * 0.5;
                    let kab = 0.5 * (ra.k + rb.k);
                    let kv = kab * vsig / (0.5 * (ra.big_n + rb.big_n));
                    let (ds, deps) = pair_dissipation(
                        conduction,
                        kv,
                        (va_par, ra),
                        (vb_par, rb, &pr.vb),
                        &e,
                        &dab,
                    );
                    // the paper's e-form (ε must be evolved for the recovery), or the pair's
                    // work without conduction ([`pair_dissipation`])
                    o.ds_diss += ds * rb.nu;
                    o.deps_diss += deps * rb.nu;
                }
            },
        );
        sys.store_derivatives(t0, |a| {
            let (o, nu) = (&out[a], recs[a].nu);
            (o.ds / nu + o.ds_diss, o.deps / nu + o.deps_diss, o.vsig)
        });
        Ok(())
    }

    fn refresh(&mut self, sys: &mut System<D>) {
        let (slots, g, conduction) = (self.slots, self.gamma_eos, self.params.conduction);
        // a refresh has no way to report; the next evaluation recovers again and reports
        let _ = density_and_pressure(sys, &self.params, self.trig.first_step, &mut |s| {
            recover_all(s, slots, g, conduction)
        });
    }

    /// Keep every particle's forward-Euler step inside the states a recovery can invert
    /// ([`recovery::light_cone_step`]; our addition to the paper's step rule).
    fn step_limit(&self, sys: &System<D>) -> f64 {
        let p = &sys.particles;
        let s = &p.extra_vectors[self.slots.momentum];
        let eps = &p.extra_scalars[self.slots.energy];
        (0..sys.owned())
            .into_par_iter()
            .with_min_len(crate::threads::LIGHT)
            .map(|a| {
                let (sd, ed) = (&p.acc[a], p.dudt[a]);
                recovery::light_cone_step(
                    eps[a],
                    s[a].norm_squared(),
                    ed,
                    s[a].dot(sd),
                    sd.norm_squared(),
                )
            })
            .reduce(|| f64::INFINITY, f64::min)
    }

    fn end_step(&mut self, sys: &mut System<D>, dt: f64) {
        let lorentz = sys.particles.extra_scalars[self.slots.lorentz].clone();
        self.trig.end_step(sys, &self.params, dt, Some(&lorentz));
    }

    /// One support, as the Newtonian F1–F4: the h–ρ–P loop, the IA matrices and the
    /// triggers refresh the halo between passes, and the primitive recovery runs on the
    /// halo copies from their refreshed N and carried S, ε (with the owners' P as its
    /// first guess), so it gives their owners' bits.
    fn halo_depth(&self) -> usize {
        1
    }

    fn trigger_levels(&self) -> Option<TriggerLevels> {
        self.trig.levels
    }

    fn carried_state(&self) -> Vec<f64> {
        self.trig.carried()
    }

    fn set_carried_state(&mut self, state: &[f64]) -> Result<(), String> {
        self.trig
            .set_carried(<Self as Scheme<D>>::name(self), state)
    }
}
