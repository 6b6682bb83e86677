//! The pair sums of the IA matrices (Rosswog (2015) Eqs. 20–25) on pair lanes
//! ([`crate::neighbours::lanes`]): per particle
//!   τ_a = Σ_b V_b (r_b − r_a)(r_b − r_a)ᵀ W_ab(h_a),
//!   I_a = Σ_b V_b (v_b − v_a)(r_b − r_a)ᵀ W_ab(h_a)   (the fIA velocity gradient's sum).
//!
//! Every lane computes what the gather with a closure per pair computed before, in the same
//! order (W on r/h; each outer product entry as (s d_i) d_j with s = V_b W, as nalgebra's
//! product gives it), and the sums run in list order, so τ and I are the same bits (the
//! snapshots of F1–F4 and SR runs compared byte for byte, BENCHMARKS.md, issue 19).

use crate::kernel::{DimKernel, Kernel, KernelVisitor};
use crate::neighbours::lanes::{
    fill_pair, finish_pairs, for_each_row, pad_separations, RowPass, LANES,
};
use crate::neighbours::unpack;
use crate::particles::Vector;
use crate::system::System;
use crate::threads::LIGHT;
use nalgebra::SMatrix;
use rayon::prelude::*;

/// τ_a and I_a of one particle.
pub type IaSums<const D: usize> = (SMatrix<f64, D, D>, SMatrix<f64, D, D>);

/// What a pair reads of one particle.
#[derive(Clone, Copy)]
struct Rec<const D: usize> {
    x: Vector<D>,
    v: Vector<D>,
    /// V = m/ρ
    vol: f64,
}

/// τ_a and I_a of every particle.
pub fn ia_sums<const D: usize>(sys: &System<D>) -> Vec<IaSums<D>> {
    let p = &sys.particles;
    let recs: Vec<Rec<D>> = (0..p.len())
        .into_par_iter()
        .with_min_len(LIGHT)
        .map(|b| Rec {
            x: p.pos[b],
            v: p.vel[b],
            vol: p.mass[b] / p.rho[b],
        })
        .collect();
    let mut out = vec![(SMatrix::zeros(), SMatrix::zeros()); p.len()];
    sys.kernel.visit(Visit {
        sys,
        recs: &recs,
        out: &mut out,
    });
    out
}

struct Visit<'a, const D: usize> {
    sys: &'a System<D>,
    recs: &'a [Rec<D>],
    out: &'a mut [IaSums<D>],
}

impl<const D: usize> KernelVisitor<D> for Visit<'_, D> {
    type Output = ();
    fn visit<K: Kernel + Copy>(self, kernel: &DimKernel<D, K>) {
        let rows = Rows {
            sys: self.sys,
            recs: self.recs,
            kernel: *kernel,
        };
        for_each_row(&rows, self.out);
    }
}

struct Rows<'a, const D: usize, K> {
    sys: &'a System<D>,
    recs: &'a [Rec<D>],
    kernel: DimKernel<D, K>,
}

/// A block of pairs: separation, v_ab and V_b.
#[derive(Default)]
struct PairBlock {
    dx: [[f64; LANES]; 3],
    vab: [[f64; LANES]; 3],
    vol: [f64; LANES],
}

/// A block's terms of τ and I, row-major D×D.
#[derive(Default)]
struct PairTerms {
    tau: [[f64; LANES]; 9],
    iv: [[f64; LANES]; 9],
}

#[derive(Default)]
struct Scratch(Box<(PairBlock, PairTerms)>);

impl<const D: usize, K: Kernel + Copy> RowPass for Rows<'_, D, K> {
    type Acc = IaSums<D>;
    type Scratch = Scratch;

    #[inline(always)]
    fn row(&self, a: usize, o: &mut IaSums<D>, scratch: &mut Scratch) {
        let (blk, t) = &mut *scratch.0;
        let dom = &self.sys.domain;
        let ra = &self.recs[a];
        let h = self.sys.particles.h[a];
        // W's factor σ/h^D, as `DimKernel::w` forms it
        let wnorm = self.kernel.norm(1.0 / h);
        let (mut tau, mut iv) = (SMatrix::<f64, D, D>::zeros(), SMatrix::<f64, D, D>::zeros());
        for block in self.sys.neighbours.of(a).chunks(LANES) {
            let n = block.len();
            for (i, &e) in block.iter().enumerate() {
                let (b, code) = unpack(e);
                let rb = &self.recs[b];
                fill_pair(dom, (&rb.x, &rb.v), code, &mut blk.dx, &mut blk.vab, i);
                blk.vol[i] = rb.vol;
            }
            finish_pairs(dom, (&ra.x, &ra.v), &mut blk.dx, &mut blk.vab, n);
            let lanes = pad_separations::<D>(&mut blk.dx, n);
            self.terms(h, wnorm, blk, t, lanes);
            // Sum in list order, as the gather did.
            for i in 0..n {
                for r in 0..D {
                    for s in 0..D {
                        tau[(r, s)] += t.tau[r * D + s][i];
                        iv[(r, s)] += t.iv[r * D + s][i];
                    }
                }
            }
        }
        *o = (tau, iv);
    }
}

impl<const D: usize, K: Kernel + Copy> Rows<'_, D, K> {
    /// One block's terms, one pair per lane, selects only. With d = r_b − r_a = −x_ab,
    /// s = V_b W(r, h_a) and v_b − v_a = −v_ab: τ ∋ (s d_i) d_j and I ∋ (s (v_b − v_a)_i) d_j.
    /// A pair outside the support adds zeros (the gather skipped it: the same sums).
    #[inline(always)]
    #[allow(clippy::needless_range_loop)]
    fn terms(&self, h: f64, wnorm: f64, b: &PairBlock, out: &mut PairTerms, lanes: usize) {
        for i in 0..lanes {
            let mut d = [0.0; 3];
            let mut dv = [0.0; 3];
            let mut r2 = 0.0;
            for k in 0..D {
                d[k] = -b.dx[k][i];
                dv[k] = -b.vab[k][i];
                // |x_ab|² summed from zero in axis order, as nalgebra's `norm` sums it
                r2 += d[k] * d[k];
            }
            let r = r2.sqrt();
            let w = self.kernel.w_normed(r, h, wnorm);
            let s = b.vol[i] * w;
            for r in 0..D {
                let (sd, sv) = (s * d[r], s * dv[r]);
                for c in 0..D {
                    out.tau[r * D + c][i] = sd * d[c];
                    out.iv[r * D + c][i] = sv * d[c];
                }
            }
        }
    }
}
