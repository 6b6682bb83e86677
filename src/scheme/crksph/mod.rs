//! CRKSPH (Frontiere, Raskin & Owen 2017; spec `crksph.md`). This module holds the reproducing
//! kernel machinery (§2); the evolution equations, compatible energy and limited viscosity
//! (§3–7) build on it.

pub mod forces;
pub mod reproducing;
pub mod viscosity;
