//! Compatible SPH, "compSPH" (Frontiere, Raskin & Owen (2017) App E, App E; Owen 2014): grad-h summation density,
//!
//!   a_ij = −m_j [ P_i/(Ω_iρ_i²) ∇W_i + P_j/(Ω_jρ_j²) ∇W_j + ½(Π_i ∇W_i + Π_j ∇W_j) ]   (E.2)
//!   du_i/dt = Σ_j m_j [P_i/(Ω_iρ_i²) + ½Π_i] v_ij·∇W_i                               (E.3)
//!
//! with ∇W_i = ∇_i W(x_ij, h_i), Π_i = Q_i/ρ_i² the *unlimited* Monaghan–Gingold pressure of
//! Frontiere, Raskin & Owen (2017) §3.2; eqs 45–55; 69–74 per side (E.7–E.9), and the final u from the compatible update with the entropy
//! weights (Frontiere, Raskin & Owen (2017) §3.3; eqs 56–68) — interim u from E.3. The E.1–E.6 text was lost in the paper's extraction;
//! this is the standard form of compatible SPH, rebuilt here (an open point, decided here). With `cullen_dehnen` the
//! coefficients become C_l,ij = ½(α_i + α_j) C_l (and C_q alike) from [`super::cullen`].
//! The paper's kernel: W5 (our quintic spline M6, native support 3) with n_h = 4/3, η = 2.

use super::compatible::PairWork;
use super::crksph::viscosity::{pair_q, ViscosityParams};
use super::cullen::{CullenDehnen, CullenParams};
use super::paper_step::{self, PairSums};
use super::standard::{check_above, check_range};
use super::{smoothing, Scheme, SchemeError};
use crate::system::System;
use nalgebra::SMatrix;
use serde::{Deserialize, Serialize};

/// Parameters of `[scheme] name = "compsph"` / `"compsph-cullen"`.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields, default)]
pub struct CompsphParams {
    /// C_l, [0, 10] (paper: 1).
    pub c_l: f64,
    /// C_q, [0, 10] (paper: 1).
    pub c_q: f64,
    /// ε² in μ's denominator, (0, 1].
    pub epsilon2: f64,
    /// Final u from the compatible update (else from du/dt, E.3).
    pub compatible_energy: bool,
}

impl Default for CompsphParams {
    fn default() -> Self {
        Self {
            c_l: 1.0,
            c_q: 1.0,
            epsilon2: 1e-2,
            compatible_energy: true,
        }
    }
}

impl CompsphParams {
    pub fn validate(&self) -> Result<(), String> {
        check_range("scheme.c_l", self.c_l, 0.0, 10.0)?;
        check_range("scheme.c_q", self.c_q, 0.0, 10.0)?;
        check_above("scheme.epsilon2", self.epsilon2, 0.0, 1.0)?;
        Ok(())
    }
}

pub struct Compsph<const D: usize> {
    params: CompsphParams,
    cullen: Option<CullenDehnen>,
    with_cullen: bool,
    native_support: f64,
    work: PairWork<D>,
}

impl<const D: usize> Compsph<D> {
    pub fn new(params: CompsphParams, cullen: bool) -> Self {
        Self {
            params,
            cullen: None,
            with_cullen: cullen,
            native_support: 3.0,
            work: PairWork::default(),
        }
    }
}

impl<const D: usize> Scheme<D> for Compsph<D> {
    fn name(&self) -> &'static str {
        if self.with_cullen {
            "compsph-cullen"
        } else {
            "compsph"
        }
    }

    fn init(&mut self, sys: &mut System<D>) {
        self.native_support = sys.kernel.kernel.native_support();
        if self.with_cullen {
            self.cullen = Some(CullenDehnen::init(sys, CullenParams::default()));
        } else {
            sys.particles.alpha.iter_mut().for_each(|a| *a = 1.0);
        }
    }

    fn evaluate(&mut self, sys: &mut System<D>) -> Result<(), SchemeError> {
        smoothing::solve_density_and_h(sys);
        smoothing::refresh_halo_after_solve(sys, true);
        sys.update_eos();
        match &self.cullen {
            Some(cd) => cd.measure(sys),
            None => plain_divergence(sys),
        }
        let t0 = std::time::Instant::now();
        let n = sys.particles.len();
        let mut out = vec![PairSums::<D>::default(); n];
        let mut work = std::mem::take(&mut self.work);
        work.reset(sys);
        let base = ViscosityParams {
            c_l: self.params.c_l,
            c_q: self.params.c_q,
            eps2: self.params.epsilon2,
            native_support: self.native_support,
            limiter: false,
            ..ViscosityParams::default()
        };
        {
            let p = &sys.particles;
            let k = &sys.kernel;
            let pterm: Vec<f64> = (0..n)
                .map(|i| p.pressure[i] / (p.omega[i] * p.rho[i] * p.rho[i]))
                .collect();
            let zero = SMatrix::<f64, D, D>::zeros();
            sys.gather_pairs(&mut out, &mut work.acc, |i, o, slot, pr| {
                if pr.r <= 0.0 {
                    return;
                }
                let j = pr.b;
                let rhat = pr.dx / pr.r;
                let gi = rhat * k.dwdr(pr.r, p.h[i]);
                let gj = rhat * k.dwdr(pr.r, p.h[j]);
                let vij = p.vel[i] - pr.vb;
                let mut visc = base;
                let a = 0.5 * (p.alpha[i] + p.alpha[j]);
                visc.c_l *= a;
                visc.c_q *= a;
                let (qi, qj) = pair_q(
                    &visc,
                    &pr.dx,
                    &vij,
                    &zero,
                    &zero,
                    (p.h[i], p.rho[i], p.sound_speed[i]),
                    (p.h[j], p.rho[j], p.sound_speed[j]),
                );
                let (pi_i, pi_j) = (qi / (p.rho[i] * p.rho[i]), qj / (p.rho[j] * p.rho[j]));
                let m_j = p.mass[j];
                // E.2 and E.3
                let a_ij = -(gi * (pterm[i] + 0.5 * pi_i) + gj * (pterm[j] + 0.5 * pi_j)) * m_j;
                *slot = a_ij;
                o.acc += a_ij;
                o.dudt += m_j * (pterm[i] + 0.5 * pi_i) * vij.dot(&gi);
                // Frontiere, Raskin & Owen (2017) (compSPH: 1×Q)
                o.q_max = o.q_max.max(qi);
                o.approach = o.approach.max(-vij.dot(&rhat));
            });
        }
        self.work = work;
        paper_step::store(sys, t0, &out);
        super::compatible::refresh_halo_accelerations(sys);
        Ok(())
    }

    /// One support: the halo's h, ρ and Ω are refreshed after the h solve, ∇·v inside the
    /// switch's measure, and a with du/dt after the forces.
    fn halo_depth(&self) -> usize {
        1
    }

    fn end_step(&mut self, sys: &mut System<D>, dt: f64) {
        if let Some(cd) = &self.cullen {
            cd.end_step(sys, dt);
        }
    }

    fn pair_work(&self) -> Option<&PairWork<D>> {
        self.params.compatible_energy.then_some(&self.work)
    }
}

/// ∇·v = −(1/(Ωρ)) Σ_j m_j v_ij·∇W_i (for the time step and the h prediction).
fn plain_divergence<const D: usize>(sys: &mut System<D>) {
    let n = sys.particles.len();
    let mut div = vec![0.0; n];
    {
        let p = &sys.particles;
        let k = &sys.kernel;
        sys.gather(&mut div, |i, d, pr| {
            if pr.r > 0.0 {
                let gw = pr.dx * (k.dwdr(pr.r, p.h[i]) / pr.r);
                *d += p.mass[pr.b] * (p.vel[i] - pr.vb).dot(&gw);
            }
        });
    }
    let p = &mut sys.particles;
    for (i, d) in div.into_iter().enumerate() {
        p.div_v[i] = -d / (p.omega[i] * p.rho[i]);
    }
}
