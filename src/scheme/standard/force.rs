//! Standard SPH's (and rpSPH's) force pass: pressure force and work, Monaghan–Gingold
//! viscosity with the Balsara factor, optional conductivity, laminar viscosity and δ-SPH
//! density diffusion (the equations are in the parent module's comment).
//!
//! The pair loop runs on lanes ([`crate::neighbours::lanes`]): each row's neighbours are read
//! into columns, the pair terms are computed in one loop with no branch, then summed in list
//! order. Measured on the 3D periodic box of `sphfmu bench --sizes 100000 --dims 3 --steps 10
//! --threads 1` (97,336 particles, 62 neighbours, Intel Xeon VM; BENCHMARKS.md, issue 19), the
//! force pass took 1.17-1.19 s as a gather with a closure per pair, and 0.71-0.73 s on lanes.

use super::StandardParams;
use crate::kernel::{DimKernel, Kernel, KernelVisitor};
use crate::neighbours::lanes::{
    fill_pair, finish_pairs, for_each_row_widest, pad_separations, RowPass, LANES,
};
use crate::neighbours::unpack;
use crate::particles::Vector;
use crate::system::System;
use crate::threads::LIGHT;
use rayon::prelude::*;

/// The pressure part of the pair force: the one place where standard SPH and rpSPH differ.
#[derive(Debug, Clone, Copy, PartialEq)]
pub(crate) enum PressureForm {
    /// Standard grad-h form (Rosswog (2015) with X = m; Abel (2011) eq. 2).
    GradH,
    /// rpSPH (Abel 2011): a_a = −Σ m_b (P_b − P_a)/ρ_b² ∇W, with ∇_a W_ab(h_a) (eq. 4,
    /// `symmetric = false`) or ∇̄W (Appendix B variant, `symmetric = true`); when
    /// `shock_switch`, particles with −h ∇·v > 3c use GradH (§3.7). The energy equation is
    /// the paper's preferred one (Discussion, after eq. 18: "we prefer the entropy formulation", which rpSPH does not
    /// change) in u form, du_a/dt = P_a/(Ω_a ρ_a²) Σ m_b v_ab·∇_a W_ab(h_a), unless
    /// `neighbour_pressure_work`: eq. 18 as printed, du_a/dt = Σ m_b P_b/ρ_b² v_ab·∇_a W_ab(h_a)
    /// (printed "ρ_j ρ_j"; ρ_a ρ_b is possible, we take the print). `morris`: eq. 5's
    /// denominator ρ_a ρ_b in place of ρ_b² (the paper's comparison).
    Relative {
        symmetric: bool,
        shock_switch: bool,
        neighbour_pressure_work: bool,
        morris: bool,
    },
}

/// What the force pass reads of one particle. The fields every pair reads come first, so
/// they share two cache lines.
#[derive(Clone, Copy)]
#[repr(C)]
struct ForceRecord<const D: usize> {
    x: Vector<D>,
    v: Vector<D>,
    hinv: f64,
    m: f64,
    /// P/(Ω ρ²)
    pstd: f64,
    rho: f64,
    h: f64,
    c: f64,
    alpha: f64,
    bal: f64,
    p: f64,
    u: f64,
    /// Velocity in the laminar viscous term (`Particles::vel_wall` for walls).
    vv: Vector<D>,
    wall: bool,
    /// Takes part in the laminar term (fluid, or a no-slip wall).
    laminar: bool,
}

#[derive(Clone, Copy)]
struct ForceAcc<const D: usize> {
    acc: Vector<D>,
    dudt: f64,
    vsig: f64,
    /// Σ_b m_b v_ab·∇_a W_ab(h_a), the continuity equation's dρ/dt
    drho: f64,
}

impl<const D: usize> Default for ForceAcc<D> {
    fn default() -> Self {
        Self {
            acc: Vector::zeros(),
            dudt: 0.0,
            vsig: 0.0,
            drho: 0.0,
        }
    }
}

/// Pair forces, pressure work, artificial viscosity (Monaghan–Gingold with Balsara) and
/// artificial conductivity; writes acc, dudt and v_sig.
pub(crate) fn force_pass<const D: usize>(
    sys: &mut System<D>,
    prm: &StandardParams,
    balsara_slot: usize,
    form: PressureForm,
) {
    let t0 = std::time::Instant::now();
    let n = sys.particles.len();
    // the per-particle arrays of this pass, kept between steps (`crate::scratch`)
    let mut out: Vec<ForceAcc<D>> = sys.scratch.take();
    out.resize(n, ForceAcc::default());
    let mut recs: Vec<ForceRecord<D>> = sys.scratch.take();
    let p = &sys.particles;
    // Which particles use the standard form (all for GradH; with rpSPH's shock switch those
    // with −h ∇·v > 3c).
    let standard_here: Vec<bool> = match form {
        PressureForm::GradH => vec![true; n],
        PressureForm::Relative { shock_switch, .. } => (0..n)
            .into_par_iter()
            .with_min_len(LIGHT)
            .map(|a| shock_switch && -p.h[a] * p.div_v[a] > 3.0 * p.sound_speed[a])
            .collect(),
    };
    // Everything the pair term reads of a particle, packed: one record instead of a cache
    // line per field array. P/(Ω ρ²) is computed once rather than per pair.
    {
        let bal = &p.extra_scalars[balsara_slot];
        let bodies = &sys.bodies;
        (0..n)
            .into_par_iter()
            .with_min_len(LIGHT)
            .map(|a| ForceRecord {
                x: p.pos[a],
                v: p.vel[a],
                hinv: 1.0 / p.h[a],
                m: p.mass[a],
                pstd: p.pressure[a] / (p.omega[a] * p.rho[a] * p.rho[a]),
                rho: p.rho[a],
                h: p.h[a],
                c: p.sound_speed[a],
                alpha: p.alpha[a],
                bal: bal[a],
                p: p.pressure[a],
                u: p.u[a],
                vv: if p.body[a] > 0 {
                    p.vel_wall[a]
                } else {
                    p.vel[a]
                },
                wall: p.body[a] > 0,
                laminar: p.body[a] == 0 || bodies[p.body[a] as usize - 1].no_slip,
            })
            .collect_into_vec(&mut recs);
    }
    let flags = match form {
        PressureForm::GradH => (false, false, false),
        PressureForm::Relative {
            symmetric,
            neighbour_pressure_work,
            morris,
            ..
        } => (symmetric, neighbour_pressure_work, morris),
    };
    let plain = form == PressureForm::GradH
        && prm.conductivity == 0.0
        && prm.viscosity == 0.0
        && prm.delta == 0.0;
    let kernel = sys.kernel;
    kernel.visit(ForceVisit {
        sys,
        recs: &recs,
        standard_here: &standard_here,
        prm,
        // the δ-SPH hydrostatic correction reads the uniform part (in a rotating frame the
        // centrifugal and Coriolis parts are left in the diffused density; our decision)
        gravity: sys.uniform_body_force(),
        symmetric: flags.0,
        eq18: flags.1,
        morris: flags.2,
        plain,
        out: &mut out,
    });
    sys.store_derivatives(t0, |a| (out[a].acc, out[a].dudt, out[a].vsig));
    sys.particles
        .drhodt
        .par_iter_mut()
        .zip(&out)
        .with_min_len(LIGHT)
        .for_each(|(d, o)| *d = o.drho);
    sys.scratch.keep(out);
    sys.scratch.keep(recs);
}

/// The force pass's inputs, handed the concrete kernel by [`DimKernel::visit`].
struct ForceVisit<'a, const D: usize> {
    sys: &'a System<D>,
    recs: &'a [ForceRecord<D>],
    standard_here: &'a [bool],
    prm: &'a StandardParams,
    gravity: Vector<D>,
    symmetric: bool,
    eq18: bool,
    morris: bool,
    /// GradH form with no conductivity, laminar viscosity or δ-SPH: the common case, compiled
    /// without the extra terms' columns and arithmetic.
    plain: bool,
    out: &'a mut [ForceAcc<D>],
}

impl<const D: usize> KernelVisitor<D> for ForceVisit<'_, D> {
    type Output = ();
    fn visit<K: Kernel + Copy>(mut self, kernel: &DimKernel<D, K>) {
        let out = std::mem::take(&mut self.out);
        if self.plain {
            for_each_row_widest(&ForceRows::<D, K, true> { v: &self, kernel }, out);
        } else {
            for_each_row_widest(&ForceRows::<D, K, false> { v: &self, kernel }, out);
        }
    }
}

/// The pair loop on lanes; `PLAIN` as [`ForceVisit::plain`].
struct ForceRows<'a, const D: usize, K, const PLAIN: bool> {
    v: &'a ForceVisit<'a, D>,
    kernel: &'a DimKernel<D, K>,
}

/// What a block of up to [`LANES`] pairs reads: separation and v_ab, b's fields, and the
/// extra terms' fields (filled only when not `PLAIN`). The padding lanes past a block's end
/// get a zero separation, which marks them, like a pair at zero distance, as adding nothing;
/// their other fields are left from an earlier block (finite, and never summed).
#[derive(Default)]
struct PairBlock {
    dx: [[f64; LANES]; 3],
    vab: [[f64; LANES]; 3],
    hinv: [f64; LANES],
    m: [f64; LANES],
    pstd: [f64; LANES],
    rho: [f64; LANES],
    h: [f64; LANES],
    c: [f64; LANES],
    alpha: [f64; LANES],
    bal: [f64; LANES],
    p: [f64; LANES],
    u: [f64; LANES],
    /// the laminar term's v_ab (a wall moves with its `vel_wall`)
    dv: [[f64; LANES]; 3],
    /// 1 when both take part in the laminar term
    lam: [f64; LANES],
    /// 1 when either is a wall particle
    wall: [f64; LANES],
}

/// A block's pair terms.
#[derive(Default)]
struct PairTerms {
    acc: [[f64; LANES]; 3],
    dudt: [f64; LANES],
    vsig: [f64; LANES],
    drho: [f64; LANES],
}

/// A thread's blocks (boxed: about 8 KB).
#[derive(Default)]
pub(super) struct ForceScratch(Box<(PairBlock, PairTerms)>);

impl<const D: usize, K: Kernel + Copy, const PLAIN: bool> RowPass for ForceRows<'_, D, K, PLAIN> {
    type Acc = ForceAcc<D>;
    type Scratch = ForceScratch;

    #[inline(always)]
    fn row(&self, a: usize, o: &mut ForceAcc<D>, scratch: &mut ForceScratch) {
        let (blk, t) = &mut *scratch.0;
        let recs = self.v.recs;
        let dom = &self.v.sys.domain;
        let ra = &recs[a];
        let standard_here = PLAIN || self.v.standard_here[a];
        let mut acc = ForceAcc::<D>::default();
        for entries in self.v.sys.neighbours.of(a).chunks(LANES) {
            // Fill: b's image through the domain (periodic wrap, mirror codes), its fields.
            let n = entries.len();
            for (i, &e) in entries.iter().enumerate() {
                let (b, code) = unpack(e);
                let rb = &recs[b];
                let vb = fill_pair(dom, (&rb.x, &rb.v), code, &mut blk.dx, &mut blk.vab, i);
                blk.hinv[i] = rb.hinv;
                blk.m[i] = rb.m;
                blk.pstd[i] = rb.pstd;
                blk.rho[i] = rb.rho;
                blk.h[i] = rb.h;
                blk.c[i] = rb.c;
                blk.alpha[i] = rb.alpha;
                blk.bal[i] = rb.bal;
                if !PLAIN {
                    blk.p[i] = rb.p;
                    blk.u[i] = rb.u;
                    let vw = ra.vv - if rb.wall { rb.vv } else { vb };
                    for k in 0..D {
                        blk.dv[k][i] = vw[k];
                    }
                    blk.lam[i] = if ra.laminar && rb.laminar { 1.0 } else { 0.0 };
                    blk.wall[i] = if ra.wall || rb.wall { 1.0 } else { 0.0 };
                }
            }
            finish_pairs(dom, (&ra.x, &ra.v), &mut blk.dx, &mut blk.vab, n);
            let lanes = pad_separations::<D>(&mut blk.dx, n);
            self.terms(ra, standard_here, blk, t, lanes);
            // Sum in list order.
            for i in 0..n {
                for k in 0..D {
                    acc.acc[k] += t.acc[k][i];
                }
                acc.dudt += t.dudt[i];
                acc.vsig = acc.vsig.max(t.vsig[i]);
                acc.drho += t.drho[i];
            }
        }
        *o = acc;
    }
}

impl<const D: usize, K: Kernel + Copy, const PLAIN: bool> ForceRows<'_, D, K, PLAIN> {
    /// The pair terms of one block: one pair per lane, no branch (selects only), so the loop
    /// becomes SIMD. (Index loops: a lane index reads several arrays at once.)
    #[inline(always)]
    #[allow(clippy::needless_range_loop)]
    fn terms(
        &self,
        ra: &ForceRecord<D>,
        standard_here: bool,
        b: &PairBlock,
        out: &mut PairTerms,
        lanes: usize,
    ) {
        // Everything the loop reads besides the block, as values: a flag or a field read
        // through a reference inside the loop (which the compiler cannot prove unchanged by
        // the loop's stores) kept it scalar.
        let k = *self.kernel;
        let (v, prm) = (self.v, *self.v.prm);
        let ra = *ra;
        let (symmetric, morris, eq18, gravity) = (v.symmetric, v.morris, v.eq18, v.gravity);
        let visc_vsig = 2.4 * prm.viscosity / ra.h;
        for i in 0..lanes {
            let mut r2 = 0.0;
            let mut vdx = 0.0;
            for d in 0..D {
                r2 += b.dx[d][i] * b.dx[d][i];
                vdx += b.vab[d][i] * b.dx[d][i];
            }
            // a pair at zero distance (two particles on one spot) adds nothing
            let valid = r2 > 0.0;
            let r = if valid { r2.sqrt() } else { 1.0 };
            let rho_bar = 0.5 * (ra.rho + b.rho[i]);
            let hbar = 0.5 * (ra.h + b.h[i]);
            let den = r * r + prm.epsilon * hbar * hbar;
            // One division for three reciprocals (1/r, 1/(r² + ε h̄²), 1/ρ̄). Every factor is
            // symmetric in (a, b), so the pair terms stay exactly antisymmetric.
            let t = 1.0 / (r * den * rho_bar);
            let rinv = t * den * rho_bar;
            let den_inv = t * r * rho_bar;
            let rho_bar_inv = t * r * den;
            // ∇_a W_ab(h) = dW/dr · r̂_ab
            let fa = k.dwdr_hinv(r, ra.hinv);
            let fb = k.dwdr_hinv(r, b.hinv[i]);
            let fbar = 0.5 * (fa + fb);
            let w = vdx * rinv;
            let mb = b.m[i];
            // pressure force along r̂ (times −m_b below) and pressure work
            let (mut force, mut dudt) = if standard_here {
                (ra.pstd * fa + b.pstd[i] * fb, ra.pstd * mb * w * fa)
            } else {
                let g = if symmetric { fbar } else { fa };
                let rho2 = if morris {
                    ra.rho * b.rho[i]
                } else {
                    b.rho[i] * b.rho[i]
                };
                let work = if eq18 { b.p[i] / rho2 } else { ra.pstd };
                ((b.p[i] - ra.p) / rho2 * g, work * mb * w * fa)
            };
            let mut vsig = ra.c + b.c[i] - 3.0 * w.min(0.0);
            // Viscosity on approaching pairs only, without a branch: receding pairs get
            // μ = 0, so Π = 0 and nothing is added.
            let mu = hbar * w.min(0.0) * r * den_inv;
            let alpha_bar = 0.5 * (ra.alpha + b.alpha[i]);
            let fbal = 0.5 * (ra.bal + b.bal[i]);
            // Cullen–Dehnen scales β with ᾱ too (Frontiere, Raskin & Owen (2017) App F)
            let beta = if prm.cullen_dehnen {
                prm.beta * alpha_bar
            } else {
                prm.beta
            };
            let pi =
                fbal * (-alpha_bar * 0.5 * (ra.c + b.c[i]) * mu + beta * mu * mu) * rho_bar_inv;
            force += pi * fbar;
            dudt += 0.5 * mb * pi * w * fbar;
            let mut drho = mb * w * fa;
            let mut extra = [0.0; 3];
            if !PLAIN {
                if prm.conductivity > 0.0 {
                    let vsig_u = ((ra.p - b.p[i]).abs() * rho_bar_inv).sqrt();
                    dudt += mb * prm.conductivity * vsig_u * (ra.u - b.u[i]) * fbar * rho_bar_inv;
                }
                if prm.viscosity > 0.0 && b.lam[i] > 0.0 {
                    // Morris et al. (1997) eq. 8 with μ = ρν: kv ≤ 0 since dW/dr ≤ 0; the pair
                    // exchanges m_a m_b kv v_ab (antisymmetric) and heats both by −½ kv |v_ab|²
                    let kv = prm.viscosity * (ra.rho + b.rho[i]) / (ra.rho * b.rho[i]) * fbar * r
                        / (r * r + 0.01 * hbar * hbar);
                    let mut dv2 = 0.0;
                    for d in 0..D {
                        extra[d] = mb * kv * b.dv[d][i];
                        dv2 += b.dv[d][i] * b.dv[d][i];
                    }
                    dudt -= 0.5 * mb * kv * dv2;
                    // viscous time step: cfl·h/v_sig ≤ 0.125 h²/ν at cfl 0.3 (Morris et al. §4)
                    vsig = vsig.max(visc_vsig);
                }
                if prm.delta > 0.0 && b.wall[i] == 0.0 {
                    // ψ_ab·∇_a W_ab = 2 (ρ_b − ρ_a − ρ^H_ba)(−dW/dr)/r, x_ba = −dx
                    let mut gdx = 0.0;
                    for d in 0..D {
                        gdx += gravity[d] * b.dx[d][i];
                    }
                    let rho_h = ra.rho * -gdx / (ra.c * ra.c);
                    let cbar = 0.5 * (ra.c + b.c[i]);
                    drho += prm.delta
                        * hbar
                        * cbar
                        * (mb / b.rho[i])
                        * 2.0
                        * (b.rho[i] - ra.rho - rho_h)
                        * (-fa)
                        * rinv;
                }
            }
            let g = mb * force * rinv;
            let zero_unless = |x: f64| if valid { x } else { 0.0 };
            for d in 0..D {
                out.acc[d][i] = zero_unless(extra[d] - g * b.dx[d][i]);
            }
            out.dudt[i] = zero_unless(dudt);
            out.vsig[i] = zero_unless(vsig);
            out.drho[i] = zero_unless(drho);
        }
    }
}
