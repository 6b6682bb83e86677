//! Units of the FMU's variables: the core's per-dimension units (`sphfmu::units`: a 2D case
//! is per metre of depth, a 1D case per square metre), every unit with its SI exponents for
//! `<UnitDefinitions>`, and the `quantity` of each variable.

pub(crate) use sphfmu::units::units;

/// Every unit a table may use, with its SI base-unit exponents (kg, m, s), for
/// `<UnitDefinitions>`.
pub const UNITS: &[(&str, [i32; 3])] = &[
    ("s", [0, 0, 1]),
    ("m", [0, 1, 0]),
    ("m/s", [0, 1, -1]),
    ("m/s2", [0, 1, -2]),
    ("rad", [0, 0, 0]),
    ("1", [0, 0, 0]),
    ("m2", [0, 2, 0]),
    ("rad/s", [0, 0, -1]),
    ("rad/s2", [0, 0, -2]),
    ("Pa", [1, -1, -2]),
    ("kg/m3", [1, -3, 0]),
    ("N/m2", [1, -1, -2]),
    ("N/m", [1, 0, -2]),
    ("N", [1, 1, -2]),
    ("N.m", [1, 2, -2]),
    ("kg/m2", [1, -2, 0]),
    ("kg/m", [1, -1, 0]),
    ("kg", [1, 0, 0]),
    ("kg/(m.s)", [1, -1, -1]),
    ("kg/(m2.s)", [1, -2, -1]),
    ("m2/s", [0, 2, -1]),
    ("m3/s", [0, 3, -1]),
    ("kg/s", [1, 0, -1]),
    ("kg.m/s", [1, 1, -1]),
    ("J/m2", [1, 0, -2]),
    ("J/m", [1, 1, -2]),
    ("J", [1, 2, -2]),
];

/// The `quantity` attribute of a variable (FMI 3.0 §2.4.7.4, FMI 2.0 §2.2.7: a free name of
/// the physical quantity, which a tool may use to check connections besides the unit).
/// Extensive quantities of a 2D case are per metre of depth and those of a 1D case per
/// square metre, so they carry that in the name (`ForcePerDepth`), as in the unit (`N/m`):
/// a tool must not connect a 2D force to a 3D model's force without the depth.
pub(crate) fn quantity(binding: &crate::table::Binding, dimension: usize) -> Option<String> {
    use crate::table::{Binding as B, MotionInput as M, Param, PortOutput as P};
    let (name, extensive) = match binding {
        B::Time | B::Dt | B::Param(Param::OutputInterval) => ("Time", false),
        B::Gravity => ("Acceleration", false),
        B::Motion(_, m) => match m {
            M::Position => ("Length", false),
            M::Angle => ("Angle", false),
            M::Quaternion | M::Matrix => ("Orientation", false),
            M::Velocity => ("Velocity", false),
            M::AngularVelocity => ("AngularVelocity", false),
            M::Acceleration => ("Acceleration", false),
            M::AngularAcceleration => ("AngularAcceleration", false),
        },
        B::ProbeVelocity(_) | B::Port(_, P::Velocity) => ("Velocity", false),
        B::BodyForce(_) | B::BodyForceBody(_) | B::PatchForce(_) => ("Force", true),
        B::BodyTorque(_) | B::BodyTorqueBody(_) => ("Torque", true),
        B::ProbeDensity(_) => ("Density", false),
        B::ProbePressure(_)
        | B::Marker(_)
        | B::PatchMean(_)
        | B::PatchPeak(_)
        | B::PortPressure(_)
        | B::Port(_, P::Pressure | P::MeanPressure) => ("Pressure", false),
        B::PatchArea(_) => ("Area", true),
        B::Port(_, P::VolumeFlow) => ("VolumeFlowRate", true),
        B::Port(_, P::MassFlow) => ("MassFlowRate", true),
        B::Port(_, P::MassIn | P::MassOut) | B::Mass => ("Mass", true),
        B::Momentum => ("Momentum", true),
        B::Energy => ("Energy", true),
        _ => return None,
    };
    Some(match (extensive, dimension) {
        (true, 2) => format!("{name}PerDepth"),
        (true, 1) => format!("{name}PerArea"),
        _ => name.to_string(),
    })
}
