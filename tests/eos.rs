//! Equations of state: closed forms, inverses and range checks.

use sphfmu::eos::{Eos, EosConfig};

#[test]
fn ideal_gas_and_stiffened_gas_invert_and_give_the_sound_speed() {
    let ideal = EosConfig::IdealGas { gamma: 1.4 };
    let stiff = EosConfig::StiffenedGas {
        gamma: 4.4,
        p_inf: 6e8,
    };
    for eos in [ideal, stiff] {
        let g = eos.gamma();
        let p_inf = match eos {
            EosConfig::StiffenedGas { p_inf, .. } => p_inf,
            _ => 0.0,
        };
        for (rho, p) in [(1.0, 1.0), (0.125, 0.1), (1000.0, 1e5)] {
            let u = eos.internal_energy(rho, p);
            // P = (γ−1)ρu − γP∞ cancels γP∞: the round-off scales with it
            let tol = 1e-14 * (p + g * p_inf).max(1.0);
            assert!((eos.pressure(rho, u) - p).abs() <= tol, "{eos:?}");
            let c = eos.sound_speed(rho, u);
            assert!(
                (c * c - g * (p + p_inf) / rho).abs() <= 1e-12 * c * c,
                "{eos:?}"
            );
        }
    }
}

#[test]
fn tait_is_background_pressure_at_rest_density_and_stiff_around_it() {
    let eos = EosConfig::Tait {
        rho0: 1000.0,
        sound_speed: 20.0,
        gamma: 7.0,
        background_pressure: 0.0,
    };
    assert_eq!(eos.pressure(1000.0, 0.0), 0.0);
    assert_eq!(eos.sound_speed(1000.0, 0.0), 20.0);
    // dP/dρ at ρ0 is c0²
    let d = 1e-3;
    let dpdrho = (eos.pressure(1000.0 + d, 0.0) - eos.pressure(1000.0 - d, 0.0)) / (2.0 * d);
    assert!((dpdrho - 400.0).abs() < 1e-6, "{dpdrho}");
    let iso = EosConfig::Isothermal { sound_speed: 3.0 };
    assert_eq!(iso.pressure(2.0, 123.0), 18.0);
}

#[test]
fn out_of_range_parameters_name_the_key() {
    for (eos, key) in [
        (EosConfig::IdealGas { gamma: 1.0 }, "eos.gamma"),
        (EosConfig::IdealGas { gamma: f64::NAN }, "eos.gamma"),
        (
            EosConfig::Isothermal { sound_speed: -1.0 },
            "eos.sound_speed",
        ),
        (
            EosConfig::Tait {
                rho0: 0.0,
                sound_speed: 1.0,
                gamma: 7.0,
                background_pressure: 0.0,
            },
            "eos.rho0",
        ),
        (
            EosConfig::StiffenedGas {
                gamma: 4.4,
                p_inf: -1.0,
            },
            "eos.p_inf",
        ),
    ] {
        let e = eos.validate().unwrap_err();
        assert!(e.starts_with(key), "{e}");
    }
}

/// The Tait law's powers by multiplication (whole exponents) stay within a few ulp of the
/// library `powf`, and a fractional exponent still goes through `powf`: P and c over a
/// liquid's density range for γ = 7 (exponents 7 and 3), γ = 1 (1 and 0), γ = 7.5 (`powf`).
#[test]
fn tait_powers_match_powf() {
    for gamma in [7.0, 1.0, 4.0, 7.5] {
        let (rho0, c0, p_bg) = (1000.0, 20.0, 1e3);
        let eos = EosConfig::Tait {
            rho0,
            sound_speed: c0,
            gamma,
            background_pressure: p_bg,
        };
        let b = rho0 * c0 * c0 / gamma;
        for i in 0..=400 {
            let rho = rho0 * (0.8 + 0.4 * i as f64 / 400.0);
            let r = rho / rho0;
            let p_want = b * (r.powf(gamma) - 1.0) + p_bg;
            let c_want = c0 * r.powf(0.5 * (gamma - 1.0));
            // 7 multiplies round 7 times: 1e-14 of B is about 10 ulp of B r^γ at r = 1.2
            assert!(
                (eos.pressure(rho, 0.0) - p_want).abs() <= 1e-14 * b * r.powf(gamma),
                "P at gamma {gamma}, rho {rho}"
            );
            assert!(
                (eos.sound_speed(rho, 0.0) - c_want).abs() <= 1e-14 * c_want,
                "c at gamma {gamma}, rho {rho}"
            );
            if gamma == 7.5 {
                assert_eq!(eos.pressure(rho, 0.0).to_bits(), p_want.to_bits());
            }
        }
    }
}
