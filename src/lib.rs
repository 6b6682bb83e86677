//! sphfmu: a smoothed-particle hydrodynamics solver for co-simulation.
//!
//! One core, three faces (CLI, FMU, zenoh). Data flows one way: a case file
//! ([`case`]) becomes a [`sim::Simulation`]; the simulation steps; the faces read its outputs.

pub mod bench;
pub mod boundary;
pub mod case;
pub mod coupling;
pub mod domain;
pub mod eos;
pub mod integrate;
pub mod io;
pub mod kernel;
mod monomorphic;
pub mod neighbours;
pub mod parallel;
pub mod particles;
pub mod runner;
pub mod scheme;
pub mod scratch;
pub mod sim;
pub mod system;
pub mod threads;
pub mod units;
pub mod verify;
