//! The solver compiled once per dimension, in this crate.
//!
//! rustc compiles a generic function in every crate that calls it: a release build does not
//! share one crate's instances of a generic function with another (`-Z share-generics` is
//! off outside debug builds). The solver is generic over the dimension D, so each crate that
//! built and stepped a `Simulation<D>` (the CLI binary, the integration tests) compiled every
//! scheme's passes for every kernel and dimension again. In a cold `make test` that was
//! 182 s for the `sphfmu` binary and 199 s for the integration tests, against 221 s for the
//! library itself (`cargo test --release --workspace --features sphfmu/mpi --no-run
//! --timings`, 2 cores).
//!
//! The entry points that reach the schemes (building a scheme and a system, a step, a
//! re-evaluation) therefore hand their work to a non-generic function per dimension,
//! compiled here ([`d1`], [`d2`], [`d3`]). The generic entry point that picks one is a few
//! lines, and it is all a calling crate compiles.

use crate::case::{Case, CaseError};
use crate::scheme::{Scheme, SchemeConfig};
use crate::sim::{Simulation, SolverError};
use crate::system::System;
use std::any::Any;

/// `x` as the type `To` it is: the callers below name `To` with the same D as `x`'s type.
fn same<From: 'static, To: 'static>(x: From) -> To {
    let mut slot = Some(x);
    (&mut slot as &mut dyn Any)
        .downcast_mut::<Option<To>>()
        .and_then(Option::take)
        .expect("the same type in the same dimension")
}

/// [`same`] for a mutable borrow.
fn same_mut<From: 'static, To: 'static>(x: &mut From) -> &mut To {
    (x as &mut dyn Any)
        .downcast_mut::<To>()
        .expect("the same type in the same dimension")
}

/// The instances for one dimension: each function is the generic one it calls, at D.
macro_rules! compiled_in {
    ($($module:ident = $d:literal),*) => {$(
        #[doc = concat!("The solver's entry points in ", stringify!($d), "D.")]
        mod $module {
            use super::*;
            const D: usize = $d;
            #[inline(never)]
            pub fn scheme(config: &SchemeConfig) -> Box<dyn Scheme<D>> {
                config.build_generic::<D>()
            }
            #[inline(never)]
            pub fn system(case: &Case) -> Result<System<D>, CaseError> {
                case.system_generic::<D>()
            }
            #[inline(never)]
            pub fn step_with(
                sim: &mut Simulation<D>,
                stable: (f64, bool),
                dt_cap: f64,
            ) -> Result<f64, SolverError> {
                sim.step_with_generic(stable, dt_cap)
            }
            #[inline(never)]
            pub fn reevaluate(sim: &mut Simulation<D>) -> Result<(), SolverError> {
                sim.reevaluate_generic()
            }
        }
    )*};
}
compiled_in!(d1 = 1, d2 = 2, d3 = 3);

/// `$f(args)` from the module of dimension `D` (a const generic in scope), its result cast
/// back to the caller's types (arguments that name D are cast by the caller with
/// [`same_mut`]).
macro_rules! pick {
    ($f:ident($($a:expr),*)) => {
        match D {
            1 => same(d1::$f($($a),*)),
            2 => same(d2::$f($($a),*)),
            3 => same(d3::$f($($a),*)),
            d => panic!("dimension {d}: the solver is built for 1, 2 and 3"),
        }
    };
}

pub(crate) fn scheme<const D: usize>(config: &SchemeConfig) -> Box<dyn Scheme<D>> {
    pick!(scheme(config))
}

pub(crate) fn system<const D: usize>(case: &Case) -> Result<System<D>, CaseError> {
    pick!(system(case))
}

pub(crate) fn step_with<const D: usize>(
    sim: &mut Simulation<D>,
    stable: (f64, bool),
    dt_cap: f64,
) -> Result<f64, SolverError> {
    pick!(step_with(same_mut(sim), stable, dt_cap))
}

pub(crate) fn reevaluate<const D: usize>(sim: &mut Simulation<D>) -> Result<(), SolverError> {
    pick!(reevaluate(same_mut(sim)))
}
