//! Relaxation of a lattice into a glass (Rosswog (2015) Sec. 7.1, Eqs. 101–102): every movable
//! particle is displaced by 0.9 r_s in a random direction, then moved repeatedly along the
//! pseudo-force f_a = −Σ_b ∇_a W_ab(h0) (Wendland C6 at 2h, h0 = 2.2 V0^{1/D}) by
//! δr_a = r0 f_a / f⁰_max with r0 = 0.5 r_s and f⁰_max the largest force of the first
//! iteration, until max_a |δr_a| / r_s < tolerance. [The paper leaves open whether f⁰_max is
//! renewed; one formula for every iteration is our reading.] r_s = ½ V0^{1/D}.

use super::ics::SplitMix64;
use crate::domain::Domain;
use crate::kernel::{AnyKernel, DimKernel, WendlandC6};
use crate::neighbours::{unpack, CellGrid, NeighbourList};
use crate::particles::{Particles, Vector};
use rayon::prelude::*;
use serde::{Deserialize, Serialize};

/// `[glass]` of a case file.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct GlassConfig {
    /// Initial random displacement, in units of r_s (spec: 0.9).
    #[serde(default = "default_kick")]
    pub perturbation: f64,
    /// Largest first-iteration step, in units of r_s (spec: 0.5).
    #[serde(default = "default_step")]
    pub step: f64,
    /// Stop when the largest step is below this many r_s (spec: 1e-3).
    #[serde(default = "default_tol")]
    pub tolerance: f64,
    #[serde(default = "default_iters")]
    pub max_iterations: usize,
    #[serde(default)]
    pub seed: u64,
}

fn default_kick() -> f64 {
    0.9
}
fn default_step() -> f64 {
    0.5
}
fn default_tol() -> f64 {
    1e-3
}
fn default_iters() -> usize {
    2000
}

impl GlassConfig {
    pub fn validate(&self) -> Result<(), String> {
        if !(self.perturbation.is_finite() && (0.0..=2.0).contains(&self.perturbation)) {
            return Err(format!(
                "glass.perturbation: must be in [0, 2] (units of r_s), got {}",
                self.perturbation
            ));
        }
        if !(self.step.is_finite() && self.step > 0.0 && self.step <= 1.0) {
            return Err(format!(
                "glass.step: must be in (0, 1] (units of r_s), got {}",
                self.step
            ));
        }
        if !(self.tolerance.is_finite() && self.tolerance > 0.0 && self.tolerance < 1.0) {
            return Err(format!(
                "glass.tolerance: must be in (0, 1), got {}",
                self.tolerance
            ));
        }
        if self.max_iterations == 0 || self.max_iterations > 100_000 {
            return Err(format!(
                "glass.max_iterations: must be in [1, 100000], got {}",
                self.max_iterations
            ));
        }
        Ok(())
    }
}

/// Relax the particle positions in place; returns (iterations, final max step / r_s).
pub fn relax<const D: usize>(
    p: &mut Particles<D>,
    domain: &Domain<D>,
    cfg: &GlassConfig,
    spacing: &[f64],
) -> (usize, f64) {
    let n = p.len();
    let kernel = DimKernel::<D>::new(AnyKernel::C6(WendlandC6));
    let rs: Vec<f64> = spacing.iter().map(|s| 0.5 * s).collect();
    let h0: Vec<f64> = spacing.iter().map(|s| 2.2 * s).collect();
    let mut rng = SplitMix64::new(cfg.seed ^ 0x6c61_7373);
    for (i, &r) in rs.iter().enumerate() {
        if p.frozen[i] {
            continue;
        }
        // random direction: normalised Gaussian-free rejection sample in the unit ball
        let dir = loop {
            let mut d = Vector::<D>::zeros();
            for k in 0..D {
                d[k] = 2.0 * rng.uniform() - 1.0;
            }
            let l = d.norm();
            if l > 1e-3 && l <= 1.0 {
                break d / l;
            }
        };
        p.pos[i] += dir * (cfg.perturbation * r);
        let mut v = Vector::<D>::zeros();
        domain.enforce(&mut p.pos[i], &mut v);
    }
    let reach: Vec<f64> = h0.iter().map(|h| kernel.radius(*h) * 1.3).collect();
    let skin = reach
        .iter()
        .zip(&h0)
        .map(|(r, h)| r - kernel.radius(*h))
        .fold(f64::INFINITY, f64::min);
    let mut list = NeighbourList::default();
    let mut moved = f64::INFINITY;
    let mut f0max = 0.0;
    let mut last = f64::INFINITY;
    for it in 0..cfg.max_iterations {
        if moved > 0.5 * skin {
            let grid = CellGrid::build(&p.pos, domain, &reach);
            list = NeighbourList::build(&p.pos, &reach, domain, &grid);
            moved = 0.0;
        }
        let pos = &p.pos;
        let force: Vec<Vector<D>> = (0..n)
            .into_par_iter()
            .map(|a| {
                let mut f = Vector::<D>::zeros();
                for &e in list.of(a) {
                    let (b, code) = unpack(e);
                    let d = domain.separation(&pos[a], &pos[b], code);
                    let r = d.norm();
                    if r > 0.0 {
                        // −∇_a W_ab = −dW/dr · r̂_ab: pushes a away from b
                        f -= d * (kernel.dwdr(r, h0[a]) / r);
                    }
                }
                f
            })
            .collect();
        if it == 0 {
            f0max = (0..n)
                .filter(|&i| !p.frozen[i])
                .map(|i| force[i].norm())
                .fold(0.0, f64::max);
            if f0max == 0.0 {
                return (0, 0.0);
            }
        }
        let mut max_step: f64 = 0.0;
        let mut max_move: f64 = 0.0;
        for i in 0..n {
            if p.frozen[i] {
                continue;
            }
            let dr = force[i] * (cfg.step * rs[i] / f0max);
            max_step = max_step.max(dr.norm() / rs[i]);
            max_move = max_move.max(dr.norm());
            p.pos[i] += dr;
            let mut v = Vector::<D>::zeros();
            domain.enforce(&mut p.pos[i], &mut v);
        }
        moved += max_move;
        last = max_step;
        if max_step < cfg.tolerance {
            return (it + 1, max_step);
        }
    }
    (cfg.max_iterations, last)
}
