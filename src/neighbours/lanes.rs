//! Pair lanes: one particle's neighbours laid out as arrays (structure of arrays), so that a
//! pass writes its pair arithmetic as a plain loop over lanes and the compiler turns it into
//! SIMD (issue 19).
//!
//! A row pass takes its neighbours in blocks of [`LANES`], and each block in three parts: a
//! *fill* that reads each neighbour (through the domain's image codes, which branch) into
//! arrays on the stack, a *compute* loop over the lanes with no branch and no call, and a
//! *sum* in list order. The sum keeps the order of the plain gather
//! ([`crate::system::System::gather_with`]), so a particle's totals do not depend on how rows
//! are cut into lanes, on the thread count or on the rank count.
//!
//! Width: the x86-64 baseline has 2-wide f64 vectors (SSE2). Where the CPU has AVX2, rows run
//! through a copy of the pass compiled for it (4-wide), chosen once per pass at run time, so
//! one binary (and one FMU) serves every x86-64 machine. Floating-point results are the same
//! bits on both paths: Rust never contracts a·b + c into a fused multiply-add by itself, and
//! a lane computes exactly what the scalar loop would.

use crate::domain::{Domain, ImageCode};
use crate::particles::Vector;
use rayon::prelude::*;

/// Pairs per block: a row is read in blocks of up to this many neighbours into arrays of
/// the thread's scratch (no aliasing for the compiler to rule out). The compute loop runs to
/// the block's length rounded up to [`PAD`]; a loop of a fixed 8 lanes was unrolled in full
/// before the vectoriser saw it, and stayed scalar. 32 holds a 2D row (about 20 neighbours)
/// in one block and a 3D row (about 60) in two.
pub const LANES: usize = 32;

/// Lanes a compute loop is padded to: two AVX2 vectors of f64.
pub const PAD: usize = 8;

/// `n` rounded up to [`PAD`], at most [`LANES`].
#[inline(always)]
pub fn padded(n: usize) -> usize {
    (n.div_ceil(PAD) * PAD).min(LANES)
}

/// The block's lane count, [`padded`] `n`, with the separations of the padding lanes set to
/// zero: the passes read a zero separation as "adds nothing".
#[inline(always)]
pub fn pad_separations<const D: usize>(dx: &mut [[f64; LANES]; 3], n: usize) -> usize {
    let lanes = padded(n);
    for i in n..lanes {
        for row in dx.iter_mut().take(D) {
            row[i] = 0.0;
        }
    }
    lanes
}

/// 1/h of every particle, so that a lane pass multiplies instead of dividing per pair.
pub fn inverse_h(h: &[f64]) -> Vec<f64> {
    h.par_iter()
        .with_min_len(crate::threads::LIGHT)
        .map(|h| 1.0 / h)
        .collect()
}

/// The fill's half of one pair's geometry lanes: image(x_b) into `dx[..][i]` and image(v_b)
/// into `vab[..][i]` (components past D left alone), through the domain's image `code` (a
/// mirror, which branches); returns image(v_b). [`finish_pairs`] turns a block of these into
/// separations once the block is filled.
#[inline(always)]
pub fn fill_pair<const D: usize>(
    dom: &Domain<D>,
    (xb, vb): (&Vector<D>, &Vector<D>),
    code: ImageCode,
    dx: &mut [[f64; LANES]; 3],
    vab: &mut [[f64; LANES]; 3],
    i: usize,
) -> Vector<D> {
    let (y, w) = if code == 0 {
        (*xb, *vb)
    } else {
        (dom.image_position(xb, code), dom.image_velocity(vb, code))
    };
    for k in 0..D {
        dx[k][i] = y[k];
        vab[k][i] = w[k];
    }
    w
}

/// The first `n` lanes filled by [`fill_pair`] made into x_a − image(x_b), minimum image on
/// periodic axes, and v_a − image(v_b): loops over lanes, which the compiler makes SIMD. The
/// wrap is [`Domain::separation`]'s to the bit (see [`crate::domain::MinimumImage`]). Taken one
/// pair at a time inside the fill, `separation`'s reloads and branches were 18 % of the 3D
/// Sod's instructions (callgrind, BENCHMARKS.md, 2026-12-07).
#[inline(always)]
pub fn finish_pairs<const D: usize>(
    dom: &Domain<D>,
    (xa, va): (&Vector<D>, &Vector<D>),
    dx: &mut [[f64; LANES]; 3],
    vab: &mut [[f64; LANES]; 3],
    n: usize,
) {
    let wrap = dom.minimum_image();
    for k in 0..D {
        for d in dx[k][..n].iter_mut() {
            *d = wrap.wrap(k, xa[k] - *d);
        }
        for w in vab[k][..n].iter_mut() {
            *w = va[k] - *w;
        }
    }
}

/// A pass over neighbour rows written on blocks of lanes (see the module comment).
pub trait RowPass: Sync {
    type Acc: Send;
    /// Per-thread scratch (the blocks of lanes).
    type Scratch: Default + Send;
    /// Row `a` into `acc`. Implementations are `#[inline(always)]`, so that they compile into
    /// [`for_each_row`]'s AVX2 copy.
    fn row(&self, a: usize, acc: &mut Self::Acc, scratch: &mut Self::Scratch);
}

/// `pass.row(a, &mut out[a], ..)` for every particle, in parallel (rows in chunks of 64).
pub fn for_each_row<P: RowPass>(pass: &P, out: &mut [P::Acc]) {
    for_each_row_at(Width::detect(), pass, out)
}

/// [`for_each_row`] with AVX-512 where the CPU has it ([`Widest`]): for the force passes,
/// whose pair arithmetic is the heaviest of a step.
pub fn for_each_row_widest<P: RowPass>(pass: &P, out: &mut [P::Acc]) {
    for_each_row_at(Widest::detect(), pass, out)
}

/// [`for_each_row`] at a given width.
fn for_each_row_at<P: RowPass>(wide: impl Runs, pass: &P, out: &mut [P::Acc]) {
    out.par_iter_mut()
        .enumerate()
        .with_min_len(64)
        .for_each_init(P::Scratch::default, |scratch, (a, acc)| {
            wide.run(OneRow {
                pass,
                a,
                acc,
                scratch,
            })
        });
}

struct OneRow<'a, P: RowPass> {
    pass: &'a P,
    a: usize,
    acc: &'a mut P::Acc,
    scratch: &'a mut P::Scratch,
}

impl<P: RowPass> Wide for OneRow<'_, P> {
    type Output = ();
    #[inline(always)]
    fn run(self) {
        self.pass.row(self.a, self.acc, self.scratch)
    }
}

/// A piece of work compiled at every [`Width`] (a trait, not a closure: a closure is compiled
/// on its own, without the target features of the function that calls it). Implementations
/// are `#[inline(always)]`.
pub trait Wide {
    type Output;
    fn run(self) -> Self::Output;
}

/// Runs [`Wide`] work compiled for a width chosen at run time.
pub trait Runs: Copy + Send + Sync {
    fn run<W: Wide>(self, work: W) -> W::Output;
}

/// The vector width the CPU offers, decided once per pass.
#[derive(Clone, Copy)]
pub enum Width {
    Baseline,
    #[cfg(target_arch = "x86_64")]
    Avx2,
}

impl Width {
    pub fn detect() -> Self {
        #[cfg(target_arch = "x86_64")]
        {
            if std::is_x86_feature_detected!("avx2") {
                return Width::Avx2;
            }
        }
        Width::Baseline
    }
}

impl Runs for Width {
    /// `work.run()`, compiled for this width.
    #[inline(always)]
    fn run<W: Wide>(self, work: W) -> W::Output {
        match self {
            Width::Baseline => work.run(),
            // SAFETY: `detect` found AVX2 on this CPU.
            #[cfg(target_arch = "x86_64")]
            Width::Avx2 => unsafe { run_avx2(work) },
        }
    }
}

/// [`Width`], or AVX-512 (F, DQ and VL) where the CPU has it. Only the force passes of
/// standard SPH, PSPH and CRKSPH take it: every pass run through it is compiled once more per
/// kernel and dimension, and the others (Rosswog's force pass among them) did not gain.
/// Zen 4 executes AVX-512 on 256-bit units, so the gain is in the registers (32 instead of
/// 16: the force terms of a block no longer spill) and the masks, not the width.
/// On `models/bench/sod3d.toml` to t = 0.05 the standard force pass took 8–18 % less time,
/// the cut took more (BENCHMARKS.md, 2026-12-07 and 12-08). The results are the same bits
/// as at the other widths: nothing is contracted into an FMA, and division and square root
/// are exactly rounded at every width.
#[derive(Clone, Copy)]
pub enum Widest {
    Lanes(Width),
    #[cfg(target_arch = "x86_64")]
    Avx512,
}

impl Widest {
    pub fn detect() -> Self {
        #[cfg(target_arch = "x86_64")]
        {
            if std::is_x86_feature_detected!("avx512f")
                && std::is_x86_feature_detected!("avx512dq")
                && std::is_x86_feature_detected!("avx512vl")
            {
                return Widest::Avx512;
            }
        }
        Widest::Lanes(Width::detect())
    }
}

impl Runs for Widest {
    #[inline(always)]
    fn run<W: Wide>(self, work: W) -> W::Output {
        match self {
            Widest::Lanes(w) => w.run(work),
            // SAFETY: `detect` found AVX-512 F, DQ and VL on this CPU.
            #[cfg(target_arch = "x86_64")]
            Widest::Avx512 => unsafe { run_avx512(work) },
        }
    }
}

/// [`Wide::run`] compiled for AVX-512 (the work inlines into it).
#[cfg(target_arch = "x86_64")]
#[target_feature(enable = "avx2,avx512f,avx512dq,avx512vl")]
unsafe fn run_avx512<W: Wide>(work: W) -> W::Output {
    work.run()
}

/// [`Wide::run`] compiled for AVX2 (the work inlines into it).
#[cfg(target_arch = "x86_64")]
#[target_feature(enable = "avx2")]
unsafe fn run_avx2<W: Wide>(work: W) -> W::Output {
    work.run()
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Σ_b (x_a − x_b)² over a row, in blocks of lanes.
    struct SquaredGaps<'a> {
        x: &'a [f64],
        rows: &'a [Vec<usize>],
    }

    impl RowPass for SquaredGaps<'_> {
        type Acc = f64;
        type Scratch = [f64; LANES];
        #[inline(always)]
        fn row(&self, a: usize, acc: &mut f64, d: &mut [f64; LANES]) {
            let mut sum = 0.0;
            for block in self.rows[a].chunks(LANES) {
                for (i, &b) in block.iter().enumerate() {
                    d[i] = self.x[a] - self.x[b];
                }
                for q in d[..padded(block.len())].iter_mut() {
                    *q *= *q;
                }
                sum = d[..block.len()].iter().fold(sum, |s, q| s + q);
            }
            *acc = sum;
        }
    }

    /// A pair term with a square root, a division, a select and a kernel derivative, in a
    /// loop over lanes as the force pass writes it.
    struct KernelTerms<'a> {
        x: &'a [f64],
        rows: &'a [Vec<usize>],
    }

    impl RowPass for KernelTerms<'_> {
        type Acc = f64;
        type Scratch = [[f64; LANES]; 2];
        #[inline(always)]
        fn row(&self, a: usize, acc: &mut f64, s: &mut [[f64; LANES]; 2]) {
            use crate::kernel::{CubicSplineM4, DimKernel};
            let k = DimKernel::<3, _>::new(CubicSplineM4);
            let [d, t] = s;
            let mut sum = 0.0;
            for block in self.rows[a].chunks(LANES) {
                for (i, &b) in block.iter().enumerate() {
                    d[i] = self.x[a] - self.x[b];
                }
                for i in 0..padded(block.len()) {
                    let r = (d[i] * d[i] + 0.01).sqrt();
                    let f = k.dwdr_hinv(r, 1.3) / (r + 0.5);
                    t[i] = if d[i] > 0.0 { f * d[i] } else { f.min(-0.1) };
                }
                sum = t[..block.len()].iter().fold(sum, |s, q| s + q);
            }
            *acc = sum;
        }
    }

    #[test]
    fn finished_pairs_are_the_domains_separations_to_the_bit() {
        use crate::domain::BoundaryKind;
        // periodic, reflecting and open axes; a near both faces of the periodic axis so that
        // the wrap acts both ways, and every mirror code of the reflecting axis (0, 3, 6)
        let dom = Domain::<3> {
            lo: [0.0, -1.0, 0.0],
            hi: [1.0, 2.0, 1.0],
            kind: [
                BoundaryKind::Periodic,
                BoundaryKind::Reflect,
                BoundaryKind::Open,
            ],
        };
        let mut dx = [[0.0; LANES]; 3];
        let mut vab = [[0.0; LANES]; 3];
        let mut wrapped = 0;
        for xa0 in [0.013, 0.5, 0.987] {
            let xa = Vector::<3>::new(xa0, -0.93, 0.4);
            let va = Vector::<3>::new(0.3, -1.7, 0.25);
            let mut want = Vec::new();
            for k in 0..10 {
                let t = k as f64;
                let xb = Vector::<3>::new((0.11 * t + 0.003).fract(), -1.0 + 0.29 * t, 0.1 * t);
                let vb = Vector::<3>::new(0.7 - 0.1 * t, 0.05 * t, -0.3);
                for code in [0u8, 3, 6] {
                    let i = want.len();
                    let w = fill_pair(&dom, (&xb, &vb), code, &mut dx, &mut vab, i);
                    assert_eq!(w, dom.image_velocity(&vb, code));
                    let d = dom.separation(&xa, &xb, code);
                    wrapped += (d[0] != xa[0] - xb[0]) as usize;
                    want.push((d, va - w));
                }
            }
            finish_pairs(&dom, (&xa, &va), &mut dx, &mut vab, want.len());
            for (j, (d, v)) in want.iter().enumerate() {
                for k in 0..3 {
                    assert_eq!(dx[k][j].to_bits(), d[k].to_bits(), "pair {j} axis {k}");
                    assert_eq!(vab[k][j].to_bits(), v[k].to_bits(), "pair {j} axis {k}");
                }
            }
        }
        assert!(wrapped > 0, "some pairs must wrap across the periodic axis");
    }

    #[test]
    fn every_width_gives_the_same_bits() {
        let n = 500;
        let x: Vec<f64> = (0..n).map(|i| (i as f64 * 0.37).sin() * 1.7).collect();
        let rows: Vec<Vec<usize>> = (0..n)
            .map(|a| (0..a % 67).map(|k| (a * 13 + k * 5) % n).collect())
            .collect();
        let pass = KernelTerms { x: &x, rows: &rows };
        let mut base = vec![0.0; n];
        for_each_row_at(Width::Baseline, &pass, &mut base);
        assert!(base.iter().any(|&v| v != 0.0));
        let mut wide = vec![0.0; n];
        for_each_row_at(Width::detect(), &pass, &mut wide);
        let mut widest = vec![0.0; n];
        for_each_row_at(Widest::detect(), &pass, &mut widest);
        for a in 0..n {
            assert_eq!(base[a].to_bits(), wide[a].to_bits(), "row {a}");
            assert_eq!(base[a].to_bits(), widest[a].to_bits(), "row {a}");
        }
    }

    #[test]
    fn rows_of_every_length_match_a_plain_loop_to_the_bit() {
        let n = 300;
        let x: Vec<f64> = (0..n).map(|i| (i as f64 * 0.7).sin()).collect();
        // rows of 0 to 40 entries: empty, partial and whole blocks
        let rows: Vec<Vec<usize>> = (0..n)
            .map(|a| (0..a % 41).map(|k| (a * 7 + k) % n).collect())
            .collect();
        let mut got = vec![0.0; n];
        for_each_row(&SquaredGaps { x: &x, rows: &rows }, &mut got);
        for a in 0..n {
            let want = rows[a]
                .iter()
                .fold(0.0, |s, &b| s + (x[a] - x[b]) * (x[a] - x[b]));
            assert_eq!(got[a].to_bits(), want.to_bits(), "row {a}");
        }
    }
}
