//! Sod shock tube (the foundation issue's acceptance case): L1(ρ) against the exact Riemann
//! solution, energy conservation with mirror walls, and the output files.

use sphfmu::case::Case;
use sphfmu::runner::run_case;
use std::path::Path;

#[test]
fn sod_1d_standard_sph_l1_density() {
    let case = Case::load(Path::new(concat!(
        env!("CARGO_MANIFEST_DIR"),
        "/models/sod.toml"
    )))
    .unwrap();
    let dir = tempfile::tempdir().unwrap();
    let s = run_case(&case, dir.path(), &mut |_| {}).unwrap();
    let e = s.shock_tube.unwrap();
    println!(
        "Sod: N = {}, steps = {}, L1 rho {:.4e} v {:.4e} P {:.4e}",
        s.particles, s.steps, e.l1_density, e.l1_velocity, e.l1_pressure
    );
    assert_eq!(s.particles, 720);
    // Measured 2.75e-3; the bound is 3.0e-3 (PySPH tsph: 1.75e-3, adke 2.81e-3).
    assert!(e.l1_density <= 3.0e-3, "L1(rho) = {}", e.l1_density);
    assert!(e.l1_pressure <= 3.5e-3, "L1(P) = {}", e.l1_pressure);
    // Mirror walls do no work: total energy to integrator accuracy (measured 1.3e-6).
    let de = (s.last.total_energy - s.initial.total_energy).abs() / s.initial.total_energy;
    assert!(de < 1e-5, "energy drift {de}");
    for f in [
        "diagnostics.csv",
        "profile.png",
        "summary.json",
        "snapshots.pvd",
        "snapshot_00003.vtu",
        "snapshot_00003.csv",
    ] {
        assert!(dir.path().join(f).exists(), "missing {f}");
    }
    // diagnostics: one row per step plus the initial and final rows
    let rows = std::fs::read_to_string(dir.path().join("diagnostics.csv"))
        .unwrap()
        .lines()
        .count();
    assert_eq!(rows as u64, s.steps + 3);
}
