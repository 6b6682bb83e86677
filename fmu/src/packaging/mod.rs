//! What goes into a `.fmu` archive besides the binary: `modelDescription.xml` for FMI 3.0 and
//! 2.0 (`xml.rs`, written from the variable table) and the archive itself with its
//! documentation page (`archive.rs`), used by `sphfmu-package`.

pub mod archive;
pub mod xml;
