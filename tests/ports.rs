//! Pressure ports (issue 6): open boundaries with particle buffers.

use sphfmu::case::Case;
use sphfmu::coupling::{Coupling, CouplingOptions};

fn model(name: &str) -> String {
    std::fs::read_to_string(format!("{}/models/{name}", env!("CARGO_MANIFEST_DIR"))).unwrap()
}

#[test]
fn poiseuille_between_two_pressure_ports() {
    let text = model("poiseuille-ports2d.toml");
    let case = Case::parse(&text).unwrap();
    let mut c = Coupling::new(&case, &CouplingOptions::default()).unwrap();
    let m0 = c.diagnostics().mass;
    let (mut qi, mut qo, mut n) = (0.0, 0.0, 0);
    for k in 1..=120 {
        let t = 0.1 * k as f64;
        c.step_to(t).unwrap();
        let d = c.diagnostics();
        let ports = c.ports();
        let bal = d.mass - m0 - (ports[0].mass_in + ports[1].mass_in) + (ports[0].mass_out + ports[1].mass_out);
        if t > 3.95 {
            qi += ports[0].volume_flow;
            qo -= ports[1].volume_flow;
            n += 1;
        }
        if k % 5 == 0 {
        println!("t {t:.2} n {} fluid {} Q_in {:.5} Q_out {:.5} P {:.4} {:.4} bal {bal:.3e}",
            d.particles, d.fluid_particles, ports[0].volume_flow, -ports[1].volume_flow,
            ports[0].mean_pressure, ports[1].mean_pressure);
        }
    }
    let sim_case = &case;
    let _ = sim_case;
    println!("mean Q in {:.5} out {:.5} exact 0.05", qi / n as f64, qo / n as f64);
}
