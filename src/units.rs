//! Units of what the solver reports, by dimension. The solver is unit-consistent: it takes
//! whatever consistent units a case uses. The liquid and body cases of `models/` are in SI
//! (m, kg, s, Pa, N), so every label (CSV headers, plot axes, CLI summaries, FMU variables)
//! is written in SI; the gas test problems (Sod, Noh, Sedov, Gresho) use the papers'
//! dimensionless units, in which the same labels read as "consistent units".
//!
//! A 2D case is a slice of unit depth: its extensive quantities are per metre of depth
//! (force N/m, mass kg/m, energy J/m); a 1D case is a column of unit cross-section (per
//! square metre). Intensive ones (pressure Pa, density kg/m3, velocity m/s) are the same in
//! every dimension.

/// Units by dimension: a 2D case is per metre of depth.
pub struct Units {
    pub area: &'static str,
    pub volume_flow: &'static str,
    pub mass_flow: &'static str,
    pub force: &'static str,
    pub torque: &'static str,
    pub mass: &'static str,
    pub momentum: &'static str,
    pub angular_momentum: &'static str,
    pub energy: &'static str,
}

pub fn units(dimension: usize) -> Units {
    match dimension {
        1 => Units {
            area: "1",
            volume_flow: "m/s",
            mass_flow: "kg/(m2.s)",
            force: "N/m2",
            torque: "N/m",
            mass: "kg/m2",
            momentum: "kg/(m.s)",
            angular_momentum: "kg/s",
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
            angular_momentum: "kg.m/s",
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
            angular_momentum: "kg.m2/s",
            energy: "J",
        },
    }
}
