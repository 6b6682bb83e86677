//! The state every scheme works on: particles, box, kernel, EOS, neighbour structures, and
//! the one neighbour loop (`gather`) that all per-pair passes go through.

use crate::domain::{Domain, ImageCode};
use crate::eos::{Eos, EosConfig};
use crate::kernel::DimKernel;
use crate::neighbours::{unpack, CellGrid, NeighbourList};
use crate::particles::{Particles, Vector};
use rayon::prelude::*;

/// Counters of the latest evaluation (for benchmarks and diagnostics).
#[derive(Debug, Clone, Copy, Default)]
pub struct EvalStats {
    /// Pair interactions evaluated in the force pass.
    pub force_pairs: u64,
    /// Pair interactions in all passes (density iterations, gradients, forces).
    pub total_pairs: u64,
    /// Neighbour-list rebuilds caused by growing smoothing lengths.
    pub list_rebuilds: u64,
    /// Mean Newton–Raphson iterations per particle in the smoothing-length solve.
    pub h_iterations: f64,
    /// Particles whose h hit the cap `h_max`.
    pub h_capped: u64,
}

/// One neighbour seen from particle a.
#[derive(Debug, Clone, Copy)]
pub struct Pair<const D: usize> {
    pub b: usize,
    pub code: ImageCode,
    /// x_a − image(x_b)
    pub dx: Vector<D>,
    pub r: f64,
    /// Velocity of b's image (normal components reversed for mirror images).
    pub vb: Vector<D>,
}

#[derive(Debug, Clone)]
pub struct System<const D: usize> {
    pub particles: Particles<D>,
    pub domain: Domain<D>,
    pub kernel: DimKernel<D>,
    pub eos: EosConfig,
    /// h = η (m/ρ)^{1/D}
    pub eta: f64,
    /// Upper bound on h (isolated particles would otherwise grow without limit).
    pub h_max: f64,
    /// Uniform body force per unit mass.
    pub gravity: Vector<D>,
    pub grid: CellGrid<D>,
    pub neighbours: NeighbourList,
    pub stats: EvalStats,
}

impl<const D: usize> System<D> {
    /// Build the grid and lists for search radius `reach_a = scale · 2h_a`.
    pub fn rebuild_neighbours(&mut self, scale: f64) -> Vec<f64> {
        let p = &self.particles;
        let reach: Vec<f64> = p.h.iter().map(|&h| self.kernel.radius(h) * scale).collect();
        let rmax = reach.iter().cloned().fold(0.0, f64::max);
        self.grid = CellGrid::build(&p.pos, &self.domain, rmax);
        self.neighbours = NeighbourList::build(&p.pos, &reach, &self.domain, &self.grid);
        reach
    }

    /// Drop list entries beyond `max(2h_a, 2h_b)` (the skin) once h is final.
    pub fn compact_neighbours(&mut self) {
        let p = &self.particles;
        let dom = &self.domain;
        let k = &self.kernel;
        self.neighbours.retain(|a, e| {
            let (b, code) = unpack(e);
            let r = k.radius(p.h[a]).max(k.radius(p.h[b]));
            dom.separation(&p.pos[a], &p.pos[b], code).norm_squared() < r * r
        });
    }

    /// The neighbour loop, written once: for every particle a (in parallel), call
    /// `f(a, &mut out[a], &pair)` for each listed neighbour. Self is not visited.
    pub fn gather<T: Send, F>(&self, out: &mut [T], f: F)
    where
        F: Fn(usize, &mut T, &Pair<D>) + Sync,
    {
        let p = &self.particles;
        let dom = &self.domain;
        let nb = &self.neighbours;
        out.par_iter_mut().enumerate().with_min_len(64).for_each(|(a, acc)| {
            let xa = p.pos[a];
            for &e in nb.of(a) {
                let (b, code) = unpack(e);
                let dx = dom.separation(&xa, &p.pos[b], code);
                let pair = Pair {
                    b,
                    code,
                    dx,
                    r: dx.norm(),
                    vb: dom.image_velocity(&p.vel[b], code),
                };
                f(a, acc, &pair);
            }
        });
    }

    /// P and c_s from the EOS for every particle.
    pub fn update_eos(&mut self) {
        let eos = self.eos;
        let p = &mut self.particles;
        p.pressure
            .par_iter_mut()
            .zip(p.sound_speed.par_iter_mut())
            .zip(p.rho.par_iter().zip(p.u.par_iter()))
            .for_each(|((pr, cs), (&rho, &u))| {
                *pr = eos.pressure(rho, u);
                *cs = eos.sound_speed(rho, u);
            });
    }

    /// Index of the first particle with a non-finite evolved or derived field, if any.
    pub fn first_non_finite(&self) -> Option<(usize, &'static str)> {
        let p = &self.particles;
        (0..p.len()).find_map(|i| {
            if !p.pos[i].iter().all(|x| x.is_finite()) {
                Some((i, "position"))
            } else if !p.vel[i].iter().all(|x| x.is_finite()) {
                Some((i, "velocity"))
            } else if !p.u[i].is_finite() {
                Some((i, "internal energy"))
            } else if !(p.rho[i].is_finite() && p.rho[i] > 0.0) {
                Some((i, "density"))
            } else if !(p.h[i].is_finite() && p.h[i] > 0.0) {
                Some((i, "smoothing length"))
            } else {
                None
            }
        })
    }
}
