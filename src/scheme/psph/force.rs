//! PSPH's force pass (G.4, the u equation, G.6 and G.10–G.12; the decisions are in the parent
//! module's comment) on pair lanes ([`crate::neighbours::lanes`]), keeping every pair
//! acceleration a_ij for the compatible energy update.
//!
//! Every pair vector of the pass lies along x̂_ij (∇W_i, ∇W_j and q_ij), so a lane works with
//! scalars along the pair and multiplies by x_ij once at the end. The pair's scalar factor is
//! written symmetric in (i, j) (sums of products that swap into each other), so a_ij and a_ji
//! differ only by sign and the mass each carries.
//!
//! Measured on Noh 2D (`models/noh2d.toml` with `[scheme] name = "psph"` and the preset's own
//! kernel, `sphfmu run --threads 2`), the pass took 4.93 s as a gather with a closure per pair
//! (BENCHMARKS.md, issue 19).

use super::super::crksph::viscosity::ViscosityParams;
use super::super::paper_step::{PairRow, PairSums};
use crate::kernel::{DimKernel, Kernel, KernelVisitor, SUPPORT};
use crate::neighbours::lanes::{
    fill_pair, finish_pairs, for_each_row_widest, pad_separations, RowPass, LANES,
};
use crate::neighbours::unpack;
use crate::particles::Vector;
use crate::system::System;
use crate::threads::LIGHT;
use rayon::prelude::*;
use std::marker::PhantomData;

/// What a pair reads of one particle, packed into one record.
#[derive(Clone, Copy)]
#[repr(C)]
struct PsphRecord<const D: usize> {
    x: Vector<D>,
    v: Vector<D>,
    hinv: f64,
    m: f64,
    /// 1/(m u), f_ij's denominator (G.7), or 0 for cold gas, where f = 1
    mu_inv: f64,
    /// C of f_ij = 1 − C_i/(m_j u_j) (G.7)
    fc: f64,
    /// 1/P, or 0 for cold gas (no pressure force: f/P → 0 rather than 0/0)
    pinv: f64,
    u: f64,
    rho: f64,
    c: f64,
    p: f64,
    alpha: f64,
    wall: bool,
}

/// The pass's inputs.
pub(super) struct PsphForce<'a, const D: usize> {
    pub sys: &'a System<D>,
    /// C_i of G.7 per particle
    pub fcoef: &'a [f64],
    pub gamma: f64,
    pub visc: ViscosityParams,
    /// α_C of the conductivity (G.10–G.12)
    pub alpha_c: f64,
}

impl<const D: usize> PsphForce<'_, D> {
    /// The pair sums per particle, and a_ij into `slots` (one per listed pair, in list order);
    /// the particles' records live in `scratch` between steps.
    pub fn run(
        &self,
        slots: &mut [Vector<D>],
        scratch: &mut crate::scratch::Scratch,
    ) -> Vec<PairSums<D>> {
        let p = &self.sys.particles;
        let mut recs: Vec<PsphRecord<D>> = scratch.take();
        (0..p.len())
            .into_par_iter()
            .with_min_len(LIGHT)
            .map(|a| PsphRecord {
                x: p.pos[a],
                v: p.vel[a],
                hinv: 1.0 / p.h[a],
                m: p.mass[a],
                mu_inv: if p.mass[a] * p.u[a] > 0.0 {
                    1.0 / (p.mass[a] * p.u[a])
                } else {
                    0.0
                },
                fc: self.fcoef[a],
                pinv: if p.pressure[a] > 0.0 {
                    1.0 / p.pressure[a]
                } else {
                    0.0
                },
                u: p.u[a],
                rho: p.rho[a],
                c: p.sound_speed[a],
                p: p.pressure[a],
                alpha: p.alpha[a],
                wall: p.body[a] > 0,
            })
            .collect_into_vec(&mut recs);
        let mut out = PairRow::split(self.sys, slots);
        self.sys.kernel.visit(Visit {
            pass: self,
            recs: &recs,
            out: &mut out,
        });
        scratch.keep(recs);
        PairRow::sums(out)
    }
}

struct Visit<'a, 's, const D: usize> {
    pass: &'a PsphForce<'a, D>,
    recs: &'a [PsphRecord<D>],
    out: &'a mut [PairRow<'s, D>],
}

impl<'s, const D: usize> KernelVisitor<D> for Visit<'_, 's, D> {
    type Output = ();
    fn visit<K: Kernel + Copy>(self, kernel: &DimKernel<D, K>) {
        let rows = Rows::<D, K> {
            pass: self.pass,
            recs: self.recs,
            kernel: *kernel,
            _slots: PhantomData,
        };
        for_each_row_widest(&rows, self.out);
    }
}

struct Rows<'a, 's, const D: usize, K> {
    pass: &'a PsphForce<'a, D>,
    recs: &'a [PsphRecord<D>],
    kernel: DimKernel<D, K>,
    _slots: PhantomData<&'s ()>,
}

/// A block of up to [`LANES`] pairs: separation, v_ij and b's fields. Padding lanes get a
/// zero separation, which marks them as adding nothing; their other fields are stale but
/// finite (or give NaN that a select drops).
#[derive(Default)]
struct PairBlock {
    dx: [[f64; LANES]; 3],
    vab: [[f64; LANES]; 3],
    hinv: [f64; LANES],
    m: [f64; LANES],
    mu_inv: [f64; LANES],
    fc: [f64; LANES],
    pinv: [f64; LANES],
    u: [f64; LANES],
    rho: [f64; LANES],
    c: [f64; LANES],
    p: [f64; LANES],
    alpha: [f64; LANES],
    /// 1 when a and b are both walls (the pair is skipped)
    walls: [f64; LANES],
}

/// A block's pair terms: a_ij = s·x_ij, du/dt, the conduction exchange, Q_i and −w.
#[derive(Default)]
struct PairTerms {
    s: [f64; LANES],
    dudt: [f64; LANES],
    exchange: [f64; LANES],
    q: [f64; LANES],
    approach: [f64; LANES],
}

/// A thread's blocks (boxed: about 6 KB).
#[derive(Default)]
pub(super) struct Scratch(Box<(PairBlock, PairTerms)>);

impl<'s, const D: usize, K: Kernel + Copy> RowPass for Rows<'_, 's, D, K> {
    type Acc = PairRow<'s, D>;
    type Scratch = Scratch;

    #[inline(always)]
    fn row(&self, a: usize, o: &mut PairRow<'s, D>, scratch: &mut Scratch) {
        let (blk, t) = &mut *scratch.0;
        let recs = self.recs;
        let dom = &self.pass.sys.domain;
        let ra = &recs[a];
        let mut sums = PairSums::<D>::default();
        let entries = self.pass.sys.neighbours.of(a);
        for (block, slots) in entries.chunks(LANES).zip(o.slots.chunks_mut(LANES)) {
            let n = block.len();
            for (i, &e) in block.iter().enumerate() {
                let (b, code) = unpack(e);
                let rb = &recs[b];
                fill_pair(dom, (&rb.x, &rb.v), code, &mut blk.dx, &mut blk.vab, i);
                blk.hinv[i] = rb.hinv;
                blk.m[i] = rb.m;
                blk.mu_inv[i] = rb.mu_inv;
                blk.fc[i] = rb.fc;
                blk.pinv[i] = rb.pinv;
                blk.u[i] = rb.u;
                blk.rho[i] = rb.rho;
                blk.c[i] = rb.c;
                blk.p[i] = rb.p;
                blk.alpha[i] = rb.alpha;
                blk.walls[i] = if ra.wall && rb.wall { 1.0 } else { 0.0 };
            }
            finish_pairs(dom, (&ra.x, &ra.v), &mut blk.dx, &mut blk.vab, n);
            let lanes = pad_separations::<D>(&mut blk.dx, n);
            self.terms(ra, blk, t, lanes);
            // Sum in list order; keep each a_ij.
            for (i, slot) in slots.iter_mut().enumerate() {
                let mut a_ij = Vector::<D>::zeros();
                for k in 0..D {
                    a_ij[k] = t.s[i] * blk.dx[k][i];
                }
                *slot = a_ij;
                sums.acc += a_ij;
                sums.dudt += t.dudt[i];
                sums.exchange += t.exchange[i];
                sums.q_max = sums.q_max.max(t.q[i]);
                sums.approach = sums.approach.max(t.approach[i]);
            }
        }
        sums.dudt += sums.exchange;
        o.sums = sums;
    }
}

impl<const D: usize, K: Kernel + Copy> Rows<'_, '_, D, K> {
    /// The pair terms of one block, one pair per lane, selects only (so the loop becomes
    /// SIMD). With r̂ = x_ij/r, ∇W_i = F_i r̂ and ∇W_j = F_j r̂ (F = ∂W/∂r at h_i, h_j):
    ///   a_ij = −m_j [(γ−1)² u_i u_j (f_ij F_i/P_i + f_ji F_j/P_j) + Π̄ (F_i + F_j)] r̂   (G.4)
    /// with Π̄ = ½(Q_i/ρ_i + Q_j/ρ_j)/(ρ_i + ρ_j) from the Monaghan–Gingold Q (G.6), and
    ///   du_i/dt ∋ m_j [(γ−1)² u_i u_j (f_ij/P_i) F_i + ½ Π̄ (F_i + F_j)] w,  w = v_ij·r̂.
    #[inline(always)]
    #[allow(clippy::needless_range_loop)]
    fn terms(&self, ra: &PsphRecord<D>, b: &PairBlock, out: &mut PairTerms, lanes: usize) {
        // Row constants as values, so that the loop does not reread them through references.
        let k = self.kernel;
        let ra = *ra;
        let visc = self.pass.visc;
        let g1 = self.pass.gamma - 1.0;
        let g1g1 = g1 * g1;
        let alpha_c = self.pass.alpha_c;
        // η = x_ij/h in the paper's kernel units (its support η_max where ours is 2h)
        let to_paper = visc.native_support / SUPPORT;
        let s_a = to_paper * ra.hinv;
        for i in 0..lanes {
            let mut r2 = 0.0;
            let mut vdx = 0.0;
            for d in 0..D {
                r2 += b.dx[d][i] * b.dx[d][i];
                vdx += b.vab[d][i] * b.dx[d][i];
            }
            let valid = r2 > 0.0 && b.walls[i] == 0.0;
            let r = if valid { r2.sqrt() } else { 1.0 };
            let rinv = 1.0 / r;
            let fa = k.dwdr_hinv(r, ra.hinv);
            let fb = k.dwdr_hinv(r, b.hinv[i]);
            let w = vdx * rinv;
            let uu = g1g1 * (ra.u * b.u[i]);
            // f_ij = 1 − C_i/(m_j u_j) (G.7); both written alike, so they swap exactly
            let f_ij = 1.0 - ra.fc * b.mu_inv[i];
            let f_ji = 1.0 - b.fc[i] * ra.mu_inv;
            let fi = f_ij * ra.pinv;
            let fj = f_ji * b.pinv[i];
            // viscosity (G.6) with C_l, C_q scaled by ᾱ (Cullen–Dehnen); μ = min(0, v·η/(η² + ε²))
            let alpha_bar = 0.5 * (ra.alpha + b.alpha[i]);
            let (cl, cq) = (visc.c_l * alpha_bar, visc.c_q * alpha_bar);
            let s_b = to_paper * b.hinv[i];
            let mu_a = (vdx * s_a / (r2 * s_a * s_a + visc.eps2)).min(0.0);
            let mu_b = (vdx * s_b / (r2 * s_b * s_b + visc.eps2)).min(0.0);
            let q_a = ra.rho * (-cl * ra.c * mu_a + cq * mu_a * mu_a);
            let q_b = b.rho[i] * (-cl * b.c[i] * mu_b + cq * mu_b * mu_b);
            let rho_sum = ra.rho + b.rho[i];
            let pi_bar = 0.5 * (q_a / ra.rho + q_b / b.rho[i]) / rho_sum;
            let fsum = fa + fb;
            let mb = b.m[i];
            let along = fa * (uu * fi) + fb * (uu * fj) + fsum * pi_bar;
            let s = -along * mb * rinv;
            let dudt = mb * (uu * fi * w * fa + 0.5 * w * fsum * pi_bar);
            // conduction (G.10–G.12), an exchange: m_i du_i = −m_j du_j
            let vs = ra.c + b.c[i] - 3.0 * w;
            let psum = ra.p + b.p[i];
            let cond = alpha_c
                * mb
                * alpha_bar
                * vs
                * (ra.u - b.u[i])
                * ((ra.p - b.p[i]).abs() / psum)
                * fsum
                / rho_sum;
            let conducts = alpha_c > 0.0 && vs > 0.0 && psum > 0.0;
            let zero_unless = |x: f64| if valid { x } else { 0.0 };
            out.s[i] = zero_unless(s);
            out.dudt[i] = zero_unless(dudt);
            out.exchange[i] = zero_unless(if conducts { cond } else { 0.0 });
            out.q[i] = zero_unless(q_a);
            out.approach[i] = zero_unless(-w);
        }
    }
}
