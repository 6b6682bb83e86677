//! CRKSPH (Frontiere, Raskin & Owen 2017): linear reproducing kernels (§2.1, eqs 8–23),
//! mass-over-volume density (eq 76), the antisymmetrised momentum equation (§3.1, eq 64),
//! the thermal-energy derivative (eq 78) for interim values, the compatible energy update
//! (§3.3, see [`crate::scheme::compatible`]) for the final one, and the limited viscosity
//! (§3.2, eqs 45–55, 69–74).
//!
//! Decisions on the points the paper leaves open, made here and nowhere else (numbered items):
//! * h (item 8): the number-density form of the "simple, robust substitute",
//!   h_i = η V_i^{1/ν} with V_i = 1/Σ_j W(x_ij, h_i) (eq 75). At t = 0 it is solved by the
//!   Newton iteration of [`smoothing`] with weights X = 1; afterwards, as IdealH does, the
//!   midpoint evaluation computes h_ideal = η V^{1/ν} (one fixed-point step, the relation
//!   hardly depends on h) and the end-of-step state takes h¹ = h_ideal (Frontiere, Raskin & Owen (2017) §4 step 4).
//!   Like IdealH it depends on the point distribution only, not on masses, so an equally
//!   spaced multi-material lattice keeps one h (Frontiere, Raskin & Owen (2017) §4.2; App B).
//! * ρ: eq 76 at every evaluation (midpoint and end of step) by default. `density =
//!   "continuity"` evolves it by eq 79 from the case's initial ρ instead (App B's choice, and
//!   Spheral's IntegrateDensity); eq 76 is then not used.
//! * Integrator (item 7): `crk-rk2`, Spheral's CheapSynchronousRK2 (Frontiere, Raskin & Owen (2017) §4), CFL 0.25.
//! * Time step (§7.2): the scheme writes v_sig = η·max(c, √(Q_max/ρ), approach speed) and
//!   h|∇·v|, so the driver's C·h/v_sig is C·l/max(...) with the nodal spacing l = h/η.
//! * η_fold (item 9): the paper's 0.2; Q_j in the energy equation as printed (eq 78), not
//!   Spheral's ½(Q_i + Q_j).
//! * No XSPH (item 17).

pub mod forces;
mod gradient;
mod momentum;
pub mod pair_kernels;
pub mod reproducing;
pub mod viscosity;

use super::compatible::PairWork;
use super::paper_step;
use super::standard::{check_above, check_range, curl_norm, DensityMode};
use super::{smoothing, Scheme, SchemeError};
use crate::parallel::rows;
use crate::system::System;
use momentum::CrkMomentum;
use pair_kernels::{pair_kernels_and_volumes, PairKernel};
use reproducing::{coefficients_and_density, RkCoefficients, RkOrder};
use serde::{Deserialize, Serialize};
use viscosity::{velocity_gradients, ViscosityParams};

/// Reproducing order as written in case files.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize, Default)]
#[serde(rename_all = "kebab-case")]
pub enum OrderName {
    Zeroth,
    #[default]
    Linear,
}

/// Parameters of `[scheme] name = "crksph"`. Unset viscosity constants follow the kernel
/// (Frontiere, Raskin & Owen (2017) Table D.1): C_l = η_max/2, C_q = η_max/4 (W7: 2 and 1), η_crit = 1/n_h.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields, default)]
pub struct CrksphParams {
    /// Linear viscosity coefficient C_l, [0, 10].
    pub c_l: Option<f64>,
    /// Quadratic viscosity coefficient C_q, [0, 10].
    pub c_q: Option<f64>,
    /// ε² in μ's denominator, (0, 1].
    pub epsilon2: f64,
    /// Limiter closeness scale η_fold, (0, 2].
    pub eta_fold: f64,
    /// Van Leer limiter on the velocity jump (off: plain Monaghan–Gingold).
    pub limiter: bool,
    /// Reproducing order: linear (the paper) or zeroth (B ≡ 0).
    pub order: OrderName,
    /// Final u from the compatible update (§5) rather than from du/dt (eq 78).
    pub compatible_energy: bool,
    /// With `compatible_energy = false`: evolve each particle's total energy
    /// E_i = m_i(u_i + ½v_i²) by eq 80 and recover u from it, the alternative the paper
    /// compares in the Kidder test (§4.0.1); otherwise u follows du/dt (eq 78).
    pub total_energy: bool,
    /// ρ by eq 76 at every evaluation (summation, the paper's), or evolved by the continuity
    /// equation, eq 79, with ∇·v from eq 54 (continuity: Spheral's IntegrateDensity, which
    /// the paper's App B box uses throughout).
    pub density: DensityMode,
}

impl Default for CrksphParams {
    fn default() -> Self {
        Self {
            c_l: None,
            c_q: None,
            epsilon2: 1e-2,
            eta_fold: 0.2,
            limiter: true,
            order: OrderName::Linear,
            compatible_energy: true,
            total_energy: false,
            density: DensityMode::Summation,
        }
    }
}

impl CrksphParams {
    pub fn validate(&self) -> Result<(), String> {
        if let Some(c) = self.c_l {
            check_range("scheme.c_l", c, 0.0, 10.0)?;
        }
        if let Some(c) = self.c_q {
            check_range("scheme.c_q", c, 0.0, 10.0)?;
        }
        check_above("scheme.epsilon2", self.epsilon2, 0.0, 1.0)?;
        check_above("scheme.eta_fold", self.eta_fold, 0.0, 2.0)?;
        if self.total_energy && self.compatible_energy {
            return Err("scheme.total_energy: needs scheme.compatible_energy = false (they are the two alternative energy updates of Frontiere, Raskin & Owen (2017) §3.3 and eq 80)".into());
        }
        Ok(())
    }

    /// Viscosity constants for a kernel of native support `eta_max` run at our η.
    pub fn viscosity(&self, eta_max: f64, eta: f64) -> ViscosityParams {
        // n_h = 2η/η_max (kernel module doc); η_crit = 1/n_h (Frontiere, Raskin & Owen (2017) §3.2; eqs 45–55; 69–74)
        let n_h = 2.0 * eta / eta_max;
        ViscosityParams {
            c_l: self.c_l.unwrap_or(0.5 * eta_max),
            c_q: self.c_q.unwrap_or(0.25 * eta_max),
            eps2: self.epsilon2,
            eta_crit: 1.0 / n_h,
            eta_fold: self.eta_fold,
            native_support: eta_max,
            limiter: self.limiter,
        }
    }
}

pub struct Crksph<const D: usize> {
    params: CrksphParams,
    visc: ViscosityParams,
    order: RkOrder,
    work: PairWork<D>,
    ones: Vec<f64>,
    /// h_ideal of the latest evaluation, for the end-of-step state (empty: solve h).
    h_next: Vec<f64>,
}

impl<const D: usize> Crksph<D> {
    pub fn new(params: CrksphParams) -> Self {
        Self {
            params,
            visc: ViscosityParams::default(),
            order: match params.order {
                OrderName::Linear => RkOrder::Linear,
                OrderName::Zeroth => RkOrder::Zeroth,
            },
            work: PairWork::default(),
            ones: vec![],
            h_next: vec![],
        }
    }

    /// h and V (eq 75), the correction coefficients, ρ (eq 76) and the EOS (Frontiere, Raskin & Owen (2017) steps 1–4).
    #[allow(clippy::type_complexity)]
    fn state(
        &mut self,
        sys: &mut System<D>,
        solve_h: bool,
    ) -> (Vec<f64>, Vec<RkCoefficients<D>>, Vec<PairKernel>) {
        let n = sys.particles.len();
        // A distributed run refreshes the halo between the passes below (`parallel::refresh`):
        // each reads of its neighbours what the previous one computed.
        let sync = sys.halo_sync();
        if solve_h {
            self.ones.resize(n, 1.0);
            // the solve writes its own ρ; an evolved ρ starts from the case's
            let evolved =
                (self.params.density == DensityMode::Continuity).then(|| sys.particles.rho.clone());
            smoothing::solve_density_and_h_weighted(sys, Some(&self.ones), true);
            if let Some(rho) = evolved {
                sys.particles.rho = rho;
            }
            smoothing::refresh_halo_after_solve(sys, true);
        } else {
            // (h from h_next, which the halo computes from refreshed V and h as its owners do)
            smoothing::update_lists(sys);
        }
        let t0 = std::time::Instant::now();
        let slots = sys.scratch.take();
        let (kern, mut vol) = pair_kernels_and_volumes(sys, slots);
        // the coefficients read the neighbours' V (eq 75)
        sync.refresh(vec![rows(&mut vol)]);
        // h_ideal = η V^{1/ν}, at most 25 % from the current h per step (IdealH relaxes too)
        let (eta, h_max) = (sys.eta, sys.h_max);
        let p = &sys.particles;
        self.h_next = (0..n)
            .map(|i| {
                if p.body[i] != 0 || p.port[i] != 0 {
                    return p.h[i]; // wall and buffer particles keep the h they were given
                }
                (eta * vol[i].powf(1.0 / D as f64))
                    .clamp(0.8 * p.h[i], 1.25 * p.h[i])
                    .min(h_max)
            })
            .collect();
        let state = coefficients_and_density(sys, &vol, &kern, self.order);
        sys.stats.ia_fallbacks = state.fallbacks;
        sys.stats.ia_fallbacks_total += state.fallbacks;
        if self.params.density == DensityMode::Summation {
            sys.particles.rho = state.rho;
        }
        let mut coef = state.coef;
        // the gradients and forces read the neighbours' corrections and ρ (P and c follow)
        sync.refresh(vec![rows(&mut coef), rows(&mut sys.particles.rho)]);
        sys.update_eos();
        sys.stats.total_pairs += 2 * sys.neighbours.total_pairs() as u64;
        sys.stats.seconds_density += t0.elapsed().as_secs_f64();
        (vol, coef, kern)
    }
}

impl<const D: usize> Scheme<D> for Crksph<D> {
    fn name(&self) -> &'static str {
        "crksph"
    }

    fn init(&mut self, sys: &mut System<D>) {
        // wall particles need full neighbourhoods for their volumes (eq 75) and reproducing
        // coefficients; the force pass skips wall–wall pairs
        sys.wall_pairs = true;
        sys.evolve_density = self.params.density == DensityMode::Continuity;
        self.visc = self
            .params
            .viscosity(sys.kernel.kernel.native_support(), sys.eta);
    }

    fn evaluate(&mut self, sys: &mut System<D>) -> Result<(), SchemeError> {
        // Newton solve for h only when no h_ideal exists yet (the first evaluation). Not "when
        // the particle count changed": ports change it, and so does a distributed run's halo
        // at every step, which made the solve (and so the particles) depend on the ranks.
        let first = self.h_next.is_empty();
        let (vol, coef, kern) = self.state(sys, first);
        let t0 = std::time::Instant::now();
        let mut grads = velocity_gradients(sys, &vol, &coef, &kern);
        // the limited viscosity reads the neighbours' velocity gradients
        sys.halo_sync().refresh(vec![rows(&mut grads)]);
        {
            let p = &mut sys.particles;
            for (i, g) in grads.iter().enumerate() {
                p.div_v[i] = g.trace();
                p.curl_v[i] = curl_norm(g);
                // eq 79, Dρ_i/Dt = −ρ_i ∂α v_i^α (read by the integrator only with
                // density = "continuity")
                p.drhodt[i] = -p.rho[i] * p.div_v[i];
            }
        }
        sys.stats.total_pairs += sys.neighbours.total_pairs() as u64;
        sys.stats.seconds_gradients += t0.elapsed().as_secs_f64();

        let t0 = std::time::Instant::now();
        let mut work = std::mem::take(&mut self.work);
        work.reset(sys);
        let out = sys.with_scratch(|sys, scratch| {
            CrkMomentum {
                sys,
                vol: &vol,
                coef: &coef,
                kern: &kern,
                grads: &grads,
                visc: self.visc,
            }
            .run(&mut work.acc, scratch)
        });
        sys.scratch.keep(kern);
        self.work = work;
        paper_step::store(sys, t0, &out);
        super::compatible::refresh_halo_accelerations(sys);
        Ok(())
    }

    /// One support: `evaluate` refreshes the halo's V, corrections, ρ, velocity gradients
    /// and accelerations between its passes (and h after a Newton solve).
    fn halo_depth(&self) -> usize {
        1
    }

    fn refresh(&mut self, sys: &mut System<D>) {
        let solve = self.h_next.len() != sys.particles.len();
        if !solve {
            sys.particles.h.clone_from(&self.h_next);
        }
        let (_, _, kern) = self.state(sys, solve);
        sys.scratch.keep(kern);
    }

    fn pair_work(&self) -> Option<&PairWork<D>> {
        self.params.compatible_energy.then_some(&self.work)
    }

    fn total_energy(&self) -> bool {
        self.params.total_energy
    }
}
