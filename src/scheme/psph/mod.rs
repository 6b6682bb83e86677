//! Pressure–energy SPH, PSPH (Frontiere, Raskin & Owen (2017) App G; Hopkins 2015 App F2; after DISPH, App G; Hopkins 2015 after Saitoh & Makino's
//! DISPH), with the Cullen–Dehnen switch and Hopkins' artificial conductivity:
//!
//!   P_i = Σ_j (γ−1) m_j u_j W_i,  ρ_i = Σ_j m_j W_i,  n_i = Σ_j W_i   (G.1–G.3, self included)
//!   a_i = −Σ_j m_j [(γ−1)² u_i u_j (f_ij/P_i ∇W_i + f_ji/P_j ∇W_j) + q_ij]     (G.4)
//!   du_i/dt = Σ_j m_j (γ−1)² u_i u_j (f_ij/P_i) v_ij·∇W_i + ½ Σ_j m_j v_ij·q_ij + conduction
//!
//! with W_i = W(x_ij, h_i), the grad-h factor f_ij of G.7–G.9 and q_ij of G.6.
//! Decisions (Frontiere, Raskin & Owen (2017), a point the paper leaves open (decided here) and gaps), made here:
//! * G.4 pairs f_ij with P_i and ∇W_i ([R]); q_ij sits inside the m_j sum.
//! * Π_i = Q_i/ρ_i² from the unlimited Monaghan–Gingold Q of Frontiere, Raskin & Owen (2017) §3.2; eqs 45–55; 69–74 with C_l,ij = ½(α_i+α_j)C_l
//!   (and C_q alike), so q_ij = ½(Q_i/ρ_i + Q_j/ρ_j)(∇W_i + ∇W_j)/(ρ_i + ρ_j). Base C_l = η_max/2,
//!   C_q = η_max/4 (Frontiere, Raskin & Owen (2017) Table D.1's scaling; 0.5 and 0.25 for the PSPH quintic).
//! * The paper evolves the total energy (G.5) so that energy is conserved to round-off. We get
//!   the same with the compatible update of the CRKSPH paper (§3.3, eqs 56–68): the final stage
//!   keeps each pair force a_ij and u¹ comes from the pair work, split by entropy. Integrating
//!   the u equation above instead lost 2.3 % of the total energy over Sedov 2D (100² quadrant).
//!   The conduction is an exchange, m_i du_i = −m_j du_j, and is added as it is.
//! * Conduction (G.10–G.12) projects ∇W_i + ∇W_j on x̂_ij ([R]); α_C = 0.25.
//! * h from the number density: h = η n^{−1/ν} (Hopkins' choice for PSPH), solved by Newton.
//! * f_ij = 1 where m_j u_j = 0 (cold gas: the G.7 correction is undefined there).

use super::compatible::PairWork;
use super::cullen::{CullenDehnen, CullenParams};
use super::paper_step;
use super::standard::{check_above, check_range};
use super::{smoothing, Scheme, SchemeError};
use crate::system::System;
use serde::{Deserialize, Serialize};

mod force;

/// Parameters of `[scheme] name = "psph"`.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields, default)]
pub struct PsphParams {
    /// Base linear viscosity coefficient (default η_max/2 of the kernel), [0, 10].
    pub c_l: Option<f64>,
    /// Base quadratic coefficient (default η_max/4), [0, 10].
    pub c_q: Option<f64>,
    /// ε² in μ's denominator, (0, 1].
    pub epsilon2: f64,
    /// Artificial conductivity α_C (0 = off, App B's box test), [0, 5].
    pub conductivity: f64,
}

impl Default for PsphParams {
    fn default() -> Self {
        Self {
            c_l: None,
            c_q: None,
            epsilon2: 1e-2,
            conductivity: 0.25,
        }
    }
}

impl PsphParams {
    pub fn validate(&self) -> Result<(), String> {
        if let Some(c) = self.c_l {
            check_range("scheme.c_l", c, 0.0, 10.0)?;
        }
        if let Some(c) = self.c_q {
            check_range("scheme.c_q", c, 0.0, 10.0)?;
        }
        check_range("scheme.conductivity", self.conductivity, 0.0, 5.0)?;
        check_above("scheme.epsilon2", self.epsilon2, 0.0, 1.0)?;
        Ok(())
    }
}

pub struct Psph<const D: usize> {
    params: PsphParams,
    /// pair forces of the last evaluation, for the compatible energy update
    work: PairWork<D>,
    gamma: f64,
    cullen: Option<CullenDehnen>,
    visc: super::crksph::viscosity::ViscosityParams,
    ones: Vec<f64>,
    /// C_i of f_ij = 1 − C_i/(m_j u_j) (G.7), per particle
    fcoef: Vec<f64>,
}

impl<const D: usize> Psph<D> {
    pub fn new(params: PsphParams) -> Self {
        Self {
            params,
            work: PairWork::default(),
            gamma: 5.0 / 3.0,
            cullen: None,
            visc: Default::default(),
            ones: vec![],
            fcoef: vec![],
        }
    }

    /// h from the number density, then ρ, P (G.1–G.2) and the f_ij coefficients (G.7–G.9).
    fn state(&mut self, sys: &mut System<D>) {
        let n = sys.particles.len();
        self.ones.resize(n, 1.0);
        let g1 = self.gamma - 1.0;
        // (m_j, (γ−1) m_j u_j): ρ, P and ∂P/∂h ride on the h solve's last kernel values
        let weights: Vec<[f64; 2]> = {
            let p = &sys.particles;
            (0..n)
                .map(|j| [p.mass[j], g1 * p.mass[j] * p.u[j]])
                .collect()
        };
        let sums = smoothing::solve_density_and_h_with_sums(sys, Some(&self.ones), true, &weights);
        let t0 = std::time::Instant::now();
        let d = D as f64;
        let gamma = self.gamma;
        let p = &mut sys.particles;
        self.fcoef.resize(n, 0.0);
        for (i, s) in sums.iter().enumerate() {
            let [rho, pres, _, dp_dh] = *s;
            // n is the solve's κ (X = 1: ρ_solve = m κ), and 1 + (h/(ν n)) ∂n/∂h its Ω
            let (num, omega) = (p.rho[i] / p.mass[i], p.omega[i]);
            p.rho[i] = rho;
            p.pressure[i] = pres;
            p.sound_speed[i] = (gamma * pres.max(0.0) / rho).sqrt();
            let h = p.h[i];
            // G.7: f_ij = 1 − [h/(ν(γ−1) n m_j u_j)] ∂P/∂h [1 + (h/(ν n)) ∂n/∂h]⁻¹
            self.fcoef[i] = h * dp_dh / (d * g1 * num) / omega;
        }
        // (no pair pass here: the h solve counted its pairs)
        sys.stats.seconds_density += t0.elapsed().as_secs_f64();
        // the force reads the neighbours' P, c and f_ij coefficients (G.7), h, ρ and Ω
        let (sync, p) = (sys.halo_sync(), &mut sys.particles);
        sync.refresh(vec![
            crate::parallel::rows(&mut p.pressure),
            crate::parallel::rows(&mut p.sound_speed),
            crate::parallel::rows(&mut self.fcoef),
        ]);
        smoothing::refresh_halo_after_solve(sys, true);
        sys.apply_boundary_conditions();
    }
}

impl<const D: usize> Scheme<D> for Psph<D> {
    fn name(&self) -> &'static str {
        "psph"
    }

    fn init(&mut self, sys: &mut System<D>) {
        self.gamma = crate::eos::Eos::gamma(&sys.eos);
        // wall particles need full neighbourhoods for their pressure sums and f coefficients
        // (G.7); the force pass skips wall–wall pairs
        sys.wall_pairs = true;
        let eta_max = sys.kernel.kernel.native_support();
        self.visc = super::crksph::viscosity::ViscosityParams {
            c_l: self.params.c_l.unwrap_or(0.5 * eta_max),
            c_q: self.params.c_q.unwrap_or(0.25 * eta_max),
            eps2: self.params.epsilon2,
            native_support: eta_max,
            limiter: false,
            ..Default::default()
        };
        self.cullen = Some(CullenDehnen::init(sys, CullenParams::default()));
    }

    fn evaluate(&mut self, sys: &mut System<D>) -> Result<(), SchemeError> {
        self.state(sys);
        if let Some(cd) = &self.cullen {
            cd.measure(sys);
        }
        let t0 = std::time::Instant::now();
        let mut work = std::mem::take(&mut self.work);
        work.reset(sys);
        let out = sys.with_scratch(|sys, scratch| {
            force::PsphForce {
                sys,
                fcoef: &self.fcoef,
                gamma: self.gamma,
                visc: self.visc,
                alpha_c: self.params.conductivity,
            }
            .run(&mut work.acc, scratch)
        });
        work.exchange = out.iter().map(|o| o.exchange).collect();
        self.work = work;
        paper_step::store(sys, t0, &out);
        super::compatible::refresh_halo_accelerations(sys);
        Ok(())
    }

    fn refresh(&mut self, sys: &mut System<D>) {
        self.state(sys);
    }

    /// One support: `state` refreshes the halo's h, ρ, Ω, P, c and f_ij, the switch's
    /// measure its ∇·v, and `evaluate` a with du/dt after the forces.
    fn halo_depth(&self) -> usize {
        1
    }

    fn end_step(&mut self, sys: &mut System<D>, dt: f64) {
        if let Some(cd) = &self.cullen {
            cd.end_step(sys, dt);
        }
    }

    fn pair_work(&self) -> Option<&PairWork<D>> {
        Some(&self.work)
    }
}
