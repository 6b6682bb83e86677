//! Smoothing lengths and summation density with generalised volume elements (Rosswog
//! (2015) Sec. 5, Eqs. 36–38): κ_a = Σ_b X_b W_ab(h_a), V_a = X_a/κ_a, ρ_a = m_a/V_a, h_a = η V_a^{1/D},
//! solved by safeguarded Newton–Raphson per particle to |Δρ|/ρ < 1e-4, and the grad-h factors
//! Ω_a = 1 + h_a/(D κ_a) Σ_b X_b ∂W_ab(h_a)/∂h_a (Eq. 51). X = m (the default) is standard
//! SPH's summation density ρ_a = Σ_b m_b W_ab(h_a).

use crate::kernel::{DimKernel, Kernel, KernelVisitor};
use crate::neighbours::lanes::{for_each_row, RowPass};
use crate::neighbours::unpack;
use crate::parallel::rows;
use crate::system::System;
use crate::threads::LIGHT;
use rayon::prelude::*;

/// Relative density tolerance of the h iteration (foundation issue; Rosswog §7.2).
pub const DENSITY_TOLERANCE: f64 = 1e-4;
/// Search radius = (1 + SKIN)·2h, so h may grow by this fraction before a list rebuild.
pub const SKIN: f64 = 0.15;
const MAX_NEWTON: usize = 50;
const MAX_ROUNDS: usize = 12;

/// Result of the h solve for one particle.
#[derive(Default)]
struct HSolve {
    h: f64,
    rho: f64,
    omega: f64,
    iterations: u32,
    /// h wanted to grow beyond the current list's reach.
    needs_rebuild: bool,
    capped: bool,
    /// The sums of [`solve_density_and_h_with_sums`] at the final h.
    sums: [f64; 4],
    /// The h the kernel lanes were last taken at: h itself, or h before the final Newton
    /// step, which is taken to first order ([`solve_one`]).
    h_eval: f64,
}

/// Make the neighbour lists valid, solve h and ρ for every particle (X = m), compute Ω, then
/// cut the working list to the final supports.
pub fn solve_density_and_h<const D: usize>(sys: &mut System<D>) {
    solve_density_and_h_weighted(sys, None, true)
}

/// As [`solve_density_and_h`] with volume weights X (`None`: X = m). X is held fixed during
/// the solve (Rosswog §7.2: P, and so X = P^k, frozen while V ↔ h iterate). `compact`: cut
/// the working list afterwards (skip it when another solve follows at once).
pub fn solve_density_and_h_weighted<const D: usize>(
    sys: &mut System<D>,
    weights: Option<&[f64]>,
    compact: bool,
) {
    solve(sys, weights, compact, None);
}

/// As [`solve_density_and_h_weighted`], and per particle a the sums, at a's final h and over
/// the same neighbours (self included), Σ_b y_b W_ab(h_a) and Σ_b y_b ∂W_ab(h_a)/∂h_a for the
/// two weights y = `extra[b][0]` and `extra[b][1]`: [Σ y0 W, Σ y1 W, Σ y0 ∂W/∂h, Σ y1 ∂W/∂h].
/// They reuse the kernel values of the solve's last Newton step, where a gather after the
/// solve evaluated every pair's kernel again (PSPH's ρ, P and ∂P/∂h, Frontiere, Raskin & Owen
/// (2017) eqs G.1–G.2 and G.7). Listed pairs beyond the support add exact zeros, so the sums
/// are those over the working list, in its order.
pub fn solve_density_and_h_with_sums<const D: usize>(
    sys: &mut System<D>,
    weights: Option<&[f64]>,
    compact: bool,
    extra: &[[f64; 2]],
) -> Vec<[f64; 4]> {
    let mut sums = vec![[0.0; 4]; sys.particles.len()];
    solve(sys, weights, compact, Some((extra, &mut sums)));
    sums
}

type ExtraSums<'a> = Option<(&'a [[f64; 2]], &'a mut Vec<[f64; 4]>)>;

fn solve<const D: usize>(
    sys: &mut System<D>,
    weights: Option<&[f64]>,
    compact: bool,
    mut extra: ExtraSums<'_>,
) {
    let mut rounds = 0;
    let mut iters = 0u64;
    let mut rebuilds = 0;
    let mut force = false;
    // Every particle's solve starts from its h on entry, in every round: a particle whose
    // Newton path outgrew the list is solved again from there once the list reaches further,
    // and the others keep their result. So h and ρ are the same path's end whatever the
    // list's history (its skin, when it was last built), which the distributed run needs
    // for identical particles on any number of ranks.
    let start_h = sys.particles.h.clone();
    let mut pending: Vec<u32> = (0..sys.particles.len() as u32).collect();
    loop {
        let h_allowed = sys.prepare_master_list(SKIN, force);
        let t0 = std::time::Instant::now();
        let buffer = sys.scratch.take();
        let results: Vec<HSolve> = {
            let s = &*sys;
            s.kernel.visit(SolvePass {
                sys: s,
                x: weights.unwrap_or(&s.particles.mass),
                pending: &pending,
                start_h: &start_h,
                h_allowed: &h_allowed,
                extra: extra.as_ref().map(|e| e.0),
                buffer,
            })
        };
        sys.stats.seconds_density += t0.elapsed().as_secs_f64();
        rounds += 1;
        let last = rounds >= MAX_ROUNDS;
        let p = &mut sys.particles;
        let rebuild = |r: &HSolve| r.needs_rebuild && !last;
        // a particle whose path outgrew the list starts its next round from beyond both its
        // start and where the path stopped (the rebuilt list reaches that far); the others
        // keep their result
        let apply = |r: &HSolve, h0: f64, (h, rho, omega): (&mut f64, &mut f64, &mut f64)| {
            if rebuild(r) {
                *h = r.h.max(h0);
            } else {
                (*h, *rho, *omega) = (r.h, r.rho, r.omega);
            }
        };
        let (its, capped) = results
            .par_iter()
            .with_min_len(LIGHT)
            .map(|r| (r.iterations as u64, r.capped as u64))
            .reduce(|| (0, 0), |a, b| (a.0 + b.0, a.1 + b.1));
        iters += its;
        let still: Vec<u32> = pending
            .par_iter()
            .zip(&results)
            .filter(|(_, r)| rebuild(r))
            .map(|(&a, _)| a)
            .collect();
        if pending.len() == p.len() {
            // the first round solves everyone in order: written back in parallel (on one
            // thread, this was a serial stretch of every step)
            p.h.par_iter_mut()
                .zip(p.rho.par_iter_mut())
                .zip(p.omega.par_iter_mut())
                .zip(results.par_iter().zip(&start_h))
                .with_min_len(LIGHT)
                .for_each(|(((h, rho), omega), (r, &h0))| apply(r, h0, (h, rho, omega)));
        } else {
            for (&a, r) in pending.iter().zip(&results) {
                let a = a as usize;
                apply(r, start_h[a], (&mut p.h[a], &mut p.rho[a], &mut p.omega[a]));
            }
        }
        if let Some((_, sums)) = &mut extra {
            for (&a, r) in pending.iter().zip(&results) {
                if !rebuild(r) {
                    sums[a as usize] = r.sums;
                }
            }
        }
        sys.stats.h_capped = capped;
        sys.scratch.keep(results);
        if still.is_empty() || last {
            break;
        }
        pending = still;
        force = true;
        rebuilds += 1;
    }
    sys.stats.list_rebuilds += rebuilds;
    sys.stats.h_iterations = iters as f64 / sys.particles.len().max(1) as f64;
    sys.stats.h_iterations_total += sys.stats.h_iterations;
    sys.stats.h_solves += 1;
    sys.stats.total_pairs += (sys.verlet.list.total_pairs() as f64 * sys.stats.h_iterations) as u64;
    if compact {
        sys.compact_neighbours();
    }
}

/// A distributed run's halo after an h solve (`parallel::refresh`): h, ρ and Ω as their
/// owners solved them (the copies solved theirs from cut neighbourhoods), a master list that
/// serves them, and, when the solve had cut the working list (`recut`), the cut again (it
/// reads the neighbours' h). Nothing on one process.
pub fn refresh_halo_after_solve<const D: usize>(sys: &mut System<D>, recut: bool) {
    let (sync, p) = (sys.halo_sync(), &mut sys.particles);
    if !sync.distributed() {
        return;
    }
    sync.refresh(vec![rows(&mut p.h), rows(&mut p.rho), rows(&mut p.omega)]);
    update_master_list(sys);
    if recut {
        sys.compact_neighbours();
    }
}

/// Make the working list valid for the current positions and h without solving for h (schemes
/// that update h themselves): reuse the master list while it serves every h, else rebuild.
pub fn update_lists<const D: usize>(sys: &mut System<D>) {
    update_master_list(sys);
    sys.compact_neighbours();
}

/// The master-list half of [`update_lists`]: valid for the current positions and h, the
/// working list left to the caller.
pub fn update_master_list<const D: usize>(sys: &mut System<D>) {
    let allowed = sys.prepare_master_list(SKIN, false);
    if sys.particles.h.iter().zip(&allowed).any(|(h, a)| h > a) {
        sys.prepare_master_list(SKIN, true);
    }
}

/// The h solves of one round (the particles in `pending`), handed the concrete kernel.
struct SolvePass<'a, const D: usize> {
    sys: &'a System<D>,
    x: &'a [f64],
    pending: &'a [u32],
    start_h: &'a [f64],
    h_allowed: &'a [f64],
    extra: Option<&'a [[f64; 2]]>,
    /// The results' array, kept between solves (`crate::scratch`).
    buffer: Vec<HSolve>,
}

impl<const D: usize> KernelVisitor<D> for SolvePass<'_, D> {
    type Output = Vec<HSolve>;
    fn visit<K: Kernel + Copy>(mut self, kernel: &DimKernel<D, K>) -> Vec<HSolve> {
        let mut out = std::mem::take(&mut self.buffer);
        self.pending
            .par_iter()
            .with_min_len(LIGHT)
            .map(|_| HSolve::default())
            .collect_into_vec(&mut out);
        for_each_row(&SolveRows { v: &self, kernel }, &mut out);
        out
    }
}

struct SolveRows<'a, const D: usize, K> {
    v: &'a SolvePass<'a, D>,
    kernel: &'a DimKernel<D, K>,
}

impl<const D: usize, K: Kernel + Copy> RowPass for SolveRows<'_, D, K> {
    type Acc = HSolve;
    type Scratch = KappaLanes;

    #[inline(always)]
    fn row(&self, i: usize, out: &mut HSolve, lanes: &mut KappaLanes) {
        let v = self.v;
        let a = v.pending[i] as usize;
        lanes.fill(v.sys, v.x, v.extra, a);
        let xa = v.x[a];
        let kappa = KappaOf {
            lanes,
            kernel: *self.kernel,
            xa,
        };
        *out = solve_one(v.sys, xa, a, v.start_h[a], v.h_allowed[a], kappa);
        if let Some(y) = v.extra {
            // the lanes hold the kernel at h_eval; carried to h to first order, as κ is
            let s = lanes.extra_sums(self.kernel, y[a], out.h_eval);
            let step = out.h - out.h_eval;
            out.sums = [s[0] + s[2] * step, s[1] + s[3] * step, s[2], s[3]];
        }
    }
}

/// κ(h) and ∂κ/∂h of one particle (a struct, not a closure: a closure is compiled on its own,
/// without the AVX2 of the pass that calls it).
struct KappaOf<'a, const D: usize, K> {
    lanes: &'a mut KappaLanes,
    kernel: DimKernel<D, K>,
    xa: f64,
}

impl<const D: usize, K: Kernel + Copy> KappaOf<'_, D, K> {
    #[inline(always)]
    fn at(&mut self, h: f64) -> (f64, f64) {
        self.lanes.kappa(&self.kernel, self.xa, h)
    }
}

/// One particle's listed neighbours as lanes for κ(h): r², r and X_b, read once per solve
/// (the Newton iterations, 1.8 a particle on the benchmark box, then only evaluate the
/// kernel), and the per-pair terms.
#[derive(Default)]
struct KappaLanes {
    /// image(x_b), then x_a − image(x_b) (component by component)
    dx: [Vec<f64>; 3],
    r2: Vec<f64>,
    r: Vec<f64>,
    x: Vec<f64>,
    /// the two extra weights of [`solve_density_and_h_with_sums`], when asked for
    y: Vec<[f64; 2]>,
    /// w(q_b) and D w + q w' (q_b) at the last h κ was taken at (0 beyond the support)
    tw: Vec<f64>,
    th: Vec<f64>,
}

impl KappaLanes {
    #[inline(always)]
    fn fill<const D: usize>(
        &mut self,
        sys: &System<D>,
        x: &[f64],
        extra: Option<&[[f64; 2]]>,
        a: usize,
    ) {
        let p = &sys.particles;
        let xa = p.pos[a];
        let row = sys.verlet.list.of(a);
        let n = row.len();
        for v in self.dx.iter_mut().take(D) {
            v.resize(n, 0.0);
        }
        for v in [&mut self.r2, &mut self.r, &mut self.x] {
            v.resize(n, 0.0);
        }
        self.y.clear();
        // Fill: b's image and X_b (a gather); then the separations, r² and r as loops over
        // the row, which the compiler makes SIMD (a scalar square root per entry in the
        // fill was the largest single cost of the h solve on the 3D Sod).
        for (j, &e) in row.iter().enumerate() {
            let (b, code) = unpack(e);
            let y = sys.domain.image_position(&p.pos[b], code);
            for k in 0..D {
                self.dx[k][j] = y[k];
            }
            self.x[j] = x[b];
        }
        let wrap = sys.domain.minimum_image();
        for (k, d) in self.dx.iter_mut().enumerate().take(D) {
            for d in d[..n].iter_mut() {
                *d = wrap.wrap(k, xa[k] - *d);
            }
        }
        let (r2, r) = (&mut self.r2[..n], &mut self.r[..n]);
        r2.fill(0.0);
        for d in self.dx.iter().take(D) {
            for (s, d) in r2.iter_mut().zip(&d[..n]) {
                *s += d * d;
            }
        }
        for (r, s) in r.iter_mut().zip(r2.iter()) {
            *r = s.sqrt();
        }
        if let Some(y) = extra {
            self.y.extend(row.iter().map(|&e| y[unpack(e).0]));
        }
        self.tw.resize(row.len(), 0.0);
        self.th.resize(row.len(), 0.0);
    }

    /// [Σ y0 W, Σ y1 W, Σ y0 ∂W/∂h, Σ y1 ∂W/∂h] (self first, then the list in order) from
    /// the kernel lanes of the last κ, which was taken at `h` (see `solve_one`).
    #[inline(always)]
    fn extra_sums<const D: usize, K: Kernel + Copy>(
        &self,
        k: &DimKernel<D, K>,
        ya: [f64; 2],
        h: f64,
    ) -> [f64; 4] {
        let hinv = 1.0 / h;
        let (w0, _) = k.kernel.shape(0.0);
        let dim = D as f64;
        let mut s = [ya[0] * w0, ya[1] * w0, ya[0] * dim * w0, ya[1] * dim * w0];
        for ((y, tw), th) in self.y.iter().zip(&self.tw).zip(&self.th) {
            s[0] += y[0] * tw;
            s[1] += y[1] * tw;
            s[2] += y[0] * th;
            s[3] += y[1] * th;
        }
        let norm = k.norm(hinv);
        [
            norm * s[0],
            norm * s[1],
            -norm * hinv * s[2],
            -norm * hinv * s[3],
        ]
    }

    /// κ(h) = Σ X_b W_ab(h) and ∂κ/∂h over a's listed neighbours (+ self).
    ///
    /// Written for the pair loop's cost (this is most of the h–ρ solve): with W = σ/h^D w(q)
    /// and ∂W/∂h = −σ/h^{D+1} [D w + q w'], the factors σ/h^D and 1/h are the same for every
    /// neighbour, so the lanes hold only w(q_b) and [D w + q w'](q_b) with q = r·(1/h) (a
    /// multiply, not a division), weighted by X_b in the sum (and kept for
    /// [`Self::extra_sums`]). Entries beyond the support (the skin and the scatter
    /// neighbours) give exact zeros, and the sum runs in list order, so κ is the same to the
    /// bit as a loop that skips them, whatever the list's skin.
    #[inline(always)]
    fn kappa<const D: usize, K: Kernel + Copy>(
        &mut self,
        k: &DimKernel<D, K>,
        xa: f64,
        h: f64,
    ) -> (f64, f64) {
        let hinv = 1.0 / h;
        let support2 = (crate::kernel::SUPPORT * h) * (crate::kernel::SUPPORT * h);
        let (w0, _) = k.kernel.shape(0.0);
        let dim = D as f64;
        kappa_terms(
            &k.kernel,
            dim,
            hinv,
            support2,
            &self.r2,
            &self.r,
            &mut self.tw,
            &mut self.th,
        );
        let mut sum_w = xa * w0;
        let mut sum_h = xa * dim * w0;
        for ((x, tw), th) in self.x.iter().zip(&self.tw).zip(&self.th) {
            sum_w += x * tw;
            sum_h += x * th;
        }
        let norm = k.norm(hinv);
        (norm * sum_w, -norm * hinv * sum_h)
    }
}

/// The per-pair terms of κ: a loop over slices passed as arguments, so the compiler knows the
/// outputs alias nothing and makes it SIMD.
#[inline(always)]
#[allow(clippy::too_many_arguments)]
fn kappa_terms<K: Kernel>(
    kernel: &K,
    dim: f64,
    hinv: f64,
    support2: f64,
    r2: &[f64],
    r: &[f64],
    tw: &mut [f64],
    th: &mut [f64],
) {
    let n = r2.len();
    let (r, tw, th) = (&r[..n], &mut tw[..n], &mut th[..n]);
    for i in 0..n {
        let q = r[i] * hinv;
        let (w, dw) = kernel.shape(q);
        let inside = r2[i] < support2;
        tw[i] = if inside { w } else { 0.0 };
        th[i] = if inside { dim * w + q * dw } else { 0.0 };
    }
}

/// Solve particle a's h from `h0`; `h_reach` is the largest h its listed neighbours serve
/// exactly. Unknown: h with κ(h) = X_a η^D / h^D (i.e. h = η V^{1/D}); then ρ = m_a κ / X_a.
#[inline(always)]
fn solve_one<const D: usize, K: Kernel + Copy>(
    sys: &System<D>,
    xa: f64,
    a: usize,
    h0: f64,
    h_reach: f64,
    mut kappa_of: KappaOf<'_, D, K>,
) -> HSolve {
    let to_rho = sys.particles.mass[a] / xa;
    let eta_d = sys.eta.powi(D as i32);
    let h_cap = h_reach.min(sys.h_max);
    // The list cannot serve even the start: solve again from h0 once it reaches further
    // (the density at the cap, below, stands only if the rounds run out).
    let h0_beyond_list = h0 > h_cap && h_reach < sys.h_max;
    let mut h = h0.min(h_cap);
    let mut it = 0;
    // wall and port-buffer particles keep their h (their density comes from the wall or port
    // condition; a buffer's back rows would otherwise grow h into the empty space behind)
    let mut lo = 0.0_f64;
    let mut hi = f64::INFINITY;
    let finish =
        |h: f64, kappa: f64, dkappa: f64, it: usize, needs_rebuild: bool, capped: bool| HSolve {
            h,
            rho: kappa * to_rho,
            omega: 1.0 + h / (D as f64 * kappa) * dkappa,
            iterations: it as u32,
            needs_rebuild,
            capped,
            sums: [0.0; 4],
            h_eval: h,
        };
    if sys.particles.body[a] != 0 || sys.particles.port[a] != 0 || h0_beyond_list {
        let (kappa, dkappa) = kappa_of.at(h);
        return finish(h, kappa, dkappa, 1, h0 > h_cap && h_cap < sys.h_max, false);
    }
    loop {
        it += 1;
        let (kappa, dkappa) = kappa_of.at(h);
        let kappa_h = xa * eta_d / h.powi(D as i32);
        let f = kappa - kappa_h;
        let df = dkappa + D as f64 * kappa_h / h;
        // Converged: the summation density and the h-implied density agree to the tolerance.
        // h still takes the Newton step, with κ carried along to first order (no new kernel
        // sum): Rosswog (2015) Sec. 6.1.3 sets h = η V^{1/D} from every new density before it
        // tests convergence, and warns that a careless h update is a source of noise. Were h
        // kept wherever the test passes, h would be a variable of its own, moved only by
        // `System::predict_h` (stale ∇·v, first order) and tied to the positions within
        // 1e-4: on a lattice at rest that lets round-off grow ×8 per sound crossing at CFL
        // 0.5 (2D noise box, periodic, F1 and F3 alike), and with the step h is the
        // positions' own again, 1.1 per crossing, which is round-off's random walk
        // (measured; tests/rosswog_static.rs).
        if (f / kappa).abs() < DENSITY_TOLERANCE {
            if df > 0.0 {
                let h1 = (h - f / df).min(h_cap);
                let mut r = finish(h1, kappa + dkappa * (h1 - h), dkappa, it, false, false);
                r.h_eval = h;
                return r;
            }
            return finish(h, kappa, dkappa, it, false, false);
        }
        if it >= MAX_NEWTON {
            return finish(h, kappa, dkappa, it, false, false);
        }
        // f is increasing in h where the solution is unique (κ_h falls as h^-D); bracket it.
        if f < 0.0 {
            lo = lo.max(h);
        } else {
            hi = hi.min(h);
        }
        let mut h_new = if df > 0.0 { h - f / df } else { f64::NAN };
        if !(h_new.is_finite() && h_new > lo && h_new < hi) || h_new > 1.5 * h || h_new < 0.6 * h {
            // Newton left the bracket or stepped too far: bisect (geometric when unbounded).
            h_new = if hi.is_finite() {
                0.5 * (lo + hi)
            } else {
                (1.3 * h).max(lo * 1.3)
            };
            if lo == 0.0 && f > 0.0 {
                h_new = 0.8 * h;
            }
        }
        if h_new > h_cap {
            let (kappa, dkappa) = kappa_of.at(h_cap);
            let capped = h_cap >= sys.h_max;
            return finish(h_cap, kappa, dkappa, it, !capped, capped);
        }
        h = h_new;
    }
}
