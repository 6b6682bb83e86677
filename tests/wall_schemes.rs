//! Walls with the paper schemes (issue 5: bodies "must work with standard SPH, Rosswog F1 and
//! CRKSPH, for gases and for liquids"): the closed water tank (Tait liquid) and the slow gas
//! piston (ideal gas) run with CRKSPH, Rosswog F1 and PSPH. These schemes keep wall–wall pairs
//! in their lists (their volume sums need a wall particle's full neighbourhood) and skip them
//! in the force pass; the standard scheme's runs are in `bodies.rs`.

use crate::common;
use sphfmu::case::Case;

/// A model's text with its `[scheme]` table replaced by `scheme`, together with a `[kernel]`
/// table between it and `[time]` (piston2d.toml's choice for standard SPH), so that each scheme
/// runs with its own kernel.
fn with_scheme(model: &str, scheme: &str) -> String {
    let text = common::model_text(model);
    let start = text.find("[scheme]").unwrap();
    let end = start + text[start..].find("\n[time]").unwrap();
    format!("{}[scheme]\n{scheme}\n{}", &text[..start], &text[end..])
}

/// The closed tank to t = 0.3: (vertical force / weight averaged over t ≥ 0.15 — five acoustic
/// periods 4H/c; largest fluid speed at the end; every fluid particle still in the box).
fn closed_tank(scheme: &str) -> (f64, f64, bool) {
    let case = Case::parse(&with_scheme("closed-tank2d.toml", scheme)).unwrap();
    let mut sim = case.build::<2>().unwrap();
    let weight = sim.diagnostics().mass * 9.81;
    let (mut f, mut n) = (0.0, 0.0);
    while sim.time < 0.3 {
        sim.step(0.3 - sim.time).unwrap();
        if sim.time >= 0.15 {
            f += -sim.sys.bodies[0].force[1] / weight;
            n += 1.0;
        }
    }
    let p = &sim.sys.particles;
    let fluid: Vec<usize> = (0..p.len()).filter(|&i| p.body[i] == 0).collect();
    let vmax = fluid.iter().map(|&i| p.vel[i].norm()).fold(0.0, f64::max);
    let inside = fluid
        .iter()
        .all(|&i| (0..2).all(|k| p.pos[i][k] > 0.0 && p.pos[i][k] < [1.0, 0.5][k]));
    (f / n, vmax, inside)
}

#[test]
fn crksph_and_rosswog_f1_walls_carry_a_liquid() {
    for scheme in ["name = \"crksph\"", "name = \"rosswog-f1\""] {
        let (f, vmax, inside) = closed_tank(scheme);
        println!("closed tank, {scheme}: force/weight {f:.4}, largest speed {vmax:.2e} m/s");
        // measured: CRKSPH 0.9992, F1 0.9996 (to t = 0.5: 1.0002, 1.0011; F3 0.9996, compSPH
        // 0.9997); largest speeds 3.4e-4 and 3.5e-3 m/s. Before wall–wall pairs were kept CRKSPH's wall volumes
        // blew up (NaN density in 8 steps) and F1 panicked. Issue: 1 %.
        assert!((f - 1.0).abs() < 0.01, "{scheme}: force/weight {f}");
        assert!(
            vmax < 0.02 && inside,
            "{scheme}: vmax {vmax}, inside {inside}"
        );
    }
}

#[test]
fn crksph_rosswog_f1_and_psph_walls_compress_a_gas_adiabatically() {
    // The gas spring (models/piston2d.toml) widened to 0.3 (Rosswog F1's Wendland C6 at
    // η = 2.2 needs a periodic side over 2·2h(1+skin) = 0.2024), over the first quarter period
    // (t ≤ 5: L from 1.0 to 1.1 and the piston's largest speed).
    for scheme in [
        "name = \"crksph\"",
        "name = \"rosswog-f1\"",
        "name = \"psph\"",
    ] {
        let text = with_scheme("piston2d.toml", scheme).replace(", 0.2]", ", 0.3]");
        let mut sim = Case::parse(&text).unwrap().build::<2>().unwrap();
        let mut worst: f64 = 0.0;
        while sim.time < 5.0 {
            sim.step(5.0 - sim.time).unwrap();
            if sim.time < 0.5 {
                continue; // the first sound crossings
            }
            let piston = &sim.sys.bodies[1];
            let exact = (1.1 + piston.pose.displacement[0]).powf(-1.4) * 0.3;
            worst = worst.max((piston.force[0] / exact - 1.0).abs());
        }
        println!("gas spring, {scheme}: largest deviation from P0 (L0/L)^γ A {worst:.4}");
        // measured: CRKSPH 0.47 %, F1 0.50 %, PSPH 0.51 % (compSPH 0.49 % at width 0.4,
        // t ≤ 6); issue: 1 %
        assert!(worst < 0.01, "{scheme}: {worst}");
    }
}
