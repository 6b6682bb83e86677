//! Neighbour search: a cell-linked grid (counting sort by cell, so particles in one cell are
//! contiguous, `grid`) built with each master list, and compressed per-particle neighbour lists built in
//! parallel. A pair (a, b) is listed when `|x_a − image(x_b)| < max(R_a, R_b)`, i.e. gather
//! *and* scatter neighbours for variable h. Entries pack the neighbour index (low 27 bits)
//! with the image code (high 5 bits: mirror ghosts of reflecting walls).

pub mod cut;
mod grid;
pub mod lanes;
pub mod slack;

pub use grid::CellGrid;

use crate::domain::{Domain, ImageCode};
use crate::particles::Vector;
use rayon::prelude::*;

const INDEX_BITS: u32 = 27;
const INDEX_MASK: u32 = (1 << INDEX_BITS) - 1;
/// Largest stencil half-width in cells (the grid's cells are at least rmax/MAX_SPAN wide).
const MAX_SPAN: usize = 16;
/// Largest particle count a list can address.
pub const MAX_PARTICLES: usize = INDEX_MASK as usize;

#[inline(always)]
pub fn pack(index: usize, code: ImageCode) -> u32 {
    (index as u32) | ((code as u32) << INDEX_BITS)
}

#[inline(always)]
pub fn unpack(entry: u32) -> (usize, ImageCode) {
    (
        (entry & INDEX_MASK) as usize,
        (entry >> INDEX_BITS) as ImageCode,
    )
}

/// Compressed neighbour lists (CSR): neighbours of a are `entries[offsets[a]..offsets[a+1]]`.
#[derive(Debug, Clone, Default, serde::Serialize, serde::Deserialize)]
pub struct NeighbourList {
    pub offsets: Vec<usize>,
    pub entries: Vec<u32>,
}

impl NeighbourList {
    #[inline(always)]
    pub fn of(&self, a: usize) -> &[u32] {
        &self.entries[self.offsets[a]..self.offsets[a + 1]]
    }
    pub fn total_pairs(&self) -> usize {
        self.entries.len()
    }

    /// `per_pair` (one slot per listed pair, in list order) cut into one slice per row.
    pub fn split_rows_mut<'a, Q>(&self, per_pair: &'a mut [Q]) -> Vec<&'a mut [Q]> {
        assert_eq!(
            per_pair.len(),
            self.total_pairs(),
            "one slot per listed pair"
        );
        split_lengths(per_pair, self.offsets.windows(2).map(|w| w[1] - w[0]))
    }

    /// Whether these lists (from a saved state) fit `n` particles: empty (built anew by the
    /// next evaluation), or offsets for every particle, increasing to the entry count, and
    /// every entry naming a particle and an image code the domain has.
    pub fn check(&self, n: usize) -> Result<(), String> {
        if self.offsets.is_empty() && self.entries.is_empty() {
            return Ok(());
        }
        if self.offsets.len() != n + 1
            || self.offsets[0] != 0
            || self.offsets.windows(2).any(|w| w[0] > w[1])
            || self.offsets[n] != self.entries.len()
        {
            return Err(format!(
                "neighbour list: {} offsets for {n} particles, not increasing to its {} entries",
                self.offsets.len(),
                self.entries.len()
            ));
        }
        if self.entries.iter().any(|&e| unpack(e).0 >= n) {
            return Err("neighbour list: an entry names no particle".into());
        }
        Ok(())
    }

    /// Build lists for all particles: b is a neighbour of a (through image `code`) when
    /// `|x_a − image(x_b)| < max(reach_a, reach_b)`. Self (a, code 0) is excluded; a particle's
    /// own mirror image is included. Each particle searches only its own radius (gather);
    /// pairs found by one side only (the scatter neighbours of the other) are then added to
    /// the other side's list, so the search cost follows the local h.
    pub fn build<const D: usize>(
        pos: &[Vector<D>],
        reach: &[f64],
        domain: &Domain<D>,
        grid: &CellGrid<D>,
    ) -> Self {
        Self::build_reusing(pos, reach, domain, grid, Self::default())
    }

    /// [`Self::build`] into `reuse`'s allocations (the list this one replaces; see
    /// [`Self::recycled`]).
    pub fn build_reusing<const D: usize>(
        pos: &[Vector<D>],
        reach: &[f64],
        domain: &Domain<D>,
        grid: &CellGrid<D>,
        reuse: Self,
    ) -> Self {
        let n = pos.len();
        const CHUNK: usize = 512;
        // What the search reads of a candidate, in cell order: position and squared reach,
        // so a cell's candidates are one contiguous run of memory.
        let cand: Vec<([f64; D], f64)> = grid
            .sorted
            .par_iter()
            .map(|&j| {
                let j = j as usize;
                (grid.local(&pos[j]), reach[j] * reach[j])
            })
            .collect();
        let sorted = &grid.sorted;
        // (counts, entries, reverse entries (target, packed source))
        type Part = (Vec<u32>, Vec<u32>, Vec<(u32, u32)>);
        let parts: Vec<Part> = (0..n.div_ceil(CHUNK))
            .into_par_iter()
            .map(|chunk| {
                let start = chunk * CHUNK;
                let end = (start + CHUNK).min(n);
                let mut counts = Vec::with_capacity(end - start);
                let mut out = Vec::with_capacity((end - start) * 32);
                let mut rev = Vec::new();
                let mut codes = Vec::with_capacity(8);
                for a in start..end {
                    let before = out.len();
                    let xa = pos[a];
                    let ra = reach[a];
                    let ra2 = ra * ra;
                    domain.image_codes(&xa, ra, &mut codes);
                    for &code in &codes {
                        // |x_a − M(x_b)| = |M(x_a) − x_b| for a mirror M: search around M(x_a)
                        let q = grid.local(&domain.image_position(&xa, code));
                        grid.for_cells(&q, ra, |s, e, shift| {
                            for (j, (xb, rb2)) in cand[s..e].iter().enumerate() {
                                let mut d2 = 0.0;
                                for k in 0..D {
                                    let d = (q[k] - xb[k]) - shift[k];
                                    d2 += d * d;
                                }
                                if d2 < ra2 {
                                    let b = sorted[s + j] as usize;
                                    if b == a && code == 0 {
                                        continue;
                                    }
                                    out.push(pack(b, code));
                                    // b's own search (radius r_b) will not find a: hand it over.
                                    if d2 >= *rb2 {
                                        rev.push((b as u32, pack(a, code)));
                                    }
                                }
                            }
                        });
                    }
                    counts.push((out.len() - before) as u32);
                }
                (counts, out, rev)
            })
            .collect();
        // Handed-over entries by target (then entry: the order is the same on any thread count).
        let mut rev: Vec<(u32, u32)> = parts.iter().flat_map(|p| p.2.iter().copied()).collect();
        rev.par_sort_unstable();
        // Row a: its gather entries, then the entries handed over to it, written once into
        // the final array (chunk by chunk, in parallel).
        let Self {
            mut offsets,
            mut entries,
        } = reuse;
        offsets.clear();
        offsets.resize(n + 1, 0);
        for (chunk, part) in parts.iter().enumerate() {
            for (i, &c) in part.0.iter().enumerate() {
                offsets[chunk * CHUNK + i + 1] = c as usize;
            }
        }
        for &(t, _) in &rev {
            offsets[t as usize + 1] += 1;
        }
        for a in 0..n {
            offsets[a + 1] += offsets[a];
        }
        Self::recycled(&mut entries, offsets[n]);
        let slices = split_lengths(
            &mut entries,
            (0..parts.len())
                .map(|chunk| offsets[((chunk + 1) * CHUNK).min(n)] - offsets[chunk * CHUNK]),
        );
        parts
            .par_iter()
            .zip(slices)
            .enumerate()
            .for_each(|(chunk, ((counts, out, _), slice))| {
                let start = chunk * CHUNK;
                let mut next = rev.partition_point(|&(t, _)| (t as usize) < start);
                let (mut src, mut dst) = (0, 0);
                for (i, &c) in counts.iter().enumerate() {
                    let c = c as usize;
                    slice[dst..dst + c].copy_from_slice(&out[src..src + c]);
                    (src, dst) = (src + c, dst + c);
                    while next < rev.len() && rev[next].0 as usize == start + i {
                        slice[dst] = rev[next].1;
                        (next, dst) = (next + 1, dst + 1);
                    }
                }
            });
        Self { offsets, entries }
    }

    /// Sort every row by the neighbours' stable ids `id` (then image code), in parallel by
    /// rows: rows in an order that does not depend on how the particles are numbered make
    /// every per-particle sum independent of it (the distributed run sorts so, see
    /// `parallel`). Each entry is sorted as one u64 key, id above the entry's own bits (code
    /// above index), so a comparison reads no id table: about a third of the time of sorting by
    /// a looked-up key (on 128k particles with 79 entries each, 2 threads: 0.097 s, as
    /// much as the build itself).
    pub fn sort_rows_by_id(&mut self, id: &[u32]) {
        let lengths = self.offsets.windows(2).map(|w| w[1] - w[0]);
        split_lengths(&mut self.entries, lengths)
            .into_par_iter()
            .with_min_len(64)
            .for_each_init(Vec::<u64>::new, |keys, row| {
                keys.clear();
                keys.extend(
                    row.iter()
                        .map(|&e| ((id[(e & INDEX_MASK) as usize] as u64) << 32) | e as u64),
                );
                keys.sort_unstable();
                for (e, k) in row.iter_mut().zip(keys.iter()) {
                    *e = *k as u32;
                }
            });
    }

    /// The same lists after the particles were reordered so that new index i is old index
    /// `perm[i]` (rows moved, neighbour indices renamed, image codes kept).
    pub fn permuted(&self, perm: &[u32]) -> Self {
        let inv = inverse(perm);
        Self::from_rows(perm.len(), |i, out| {
            out.extend(self.of(perm[i] as usize).iter().map(|&e| {
                let (b, code) = unpack(e);
                pack(inv[b] as usize, code)
            }))
        })
    }

    /// Lists for n particles whose row a is written by `fill(a, out)` (appending to `out`),
    /// built in parallel chunks of rows and joined in order.
    fn from_rows(n: usize, fill: impl Fn(usize, &mut Vec<u32>) + Sync) -> Self {
        let rows_of = |start: usize, rows: &mut [()]| {
            let mut counts = Vec::with_capacity(rows.len());
            let mut out = Vec::new();
            for a in start..start + rows.len() {
                let before = out.len();
                fill(a, &mut out);
                counts.push((out.len() - before) as u32);
            }
            (counts, out)
        };
        Self::from_chunks(&mut vec![(); n], rows_of, Self::default())
    }

    /// `entries` made `len` long for every slot to be written anew: what it held is kept
    /// (no zeroing), only a longer list appends zeros. Lists are made every step (the cut)
    /// and at every rebuild; a fresh array each time cost one page fault per 4 KiB written
    /// once it outgrew the allocator's reuse (glibc maps blocks over 32 MiB afresh and unmaps
    /// them when freed): at 10⁶ particles in 3D, 1.46 million faults in the six steps of
    /// `sphfmu bench --sizes 1000000 --dims 3 --steps 5`, 29 % of them writing the cut's
    /// entries (BENCHMARKS.md, 2026-12-07, sixth session).
    fn recycled(entries: &mut Vec<u32>, len: usize) {
        entries.resize(len, 0);
    }

    /// Lists for `acc.len()` particles built in parallel chunks of rows ([`row_chunk`]) and
    /// joined in order: `chunk(start, &mut acc[start..])` returns the entry counts and the
    /// entries of rows `start..start + its slice's length`, and may accumulate into their
    /// slots of `acc`. The lists are written into `reuse`'s allocations.
    pub(crate) fn from_chunks<T: Send>(
        acc: &mut [T],
        chunk: impl Fn(usize, &mut [T]) -> (Vec<u32>, Vec<u32>) + Sync,
        reuse: Self,
    ) -> Self {
        let n = acc.len();
        let chunk_len = row_chunk(n);
        let parts: Vec<(Vec<u32>, Vec<u32>)> = acc
            .par_chunks_mut(chunk_len)
            .enumerate()
            .map(|(c, rows)| chunk(c * chunk_len, rows))
            .collect();
        Self::concat(n, parts, reuse)
    }

    /// The lists whose rows are the chunks' rows in order: each part holds its rows' entry
    /// counts and their entries.
    fn concat(n: usize, parts: Vec<(Vec<u32>, Vec<u32>)>, reuse: Self) -> Self {
        let Self {
            mut offsets,
            mut entries,
        } = reuse;
        offsets.clear();
        offsets.reserve(n + 1);
        offsets.push(0usize);
        for (counts, _) in &parts {
            for &c in counts {
                offsets.push(offsets.last().unwrap() + c as usize);
            }
        }
        // each part's entries copied into its own slice of the array, in parallel (joined
        // on one thread, the copy was a serial stretch of every step's cut); the slices cover
        // the array, so nothing of the list it recycles is left
        assert_eq!(
            parts.iter().map(|(_, out)| out.len()).sum::<usize>(),
            offsets[n],
            "a chunk's entry counts add up to its entries"
        );
        Self::recycled(&mut entries, offsets[n]);
        let slices = split_lengths(&mut entries, parts.iter().map(|(_, out)| out.len()));
        parts
            .par_iter()
            .zip(slices)
            .for_each(|((_, out), slice)| slice.copy_from_slice(out));
        Self { offsets, entries }
    }
}

/// `slice` cut into consecutive pieces of the given lengths (the rows of a list, a chunk's
/// rows), so that each can be written by its own task.
fn split_lengths<T>(mut slice: &mut [T], lengths: impl Iterator<Item = usize>) -> Vec<&mut [T]> {
    let mut pieces = Vec::with_capacity(lengths.size_hint().0);
    for len in lengths {
        let (piece, rest) = std::mem::take(&mut slice).split_at_mut(len);
        pieces.push(piece);
        slice = rest;
    }
    pieces
}

/// The inverse of the renumbering "new index i = old index `perm[i]`": old index → new.
pub(crate) fn inverse(perm: &[u32]) -> Vec<u32> {
    let mut inv = vec![0u32; perm.len()];
    for (new, &old) in perm.iter().enumerate() {
        inv[old as usize] = new as u32;
    }
    inv
}

/// O(N²) reference: same rule as [`NeighbourList::build`], for tests. Lists come sorted.
pub fn brute_force<const D: usize>(
    pos: &[Vector<D>],
    reach: &[f64],
    domain: &Domain<D>,
) -> Vec<Vec<u32>> {
    let maxr = reach.iter().cloned().fold(0.0, f64::max);
    let mut codes = Vec::new();
    (0..pos.len())
        .map(|a| {
            let mut l = Vec::new();
            domain.image_codes(&pos[a], maxr, &mut codes);
            for &code in &codes {
                for b in 0..pos.len() {
                    if b == a && code == 0 {
                        continue;
                    }
                    let d = domain.separation(&pos[a], &pos[b], code);
                    let r = reach[a].max(reach[b]);
                    if d.norm_squared() < r * r {
                        l.push(pack(b, code));
                    }
                }
            }
            l.sort_unstable();
            l
        })
        .collect()
}

/// Rows per parallel chunk: at most 1024 (a chunk's row counts and entries stay in cache),
/// and small enough that every thread gets several chunks. A fixed 1024 split the closed
/// tank's 1,566 particles into two chunks of 1024 and 542, so a second thread could cut
/// the cut of the working list by a third at most. The joined list does not depend on it.
fn row_chunk(n: usize) -> usize {
    (n / (8 * rayon::current_num_threads())).clamp(64, 1024)
}
