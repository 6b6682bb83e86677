//! Boundaries beyond periodic and mirror walls (issue 5): rigid bodies made of wall particles,
//! their shapes ([`geometry`]) and motions ([`kinematics`]), and the non-inertial frame
//! ([`frame`]).

pub mod bodies;
pub mod frame;
pub mod geometry;
pub mod kinematics;
