//! Arrays a pass fills anew every step (the per-particle records the pair passes read, the h
//! solve's results), kept between steps so that the next step writes into memory the process
//! already holds.
//!
//! Why: glibc's `malloc` maps a block over 32 MiB afresh and unmaps it when it is freed, so a
//! per-step array that large costs one page fault per 4 KiB on its first write, every step. At
//! 10⁶ particles in 3D the per-step arrays are 10–160 MB each, and `sphfmu bench --sizes 1000000
//! --dims 3 --steps 5` took 1.46 million page faults (3.5 s of system time in 13–14 s) where the
//! same run with the allocator told to keep its memory took 0.46 million (BENCHMARKS.md,
//! 2026-12-07, sixth session). Below about 32 MiB an array is recycled by the allocator itself,
//! which is why the small cases never showed it.
//!
//! One store per [`crate::system::System`] (no global state: several FMU instances each keep
//! their own), one array per element type. A pass takes its array, fills it with
//! `collect_into_vec` (which keeps the capacity) and gives it back. Nothing in here is part of
//! the solver's state: a clone starts empty, and saved states never see it.

use std::any::{Any, TypeId};
use std::collections::HashMap;

#[derive(Default)]
pub struct Scratch {
    arrays: HashMap<TypeId, Box<dyn Any + Send + Sync>>,
}

impl Scratch {
    /// The array kept for element type `T` (empty, with its capacity), or a new one.
    pub fn take<T: Send + Sync + 'static>(&mut self) -> Vec<T> {
        self.arrays
            .remove(&TypeId::of::<Vec<T>>())
            .and_then(|b| b.downcast::<Vec<T>>().ok())
            .map(|b| {
                let mut v = *b;
                v.clear();
                v
            })
            .unwrap_or_default()
    }

    /// Keep `array` for the next [`Self::take`] of its element type.
    pub fn keep<T: Send + Sync + 'static>(&mut self, array: Vec<T>) {
        self.arrays.insert(TypeId::of::<Vec<T>>(), Box::new(array));
    }

    /// How many arrays are kept.
    pub fn arrays(&self) -> usize {
        self.arrays.len()
    }
}

/// A clone (a rolled-back copy, a saved system) starts with nothing kept: the store is
/// memory, not state.
impl Clone for Scratch {
    fn clone(&self) -> Self {
        Self::default()
    }
}

impl std::fmt::Debug for Scratch {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        write!(f, "Scratch({} arrays)", self.arrays.len())
    }
}

#[cfg(test)]
mod tests {
    use super::Scratch;

    #[test]
    fn an_array_comes_back_empty_with_its_capacity_and_only_for_its_type() {
        let mut s = Scratch::default();
        let mut v: Vec<f64> = s.take();
        assert!(v.is_empty());
        v.extend([1.0, 2.0, 3.0]);
        let (cap, ptr) = (v.capacity(), v.as_ptr());
        s.keep(v);
        // another element type gets its own array
        let w: Vec<u32> = s.take();
        assert_eq!(w.capacity(), 0);
        let v: Vec<f64> = s.take();
        assert!(v.is_empty());
        assert_eq!((v.capacity(), v.as_ptr()), (cap, ptr));
        // taken out, it is no longer kept
        let again: Vec<f64> = s.take();
        assert_eq!(again.capacity(), 0);
        s.keep(v);
        assert_eq!(s.clone().arrays(), 0);
        assert_eq!(s.arrays(), 1);
    }
}
