//! The Newtonian force pass of F1–F4 (hydro Rosswog (2015) Eqs. 55/61 or 64/65; the
//! Chow–Monaghan dissipation of §6.3 with D_ab = ½(g_a + g_b); the decisions are in the parent
//! module's comment) on pair lanes ([`crate::neighbours::lanes`]).
//!
//! With IA gradients g_a = C_a (r_b − r_a) W_ab(h_a) does not lie along x̂_ab, so a lane carries
//! whole vectors and b's matrix (mirrored for an image). Every lane computes exactly what the
//! gather with a closure per pair computed before (the same operations in the same order: the
//! kernel on r/h, the IA product in nalgebra's order, see [`dot`] and [`mat_vec`]), and sums
//! in list order, so the results are the same bits: the snapshots of F1–F4 runs compared
//! byte for byte before and after (BENCHMARKS.md, issue 19).
//!
//! A particle whose τ is near-singular falls back to the kernel gradient. Blocks where every
//! particle takes one kind of gradient compute only that kind; a block that mixes them (rare:
//! a fallback particle in it) computes both and selects per lane.

use super::gradients::{reflect, IaMatrix};
use super::{dissipative_heating, APPROACH_TOLERANCE};
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

/// What a pair reads of one particle, packed into one record.
#[derive(Clone, Copy)]
pub(super) struct Rec<const D: usize> {
    x: Vector<D>,
    v: Vector<D>,
    h: f64,
    hinv: f64,
    /// σ/h^D, W's factor
    wnorm: f64,
    /// σ/h^(D+1), ∂W/∂r's factor
    dnorm: f64,
    m: f64,
    /// X_a
    xw: f64,
    /// A_a = P_a V_a² / (Ω_a X_a)
    a: f64,
    rho: f64,
    c: f64,
    u: f64,
    k: f64,
    /// the particle takes the IA gradient (IA formulation and τ invertible)
    ia: bool,
    wall: bool,
    /// C_a (zero unless `ia`)
    mat: SMatrix<f64, D, D>,
}

/// A particle's pair sums.
#[derive(Clone, Copy)]
pub(super) struct Acc<const D: usize> {
    dv: Vector<D>,
    du_hydro: f64,
    dv_diss: Vector<D>,
    du_diss: f64,
    vsig: f64,
}

impl<const D: usize> Default for Acc<D> {
    fn default() -> Self {
        Self {
            dv: Vector::zeros(),
            du_hydro: 0.0,
            dv_diss: Vector::zeros(),
            du_diss: 0.0,
            vsig: 0.0,
        }
    }
}

/// The pass's inputs.
pub(super) struct RosswogForce<'a, const D: usize> {
    pub sys: &'a System<D>,
    /// X per particle
    pub xw: &'a [f64],
    pub mats: &'a [IaMatrix<D>],
    /// IA gradients (F1, F3), else kernel gradients with grad-h (F2, F4)
    pub ia: bool,
    /// the literal Newtonian limit of Eq. 79 for v_sig
    pub literal: bool,
    /// 1 to keep the conduction part of the dissipation, 0 to drop it
    pub conduction: f64,
}

impl<const D: usize> RosswogForce<'_, D> {
    /// Each particle's pair sums into `out`, its record into `recs` (both kept by the caller
    /// between steps).
    pub fn run(&self, recs: &mut Vec<Rec<D>>, out: &mut Vec<Acc<D>>) {
        let p = &self.sys.particles;
        let kernel = &self.sys.kernel;
        (0..p.len())
            .into_par_iter()
            .with_min_len(LIGHT)
            .map(|a| {
                let v = p.mass[a] / p.rho[a];
                let om = if self.ia { 1.0 } else { p.omega[a] };
                let ia = self.ia && !self.mats[a].fallback;
                let (h, xw) = (p.h[a], self.xw[a]);
                let hinv = 1.0 / h;
                // the factors of `DimKernel::w_normed` and `dwdr_normed`
                let wnorm = kernel.norm(hinv);
                Rec {
                    x: p.pos[a],
                    v: p.vel[a],
                    h,
                    hinv,
                    wnorm,
                    dnorm: wnorm * hinv,
                    m: p.mass[a],
                    xw,
                    a: p.pressure[a] * v * v / (om * xw),
                    rho: p.rho[a],
                    c: p.sound_speed[a],
                    u: p.u[a],
                    k: p.alpha[a],
                    ia,
                    wall: p.body[a] != 0,
                    mat: if ia { self.mats[a].c } else { SMatrix::zeros() },
                }
            })
            .collect_into_vec(recs);
        out.clear();
        out.resize(p.len(), Acc::default());
        self.sys.kernel.visit(Visit {
            pass: self,
            recs,
            out,
        });
    }
}

struct Visit<'a, const D: usize> {
    pass: &'a RosswogForce<'a, D>,
    recs: &'a [Rec<D>],
    out: &'a mut [Acc<D>],
}

impl<const D: usize> KernelVisitor<D> for Visit<'_, D> {
    type Output = ();
    fn visit<K: Kernel + Copy>(self, kernel: &DimKernel<D, K>) {
        let rows = Rows {
            pass: self.pass,
            recs: self.recs,
            kernel: *kernel,
        };
        for_each_row(&rows, self.out);
    }
}

struct Rows<'a, const D: usize, K> {
    pass: &'a RosswogForce<'a, D>,
    recs: &'a [Rec<D>],
    kernel: DimKernel<D, K>,
}

/// A block of up to [`LANES`] pairs: separation, v_ab, image(v_b), b's matrix (row-major) and
/// b's fields. Padding lanes get a zero separation, which marks them as adding nothing.
#[derive(Default)]
struct PairBlock {
    dx: [[f64; LANES]; 3],
    vab: [[f64; LANES]; 3],
    vb: [[f64; LANES]; 3],
    mat: [[f64; LANES]; 9],
    h: [f64; LANES],
    hinv: [f64; LANES],
    wnorm: [f64; LANES],
    dnorm: [f64; LANES],
    m: [f64; LANES],
    xw: [f64; LANES],
    a: [f64; LANES],
    rho: [f64; LANES],
    c: [f64; LANES],
    u: [f64; LANES],
    k: [f64; LANES],
    /// 1 where b takes the IA gradient
    ia: [f64; LANES],
    /// 1 when a and b are both walls (the pair is skipped)
    walls: [f64; LANES],
}

/// A block's pair terms, each to be summed into a's [`Acc`] in list order.
#[derive(Default)]
struct PairTerms {
    dv: [[f64; LANES]; 3],
    du_hydro: [f64; LANES],
    dv_diss: [[f64; LANES]; 3],
    du_diss: [f64; LANES],
    vsig: [f64; LANES],
}

/// A thread's blocks (boxed: about 10 KB).
#[derive(Default)]
struct Scratch(Box<(PairBlock, PairTerms)>);

/// Which gradients a block's pairs take.
const IA_ONLY: u8 = 0;
const KERNEL_ONLY: u8 = 1;
const MIXED: u8 = 2;

impl<const D: usize, K: Kernel + Copy> RowPass for Rows<'_, D, K> {
    type Acc = Acc<D>;
    type Scratch = Scratch;

    #[inline(always)]
    fn row(&self, a: usize, o: &mut Acc<D>, scratch: &mut Scratch) {
        let (blk, t) = &mut *scratch.0;
        let recs = self.recs;
        let dom = &self.pass.sys.domain;
        let ra = &recs[a];
        let mut acc = Acc::<D>::default();
        for block in self.pass.sys.neighbours.of(a).chunks(LANES) {
            let n = block.len();
            let (mut any_ia, mut any_kernel) = (ra.ia, !ra.ia);
            for (i, &e) in block.iter().enumerate() {
                let (b, code) = unpack(e);
                let rb = &recs[b];
                let vb = fill_pair(dom, (&rb.x, &rb.v), code, &mut blk.dx, &mut blk.vab, i);
                for k in 0..D {
                    blk.vb[k][i] = vb[k];
                }
                if rb.ia {
                    // an image carries the mirrored matrix R C R
                    let c = if code == 0 {
                        rb.mat
                    } else {
                        reflect(&rb.mat, code)
                    };
                    for r in 0..D {
                        for s in 0..D {
                            blk.mat[r * D + s][i] = c[(r, s)];
                        }
                    }
                }
                any_ia |= rb.ia;
                any_kernel |= !rb.ia;
                blk.h[i] = rb.h;
                blk.hinv[i] = rb.hinv;
                blk.wnorm[i] = rb.wnorm;
                blk.dnorm[i] = rb.dnorm;
                blk.m[i] = rb.m;
                blk.xw[i] = rb.xw;
                blk.a[i] = rb.a;
                blk.rho[i] = rb.rho;
                blk.c[i] = rb.c;
                blk.u[i] = rb.u;
                blk.k[i] = rb.k;
                blk.ia[i] = if rb.ia { 1.0 } else { 0.0 };
                blk.walls[i] = if ra.wall && rb.wall { 1.0 } else { 0.0 };
            }
            finish_pairs(dom, (&ra.x, &ra.v), &mut blk.dx, &mut blk.vab, n);
            let lanes = pad_separations::<D>(&mut blk.dx, n);
            match (any_ia, any_kernel) {
                (true, false) => self.terms::<IA_ONLY>(ra, blk, t, lanes),
                (false, true) => self.terms::<KERNEL_ONLY>(ra, blk, t, lanes),
                _ => self.terms::<MIXED>(ra, blk, t, lanes),
            }
            // Sum in list order, as the gather did.
            for i in 0..n {
                for k in 0..D {
                    acc.dv[k] -= t.dv[k][i];
                    acc.dv_diss[k] -= t.dv_diss[k][i];
                }
                acc.du_hydro += t.du_hydro[i];
                acc.du_diss += t.du_diss[i];
                acc.vsig = acc.vsig.max(t.vsig[i]);
            }
        }
        *o = acc;
    }
}

/// a·b in nalgebra's order (its `dotx`: written out for 2 and 3 components, a sum from zero
/// otherwise), so that a lane gives the bits the nalgebra expressions gave.
#[inline(always)]
fn dot<const D: usize>(a: &[f64; 3], b: &[f64; 3]) -> f64 {
    match D {
        1 => 0.0 + a[0] * b[0],
        2 => a[0] * b[0] + a[1] * b[1],
        _ => a[0] * b[0] + a[1] * b[1] + a[2] * b[2],
    }
}

/// M·x in nalgebra's order (its `gemv`: column by column, y = M_r0 x_0, then
/// y = M_rs x_s + y, which is y + M_rs x_s to the bit).
#[inline(always)]
fn mat_vec<const D: usize>(m: &[[f64; 3]; 3], x: &[f64; 3]) -> [f64; 3] {
    let mut y = [0.0; 3];
    for r in 0..D {
        y[r] = m[r][0] * x[0];
        for s in 1..D {
            y[r] += m[r][s] * x[s];
        }
    }
    y
}

/// g = C (r_b − r_a) W, the IA gradient (Eqs. 64/65), with `minus_dx` = r_b − r_a.
#[inline(always)]
fn ia_gradient<const D: usize>(c: &[[f64; 3]; 3], minus_dx: &[f64; 3], w: f64) -> [f64; 3] {
    let mut g = mat_vec::<D>(c, minus_dx);
    for gd in g.iter_mut() {
        *gd *= w;
    }
    g
}

/// g = (dW/dr / r) x_ab, the kernel gradient.
#[inline(always)]
fn kernel_gradient(dx: &[f64; 3], dwdr: f64, r: f64) -> [f64; 3] {
    let f = dwdr / r;
    [dx[0] * f, dx[1] * f, dx[2] * f]
}

impl<const D: usize, K: Kernel + Copy> Rows<'_, D, K> {
    /// The pair terms of one block, one pair per lane, selects only (so the loop becomes
    /// SIMD). `MODE` says which gradients the block's particles take ([`IA_ONLY`],
    /// [`KERNEL_ONLY`] or [`MIXED`]). Per pair, as in `super::pair_gradient`:
    ///   g_a = C_a (r_b − r_a) W(r, h_a) (IA, Eqs. 64/65)  or  (dW/dr(r, h_a)/r) x_ab,
    /// the hydro terms −(A_a X_b g_a + A_b X_a g_b) and X_b v_ab·g_a (Eqs. 55/61, 64/65), and,
    /// for an approaching pair, the dissipation (§6.3) with D_ab = ½(g_a + g_b).
    #[inline(always)]
    #[allow(clippy::needless_range_loop)]
    fn terms<const MODE: u8>(&self, ra: &Rec<D>, b: &PairBlock, out: &mut PairTerms, lanes: usize) {
        // Row constants as values, so that the loop does not reread them through references.
        let ra = *ra;
        let k = self.kernel;
        let literal = self.pass.literal;
        let conduction = self.pass.conduction;
        let mut ca = [[0.0; 3]; 3];
        for r in 0..D {
            for s in 0..D {
                ca[r][s] = ra.mat[(r, s)];
            }
        }
        for i in 0..lanes {
            let mut dx = [0.0; 3];
            let mut v = [0.0; 3];
            let mut vb = [0.0; 3];
            let mut va = [0.0; 3];
            for d in 0..D {
                dx[d] = b.dx[d][i];
                v[d] = b.vab[d][i];
                vb[d] = b.vb[d][i];
                va[d] = ra.v[d];
            }
            let r2 = 0.0 + dot::<D>(&dx, &dx);
            let valid = r2 > 0.0 && b.walls[i] == 0.0;
            let r = r2.sqrt();
            let mut minus_dx = [0.0; 3];
            for d in 0..D {
                minus_dx[d] = -dx[d];
            }
            // g_a and g_b (`super::pair_gradient`)
            let ia_pair = || {
                let mut cb = [[0.0; 3]; 3];
                for r in 0..D {
                    for s in 0..D {
                        cb[r][s] = b.mat[r * D + s][i];
                    }
                }
                (
                    ia_gradient::<D>(&ca, &minus_dx, k.w_normed(r, ra.h, ra.wnorm)),
                    ia_gradient::<D>(&cb, &minus_dx, k.w_normed(r, b.h[i], b.wnorm[i])),
                )
            };
            let kernel_pair = || {
                (
                    kernel_gradient(&dx, k.dwdr_normed(r, ra.hinv, ra.dnorm), r),
                    kernel_gradient(&dx, k.dwdr_normed(r, b.hinv[i], b.dnorm[i]), r),
                )
            };
            let (ga, gb) = match MODE {
                IA_ONLY => ia_pair(),
                KERNEL_ONLY => kernel_pair(),
                _ => {
                    let (ia_a, ia_b) = ia_pair();
                    let (k_a, k_b) = kernel_pair();
                    let b_ia = b.ia[i] != 0.0;
                    let mut ga = [0.0; 3];
                    let mut gb = [0.0; 3];
                    for d in 0..D {
                        ga[d] = if ra.ia { ia_a[d] } else { k_a[d] };
                        gb[d] = if b_ia { ia_b[d] } else { k_b[d] };
                    }
                    (ga, gb)
                }
            };
            // hydro (Eqs. 55/61 or 64/65), without the 1/m_a factor
            let (s_a, s_b) = (ra.a * b.xw[i], b.a[i] * ra.xw);
            let du_hydro = b.xw[i] * dot::<D>(&v, &ga);
            let mut e = [0.0; 3];
            for d in 0..D {
                e[d] = dx[d] / r;
            }
            let w = dot::<D>(&v, &e);
            let c_max = ra.c.max(b.c[i]);
            let vsig = if literal {
                (ra.c + dot::<D>(&va, &e).abs()).max(b.c[i] + dot::<D>(&vb, &e).abs())
            } else {
                c_max - w.min(0.0)
            };
            // approaching beyond round-off (the parent's APPROACH_TOLERANCE)
            let approach = w < -APPROACH_TOLERANCE * c_max;
            let mut dab = [0.0; 3];
            for d in 0..D {
                dab[d] = (ga[d] + gb[d]) * 0.5;
            }
            let kab = 0.5 * (ra.k + b.k[i]);
            let rho_bar = 0.5 * (ra.rho + b.rho[i]);
            let pi = -kab * vsig * w / rho_bar;
            let mb = b.m[i];
            let du_diss = mb
                * dissipative_heating(
                    kab * vsig / rho_bar,
                    pi,
                    conduction * (ra.u - b.u[i]),
                    dot::<D>(&e, &dab),
                    dot::<D>(&v, &dab),
                );
            let diss = valid && approach;
            for d in 0..D {
                let hydro = ga[d] * s_a + gb[d] * s_b;
                out.dv[d][i] = if valid { hydro } else { 0.0 };
                let visc = dab[d] * (mb * pi);
                out.dv_diss[d][i] = if diss { visc } else { 0.0 };
            }
            out.du_hydro[i] = if valid { du_hydro } else { 0.0 };
            out.vsig[i] = if valid { vsig } else { 0.0 };
            out.du_diss[i] = if diss { du_diss } else { 0.0 };
        }
    }
}

/// The accelerations, du/dt and v_sig from the pair sums: du/dt = (A_a/m_a) Σ X_b v_ab·g_a
/// (Rosswog (2015) §6.2/6.3, u-form) plus the heating.
pub(super) fn derivatives<const D: usize>(rec: &Rec<D>, o: &Acc<D>) -> (Vector<D>, f64, f64) {
    let m = rec.m;
    let du = rec.a / m * o.du_hydro + o.du_diss;
    (o.dv / m + o.dv_diss, du, o.vsig)
}
