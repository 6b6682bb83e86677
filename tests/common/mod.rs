//! Helpers shared by the integration tests.
#![allow(dead_code)]

use sphfmu::sim::Simulation;
use std::path::PathBuf;

/// `models/<name>` of this repository.
pub fn model_path(name: &str) -> PathBuf {
    PathBuf::from(env!("CARGO_MANIFEST_DIR"))
        .join("models")
        .join(name)
}

/// The text of `models/<name>`.
pub fn model_text(name: &str) -> String {
    std::fs::read_to_string(model_path(name)).unwrap()
}

/// The `[case]`, `[domain]` and `[eos]` tables of a test case: dimension, box [lo, hi]^D with
/// one boundary kind on every axis, ideal gas with γ.
pub fn header(d: usize, lo: f64, hi: f64, boundary: &str, gamma: f64) -> String {
    let v = |x: f64| format!("[{}]", vec![format!("{x:?}"); d].join(", "));
    format!(
        "[case]\nname = \"test\"\ndimension = {d}\n[domain]\nmin = {}\nmax = {}\nboundary = [{}]\n[eos]\ntype = \"ideal-gas\"\ngamma = {gamma:?}\n",
        v(lo),
        v(hi),
        vec![format!("\"{boundary}\""); d].join(", ")
    )
}

/// Step `steps` times asserting that total linear momentum changes by less than 1e-12 of
/// Σ m|v| per step; returns the relative total-energy change over the run.
pub fn momentum_exact_energy_drift<const D: usize>(
    sim: &mut Simulation<D>,
    steps: usize,
    label: &str,
) -> f64 {
    let d0 = sim.diagnostics();
    let p = &sim.sys.particles;
    let p_scale: f64 = (0..p.len()).map(|i| p.mass[i] * p.vel[i].norm()).sum();
    let mut prev = d0;
    for _ in 0..steps {
        sim.step(f64::INFINITY).unwrap();
        let d = sim.diagnostics();
        for k in 0..D {
            let rel = (d.momentum[k] - prev.momentum[k]).abs() / p_scale;
            // measured ~1e-16 per step; the issues allow 1e-12
            assert!(
                rel < 1e-12,
                "{label}: momentum[{k}] changed by {rel:e} (relative) in one step"
            );
        }
        prev = d;
    }
    (sim.diagnostics().total_energy - d0.total_energy).abs() / d0.total_energy
}

/// The violent random 2D periodic box of the conservation tests: a moving background with a
/// denser, hotter disc moving the other way, every particle displaced by up to 0.3 spacings.
/// `scheme`: the `[scheme]` table's lines; `time`: extra `[time]` lines; spacings of the
/// background and the disc.
pub fn random_box(scheme: &str, time: &str, spacing: (f64, f64)) -> String {
    format!(
        r#"
{header}[scheme]
{scheme}
[time]
t_end = 1.0
{time}
[[region]]
spacing = {s0:?}
density = 1.0
pressure = 1.0
velocity = [0.3, -0.2]
[[region]]
shape = "sphere"
center = [0.5, 0.5]
radius = 0.25
spacing = {s1:?}
density = 2.0
pressure = 3.0
velocity = [-0.4, 0.1]
[perturbation]
amplitude = 0.3
seed = 42
"#,
        header = header(2, 0.0, 1.0, "periodic", 1.6666666666666667),
        s0 = spacing.0,
        s1 = spacing.1
    )
}
