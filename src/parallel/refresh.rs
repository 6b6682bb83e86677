//! Halo refreshes between passes (issue 23's design): when a pass reads of its neighbours what
//! the previous pass computed, the halo copies' values of those fields are overwritten with
//! their owners' before it runs. Every copy then holds its owner's bits at any depth, so a
//! scheme that refreshes this way needs a halo of one support (`Scheme::halo_depth` 1), and
//! the halo's own redundant work is one support's worth.
//!
//! A refresh carries any per-particle arrays, in the particles or the scheme's own (CRKSPH's
//! volumes and corrections, the IA matrices): each is a [`HaloColumn`], and one refresh sends
//! all of its columns in one message per neighbour rank. On one process it does nothing.
//! A pass refreshes with `sys.halo_sync().refresh(vec![rows(&mut p.h), rows(&mut volumes)])`
//! (the handle taken before the arrays are borrowed).

use crate::system::{RankSums, System};
use nalgebra::SMatrix;
use std::sync::Arc;

/// A per-particle value a halo refresh can carry, as `WIDTH` numbers.
pub trait HaloRow: Copy {
    const WIDTH: usize;
    fn put(&self, out: &mut Vec<f64>);
    fn take(x: &[f64]) -> Self;
}

impl HaloRow for f64 {
    const WIDTH: usize = 1;
    fn put(&self, out: &mut Vec<f64>) {
        out.push(*self);
    }
    fn take(x: &[f64]) -> Self {
        x[0]
    }
}

/// Vectors (`SVector` is a one-column matrix) and matrices, column by column.
impl<const R: usize, const C: usize> HaloRow for SMatrix<f64, R, C> {
    const WIDTH: usize = R * C;
    fn put(&self, out: &mut Vec<f64>) {
        out.extend_from_slice(self.as_slice());
    }
    fn take(x: &[f64]) -> Self {
        SMatrix::from_column_slice(x)
    }
}

/// One array of a refresh: its values of particle i out (the owner) and in (the halo copy).
pub trait HaloColumn {
    fn width(&self) -> usize;
    fn put(&self, i: usize, out: &mut Vec<f64>);
    fn take(&mut self, i: usize, x: &[f64]);
}

struct Rows<'a, T>(&'a mut [T]);

impl<T: HaloRow> HaloColumn for Rows<'_, T> {
    fn width(&self) -> usize {
        T::WIDTH
    }
    fn put(&self, i: usize, out: &mut Vec<f64>) {
        self.0[i].put(out)
    }
    fn take(&mut self, i: usize, x: &[f64]) {
        self.0[i] = T::take(x)
    }
}

/// A per-particle array (indexed as the particles, halo copies last) as a column of a refresh.
pub fn rows<T: HaloRow>(x: &mut [T]) -> Box<dyn HaloColumn + '_> {
    Box::new(Rows(x))
}

/// What a refresh needs of the system: the other ranks, and where the halo starts. Taken
/// with [`System::halo_sync`] before borrowing the arrays to refresh.
pub struct HaloSync {
    ranks: Option<Arc<dyn RankSums>>,
    owned: usize,
}

impl HaloSync {
    /// Whether the run is shared among ranks (a refresh does something).
    pub fn distributed(&self) -> bool {
        self.ranks.is_some()
    }

    /// Overwrite the halo copies' values in `columns` with their owners' (a collective on a
    /// distributed run; nothing on one process). A failed exchange leaves them as they are
    /// and is reported at the evaluation's agreement.
    pub fn refresh(&self, mut columns: Vec<Box<dyn HaloColumn + '_>>) {
        let Some(ranks) = &self.ranks else {
            return;
        };
        let width: usize = columns.iter().map(|c| c.width()).sum();
        let got = {
            let cols = &columns;
            let pack = |pick: &[u32]| -> Vec<f64> {
                let mut out = Vec::with_capacity(pick.len() * width);
                for &i in pick {
                    for c in cols {
                        c.put(i as usize, &mut out);
                    }
                }
                out
            };
            ranks.halo_values(width, &pack)
        };
        let Some(got) = got else {
            return;
        };
        for (k, row) in got.chunks_exact(width.max(1)).enumerate() {
            let mut at = 0;
            for c in columns.iter_mut() {
                let w = c.width();
                c.take(self.owned + k, &row[at..at + w]);
                at += w;
            }
        }
    }
}

impl<const D: usize> System<D> {
    /// The handle for refreshing the halo between passes ([`HaloSync::refresh`]).
    pub fn halo_sync(&self) -> HaloSync {
        HaloSync {
            ranks: self.ranks.clone(),
            owned: self.owned(),
        }
    }
}
