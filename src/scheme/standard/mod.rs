//! "Traditional" SPH, the baseline every paper compares with (Rosswog (2015) with X = m;
//! Price 2012 review): grad-h momentum and energy equations, Monaghan–Gingold artificial
//! viscosity with the Balsara (1995) switch, optional Price (2008) artificial conductivity.
//!
//!   dv_a/dt = −Σ_b m_b [ P_a/(Ω_a ρ_a²) ∇_a W_ab(h_a) + P_b/(Ω_b ρ_b²) ∇_a W_ab(h_b) ]
//!             − Σ_b m_b Π_ab ∇̄_a W_ab + g
//!   du_a/dt =  P_a/(Ω_a ρ_a²) Σ_b m_b v_ab·∇_a W_ab(h_a) + ½ Σ_b m_b Π_ab v_ab·∇̄_a W_ab
//!             + Σ_b m_b α_u v_sig,u (u_a − u_b) F̄_ab / ρ̄_ab
//!
//! with ∇̄W = ½[∇W(h_a) + ∇W(h_b)], F̄_ab = r̂_ab·∇̄_a W_ab (≤ 0), and for approaching pairs
//! (v_ab·r_ab < 0): μ_ab = h̄ v_ab·r_ab/(r_ab² + ε h̄²), Π_ab = (−α c̄ μ + β μ²)/ρ̄ · f̄_Balsara.
//! Every pair term is evaluated from the same expression in a's and b's loops with dx
//! negated, so Σ m_a dv_a/dt = 0 to round-off and the energy pair terms cancel likewise.

mod force;

pub(crate) use force::{force_pass, PressureForm};

use super::{smoothing, Scheme, SchemeError};
use crate::kernel::{DimKernel, Kernel, KernelVisitor};
use crate::neighbours::cut::{CutBlock, CutVisitor};
use crate::neighbours::lanes::LANES;
use crate::parallel::rows;
use crate::system::System;
use crate::threads::LIGHT;
use rayon::prelude::*;
use serde::{Deserialize, Serialize};

/// Parameters of `[scheme] name = "standard"`.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields, default)]
pub struct StandardParams {
    /// Linear viscosity coefficient α (Monaghan–Gingold), [0, 10].
    pub alpha: f64,
    /// Quadratic viscosity coefficient β, [0, 20].
    pub beta: f64,
    /// Balsara shear switch on the viscosity.
    pub balsara: bool,
    /// Artificial-conductivity coefficient α_u (0 = off), [0, 5].
    pub conductivity: f64,
    /// ε in μ_ab's denominator, (0, 1].
    pub epsilon: f64,
    /// Per-particle α from the Cullen–Dehnen switch (replaces Balsara; α and β both scale
    /// with ½(α_a + α_b), Frontiere, Raskin & Owen (2017) App F).
    pub cullen_dehnen: bool,
    /// Density by summation (default) or evolved by the continuity equation
    /// dρ_a/dt = Σ_b m_b v_ab·∇_a W_ab(h_a) with h_a = η (m_a/ρ_a)^{1/D} — the usual choice for
    /// liquids with a free surface, where a summation misses the mass beyond the surface.
    pub density: DensityMode,
    /// Kinematic viscosity ν (m²/s) of the laminar term of Morris, Fox & Zhu (1997, eq. 8):
    /// dv_a/dt += Σ_b m_b (μ_a + μ_b)/(ρ_a ρ_b) · x_ab·∇_a W_ab/(r² + 0.01 h̄²) · v_ab with
    /// μ = ρν, beside the artificial viscosity; 0 = off, [0, 1e3]. Walls take part with the
    /// velocity of `Particles::vel_wall` (no-slip bodies) or not at all (free slip).
    pub viscosity: f64,
    /// δ of the density-diffusion term (δ-SPH, Molteni & Colagrossi 2009, eq. 9) added to the
    /// continuity equation: dρ_a/dt += δ h̄ c̄ Σ_b V_b ψ_ab·∇_a W_ab, ψ_ab = 2 (ρ_ba − ρ^H_ba)
    /// x_ba/r², with the hydrostatic part ρ^H_ba = ρ_a g·x_ba / c_a² taken out (the
    /// correction of Fourtakas et al. 2019, linearised in g·x/c², so a liquid at rest under
    /// gravity is left alone). Fluid–fluid pairs only. 0 = off (default), [0, 1]; only with
    /// `density = "continuity"`.
    pub delta: f64,
}

/// How standard SPH gets ρ.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize, Default)]
#[serde(rename_all = "kebab-case")]
pub enum DensityMode {
    #[default]
    Summation,
    Continuity,
}

impl Default for StandardParams {
    fn default() -> Self {
        Self {
            alpha: 1.0,
            beta: 2.0,
            balsara: true,
            conductivity: 0.0,
            epsilon: 0.01,
            cullen_dehnen: false,
            density: DensityMode::Summation,
            viscosity: 0.0,
            delta: 0.0,
        }
    }
}

/// `v` in (lo, hi]: finite, above `lo`, at most `hi`; the error names the key and the range.
pub(crate) fn check_above(key: &str, v: f64, lo: f64, hi: f64) -> Result<(), String> {
    if v > lo && v <= hi {
        Ok(())
    } else {
        Err(format!("{key}: must be in ({lo}, {hi}], got {v}"))
    }
}

pub(crate) fn check_range(key: &str, v: f64, lo: f64, hi: f64) -> Result<(), String> {
    if v.is_finite() && v >= lo && v <= hi {
        Ok(())
    } else {
        Err(format!("{key}: must be in [{lo}, {hi}], got {v}"))
    }
}

impl StandardParams {
    pub fn validate(&self) -> Result<(), String> {
        check_range("scheme.alpha", self.alpha, 0.0, 10.0)?;
        check_range("scheme.beta", self.beta, 0.0, 20.0)?;
        check_range("scheme.conductivity", self.conductivity, 0.0, 5.0)?;
        check_range("scheme.viscosity", self.viscosity, 0.0, 1e3)?;
        check_range("scheme.delta", self.delta, 0.0, 1.0)?;
        if self.delta > 0.0 && self.density != DensityMode::Continuity {
            return Err(format!(
                "scheme.delta: density diffusion needs density = \"continuity\", got delta = {} with summation density",
                self.delta
            ));
        }
        check_above("scheme.epsilon", self.epsilon, 0.0, 1.0)
    }
}

pub struct StandardSph {
    params: StandardParams,
    /// Standard grad-h pressure force, or rpSPH's relative-pressure form (see `rpsph`).
    form: PressureForm,
    name: &'static str,
    /// Slot of the Balsara factor in `extra_scalars`.
    balsara_slot: usize,
    cullen: Option<super::cullen::CullenDehnen>,
}

impl StandardSph {
    pub fn new(params: StandardParams) -> Self {
        Self::with_form(params, PressureForm::GradH, "standard")
    }

    pub(crate) fn with_form(
        params: StandardParams,
        form: PressureForm,
        name: &'static str,
    ) -> Self {
        Self {
            params,
            form,
            name,
            balsara_slot: usize::MAX,
            cullen: None,
        }
    }
}

#[derive(Clone, Copy)]
struct GradAcc<const D: usize> {
    div: f64,
    /// Σ m_b v_ab ⊗ ∇W, the velocity-gradient sum (curl from its antisymmetric part).
    grad: nalgebra::SMatrix<f64, D, D>,
    /// 1/h_a, set before the pair loop (no division per pair).
    hinv: f64,
}

impl<const D: usize> GradAcc<D> {
    fn new(h: f64) -> Self {
        Self {
            div: 0.0,
            grad: nalgebra::SMatrix::zeros(),
            hinv: 1.0 / h,
        }
    }
}

/// |∇×v| from the velocity-gradient tensor (2D: |∂v_y/∂x − ∂v_x/∂y|; 1D: 0).
pub(crate) fn curl_norm<const D: usize>(g: &nalgebra::SMatrix<f64, D, D>) -> f64 {
    match D {
        2 => (g[(1, 0)] - g[(0, 1)]).abs(),
        3 => {
            let cx = g[(2, 1)] - g[(1, 2)];
            let cy = g[(0, 2)] - g[(2, 0)];
            let cz = g[(1, 0)] - g[(0, 1)];
            (cx * cx + cy * cy + cz * cz).sqrt()
        }
        _ => 0.0,
    }
}

impl<const D: usize> Scheme<D> for StandardSph {
    fn name(&self) -> &'static str {
        self.name
    }

    /// h and ρ (neighbours' positions), the working list's cut (their h), then the velocity
    /// gradients on the cut rows, and the force (their ρ, P, Ω and Balsara factors).
    /// `evaluate` refreshes the halo's h, ρ, Ω and Balsara factors between those passes (the
    /// Cullen–Dehnen switch its ∇·v), so one support is deep enough.
    fn halo_depth(&self) -> usize {
        1
    }

    fn init(&mut self, sys: &mut System<D>) {
        sys.evolve_density = self.params.density == DensityMode::Continuity;
        self.balsara_slot = sys.particles.add_scalar_field(1.0);
        if self.params.cullen_dehnen {
            self.cullen = Some(super::cullen::CullenDehnen::init(
                sys,
                super::cullen::CullenParams::default(),
            ));
        } else {
            let alpha = self.params.alpha;
            sys.particles.alpha.iter_mut().for_each(|a| *a = alpha);
        }
    }

    fn end_step(&mut self, sys: &mut System<D>, dt: f64) {
        if let Some(cd) = &self.cullen {
            cd.end_step(sys, dt);
        }
    }

    fn evaluate(&mut self, sys: &mut System<D>) -> Result<(), SchemeError> {
        match self.params.density {
            DensityMode::Summation => {
                smoothing::solve_density_and_h_weighted(sys, None, false);
                // the cut reads the neighbours' h, the force their ρ and Ω (with an evolved
                // ρ they come from the halo's own fields, refreshed whole before this pass)
                smoothing::refresh_halo_after_solve(sys, false);
            }
            DensityMode::Continuity => continuity_h(sys),
        }
        match &self.cullen {
            // the Balsara factor stays 1: the switch limits shear itself
            Some(cd) => {
                sys.compact_neighbours();
                sys.update_eos();
                cd.measure(sys);
            }
            None => {
                let grads = cut_lists_with_gradient_sums(sys);
                sys.update_eos();
                let t0 = std::time::Instant::now();
                finish_gradients(sys, &grads, self.balsara_slot, self.params.balsara);
                sys.scratch.keep(grads);
                sys.stats.seconds_gradients += t0.elapsed().as_secs_f64();
                // the force reads the neighbours' Balsara factors
                let (sync, p) = (sys.halo_sync(), &mut sys.particles);
                sync.refresh(vec![rows(&mut p.extra_scalars[self.balsara_slot])]);
            }
        }
        force_pass(sys, &self.params, self.balsara_slot, self.form);
        Ok(())
    }
}

/// With an evolved ρ: h_a = η (m_a/ρ_a)^{1/D} (walls keep theirs), Ω = 1, and a master list
/// that serves every h (the working list is cut by the caller).
fn continuity_h<const D: usize>(sys: &mut System<D>) {
    let (eta, h_max) = (sys.eta, sys.h_max);
    let p = &mut sys.particles;
    for i in 0..p.len() {
        if p.body[i] == 0 && p.port[i] == 0 {
            p.h[i] = (eta * (p.mass[i] / p.rho[i]).powf(1.0 / D as f64)).min(h_max);
        }
        p.omega[i] = 1.0;
    }
    smoothing::update_master_list(sys);
}

/// Velocity divergence and |curl| (SPH estimate with grad-h:
/// ∂v^i/∂x^j = −1/(Ω_a ρ_a) Σ_b m_b v_ab^i ∂_j W_ab(h_a)), and the Balsara factor
/// f = |∇·v| / (|∇·v| + |∇×v| + 10⁻⁴ c/h) into `extra_scalars[balsara_slot]` (1 when off or 1D),
/// in two parts: the pair sums, taken while the working list is cut, then the per-particle
/// finish once the EOS has given c.
/// Cut the working list from the master list with the velocity-gradient sums taken on the
/// way: one walk over the pairs instead of two (a separate gather over the working list
/// visits the same pairs in the same order, so the sums are the same to the bit). Their time
/// counts as neighbour time. Finish with [`finish_gradients`] once the EOS has given c.
fn cut_lists_with_gradient_sums<const D: usize>(sys: &mut System<D>) -> Vec<GradAcc<D>> {
    let mut grads: Vec<GradAcc<D>> = sys.scratch.take();
    sys.particles
        .h
        .par_iter()
        .with_min_len(LIGHT)
        .map(|&h| GradAcc::new(h))
        .collect_into_vec(&mut grads);
    let kernel = sys.kernel;
    kernel.visit(GradientCut {
        sys,
        grads: &mut grads,
    });
    grads
}

/// The cut with the gradient sums, handed the concrete kernel.
struct GradientCut<'a, const D: usize> {
    sys: &'a mut System<D>,
    grads: &'a mut [GradAcc<D>],
}

impl<const D: usize> KernelVisitor<D> for GradientCut<'_, D> {
    type Output = ();
    fn visit<K: Kernel + Copy>(self, kernel: &DimKernel<D, K>) {
        self.sys
            .compact_neighbours_with(self.grads, &GradientSums { kernel: *kernel });
    }
}

/// Pair b's share of a's velocity-gradient sums Σ m_b v_ab·∇_a W_ab(h_a) and
/// Σ m_b v_ab ⊗ ∇_a W_ab(h_a), for the kept lanes of a block.
struct GradientSums<const D: usize, K> {
    kernel: DimKernel<D, K>,
}

impl<const D: usize, K: Kernel + Copy> CutVisitor<D> for GradientSums<D, K> {
    type Acc = GradAcc<D>;
    /// The lanes' ∇·v and ∇v terms.
    type Scratch = GradLanes;

    /// (Index loops: a lane index reads several arrays at once.)
    #[inline(always)]
    #[allow(clippy::needless_range_loop)]
    fn block(
        &self,
        _: &System<D>,
        _: usize,
        g: &mut GradAcc<D>,
        blk: &CutBlock,
        lanes: &mut GradLanes,
    ) {
        let k = self.kernel;
        let hinv = g.hinv;
        let GradLanes { div, grad } = lanes;
        for i in 0..blk.lanes {
            let r = blk.r2[i].sqrt();
            let dwdr = k.dwdr_hinv(r, hinv);
            // a lane that is not kept, at zero distance or beyond h_a's support adds nothing
            let adds = blk.keep[i] && r > 0.0 && dwdr != 0.0;
            let f = dwdr / r;
            let mut gw = [0.0; 3];
            let mut dot = 0.0;
            for c in 0..D {
                gw[c] = blk.dx[c][i] * f;
                dot += blk.vab[c][i] * gw[c];
            }
            let m = blk.m[i];
            div[i] = if adds { m * dot } else { 0.0 };
            for r in 0..D {
                for c in 0..D {
                    grad[r][c][i] = if adds {
                        (m * blk.vab[r][i]) * gw[c]
                    } else {
                        0.0
                    };
                }
            }
        }
        // in list order; a lane's exact zero leaves a sum as it was (a sum that starts at
        // +0 never becomes −0), so the sums equal those over the kept pairs alone
        for i in 0..blk.n {
            g.div += div[i];
            for r in 0..D {
                for c in 0..D {
                    g.grad[(r, c)] += grad[r][c][i];
                }
            }
        }
    }
}

/// [`GradientSums`]' lane terms (every lane the compute loop reaches is written before the
/// sum reads it).
pub struct GradLanes {
    div: [f64; LANES],
    grad: [[[f64; LANES]; 3]; 3],
}

impl Default for GradLanes {
    fn default() -> Self {
        Self {
            div: [0.0; LANES],
            grad: [[[0.0; LANES]; 3]; 3],
        }
    }
}

/// ∇·v, |∇×v| and the Balsara factor from the pair sums.
fn finish_gradients<const D: usize>(
    sys: &mut System<D>,
    grads: &[GradAcc<D>],
    balsara_slot: usize,
    balsara: bool,
) {
    sys.stats.total_pairs += sys.neighbours.total_pairs() as u64;
    let use_balsara = balsara && D > 1;
    let p = &mut sys.particles;
    let (omega, rho, cs, h) = (&p.omega, &p.rho, &p.sound_speed, &p.h);
    p.div_v
        .par_iter_mut()
        .zip(p.curl_v.par_iter_mut())
        .zip(p.extra_scalars[balsara_slot].par_iter_mut())
        .enumerate()
        .with_min_len(LIGHT)
        .for_each(|(a, ((dv, cv), bal))| {
            let s = -1.0 / (omega[a] * rho[a]);
            let div = s * grads[a].div;
            let curl = s.abs() * curl_norm(&grads[a].grad);
            *dv = div;
            *cv = curl;
            *bal = if use_balsara {
                div.abs() / (div.abs() + curl + 1e-4 * cs[a] / h[a] + 1e-300)
            } else {
                1.0
            };
        });
}
