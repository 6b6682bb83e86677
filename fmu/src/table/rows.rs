//! The rows of the variable table, in value-reference order: parameters, inputs, then the
//! outputs of bodies, probes, markers, patches and ports, and the diagnostics.

use super::*;
use crate::instance::inputs::OrientationForm;
use crate::table::units::units;
use sphfmu::boundary::kinematics::Motion;
use sphfmu::boundary::ports::PortPressure;
use sphfmu::case::bodies::OrientationInput;

fn pad3(v: &[f64]) -> Vec<f64> {
    (0..3).map(|k| v.get(k).copied().unwrap_or(0.0)).collect()
}

/// The table's rows in the order they are added (the value references).
struct Rows(Vec<Variable>);

impl Rows {
    #[allow(clippy::too_many_arguments)]
    fn add(
        &mut self,
        name: impl Into<String>,
        kind: Kind,
        causality: Causality,
        size: usize,
        start: Start,
        unit: Option<&'static str>,
        description: impl Into<String>,
        binding: Binding,
    ) {
        let vr = self.0.len() as u32;
        self.0.push(Variable {
            name: name.into(),
            vr,
            kind,
            causality,
            size,
            start,
            unit,
            description: description.into(),
            binding,
        });
    }

    /// A scalar parameter.
    fn param(
        &mut self,
        name: &str,
        kind: Kind,
        start: Start,
        unit: Option<&'static str>,
        description: &str,
        param: Param,
    ) {
        let c = Causality::Parameter;
        self.add(
            name,
            kind,
            c,
            1,
            start,
            unit,
            description,
            Binding::Param(param),
        );
    }

    /// A Float64 input of `start.len()` entries.
    fn input(
        &mut self,
        name: String,
        start: Vec<f64>,
        unit: &'static str,
        description: String,
        binding: Binding,
    ) {
        let (size, start) = (start.len(), Start::Float(start));
        let c = Causality::Input;
        self.add(
            name,
            Kind::Float64,
            c,
            size,
            start,
            Some(unit),
            description,
            binding,
        );
    }

    /// A Float64 output of `size` entries.
    fn output(
        &mut self,
        name: String,
        size: usize,
        unit: Option<&'static str>,
        description: String,
        binding: Binding,
    ) {
        let (c, s) = (Causality::Output, Start::None);
        self.add(name, Kind::Float64, c, size, s, unit, description, binding);
    }
}

impl Rows {
    /// The inputs of a rigid motion set from outside (`<n>.position`, its orientation in the
    /// form the case chose, `.velocity`, `.angular_velocity`, `.acceleration`,
    /// `.angular_acceleration`); `what` names the mover in descriptions.
    #[allow(clippy::too_many_arguments)]
    fn motion_inputs(
        &mut self,
        n: &str,
        what: &str,
        mover: Mover,
        d: usize,
        orientation: OrientationInput,
        reference: Vec<f64>,
    ) -> OrientationForm {
        let m = |input| Binding::Motion(mover, input);
        self.input(
            format!("{n}.position"),
            reference,
            "m",
            format!("Position of {what}'s reference point"),
            m(MotionInput::Position),
        );
        let form = match (d, orientation) {
            (1 | 2, _) => OrientationForm::Angle,
            (_, OrientationInput::Quaternion) => OrientationForm::Quaternion,
            (_, OrientationInput::Matrix) => OrientationForm::Matrix,
        };
        match form {
            OrientationForm::Angle => self.input(format!("{n}.angle"), vec![0.0], "rad",
                format!("Rotation of {what} about z"), m(MotionInput::Angle)),
            OrientationForm::Quaternion => self.input(format!("{n}.orientation"),
                sphfmu::coupling::orientation::IDENTITY.to_vec(), "1",
                format!("Orientation of {what}: unit quaternion [w, x, y, z] turning its axes into world axes (renormalised within 1e-6 of unit length, refused beyond)"),
                m(MotionInput::Quaternion)),
            OrientationForm::Matrix => self.input(format!("{n}.T"),
                sphfmu::coupling::orientation::IDENTITY_T.to_vec(), "1",
                format!("Orientation of {what} as Modelica MultiBody's R.T (row major; rows are its axes in world coordinates, v_local = T v_world; orthonormal within 1e-6, det +1)"),
                m(MotionInput::Matrix)),
        }
        self.input(
            format!("{n}.velocity"),
            vec![0.0; 3],
            "m/s",
            format!("Velocity of {what}'s reference point"),
            m(MotionInput::Velocity),
        );
        let (omega, about) = if d == 3 {
            (vec![0.0; 3], "in world axes")
        } else {
            (vec![0.0], "about z")
        };
        self.input(
            format!("{n}.angular_velocity"),
            omega.clone(),
            "rad/s",
            format!("Angular velocity of {what} {about}"),
            m(MotionInput::AngularVelocity),
        );
        self.input(format!("{n}.acceleration"), vec![0.0; 3], "m/s2",
            format!("Acceleration of {what}'s reference point over the next step (0: it moves on at constant velocity; a trapezoidal master gives (v1 - v0)/H)"),
            m(MotionInput::Acceleration));
        self.input(
            format!("{n}.angular_acceleration"),
            omega,
            "rad/s2",
            format!("Angular acceleration of {what} {about} over the next step"),
            m(MotionInput::AngularAcceleration),
        );
        form
    }
}

impl Table {
    /// The variables of `case` (as packaged; `case_file` is the `case` parameter's start).
    pub fn new(case: &Case, case_file: &str) -> Table {
        let d = case.case.dimension;
        let u = units(d);
        let mut v = Rows(vec![]);
        let (float, text) = (
            |x: f64| Start::Float(vec![x]),
            |t: &str| Start::Text(t.into()),
        );
        v.add(
            "time",
            Kind::Float64,
            Causality::Independent,
            1,
            Start::None,
            Some("s"),
            "Simulation time",
            Binding::Time,
        );
        v.param("case", Kind::String, text(case_file), None,
            "Case file: a name in the FMU's resources/ folder or an absolute path; it must have the packaged case's bodies, probes, markers, patches and ports",
            Param::Case);
        v.param("scheme", Kind::String, text(""), None,
            "Scheme preset replacing the case's (with its own kernel and integrator): standard, rpsph, rosswog-f1..f4, crksph, compsph, compsph-cullen, psph; empty = the case's",
            Param::Scheme);
        v.param(
            "resolution",
            Kind::Float64,
            float(1.0),
            None,
            "Refinement factor on every particle spacing, in [0.1, 10] (2 = twice as fine)",
            Param::Resolution,
        );
        v.param(
            "cfl",
            Kind::Float64,
            float(0.0),
            None,
            "Courant factor in (0, 1]; 0 = the case's",
            Param::Cfl,
        );
        v.param(
            "threads",
            Kind::Int64,
            Start::Int(0),
            None,
            "Worker threads of this instance, in [0, 1024]; 0 = one per core",
            Param::Threads,
        );
        v.param(
            "output_dir",
            Kind::String,
            text(""),
            None,
            "Folder for VTU snapshots of the particles and snapshots.pvd (ParaView); empty = none",
            Param::OutputDir,
        );
        v.param(
            "output_interval",
            Kind::Float64,
            float(0.0),
            Some("s"),
            "Simulation time between snapshots, ≥ 0; 0 = after every doStep",
            Param::OutputInterval,
        );
        for (name, which, integer, unit, description) in crate::instance::limits::ROWS {
            let (kind, start) = if integer {
                (Kind::Int64, Start::Int(0))
            } else {
                (Kind::Float64, float(0.0))
            };
            v.param(name, kind, start, unit, description, Param::Limit(which));
        }
        for (name, kind, start, description, which) in crate::bridge::settings::parameter_rows() {
            let start = match kind {
                Kind::Float64 => float(start.parse().expect("a number")),
                _ => text(start),
            };
            let unit = (kind == Kind::Float64).then_some("s");
            v.param(name, kind, start, unit, description, Param::Zenoh(which));
        }
        v.input("gravity".into(), pad3(case.gravity.as_deref().unwrap_or(&[])), "m/s2",
            format!("Uniform gravity (entries beyond the case's {d} dimensions must be 0), held between steps"),
            Binding::Gravity);
        let mut external_bodies = vec![];
        let mut external_forms = vec![];
        for (i, b) in case.bodies.iter().enumerate() {
            if b.motion != Motion::External {
                continue;
            }
            external_bodies.push(i);
            let reference = pad3(b.reference.as_deref().unwrap_or(&[]));
            let form = v.motion_inputs(
                &b.name,
                &format!("body {}", b.name),
                Mover::Body(i),
                d,
                b.orientation,
                reference,
            );
            external_forms.push((b.name.clone(), form));
        }
        let frame_form = case
            .frame
            .as_ref()
            .filter(|f| f.motion == Motion::External)
            .map(|f| {
                let reference = pad3(f.reference.as_deref().unwrap_or(&[]));
                v.motion_inputs(
                    "frame",
                    "the frame",
                    Mover::Frame,
                    d,
                    f.orientation,
                    reference,
                )
            });
        for (i, b) in case.bodies.iter().enumerate() {
            let n = &b.name;
            v.output(
                format!("{n}.force"),
                3,
                Some(u.force),
                format!("Force of the fluid on body {n}"),
                Binding::BodyForce(i),
            );
            v.output(
                format!("{n}.torque"),
                3,
                Some(u.torque),
                format!(
                    "Torque of the fluid on body {n} about its moved reference point (2D: z only)"
                ),
                Binding::BodyTorque(i),
            );
            v.output(
                format!("{n}.force_body"),
                3,
                Some(u.force),
                format!("Force of the fluid on body {n} in the body's own axes"),
                Binding::BodyForceBody(i),
            );
            v.output(
                format!("{n}.torque_body"),
                3,
                Some(u.torque),
                format!("Torque of the fluid on body {n} about its moved reference point, in the body's own axes"),
                Binding::BodyTorqueBody(i),
            );
        }
        for (i, p) in case.probes.iter().enumerate() {
            let n = &p.name;
            v.output(
                format!("probe.{n}.density"),
                1,
                Some("kg/m3"),
                format!("Fluid density at probe {n}"),
                Binding::ProbeDensity(i),
            );
            v.output(
                format!("probe.{n}.pressure"),
                1,
                Some("Pa"),
                format!("Fluid pressure at probe {n}"),
                Binding::ProbePressure(i),
            );
            v.output(
                format!("probe.{n}.velocity"),
                3,
                Some("m/s"),
                format!("Fluid velocity at probe {n}"),
                Binding::ProbeVelocity(i),
            );
            v.output(format!("probe.{n}.coverage"), 1, None,
                format!("Kernel coverage at probe {n}: about 1 in the fluid, 0 where no fluid reaches (values then 0)"),
                Binding::ProbeCoverage(i));
        }
        for (i, m) in case.markers.iter().enumerate() {
            v.output(
                format!("marker.{}.pressure", m.name),
                1,
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
                v.output(
                    format!("patch.{n}.{suffix}"),
                    size,
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
                v.input(format!("port.{n}.pressure"), vec![initial], "Pa",
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
                v.output(
                    format!("port.{n}.{suffix}"),
                    1,
                    Some(unit),
                    description.replace("{n}", n),
                    Binding::Port(i, what),
                );
            }
        }
        let diagnostics = [
            (
                "diag.steps",
                Kind::Int64,
                1,
                None,
                "Solver steps since the start",
                Binding::Steps,
            ),
            (
                "diag.dt",
                Kind::Float64,
                1,
                Some("s"),
                "Latest internal time step",
                Binding::Dt,
            ),
            (
                "diag.particles",
                Kind::Int64,
                1,
                None,
                "Particles (fluid, wall and port buffer)",
                Binding::Particles,
            ),
            (
                "diag.fluid_particles",
                Kind::Int64,
                1,
                None,
                "Fluid particles (ports create and delete them)",
                Binding::FluidParticles,
            ),
            (
                "diag.mass",
                Kind::Float64,
                1,
                Some(u.mass),
                "Fluid mass",
                Binding::Mass,
            ),
            (
                "diag.momentum",
                Kind::Float64,
                3,
                Some(u.momentum),
                "Fluid momentum",
                Binding::Momentum,
            ),
            (
                "diag.energy",
                Kind::Float64,
                1,
                Some(u.energy),
                "Fluid kinetic + internal + potential energy in gravity (2D: per metre of depth)",
                Binding::Energy,
            ),
        ];
        for (name, kind, size, unit, description, binding) in diagnostics {
            v.add(
                name,
                kind,
                Causality::Output,
                size,
                Start::None,
                unit,
                description,
                binding,
            );
        }
        let v = v.0;
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
            external_forms,
            frame_form,
            external_ports,
        }
    }
}
