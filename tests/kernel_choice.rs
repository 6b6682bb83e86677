//! Why the bodies models pick their kernels (README § Case files, "Choose the kernel"): the
//! same runs as `bodies.rs` with the standard scheme's default cubic spline (η = 1.2), which
//! is measurably off in each. `make verify` runs these and prints the figures the README
//! quotes; they pin the cubic spline's errors so that the README changes when they do.

use crate::bodies::{
    cubic_lattice_gradient_moment, gas_spring_worst_deviation, open_tank_3d, sloshing,
};
use crate::common::model_text;

/// `models/<name>` with its `[kernel]` table taken out: the scheme's default kernel.
fn without_kernel(name: &str, table: &str) -> String {
    let text = model_text(name);
    assert!(text.contains(table), "{name} has no {table:?}");
    text.replace(table, "")
}

#[test]
#[ignore = "the cubic spline's errors, for the README (two minutes): make verify"]
fn the_cubic_spline_is_measurably_off_in_the_bodies_cases() {
    let c4 = "[kernel]\nname = \"wendland-c4\"\n";
    let s = sloshing(&without_kernel("sloshing2d.toml", c4));
    let w = gas_spring_worst_deviation(&without_kernel("piston2d.toml", c4));
    let (phases, _) = open_tank_3d("eta = 1.2", false);
    let floor = phases[0].2;
    let excess = 1.0 / cubic_lattice_gradient_moment(1.2) - 1.0;
    println!(
        "cubic spline: sloshing period / linear theory {:.4} (damping {:.3} /s); gas spring worst deviation {w:.4}; 3D floor pressure / exact {floor:.4} (1/M − 1 = {:+.2} %)",
        s.period_ratio, s.damping, 100.0 * excess
    );
    // measured: sloshing 0.9601, damping 0.194 /s (Wendland C4: 1.0005, 0.011 /s); gas spring
    // 1.17 % (C4: 0.72 %); 3D floor +2.04 % (1/M − 1 = +1.87 %; η = 1.3: +0.79 %)
    assert!(s.period_ratio < 0.98, "sloshing {}", s.period_ratio);
    // more neighbours help the cubic spline only so far: SPH's zeroth-order error at a fixed
    // neighbour number does not fall with resolution, and past η ≈ 1.5 the B-spline pairs
    // instead (Dehnen & Aly 2012); measured 0.9792 at η = 1.5, 0.9784 at η = 1.8
    for eta in [1.5, 1.8] {
        let more = sloshing(
            &without_kernel("sloshing2d.toml", c4)
                .replace("[time]", &format!("[kernel]\neta = {eta}\n\n[time]")),
        );
        println!(
            "cubic spline, η = {eta}: sloshing period / linear theory {:.4} (damping {:.3} /s)",
            more.period_ratio, more.damping
        );
        assert!(
            more.period_ratio > 0.97 && more.period_ratio < 0.99,
            "η = {eta}: {}",
            more.period_ratio
        );
    }
    assert!(w > 0.01, "gas spring {w}");
    assert!((floor - 1.0 - excess).abs() < 0.003, "3D floor {floor}");
}
