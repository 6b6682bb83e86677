//! rpSPH (Abel 2011): Newton's first law for any particle arrangement, and the static-lattice
//! noise test of the Abel (2011) Sec. 3.1; extra numbers in App. A against standard SPH.

use crate::common;

use sphfmu::case::Case;

fn lattice(scheme: &str, extra: &str, perturb: f64) -> String {
    format!(
        r#"
{header}[kernel]
name = "cubic-spline"
eta = 1.2616
[scheme]
name = "{scheme}"
alpha = 1.0
{extra}
[time]
t_end = 4.0
[[region]]
spacing = 0.02
density = 1.0
pressure = 0.7142857142857143
[perturbation]
amplitude = {perturb}
seed = 11
"#,
        header = common::header(2, 0.0, 1.0, "periodic", 1.4)
    )
}

#[test]
fn uniform_pressure_gives_zero_acceleration_for_any_positions_and_masses() {
    // Strongly disordered positions (±40% of the spacing) and two different particle masses.
    let text = lattice("rpsph", "", 0.4).replace(
        "[perturbation]",
        "[[region]]\nshape = \"sphere\"\ncenter = [0.5, 0.5]\nradius = 0.2\nspacing = 0.015\ndensity = 3.0\npressure = 1.0\n[perturbation]",
    );
    for gradient in ["own-h", "symmetric"] {
        let t = text.replace(
            "alpha = 1.0",
            &format!("alpha = 1.0\ngradient = \"{gradient}\""),
        );
        let case = Case::parse(&t).unwrap();
        let mut sim = case.build::<2>().unwrap();
        // Make the pressure exactly uniform for the densities the scheme computes: one
        // evaluation first, since the h solve's last Newton step moves ρ by the square of the
        // residual it starts from (1e-8 after the build's solve, round-off after this one).
        sim.scheme.evaluate(&mut sim.sys).unwrap();
        let p0 = 0.7;
        let p = &mut sim.sys.particles;
        for i in 0..p.len() {
            p.u[i] = p0 / (0.4 * p.rho[i]);
        }
        sim.scheme.evaluate(&mut sim.sys).unwrap();
        let p = &sim.sys.particles;
        let amax = p.acc.iter().map(|a| a.norm()).fold(0.0, f64::max);
        // Scale of one pressure term: P/(ρ h) ~ 0.7/(1·0.02) = 35; round-off is ~1e-16 of it.
        let mut std_case = Case::parse(
            &t.replace("name = \"rpsph\"", "name = \"standard\"")
                .replace(&format!("gradient = \"{gradient}\""), ""),
        )
        .unwrap()
        .build::<2>()
        .unwrap();
        std_case.scheme.evaluate(&mut std_case.sys).unwrap();
        let q = &mut std_case.sys.particles;
        for i in 0..q.len() {
            q.u[i] = p0 / (0.4 * q.rho[i]);
        }
        std_case.scheme.evaluate(&mut std_case.sys).unwrap();
        let amax_std = std_case
            .sys
            .particles
            .acc
            .iter()
            .map(|a| a.norm())
            .fold(0.0, f64::max);
        println!("{gradient}: max |a| rpSPH {amax:.3e}, standard SPH {amax_std:.3e}");
        assert!(
            amax < 1e-12,
            "rpSPH ({gradient}) pushes a uniform-pressure gas: |a| = {amax:e}"
        );
        assert!(
            amax_std > 1e-2,
            "standard SPH should push on a disordered set: {amax_std:e}"
        );
    }
}

fn kinetic_energy_after(scheme: &str, t_end: f64) -> f64 {
    let case = Case::parse(&lattice(scheme, "", 0.0)).unwrap();
    let mut sim = case.build::<2>().unwrap();
    sim.advance_to(t_end, |_| {}).unwrap();
    sim.diagnostics().kinetic_energy
}

#[test]
fn static_lattice_kinetic_energy_stays_at_round_off() {
    // Abel (2011) Sec. 3.1; extra numbers in App. A: 50² square lattice, ρ = 1, c_s = 1, γ = 1.4, 20 neighbours (η = 1.2616
    // for M4 in 2D), α = 1, to t = 4 (four sound-crossing times).
    let rp = kinetic_energy_after("rpsph", 4.0);
    let std = kinetic_energy_after("standard", 4.0);
    println!("static lattice, t = 4: E_kin rpSPH {rp:.3e}, standard SPH {std:.3e}");
    assert!(rp < 1e-25, "rpSPH kinetic energy {rp:e}");
    assert!(
        rp * 1e7 <= std,
        "rpSPH {rp:e} not 1e7 below standard {std:e}"
    );
}
