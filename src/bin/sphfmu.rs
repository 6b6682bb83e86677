//! `sphfmu` command line: run and check case files, benchmark the solver.

use clap::{Parser, Subcommand};
use indicatif::{ProgressBar, ProgressStyle};
use sphfmu::case::Case;
use sphfmu::runner::{run_case, Progress, RunError};
use std::path::PathBuf;
use std::process::ExitCode;

const RUN_HELP: &str = "\
Schemes and presets (scheme.name):
  standard      traditional grad-h SPH, Monaghan-Gingold viscosity (alpha, beta), Balsara
                switch, optional artificial conductivity
  rpsph         relative-pressure SPH (Abel 2011): gradient = own-h | symmetric, shock_switch
  rosswog-f1    Rosswog 2015 F1: IA gradients, X = P^k (k = 0.05), triggered dissipation,
                Wendland C6 eta = 2.2, SSP-RK3, CFL 0.5
  rosswog-f2    as F1 with kernel gradients and grad-h terms
  rosswog-f3    as F1 with X = m
  rosswog-f4    kernel gradients, X = m, constant K = 1, M4 eta = 1.2 ('standard SPH')
  Rosswog keys override a preset: volume (one|mass|pressure), k, gradient
  (kernel|integral-approximation), triggers, k_constant, k_max, n_noise, chi, k_min,
  signal_velocity (galilean|literal).
Kernels (kernel.name): cubic-spline, quartic-spline, quintic-spline, septic-spline,
  wendland-c2, wendland-c4, wendland-c6, sinc (kernel.sinc_n = 3..9), liq, qcm6.
Integrators (time.integrator): leapfrog, ssp-rk3, crk-rk2.
Exit codes: 0 done, 2 bad case file, 3 unstable run (snapshots so far kept), 4 I/O error.";

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
    #[command(after_help = RUN_HELP)]
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
        /// crksph, compsph, compsph-cullen, psph), with the preset's kernel and integrator
        #[arg(long)]
        scheme: Option<String>,
    },
    /// Validate a case file without running it.
    Check {
        case: PathBuf,
        /// Also generate the particles and evaluate the initial state.
        #[arg(long)]
        build: bool,
    },
    /// Kernel table: normalisations, η, neighbours, and the lattice quality indicators Q1–Q4
    /// and the standard-gradient error on a periodic 2D hexagonal lattice (Rosswog §2, §3.6).
    Kernels,
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
        /// Kernel name
        #[arg(long, default_value = "cubic-spline")]
        kernel: String,
        #[arg(long)]
        threads: Option<usize>,
        /// Write the table as JSON too
        #[arg(long)]
        json: Option<PathBuf>,
    },
    /// Serve a case over zenoh (step, get, set, save_state, restore_state, snapshot): runs
    /// `sphfmu-serve` from the same folder (built with the FMU crate, which has zenoh; the
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
    match std::process::Command::new(&node).args(args).status() {
        Ok(s) => ExitCode::from(s.code().unwrap_or(1).clamp(0, 255) as u8),
        Err(e) => fail(1, format!("serve: cannot run {}: {e}", node.display())),
    }
}

fn fail(code: u8, msg: impl std::fmt::Display) -> ExitCode {
    eprintln!("sphfmu: {msg}");
    ExitCode::from(code)
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
    let cli = match Cli::try_parse() {
        Ok(c) => c,
        Err(e) => {
            let code = if e.use_stderr() { 2 } else { 0 };
            let _ = e.print();
            return ExitCode::from(code);
        }
    };
    match cli.command {
        Command::Serve { args } => serve(&args),
        Command::Kernels => {
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
        Command::Check { case, build } => match Case::load(&case) {
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
                    println!("{}: ok", case.display());
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
        } => {
            if let Err(e) = set_threads(threads) {
                return fail(2, e);
            }
            let c = match Case::load(&case) {
                Ok(c) => c,
                Err(e) => return fail(2, e),
            };
            let c = match scheme.map(|s| c.with_scheme(&s)).unwrap_or(Ok(c)) {
                Ok(c) => c,
                Err(e) => return fail(2, e),
            };
            let bar = if quiet {
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
            let res = run_case(&c, &out, &mut on);
            bar.finish_and_clear();
            match res {
                Ok(s) => {
                    println!(
                        "{}: {} particles, {} steps to t = {:.6}, {:.2} s, {:.3e} particle-updates/s",
                        s.case, s.particles, s.steps, s.time, s.wall_seconds, s.particle_updates_per_second
                    );
                    let ph = s.phase_seconds;
                    println!(
                        "time per phase: neighbours {:.2} s ({} list builds: {:.2} s), density/h {:.2} s ({:.2} iterations), gradients {:.2} s, forces {:.2} s",
                        ph[0], s.neighbour_list_builds, s.list_build_seconds, ph[1], s.mean_h_iterations, ph[2], ph[3]
                    );
                    println!(
                        "momentum change |P(t) - P(0)| / max Σ m|v|: {:.3e} (walls and gravity included; periodic boxes: the scheme's drift)",
                        s.momentum_drift
                    );
                    if s.ia_fallbacks > 0 {
                        println!("IA gradient fell back to the kernel gradient {} times (near-singular τ)", s.ia_fallbacks);
                    }
                    let (e0, e1) = (s.initial.total_energy, s.last.total_energy);
                    // kinetic + internal (no potential energy of gravity): a liquid at rest
                    // starts at 0, where a relative change means nothing
                    if e0 != 0.0 {
                        println!(
                            "total energy {e0:.12e} -> {e1:.12e} (relative change {:.3e})",
                            (e1 - e0) / e0.abs()
                        );
                    } else {
                        println!("total energy (kinetic + internal) {e0:.12e} -> {e1:.12e}");
                    }
                    if let Some(e) = s.shock_tube {
                        println!(
                            "L1 against the exact Riemann solution: rho {:.4e}, v {:.4e}, P {:.4e} ({} particles)",
                            e.l1_density, e.l1_velocity, e.l1_pressure, e.particles
                        );
                    }
                    if let Some(l1) = s.vortex_l1 {
                        println!("L1(v) against the stationary Gresho vortex: {l1:.4e}");
                    }
                    for b in &s.bodies {
                        println!(
                            "body {:?}: force [{:.6e}, {:.6e}, {:.6e}], torque [{:.6e}, {:.6e}, {:.6e}]",
                            b.name, b.force[0], b.force[1], b.force[2], b.torque[0], b.torque[1], b.torque[2]
                        );
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
            kernel,
            threads,
            json,
        } => {
            if let Err(e) = set_threads(threads) {
                return fail(2, e);
            }
            match sphfmu::bench::run_table(&sizes, &dims, steps, &kernel) {
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
