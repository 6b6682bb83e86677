//! How a loop over the particles splits across the instance's rayon pool.
//!
//! Rayon splits an indexed loop down to single elements when threads are idle. For a few
//! arithmetic operations per particle that hands out tasks of a few nanoseconds, each handed
//! over to (and perhaps waking) another worker. A minimum length keeps a small loop on the
//! calling thread and still gives a 1e6-particle loop hundreds of tasks. Pair loops (tens of
//! neighbours per particle) split finer (see `System::gather_with`). Measured on the closed
//! tank (`sphfmu run models/closed-tank2d.toml --threads 2`, BENCHMARKS.md): on its own this
//! left the wall time as it was (5.80 s both ways); what the second thread lost there was its
//! wake-ups, see [`with_partner_awake`]. Results never depend on these lengths: every element
//! is written by itself, and the reductions split this way (min, max, any) do not depend on
//! the order of their terms.

/// Minimum elements per task for an elementwise update of a few arithmetic operations
/// (integrator stages, h prediction, packing a particle's record).
pub const LIGHT: usize = 4096;

/// Minimum elements per task for an elementwise loop with a transcendental function per
/// element (an equation of state's `powf`, an entropy): an estimate of ten times a light
/// element's cost, not a measurement.
pub const MEDIUM: usize = 512;

/// Elements per block of [`block_reduce`]. Fixed, so the grouping of a sum's terms depends
/// on the element count only.
pub const BLOCK: usize = 1024;

/// Reduce `0..n` in blocks of [`BLOCK`] elements: `block(range)` gives each block's partial
/// result (blocks in parallel), and `combine` joins the partials in block order on the
/// calling thread. The result is the same bits on any number of threads, which rayon's own
/// `reduce` (whose splits follow the work stealing) does not promise for floating-point sums.
/// Why: the per-step totals (diagnostics, the momentum scale, the finite check) were serial
/// loops, 3 % of a one-thread Noh 2D run that a second thread did not share (BENCHMARKS.md).
pub fn block_reduce<T: Send>(
    n: usize,
    block: impl Fn(std::ops::Range<usize>) -> T + Sync,
    combine: impl FnMut(T, T) -> T,
    empty: T,
) -> T {
    use rayon::prelude::*;
    let parts: Vec<T> = (0..n.div_ceil(BLOCK))
        .into_par_iter()
        .map(|b| block(b * BLOCK..((b + 1) * BLOCK).min(n)))
        .collect();
    parts.into_iter().fold(empty, combine)
}

thread_local! {
    /// Whether this thread is inside [`with_partner_awake`]'s step.
    static STEPPING: std::cell::Cell<bool> = const { std::cell::Cell::new(false) };
}

/// Run `f` (one time step) with the pool's second thread kept awake: it spins for work
/// through `rayon::yield_now` (which steals and runs pending jobs) until `f` returns.
///
/// Why: a rayon worker that finds no work for about thirty yields goes to sleep on a futex,
/// and the next parallel loop has to wake it. A step has several serial stretches (the
/// integrator's light loops, the list's join, the checks), so on small cases the second
/// thread slept and woke about five times a step (76,000 context switches in the
/// closed tank's 7,728 steps). Kept awake, it made 22,000 and the run took 5.3 s instead of
/// 5.8 s (BENCHMARKS.md). Spinning costs the second core nothing it would otherwise use
/// during a step, and it yields to the OS between polls. `Simulation` does not use it in a
/// distributed run, whose ranks may share cores.
///
/// Only for a pool of exactly two threads: there the spinner is the oldest job in the
/// calling thread's deque, so the other worker's first steal is the spinner itself and it
/// can never end up spinning on top of a job that the caller waits for (which would
/// deadlock). If the caller pops the spinner itself (waiting inside a join with nothing
/// else queued), the spinner sees it runs on the caller's thread and returns at once. With
/// more threads a worker could steal a real job first and then, while that job waits,
/// take a spinner; so larger pools keep rayon's own sleep. Two steps sharing one pool (two
/// simulations stepped from a parallel loop) could each pick up the other's spinner while
/// waiting inside their own step, and wait for each other; so a spinner that lands on a
/// thread which is inside a step of its own returns at once. The flag is set by a drop
/// guard, so a panic in `f` still ends the spinner (no hang).
pub fn with_partner_awake<R>(f: impl FnOnce() -> R) -> R {
    use std::sync::atomic::{AtomicBool, Ordering};
    let Some(me) = rayon::current_thread_index() else {
        return f();
    };
    if rayon::current_num_threads() != 2 || STEPPING.with(|s| s.get()) {
        return f();
    }
    struct Done<'a>(&'a AtomicBool, bool);
    impl Drop for Done<'_> {
        fn drop(&mut self) {
            self.0.store(true, Ordering::Release);
            STEPPING.with(|s| s.set(self.1));
        }
    }
    let done = AtomicBool::new(false);
    rayon::in_place_scope(|s| {
        let done = &done;
        s.spawn(move |_| {
            if rayon::current_thread_index() == Some(me) || STEPPING.with(|s| s.get()) {
                return;
            }
            let mut idle = 0u32;
            while !done.load(Ordering::Acquire) {
                match rayon::yield_now() {
                    Some(rayon::Yield::Executed) => idle = 0,
                    Some(rayon::Yield::Idle) => {
                        idle += 1;
                        if idle % 64 == 0 {
                            std::thread::yield_now();
                        } else {
                            std::hint::spin_loop();
                        }
                    }
                    None => return,
                }
            }
        });
        let _done = Done(done, STEPPING.with(|s| s.replace(true)));
        f()
    })
}

#[cfg(test)]
mod tests {
    use super::*;
    use rayon::prelude::*;

    fn pool(n: usize) -> rayon::ThreadPool {
        rayon::ThreadPoolBuilder::new()
            .num_threads(n)
            .build()
            .unwrap()
    }

    /// A "step": parallel loops with serial stretches between them.
    fn step(seed: u64) -> u64 {
        let mut x: Vec<u64> = (0..5000).map(|i| i ^ seed).collect();
        for _ in 0..4 {
            x.par_iter_mut()
                .for_each(|v| *v = v.wrapping_mul(6364136223846793005) + 1);
            x[0] = x.iter().fold(0, |a, b| a ^ b);
        }
        x.iter().fold(0, |a, b| a.wrapping_add(*b))
    }

    #[test]
    fn block_sums_are_the_same_bits_on_any_pool() {
        // terms of very different size, so the grouping shows in the last bits
        let x: Vec<f64> = (0..5000)
            .map(|i| 1.0 / (1.0 + i as f64).powi(3) + 1e3 * (i % 7) as f64)
            .collect();
        let sum = || block_reduce(x.len(), |r| x[r].iter().sum::<f64>(), |a, b| a + b, 0.0);
        let expected: f64 = x.chunks(BLOCK).map(|c| c.iter().sum::<f64>()).sum();
        for n in 1..=3 {
            assert_eq!(pool(n).install(sum).to_bits(), expected.to_bits());
        }
        assert_eq!(
            block_reduce(0, |_| 1.0, |a, b| a + b, 0.0),
            0.0,
            "no blocks: the empty value"
        );
    }

    #[test]
    fn gives_the_same_answer_on_any_pool() {
        let expected = step(7);
        for n in 1..=3 {
            assert_eq!(pool(n).install(|| with_partner_awake(|| step(7))), expected);
        }
        assert_eq!(with_partner_awake(|| step(7)), expected, "outside any pool");
    }

    #[test]
    fn steps_sharing_a_pool_do_not_wait_for_each_other() {
        // several simulations stepped from one parallel loop on a two-thread pool, where a
        // step waiting inside a join may meet another step's spinner (the case the STEPPING
        // flag guards; this loop did not hang without the flag either, in 3 runs of 400
        // steps each, so it checks the answers and that nothing hangs, not the race)
        let p = pool(2);
        let sums: Vec<u64> = p.install(|| {
            (0..16u64)
                .into_par_iter()
                .map(|s| (0..20).map(|_| with_partner_awake(|| step(s))).sum::<u64>())
                .collect()
        });
        let expected: Vec<u64> = (0..16u64).map(|s| 20 * step(s)).collect();
        assert_eq!(sums, expected);
    }

    #[test]
    fn a_panicking_step_ends_its_spinner() {
        let p = pool(2);
        let caught = p.install(|| {
            std::panic::catch_unwind(|| with_partner_awake(|| -> u64 { panic!("in the step") }))
        });
        assert!(caught.is_err());
        // the pool still works, so the spinner did not keep the other thread
        assert_eq!(p.install(|| with_partner_awake(|| step(3))), step(3));
    }
}
