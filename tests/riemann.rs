//! The exact Riemann solver against Toro's tabulated star states (Toro 2009, Table 4.3) and
//! the Sod wave positions computed independently with PyPI `sodshock` (https://pypi.org/project/sodshock/0.1.9/).

use sphfmu::verify::riemann::{ExactRiemann, Primitive};

fn prim(rho: f64, u: f64, p: f64) -> Primitive {
    Primitive { rho, u, p }
}

#[test]
fn toro_table_4_3_star_states() {
    // (left, right, p*, u*) — Toro prints 6 significant digits.
    let cases = [
        (prim(1.0, 0.0, 1.0), prim(0.125, 0.0, 0.1), 0.30313, 0.92745),
        (prim(1.0, -2.0, 0.4), prim(1.0, 2.0, 0.4), 0.00189, 0.0),
        (
            prim(1.0, 0.0, 1000.0),
            prim(1.0, 0.0, 0.01),
            460.894,
            19.5975,
        ),
        (
            prim(1.0, 0.0, 0.01),
            prim(1.0, 0.0, 100.0),
            46.0950,
            -6.19633,
        ),
        (
            prim(5.99924, 19.5975, 460.894),
            prim(5.99242, -6.19633, 46.0950),
            1691.64,
            8.68975,
        ),
    ];
    for (l, r, ps, us) in cases {
        let rs = ExactRiemann::new(l, r, 1.4).unwrap();
        assert!(
            (rs.p_star - ps).abs() <= 5e-6 * ps.max(1.0) + 5e-6,
            "p* {} vs {ps}",
            rs.p_star
        );
        assert!(
            (rs.u_star - us).abs() <= 5e-5 * us.abs().max(1.0),
            "u* {} vs {us}",
            rs.u_star
        );
    }
}

#[test]
fn sod_wave_positions_match_sodshock() {
    // sodshock 0.1.9 at t = 0.15, x0 = 0: contact 0.13912, shock 0.26282, p* = 0.303130.
    let rs = ExactRiemann::new(prim(1.0, 0.0, 1.0), prim(0.125, 0.0, 0.1), 1.4).unwrap();
    assert!((rs.p_star - 0.303130).abs() < 1e-6);
    let t = 0.15;
    let contact = rs.u_star * t;
    assert!((contact - 0.13912).abs() < 1e-5, "contact {contact}");
    // shock: the last x where the state differs from the right state
    let mut x = 0.2;
    while rs.at(x, 0.0, t).rho > 0.125 + 1e-12 {
        x += 1e-6;
    }
    assert!((x - 0.26282).abs() < 2e-5, "shock {x}");
    // post-shock density (Rankine–Hugoniot) and the state at rest far away
    assert!((rs.at(0.2, 0.0, t).rho - 0.26557).abs() < 1e-4);
    assert_eq!(rs.at(-0.4, 0.0, t), prim(1.0, 0.0, 1.0));
}

#[test]
fn vacuum_generation_and_vacuum_states() {
    // Strong rarefactions pulling apart faster than 2(c_L + c_R)/(γ−1): vacuum in the middle.
    let rs = ExactRiemann::new(prim(1.0, -5.0, 0.4), prim(1.0, 5.0, 0.4), 1.4).unwrap();
    let mid = rs.sample(0.0);
    assert_eq!((mid.rho, mid.p), (0.0, 0.0));
    // Expansion into vacuum on the right: front speed u_L + 2c_L/(γ−1).
    let rs = ExactRiemann::new(prim(1.0, 0.0, 1.0), prim(0.0, 0.0, 0.0), 1.4).unwrap();
    let c = (1.4f64).sqrt();
    assert!(rs.sample(2.0 * c / 0.4 - 1e-6).rho > 0.0);
    assert_eq!(rs.sample(2.0 * c / 0.4 + 1e-6).rho, 0.0);
    // Fan is continuous at the head.
    let head = rs.sample(-c + 1e-9);
    assert!((head.rho - 1.0).abs() < 1e-8);
    assert!(ExactRiemann::new(prim(-1.0, 0.0, 1.0), prim(1.0, 0.0, 1.0), 1.4).is_err());
}
