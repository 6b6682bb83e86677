//! Time integrators with a global time step. Each works on the evolved fields (x, v, u) of
//! the particles and calls the scheme for derivatives; none knows which scheme runs.
//!
//! * `leapfrog` — kick-drift-kick, one evaluation per step (velocity-dependent forces use
//!   the predicted v and u at the end of the drift).
//! * `ssp-rk3` — Shu–Osher third-order strong-stability-preserving Runge–Kutta (Rosswog
//!   (2015) Sec. 6.5), three evaluations per step.
//! * `crk-rk2` — the one-evaluation "cheap synchronous" RK2 of the Frontiere, Raskin & Owen (2017) §4:
//!   predict to t+dt/2 with the previous midpoint derivatives, evaluate there, advance the
//!   full step from the start state, then refresh ρ, h, P. When the scheme keeps its pair
//!   accelerations ([`Scheme::pair_work`]) the final u comes from the compatible update
//!   (Frontiere, Raskin & Owen (2017) §3.3; eqs 56–68) with the midpoint a_ij and v^{1/2} = (v⁰ + v¹)/2; otherwise from du/dt.
//!
//! Positions are wrapped / reflected only at the end of a full step, so the stage
//! combinations never mix a wrapped and an unwrapped coordinate.

use crate::particles::Vector;
use crate::scheme::{compatible, Scheme, SchemeError};
use crate::system::System;
use crate::threads::{LIGHT, MEDIUM};
use rayon::prelude::*;
use serde::{Deserialize, Serialize};

#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "kebab-case")]
pub enum IntegratorKind {
    Leapfrog,
    SspRk3,
    CrkRk2,
}

impl IntegratorKind {
    /// The case-file name (`time.integrator`).
    pub fn name(self) -> &'static str {
        match self {
            IntegratorKind::Leapfrog => "leapfrog",
            IntegratorKind::SspRk3 => "ssp-rk3",
            IntegratorKind::CrkRk2 => "crk-rk2",
        }
    }
}

/// Saved start-of-step state.
#[derive(Debug, Clone, Default, Serialize, Deserialize)]
struct Saved<const D: usize> {
    pos: Vec<Vector<D>>,
    vel: Vec<Vector<D>>,
    u: Vec<f64>,
    /// ρ (only when the scheme evolves it; the leapfrog keeps ρ at the half step here).
    rho: Vec<f64>,
    /// Start-of-step entropy proxies (compatible energy update only).
    entropy: Vec<Option<f64>>,
    /// Canonical momentum S and energy ε per baryon (special-relativistic schemes only).
    #[serde(default)]
    momentum: Vec<Vector<D>>,
    #[serde(default)]
    energy: Vec<f64>,
}

impl<const D: usize> Saved<D> {
    fn save(&mut self, sys: &System<D>) {
        let p = &sys.particles;
        self.pos.clone_from(&p.pos);
        self.vel.clone_from(&p.vel);
        self.u.clone_from(&p.u);
        if sys.evolve_density {
            self.rho.clone_from(&p.rho);
        }
        if let Some(sr) = sys.relativistic {
            self.momentum.clone_from(&p.extra_vectors[sr.momentum]);
            self.energy.clone_from(&p.extra_scalars[sr.energy]);
        }
    }

    fn save_entropy(&mut self, sys: &System<D>) {
        let p = &sys.particles;
        self.entropy = (0..p.len())
            .into_par_iter()
            .with_min_len(MEDIUM)
            .map(|i| sys.eos_of(p.material[i]).entropy_proxy(p.rho[i], p.u[i]))
            .collect();
    }
}

#[derive(Debug, Clone, Serialize, Deserialize)]
pub struct Integrator<const D: usize> {
    pub kind: IntegratorKind,
    saved: Saved<D>,
}

impl<const D: usize> Integrator<D> {
    /// Whether a saved integrator (from a saved state) holds only finite numbers. Its stage
    /// arrays are refilled at the start of every step, so their lengths do not matter.
    pub fn check(&self) -> Result<(), String> {
        let s = &self.saved;
        let ok = s
            .pos
            .iter()
            .chain(&s.vel)
            .all(|x| x.iter().all(|c| c.is_finite()))
            && s.momentum.iter().all(|x| x.iter().all(|c| c.is_finite()))
            && s.u
                .iter()
                .chain(&s.rho)
                .chain(&s.energy)
                .all(|x| x.is_finite())
            && s.entropy.iter().flatten().all(|x| x.is_finite());
        if ok {
            Ok(())
        } else {
            Err("the integrator's saved stage is not finite".into())
        }
    }
}

/// U ← c0·U0 + c1·(U + dt·L(U)) on (x, v, u), or on (x, S, ε) in special-relativistic runs.
fn combine<const D: usize>(sys: &mut System<D>, s0: &Saved<D>, c0: f64, c1: f64, dt: f64) {
    if let Some(sr) = sys.relativistic {
        return combine_canonical(sys, s0, sr, c0, c1, dt);
    }
    let p = &mut sys.particles;
    let (acc, dudt) = (&p.acc, &p.dudt);
    p.pos
        .par_iter_mut()
        .zip(p.vel.par_iter_mut())
        .zip(p.u.par_iter_mut())
        .enumerate()
        .with_min_len(LIGHT)
        .for_each(|(i, ((x, v), u))| {
            let xn = *x + *v * dt;
            let vn = *v + acc[i] * dt;
            let un = *u + dudt[i] * dt;
            *x = s0.pos[i] * c0 + xn * c1;
            *v = s0.vel[i] * c0 + vn * c1;
            *u = s0.u[i] * c0 + un * c1;
        });
}

/// The SR form of [`combine`] (Rosswog (2015) Sec. 6.5): S advances with `acc` = dS/dt, ε
/// with `dudt` = dε/dt, x with the velocity the latest evaluation recovered (dx/dt = v).
/// v and u stay as they are until the next evaluation recovers them from S, ε and N.
fn combine_canonical<const D: usize>(
    sys: &mut System<D>,
    s0: &Saved<D>,
    sr: crate::scheme::rosswog::sr::SrSlots,
    c0: f64,
    c1: f64,
    dt: f64,
) {
    let p = &mut sys.particles;
    let (acc, dedt, vel) = (&p.acc, &p.dudt, &p.vel);
    p.pos
        .par_iter_mut()
        .enumerate()
        .with_min_len(LIGHT)
        .for_each(|(i, x)| {
            *x = s0.pos[i] * c0 + (*x + vel[i] * dt) * c1;
        });
    p.extra_vectors[sr.momentum]
        .par_iter_mut()
        .enumerate()
        .with_min_len(LIGHT)
        .for_each(|(i, s)| *s = s0.momentum[i] * c0 + (*s + acc[i] * dt) * c1);
    p.extra_scalars[sr.energy]
        .par_iter_mut()
        .enumerate()
        .with_min_len(LIGHT)
        .for_each(|(i, e)| *e = s0.energy[i] * c0 + (*e + dedt[i] * dt) * c1);
}

/// ρ ← c0·ρ0 + c1·(ρ + dt·dρ/dt), when the scheme evolves ρ (`ρ0` = `s0`).
fn combine_density<const D: usize>(sys: &mut System<D>, s0: &[f64], c0: f64, c1: f64, dt: f64) {
    if !sys.evolve_density {
        return;
    }
    let p = &mut sys.particles;
    p.rho
        .par_iter_mut()
        .zip(p.drhodt.par_iter())
        .enumerate()
        .with_min_len(LIGHT)
        .for_each(|(i, (r, d))| *r = s0[i] * c0 + (*r + d * dt) * c1);
}

/// ρ ← ρ_from + dt·dρ/dt (when the scheme evolves ρ).
fn kick_density<const D: usize>(sys: &mut System<D>, from: &[f64], dt: f64) {
    if !sys.evolve_density {
        return;
    }
    let p = &mut sys.particles;
    p.rho
        .par_iter_mut()
        .zip(p.drhodt.par_iter())
        .enumerate()
        .with_min_len(LIGHT)
        .for_each(|(i, (r, d))| *r = from[i] + d * dt);
}

/// The next evaluation sees the state at time t: driven particles take their state there
/// (`boundary::drive`), time-dependent boundary values (port pressures) their value.
fn stage_time<const D: usize>(sys: &mut System<D>, t: f64) -> Result<(), SchemeError> {
    sys.time = t;
    sys.apply_drives().map_err(SchemeError)
}

/// Wrap periodic and reflect mirrored coordinates; a reflection reverses the normal velocity
/// and, in SR runs, the normal component of S with it.
fn enforce_boundaries<const D: usize>(sys: &mut System<D>) {
    let dom = sys.domain;
    let p = &mut sys.particles;
    match sys.relativistic {
        None => p
            .pos
            .par_iter_mut()
            .zip(p.vel.par_iter_mut())
            .with_min_len(LIGHT)
            .for_each(|(x, v)| dom.enforce(x, v)),
        Some(sr) => p
            .pos
            .par_iter_mut()
            .zip(p.extra_vectors[sr.momentum].par_iter_mut())
            // S decides the direction; v is the previous stage's until the next evaluation
            // recovers it from S
            .with_min_len(LIGHT)
            .for_each(|(x, s)| dom.enforce(x, s)),
    }
}

impl<const D: usize> Integrator<D> {
    pub fn new(kind: IntegratorKind) -> Self {
        Self {
            kind,
            saved: Saved::default(),
        }
    }

    /// Advance by dt. On entry the particles hold the derivatives of the current state
    /// (for `crk-rk2`: of the previous midpoint) and `sys.time` is the end of the step; on
    /// exit those of the new state. Each evaluation sees its stage's time in `sys.time`.
    pub fn step(
        &mut self,
        sys: &mut System<D>,
        scheme: &mut dyn Scheme<D>,
        dt: f64,
    ) -> Result<(), SchemeError> {
        let t_end = sys.time;
        let t0 = t_end - dt;
        if sys.relativistic.is_some() && self.kind != IntegratorKind::SspRk3 {
            return Err(SchemeError(format!(
                "time.integrator: special-relativistic runs evolve S and ε with ssp-rk3 only, got {}",
                self.kind.name()
            )));
        }
        match self.kind {
            IntegratorKind::Leapfrog => {
                let half = 0.5 * dt;
                // kick + drift; keep v_half in `saved.vel`, u_half in `saved.u`, ρ_half in
                // `saved.rho`; ρ is predicted to the end of the step like u
                if sys.evolve_density {
                    self.saved.rho.clone_from(&sys.particles.rho);
                    kick_density(sys, &self.saved.rho, half);
                    self.saved.rho.clone_from(&sys.particles.rho);
                    kick_density(sys, &self.saved.rho, half);
                }
                {
                    let p = &mut sys.particles;
                    self.saved.vel.resize(p.len(), Vector::zeros());
                    self.saved.u.resize(p.len(), 0.0);
                    let (sv, su) = (&mut self.saved.vel, &mut self.saved.u);
                    p.pos
                        .par_iter_mut()
                        .zip(p.vel.par_iter_mut())
                        .zip(p.u.par_iter_mut())
                        .zip(sv.par_iter_mut().zip(su.par_iter_mut()))
                        .zip(p.acc.par_iter().zip(p.dudt.par_iter()))
                        .with_min_len(LIGHT)
                        .for_each(|((((x, v), u), (vh, uh)), (a, du))| {
                            *vh = *v + *a * half;
                            *uh = *u + *du * half;
                            *x += *vh * dt;
                            // predicted end-of-step values for the force evaluation
                            *v = *vh + *a * half;
                            *u = *uh + *du * half;
                        });
                }
                // A reflection flips the normal velocity: apply it to v_half as well.
                {
                    let dom = sys.domain;
                    let p = &mut sys.particles;
                    p.pos
                        .par_iter_mut()
                        .zip(p.vel.par_iter_mut())
                        .zip(self.saved.vel.par_iter_mut())
                        .with_min_len(LIGHT)
                        .for_each(|((x, v), vh)| {
                            let before = *v;
                            dom.enforce(x, v);
                            for k in 0..D {
                                if v[k] != before[k] {
                                    vh[k] = -vh[k];
                                }
                            }
                        });
                }
                sys.predict_h(dt);
                // KDK: the step's impulse is ½dt (F_n + F_n+1)
                sys.accumulate_impulse(half);
                stage_time(sys, t_end)?;
                scheme.evaluate(sys)?;
                sys.hold_constrained();
                sys.accumulate_impulse(half);
                kick_density(sys, &self.saved.rho, half);
                let p = &mut sys.particles;
                let (sv, su) = (&self.saved.vel, &self.saved.u);
                p.vel
                    .par_iter_mut()
                    .zip(p.u.par_iter_mut())
                    .enumerate()
                    .with_min_len(LIGHT)
                    .for_each(|(i, (v, u))| {
                        *v = sv[i] + p.acc[i] * half;
                        *u = su[i] + p.dudt[i] * half;
                    });
            }
            IntegratorKind::SspRk3 => {
                let mut s0 = std::mem::take(&mut self.saved);
                s0.save(sys);
                // predict_h: the stage times are t+dt, t+dt/2, t+dt.
                // Shu–Osher's three stages advance u0 by dt(⅙L0 + ⅙L1 + ⅔L2)
                sys.accumulate_impulse(dt / 6.0);
                combine(sys, &s0, 0.0, 1.0, dt);
                combine_density(sys, &s0.rho, 0.0, 1.0, dt);
                sys.predict_h(dt);
                stage_time(sys, t_end)?;
                scheme.evaluate(sys)?;
                sys.hold_constrained();
                sys.accumulate_impulse(dt / 6.0);
                combine(sys, &s0, 0.75, 0.25, dt);
                combine_density(sys, &s0.rho, 0.75, 0.25, dt);
                sys.predict_h(-0.5 * dt);
                stage_time(sys, t0 + 0.5 * dt)?;
                scheme.evaluate(sys)?;
                sys.hold_constrained();
                sys.accumulate_impulse(2.0 * dt / 3.0);
                combine(sys, &s0, 1.0 / 3.0, 2.0 / 3.0, dt);
                combine_density(sys, &s0.rho, 1.0 / 3.0, 2.0 / 3.0, dt);
                enforce_boundaries(sys);
                sys.predict_h(0.5 * dt);
                stage_time(sys, t_end)?;
                scheme.evaluate(sys)?;
                sys.hold_constrained();
                self.saved = s0;
            }
            IntegratorKind::CrkRk2 => {
                let mut s0 = std::mem::take(&mut self.saved);
                s0.save(sys);
                if scheme.pair_work().is_some() {
                    s0.save_entropy(sys);
                }
                // predictor to the midpoint with the previous (midpoint) derivatives
                combine(sys, &s0, 0.0, 1.0, 0.5 * dt);
                combine_density(sys, &s0.rho, 0.0, 1.0, 0.5 * dt);
                sys.predict_h(0.5 * dt);
                stage_time(sys, t0 + 0.5 * dt)?;
                scheme.evaluate(sys)?;
                sys.hold_constrained();
                // the full step uses the midpoint forces only
                sys.accumulate_impulse(dt);
                // full step from the start state with the midpoint derivatives
                let total_energy = scheme.pair_work().is_none() && scheme.total_energy();
                {
                    let p = &mut sys.particles;
                    let (acc, dudt, vmid) = (&p.acc, &p.dudt, p.vel.clone());
                    p.pos
                        .par_iter_mut()
                        .zip(p.vel.par_iter_mut())
                        .zip(p.u.par_iter_mut())
                        .enumerate()
                        .with_min_len(LIGHT)
                        .for_each(|(i, ((x, v), u))| {
                            *x = s0.pos[i] + vmid[i] * dt;
                            *v = s0.vel[i] + acc[i] * dt;
                            *u = s0.u[i] + dudt[i] * dt;
                            if total_energy {
                                // eq 80 by the midpoint rule: E¹ = E⁰ + Δt m(v_mid·a + du/dt),
                                // u¹ = E¹/m − ½|v¹|², i.e. u¹ = u⁰ + Δt du/dt
                                // + Δt (v_mid − (v⁰ + v¹)/2)·a
                                let v_half = (s0.vel[i] + *v) * 0.5;
                                *u += dt * (vmid[i] - v_half).dot(&acc[i]);
                            }
                        });
                }
                kick_density(sys, &s0.rho, dt);
                // driven particles at the step's end first: their v¹ enters v^{1/2} below
                stage_time(sys, t_end)?;
                if let Some(work) = scheme.pair_work() {
                    let p = &sys.particles;
                    let v_half: Vec<Vector<D>> = (0..p.len())
                        .into_par_iter()
                        .with_min_len(LIGHT)
                        .map(|i| (s0.vel[i] + p.vel[i]) * 0.5)
                        .collect();
                    let u1 = compatible::thermal_update(sys, work, &v_half, &s0.entropy, &s0.u, dt);
                    sys.particles.u = u1;
                }
                enforce_boundaries(sys);
                sys.predict_h(0.5 * dt);
                scheme.refresh(sys);
                // a refresh evaluates no forces: the bodies keep the midpoint loads (re-deriving
                // them from the walls' accelerations would read the rigid motion as a load)
                sys.particles.hold_frozen();
                self.saved = s0;
            }
        }
        Ok(())
    }
}
