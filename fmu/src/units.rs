//! Units of the FMU's variables: per dimension (a 2D case is per metre of depth, a 1D case
//! per square metre), and every unit with its SI exponents for `<UnitDefinitions>`.

/// Units by dimension: a 2D case is per metre of depth.
pub(crate) struct Units {
    pub area: &'static str,
    pub volume_flow: &'static str,
    pub mass_flow: &'static str,
    pub force: &'static str,
    pub torque: &'static str,
    pub mass: &'static str,
    pub momentum: &'static str,
    pub energy: &'static str,
}

pub(crate) fn units(dimension: usize) -> Units {
    match dimension {
        1 => Units {
            area: "1",
            volume_flow: "m/s",
            mass_flow: "kg/(m2.s)",
            force: "N/m2",
            torque: "N/m",
            mass: "kg/m2",
            momentum: "kg/(m.s)",
            energy: "J/m2",
        },
        2 => Units {
            area: "m",
            volume_flow: "m2/s",
            mass_flow: "kg/(m.s)",
            force: "N/m",
            torque: "N",
            mass: "kg/m",
            momentum: "kg/s",
            energy: "J/m",
        },
        _ => Units {
            area: "m2",
            volume_flow: "m3/s",
            mass_flow: "kg/s",
            force: "N",
            torque: "N.m",
            mass: "kg",
            momentum: "kg.m/s",
            energy: "J",
        },
    }
}

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
