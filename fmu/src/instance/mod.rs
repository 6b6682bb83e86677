//! One FMU instance behind both FMI faces: the state machine, parameters, inputs, outputs,
//! FMU states. `fmi2.rs` and `fmi3.rs` only translate C arguments and status codes.

pub mod inputs;
pub mod limits;
mod remote;
pub(crate) mod solver;
mod values;

use crate::bridge::settings::ZenohSettings;
use crate::table::{Start, Table};
use inputs::{start_inputs, Inputs, Snapshot};
use sphfmu::case::Case;
use sphfmu::coupling::{Coupling, CouplingOptions, StepLimit};
use std::path::{Path, PathBuf};

/// The kinematics of the externally driven bodies (table order) and of the frame.
type MasterMotions = (
    Vec<sphfmu::coupling::BodyKinematics>,
    Option<sphfmu::coupling::BodyKinematics>,
);

/// FMI status codes (the same numbers in FMI 2.0 and 3.0).
#[derive(Debug, Clone, Copy, PartialEq, Eq, PartialOrd, Ord)]
#[repr(i32)]
pub enum Status {
    Ok = 0,
    Warning = 1,
    Discard = 2,
    Error = 3,
    Fatal = 4,
}

#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Mode {
    Instantiated,
    Initialization,
    Step,
    Terminated,
    /// A call failed with Error: only get/set FMU state, reset, terminate? no: reset and free.
    Failed,
}

/// Messages go through the master's callback: (status, category, message).
pub type Logger = Box<dyn Fn(Status, &str, &str)>;

/// The file in resources/ naming the packaged case.
pub const DEFAULT_CASE_FILE: &str = "default-case.txt";

#[derive(Debug, Clone, PartialEq)]
pub(crate) struct Params {
    pub(crate) case: String,
    pub(crate) scheme: String,
    pub(crate) resolution: f64,
    pub(crate) cfl: f64,
    pub(crate) threads: i64,
    pub(crate) output_dir: String,
    pub(crate) output_interval: f64,
    pub(crate) zenoh: ZenohSettings,
    pub(crate) limits: limits::Limits,
}

impl Params {
    fn start(case: String) -> Params {
        Params {
            case,
            scheme: String::new(),
            resolution: 1.0,
            cfl: 0.0,
            threads: 0,
            output_dir: String::new(),
            output_interval: 0.0,
            zenoh: ZenohSettings::default(),
            limits: Default::default(),
        }
    }
}

/// Snapshots written from inside the FMU (`output_dir`): the entries of snapshots.pvd and
/// the next output time.
#[derive(Debug, Clone, Default)]
struct Output {
    written: Vec<(f64, String)>,
    next: f64,
}

pub struct Instance {
    pub name: String,
    resources: PathBuf,
    pub(crate) packaged: Case,
    pub table: Table,
    pub(crate) params: Params,
    pub(crate) inputs: Inputs,
    pub(crate) coupling: crate::instance::solver::Solver,
    /// The zenoh bridge while live coupling is on (`zenoh.mode`).
    #[cfg(feature = "zenoh")]
    pub(crate) bridge: Option<crate::bridge::Bridge>,
    /// The node this instance forwards to (`remote`), once reached.
    #[cfg(feature = "zenoh")]
    pub(crate) remote: Option<crate::bridge::proxy::RemoteNode>,
    /// The ranks this instance's solver is shared among (`sphfmu serve` under mpirun): every
    /// rank holds an instance and makes the same calls in the same order.
    ranks: Option<std::sync::Arc<dyn sphfmu::parallel::comm::Comm>>,
    output: Output,
    pub mode: Mode,
    start_time: f64,
    logger: Logger,
    logging_on: bool,
    categories: Vec<String>,
}

/// A rejected call: its status and the message logged for it.
pub type CallResult<T> = Result<T, (Status, String)>;

pub(crate) fn err<T>(msg: impl Into<String>) -> CallResult<T> {
    Err((Status::Error, msg.into()))
}

impl Instance {
    /// Read the packaged case named by resources/default-case.txt and build the table.
    pub fn new(name: &str, resources: &Path, logger: Logger) -> Result<Instance, String> {
        let marker = resources.join(DEFAULT_CASE_FILE);
        let case_file = std::fs::read_to_string(&marker)
            .map_err(|e| {
                format!(
                    "resources: cannot read {} ({e}); is this the packaged FMU's resources folder?",
                    marker.display()
                )
            })?
            .trim()
            .to_string();
        Instance::with_case(name, resources, &case_file, logger)
    }

    /// An instance of case file `case_file` in folder `resources` (the packaged FMU's
    /// resources, or any folder for the zenoh node `sphfmu-serve`).
    pub fn with_case(
        name: &str,
        resources: &Path,
        case_file: &str,
        logger: Logger,
    ) -> Result<Instance, String> {
        let case_file = case_file.to_string();
        // (the error names the file)
        let packaged = Case::load(&resources.join(&case_file)).map_err(|e| e.0)?;
        let table = Table::new(&packaged, &case_file);
        let params = Params::start(case_file);
        let inputs = start_inputs(&table);
        Ok(Instance {
            name: name.to_string(),
            resources: resources.to_path_buf(),
            packaged,
            table,
            params,
            inputs,
            coupling: Default::default(),
            #[cfg(feature = "zenoh")]
            bridge: None,
            #[cfg(feature = "zenoh")]
            remote: None,
            ranks: None,
            output: Output::default(),
            mode: Mode::Instantiated,
            start_time: 0.0,
            logger,
            logging_on: false,
            categories: vec![],
        })
    }

    /// Log through the master: errors and discards always, the rest when logging is on for
    /// the category.
    pub fn log(&self, status: Status, category: &str, msg: &str) {
        if status >= Status::Discard || self.logs(category) {
            (self.logger)(status, category, msg);
        }
    }

    /// Whether messages of `category` go to the master now.
    fn logs(&self, category: &str) -> bool {
        self.logging_on
            && (self.categories.is_empty() || self.categories.iter().any(|c| c == category))
    }

    pub fn set_debug_logging(&mut self, on: bool, categories: Vec<String>) -> CallResult<()> {
        for c in &categories {
            if !crate::packaging::xml::LOG_CATEGORIES
                .iter()
                .any(|(n, _)| n == c)
            {
                return err(format!(
                    "setDebugLogging: unknown category {c:?} (known: logEvents, logStatusWarning, logStatusError, logSolver)"
                ));
            }
        }
        self.logging_on = on;
        self.categories = categories;
        Ok(())
    }

    pub(crate) fn expect_mode(&self, call: &str, allowed: &[Mode]) -> CallResult<()> {
        if allowed.contains(&self.mode) {
            Ok(())
        } else {
            err(format!("{call}: not allowed in state {:?}", self.mode))
        }
    }

    pub fn enter_initialization(&mut self, start_time: f64) -> CallResult<()> {
        self.expect_mode("enterInitializationMode", &[Mode::Instantiated])?;
        if !start_time.is_finite() {
            return err(format!(
                "enterInitializationMode: startTime must be finite, got {start_time}"
            ));
        }
        self.start_time = start_time;
        self.mode = Mode::Initialization;
        self.log(
            Status::Ok,
            "logEvents",
            &format!("initialisation at t = {start_time}"),
        );
        // f64 resolves a time t to about 2.2e-16 |t|: past 1e7 s a step of 1e-9 s is lost
        let resolution = f64::EPSILON * start_time.abs();
        if resolution > 1e-9 {
            return Err((
                Status::Warning,
                format!(
                    "enterInitializationMode: startTime {start_time} resolves times only to {resolution:.1e} s; doStep refuses steps shorter than that"
                ),
            ));
        }
        Ok(())
    }

    pub fn exit_initialization(&mut self) -> CallResult<()> {
        self.expect_mode("exitInitializationMode", &[Mode::Initialization])?;
        if self.proxied() {
            self.ensure_remote()?;
            self.mode = Mode::Step;
            return Ok(());
        }
        self.ensure_coupling()?;
        self.apply_inputs()?;
        self.open_live()?;
        self.mode = Mode::Step;
        self.output = Output::default();
        self.write_output()?;
        self.publish_live();
        let c = self.coupling.get().expect("built above");
        let d = c.diagnostics();
        self.log(
            Status::Ok,
            "logEvents",
            &format!(
                "case {:?} ready: {} particles, {}D, scheme {}",
                self.params.case,
                d.particles,
                c.dimension(),
                if self.params.scheme.trim().is_empty() {
                    "of the case"
                } else {
                    self.params.scheme.trim()
                }
            ),
        );
        Ok(())
    }

    /// Share the solver among `ranks` (before initialisation ends): the node under mpirun,
    /// where every rank runs this instance and makes the same calls in the same order (most
    /// reach collectives), and rank 0 alone talks to the outside.
    pub fn share_among(&mut self, ranks: std::sync::Arc<dyn sphfmu::parallel::comm::Comm>) {
        self.ranks = Some(ranks);
        self.coupling.put(None);
    }

    /// Whether the solver is shared among ranks.
    pub fn distributed(&self) -> bool {
        self.ranks.is_some()
    }

    /// Build the solver from the parameters (when not built yet).
    pub(crate) fn ensure_coupling(&mut self) -> CallResult<()> {
        if self.coupling.is_some() {
            return Ok(());
        }
        let p = &self.params;
        if self.ranks.is_some() && !p.output_dir.trim().is_empty() {
            return err(
                "output_dir: a node on several ranks writes no snapshots of its own (`mpirun -n R sphfmu run` writes VTU pieces); leave output_dir empty",
            );
        }
        let path = if Path::new(&p.case).is_absolute() {
            PathBuf::from(&p.case)
        } else {
            self.resources.join(&p.case)
        };
        let case = Case::load(&path).map_err(|e| (Status::Error, format!("case: {}", e.0)))?;
        self.table
            .accepts(&self.packaged, &case)
            .map_err(|e| (Status::Error, format!("case {:?} has {e}", p.case)))?;
        let options = CouplingOptions {
            scheme: (!p.scheme.trim().is_empty()).then(|| p.scheme.clone()),
            resolution: p.resolution,
            cfl: (p.cfl != 0.0).then_some(p.cfl),
            threads: p.threads as usize,
            limits: p.limits.size(),
        };
        let c = Coupling::new_on(&case, &options, self.ranks.clone())
            .map_err(|e| (Status::Error, e.0))?;
        self.coupling.put(Some(c));
        Ok(())
    }

    /// The solver's kinematics of every externally driven body and of the frame from
    /// `inputs`, each checked as [`Coupling::set_body_kinematics`] would, or the first reason
    /// one is refused.
    fn body_kinematics(&self, c: &Coupling, inputs: &Inputs) -> Result<MasterMotions, String> {
        let mut bodies = vec![];
        for (k, &b) in self.table.external_bodies.iter().enumerate() {
            let (name, form) = &self.table.external_forms[k];
            let kin = inputs.bodies[k].kinematics(name, *form)?;
            c.check_body_kinematics(b, &kin).map_err(|e| e.0)?;
            bodies.push(kin);
        }
        let frame = match (&inputs.frame, self.table.frame_form) {
            (Some(f), Some(form)) => {
                let kin = f.kinematics("frame", form)?;
                c.check_frame_kinematics(&kin).map_err(|e| e.0)?;
                Some(kin)
            }
            _ => None,
        };
        Ok((bodies, frame))
    }

    /// Hand the inputs to the solver (it ignores unchanged values). Every input is checked
    /// before any is handed on, so a refused one changes nothing.
    pub(crate) fn apply_inputs(&mut self) -> CallResult<()> {
        let c = self.coupling.get().expect("coupling built");
        c.check_gravity(&self.inputs.gravity)
            .map_err(|e| (Status::Error, e.0))?;
        let (bodies, frame) = self
            .body_kinematics(c, &self.inputs)
            .map_err(|e| (Status::Error, e))?;
        for (k, &p) in self.table.external_ports.iter().enumerate() {
            c.check_port_pressure(p, self.inputs.ports[k])
                .map_err(|e| (Status::Error, e.0))?;
        }
        let c = self.coupling.get_mut().expect("coupling built");
        c.set_gravity(self.inputs.gravity)
            .map_err(|e| (Status::Error, e.0))?;
        for (k, &b) in self.table.external_bodies.iter().enumerate() {
            c.set_body_kinematics(b, &bodies[k])
                .map_err(|e| (Status::Error, e.0))?;
        }
        if let Some(f) = frame {
            c.set_frame_kinematics(&f)
                .map_err(|e| (Status::Error, e.0))?;
        }
        for (k, &p) in self.table.external_ports.iter().enumerate() {
            c.set_port_pressure(p, self.inputs.ports[k])
                .map_err(|e| (Status::Error, e.0))?;
        }
        Ok(())
    }

    pub fn time(&self) -> f64 {
        self.start_time + self.solver_time()
    }

    /// One communication step. Its arguments are checked first: a bad one is an Error that
    /// changes nothing (the instance stays in step mode). Only a failure of the solver itself
    /// moves the instance to Failed, from which `setFMUState` or `reset` recover it. A step
    /// that runs out of its `limits.*` budget returns Discard at the time it reached.
    pub fn do_step(&mut self, current: f64, h: f64) -> CallResult<()> {
        self.expect_mode("doStep", &[Mode::Step])?;
        let now = self.time();
        if !(h.is_finite() && h > 0.0) {
            return err(format!(
                "communicationStepSize must be finite and > 0, got {h}"
            ));
        }
        if !current.is_finite() || (current - now).abs() > 1e-9 * now.abs().max(1.0) {
            return err(format!(
                "currentCommunicationPoint {current} is not the FMU's time {now}"
            ));
        }
        let target = current + h - self.start_time;
        let solver_time = self.solver_time();
        if target.is_nan() || target <= solver_time {
            return err(format!(
                "communicationStepSize {h}: the step from {current} ends at {}, not after the FMU's time {now} (the step is below the resolution of the time, or the communication point lies behind it within the 1e-9 tolerance)",
                current + h
            ));
        }
        #[cfg(feature = "zenoh")]
        if self.remote.is_some() {
            return self.do_step_remote(h);
        }
        self.apply_inputs_live()?;
        let limits = self.params.limits;
        let (logger, logging) = (&self.logger, self.logs("logSolver"));
        let start_time = self.start_time;
        let mut progress = |t: f64, steps: u64, seconds: f64| {
            if logging {
                logger(
                    Status::Ok,
                    "logSolver",
                    &format!(
                        "doStep to t = {}: at t = {} after {steps} internal steps, {seconds:.1} s",
                        current + h,
                        start_time + t
                    ),
                );
            }
        };
        let mut budget = limits.budget(&mut progress);
        let c = self
            .coupling
            .get_mut()
            .expect("coupling built in step mode");
        let result = c.step_within(target, &mut budget);
        match result {
            Ok(r) => {
                let reached = self.time();
                if let Some(why) = r.stopped {
                    let limit = match why {
                        StepLimit::Steps(n) => format!(
                            "limits.max_internal_steps = {} ({n} internal steps taken)",
                            limits.max_internal_steps
                        ),
                        StepLimit::Seconds(s) => format!(
                            "limits.max_step_seconds = {} ({s:.3} s of wall clock)",
                            limits.max_step_seconds
                        ),
                    };
                    // (a snapshot that cannot be written is the lesser news here)
                    let _ = self.write_output();
                    self.publish_live();
                    return Err((
                        Status::Discard,
                        format!(
                            "the step to t = {} {} {reached} after {} internal steps: {limit}; lastSuccessfulTime = {reached}. Go on from there, or restore an earlier FMU state",
                            current + h,
                            remote::STEP_STOPPED,
                            r.steps
                        ),
                    ));
                }
                let msg = format!(
                    "doStep to t = {}: {} internal steps, dt in [{:.3e}, {:.3e}]",
                    current + h,
                    r.steps,
                    r.dt_min,
                    r.dt_max
                );
                self.log(Status::Ok, "logSolver", &msg);
                let written = self.write_output();
                self.publish_live();
                written
            }
            Err(e) => {
                self.mode = Mode::Failed;
                err(format!(
                    "{} ({e}); restore a saved FMU state or reset",
                    remote::SOLVER_FAILED
                ))
            }
        }
    }

    /// A snapshot when `output_dir` is set and the output time has come; a file-system
    /// failure is a warning (the simulation itself is fine).
    fn write_output(&mut self) -> CallResult<()> {
        let dir = self.params.output_dir.trim();
        let Some(c) = self.coupling.get() else {
            return Ok(());
        };
        // (the output time may be missed by a rounding of the master's time grid)
        if dir.is_empty() || c.time() < self.output.next - 1e-9 * self.output.next.abs().max(1.0) {
            return Ok(());
        }
        let index = self.output.written.len();
        match c.write_snapshot(Path::new(dir), index, &self.output.written) {
            Ok(entry) => {
                self.output.written.push(entry);
                self.output.next = c.time() + self.params.output_interval;
                Ok(())
            }
            Err(e) => Err((
                Status::Warning,
                format!("output_dir: snapshot not written ({})", e.0),
            )),
        }
    }

    pub fn terminate(&mut self) -> CallResult<()> {
        self.expect_mode(
            "terminate",
            &[Mode::Step, Mode::Initialization, Mode::Failed],
        )?;
        self.mode = Mode::Terminated;
        self.close_live();
        self.log(Status::Ok, "logEvents", "terminated");
        Ok(())
    }

    /// Back to the state after instantiation: start values, no solver.
    pub fn reset(&mut self) {
        self.coupling.put(None);
        self.close_live();
        #[cfg(feature = "zenoh")]
        {
            self.remote = None;
        }
        self.params = Params::start(match &self.table.variables[1].start {
            Start::Text(t) => t.clone(),
            _ => unreachable!("variable 1 is the case parameter"),
        });
        self.output = Output::default();
        self.inputs = start_inputs(&self.table);
        self.start_time = 0.0;
        self.mode = Mode::Instantiated;
        self.log(Status::Ok, "logEvents", "reset");
    }

    // ---- FMU state ---------------------------------------------------------------------

    pub fn get_state(&self) -> CallResult<Snapshot> {
        #[cfg(feature = "zenoh")]
        if self.proxied() {
            return self.get_state_remote();
        }
        let Some(c) = self.coupling.get() else {
            return err(
                "getFMUState: available once initialisation has ended (no solver state yet)",
            );
        };
        Ok(Snapshot {
            inputs: self.inputs.clone(),
            start_time: self.start_time,
            solver: c
                .save()
                .map_err(|e| (Status::Error, format!("getFMUState: {}", e.0)))?,
        })
    }

    pub fn set_state(&mut self, s: &Snapshot) -> CallResult<()> {
        self.expect_mode(
            "setFMUState",
            &[Mode::Step, Mode::Failed, Mode::Initialization],
        )?;
        if !self.proxied() {
            self.ensure_coupling()?;
        }
        if s.inputs.bodies.len() != self.table.external_bodies.len()
            || s.inputs.frame.is_some() != self.table.frame_form.is_some()
            || s.inputs.ports.len() != self.table.external_ports.len()
        {
            return err(
                "setFMUState: the state belongs to another model (body or port inputs differ)",
            );
        }
        #[cfg(feature = "zenoh")]
        if self.proxied() {
            return self.set_state_remote(s);
        }
        let c = self.coupling.get().expect("built above");
        // the inputs the state carries pass the checks a master's set would
        let bad = |e: sphfmu::coupling::CouplingError| {
            (
                Status::Error,
                format!("setFMUState: the state's inputs: {}", e.0),
            )
        };
        if !s.start_time.is_finite() {
            return err(format!(
                "setFMUState: the state's start time {} is not finite",
                s.start_time
            ));
        }
        c.check_gravity(&s.inputs.gravity).map_err(bad)?;
        self.body_kinematics(c, &s.inputs)
            .map_err(|e| bad(sphfmu::coupling::CouplingError(e)))?;
        for (k, &p) in self.table.external_ports.iter().enumerate() {
            c.check_port_pressure(p, s.inputs.ports[k]).map_err(bad)?;
        }
        let c = self.coupling.get_mut().expect("built above");
        c.restore(&s.solver)
            .map_err(|e| (Status::Error, format!("setFMUState: {}", e.0)))?;
        self.inputs = s.inputs.clone();
        self.start_time = s.start_time;
        self.mode = Mode::Step;
        Ok(())
    }
}
