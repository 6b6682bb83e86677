//! `sphfmu` command line: run and check case files, benchmark the solver.

use clap::{Parser, Subcommand};
use indicatif::{ProgressBar, ProgressStyle};
use sphfmu::case::Case;
use sphfmu::runner::{run_case_on, Progress, RunError};
use std::path::PathBuf;
use std::process::ExitCode;

/// `sphfmu run --help`'s epilogue, written from the library's own lists (the scheme presets,
/// the kernels with their default η, the integrators), so it names every one of them.
fn run_help() -> String {
    use sphfmu::kernel::{AnyKernel, Kernel, KernelName};
    use sphfmu::scheme::{SchemeConfig, PRESETS};
    let mut o = String::from(
        "Schemes and presets (scheme.name, or --scheme; each with its own kernel, eta, integrator and CFL\n\
         unless the case sets [kernel] and [time]):\n",
    );
    for (name, what) in PRESETS {
        let defaults = toml::from_str::<SchemeConfig>(&format!("name = {name:?}"))
            .map(|c| {
                let (k, eta) = c.preferred_kernel();
                let kernel = KernelName::ALL
                    .iter()
                    .find(|e| e.0 == k)
                    .map_or("?", |e| e.1);
                let eta = eta.unwrap_or_else(|| {
                    AnyKernel::from_name(k, 5).map_or(f64::NAN, |k| k.default_eta())
                });
                let (integrator, cfl) = c.preferred_integrator();
                format!("{kernel} eta {eta}, {}, CFL {cfl}", integrator.name())
            })
            .unwrap_or_default();
        o.push_str(&format!("  {name:<15}{what}\n  {:<15}[{defaults}]\n", ""));
    }
    o.push_str(
        "  Rosswog keys override a preset: volume (one|mass|pressure), k, gradient\n\
         \x20 (kernel|integral-approximation), triggers, k_constant, k_max, n_noise, chi, k_min,\n\
         \x20 signal_velocity (galilean|literal).\n\
         Kernels (kernel.name; all with support 2h, h = eta (m/rho)^(1/D); eta = the kernel's default):\n",
    );
    for (k, name, what) in KernelName::ALL {
        let eta = AnyKernel::from_name(k, 5).map_or(f64::NAN, |k| k.default_eta());
        o.push_str(&format!("  {name:<15}eta {eta:<4} {what}\n"));
    }
    o.push_str(
        "Integrators (time.integrator): leapfrog (kick-drift-kick), ssp-rk3 (Shu-Osher), crk-rk2\n\
         \x20 (the CRKSPH paper's one-evaluation RK2).\n\
         Units: SI (m, kg, s, Pa, N) in every label; the liquid and body cases are in SI, the gas\n\
         \x20 test problems (Sod, Noh, Sedov, Gresho) in the papers' dimensionless units. A 2D case\n\
         \x20 is per metre of depth (forces N/m, masses kg/m, energies J/m), a 1D case per m2.\n\
         Exit codes: 0 done, 2 bad case file, 3 unstable run (snapshots so far kept), 4 I/O error.",
    );
    o
}

#[derive(Parser)]
#[command(
    name = "sphfmu",
    version,
    about = "Smoothed-particle hydrodynamics for co-simulation"
)]
struct Cli {
    #[command(subcommand)]
    command: Command,
}

#[derive(Subcommand)]
enum Command {
    /// Run a case: snapshots (VTU, CSV), diagnostics.csv, summary.json, and for cases with a
    /// [verify] table the L1 errors and profile.png against the exact solution.
    Run {
        /// Case file (TOML), e.g. models/sod.toml
        case: PathBuf,
        /// Output directory
        #[arg(long, default_value = "out")]
        out: PathBuf,
        /// No progress bar
        #[arg(long)]
        quiet: bool,
        /// Worker threads (default: all cores)
        #[arg(long)]
        threads: Option<usize>,
        /// Run with this scheme preset instead of the case's (standard, rpsph, rosswog-f1..f4,
        /// rosswog-sr-f1..f4, crksph, compsph, compsph-cullen, psph), with the preset's kernel and
        /// integrator
        #[arg(long)]
        scheme: Option<String>,
        /// Change a key of the case file, e.g. --set time.t_end=0.1 --set 'region.*.spacing=0.005'
        /// (a dotted path; * for every entry of an array of tables; the value in TOML syntax)
        #[arg(long = "set", value_name = "KEY=VALUE")]
        sets: Vec<String>,
    },
    /// Validate a case file without running it: every key, and its size (particles and
    /// memory, estimated without allocating) against the machine and the case's [limits].
    Check {
        case: PathBuf,
        /// With this scheme preset instead of the case's, as for `run`
        #[arg(long)]
        scheme: Option<String>,
        /// Change a key of the case file first, as for `run`
        #[arg(long = "set", value_name = "KEY=VALUE")]
        sets: Vec<String>,
        /// Also generate the particles and evaluate the initial state.
        #[arg(long)]
        build: bool,
    },
    /// Kernel table: normalisations, η, neighbours, and the lattice quality indicators Q1–Q4
    /// and the standard-gradient error on a periodic 2D hexagonal lattice (Rosswog §2, §3.6).
    Kernels {
        /// Instead, the density error Q1 = ε_ρ of every kernel against η, from FROM to TO in
        /// steps of STEP (Rosswog (2015) Fig. 4), e.g. 1.0:3.0:0.02
        #[arg(long, value_name = "FROM:TO:STEP")]
        eta_scan: Option<String>,
    },
    /// Measure particle-updates/s and pair-interactions/s on periodic boxes.
    Bench {
        /// Particle counts
        #[arg(long, value_delimiter = ',', default_values_t = vec![10_000usize, 100_000, 1_000_000])]
        sizes: Vec<usize>,
        /// Dimensions
        #[arg(long, value_delimiter = ',', default_values_t = vec![2usize, 3])]
        dims: Vec<usize>,
        /// Steps per measurement
        #[arg(long, default_value_t = 5)]
        steps: u64,
        /// At least this many particle-updates per measurement: a size of N particles times
        /// the same `--steps` steps ⌈U/(N·steps)⌉ times over, each time from a fresh box, so a
        /// small box is timed over as long as a large one and over the same stretch of the run
        /// (five steps of 1e4 particles last a few hundredths of a second)
        #[arg(long, value_name = "U", default_value_t = 0)]
        min_updates: u64,
        /// Kernel name
        #[arg(long, default_value = "cubic-spline")]
        kernel: String,
        #[arg(long)]
        threads: Option<usize>,
        /// Write the table as JSON too
        #[arg(long)]
        json: Option<PathBuf>,
        /// Instead: time saving and restoring a whole solver state (an FMU state) of each
        /// size, and the CRC-32 and checks that guard it
        #[arg(long)]
        state: bool,
    },
    /// Serve a case over zenoh (step, get, set, save_state, restore_state, reset, snapshot):
    /// runs `sphfmu-serve` from the same folder in this process's place (built with the FMU crate, which has zenoh; the
    /// core library does not). `sphfmu serve --help` lists its options.
    #[command(disable_help_flag = true)]
    Serve {
        #[arg(trailing_var_arg = true, allow_hyphen_values = true)]
        args: Vec<String>,
    },
}

/// `sphfmu serve ...`: hand over to `sphfmu-serve` next to this binary (as git does with
/// `git-<name>`), so the core CLI needs no zenoh.
fn serve(args: &[String]) -> ExitCode {
    let node = std::env::current_exe()
        .ok()
        .map(|p| p.with_file_name("sphfmu-serve"))
        .filter(|p| p.exists());
    let Some(node) = node else {
        return fail(
            1,
            "serve: sphfmu-serve is not next to sphfmu; build it with `cargo build --release --workspace` (or `make fmu`)",
        );
    };
    // exec: the node replaces this process (same pid), so SIGTERM, SIGINT, SIGHUP or SIGKILL
    // to `sphfmu serve` reach the node itself and no orphan child keeps its port
    #[cfg(unix)]
    {
        use std::os::unix::process::CommandExt;
        let e = std::process::Command::new(&node).args(args).exec();
        fail(1, format!("serve: cannot run {}: {e}", node.display()))
    }
    #[cfg(not(unix))]
    match std::process::Command::new(&node).args(args).status() {
        Ok(s) => ExitCode::from(s.code().unwrap_or(1).clamp(0, 255) as u8),
        Err(e) => fail(1, format!("serve: cannot run {}: {e}", node.display())),
    }
}

/// The run summary's momentum and energy lines, each saying what it measures: a conservation
/// error only where nothing outside the fluid acts on it.
fn print_balances(s: &sphfmu::runner::RunSummary) {
    use sphfmu::runner::MomentumCheck;
    let u = sphfmu::units::units(s.dimension);
    let v = |a: &[f64; 3]| {
        let a = &a[..s.dimension];
        let parts: Vec<String> = a.iter().map(|x| format!("{x:.4e}")).collect();
        format!("[{}] {}", parts.join(", "), u.momentum)
    };
    let residual = s.momentum_residual.unwrap_or(f64::NAN);
    match s.momentum_check {
        MomentumCheck::Conservation => println!(
            "momentum conservation: |P(t) - P(0)| = {residual:.3e} of max Σ m|v| (nothing outside the fluid acts on it: the scheme's own error)"
        ),
        MomentumCheck::Balance => println!(
            "momentum balance: change {} = gravity impulse {} + wall impulse {}; residual {residual:.3e} of the largest impulse (the scheme's own error)",
            v(&s.momentum_change), v(&s.gravity_impulse), v(&s.wall_impulse)
        ),
        MomentumCheck::Boundaries => println!(
            "momentum change {}: the impulse of the domain's mirror walls, frozen layers, ports or frame on the fluid (physical, not a conservation error; no balance is computed for these boundaries)",
            v(&s.momentum_change)
        ),
    }
    let (d0, d1) = (&s.initial, &s.last);
    let with_gravity = d0.potential_energy != 0.0 || d1.potential_energy != 0.0;
    let what = if with_gravity {
        "kinetic + internal + potential in gravity"
    } else if s.relativistic.is_some() {
        "Σ ν (ε − 1), c = 1"
    } else {
        "kinetic + internal"
    };
    let (e0, e1) = (d0.total_energy, d1.total_energy);
    let change = if e0 != 0.0 {
        format!(" (relative change {:.3e})", (e1 - e0) / e0.abs())
    } else {
        String::new()
    };
    println!(
        "total energy ({what}) {e0:.9e} -> {e1:.9e} {}{change}",
        u.energy
    );
    if let Some(r) = &s.relativistic {
        println!(
            "special relativity: largest Lorentz factor {:.4}; {} primitive recoveries, {:.2} Newton-Raphson iterations on average, {} at most, {} fell back to the cold state; the light-cone margin shortened {} steps",
            r.max_lorentz, r.recoveries, r.mean_iterations, r.max_iterations, r.fallbacks, r.light_cone_steps
        );
    }
    if with_gravity {
        println!(
            "  kinetic {:.4e} -> {:.4e}, internal {:.4e} -> {:.4e}, potential {:.4e} -> {:.4e} {}",
            d0.kinetic_energy,
            d1.kinetic_energy,
            d0.internal_energy,
            d1.internal_energy,
            d0.potential_energy,
            d1.potential_energy,
            u.energy,
        );
    }
}

fn fail(code: u8, msg: impl std::fmt::Display) -> ExitCode {
    eprintln!("sphfmu: {msg}");
    ExitCode::from(code)
}

/// The pool a CLI run steps in: `--threads` workers, else one per core.
fn threads_pool(threads: Option<usize>) -> Result<rayon::ThreadPool, String> {
    let mut b = rayon::ThreadPoolBuilder::new();
    if let Some(n) = threads {
        b = b.num_threads(n);
    }
    b.build()
        .map_err(|e| format!("--threads: cannot start the workers ({e})"))
}

fn set_threads(threads: Option<usize>) -> Result<(), String> {
    if let Some(n) = threads {
        if n == 0 {
            return Err("--threads: must be ≥ 1".into());
        }
        rayon::ThreadPoolBuilder::new()
            .num_threads(n)
            .build_global()
            .map_err(|e| e.to_string())?;
    }
    Ok(())
}

fn main() -> ExitCode {
    use clap::{CommandFactory, FromArgMatches};
    let command = Cli::command().mut_subcommand("run", |c| c.after_help(run_help()));
    let cli = match command
        .try_get_matches()
        .and_then(|m| Cli::from_arg_matches(&m))
    {
        Ok(c) => c,
        Err(e) => {
            let code = if e.use_stderr() { 2 } else { 0 };
            let _ = e.print();
            return ExitCode::from(code);
        }
    };
    match cli.command {
        Command::Serve { args } => serve(&args),
        Command::Kernels {
            eta_scan: Some(spec),
        } => match sphfmu::verify::lattice::eta_grid(&spec) {
            Ok(etas) => {
                print!("{}", sphfmu::verify::lattice::eta_scan_table(&etas));
                ExitCode::SUCCESS
            }
            Err(e) => fail(2, e),
        },
        Command::Kernels { eta_scan: None } => {
            use sphfmu::kernel::{neighbours_for_eta, AnyKernel, Kernel};
            println!("| kernel | σ 1D | σ 2D | σ 3D | η | neighbours 2D | 3D | Q1 = ε_ρ | Q2/r_s | Q3·r_s | Q4 | ∇x error |");
            println!("|---|---|---|---|---|---|---|---|---|---|---|---|");
            for k in AnyKernel::all() {
                let eta = k.default_eta();
                let q = sphfmu::verify::lattice::hex_quality(k, eta);
                println!(
                    "| {} | {:.6} | {:.6} | {:.6} | {eta} | {:.0} | {:.0} | {:.2e} | {:.1e} | {:.1e} | {:.2e} | {:.2e} |",
                    q.kernel, k.sigma(1), k.sigma(2), k.sigma(3), neighbours_for_eta(eta, 2), neighbours_for_eta(eta, 3),
                    q.q1, q.q2, q.q3, q.q4, q.gradient_error
                );
            }
            ExitCode::SUCCESS
        }
        Command::Check {
            case,
            scheme,
            sets,
            build,
        } => match Case::load_with(&case, scheme.as_deref(), &sets) {
            Ok(c) => {
                if build {
                    let r = match c.dimension() {
                        1 => c.build::<1>().map(|s| s.sys.particles.len()),
                        2 => c.build::<2>().map(|s| s.sys.particles.len()),
                        _ => c.build::<3>().map(|s| s.sys.particles.len()),
                    };
                    match r {
                        Ok(n) => {
                            println!("{}: ok ({}D, {n} particles)", case.display(), c.dimension())
                        }
                        Err(e) => return fail(2, format!("{}: {e}", case.display())),
                    }
                } else {
                    // the size checks of a build, without allocating
                    match c.check_resources(&c.limits) {
                        Ok(e) => println!(
                            "{}: ok (about {:.0} particles, {:.2} GB)",
                            case.display(),
                            e.particles,
                            e.bytes / 1e9
                        ),
                        Err(e) => return fail(2, format!("{}: {e}", case.display())),
                    }
                }
                ExitCode::SUCCESS
            }
            Err(e) => fail(2, e),
        },
        Command::Run {
            case,
            out,
            quiet,
            threads,
            scheme,
            sets,
        } => {
            let ranks = match sphfmu::parallel::launched() {
                Ok(r) => r,
                Err(e) => return fail(2, format!("run: {e}")),
            };
            let threads = threads.or(ranks.as_ref().and(sphfmu::parallel::threads_per_rank()));
            if let Err(e) = set_threads(threads) {
                return fail(2, e);
            }
            let c = match Case::load_with(&case, scheme.as_deref(), &sets) {
                Ok(c) => c,
                Err(e) => return fail(2, e),
            };
            // under mpirun, rank 0 alone draws and prints
            let root = ranks.as_ref().is_none_or(|r| r.rank() == 0);
            let bar = if quiet || !root {
                ProgressBar::hidden()
            } else {
                ProgressBar::new(1000)
            };
            bar.set_style(
                ProgressStyle::with_template(
                    "{bar:30} t={msg} [{elapsed_precise} < {eta_precise}]",
                )
                .unwrap_or_else(|_| ProgressStyle::default_bar()),
            );
            let mut last_draw = std::time::Instant::now();
            let mut on = |p: &Progress| {
                if last_draw.elapsed().as_millis() < 100 && p.time < p.t_end {
                    return;
                }
                last_draw = std::time::Instant::now();
                bar.set_position((1000.0 * p.time / p.t_end) as u64);
                bar.set_message(format!(
                    "{:.4e}/{:.4e} step {} dt {:.3e} N {} {:.3e} particles/s",
                    p.time, p.t_end, p.step, p.dt, p.particles, p.rate
                ));
            };
            // the time loop runs inside the pool, as the FMU's does: driven from the main thread,
            // every parallel pass paid the hand-over into the pool (issue 19 measured the
            // closed tank 19.1 s -> 14.1 s and Noh 15.8 s -> 13.6 s this way)
            let res = match threads_pool(threads) {
                Ok(pool) => pool.install(|| run_case_on(&c, &out, &mut on, ranks)),
                Err(e) => return fail(2, e),
            };
            bar.finish_and_clear();
            match res {
                Ok(_) if !root => ExitCode::SUCCESS,
                Ok(s) => {
                    if let Some(x) = &s.exchange {
                        println!(
                            "{} ranks: rank 0 sent {:.3e} bytes in {} messages, {:.2} s in exchanges, {} halo copies, {} particles migrated, {} rebalances",
                            s.ranks, x.bytes_sent as f64, x.messages, x.seconds, x.halo_particles, x.migrated, x.rebalances
                        );
                    }
                    println!(
                        "{}: {} particles, {} steps to t = {:.6} s, {:.2} s wall clock, {:.3e} particle-updates/s",
                        s.case, s.particles, s.steps, s.time, s.wall_seconds, s.particle_updates_per_second
                    );
                    let ph = s.phase_seconds;
                    println!(
                        "time per phase: neighbours {:.2} s ({} list builds in {:.2} s, {} of them for growing h; working-list cuts {:.2} s), density/h {:.2} s ({:.2} iterations), gradients {:.2} s, forces {:.2} s",
                        ph[0], s.neighbour_list_builds, s.list_build_seconds, s.h_growth_rebuilds, s.cut_seconds, ph[1], s.mean_h_iterations, ph[2], ph[3]
                    );
                    print_balances(&s);
                    if let Some(e) = s.shock_tube {
                        println!(
                            "L1 against the exact Riemann solution: rho {:.4e}, v {:.4e}, P {:.4e} ({} particles)",
                            e.l1_density, e.l1_velocity, e.l1_pressure, e.particles
                        );
                    }
                    if let Some(l1) = s.vortex_l1 {
                        println!("L1(v) against the stationary Gresho vortex: {l1:.4e}");
                    }
                    let u = sphfmu::units::units(s.dimension);
                    for b in &s.bodies {
                        println!(
                            "body {:?}: force [{:.6e}, {:.6e}, {:.6e}] {}, torque [{:.6e}, {:.6e}, {:.6e}] {}",
                            b.name, b.force[0], b.force[1], b.force[2], u.force, b.torque[0], b.torque[1], b.torque[2], u.torque
                        );
                    }
                    if s.dimension == 2 && !s.bodies.is_empty() {
                        println!("(2D: loads, masses and energies are per metre of depth)");
                    }
                    if let Some(r) = s.radial {
                        println!(
                            "against the exact solution: shock at r = {:.4} (exact {:.4}), post-shock density {:.3} (exact {:.3}), L1(rho) {:.4e} ({} particles)",
                            r.shock_radius, r.shock_radius_exact, r.post_shock_density,
                            r.post_shock_density_exact, r.l1_density, r.particles
                        );
                    }
                    if let Some(p) = s.plot {
                        println!("profile plot: {}", p.display());
                    }
                    println!("output: {}", out.display());
                    ExitCode::SUCCESS
                }
                Err(e) => {
                    let code = e.exit_code() as u8;
                    let msg = match &e {
                        RunError::Solver(_) => {
                            format!("{e} (snapshots so far kept in {})", out.display())
                        }
                        _ => e.to_string(),
                    };
                    fail(code, msg)
                }
            }
        }
        Command::Bench {
            sizes,
            dims,
            steps,
            min_updates,
            kernel,
            threads,
            json,
            state,
        } => {
            let ranks = match sphfmu::parallel::launched() {
                Ok(r) => r,
                Err(e) => return fail(2, format!("bench: {e}")),
            };
            let threads = threads.or(ranks.as_ref().and(sphfmu::parallel::threads_per_rank()));
            let root = ranks.as_ref().is_none_or(|r| r.rank() == 0);
            if let Err(e) = set_threads(threads) {
                return fail(2, e);
            }
            if state {
                println!("| dim | particles | state bytes | save | restore (CRC and checks included) | CRC-32 alone |");
                println!("|---|---|---|---|---|---|");
                for &d in &dims {
                    for &n in &sizes {
                        match sphfmu::bench::state_cost(d, n, 9) {
                            Ok(r) => {
                                println!(
                                "| {}D | {} | {} | {:.2} ms | {:.2} ms | {:.2} ms ({:.1} GB/s) |",
                                r.dimension, r.particles, r.bytes, 1e3 * r.save, 1e3 * r.restore,
                                1e3 * r.crc32, r.bytes as f64 / r.crc32 / 1e9
                            )
                            }
                            Err(e) => return fail(2, e),
                        }
                    }
                }
                return ExitCode::SUCCESS;
            }
            match sphfmu::bench::run_table(&sizes, &dims, (steps, min_updates), &kernel, ranks) {
                Ok(_) if !root => ExitCode::SUCCESS,
                Ok(rows) => {
                    println!("{}", sphfmu::bench::format_table(&rows));
                    if let Some(p) = json {
                        if let Err(e) = std::fs::write(
                            &p,
                            serde_json::to_string_pretty(&rows).unwrap_or_default(),
                        ) {
                            return fail(4, format!("{}: {e}", p.display()));
                        }
                    }
                    ExitCode::SUCCESS
                }
                Err(e) => fail(2, e),
            }
        }
    }
}
