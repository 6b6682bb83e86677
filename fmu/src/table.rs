//! The one table of FMU variables. Both modelDescription.xml files are written from it and
//! every getter and setter dispatches through it, so the XML and the binary cannot disagree.
//! It is a function of the packaged case (its dimension, bodies, probes, markers, patches and ports).
//!
//! FMI 3.0 sees 3-vectors as arrays (`<Dimension start="3"/>`, one value reference); FMI 2.0
//! sees them flattened to `name[1]`, `name[2]`, `name[3]` (structured naming convention),
//! each with its own value reference.

use crate::units::units;
use sphfmu::boundary::kinematics::Motion;
use sphfmu::boundary::ports::PortPressure;
use sphfmu::case::Case;

#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Kind {
    Float64,
    /// FMI 3.0 Int64, FMI 2.0 Integer.
    Int64,
    String,
}

#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Causality {
    Independent,
    Parameter,
    Input,
    Output,
}

/// Parameters (fixed: set before the end of initialisation).
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Param {
    Case,
    Scheme,
    Resolution,
    Cfl,
    Threads,
    OutputDir,
    OutputInterval,
    Zenoh(crate::zenoh_settings::ZenohParam),
}

/// What a variable reads or writes.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Binding {
    Time,
    Param(Param),
    Gravity,
    BodyPosition(usize),
    BodyAngle(usize),
    BodyVelocity(usize),
    BodyAngularVelocity(usize),
    BodyForce(usize),
    BodyTorque(usize),
    ProbeDensity(usize),
    ProbePressure(usize),
    ProbeVelocity(usize),
    ProbeCoverage(usize),
    Marker(usize),
    PatchMean(usize),
    PatchPeak(usize),
    PatchArea(usize),
    PatchForce(usize),
    /// Input: the pressure of case port k (its pressure is `external`).
    PortPressure(usize),
    /// Output: one value of case port k.
    Port(usize, PortOutput),
    Steps,
    Dt,
    Particles,
    FluidParticles,
    Mass,
    Momentum,
    Energy,
}

/// What a port output reports (see `sphfmu::coupling::PortValue`).
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum PortOutput {
    Pressure,
    MeanPressure,
    Velocity,
    VolumeFlow,
    MassFlow,
    MassIn,
    MassOut,
}

impl PortOutput {
    pub fn of(self, v: &sphfmu::coupling::PortValue) -> f64 {
        match self {
            PortOutput::Pressure => v.pressure,
            PortOutput::MeanPressure => v.mean_pressure,
            PortOutput::Velocity => v.velocity,
            PortOutput::VolumeFlow => v.volume_flow,
            PortOutput::MassFlow => v.mass_flow,
            PortOutput::MassIn => v.mass_in,
            PortOutput::MassOut => v.mass_out,
        }
    }
}

#[derive(Debug, Clone, PartialEq)]
pub enum Start {
    None,
    Float(Vec<f64>),
    Int(i64),
    Text(String),
}

#[derive(Debug, Clone, PartialEq)]
pub struct Variable {
    pub name: String,
    /// FMI 3.0 value reference (FMI 2.0 ones are in `Table::fmi2`).
    pub vr: u32,
    pub kind: Kind,
    pub causality: Causality,
    /// 1 or 3 (a 3-vector).
    pub size: usize,
    pub start: Start,
    pub unit: Option<&'static str>,
    pub description: String,
    pub binding: Binding,
}

impl Variable {
    pub fn is_discrete(&self) -> bool {
        self.kind != Kind::Float64
            || matches!(
                self.binding,
                Binding::Steps | Binding::Dt | Binding::Particles | Binding::FluidParticles
            )
    }
}

/// One FMI 2.0 scalar: element `element` of `variables[variable]`.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct Scalar2 {
    pub variable: usize,
    pub element: usize,
}

#[derive(Debug, Clone, PartialEq)]
pub struct Table {
    pub variables: Vec<Variable>,
    /// FMI 2.0 value reference r is `fmi2[r]`.
    pub fmi2: Vec<Scalar2>,
    pub dimension: usize,
    /// Bodies driven from outside (index into the case's bodies).
    pub external_bodies: Vec<usize>,
    /// Ports whose pressure is set from outside (index into the case's ports).
    pub external_ports: Vec<usize>,
}

fn pad3(v: &[f64]) -> Vec<f64> {
    (0..3).map(|k| v.get(k).copied().unwrap_or(0.0)).collect()
}

impl Table {
    /// The variables of `case` (as packaged; `case_file` is the `case` parameter's start).
    pub fn new(case: &Case, case_file: &str) -> Table {
        let d = case.case.dimension;
        let u = units(d);
        let mut v: Vec<Variable> = vec![];
        let mut add = |name: String,
                       kind: Kind,
                       causality: Causality,
                       size: usize,
                       start: Start,
                       unit: Option<&'static str>,
                       description: String,
                       binding: Binding| {
            let vr = v.len() as u32;
            v.push(Variable {
                name,
                vr,
                kind,
                causality,
                size,
                start,
                unit,
                description,
                binding,
            });
        };
        use Causality::*;
        add(
            "time".into(),
            Kind::Float64,
            Independent,
            1,
            Start::None,
            Some("s"),
            "Simulation time".into(),
            Binding::Time,
        );
        add("case".into(), Kind::String, Parameter, 1, Start::Text(case_file.into()), None,
            "Case file: a name in the FMU's resources/ folder or an absolute path; it must have the packaged case's bodies, probes, markers, patches and ports".into(),
            Binding::Param(Param::Case));
        add("scheme".into(), Kind::String, Parameter, 1, Start::Text(String::new()), None,
            "Scheme preset replacing the case's (with its own kernel and integrator): standard, rpsph, rosswog-f1..f4, crksph, compsph, compsph-cullen, psph; empty = the case's".into(),
            Binding::Param(Param::Scheme));
        add(
            "resolution".into(),
            Kind::Float64,
            Parameter,
            1,
            Start::Float(vec![1.0]),
            None,
            "Refinement factor on every particle spacing, in [0.1, 10] (2 = twice as fine)".into(),
            Binding::Param(Param::Resolution),
        );
        add(
            "cfl".into(),
            Kind::Float64,
            Parameter,
            1,
            Start::Float(vec![0.0]),
            None,
            "Courant factor in (0, 1]; 0 = the case's".into(),
            Binding::Param(Param::Cfl),
        );
        add(
            "threads".into(),
            Kind::Int64,
            Parameter,
            1,
            Start::Int(0),
            None,
            "Worker threads of this instance, in [0, 1024]; 0 = one per core".into(),
            Binding::Param(Param::Threads),
        );
        add(
            "output_dir".into(),
            Kind::String,
            Parameter,
            1,
            Start::Text(String::new()),
            None,
            "Folder for VTU snapshots of the particles and snapshots.pvd (ParaView); empty = none"
                .into(),
            Binding::Param(Param::OutputDir),
        );
        add(
            "output_interval".into(),
            Kind::Float64,
            Parameter,
            1,
            Start::Float(vec![0.0]),
            Some("s"),
            "Simulation time between snapshots, ≥ 0; 0 = after every doStep".into(),
            Binding::Param(Param::OutputInterval),
        );
        for (name, kind, start, description, which) in crate::zenoh_settings::parameter_rows() {
            let start = match kind {
                Kind::Float64 => Start::Float(vec![start.parse().expect("a number")]),
                _ => Start::Text(start.into()),
            };
            let unit = (kind == Kind::Float64).then_some("s");
            add(
                name.into(),
                kind,
                Parameter,
                1,
                start,
                unit,
                description.into(),
                Binding::Param(Param::Zenoh(which)),
            );
        }
        add("gravity".into(), Kind::Float64, Input, 3,
            Start::Float(pad3(case.gravity.as_deref().unwrap_or(&[]))), Some("m/s2"),
            format!("Uniform gravity (entries beyond the case's {d} dimensions must be 0), held between steps"),
            Binding::Gravity);
        let mut external_bodies = vec![];
        for (i, b) in case.bodies.iter().enumerate() {
            if b.motion != Motion::External {
                continue;
            }
            external_bodies.push(i);
            let n = &b.name;
            let r = pad3(b.reference.as_deref().unwrap_or(&[]));
            add(
                format!("{n}.position"),
                Kind::Float64,
                Input,
                3,
                Start::Float(r),
                Some("m"),
                format!("Position of body {n}'s reference point"),
                Binding::BodyPosition(i),
            );
            add(
                format!("{n}.angle"),
                Kind::Float64,
                Input,
                1,
                Start::Float(vec![0.0]),
                Some("rad"),
                format!("Rotation of body {n} about its axis (2D: about z)"),
                Binding::BodyAngle(i),
            );
            add(format!("{n}.velocity"), Kind::Float64, Input, 3, Start::Float(vec![0.0; 3]), Some("m/s"),
                format!("Velocity of body {n}'s reference point (the body moves on with it until the next step)"),
                Binding::BodyVelocity(i));
            add(
                format!("{n}.angular_velocity"),
                Kind::Float64,
                Input,
                1,
                Start::Float(vec![0.0]),
                Some("rad/s"),
                format!("Angular velocity of body {n} about its axis"),
                Binding::BodyAngularVelocity(i),
            );
        }
        for (i, b) in case.bodies.iter().enumerate() {
            let n = &b.name;
            add(
                format!("{n}.force"),
                Kind::Float64,
                Output,
                3,
                Start::None,
                Some(u.force),
                format!("Force of the fluid on body {n}"),
                Binding::BodyForce(i),
            );
            add(
                format!("{n}.torque"),
                Kind::Float64,
                Output,
                3,
                Start::None,
                Some(u.torque),
                format!(
                    "Torque of the fluid on body {n} about its moved reference point (2D: z only)"
                ),
                Binding::BodyTorque(i),
            );
        }
        for (i, p) in case.probes.iter().enumerate() {
            let n = &p.name;
            add(
                format!("probe.{n}.density"),
                Kind::Float64,
                Output,
                1,
                Start::None,
                Some("kg/m3"),
                format!("Fluid density at probe {n}"),
                Binding::ProbeDensity(i),
            );
            add(
                format!("probe.{n}.pressure"),
                Kind::Float64,
                Output,
                1,
                Start::None,
                Some("Pa"),
                format!("Fluid pressure at probe {n}"),
                Binding::ProbePressure(i),
            );
            add(
                format!("probe.{n}.velocity"),
                Kind::Float64,
                Output,
                3,
                Start::None,
                Some("m/s"),
                format!("Fluid velocity at probe {n}"),
                Binding::ProbeVelocity(i),
            );
            add(format!("probe.{n}.coverage"), Kind::Float64, Output, 1, Start::None, None,
                format!("Kernel coverage at probe {n}: about 1 in the fluid, 0 where no fluid reaches (values then 0)"),
                Binding::ProbeCoverage(i));
        }
        for (i, m) in case.markers.iter().enumerate() {
            add(
                format!("marker.{}.pressure", m.name),
                Kind::Float64,
                Output,
                1,
                Start::None,
                Some("Pa"),
                format!("Wall pressure at marker {} on body {}", m.name, m.body),
                Binding::Marker(i),
            );
        }
        for (i, pa) in case.patches.iter().enumerate() {
            let n = &pa.name;
            let outputs = [
                (
                    "mean_pressure",
                    1,
                    "Pa",
                    Binding::PatchMean(i),
                    "Mean wall pressure on patch {n} of body {b}",
                ),
                (
                    "peak_pressure",
                    1,
                    "Pa",
                    Binding::PatchPeak(i),
                    "Peak wall pressure on patch {n}",
                ),
                (
                    "area",
                    1,
                    u.area,
                    Binding::PatchArea(i),
                    "Area of patch {n}",
                ),
                (
                    "force",
                    3,
                    u.force,
                    Binding::PatchForce(i),
                    "Force of the fluid on patch {n}",
                ),
            ];
            for (suffix, size, unit, binding, description) in outputs {
                let description = description.replace("{n}", n).replace("{b}", &pa.body);
                add(
                    format!("patch.{n}.{suffix}"),
                    Kind::Float64,
                    Output,
                    size,
                    Start::None,
                    Some(unit),
                    description,
                    binding,
                );
            }
        }
        let mut external_ports = vec![];
        for (i, p) in case.ports.iter().enumerate() {
            let n = &p.name;
            if let PortPressure::External { initial } = p.pressure {
                external_ports.push(i);
                add(format!("port.{n}.pressure"), Kind::Float64, Input, 1,
                    Start::Float(vec![initial]), Some("Pa"),
                    format!("Pressure at port {n} (gauge of the case's EOS, finite and ≥ 0), held between steps"),
                    Binding::PortPressure(i));
            }
            use PortOutput::*;
            let outputs = [
                ("pressure_set", "Pa", Pressure, "Pressure in force at port {n} (the input or the case's function)"),
                ("mean_pressure", "Pa", MeanPressure, "Mean fluid pressure across the opening of port {n}"),
                ("velocity", "m/s", Velocity, "Mean velocity through port {n} along its normal (positive into the fluid)"),
                ("volume_flow", u.volume_flow, VolumeFlow, "Volume flow into the fluid through port {n} (sampled on the opening)"),
                ("mass_flow", u.mass_flow, MassFlow, "Mass flow into the fluid through port {n} (sampled on the opening)"),
                ("mass_in", u.mass, MassIn, "Fluid mass that entered through port {n} since the start (exact: particles counted as they cross)"),
                ("mass_out", u.mass, MassOut, "Fluid mass that left through port {n} since the start (exact)"),
            ];
            for (suffix, unit, what, description) in outputs {
                add(
                    format!("port.{n}.{suffix}"),
                    Kind::Float64,
                    Output,
                    1,
                    Start::None,
                    Some(unit),
                    description.replace("{n}", n),
                    Binding::Port(i, what),
                );
            }
        }
        add(
            "diag.steps".into(),
            Kind::Int64,
            Output,
            1,
            Start::None,
            None,
            "Solver steps since the start".into(),
            Binding::Steps,
        );
        add(
            "diag.dt".into(),
            Kind::Float64,
            Output,
            1,
            Start::None,
            Some("s"),
            "Latest internal time step".into(),
            Binding::Dt,
        );
        add(
            "diag.particles".into(),
            Kind::Int64,
            Output,
            1,
            Start::None,
            None,
            "Particles (fluid, wall and port buffer)".into(),
            Binding::Particles,
        );
        add(
            "diag.fluid_particles".into(),
            Kind::Int64,
            Output,
            1,
            Start::None,
            None,
            "Fluid particles (ports create and delete them)".into(),
            Binding::FluidParticles,
        );
        add(
            "diag.mass".into(),
            Kind::Float64,
            Output,
            1,
            Start::None,
            Some(u.mass),
            "Fluid mass".into(),
            Binding::Mass,
        );
        add(
            "diag.momentum".into(),
            Kind::Float64,
            Output,
            3,
            Start::None,
            Some(u.momentum),
            "Fluid momentum".into(),
            Binding::Momentum,
        );
        add(
            "diag.energy".into(),
            Kind::Float64,
            Output,
            1,
            Start::None,
            Some(u.energy),
            "Fluid kinetic plus internal energy".into(),
            Binding::Energy,
        );
        let mut fmi2 = vec![];
        for (i, var) in v.iter().enumerate() {
            for element in 0..var.size {
                fmi2.push(Scalar2 {
                    variable: i,
                    element,
                });
            }
        }
        Table {
            variables: v,
            fmi2,
            dimension: d,
            external_bodies,
            external_ports,
        }
    }

    /// Position of case port `port` among those with an external pressure (they have inputs).
    pub fn external_port_index(&self, port: usize) -> usize {
        self.external_ports
            .iter()
            .position(|&x| x == port)
            .expect("inputs exist only for externally driven ports")
    }

    /// Position of case body `body` among the externally driven ones (those have inputs).
    pub fn external_index(&self, body: usize) -> usize {
        self.external_bodies
            .iter()
            .position(|&x| x == body)
            .expect("inputs exist only for externally driven bodies")
    }

    /// The FMI 2.0 name of a scalar.
    pub fn fmi2_name(&self, s: &Scalar2) -> String {
        let v = &self.variables[s.variable];
        if v.size == 1 {
            v.name.clone()
        } else {
            format!("{}[{}]", v.name, s.element + 1)
        }
    }

    /// Whether another case can run behind this table: same dimension, bodies (names, and
    /// which are driven from outside), probes and markers. The reason when not.
    pub fn accepts(&self, packaged: &Case, other: &Case) -> Result<(), String> {
        let sig = |c: &Case| {
            (
                c.case.dimension,
                c.bodies
                    .iter()
                    .map(|b| (b.name.clone(), b.motion == Motion::External))
                    .collect::<Vec<_>>(),
                c.probes.iter().map(|p| p.name.clone()).collect::<Vec<_>>(),
                c.markers
                    .iter()
                    .map(|m| m.name.clone())
                    .chain(c.patches.iter().map(|p| format!("patch {}", p.name)))
                    .chain(c.ports.iter().map(|p| {
                        let ext = matches!(p.pressure, PortPressure::External { .. });
                        format!("port {} (external: {ext})", p.name)
                    }))
                    .collect::<Vec<_>>(),
            )
        };
        let (a, b) = (sig(packaged), sig(other));
        if a.0 != b.0 {
            return Err(format!(
                "dimension {} (the FMU was packaged for {})",
                b.0, a.0
            ));
        }
        if a.1 != b.1 {
            return Err(format!(
                "bodies (name, driven from outside) {:?}; the FMU's variables are for {:?}",
                b.1, a.1
            ));
        }
        if a.2 != b.2 || a.3 != b.3 {
            return Err(format!(
                "probes {:?} and markers, patches and ports {:?}; the FMU's variables are for {:?} and {:?}",
                b.2, b.3, a.2, a.3
            ));
        }
        Ok(())
    }
}
