//! The cut of the working list from the master list, on lanes ([`super::lanes`]): once h is
//! final, a pair (a, b) stays listed while |x_a − image(x_b)| < max(2h_a, 2h_b), and wall–wall
//! pairs go unless the scheme asked for them. A pass that needs only the pairs' geometry,
//! velocities and masses (standard SPH's velocity gradients) rides on the cut through a
//! [`CutVisitor`] instead of walking the lists once more.
//!
//! Each row is read in blocks: the fill reads a neighbour's image through the domain, the keep
//! test and the visitor's pair terms run as branch-free loops over the lanes, and the kept
//! entries are appended with no branch (write, then advance by the test's 0 or 1). The keep
//! test on the 3D Sod holds for about two entries in three at random (the skin and the
//! scatter neighbours are the rest), which is why the branch per entry was suspected. Measured
//! against the per-entry loop it replaced, it is neutral, not a gain (BENCHMARKS.md, "Pair
//! loops on lanes": 5 % faster on the periodic box, 5 % slower on the 3D Sod): the gradient
//! terms are now computed for the dropped third of the entries too. The plain cut
//! ([`NoVisit`]) also fills v_ab and m_b, which only a visitor reads.

use super::lanes::{fill_pair, finish_pairs, padded, Runs, Wide, Width, LANES};
use super::{unpack, NeighbourList};
use crate::particles::Vector;
use crate::scratch::Scratch;
use crate::system::System;
use crate::threads::LIGHT;
use rayon::prelude::*;

/// A block of up to [`LANES`] master-list entries of particle a. Lanes at and past `n` are
/// padding, with `keep` false; their other fields hold whatever an earlier block of the same
/// chunk left there (finite values of real pairs, or the zeros the block started with).
pub struct CutBlock {
    /// Entries in this block (the rest up to [`padded`] is padding).
    pub n: usize,
    /// Lanes the compute loops run to (`n` rounded up).
    pub lanes: usize,
    /// x_a − image(x_b) (components past D unused).
    pub dx: [[f64; LANES]; 3],
    pub r2: [f64; LANES],
    /// v_a − image(v_b).
    pub vab: [[f64; LANES]; 3],
    /// m_b
    pub m: [f64; LANES],
    /// Listed in the working list.
    pub keep: [bool; LANES],
}

impl Default for CutBlock {
    fn default() -> Self {
        Self {
            n: 0,
            lanes: 0,
            dx: [[0.0; LANES]; 3],
            r2: [0.0; LANES],
            vab: [[0.0; LANES]; 3],
            m: [0.0; LANES],
            keep: [false; LANES],
        }
    }
}

/// A pass over the kept pairs during the cut.
pub trait CutVisitor<const D: usize>: Sync {
    type Acc: Send;
    /// The pass's own lane arrays, made once per chunk of rows (see [`CutRows`]).
    type Scratch: Default;
    /// Add the kept lanes' pair terms to `acc`, in lane order; a lane with `keep` false adds
    /// nothing (it must not read `scratch` lanes this block did not write). `#[inline(always)]`,
    /// so it compiles into the cut's AVX2 copy.
    fn block(
        &self,
        sys: &System<D>,
        a: usize,
        acc: &mut Self::Acc,
        blk: &CutBlock,
        scratch: &mut Self::Scratch,
    );
}

/// The plain cut.
pub struct NoVisit;

impl<const D: usize> CutVisitor<D> for NoVisit {
    type Acc = ();
    type Scratch = ();
    #[inline(always)]
    fn block(&self, _: &System<D>, _: usize, _: &mut (), _: &CutBlock, _: &mut ()) {}
}

/// What the cut reads of a neighbour, packed: one record instead of a cache line per field.
#[derive(Clone, Copy)]
struct CutRecord<const D: usize> {
    x: Vector<D>,
    v: Vector<D>,
    /// 2h
    reach: f64,
    m: f64,
    wall: bool,
}

/// The working list cut from `sys`'s master list, with `visitor` run on the kept pairs,
/// written into `reuse`'s allocations (the working list it replaces); the records it packs
/// live in `scratch` between steps.
pub fn cut<const D: usize, V: CutVisitor<D>>(
    sys: &System<D>,
    out: &mut [V::Acc],
    visitor: &V,
    reuse: NeighbourList,
    scratch: &mut Scratch,
) -> NeighbourList {
    let p = &sys.particles;
    let k = &sys.kernel;
    let n = p.len();
    let mut recs: Vec<CutRecord<D>> = scratch.take();
    (0..n)
        .into_par_iter()
        .with_min_len(LIGHT)
        .map(|i| CutRecord {
            x: p.pos[i],
            v: p.vel[i],
            reach: k.radius(p.h[i]),
            m: p.mass[i],
            wall: p.body[i] != 0,
        })
        .collect_into_vec(&mut recs);
    let wide = Width::detect();
    let master = &sys.verlet.list;
    let list = NeighbourList::from_chunks(
        out,
        |start, accs| {
            wide.run(CutRows {
                sys,
                recs: &recs,
                visitor,
                start,
                accs,
                list: master,
            })
        },
        reuse,
    );
    scratch.keep(recs);
    list
}

/// One chunk of rows: its entry counts and kept entries. The lane arrays live in `run`'s
/// frame, made once per chunk: zeroed for every row they were 4.5 % of the 3D Sod's samples
/// (`memset`), and kept behind a reference the compiler could no longer tell them apart from
/// the output, which cost more than that.
struct CutRows<'a, const D: usize, V: CutVisitor<D>> {
    sys: &'a System<D>,
    recs: &'a [CutRecord<D>],
    visitor: &'a V,
    start: usize,
    accs: &'a mut [V::Acc],
    list: &'a NeighbourList,
}

impl<const D: usize, V: CutVisitor<D>> Wide for CutRows<'_, D, V> {
    type Output = (Vec<u32>, Vec<u32>);

    #[inline(always)]
    fn run(self) -> Self::Output {
        let dom = &self.sys.domain;
        let rows = self.start..self.start + self.accs.len();
        let list = self.list;
        let mut counts = Vec::with_capacity(rows.len());
        let mut kept: Vec<u32> = vec![0; list.offsets[rows.end] - list.offsets[rows.start]];
        let mut len = 0;
        let mut blk = CutBlock::default();
        let mut reach = [0.0; LANES];
        let mut wall = [false; LANES];
        let mut scratch = V::Scratch::default();
        for (a, acc) in rows.zip(self.accs.iter_mut()) {
            let ra = self.recs[a];
            // wall–wall pairs stay only when the scheme asked for them
            let drop_walls = ra.wall && !self.sys.wall_pairs;
            let before = len;
            for entries in list.of(a).chunks(LANES) {
                let n = entries.len();
                let lanes = padded(n);
                for (i, &e) in entries.iter().enumerate() {
                    let (b, code) = unpack(e);
                    let rb = &self.recs[b];
                    fill_pair(dom, (&rb.x, &rb.v), code, &mut blk.dx, &mut blk.vab, i);
                    reach[i] = rb.reach;
                    blk.m[i] = rb.m;
                    wall[i] = rb.wall;
                }
                finish_pairs(dom, (&ra.x, &ra.v), &mut blk.dx, &mut blk.vab, n);
                for i in 0..lanes {
                    let mut r2 = 0.0;
                    for k in 0..D {
                        r2 += blk.dx[k][i] * blk.dx[k][i];
                    }
                    let reach = ra.reach.max(reach[i]);
                    blk.r2[i] = r2;
                    // `&`, not `&&`: three lane-wise tests, no branches (callgrind: the
                    // short-circuit form was 2.3 % of Noh 2D's instructions, this one 1.2 %)
                    blk.keep[i] = (i < n) & (r2 < reach * reach) & !(drop_walls & wall[i]);
                }
                blk.n = n;
                blk.lanes = lanes;
                // every entry is written, and kept by advancing past it (no branch)
                for (i, &e) in entries.iter().enumerate() {
                    kept[len] = e;
                    len += blk.keep[i] as usize;
                }
                self.visitor.block(self.sys, a, acc, &blk, &mut scratch);
            }
            counts.push((len - before) as u32);
        }
        kept.truncate(len);
        (counts, kept)
    }
}
