//! The RK velocity gradient (Frontiere, Raskin & Owen (2017) eq 54),
//! ∂β v_i^α = −Σ_j V_j v_ij^α G_ij^β, on pair lanes ([`crate::neighbours::lanes`]), with G_ij
//! from [`super::momentum::corrected_gradient`], the function the force pass uses.

use super::momentum::{corrected_gradient, Coef};
use super::pair_kernels::PairKernel;
use super::reproducing::RkCoefficients;
use crate::neighbours::lanes::{fill_pair, finish_pairs, for_each_row, padded, RowPass, LANES};
use crate::neighbours::unpack;
use crate::system::System;
use nalgebra::SMatrix;

/// RK velocity gradients (eq 54): grad[(α, β)] = ∂β v^α.
pub fn velocity_gradients<const D: usize>(
    sys: &System<D>,
    vol: &[f64],
    coef: &[RkCoefficients<D>],
    kern: &[PairKernel],
) -> Vec<SMatrix<f64, D, D>> {
    let mut out = vec![SMatrix::<f64, D, D>::zeros(); sys.particles.len()];
    let rows = Rows {
        sys,
        vol,
        coef,
        kern,
    };
    for_each_row(&rows, &mut out);
    out
}

struct Rows<'a, const D: usize> {
    sys: &'a System<D>,
    vol: &'a [f64],
    coef: &'a [RkCoefficients<D>],
    kern: &'a [PairKernel],
}

/// A block of pairs: separation, v_ij, the pair kernel and V_j in; V_j v_ij^α G^β out.
/// Padding lanes compute stale values that the sum (to the block's length) never reads.
#[derive(Default)]
struct Scratch(Box<GradientBlock>);

#[derive(Default)]
struct GradientBlock {
    dx: [[f64; LANES]; 3],
    vab: [[f64; LANES]; 3],
    w: [f64; LANES],
    g: [f64; LANES],
    vol: [f64; LANES],
    out: [[[f64; LANES]; 3]; 3],
}

impl<const D: usize> RowPass for Rows<'_, D> {
    type Acc = SMatrix<f64, D, D>;
    type Scratch = Scratch;

    #[inline(always)]
    #[allow(clippy::needless_range_loop)]
    fn row(&self, a: usize, acc: &mut SMatrix<f64, D, D>, scratch: &mut Scratch) {
        let blk = &mut *scratch.0;
        let sys = self.sys;
        let (dom, p) = (&sys.domain, &sys.particles);
        let ca = Coef::from_rk(&self.coef[a]);
        let first = sys.neighbours.offsets[a];
        let mut grad = SMatrix::<f64, D, D>::zeros();
        for (nb, block) in sys.neighbours.of(a).chunks(LANES).enumerate() {
            let n = block.len();
            let kern = &self.kern[first + nb * LANES..];
            for (i, &e) in block.iter().enumerate() {
                let (b, code) = unpack(e);
                fill_pair(
                    dom,
                    (&p.pos[b], &p.vel[b]),
                    code,
                    &mut blk.dx,
                    &mut blk.vab,
                    i,
                );
                blk.w[i] = kern[i].w;
                blk.g[i] = kern[i].g;
                blk.vol[i] = self.vol[b];
            }
            finish_pairs(dom, (&p.pos[a], &p.vel[a]), &mut blk.dx, &mut blk.vab, n);
            let lanes = padded(n);
            for i in 0..lanes {
                let mut x = [0.0; 3];
                for d in 0..D {
                    x[d] = blk.dx[d][i];
                }
                let gij = corrected_gradient::<D>(&ca, &x, blk.w[i], blk.g[i]);
                for al in 0..D {
                    for be in 0..D {
                        blk.out[al][be][i] = blk.vab[al][i] * gij[be] * blk.vol[i];
                    }
                }
            }
            // sum in list order
            for i in 0..n {
                for al in 0..D {
                    for be in 0..D {
                        grad[(al, be)] -= blk.out[al][be][i];
                    }
                }
            }
        }
        *acc = grad;
    }
}
