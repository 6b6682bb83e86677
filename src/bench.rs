//! Throughput benchmark: standard SPH on periodic boxes (a perturbed cubic lattice at rest
//! with small random velocities), timed over whole steps (neighbour search, h iteration,
//! gradients, forces, integration).

use crate::case::Case;
use crate::parallel::comm::Comm;
use serde::Serialize;
use std::sync::Arc;
use std::time::Instant;

#[derive(Debug, Clone, Serialize)]
pub struct BenchRow {
    pub dimension: usize,
    pub particles: usize,
    pub kernel: String,
    pub neighbours: f64,
    /// Timed steps per repeat, and repeats (each a fresh box timed over the same steps).
    pub steps: u64,
    pub repeats: u64,
    pub seconds: f64,
    pub threads: usize,
    pub particle_updates_per_second: f64,
    pub force_pairs_per_second: f64,
    pub all_pairs_per_second: f64,
    /// Force-pass pairs per second of force-pass time per thread: the force loop's own rate.
    pub force_loop_pairs_per_second_per_thread: f64,
    /// Share of the step spent on neighbour upkeep (list builds, validity checks, the cut of
    /// the working list with the gradient sums that ride on it).
    pub neighbour_share: f64,
    /// Ranks the box was shared among (1: one process; `mpirun -n R sphfmu bench`).
    pub ranks: usize,
    /// Distributed runs, rank 0's figures: bytes it sent per step, the share of its step time
    /// spent in exchanges (waiting for the other ranks included), and its halo copies
    /// against its own particles.
    pub bytes_per_step: f64,
    pub exchange_share: f64,
    pub halo_per_owned: f64,
}

/// Case text for an N-particle periodic box in dimension d.
pub fn box_case(d: usize, n: usize, kernel: &str) -> String {
    let side = (n as f64).powf(1.0 / d as f64).round().max(4.0);
    let spacing = 1.0 / side;
    let v = |x: f64| format!("[{}]", vec![format!("{x}"); d].join(", "));
    let b = format!("[{}]", vec!["\"periodic\""; d].join(", "));
    format!(
        r#"
[case]
name = "bench-{d}d-{n}"
dimension = {d}
[domain]
min = {min}
max = {max}
boundary = {b}
[eos]
type = "ideal-gas"
gamma = 1.6666666666666667
[kernel]
name = "{kernel}"
[scheme]
name = "standard"
[time]
t_end = 1.0
integrator = "leapfrog"
[[region]]
spacing = {spacing}
density = 1.0
pressure = 1.0
[perturbation]
amplitude = 0.1
seed = 7
"#,
        min = v(0.0),
        max = v(1.0),
    )
}

/// Sums over the timed windows of one size.
#[derive(Default)]
struct Window {
    seconds: f64,
    force_pairs: u64,
    all_pairs: u64,
    neighbours: f64,
    density: f64,
    gradients: f64,
    forces: f64,
    h_iterations: f64,
    h_solves: u64,
    bytes_sent: u64,
    exchange_seconds: f64,
}

/// `steps` timed steps of an N-particle box, `repeats` times over (each a fresh box with one
/// untimed warm-up step, so every repeat times the same steps of the same run).
pub fn run_one<const D: usize>(
    n: usize,
    (steps, repeats): (u64, u64),
    kernel: &str,
    ranks: Option<Arc<dyn Comm>>,
) -> Result<BenchRow, String> {
    let case = Case::parse(&box_case(D, n, kernel)).map_err(|e| e.0)?;
    let repeats = repeats.max(1);
    // a distributed run's exchange counters (ranks, bytes, seconds, halo size)
    let exchanged = |s: &crate::sim::Simulation<D>| s.layout.as_ref().map(|l| l.exchange());
    let mut w = Window::default();
    let mut last = None;
    for _ in 0..repeats {
        let mut sim = match ranks.clone() {
            Some(comm) => case.distributed::<D>(comm).map_err(|e| e.0)?,
            None => case.build::<D>().map_err(|e| e.0)?,
        };
        // warm-up step (allocations, first list build)
        sim.step(f64::INFINITY).map_err(|e| e.to_string())?;
        sim.sys.stats = Default::default();
        let before = exchanged(&sim);
        let t0 = Instant::now();
        for _ in 0..steps {
            sim.sys.stats.total_pairs = 0;
            sim.step(f64::INFINITY).map_err(|e| e.to_string())?;
            w.force_pairs += sim.sys.stats.force_pairs;
            w.all_pairs += sim.sys.stats.total_pairs;
        }
        w.seconds += t0.elapsed().as_secs_f64();
        if let (Some((_, b)), Some((_, a))) = (before, exchanged(&sim)) {
            w.bytes_sent += a.bytes_sent - b.bytes_sent;
            w.exchange_seconds += a.seconds - b.seconds;
        }
        let st = &sim.sys.stats;
        w.neighbours += st.seconds_neighbours;
        w.density += st.seconds_density;
        w.gradients += st.seconds_gradients;
        w.forces += st.seconds_forces;
        w.h_iterations += st.h_iterations_total;
        w.h_solves += st.h_solves;
        last = Some(sim);
    }
    let sim = last.expect("at least one repeat");
    let secs = w.seconds;
    // every particle, on every rank
    let np = sim.diagnostics().particles;
    let timed_steps = steps * repeats;
    eprintln!(
        "{D}D N={}: neighbours {:.2} s, density/h {:.2} s ({:.2} Newton iterations/particle per solve, mean over the timed steps), gradients {:.2} s, forces {:.2} s, total {:.2} s",
        sim.sys.particles.len(), w.neighbours, w.density,
        w.h_iterations / w.h_solves.max(1) as f64, w.gradients, w.forces, secs
    );
    let threads = rayon::current_num_threads();
    let (ranks, bytes, exchange, halo) = match exchanged(&sim) {
        Some((r, a)) => (
            r,
            w.bytes_sent as f64 / timed_steps as f64,
            w.exchange_seconds / secs,
            a.halo_particles as f64 / sim.sys.owned().max(1) as f64,
        ),
        None => (1, 0.0, 0.0, 0.0),
    };
    Ok(BenchRow {
        dimension: D,
        particles: np,
        kernel: sim.sys.kernel.kernel.to_string_name(),
        // this rank's pairs per particle it holds (its halo copies included), last step
        neighbours: sim.sys.stats.force_pairs as f64 / sim.sys.particles.len().max(1) as f64,
        steps,
        repeats,
        seconds: secs,
        threads,
        particle_updates_per_second: np as f64 * timed_steps as f64 / secs,
        force_pairs_per_second: w.force_pairs as f64 / secs,
        all_pairs_per_second: w.all_pairs as f64 / secs,
        force_loop_pairs_per_second_per_thread: w.force_pairs as f64
            / w.forces.max(1e-12)
            / threads as f64,
        neighbour_share: w.neighbours / secs,
        ranks,
        bytes_per_step: bytes,
        exchange_share: exchange,
        halo_per_owned: halo,
    })
}

/// Every size in every dimension; `(steps, min_updates)`: a size of n particles times the same
/// `steps` steps ⌈min_updates/(n·steps)⌉ times over. The perturbed box relaxes over its first
/// ~100 steps (the h solve needs 1.6 Newton iterations per particle in steps 1–10 and 1.05
/// over steps 1–1000 of 10⁴ particles in 2D), so timing more steps of a small box than of a
/// large one would compare different stretches of the run, not the cost of N.
pub fn run_table(
    sizes: &[usize],
    dims: &[usize],
    (at_least, min_updates): (u64, u64),
    kernel: &str,
    ranks: Option<Arc<dyn Comm>>,
) -> Result<Vec<BenchRow>, String> {
    let mut rows = Vec::new();
    for &d in dims {
        for &n in sizes {
            let window = (
                at_least,
                min_updates.div_ceil((n.max(1) as u64) * at_least.max(1)),
            );
            let row = match d {
                1 => run_one::<1>(n, window, kernel, ranks.clone())?,
                2 => run_one::<2>(n, window, kernel, ranks.clone())?,
                3 => run_one::<3>(n, window, kernel, ranks.clone())?,
                _ => return Err(format!("--dims: must be 1, 2 or 3, got {d}")),
            };
            eprintln!(
                "{}D N={} done in {:.2} s",
                row.dimension, row.particles, row.seconds
            );
            rows.push(row);
        }
    }
    Ok(rows)
}

pub fn format_table(rows: &[BenchRow]) -> String {
    let mut s = String::from(
        "| dim | particles | kernel | neighbours | ranks × threads | steps (× repeats) | particle-updates/s | force pairs/s | all pairs/s | force loop pairs/s/thread | neighbour share | bytes sent/step | exchange share | halo/owned |\n|---|---|---|---|---|---|---|---|---|---|---|---|---|---|\n",
    );
    for r in rows {
        s.push_str(&format!(
            "| {}D | {} | {} | {:.1} | {} × {} | {} | {:.3e} | {:.3e} | {:.3e} | {:.3e} | {:.0} % | {:.3e} | {:.0} % | {:.2} |\n",
            r.dimension,
            r.particles,
            r.kernel,
            r.neighbours,
            r.ranks,
            r.threads,
            if r.repeats > 1 { format!("{} × {}", r.steps, r.repeats) } else { r.steps.to_string() },
            r.particle_updates_per_second,
            r.force_pairs_per_second,
            r.all_pairs_per_second,
            r.force_loop_pairs_per_second_per_thread,
            100.0 * r.neighbour_share,
            r.bytes_per_step,
            100.0 * r.exchange_share,
            r.halo_per_owned
        ));
    }
    s
}

/// The cost of saving and restoring a whole solver state (an FMU state), and the share of it
/// the integrity checks take: the CRC-32 over the bytes and the invariant checks of a restore.
#[derive(Debug, Clone, Serialize)]
pub struct StateCost {
    pub dimension: usize,
    pub particles: usize,
    pub bytes: usize,
    /// Median seconds over the repeats.
    pub save: f64,
    pub restore: f64,
    pub crc32: f64,
    pub repeats: usize,
}

/// Save and restore an N-particle periodic box (after one step, so every list is built)
/// `repeats` times; medians.
pub fn state_cost(d: usize, n: usize, repeats: usize) -> Result<StateCost, String> {
    let case = Case::parse(&box_case(d, n, "cubic-spline")).map_err(|e| e.0)?;
    let mut c = crate::coupling::Coupling::new(&case, &Default::default()).map_err(|e| e.0)?;
    c.step_to(1e-4).map_err(|e| e.0)?;
    let particles = c.diagnostics().particles;
    let median = |mut v: Vec<f64>| {
        v.sort_by(f64::total_cmp);
        v[v.len() / 2]
    };
    let time = |f: &mut dyn FnMut()| {
        let t = Instant::now();
        f();
        t.elapsed().as_secs_f64()
    };
    let (mut save, mut restore, mut crc) = (vec![], vec![], vec![]);
    let mut bytes = c.save().map_err(|e| e.0)?;
    for _ in 0..repeats.max(1) {
        let mut saved = Ok(vec![]);
        save.push(time(&mut || saved = c.save()));
        bytes = saved.map_err(|e| e.0)?;
        let mut ok = Ok(());
        restore.push(time(&mut || ok = c.restore(&bytes)));
        ok.map_err(|e| e.0)?;
        let mut h = 0;
        crc.push(time(&mut || h = crc32fast::hash(&bytes)));
        std::hint::black_box(h);
    }
    Ok(StateCost {
        dimension: d,
        particles,
        bytes: bytes.len(),
        save: median(save),
        restore: median(restore),
        crc32: median(crc),
        repeats: repeats.max(1),
    })
}
