//! One FMU instance behind both FMI faces: the state machine, parameters, inputs, outputs,
//! FMU states. `fmi2.rs` and `fmi3.rs` only translate C arguments and status codes.

use crate::inputs::{start_inputs, Inputs, Snapshot};
use crate::table::{Binding, Causality, Kind, Param, Start, Table};
use crate::zenoh_settings::{ZenohParam, ZenohSettings};
use sphfmu::case::Case;
use sphfmu::coupling::{Coupling, CouplingOptions};
use std::path::{Path, PathBuf};

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
    case: String,
    scheme: String,
    resolution: f64,
    cfl: f64,
    threads: i64,
    output_dir: String,
    output_interval: f64,
    pub(crate) zenoh: ZenohSettings,
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
    packaged: Case,
    pub table: Table,
    pub(crate) params: Params,
    pub(crate) inputs: Inputs,
    pub(crate) coupling: Option<Coupling>,
    /// The zenoh bridge while live coupling is on (`zenoh.mode`).
    #[cfg(feature = "zenoh")]
    pub(crate) bridge: Option<crate::bridge::Bridge>,
    output: Output,
    pub mode: Mode,
    start_time: f64,
    logger: Logger,
    logging_on: bool,
    categories: Vec<String>,
}

/// A rejected call: its status and the message logged for it.
pub type CallResult<T> = Result<T, (Status, String)>;

fn err<T>(msg: impl Into<String>) -> CallResult<T> {
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
            coupling: None,
            #[cfg(feature = "zenoh")]
            bridge: None,
            output: Output::default(),
            mode: Mode::Instantiated,
            start_time: 0.0,
            logger,
            logging_on: false,
            categories: vec![],
        })
    }

    /// Log through the master: errors always, the rest when logging is on for the category.
    pub fn log(&self, status: Status, category: &str, msg: &str) {
        let wanted = status >= Status::Error
            || (self.logging_on
                && (self.categories.is_empty() || self.categories.iter().any(|c| c == category)));
        if wanted {
            (self.logger)(status, category, msg);
        }
    }

    pub fn set_debug_logging(&mut self, on: bool, categories: Vec<String>) -> CallResult<()> {
        for c in &categories {
            if !crate::xml::LOG_CATEGORIES.iter().any(|(n, _)| n == c) {
                return err(format!(
                    "setDebugLogging: unknown category {c:?} (known: logEvents, logStatusWarning, logStatusError, logSolver)"
                ));
            }
        }
        self.logging_on = on;
        self.categories = categories;
        Ok(())
    }

    fn expect_mode(&self, call: &str, allowed: &[Mode]) -> CallResult<()> {
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
        Ok(())
    }

    pub fn exit_initialization(&mut self) -> CallResult<()> {
        self.expect_mode("exitInitializationMode", &[Mode::Initialization])?;
        self.ensure_coupling()?;
        self.apply_inputs()?;
        self.open_live()?;
        self.mode = Mode::Step;
        self.output = Output::default();
        self.write_output()?;
        self.publish_live();
        let c = self.coupling.as_ref().expect("built above");
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

    /// Build the solver from the parameters (when not built yet).
    fn ensure_coupling(&mut self) -> CallResult<()> {
        if self.coupling.is_some() {
            return Ok(());
        }
        let p = &self.params;
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
        };
        let c = Coupling::new(&case, &options).map_err(|e| (Status::Error, e.0))?;
        self.coupling = Some(c);
        Ok(())
    }

    /// Hand the inputs to the solver (it ignores unchanged values).
    pub(crate) fn apply_inputs(&mut self) -> CallResult<()> {
        let c = self.coupling.as_mut().expect("coupling built");
        c.set_gravity(self.inputs.gravity)
            .map_err(|e| (Status::Error, e.0))?;
        for (k, &b) in self.table.external_bodies.iter().enumerate() {
            c.set_body_kinematics(b, &self.inputs.bodies[k])
                .map_err(|e| (Status::Error, e.0))?;
        }
        for (k, &p) in self.table.external_ports.iter().enumerate() {
            c.set_port_pressure(p, self.inputs.ports[k])
                .map_err(|e| (Status::Error, e.0))?;
        }
        Ok(())
    }

    pub fn time(&self) -> f64 {
        self.start_time + self.coupling.as_ref().map(|c| c.time()).unwrap_or(0.0)
    }

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
        self.apply_inputs_live()?;
        let target = current + h - self.start_time;
        let c = self.coupling.as_mut().expect("coupling built in step mode");
        match c.step_to(target) {
            Ok(r) => {
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
                    "the solver failed ({e}); restore a saved FMU state or reset"
                ))
            }
        }
    }

    /// A snapshot when `output_dir` is set and the output time has come; a file-system
    /// failure is a warning (the simulation itself is fine).
    fn write_output(&mut self) -> CallResult<()> {
        let dir = self.params.output_dir.trim();
        let Some(c) = &self.coupling else {
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
        self.coupling = None;
        self.close_live();
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

    // ---- values ------------------------------------------------------------------------

    /// Run a multi-variable set so that a rejected value leaves every value as it was.
    pub fn atomically(&mut self, f: impl FnOnce(&mut Self) -> CallResult<()>) -> CallResult<()> {
        let (params, inputs) = (self.params.clone(), self.inputs.clone());
        let r = f(self);
        if r.is_err() {
            if self.params != params {
                self.coupling = None;
            }
            self.params = params;
            self.inputs = inputs;
        }
        r
    }

    /// Check that variable `i` may be set now; parameters only before step mode.
    fn settable(&self, i: usize) -> CallResult<()> {
        let v = &self.table.variables[i];
        match v.causality {
            Causality::Parameter => self.expect_mode(
                &format!("set {}", v.name),
                &[Mode::Instantiated, Mode::Initialization],
            ),
            Causality::Input => self.expect_mode(
                &format!("set {}", v.name),
                &[Mode::Instantiated, Mode::Initialization, Mode::Step],
            ),
            _ => err(format!(
                "{}: is not a parameter or input (causality {:?}), it cannot be set",
                v.name, v.causality
            )),
        }
    }

    /// Set elements `elems` of Float64 variable `i` (checked first, then stored: a rejected
    /// call changes nothing).
    pub fn set_f64(&mut self, i: usize, first: usize, values: &[f64]) -> CallResult<()> {
        self.settable(i)?;
        let v = &self.table.variables[i];
        let name = v.name.clone();
        if let Some(x) = values.iter().find(|x| !x.is_finite()) {
            return err(format!("{name}: must be finite, got {x}"));
        }
        let put = |dst: &mut [f64; 3]| dst[first..first + values.len()].copy_from_slice(values);
        let ext = |b: usize| self.table.external_index(b);
        match v.binding {
            Binding::Param(Param::Resolution) => {
                let r = values[0];
                if !(0.1..=10.0).contains(&r) {
                    return err(format!("resolution: must be in [0.1, 10], got {r}"));
                }
                self.params.resolution = r;
                self.coupling = None;
            }
            Binding::Param(Param::OutputInterval) => {
                let dt = values[0];
                if dt < 0.0 {
                    return err(format!("output_interval: must be ≥ 0, got {dt}"));
                }
                self.params.output_interval = dt;
            }
            Binding::Param(Param::Zenoh(ZenohParam::Staleness)) => self
                .params
                .zenoh
                .set_staleness(values[0])
                .map_err(|e| (Status::Error, e))?,
            Binding::Param(Param::Cfl) => {
                let c = values[0];
                if !(0.0..=1.0).contains(&c) {
                    return err(format!(
                        "cfl: must be in (0, 1] or 0 for the case's, got {c}"
                    ));
                }
                self.params.cfl = c;
                self.coupling = None;
            }
            Binding::Gravity => {
                let mut g = self.inputs.gravity;
                put(&mut g);
                for (k, x) in g.iter().enumerate() {
                    if k >= self.table.dimension && *x != 0.0 {
                        return err(format!(
                            "gravity[{}]: must be 0 in a {}D case, got {x}",
                            k + 1,
                            self.table.dimension
                        ));
                    }
                }
                self.inputs.gravity = g;
            }
            Binding::BodyPosition(b) => put(&mut self.inputs.bodies[ext(b)].position),
            Binding::BodyVelocity(b) => put(&mut self.inputs.bodies[ext(b)].velocity),
            Binding::BodyAngle(b) => self.inputs.bodies[ext(b)].angle = values[0],
            Binding::BodyAngularVelocity(b) => {
                self.inputs.bodies[ext(b)].angular_velocity = values[0]
            }
            Binding::PortPressure(k) => {
                let p = values[0];
                if p < 0.0 {
                    return err(format!("{name}: must be a finite number ≥ 0, got {p}"));
                }
                let e = self.table.external_port_index(k);
                self.inputs.ports[e] = p;
            }
            _ => return err(format!("{name}: cannot be set")),
        }
        Ok(())
    }

    pub fn set_i64(&mut self, i: usize, value: i64) -> CallResult<()> {
        self.settable(i)?;
        match self.table.variables[i].binding {
            Binding::Param(Param::Threads) => {
                if !(0..=1024).contains(&value) {
                    return err(format!("threads: must be in [0, 1024], got {value}"));
                }
                self.params.threads = value;
                self.coupling = None;
                Ok(())
            }
            _ => err(format!("{}: cannot be set", self.table.variables[i].name)),
        }
    }

    pub fn set_string(&mut self, i: usize, value: &str) -> CallResult<()> {
        self.settable(i)?;
        match self.table.variables[i].binding {
            Binding::Param(Param::Case) => {
                if value.trim().is_empty() {
                    return err("case: must name a case file, got an empty string");
                }
                self.params.case = value.to_string();
            }
            Binding::Param(Param::Scheme) => self.params.scheme = value.to_string(),
            Binding::Param(Param::OutputDir) => {
                self.params.output_dir = value.to_string();
                return Ok(());
            }
            Binding::Param(Param::Zenoh(z)) => {
                return self
                    .params
                    .zenoh
                    .set_text(z, value)
                    .map_err(|e| (Status::Error, e));
            }
            _ => return err(format!("{}: cannot be set", self.table.variables[i].name)),
        }
        self.coupling = None;
        Ok(())
    }

    /// All elements of Float64 variable `i`.
    pub fn get_f64(&mut self, i: usize) -> CallResult<Vec<f64>> {
        let v = &self.table.variables[i];
        let b = v.binding;
        let ext = |b: usize| self.table.external_index(b);
        Ok(match b {
            Binding::Time => vec![self.time()],
            Binding::Param(Param::Resolution) => vec![self.params.resolution],
            Binding::Param(Param::Cfl) => vec![self.params.cfl],
            Binding::Param(Param::OutputInterval) => vec![self.params.output_interval],
            Binding::Param(Param::Zenoh(ZenohParam::Staleness)) => {
                vec![self.params.zenoh.staleness]
            }
            Binding::Gravity => self.inputs.gravity.to_vec(),
            Binding::BodyPosition(b) => self.inputs.bodies[ext(b)].position.to_vec(),
            Binding::BodyVelocity(b) => self.inputs.bodies[ext(b)].velocity.to_vec(),
            Binding::BodyAngle(b) => vec![self.inputs.bodies[ext(b)].angle],
            Binding::BodyAngularVelocity(b) => vec![self.inputs.bodies[ext(b)].angular_velocity],
            Binding::PortPressure(k) => vec![self.inputs.ports[self.table.external_port_index(k)]],
            _ => {
                if v.causality != Causality::Output {
                    return err(format!("{}: not a Float64 value", v.name));
                }
                self.output(i)?
            }
        })
    }

    fn output(&mut self, i: usize) -> CallResult<Vec<f64>> {
        if !matches!(
            self.mode,
            Mode::Initialization | Mode::Step | Mode::Terminated | Mode::Failed
        ) {
            return err(format!(
                "{}: outputs are available from initialisation mode on (state {:?})",
                self.table.variables[i].name, self.mode
            ));
        }
        self.ensure_coupling()?;
        let c = self.coupling.as_ref().expect("built above");
        let b = self.table.variables[i].binding;
        let d = || c.diagnostics();
        Ok(match b {
            Binding::BodyForce(k) => c.loads()[k].force.to_vec(),
            Binding::BodyTorque(k) => c.loads()[k].torque.to_vec(),
            Binding::ProbeDensity(k) => vec![c.probes()[k].density],
            Binding::ProbePressure(k) => vec![c.probes()[k].pressure],
            Binding::ProbeVelocity(k) => c.probes()[k].velocity.to_vec(),
            Binding::ProbeCoverage(k) => vec![c.probes()[k].coverage],
            Binding::Marker(k) => vec![c.markers()[k]],
            Binding::PatchMean(k) => vec![c.patches()[k].mean_pressure],
            Binding::PatchPeak(k) => vec![c.patches()[k].peak_pressure],
            Binding::PatchArea(k) => vec![c.patches()[k].area],
            Binding::PatchForce(k) => c.patches()[k].force.to_vec(),
            Binding::Port(k, what) => vec![what.of(&c.ports()[k])],
            Binding::FluidParticles => vec![d().fluid_particles as f64],
            Binding::Dt => vec![d().dt],
            Binding::Mass => vec![d().mass],
            Binding::Momentum => d().momentum.to_vec(),
            Binding::Energy => vec![d().total_energy],
            Binding::Steps => vec![d().step as f64],
            Binding::Particles => vec![d().particles as f64],
            _ => unreachable!("inputs and parameters are answered by get_f64"),
        })
    }

    pub fn get_i64(&mut self, i: usize) -> CallResult<i64> {
        let v = &self.table.variables[i];
        match v.binding {
            Binding::Param(Param::Threads) => Ok(self.params.threads),
            Binding::Steps | Binding::Particles | Binding::FluidParticles => {
                Ok(self.output(i)?[0] as i64)
            }
            _ => err(format!("{}: not an integer", v.name)),
        }
    }

    pub fn get_string(&self, i: usize) -> CallResult<String> {
        match self.table.variables[i].binding {
            Binding::Param(Param::Case) => Ok(self.params.case.clone()),
            Binding::Param(Param::Scheme) => Ok(self.params.scheme.clone()),
            Binding::Param(Param::OutputDir) => Ok(self.params.output_dir.clone()),
            Binding::Param(Param::Zenoh(z)) if z != ZenohParam::Staleness => {
                Ok(self.params.zenoh.text(z))
            }
            _ => err(format!("{}: not a string", self.table.variables[i].name)),
        }
    }

    /// Variable index of FMI 3.0 value reference `vr` of kind `kind`.
    pub fn var3(&self, vr: u32, kind: Kind) -> CallResult<usize> {
        match self.table.variables.get(vr as usize) {
            Some(v) if v.kind == kind => Ok(vr as usize),
            Some(v) => err(format!(
                "valueReference {vr} ({}) is {:?}, not {kind:?}",
                v.name, v.kind
            )),
            None => err(format!(
                "valueReference {vr}: no such variable (0..{})",
                self.table.variables.len()
            )),
        }
    }

    // ---- FMU state ---------------------------------------------------------------------

    pub fn get_state(&self) -> CallResult<Snapshot> {
        let Some(c) = &self.coupling else {
            return err(
                "getFMUState: available once initialisation has ended (no solver state yet)",
            );
        };
        Ok(Snapshot {
            inputs: self.inputs.clone(),
            start_time: self.start_time,
            solver: c.save(),
        })
    }

    pub fn set_state(&mut self, s: &Snapshot) -> CallResult<()> {
        self.expect_mode(
            "setFMUState",
            &[Mode::Step, Mode::Failed, Mode::Initialization],
        )?;
        self.ensure_coupling()?;
        if s.inputs.bodies.len() != self.table.external_bodies.len()
            || s.inputs.ports.len() != self.table.external_ports.len()
        {
            return err(
                "setFMUState: the state belongs to another model (body or port inputs differ)",
            );
        }
        let c = self.coupling.as_mut().expect("built above");
        c.restore(&s.solver)
            .map_err(|e| (Status::Error, format!("setFMUState: {}", e.0)))?;
        self.inputs = s.inputs.clone();
        self.start_time = s.start_time;
        self.mode = Mode::Step;
        Ok(())
    }
}
