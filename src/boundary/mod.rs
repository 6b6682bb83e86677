//! Boundaries beyond periodic and mirror walls (issue 5): rigid bodies made of wall particles,
//! their shapes ([`geometry`]) and motions ([`kinematics`]).

pub mod bodies;
pub mod geometry;
pub mod kinematics;
