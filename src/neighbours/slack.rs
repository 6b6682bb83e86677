//! How far the master list's skin is used up, measured locally.
//!
//! A pair (a, b) within range now, |x_a − M x_b| < max(R_a, R_b) (M the image of b's code),
//! was listed at the build when that range plus |d_a − M d_b| stays within the build reach
//! (d = displacement since the build; see `System::prepare_master_list`). Any bound on
//! |d_a − M d_b| over the partners a can have now serves. The global one,
//! |d_a − u| + max_b |d_b − u| for one u, spends the skin on the largest relative motion
//! anywhere in the box: in a periodic Sod tube the two interfaces push gas both ways at
//! |v| ≈ 0.93, so every list expired after ~2.7 steps wherever the gas was at rest.
//!
//! Here the bound is local. Space is cut into coarse cells at least as wide as the largest
//! build reach, so a partner's image lies in one of the 3^D cells around a's cell. Each cell
//! keeps the bounding box of the displacements found there (of the particles, and of the
//! mirror images M d_b of particles near reflecting faces, filed where the image lies); the
//! union N_a of the boxes around a's cell contains every M d_b a can meet, so with u_a the
//! centre of N_a,
//!
//!   |d_a − M d_b| ≤ |d_a − u_a| + |M d_b − u_a| ≤ |d_a − u_a| + ½ diag(N_a).
//!
//! Where the flow moves as a whole (a post-shock plateau, a sloshing tank's bulk), N_a is
//! small whatever the speed.

use super::grid::{cell_box, next_index, tile};
use crate::domain::{BoundaryKind, Domain};
use crate::particles::Vector;
use crate::threads::LIGHT;
use rayon::prelude::*;

/// Per particle a, a bound on |d_a − M d_b| over every particle image M x_b within `reach` of
/// x_a now (`reach` ≥ the largest range a pair can have), from the displacements `disp`
/// since the build.
pub fn local_bound<const D: usize>(
    pos: &[Vector<D>],
    disp: &[Vector<D>],
    reach: f64,
    domain: &Domain<D>,
) -> Vec<f64> {
    let n = pos.len();
    if n == 0 {
        return vec![];
    }
    let grid = Coarse::new(pos, reach, domain);
    let cells = grid.count();
    let empty = ([f64::INFINITY; D], [f64::NEG_INFINITY; D]);
    let mut boxes = vec![empty; cells];
    let file = |boxes: &mut [([f64; D], [f64; D])], c: usize, d: &Vector<D>| {
        let (lo, hi) = &mut boxes[c];
        for k in 0..D {
            lo[k] = lo[k].min(d[k]);
            hi[k] = hi[k].max(d[k]);
        }
    };
    let home: Vec<usize> = pos
        .par_iter()
        .with_min_len(LIGHT)
        .map(|x| grid.cell(x))
        .collect();
    let mirrors = domain.kind.contains(&BoundaryKind::Reflect);
    let mut codes = Vec::new();
    for b in 0..n {
        file(&mut boxes, home[b], &disp[b]);
        if mirrors {
            // images within `reach` of the box: the only ones a particle inside can meet
            domain.image_codes(&pos[b], reach, &mut codes);
            for &code in &codes[1..] {
                let c = grid.cell(&domain.image_position(&pos[b], code));
                file(&mut boxes, c, &domain.image_velocity(&disp[b], code));
            }
        }
    }
    // The union over the 3^D cells around each cell (each cell once on short periodic axes).
    let around: Vec<([f64; D], [f64; D])> = (0..cells)
        .into_par_iter()
        .with_min_len(LIGHT)
        .map(|c| {
            let mut u = empty;
            grid.for_adjacent(c, |m| {
                for k in 0..D {
                    u.0[k] = u.0[k].min(boxes[m].0[k]);
                    u.1[k] = u.1[k].max(boxes[m].1[k]);
                }
            });
            u
        })
        .collect();
    (0..n)
        .into_par_iter()
        .with_min_len(LIGHT)
        .map(|a| {
            let (lo, hi) = &around[home[a]];
            let mut off = 0.0;
            let mut diag = 0.0;
            for k in 0..D {
                let centre = 0.5 * (lo[k] + hi[k]);
                off += (disp[a][k] - centre) * (disp[a][k] - centre);
                diag += (hi[k] - lo[k]) * (hi[k] - lo[k]);
            }
            off.sqrt() + 0.5 * diag.sqrt()
        })
        .collect()
}

/// A uniform grid of cells at least `reach` wide over the particles (tiling periodic axes
/// exactly), with positions outside it filed in its edge cells: an image across a
/// reflecting face lands in the cell by the face, next to every particle within `reach`.
struct Coarse<const D: usize> {
    lo: [f64; D],
    width: [f64; D],
    dims: [usize; D],
    periodic: [bool; D],
}

impl<const D: usize> Coarse<D> {
    fn new(pos: &[Vector<D>], reach: f64, domain: &Domain<D>) -> Self {
        let (lo, hi, periodic) = cell_box(pos, domain);
        // At most ~one cell per particle (far-flung particles in an open box): wider cells
        // only loosen the bound.
        let mut w = reach.max(1e-300);
        let count = |w: f64| -> f64 {
            (0..D)
                .map(|k| ((hi[k] - lo[k]) / w).floor().max(0.0) + 1.0)
                .product()
        };
        while count(w) > pos.len() as f64 + 8.0 {
            w *= 1.5;
        }
        let (dims, width) = tile(&lo, &hi, &periodic, w);
        Self {
            lo,
            width,
            dims,
            periodic,
        }
    }

    fn count(&self) -> usize {
        self.dims.iter().product()
    }

    fn cell(&self, x: &Vector<D>) -> usize {
        let mut c = 0;
        for k in (0..D).rev() {
            let d = self.dims[k] as isize;
            let i = ((x[k] - self.lo[k]) / self.width[k]).floor();
            // NaN and far positions land in an edge cell; periodic positions wrap
            let i = if self.periodic[k] {
                (i.clamp(-1e15, 1e15) as isize).rem_euclid(d)
            } else {
                (i.clamp(-1.0, d as f64) as isize).clamp(0, d - 1)
            };
            c = c * self.dims[k] + i as usize;
        }
        c
    }

    /// Visit the cells within one cell of cell `c` along every axis (wrapping periodic axes,
    /// each cell once).
    fn for_adjacent(&self, c: usize, mut f: impl FnMut(usize)) {
        let mut rest = c;
        let idx: [usize; D] = std::array::from_fn(|k| {
            let i = rest % self.dims[k];
            rest /= self.dims[k];
            i
        });
        // per axis: the distinct cell indices among idx − 1, idx, idx + 1
        let mut axis: [[usize; 3]; D] = [[0; 3]; D];
        let mut len = [0usize; D];
        for k in 0..D {
            let d = self.dims[k] as isize;
            for off in -1isize..=1 {
                let mut i = idx[k] as isize + off;
                if self.periodic[k] {
                    i = i.rem_euclid(d);
                } else if i < 0 || i >= d {
                    continue;
                }
                let i = i as usize;
                if !axis[k][..len[k]].contains(&i) {
                    axis[k][len[k]] = i;
                    len[k] += 1;
                }
            }
        }
        let mut pick = [0usize; D];
        loop {
            let mut m = 0;
            for k in (0..D).rev() {
                m = m * self.dims[k] + axis[k][pick[k]];
            }
            f(m);
            if !next_index(&mut pick, &len, 0) {
                return;
            }
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Against the bound's definition by brute force: for every pair of particle images
    /// within `reach`, |d_a − M d_b| ≤ bound_a, on a box with a periodic, a reflecting and an
    /// open axis and random displacements with a shear.
    #[test]
    fn bounds_every_pair_within_reach() {
        let domain = Domain::<3> {
            lo: [0.0, 0.0, 0.0],
            hi: [1.0, 0.7, 0.5],
            kind: [
                BoundaryKind::Periodic,
                BoundaryKind::Reflect,
                BoundaryKind::Open,
            ],
        };
        let mut seed = 12345u64;
        let mut rnd = || {
            seed = seed
                .wrapping_mul(6364136223846793005)
                .wrapping_add(1442695040888963407);
            (seed >> 11) as f64 / (1u64 << 53) as f64
        };
        let n = 600;
        let pos: Vec<Vector<3>> = (0..n)
            .map(|_| Vector::<3>::new(rnd(), 0.7 * rnd(), 0.5 * rnd()))
            .collect();
        let disp: Vec<Vector<3>> = pos
            .iter()
            .map(|x| Vector::<3>::new(0.02 * x[1] + 0.003 * rnd(), 0.003 * rnd(), -0.01 * x[0]))
            .collect();
        let reach = 0.13;
        let bound = local_bound(&pos, &disp, reach, &domain);
        let mut codes = Vec::new();
        let mut checked = 0;
        for a in 0..n {
            domain.image_codes(&pos[a], reach, &mut codes);
            for &code in &codes {
                for b in 0..n {
                    if domain.separation(&pos[a], &pos[b], code).norm() < reach {
                        let rel = disp[a] - domain.image_velocity(&disp[b], code);
                        assert!(rel.norm() <= bound[a] + 1e-15, "{a} {b} {code}");
                        checked += 1;
                    }
                }
            }
        }
        assert!(checked > 10 * n);
        // local: tighter than the global bound somewhere (the shear spreads d over the box)
        let global = disp.iter().map(|d| d.norm()).fold(0.0, f64::max);
        assert!(bound.iter().any(|&s| s < global));
    }
}
