//! Getting and setting variables of an instance: parameters, inputs (checked first, then
//! stored, so a rejected call changes nothing) and outputs read from the solver.

use crate::bridge::settings::ZenohParam;
use crate::instance::{err, CallResult, Instance, Mode, Status};
use crate::table::{Binding, Causality, Kind, MotionInput, Param};

impl Instance {
    /// Run a multi-variable set so that a rejected value leaves every value as it was.
    pub fn atomically(&mut self, f: impl FnOnce(&mut Self) -> CallResult<()>) -> CallResult<()> {
        let (params, inputs) = (self.params.clone(), self.inputs.clone());
        let r = f(self);
        if r.is_err() {
            if self.params != params {
                self.coupling.put(None);
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
        let put = |dst: &mut [f64]| dst[first..first + values.len()].copy_from_slice(values);
        match v.binding {
            Binding::Param(Param::Resolution) => {
                let r = values[0];
                if !(0.1..=10.0).contains(&r) {
                    return err(format!("resolution: must be in [0.1, 10], got {r}"));
                }
                self.params.resolution = r;
                self.coupling.put(None);
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
            Binding::Param(Param::Limit(which)) => {
                self.params.limits.set_f64(which, values[0])?;
                // the size limits act when the solver is built
                self.coupling.put(None);
            }
            Binding::Param(Param::Cfl) => {
                let c = values[0];
                if !(0.0..=1.0).contains(&c) {
                    return err(format!(
                        "cfl: must be in (0, 1] or 0 for the case's, got {c}"
                    ));
                }
                self.params.cfl = c;
                self.coupling.put(None);
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
            Binding::Motion(mover, input) => {
                let (size, table) = (v.size, &self.table);
                let mut motion = *self.inputs.mover(table, mover);
                put(motion.field_mut(input, size));
                // a whole orientation is checked now; one set element by element (FMI 2.0
                // scalars) is checked as a whole by the next doStep
                if matches!(input, MotionInput::Quaternion | MotionInput::Matrix)
                    && values.len() == size
                {
                    let (name, form) = table.form_of(mover);
                    motion
                        .kinematics(name, form)
                        .map_err(|m| (Status::Error, m))?;
                }
                *self.inputs.mover_mut(table, mover) = motion;
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
                self.coupling.put(None);
                Ok(())
            }
            Binding::Param(Param::Limit(which)) => {
                self.params.limits.set_i64(which, value)?;
                self.coupling.put(None);
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
        self.coupling.put(None);
        Ok(())
    }

    /// All elements of Float64 variable `i`.
    pub fn get_f64(&mut self, i: usize) -> CallResult<Vec<f64>> {
        let v = &self.table.variables[i];
        let b = v.binding;
        Ok(match b {
            Binding::Time => vec![self.time()],
            Binding::Param(Param::Resolution) => vec![self.params.resolution],
            Binding::Param(Param::Cfl) => vec![self.params.cfl],
            Binding::Param(Param::OutputInterval) => vec![self.params.output_interval],
            Binding::Param(Param::Limit(which)) => vec![self.params.limits.get(which)],
            Binding::Param(Param::Zenoh(ZenohParam::Staleness)) => {
                vec![self.params.zenoh.staleness]
            }
            Binding::Gravity => self.inputs.gravity.to_vec(),
            Binding::Motion(mover, input) => self
                .inputs
                .mover(&self.table, mover)
                .field(input, v.size)
                .to_vec(),
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
        #[cfg(feature = "zenoh")]
        if self.proxied() {
            return self.remote_output(i);
        }
        self.ensure_coupling()?;
        let mut c = self.coupling.outputs().expect("built above");
        let b = self.table.variables[i].binding;
        let mut d = || c.diagnostics();
        Ok(match b {
            Binding::BodyForce(k) => c.loads()[k].force.to_vec(),
            Binding::BodyTorque(k) => c.loads()[k].torque.to_vec(),
            Binding::BodyForceBody(k) => c.loads()[k].force_body.to_vec(),
            Binding::BodyTorqueBody(k) => c.loads()[k].torque_body.to_vec(),
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
            Binding::Param(Param::Limit(which)) => Ok(self.params.limits.get(which) as i64),
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
}
