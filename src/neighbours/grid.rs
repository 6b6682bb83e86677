//! The cell grid of the neighbour search: particles filed by cell (counting sort, so a
//! cell's particles are contiguous), cells tiling periodic axes exactly, and the stencil of
//! cells a search sphere touches.

use super::MAX_SPAN;
use crate::domain::{BoundaryKind, Domain};
use crate::particles::Vector;
use rayon::prelude::*;

/// Uniform cell grid over the particles' bounding box (the domain on periodic axes).
///
/// On a periodic axis the cells tile the period exactly (width = period / cell count, so at
/// least the nominal cell size): every particle of cell c lies in
/// `[origin + c·width, origin + (c+1)·width)`, and the image of a cell reached across the
/// period is that cell shifted by one period. The search can then hand out whole cells with
/// one shift each instead of taking the minimum image of every candidate.
#[derive(Debug, Clone, serde::Serialize, serde::Deserialize)]
pub struct CellGrid<const D: usize> {
    #[serde(with = "crate::coupling::state::const_array")]
    origin: [f64; D],
    /// Cell width per axis.
    #[serde(with = "crate::coupling::state::const_array")]
    width: [f64; D],
    /// Period per axis (hi − lo of the domain, exactly as `Domain::separation` takes it; 0
    /// on other axes).
    #[serde(with = "crate::coupling::state::const_array")]
    period: [f64; D],
    #[serde(with = "crate::coupling::state::const_array")]
    dims: [usize; D],
    #[serde(with = "crate::coupling::state::const_array")]
    periodic: [bool; D],
    /// Particle indices sorted by cell.
    pub sorted: Vec<u32>,
    /// `cell_start[c]..cell_start[c+1]` indexes `sorted` for cell c.
    cell_start: Vec<u32>,
}

impl<const D: usize> Default for CellGrid<D> {
    fn default() -> Self {
        Self {
            origin: [0.0; D],
            width: [1.0; D],
            period: [0.0; D],
            dims: [1; D],
            periodic: [false; D],
            sorted: vec![],
            cell_start: vec![0, 0],
        }
    }
}

impl<const D: usize> CellGrid<D> {
    /// Build a grid for the search radii `reach`: cells half the median radius wide (so
    /// dense regions with small h are not scanned with the largest radius), but never less
    /// than 1/MAX_SPAN of the largest radius.
    pub fn build(pos: &[Vector<D>], domain: &Domain<D>, reach: &[f64]) -> Self {
        let rmax = reach.iter().cloned().fold(0.0, f64::max);
        let median = if reach.is_empty() {
            1.0
        } else {
            let mut r = reach.to_vec();
            let mid = r.len() / 2;
            *r.select_nth_unstable_by(mid, |a, b| a.total_cmp(b)).1
        };
        let cell_size = (0.5 * median).max(rmax / MAX_SPAN as f64);
        let n = pos.len();
        let (lo, hi, periodic) = cell_box(pos, domain);
        // Cap the cell count at ~2 cells per particle (sparse or far-flung particles).
        let mut cell = cell_size.max(1e-300);
        loop {
            let total: f64 = (0..D)
                .map(|k| ((hi[k] - lo[k]) / cell).floor().max(1.0))
                .product();
            if total <= 2.0 * n as f64 + 8.0 {
                break;
            }
            cell *= 1.25;
        }
        let (dims, width) = tile(&lo, &hi, &periodic, cell);
        let period: [f64; D] =
            std::array::from_fn(|k| if periodic[k] { hi[k] - lo[k] } else { 0.0 });
        let mut grid = Self {
            origin: lo,
            width,
            period,
            dims,
            periodic,
            sorted: Vec::new(),
            cell_start: Vec::new(),
        };
        let ncells: usize = dims.iter().product();
        let cells: Vec<u32> = pos.par_iter().map(|x| grid.cell_of(x) as u32).collect();
        let mut count = vec![0u32; ncells + 1];
        for &c in &cells {
            count[c as usize + 1] += 1;
        }
        for c in 0..ncells {
            count[c + 1] += count[c];
        }
        let mut fill = count.clone();
        let mut sorted = vec![0u32; n];
        for (i, &c) in cells.iter().enumerate() {
            sorted[fill[c as usize] as usize] = i as u32;
            fill[c as usize] += 1;
        }
        grid.sorted = sorted;
        grid.cell_start = count;
        grid
    }

    /// x relative to the grid's origin, brought into [0, period) on periodic axes (positions
    /// between drifts may lie outside the box). Cells, candidates and queries all use these
    /// coordinates, so a particle lies in the cell it is filed under, and a pair's two
    /// searches compute the same separation with opposite signs.
    #[inline(always)]
    pub fn local(&self, x: &Vector<D>) -> [f64; D] {
        std::array::from_fn(|k| {
            let mut y = x[k] - self.origin[k];
            if self.periodic[k] {
                let l = self.period[k];
                y -= l * (y / l).floor();
                // rounding may land on the period itself, or a NaN guard: file it at 0
                if !(0.0..l).contains(&y) {
                    y = 0.0;
                }
            }
            y
        })
    }

    fn cell_of(&self, x: &Vector<D>) -> usize {
        let y = self.local(x);
        let mut c = 0usize;
        for k in (0..D).rev() {
            let ck = ((y[k] / self.width[k]).floor() as isize).clamp(0, self.dims[k] as isize - 1);
            c = c * self.dims[k] + ck as usize;
        }
        c
    }

    /// Rename the particles of [`Self::sorted`] after a reorder (new index i = old index
    /// `perm[i]`); the cells stay as they are. Without it the cell order stayed in the
    /// numbering of the grid's build, and the next reorder before a rebuild applied it to
    /// particles already renumbered.
    pub fn permute(&mut self, perm: &[u32]) {
        if self.sorted.len() != perm.len() {
            return;
        }
        let inv = super::inverse(perm);
        for s in &mut self.sorted {
            *s = inv[*s as usize];
        }
    }

    /// Visit every cell that can hold points within `reach` of the point with local
    /// coordinates `y` (see [`Self::local`]), in runs of neighbouring cells along x, as
    /// `f(start, end, shift)`: positions `start..end` of [`Self::sorted`] hold the run's
    /// particles, and `shift` is the period
    /// on the axes where the cell was reached across it (with its sign, 0 elsewhere), so
    /// `(y − y_b) − shift` is the separation from the image of b near y. Taken in that order
    /// it is exactly the negative of the separation b finds for y (a pair's two searches
    /// agree on whether it is in range).
    /// The stencil spans ⌈reach/width⌉ cells each way, pruned to cells the search sphere
    /// touches; each cell is visited once (small periodic grids wrap onto a cell only once,
    /// through its nearest image).
    #[inline]
    pub fn for_cells(&self, y: &[f64; D], reach: f64, mut f: impl FnMut(usize, usize, &[f64; D])) {
        const MAXS: usize = 2 * MAX_SPAN + 1;
        let mut ranges: [[u32; MAXS]; D] = [[0; MAXS]; D];
        // squared distance from x to the slab of each candidate cell along each axis
        let mut gaps: [[f64; MAXS]; D] = [[0.0; MAXS]; D];
        // the period to subtract from x − x_b for each candidate cell's image
        let mut shifts: [[f64; MAXS]; D] = [[0.0; MAXS]; D];
        let mut counts = [0usize; D];
        let r2 = reach * reach;
        for k in 0..D {
            let w = self.width[k];
            let span = ((reach / w).ceil() as isize).min(MAX_SPAN as isize);
            let fc = y[k] / w;
            let c = fc.floor() as isize;
            let within = (fc - c as f64) * w; // offset of x inside its cell
            let dk = self.dims[k] as isize;
            let mut m = 0;
            for off in -span..=span {
                let gap = match off {
                    0 => 0.0,
                    o if o < 0 => within + (-o - 1) as f64 * w,
                    o => o as f64 * w - within,
                };
                if gap * gap >= r2 {
                    continue;
                }
                let mut ci = c + off;
                let mut shift = 0.0;
                if self.periodic[k] {
                    // the cell's image at c + off is cell ci moved by `wraps` periods
                    let wraps = ci.div_euclid(dk);
                    ci -= wraps * dk;
                    shift = wraps as f64 * self.period[k];
                } else if ci < 0 || ci >= dk {
                    // Outside the grid: holds no particle (the grid spans them all).
                    continue;
                }
                let ci = ci as u32;
                if let Some(j) = ranges[k][..m].iter().position(|&r| r == ci) {
                    if gap * gap < gaps[k][j] {
                        gaps[k][j] = gap * gap;
                        shifts[k][j] = shift;
                    }
                } else {
                    ranges[k][m] = ci;
                    gaps[k][m] = gap * gap;
                    shifts[k][m] = shift;
                    m += 1;
                }
            }
            if m == 0 {
                return;
            }
            counts[k] = m;
        }
        // Cells along x (the fastest axis of the cell numbering) that follow each other in
        // the numbering and share a shift hold one contiguous run of `sorted`: hand out each
        // such run at once (a sphere of 2 cells' radius spans ~20 runs but ~70 cells of two
        // particles each in 3D, and the per-cell work cost as much as the candidates).
        let mut idx = [0usize; D];
        let mut sh = [0.0; D];
        loop {
            let mut base = 0usize;
            let mut g2 = 0.0;
            for k in (1..D).rev() {
                base = base * self.dims[k] + ranges[k][idx[k]] as usize;
                g2 += gaps[k][idx[k]];
                sh[k] = shifts[k][idx[k]];
            }
            base *= self.dims[0];
            if g2 < r2 {
                // the open run: first and last cell along x, and its shift
                let mut run: Option<(u32, u32, f64)> = None;
                for j in 0..counts[0] {
                    if g2 + gaps[0][j] >= r2 {
                        continue;
                    }
                    let (ci, s) = (ranges[0][j], shifts[0][j]);
                    match &mut run {
                        Some((_, last, rs)) if ci == *last + 1 && s == *rs => *last = ci,
                        _ => {
                            if let Some((first, last, rs)) = run {
                                sh[0] = rs;
                                self.visit_run(base, first, last, &sh, &mut f);
                            }
                            run = Some((ci, ci, s));
                        }
                    }
                }
                if let Some((first, last, rs)) = run {
                    sh[0] = rs;
                    self.visit_run(base, first, last, &sh, &mut f);
                }
            }
            if !next_index(&mut idx, &counts, 1) {
                return;
            }
        }
    }

    /// Hand cells `base + first ..= base + last` (one run of `sorted`) to `f`, if not empty.
    #[inline(always)]
    fn visit_run(
        &self,
        base: usize,
        first: u32,
        last: u32,
        sh: &[f64; D],
        f: &mut impl FnMut(usize, usize, &[f64; D]),
    ) {
        let s = self.cell_start[base + first as usize] as usize;
        let e = self.cell_start[base + last as usize + 1] as usize;
        if s < e {
            f(s, e, sh);
        }
    }
}

/// The box a grid of cells covers, and which axes are periodic: the particles' bounding box,
/// the domain itself on periodic axes (which the cells tile exactly), [0, 1] without
/// particles.
pub(super) fn cell_box<const D: usize>(
    pos: &[Vector<D>],
    domain: &Domain<D>,
) -> ([f64; D], [f64; D], [bool; D]) {
    let mut lo = [f64::INFINITY; D];
    let mut hi = [f64::NEG_INFINITY; D];
    for x in pos {
        for k in 0..D {
            lo[k] = lo[k].min(x[k]);
            hi[k] = hi[k].max(x[k]);
        }
    }
    let periodic: [bool; D] = std::array::from_fn(|k| domain.kind[k] == BoundaryKind::Periodic);
    for k in 0..D {
        if periodic[k] {
            (lo[k], hi[k]) = (domain.lo[k], domain.hi[k]);
        }
        if pos.is_empty() {
            (lo[k], hi[k]) = (0.0, 1.0);
        }
    }
    (lo, hi, periodic)
}

/// Cell counts and widths per axis for cells at least `cell` wide over [lo, hi]: an integer
/// number exactly tiling the period on periodic axes, elsewhere as many as reach past hi.
pub(super) fn tile<const D: usize>(
    lo: &[f64; D],
    hi: &[f64; D],
    periodic: &[bool; D],
    cell: f64,
) -> ([usize; D], [f64; D]) {
    let mut dims = [1usize; D];
    let mut width = [cell; D];
    for k in 0..D {
        if periodic[k] {
            dims[k] = ((hi[k] - lo[k]) / cell).floor().max(1.0) as usize;
            width[k] = (hi[k] - lo[k]) / dims[k] as f64;
        } else {
            dims[k] = (((hi[k] - lo[k]) / cell).floor() as usize + 1).max(1);
        }
    }
    (dims, width)
}

/// Step the multi-index `idx` (digit k in 0..len[k]) to the next one over the axes from
/// `from` up, lowest axis first; false once every combination was visited.
#[inline(always)]
pub(super) fn next_index<const D: usize>(
    idx: &mut [usize; D],
    len: &[usize; D],
    from: usize,
) -> bool {
    for k in from..D {
        idx[k] += 1;
        if idx[k] < len[k] {
            return true;
        }
        idx[k] = 0;
    }
    false
}

impl<const D: usize> CellGrid<D> {
    /// Whether this grid (from a saved state) is one a later step can use with `n`
    /// particles: finite geometry, a cell table matching its dimensions, and `sorted` a
    /// permutation of the particles (or the empty grid of a state whose lists were reset).
    pub fn check(&self, n: usize) -> Result<(), String> {
        if self.width.iter().any(|w| !(w.is_finite() && *w > 0.0))
            || self.origin.iter().any(|x| !x.is_finite())
        {
            return Err("cell grid: non-finite or non-positive geometry".into());
        }
        let cells = self
            .dims
            .iter()
            .try_fold(1usize, |a, &d| if d == 0 { None } else { a.checked_mul(d) })
            .filter(|&c| c <= 2 * n + 1024)
            .ok_or("cell grid: dimensions out of range")?;
        if self.sorted.is_empty() && self.cell_start.len() <= cells + 1 {
            // the default grid, or one whose particles were reset (ports)
            return if self.cell_start.iter().all(|&c| c == 0) {
                Ok(())
            } else {
                Err("cell grid: cell table without particles".into())
            };
        }
        if self.sorted.len() != n || self.cell_start.len() != cells + 1 {
            return Err(format!(
                "cell grid: {} sorted particles and {} cell starts for {n} particles and {cells} cells",
                self.sorted.len(),
                self.cell_start.len()
            ));
        }
        if self.cell_start[0] != 0
            || self.cell_start.windows(2).any(|w| w[0] > w[1])
            || self.cell_start[cells] as usize != n
        {
            return Err("cell grid: cell starts not increasing to the particle count".into());
        }
        let mut seen = vec![false; n];
        for &i in &self.sorted {
            match seen.get_mut(i as usize) {
                Some(s) if !*s => *s = true,
                _ => return Err("cell grid: sorted particles are not a permutation".into()),
            }
        }
        Ok(())
    }
}
