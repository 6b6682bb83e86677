//! Boundaries beyond periodic and mirror walls (issue 5): rigid bodies made of wall particles,
//! their shapes ([`geometry`]) and motions ([`kinematics`]), and the non-inertial frame
//! ([`frame`]); and the pressure ports that open a body to an outside model ([`ports`]).

pub mod bodies;
pub mod drive;
pub mod frame;
pub mod geometry;
pub mod kinematics;
pub mod ports;
