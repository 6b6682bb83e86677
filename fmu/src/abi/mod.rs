//! The C ABI: the FMI 3.0 and FMI 2.0 entry points (`fmi3.rs`, `fmi2.rs`), the FMU-state
//! calls both share (`state_ffi.rs`), and what every entry point goes through (`ffi.rs`):
//! NULL checks, C strings and arrays, panic containment, and the logging of every rejected
//! call with its function's name. No logic of the model lives here.

pub mod ffi;
pub mod fmi2;
pub mod fmi3;
pub mod state_ffi;
