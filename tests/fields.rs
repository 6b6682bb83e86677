//! `[[field]]` initial-state expressions: a velocity mode, a density field at uniform
//! pressure, and each bad entry rejected with the key named.

use crate::common;

use sphfmu::case::Case;
use sphfmu::eos::Eos;

fn case_with(fields: &str) -> String {
    format!(
        r#"
{header}[time]
t_end = 1.0
[[region]]
max = [1.0, 0.5]
spacing = 0.05
density = 1.0
pressure = 2.5
[[region]]
min = [0.0, 0.5]
spacing = 0.05
density = 2.0
pressure = 2.5
{fields}
"#,
        header = common::header(2, 0.0, 1.0, "periodic", 1.4)
    )
}

#[test]
fn a_velocity_mode_and_a_density_field_are_set_as_written() {
    let text = case_with(
        r#"
[[field]]
quantity = "velocity.y"
expression = "A*sin(4*PI*x)*exp(-(((y-0.5)/s)^2))"
parameters = { A = 0.01, s = 0.1 }
[[field]]
quantity = "density"
expression = "rho*(1 + 0.1*cos(2*PI*x))"
regions = [1]
"#,
    );
    let plain = Case::parse(&case_with("")).unwrap().build::<2>().unwrap();
    let case = Case::parse(&text).unwrap();
    let eos = case.eos;
    let sim = case.build::<2>().unwrap();
    let (p, q) = (&sim.sys.particles, &plain.sys.particles);
    assert_eq!(p.len(), q.len());
    let mut checked = 0;
    for a in 0..p.len() {
        let (x, y) = (p.pos[a][0], p.pos[a][1]);
        let vy =
            0.01 * (4.0 * std::f64::consts::PI * x).sin() * (-((y - 0.5) / 0.1f64).powi(2)).exp();
        assert!(
            (p.vel[a][1] - vy).abs() < 1e-15,
            "v_y at {x}, {y}: {} vs {vy}",
            p.vel[a][1]
        );
        assert_eq!(p.vel[a][0], 0.0);
        if y > 0.5 {
            // region 1: ρ follows the expression, the volume (m/ρ) and the pressure stay
            let f = 1.0 + 0.1 * (2.0 * std::f64::consts::PI * x).cos();
            assert!((p.mass[a] / q.mass[a] - f).abs() < 1e-12);
            checked += 1;
        } else {
            assert_eq!(p.mass[a], q.mass[a]);
        }
        // the pressure at the density the entry set (the region's times the mode)
        let rho = if y > 0.5 { 2.0 } else { 1.0 } * p.mass[a] / q.mass[a];
        let pa = eos.pressure(rho, p.u[a]);
        assert!((pa - 2.5).abs() < 1e-12, "pressure {pa}");
    }
    assert!(checked > 100);
}

#[test]
fn each_bad_field_entry_names_its_key() {
    let bad: &[(&str, &[&str])] = &[
        (
            "[[field]]\nquantity = \"velocity.y\"\nexpression = \"sin(4*PI*x\"",
            &["field[0].expression", "cannot parse"],
        ),
        (
            "[[field]]\nquantity = \"velocity.y\"\nexpression = \"amp*x\"",
            &["field[0].expression", "unknown name `amp`", "parameters"],
        ),
        (
            "[[field]]\nquantity = \"velocity.y\"\nexpression = \"z\"",
            &["field[0].expression", "`z`", "2D"],
        ),
        (
            "[[field]]\nquantity = \"velocity.z\"\nexpression = \"x\"",
            &["field[0].quantity", "2D"],
        ),
        (
            "[[field]]\nquantity = \"density\"\nexpression = \"x\"\nregions = [2]",
            &["field[0].regions", "0 to 1"],
        ),
        (
            "[[field]]\nquantity = \"temperature\"\nexpression = \"x\"",
            &["unknown variant", "temperature"],
        ),
    ];
    for (fields, want) in bad {
        let err = Case::parse(&case_with(fields)).expect_err(fields).0;
        for w in *want {
            assert!(err.contains(w), "{fields}: {err} lacks {w}");
        }
    }
    // a value outside the quantity's range is an error at build time, with the position
    let text = case_with("[[field]]\nquantity = \"density\"\nexpression = \"x - 0.5\"");
    let err = Case::parse(&text)
        .unwrap()
        .build::<2>()
        .err()
        .expect("negative density")
        .to_string();
    assert!(
        err.contains("field[0].expression") && err.contains("> 0"),
        "{err}"
    );
}
