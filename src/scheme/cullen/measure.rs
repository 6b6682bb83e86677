//! The switch's two neighbour passes on pair lanes ([`crate::neighbours::lanes`]):
//! * [`GradientRows`]: Σ_b m_b v_ab ⊗ ∇_a W_ab(h_a) and the matrix M = Σ_b m_b x_ab ⊗ ∇_a W_ab(h_a)
//!   of the corrected gradient (Frontiere, Raskin & Owen (2017) E.4, E.6), and the signal speed
//!   v_sig,a = max_b [½(c_a + c_b) − min(0, v_ab·x̂_ab)];
//! * [`XiRows`]: Σ_b sgn(∇·v_b) m_b W_ab(h_a), the sum in ξ (F.4).
//!
//! Measured on Noh 2D with PSPH (`sphfmu run --threads 2`, BENCHMARKS.md, issue 19), the two
//! passes took 1.73 s as gathers with a closure per pair.

use crate::kernel::{DimKernel, Kernel};
use crate::neighbours::lanes::{fill_pair, finish_pairs, pad_separations, padded, RowPass, LANES};
use crate::neighbours::unpack;
use crate::particles::Vector;
use crate::system::System;
use nalgebra::SMatrix;

/// What the gradient pass reads of a neighbour.
#[derive(Clone, Copy)]
pub(super) struct GradientRecord<const D: usize> {
    pub x: Vector<D>,
    pub v: Vector<D>,
    pub m: f64,
    pub c: f64,
}

/// One row of the gradient pass: the two matrix sums and v_sig.
#[derive(Clone, Copy)]
pub(super) struct GradientSums<const D: usize> {
    pub v: SMatrix<f64, D, D>,
    pub m: SMatrix<f64, D, D>,
    pub vsig: f64,
}

impl<const D: usize> Default for GradientSums<D> {
    fn default() -> Self {
        Self {
            v: SMatrix::zeros(),
            m: SMatrix::zeros(),
            vsig: 0.0,
        }
    }
}

pub(super) struct GradientRows<'a, const D: usize, K> {
    pub sys: &'a System<D>,
    pub recs: &'a [GradientRecord<D>],
    pub hinv: &'a [f64],
    pub kernel: DimKernel<D, K>,
}

/// A block's columns and pair terms (index k·3 + l for the (k, l) entry of a matrix).
#[derive(Default)]
pub(super) struct GradientScratch(Box<GradientBlock>);

#[derive(Default)]
struct GradientBlock {
    dx: [[f64; LANES]; 3],
    vab: [[f64; LANES]; 3],
    m: [f64; LANES],
    c: [f64; LANES],
    tv: [[f64; LANES]; 9],
    tm: [[f64; LANES]; 9],
    vsig: [f64; LANES],
}

impl<const D: usize, K: Kernel + Copy> RowPass for GradientRows<'_, D, K> {
    type Acc = GradientSums<D>;
    type Scratch = GradientScratch;

    #[inline(always)]
    #[allow(clippy::needless_range_loop)]
    fn row(&self, a: usize, o: &mut GradientSums<D>, scratch: &mut GradientScratch) {
        let blk = &mut *scratch.0;
        let dom = &self.sys.domain;
        let (ra, hinv) = (self.recs[a], self.hinv[a]);
        let k = self.kernel;
        let mut sums = GradientSums::<D>::default();
        for block in self.sys.neighbours.of(a).chunks(LANES) {
            let n = block.len();
            for (i, &e) in block.iter().enumerate() {
                let (b, code) = unpack(e);
                let rb = &self.recs[b];
                fill_pair(dom, (&rb.x, &rb.v), code, &mut blk.dx, &mut blk.vab, i);
                blk.m[i] = rb.m;
                blk.c[i] = rb.c;
            }
            finish_pairs(dom, (&ra.x, &ra.v), &mut blk.dx, &mut blk.vab, n);
            let lanes = pad_separations::<D>(&mut blk.dx, n);
            for i in 0..lanes {
                let mut r2 = 0.0;
                let mut vdx = 0.0;
                for d in 0..D {
                    r2 += blk.dx[d][i] * blk.dx[d][i];
                    vdx += blk.vab[d][i] * blk.dx[d][i];
                }
                // a pair at zero distance has no gradient, but its sound speed counts
                let valid = r2 > 0.0;
                let r = if valid { r2.sqrt() } else { 1.0 };
                let g = if valid { k.dwdr_hinv(r, hinv) / r } else { 0.0 };
                for kk in 0..D {
                    for l in 0..D {
                        let gw = blk.dx[l][i] * g;
                        blk.tv[kk * 3 + l][i] = blk.vab[kk][i] * gw * blk.m[i];
                        blk.tm[kk * 3 + l][i] = blk.dx[kk][i] * gw * blk.m[i];
                    }
                }
                let w = if valid { vdx / r } else { 0.0 };
                blk.vsig[i] = 0.5 * (ra.c + blk.c[i]) - w.min(0.0);
            }
            for i in 0..n {
                for kk in 0..D {
                    for l in 0..D {
                        sums.v[(kk, l)] += blk.tv[kk * 3 + l][i];
                        sums.m[(kk, l)] += blk.tm[kk * 3 + l][i];
                    }
                }
                sums.vsig = sums.vsig.max(blk.vsig[i]);
            }
        }
        *o = sums;
    }
}

/// ξ's sum: Σ_b sgn(∇·v_b) m_b W_ab(h_a); `weight[b]` = sgn(∇·v_b) m_b.
pub(super) struct XiRows<'a, const D: usize, K> {
    pub sys: &'a System<D>,
    pub x: &'a [Vector<D>],
    pub weight: &'a [f64],
    pub hinv: &'a [f64],
    pub kernel: DimKernel<D, K>,
}

/// Columns r² and the weight, and the pair terms.
#[derive(Default)]
pub(super) struct XiScratch(Box<[[f64; LANES]; 3]>);

impl<const D: usize, K: Kernel + Copy> RowPass for XiRows<'_, D, K> {
    type Acc = f64;
    type Scratch = XiScratch;

    #[inline(always)]
    fn row(&self, a: usize, o: &mut f64, scratch: &mut XiScratch) {
        let [r2, wt, t] = &mut *scratch.0;
        let dom = &self.sys.domain;
        let (xa, hinv) = (self.x[a], self.hinv[a]);
        let k = self.kernel;
        let mut sum = 0.0;
        for block in self.sys.neighbours.of(a).chunks(LANES) {
            let n = block.len();
            for (i, &e) in block.iter().enumerate() {
                let (b, code) = unpack(e);
                r2[i] = dom.separation(&xa, &self.x[b], code).norm_squared();
                wt[i] = self.weight[b];
            }
            let lanes = padded(n);
            for i in 0..lanes {
                t[i] = wt[i] * k.w_hinv(r2[i].sqrt(), hinv);
            }
            sum = t[..n].iter().fold(sum, |s, x| s + x);
        }
        *o = sum;
    }
}
