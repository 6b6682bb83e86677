//! CRKSPH's momentum and energy pass (Frontiere, Raskin & Owen (2017) eq 64 with P → P + Q,
//! eq 78, and the limited viscosity of eqs 45–55, 69–74; the decisions are in the parent
//! module's comment) on pair lanes ([`crate::neighbours::lanes`]), keeping every pair
//! acceleration a_ij for the compatible energy update.
//!
//! Per pair: G_ij from i's coefficients at x_ij, G_ji from j's (mirrored for an image) at
//! x_ji = −x_ij, both by [`corrected_gradient`] so that row j computes bit for bit the G's that
//! row i did, with their roles swapped. The pressure sum is written (P_i + P_j) + (Q_i + Q_j),
//! symmetric in (i, j), so m_i a_ij = −m_j a_ji up to the one product V_i V_j / m_i · m_i.
//!
//! The closeness factor of the limiter (eq 74) needs an exponential, which would keep the
//! whole loop scalar; it gets a loop of its own, which evaluates it only for the lanes that are
//! closer than η_crit.
//!
//! Measured on Noh 2D with CRKSPH (`tools/bench_peer.py`'s case, `sphfmu run --threads 2`):
//! the scalar gather with a closure per pair took 8.3 s of 32 s, a fifth of it in `pair_q`
//! on nalgebra vectors (BENCHMARKS.md, issue 19).

use super::super::paper_step::{PairRow, PairSums};
use super::pair_kernels::PairKernel;
use super::reproducing::RkCoefficients;
use super::viscosity::ViscosityParams;
use crate::kernel::SUPPORT;
use crate::neighbours::lanes::{
    fill_pair, finish_pairs, for_each_row_widest, padded, RowPass, LANES,
};
use crate::neighbours::unpack;
use crate::particles::Vector;
use crate::scheme::rosswog::gradients::reflect;
use crate::system::System;
use crate::threads::LIGHT;
use nalgebra::SMatrix;
use rayon::prelude::*;
use std::marker::PhantomData;

/// The pass's inputs: the state's volumes, coefficients and pair kernels, and the RK
/// velocity gradients (eq 54), grad[(α, β)] = ∂β v^α.
pub(super) struct CrkMomentum<'a, const D: usize> {
    pub sys: &'a System<D>,
    pub vol: &'a [f64],
    pub coef: &'a [RkCoefficients<D>],
    pub kern: &'a [PairKernel],
    pub grads: &'a [SMatrix<f64, D, D>],
    pub visc: ViscosityParams,
}

/// What a pair reads of one particle, packed into one record.
#[derive(Clone, Copy)]
struct CrkRecord<const D: usize> {
    x: Vector<D>,
    v: Vector<D>,
    hinv: f64,
    m: f64,
    rho: f64,
    c: f64,
    p: f64,
    vol: f64,
    wall: bool,
    coef: RkCoefficients<D>,
    grad: SMatrix<f64, D, D>,
}

impl<const D: usize> CrkMomentum<'_, D> {
    /// The pair sums per particle, and a_ij into `slots` (one per listed pair, in list order);
    /// the particles' records live in `scratch` between steps.
    pub fn run(
        &self,
        slots: &mut [Vector<D>],
        scratch: &mut crate::scratch::Scratch,
    ) -> Vec<PairSums<D>> {
        let p = &self.sys.particles;
        let mut recs: Vec<CrkRecord<D>> = scratch.take();
        (0..p.len())
            .into_par_iter()
            .with_min_len(LIGHT)
            .map(|a| CrkRecord {
                x: p.pos[a],
                v: p.vel[a],
                hinv: 1.0 / p.h[a],
                m: p.mass[a],
                rho: p.rho[a],
                c: p.sound_speed[a],
                p: p.pressure[a],
                vol: self.vol[a],
                wall: p.body[a] != 0,
                coef: self.coef[a],
                grad: self.grads[a],
            })
            .collect_into_vec(&mut recs);
        let mut out = PairRow::split(self.sys, slots);
        let rows = Rows {
            pass: self,
            recs: &recs,
            _slots: PhantomData,
        };
        for_each_row_widest(&rows, &mut out);
        scratch.keep(recs);
        PairRow::sums(out)
    }
}

struct Rows<'a, 's, const D: usize> {
    pass: &'a CrkMomentum<'a, D>,
    recs: &'a [CrkRecord<D>],
    _slots: PhantomData<&'s ()>,
}

/// A block of up to [`LANES`] pairs: the pair kernel, separation, v_ij and b's fields
/// (coefficients and velocity gradient mirrored for an image). Padding lanes are marked
/// `skip` and add nothing; their other fields are stale but finite.
#[derive(Default)]
struct PairBlock {
    dx: [[f64; LANES]; 3],
    vab: [[f64; LANES]; 3],
    w: [f64; LANES],
    g: [f64; LANES],
    hinv: [f64; LANES],
    rho: [f64; LANES],
    c: [f64; LANES],
    p: [f64; LANES],
    vol: [f64; LANES],
    /// 1 for a wall–wall pair or a padding lane
    skip: [f64; LANES],
    a: [f64; LANES],
    b: [[f64; LANES]; 3],
    ga: [[f64; LANES]; 3],
    /// gb[α][γ] = ∂γ B^α
    gb: [[[f64; LANES]; 3]; 3],
    /// gv[α][β] = ∂β v^α
    gv: [[[f64; LANES]; 3]; 3],
}

/// A block's pair terms.
#[derive(Default)]
struct PairTerms {
    /// the limiter's closeness factor (eq 74), or 0 with the limiter off
    close: [f64; LANES],
    acc: [[f64; LANES]; 3],
    dudt: [f64; LANES],
    q: [f64; LANES],
    approach: [f64; LANES],
}

/// A thread's blocks (boxed: about 15 KB).
#[derive(Default)]
struct Scratch(Box<(PairBlock, PairTerms)>);

/// One side's correction coefficients as plain arrays (components past D zero), the form a
/// lane loop reads.
#[derive(Clone, Copy, Default)]
pub(super) struct Coef {
    pub a: f64,
    pub b: [f64; 3],
    pub ga: [f64; 3],
    /// gb[α][γ] = ∂γ B^α
    pub gb: [[f64; 3]; 3],
}

impl Coef {
    pub fn from_rk<const D: usize>(c: &RkCoefficients<D>) -> Self {
        let pad = |k: usize| if k < D { c.b[k] } else { 0.0 };
        Self {
            a: c.a,
            b: std::array::from_fn(pad),
            ga: std::array::from_fn(|k| if k < D { c.grad_a[k] } else { 0.0 }),
            gb: std::array::from_fn(|k| {
                std::array::from_fn(|l| {
                    if k < D && l < D {
                        c.grad_b[(k, l)]
                    } else {
                        0.0
                    }
                })
            }),
        }
    }
}

/// The corrected-kernel gradient G (eq 9) of a side with coefficients `c` at separation `x`
/// from it, for the pair kernel W̄ = `w`, ∇W̄ = `g`·x (Frontiere, Raskin & Owen (2017) eqs 8–9):
/// G^γ = A(1 + B·x) g x^γ + ∂γA (1 + B·x) W̄ + A(∂γB^α x^α + B^γ) W̄.
#[inline(always)]
#[allow(clippy::needless_range_loop)] // components 0..D of padded [f64; 3] arrays
pub(super) fn corrected_gradient<const D: usize>(
    c: &Coef,
    x: &[f64; 3],
    w: f64,
    g: f64,
) -> [f64; 3] {
    let mut bx = 0.0;
    for k in 0..D {
        bx += c.b[k] * x[k];
    }
    let lin = 1.0 + bx;
    let (radial, lw, aw) = (c.a * lin * g, lin * w, c.a * w);
    let mut out = [0.0; 3];
    for gam in 0..D {
        let mut gbx = 0.0;
        for al in 0..D {
            gbx += c.gb[al][gam] * x[al];
        }
        out[gam] = x[gam] * radial + c.ga[gam] * lw + (gbx + c.b[gam]) * aw;
    }
    out
}

/// x·(M x) for a D×D matrix M given by rows.
#[inline(always)]
#[allow(clippy::needless_range_loop)] // components 0..D of padded arrays
fn quadratic<const D: usize>(m: &[[f64; 3]; 3], x: &[f64; 3]) -> f64 {
    let mut s = 0.0;
    for al in 0..D {
        let mut row = 0.0;
        for be in 0..D {
            row += m[al][be] * x[be];
        }
        s += x[al] * row;
    }
    s
}

impl<'s, const D: usize> RowPass for Rows<'_, 's, D> {
    type Acc = PairRow<'s, D>;
    type Scratch = Scratch;

    #[inline(always)]
    fn row(&self, a: usize, o: &mut PairRow<'s, D>, scratch: &mut Scratch) {
        let (blk, t) = &mut *scratch.0;
        let sys = self.pass.sys;
        let dom = &sys.domain;
        let ra = &self.recs[a];
        let first = sys.neighbours.offsets[a];
        let mut sums = PairSums::<D>::default();
        let entries = sys.neighbours.of(a);
        for (nb, (block, slots)) in entries
            .chunks(LANES)
            .zip(o.slots.chunks_mut(LANES))
            .enumerate()
        {
            let n = block.len();
            let kern = &self.pass.kern[first + nb * LANES..];
            for (i, &e) in block.iter().enumerate() {
                let (b, code) = unpack(e);
                let rb = &self.recs[b];
                fill_pair(dom, (&rb.x, &rb.v), code, &mut blk.dx, &mut blk.vab, i);
                blk.w[i] = kern[i].w;
                blk.g[i] = kern[i].g;
                blk.hinv[i] = rb.hinv;
                blk.rho[i] = rb.rho;
                blk.c[i] = rb.c;
                blk.p[i] = rb.p;
                blk.vol[i] = rb.vol;
                blk.skip[i] = if ra.wall && rb.wall { 1.0 } else { 0.0 };
                let (cb, gv) = if code == 0 {
                    (rb.coef, rb.grad)
                } else {
                    (rb.coef.reflected(code), reflect(&rb.grad, code))
                };
                blk.a[i] = cb.a;
                for k in 0..D {
                    blk.b[k][i] = cb.b[k];
                    blk.ga[k][i] = cb.grad_a[k];
                    for l in 0..D {
                        blk.gb[k][l][i] = cb.grad_b[(k, l)];
                        blk.gv[k][l][i] = gv[(k, l)];
                    }
                }
            }
            finish_pairs(dom, (&ra.x, &ra.v), &mut blk.dx, &mut blk.vab, n);
            let lanes = padded(n);
            for i in n..lanes {
                blk.skip[i] = 1.0;
            }
            self.closeness(ra, blk, t, lanes);
            self.terms(ra, blk, t, lanes);
            // Sum in list order; keep each a_ij.
            for (i, slot) in slots.iter_mut().enumerate() {
                let mut a_ij = Vector::<D>::zeros();
                for k in 0..D {
                    a_ij[k] = t.acc[k][i];
                }
                *slot = a_ij;
                sums.acc += a_ij;
                sums.dudt += t.dudt[i];
                sums.q_max = sums.q_max.max(t.q[i]);
                sums.approach = sums.approach.max(t.approach[i]);
            }
        }
        o.sums = sums;
    }
}

impl<const D: usize> Rows<'_, '_, D> {
    /// The limiter's closeness factor of every lane (eq 74): exp(−((η_ij − η_crit)/η_fold)²)
    /// closer than η_crit, else 1, with η_ij = |x_ij| / max(h_i, h_j) in the paper's units.
    /// The distance loop is SIMD; the exponential runs only for the close lanes.
    #[inline(always)]
    fn closeness(&self, ra: &CrkRecord<D>, b: &PairBlock, t: &mut PairTerms, lanes: usize) {
        let visc = self.pass.visc;
        if !visc.limiter {
            t.close[..lanes].fill(0.0);
            return;
        }
        let to_paper = visc.native_support / SUPPORT;
        let hinv_a = ra.hinv;
        for i in 0..lanes {
            let mut r2 = 0.0;
            for d in 0..D {
                r2 += b.dx[d][i] * b.dx[d][i];
            }
            let r = r2.sqrt();
            t.close[i] = (r * to_paper * hinv_a).min(r * to_paper * b.hinv[i]);
        }
        for c in t.close[..lanes].iter_mut() {
            *c = if *c < visc.eta_crit {
                (-((*c - visc.eta_crit) / visc.eta_fold).powi(2)).exp()
            } else {
                1.0
            };
        }
    }

    /// The pair terms of one block, one pair per lane, selects only (so the loop becomes
    /// SIMD): a_ij = −½ (V_i V_j / m_i)[(P_i + P_j) + (Q_i + Q_j)](G_ij − G_ji) (eq 64),
    /// du_i/dt ∋ ½ (V_i V_j / m_i)(P_j + Q_j) v_ij·(G_ij − G_ji) (eq 78), and the limited
    /// Monaghan–Gingold Q_i, Q_j of [`super::viscosity::pair_q`], which this computes the same way.
    #[inline(always)]
    #[allow(clippy::needless_range_loop)]
    fn terms(&self, ra: &CrkRecord<D>, b: &PairBlock, t: &mut PairTerms, lanes: usize) {
        let visc = self.pass.visc;
        let to_paper = visc.native_support / SUPPORT;
        let s_a = to_paper * ra.hinv;
        let ca = Coef::from_rk(&ra.coef);
        let gva: [[f64; 3]; 3] = std::array::from_fn(|k| {
            std::array::from_fn(|l| if k < D && l < D { ra.grad[(k, l)] } else { 0.0 })
        });
        let (rho_a, c_a, p_a) = (ra.rho, ra.c, ra.p);
        let vv_a = ra.vol / ra.m;
        for i in 0..lanes {
            let mut x = [0.0; 3];
            let mut xn = [0.0; 3];
            let mut vij = [0.0; 3];
            let mut r2 = 0.0;
            let mut vdx = 0.0;
            for d in 0..D {
                x[d] = b.dx[d][i];
                xn[d] = -x[d];
                vij[d] = b.vab[d][i];
                r2 += x[d] * x[d];
                vdx += vij[d] * x[d];
            }
            let r = r2.sqrt();
            let cb = Coef {
                a: b.a[i],
                b: std::array::from_fn(|k| b.b[k][i]),
                ga: std::array::from_fn(|k| b.ga[k][i]),
                gb: std::array::from_fn(|k| std::array::from_fn(|l| b.gb[k][l][i])),
            };
            let gvb: [[f64; 3]; 3] =
                std::array::from_fn(|k| std::array::from_fn(|l| b.gv[k][l][i]));
            let gij = corrected_gradient::<D>(&ca, &x, b.w[i], b.g[i]);
            let gji = corrected_gradient::<D>(&cb, &xn, b.w[i], b.g[i]);
            // limiter (eqs 69–74): van Leer on r = x·∇v_i·x / x·∇v_j·x, times the closeness
            let num = quadratic::<D>(&gva, &x);
            let den0 = quadratic::<D>(&gvb, &x);
            let den = if den0 < 0.0 { -1.0 } else { 1.0 } * den0.abs().max(1e-30);
            let ratio = num / den;
            let van_leer = if ratio > 0.0 {
                (4.0 * ratio / ((1.0 + ratio) * (1.0 + ratio))).min(1.0)
            } else {
                0.0
            };
            let phi = van_leer * t.close[i];
            // v̂_ij = v_ij − (φ/2)(∇v_i + ∇v_j)·x_ij; μ = min(0, v̂·η/(η² + ε²)), η = x/h
            let mut vhat_x = 0.0;
            for al in 0..D {
                let mut sx = 0.0;
                for be in 0..D {
                    sx += (gva[al][be] + gvb[al][be]) * x[be];
                }
                vhat_x += (vij[al] - sx * (0.5 * phi)) * x[al];
            }
            let s_b = to_paper * b.hinv[i];
            let mu_a = (vhat_x * s_a / (r2 * s_a * s_a + visc.eps2)).min(0.0);
            let mu_b = (vhat_x * s_b / (r2 * s_b * s_b + visc.eps2)).min(0.0);
            let q_a = rho_a * (-visc.c_l * c_a * mu_a + visc.c_q * mu_a * mu_a);
            let q_b = b.rho[i] * (-visc.c_l * b.c[i] * mu_b + visc.c_q * mu_b * mu_b);
            let vv = vv_a * b.vol[i];
            let scale = -0.5 * vv * ((p_a + b.p[i]) + (q_a + q_b));
            let live = b.skip[i] == 0.0;
            let mut vdg = 0.0;
            for d in 0..D {
                let dg = gij[d] - gji[d];
                vdg += vij[d] * dg;
                t.acc[d][i] = if live { dg * scale } else { 0.0 };
            }
            let rr = if r > 0.0 { r } else { 1.0 };
            t.dudt[i] = if live {
                0.5 * vv * (b.p[i] + q_b) * vdg
            } else {
                0.0
            };
            t.q[i] = if live { 4.0 * q_a } else { 0.0 };
            t.approach[i] = if live && r > 0.0 { -vdx / rr } else { 0.0 };
        }
    }
}
