//! Every integration test in one binary. Each test file used to be its own binary, and each
//! compiled the solver's generic code (monomorphised per dimension and scheme) again at
//! opt-level 3: 22 binaries took about 11 of a cold build's minutes on 2 cores. Filter as
//! before by module: `cargo test --release --test all -- sod::` (or any part of a test name).

mod common;

mod bench_table;
mod bodies;
mod case_errors;
mod case_size;
mod conservation;
mod coupling;
mod crk_reproducing;
mod crksph;
mod cullen;
mod dambreak;
mod eos;
mod fields;
mod frame;
mod glass;
mod initial_states;
mod kernel_choice;
mod kernels;
mod lattice;
mod neighbours;
mod parallel;
mod ports;
mod riemann;
mod rosswog;
mod rosswog_static;
mod rpsph;
mod six_dof;
mod sod;
mod sr;
mod suite_small;
mod viscosity;
mod wall_schemes;
