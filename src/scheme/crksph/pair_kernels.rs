//! The symmetrised kernel of every listed pair and the volumes V_i = 1/Σ_j W(x_ij, h_i)
//! (Frontiere, Raskin & Owen (2017) eq 75, self included), in one pass on pair lanes
//! ([`crate::neighbours::lanes`]).
//!
//! W_ij = ½[W(x_ij, h_i) + W(x_ij, h_j)] and ∇_i W_ij = ½[∂W/∂r(h_i) + ∂W/∂r(h_j)] x̂_ij lie
//! along x_ij, so a pair keeps two scalars, W̄ and ḡ with ∇_i W_ij = ḡ x_ij, and every later
//! pass multiplies by its own x_ij. Both are symmetric in (i, j) bit for bit (a sum of two
//! terms), so row i and row j hold the same pair kernel.
//!
//! Measured on Noh 2D with CRKSPH (`tools/bench_peer.py`'s case, `sphfmu run --threads 2`), the
//! scalar gather this replaces was a third of the run: two septic-spline evaluations per
//! listed pair, twice a step (BENCHMARKS.md, issue 19).

use crate::kernel::{DimKernel, Kernel, KernelVisitor};
use crate::neighbours::lanes::{for_each_row, inverse_h, pad_separations, RowPass, LANES};
use crate::neighbours::unpack;
use crate::particles::Vector;
use crate::system::System;
use std::marker::PhantomData;

/// The symmetrised kernel of one listed pair: W̄_ij and ḡ with ∇_i W̄_ij = ḡ x_ij.
#[derive(Debug, Clone, Copy, Default, PartialEq)]
pub struct PairKernel {
    pub w: f64,
    pub g: f64,
}

impl PairKernel {
    /// ∇_i W̄_ij for the pair separation x_ij = x_i − x_j.
    #[inline(always)]
    pub fn gradient<const D: usize>(&self, xij: &Vector<D>) -> Vector<D> {
        xij * self.g
    }
}

/// [`PairKernel`] for every pair of the working list, in list order (indexed by
/// [`crate::system::Pair::index`]), and the volumes V_i (eq 75). The pairs are written into
/// `slots`' allocation (an earlier step's, kept in `crate::scratch`: one slot per pair is the
/// largest array of a step).
pub fn pair_kernels_and_volumes<const D: usize>(
    sys: &System<D>,
    mut slots: Vec<PairKernel>,
) -> (Vec<PairKernel>, Vec<f64>) {
    let p = &sys.particles;
    let hinv = inverse_h(&p.h);
    slots.clear();
    slots.resize(sys.neighbours.total_pairs(), PairKernel::default());
    let vol = {
        let mut out: Vec<RowOut> = sys
            .neighbours
            .split_rows_mut(&mut slots)
            .into_iter()
            .map(|slots| RowOut { sum: 0.0, slots })
            .collect();
        sys.kernel.visit(Visit {
            sys,
            hinv: &hinv,
            out: &mut out,
        });
        out.iter().map(|o| 1.0 / o.sum).collect()
    };
    (slots, vol)
}

/// [`pair_kernels_and_volumes`] without the volumes.
pub fn pair_kernels<const D: usize>(sys: &System<D>) -> Vec<PairKernel> {
    pair_kernels_and_volumes(sys, Vec::new()).0
}

/// One row's Σ_j W(x_ij, h_i) (self included) and its pair slots.
struct RowOut<'s> {
    sum: f64,
    slots: &'s mut [PairKernel],
}

struct Visit<'a, 's, const D: usize> {
    sys: &'a System<D>,
    hinv: &'a [f64],
    out: &'a mut [RowOut<'s>],
}

impl<'s, const D: usize> KernelVisitor<D> for Visit<'_, 's, D> {
    type Output = ();
    fn visit<K: Kernel + Copy>(self, kernel: &DimKernel<D, K>) {
        let rows = Rows::<D, K> {
            sys: self.sys,
            hinv: self.hinv,
            kernel: *kernel,
            _slots: PhantomData,
        };
        for_each_row(&rows, self.out);
    }
}

struct Rows<'a, 's, const D: usize, K> {
    sys: &'a System<D>,
    hinv: &'a [f64],
    kernel: DimKernel<D, K>,
    _slots: PhantomData<&'s ()>,
}

/// A block of pairs: the separation and b's 1/h in, W(h_a), W̄ and ḡ out. Padding lanes get
/// a zero separation and add nothing.
#[derive(Default)]
pub(super) struct Scratch(Box<KernelBlock>);

#[derive(Default)]
struct KernelBlock {
    dx: [[f64; LANES]; 3],
    hinv: [f64; LANES],
    wa: [f64; LANES],
    w: [f64; LANES],
    g: [f64; LANES],
}

impl<'s, const D: usize, K: Kernel + Copy> RowPass for Rows<'_, 's, D, K> {
    type Acc = RowOut<'s>;
    type Scratch = Scratch;

    #[inline(always)]
    fn row(&self, a: usize, o: &mut RowOut<'s>, scratch: &mut Scratch) {
        let blk = &mut *scratch.0;
        let dom = &self.sys.domain;
        let pos = &self.sys.particles.pos;
        let k = self.kernel;
        let hinv_a = self.hinv[a];
        let xa = pos[a];
        let mut sum = k.norm(hinv_a) * k.kernel.shape(0.0).0;
        let entries = self.sys.neighbours.of(a);
        for (block, slots) in entries.chunks(LANES).zip(o.slots.chunks_mut(LANES)) {
            let n = block.len();
            for (i, &e) in block.iter().enumerate() {
                let (b, code) = unpack(e);
                let d = dom.separation(&xa, &pos[b], code);
                for c in 0..D {
                    blk.dx[c][i] = d[c];
                }
                blk.hinv[i] = self.hinv[b];
            }
            let lanes = pad_separations::<D>(&mut blk.dx, n);
            for i in 0..lanes {
                let mut r2 = 0.0;
                for c in 0..D {
                    r2 += blk.dx[c][i] * blk.dx[c][i];
                }
                let r = r2.sqrt();
                let (wa, fa) = k.w_dwdr_hinv(r, hinv_a);
                let (wb, fb) = k.w_dwdr_hinv(r, blk.hinv[i]);
                let rr = if r > 0.0 { r } else { 1.0 };
                blk.wa[i] = wa;
                blk.w[i] = 0.5 * (wa + wb);
                blk.g[i] = if r > 0.0 { 0.5 * (fa + fb) / rr } else { 0.0 };
            }
            for (i, slot) in slots.iter_mut().enumerate() {
                sum += blk.wa[i];
                *slot = PairKernel {
                    w: blk.w[i],
                    g: blk.g[i],
                };
            }
        }
        o.sum = sum;
    }
}
