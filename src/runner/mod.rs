//! Running a case end to end: snapshots, diagnostics, verification against the exact
//! solution named in the case's `[verify]` table. Shared by the CLI and the tests.

use crate::case::{Case, CaseError, SnapshotFormat};
use crate::io::{self, DiagnosticsWriter};
use crate::parallel::comm::Comm;
use crate::sim::{Simulation, SolverError};
use crate::verify::radial::RadialErrors;
use crate::verify::ShockTubeErrors;
use std::fmt;
use std::path::{Path, PathBuf};
use std::sync::Arc;
use std::time::Instant;

mod checks;
mod loads;
mod ranks;

/// Why a run failed, and the exit code the CLI uses for it.
#[derive(Debug)]
pub enum RunError {
    /// Bad input: exit code 2.
    Case(CaseError),
    /// Instability or solver failure: exit code 3 (snapshots written so far are kept).
    Solver(SolverError),
    /// File-system problem: exit code 4.
    Io(String),
}

impl RunError {
    pub fn exit_code(&self) -> i32 {
        match self {
            RunError::Case(_) => 2,
            RunError::Solver(_) => 3,
            RunError::Io(_) => 4,
        }
    }
}

impl fmt::Display for RunError {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match self {
            RunError::Case(e) => write!(f, "{e}"),
            RunError::Solver(e) => write!(f, "{e}"),
            RunError::Io(e) => write!(f, "{e}"),
        }
    }
}

impl From<CaseError> for RunError {
    fn from(e: CaseError) -> Self {
        RunError::Case(e)
    }
}
impl From<SolverError> for RunError {
    fn from(e: SolverError) -> Self {
        RunError::Solver(e)
    }
}

fn io_err(path: &Path, e: impl fmt::Display) -> RunError {
    RunError::Io(format!("{}: {e}", path.display()))
}

/// Progress facts passed to the caller after every step.
#[derive(Debug, Clone, Copy)]
pub struct Progress {
    pub time: f64,
    pub t_end: f64,
    pub step: u64,
    pub dt: f64,
    pub particles: usize,
    /// particle-updates per second of wall time since the start
    pub rate: f64,
}

/// Load of the fluid on one body.
#[derive(Debug, Clone, serde::Serialize)]
pub struct BodyLoad {
    pub name: String,
    /// Force (x, y, z).
    pub force: Vec<f64>,
    /// Torque about the body's reference point (x, y, z).
    pub torque: Vec<f64>,
    /// Impulse of the fluid on the body since t = 0 (x, y, z).
    pub impulse: Vec<f64>,
}

/// What a finished run reports.
#[derive(Debug, Clone, serde::Serialize)]
pub struct RunSummary {
    pub case: String,
    pub dimension: usize,
    pub particles: usize,
    /// Ranks the run was shared among (1: one process).
    pub ranks: usize,
    /// A distributed run's exchanges (rank 0's counters: bytes and messages it sent, time
    /// in exchanges, halo copies at the end, migrations, rebalances).
    pub exchange: Option<crate::parallel::ExchangeStats>,
    pub steps: u64,
    pub time: f64,
    pub wall_seconds: f64,
    pub particle_updates_per_second: f64,
    pub snapshots: Vec<PathBuf>,
    pub initial: crate::sim::Diagnostics,
    pub last: crate::sim::Diagnostics,
    pub shock_tube: Option<ShockTubeErrors>,
    /// Gresho vortex: L1 of the velocity, Rosswog Eq. 106.
    pub vortex_l1: Option<f64>,
    /// Sedov / Noh: L1(ρ), shock position and post-shock density against the exact solution.
    pub radial: Option<RadialErrors>,
    /// Force and torque of the fluid on each body at the end (latest evaluation).
    pub bodies: Vec<BodyLoad>,
    pub plot: Option<PathBuf>,
    /// Wall-clock seconds per phase: neighbour lists, density/h, gradients, forces.
    pub phase_seconds: [f64; 4],
    /// Mean density evaluations per particle per h solve, and master-list builds.
    pub mean_h_iterations: f64,
    /// IA kernel-gradient fallbacks summed over all evaluations (Rosswog IA formulations).
    pub ia_fallbacks: u64,
    /// |P(t) − P(0)| / max_t Σ m|v|. Walls and gravity change P physically; in a periodic box
    /// without gravity this is the momentum the scheme fails to conserve (rpSPH; round-off for
    /// the conservative schemes).
    pub momentum_drift: f64,
    /// P(t) − P(0) of the fluid (x, y, z).
    pub momentum_change: [f64; 3],
    /// The impulse of gravity on the fluid, Σ_steps M g dt (x, y, z).
    pub gravity_impulse: [f64; 3],
    /// The impulse of the bodies' walls on the fluid, −Σ_bodies (impulse of the fluid on the
    /// body) (x, y, z).
    pub wall_impulse: [f64; 3],
    /// What the momentum check means for this case (see [`MomentumCheck`]).
    pub momentum_check: MomentumCheck,
    /// |ΔP − gravity impulse − wall impulse| / max(max_t Σ m|v|, |gravity impulse|, |wall
    /// impulse|) when those are every external impulse (`MomentumCheck::Conservation` or
    /// `Balance`): the scheme's own error.
    pub momentum_residual: Option<f64>,
    pub list_build_seconds: f64,
    /// Seconds cutting the working list (part of the neighbour phase, with what rides on it).
    #[serde(default)]
    pub cut_seconds: f64,
    pub neighbour_list_builds: u64,
    /// The builds of `neighbour_list_builds` made within an h solve because a smoothing
    /// length outgrew its listed reach (the rest: particles moved through the skin).
    pub h_growth_rebuilds: u64,
    /// Special-relativistic runs: the primitive recoveries (Rosswog (2015) Eqs. 97–99).
    pub relativistic: Option<RecoverySummary>,
}

/// The primitive recoveries of a special-relativistic run and the largest Lorentz factor.
#[derive(Debug, Clone, Copy, serde::Serialize)]
pub struct RecoverySummary {
    /// Particle recoveries over the run (every density pass of every evaluation).
    pub recoveries: u64,
    /// Mean and largest Newton–Raphson iterations per recovery.
    pub mean_iterations: f64,
    pub max_iterations: u64,
    /// Recoveries with no root at u ≥ 0, taken at the cold state (u floored) instead.
    pub fallbacks: u64,
    /// The largest Lorentz factor at the end and over the recorded diagnostics.
    pub max_lorentz: f64,
    /// Steps the light-cone margin shortened below the Courant and force criteria
    /// (`recovery::light_cone_step`).
    pub light_cone_steps: u64,
}

/// Which external impulses act on the fluid, and so what its momentum change means.
#[derive(Debug, Clone, Copy, PartialEq, Eq, serde::Serialize)]
#[serde(rename_all = "kebab-case")]
pub enum MomentumCheck {
    /// No gravity, no bodies, no other boundary: momentum is the scheme's to conserve.
    Conservation,
    /// Gravity and/or bodies only: the change balances their impulses, which are known.
    Balance,
    /// Mirror walls, frozen layers, ports or a moving frame act on the fluid too, and their
    /// impulse is not accumulated: the change is physical, and no balance is computed.
    Boundaries,
}

/// Run `case` writing into `out`. `progress` is called after every step.
pub fn run_case(
    case: &Case,
    out: &Path,
    progress: &mut dyn FnMut(&Progress),
) -> Result<RunSummary, RunError> {
    run_case_on(case, out, progress, None)
}

/// [`run_case`] shared among the ranks of `ranks` (`parallel`), or in this process alone
/// (`None`). Every rank calls it; rank 0 writes the outputs and calls `progress`.
pub fn run_case_on(
    case: &Case,
    out: &Path,
    progress: &mut dyn FnMut(&Progress),
    ranks: Option<Arc<dyn Comm>>,
) -> Result<RunSummary, RunError> {
    std::fs::create_dir_all(out).map_err(|e| io_err(out, e))?;
    match case.dimension() {
        1 => run_dim::<1>(case, out, progress, ranks),
        2 => run_dim::<2>(case, out, progress, ranks),
        _ => run_dim::<3>(case, out, progress, ranks),
    }
}

struct Snapshots {
    dir: PathBuf,
    formats: Vec<SnapshotFormat>,
    written: Vec<(f64, PathBuf)>,
    files: Vec<PathBuf>,
}

impl Snapshots {
    fn write<const D: usize>(
        &mut self,
        sim: &Simulation<D>,
        ranks: Option<&dyn Comm>,
    ) -> Result<(), RunError> {
        let idx = self.written.len();
        for f in &self.formats {
            let path = match (f, ranks) {
                (SnapshotFormat::Vtu, Some(comm)) => {
                    ranks::write_vtu_pieces(&self.dir, idx, sim, comm)?
                }
                (SnapshotFormat::Csv, Some(comm)) => {
                    let all = crate::parallel::gather_particles(sim, comm)
                        .map_err(|e| RunError::Io(format!("distributed run: {e}")))?;
                    let path = self.dir.join(format!("snapshot_{idx:05}.csv"));
                    if comm.rank() == 0 {
                        io::write_csv(&path, &all).map_err(|e| io_err(&path, e))?;
                    }
                    path
                }
                (SnapshotFormat::Vtu, None) => {
                    let path = self.dir.join(format!("snapshot_{idx:05}.vtu"));
                    io::write_vtu(&path, &sim.sys.particles, sim.time)
                        .map_err(|e| io_err(&path, e))?;
                    path
                }
                (SnapshotFormat::Csv, None) => {
                    let path = self.dir.join(format!("snapshot_{idx:05}.csv"));
                    io::write_csv(&path, &sim.sys.particles).map_err(|e| io_err(&path, e))?;
                    path
                }
            };
            if *f == SnapshotFormat::Vtu {
                self.written.push((sim.time, path.clone()));
            }
            self.files.push(path);
        }
        if !self.formats.contains(&SnapshotFormat::Vtu) {
            self.written.push((sim.time, PathBuf::new()));
        }
        if ranks.is_some_and(|c| c.rank() != 0) {
            return Ok(());
        }
        self.write_index()?;
        self.write_pvd()
    }

    /// `snapshots.csv`: each snapshot's number and time, whatever the formats (the CSV
    /// snapshots carry no time; scripts reading a time series from them need it).
    fn write_index(&self) -> Result<(), RunError> {
        let mut text = String::from("snapshot,time [s]\n");
        for (i, (t, _)) in self.written.iter().enumerate() {
            text += &format!("{i},{t:e}\n");
        }
        let path = self.dir.join("snapshots.csv");
        std::fs::write(&path, text).map_err(|e| io_err(&path, e))
    }

    /// ParaView collection so the snapshots open as one time series.
    fn write_pvd(&self) -> Result<(), RunError> {
        if !self.formats.contains(&SnapshotFormat::Vtu) {
            return Ok(());
        }
        let entries: Vec<(f64, String)> = self
            .written
            .iter()
            .map(|(t, p)| {
                let name = p.file_name().map(|n| n.to_string_lossy().to_string());
                (*t, name.unwrap_or_default())
            })
            .collect();
        let path = self.dir.join("snapshots.pvd");
        io::write_pvd(&path, &entries).map_err(|e| io_err(&path, e))
    }
}

/// Which impulses act on the fluid of `case` (see [`MomentumCheck`]).
fn momentum_check<const D: usize>(case: &Case, sim: &Simulation<D>) -> MomentumCheck {
    use crate::domain::BoundaryKind;
    let other = sim.sys.domain.kind.contains(&BoundaryKind::Reflect)
        || case.domain.frozen_margin > 0.0
        || case.regions.iter().any(|r| r.frozen || r.drive.is_some())
        || !sim.sys.ports.is_empty()
        || sim.sys.frame.is_some();
    if other {
        MomentumCheck::Boundaries
    } else if sim.sys.gravity.norm() > 0.0 || !sim.sys.bodies.is_empty() {
        MomentumCheck::Balance
    } else {
        MomentumCheck::Conservation
    }
}

fn run_dim<const D: usize>(
    case: &Case,
    out: &Path,
    progress: &mut dyn FnMut(&Progress),
    ranks: Option<Arc<dyn Comm>>,
) -> Result<RunSummary, RunError> {
    let mut sim = match &ranks {
        Some(comm) => case.distributed::<D>(comm.clone())?,
        None => case.build::<D>()?,
    };
    let comm = ranks.as_deref();
    let root = comm.is_none_or(|c| c.rank() == 0);
    let diag_path = out.join("diagnostics.csv");
    let mut diag = match root {
        true => Some(DiagnosticsWriter::create(&diag_path, D).map_err(|e| io_err(&diag_path, e))?),
        false => None,
    };
    let mut record = |d: &crate::sim::Diagnostics| match &mut diag {
        Some(w) => w.record(d),
        None => Ok(()),
    };
    let mut snaps = Snapshots {
        dir: out.to_path_buf(),
        formats: case.output.formats.clone(),
        written: vec![],
        files: vec![],
    };
    let initial = sim.diagnostics();
    record(&initial).map_err(|e| io_err(&diag_path, e))?;
    let mut loads = loads::LoadHistory::default();
    loads.record(&sim);
    snaps.write(&sim, comm)?;
    let t_end = case.time.t_end;
    let every = case.output.snapshot_every;
    let start = Instant::now();
    let mut updates = 0.0;
    let mut snap_index = 1u64;
    let mut diag_err = None;
    let mut max_abs_momentum: f64 = 0.0;
    let mut max_lorentz: f64 = initial.max_lorentz;
    let mut gravity_impulse = [0.0f64; 3];
    let mut t_prev = sim.time;
    let result = (|| -> Result<(), RunError> {
        while sim.time < t_end {
            // Targets by index (no accumulated rounding); a target within 1e-9 of t_end is t_end.
            let mut target = if every > 0.0 {
                (every * snap_index as f64).min(t_end)
            } else {
                t_end
            };
            if t_end - target <= 1e-9 * t_end {
                target = t_end;
            }
            sim.advance_to(target, |s| {
                updates += match comm {
                    Some(_) => initial.particles as f64,
                    None => s.sys.particles.len() as f64,
                };
                let p = &s.sys.particles;
                // Σ m|v| (SR: Σ ν|S|) and the mass of the fluid, in one pass
                let momentum = |i: usize| match s.sys.relativistic {
                    Some(sr) => p.extra_vectors[sr.momentum][i].norm(),
                    None => p.vel[i].norm(),
                };
                let (mut scale, mut mass) = crate::threads::block_reduce(
                    s.sys.owned(),
                    |r| {
                        r.filter(|&i| p.body[i] == 0 && p.port[i] == 0)
                            .fold((0.0, 0.0), |(s, m), i| {
                                (s + p.mass[i] * momentum(i), m + p.mass[i])
                            })
                    },
                    |a, b| (a.0 + b.0, a.1 + b.1),
                    (0.0, 0.0),
                );
                if let Some(layout) = &s.layout {
                    let t = layout.sum(&[scale, mass]).unwrap_or(vec![f64::NAN; 2]);
                    (scale, mass) = (t[0], t[1]);
                }
                max_abs_momentum = max_abs_momentum.max(scale);
                // every integrator applies g over the whole step: Σ_steps M g dt exactly (the
                // step's own dt: last_dt skips the shortened steps that land on a target)
                let dt = s.time - t_prev;
                t_prev = s.time;
                for (k, g) in gravity_impulse.iter_mut().enumerate().take(D) {
                    *g += mass * s.sys.gravity[k] * dt;
                }
                if s.steps % case.output.diagnostics_every == 0 {
                    let d = s.diagnostics();
                    max_lorentz = max_lorentz.max(d.max_lorentz);
                    if let Err(e) = record(&d) {
                        diag_err.get_or_insert(io_err(&diag_path, e));
                    }
                    loads.record(s);
                }
                if root {
                    progress(&Progress {
                        time: s.time,
                        t_end,
                        step: s.steps,
                        dt: s.last_dt,
                        particles: s.sys.particles.len(),
                        rate: updates / start.elapsed().as_secs_f64().max(1e-9),
                    });
                }
            })?;
            if sim.steps > case.time.max_steps {
                return Err(RunError::Case(CaseError(format!(
                    "time.max_steps: the run needed more than {} steps before t_end; raise the limit (≥ 1)",
                    case.time.max_steps
                ))));
            }
            if let Some(e) = diag_err.take() {
                return Err(e);
            }
            snaps.write(&sim, comm)?;
            snap_index += 1;
        }
        Ok(())
    })();
    let last = sim.diagnostics();
    let _ = record(&last);
    loads.record(&sim);
    // the history so far is worth keeping even when the run failed
    let written = if root { loads.write(out) } else { Ok(()) };
    result?;
    written.map_err(RunError::Io)?;
    let exchange = sim.layout.as_ref().map(|l| l.exchange());
    if let Some(c) = comm {
        ranks::gather_to_root(&mut sim, c)?;
    }
    let wall = start.elapsed().as_secs_f64();
    let mut summary = RunSummary {
        case: case.case.name.clone(),
        dimension: D,
        particles: sim.sys.particles.len(),
        ranks: exchange.map_or(1, |e| e.0),
        exchange: exchange.map(|e| e.1),
        steps: sim.steps,
        time: sim.time,
        wall_seconds: wall,
        particle_updates_per_second: updates / wall.max(1e-9),
        snapshots: snaps.files.clone(),
        initial,
        last,
        shock_tube: None,
        vortex_l1: None,
        radial: None,
        bodies: sim
            .sys
            .bodies
            .iter()
            .map(|b| BodyLoad {
                name: b.name.clone(),
                force: (0..3)
                    .map(|k| if k < D { b.force[k] } else { 0.0 })
                    .collect(),
                torque: b.torque.to_vec(),
                impulse: (0..3)
                    .map(|k| if k < D { b.impulse[k] } else { 0.0 })
                    .collect(),
            })
            .collect(),
        plot: None,
        phase_seconds: {
            let st = &sim.sys.stats;
            [
                st.seconds_neighbours,
                st.seconds_density,
                st.seconds_gradients,
                st.seconds_forces,
            ]
        },
        list_build_seconds: sim.sys.stats.seconds_list_builds,
        cut_seconds: sim.sys.stats.seconds_cut,
        ia_fallbacks: sim.sys.stats.ia_fallbacks_total,
        momentum_drift: {
            let dp: f64 = (0..3)
                .map(|k| (last.momentum[k] - initial.momentum[k]).powi(2))
                .sum::<f64>()
                .sqrt();
            dp / max_abs_momentum.max(1e-300)
        },
        momentum_change: std::array::from_fn(|k| last.momentum[k] - initial.momentum[k]),
        gravity_impulse,
        wall_impulse: std::array::from_fn(|k| {
            -sim.sys
                .bodies
                .iter()
                .map(|b| if k < D { b.impulse[k] } else { 0.0 })
                .sum::<f64>()
        }),
        momentum_check: momentum_check(case, &sim),
        momentum_residual: None,
        mean_h_iterations: sim.sys.stats.h_iterations_total / sim.sys.stats.h_solves.max(1) as f64,
        neighbour_list_builds: sim.sys.verlet.builds,
        h_growth_rebuilds: sim.sys.stats.list_rebuilds,
        relativistic: sim.sys.relativistic.map(|_| {
            let st = &sim.sys.stats;
            RecoverySummary {
                recoveries: st.sr_recoveries,
                mean_iterations: st.sr_recovery_iterations as f64 / st.sr_recoveries.max(1) as f64,
                max_iterations: st.sr_recovery_max_iterations,
                fallbacks: st.sr_recovery_fallbacks,
                max_lorentz: max_lorentz.max(last.max_lorentz),
                light_cone_steps: st.steps_set_by_scheme,
            }
        }),
    };
    if summary.momentum_check != MomentumCheck::Boundaries {
        let r: f64 = (0..3)
            .map(|k| {
                let e = summary.momentum_change[k]
                    - summary.gravity_impulse[k]
                    - summary.wall_impulse[k];
                e * e
            })
            .sum::<f64>()
            .sqrt();
        let norm = |a: &[f64; 3]| a.iter().map(|x| x * x).sum::<f64>().sqrt();
        let scale = max_abs_momentum
            .max(norm(&summary.gravity_impulse))
            .max(norm(&summary.wall_impulse));
        summary.momentum_residual = Some(r / scale.max(1e-300));
    }
    if !root {
        // rank 0 checks and writes the summary of the whole run
        return Ok(summary);
    }
    if let Some(v) = &case.verify {
        checks::verify(case, v, &sim, out, &mut summary)?;
    }
    let path = out.join("summary.json");
    std::fs::write(
        &path,
        serde_json::to_string_pretty(&summary).unwrap_or_default(),
    )
    .map_err(|e| io_err(&path, e))?;
    Ok(summary)
}
