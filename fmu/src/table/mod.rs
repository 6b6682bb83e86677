//! The one table of FMU variables. Both modelDescription.xml files are written from it and
//! every getter and setter dispatches through it, so the XML and the binary cannot disagree.
//! It is a function of the packaged case (its dimension, bodies, probes, markers, patches and ports).
//!
//! FMI 3.0 sees 3-vectors as arrays (`<Dimension start="3"/>`, one value reference); FMI 2.0
//! sees them flattened to `name[1]`, `name[2]`, `name[3]` (structured naming convention),
//! each with its own value reference.

mod rows;
pub mod units;

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
    Zenoh(crate::bridge::settings::ZenohParam),
    Limit(crate::instance::limits::LimitParam),
}

/// What a variable reads or writes.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Binding {
    Time,
    Param(Param),
    Gravity,
    /// Input: one part of the motion of an externally driven body or frame.
    Motion(Mover, MotionInput),
    BodyForce(usize),
    BodyTorque(usize),
    BodyForceBody(usize),
    BodyTorqueBody(usize),
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

/// What a master moves: case body k, or the case's frame.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Mover {
    Body(usize),
    Frame,
}

/// The parts of a rigid motion a master sets (`sphfmu::coupling::BodyKinematics`).
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum MotionInput {
    Position,
    /// 2D and 1D: the angle about z.
    Angle,
    /// 3D: a unit quaternion [w, x, y, z].
    Quaternion,
    /// 3D: Modelica's R.T, row major.
    Matrix,
    Velocity,
    /// 3D: 3 entries in world axes; 2D: the z entry alone.
    AngularVelocity,
    Acceleration,
    /// As `AngularVelocity`.
    AngularAcceleration,
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
    /// 1, or an array's length (3-vectors; 4 for a quaternion, 9 for a rotation matrix).
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
    /// Their names and the form of their orientation input (same order).
    pub external_forms: Vec<(String, crate::instance::inputs::OrientationForm)>,
    /// The form of the frame's orientation input, when the case's frame is driven from outside.
    pub frame_form: Option<crate::instance::inputs::OrientationForm>,
    /// Ports whose pressure is set from outside (index into the case's ports).
    pub external_ports: Vec<usize>,
}

impl Table {
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

    /// The name and orientation form of a body or the frame driven from outside.
    pub fn form_of(&self, m: Mover) -> (&str, crate::instance::inputs::OrientationForm) {
        match m {
            Mover::Body(b) => {
                let (name, form) = &self.external_forms[self.external_index(b)];
                (name, *form)
            }
            Mover::Frame => (
                "frame",
                self.frame_form.expect("the table has frame inputs"),
            ),
        }
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
                    .map(|b| {
                        let external = b.motion == Motion::External;
                        (b.name.clone(), external, external.then_some(b.orientation))
                    })
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
        let frame = |c: &Case| {
            c.frame
                .as_ref()
                .map(|f| (f.motion == Motion::External, f.orientation))
        };
        if frame(packaged) != frame(other) {
            return Err(format!(
                "a frame (driven from outside, orientation input) {:?}; the FMU's variables are for {:?}",
                frame(other),
                frame(packaged)
            ));
        }
        let (a, b) = (sig(packaged), sig(other));
        if a.0 != b.0 {
            return Err(format!(
                "dimension {} (the FMU was packaged for {})",
                b.0, a.0
            ));
        }
        if a.1 != b.1 {
            return Err(format!(
                "bodies (name, driven from outside, orientation input) {:?}; the FMU's variables are for {:?}",
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
