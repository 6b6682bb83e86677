//! sphfmu as an FMU: the FMI 3.0 and FMI 2.0 co-simulation C APIs over the library's
//! `Coupling` interface, hand-written (rust-fmi's exporter is FMI 3.0 only and aborts on FMU
//! state calls with `todo!()`: crates.io fmi-export 0.3.0, checked 2026). One binary exports both APIs; the packager
//! (`src/bin/package.rs`, `make fmu`) writes `sphfmu.fmu` (3.0) and `sphfmu-fmi2.fmu` (2.0)
//! around it.
//!
//! No global mutable state: everything lives in the instance the master holds, each with its
//! own rayon pool; every entry point catches panics.

// The crate's rooms: the C faces, one instance behind them, the variable table, the
// packaging of .fmu archives, and the zenoh bridge.
pub mod abi;
pub mod bridge;
pub mod instance;
pub mod packaging;
pub mod table;

/// `name` with every character but ASCII letters, digits, '-', '_' and '.' replaced by '_':
/// safe as a folder name (the packager's output) and as one zenoh key chunk (the default
/// prefix of an instance).
pub fn plain_name(name: &str) -> String {
    name.chars()
        .map(|c| {
            if c.is_ascii_alphanumeric() || "-_.".contains(c) {
                c
            } else {
                '_'
            }
        })
        .collect()
}
