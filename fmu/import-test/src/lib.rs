//! Empty: this crate only holds tests/import.rs.
