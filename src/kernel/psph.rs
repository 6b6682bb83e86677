//! PSPH quintic (Frontiere, Raskin & Owen (2017) eq G.13, eq G.13; Hopkins 2015): the M6 quintic B-spline rescaled to
//! native support 1, stretched here to 2h (`w(q) = ψ(q/2)`, σ_2h = σ_1/2^D). Normalisations
//! (Frontiere, Raskin & Owen (2017) eq G.13): 1D 243/40, 2D 15309/(478π), 3D 2187/(40π).

use super::{stretched_sigma, Kernel, SUPPORT};
use std::f64::consts::PI;

/// The PSPH quintic kernel (η_max = 1, n_h = 4 in the paper's units).
#[derive(Debug, Clone, Copy, PartialEq, Default)]
pub struct PsphQuintic;

impl Kernel for PsphQuintic {
    #[inline(always)]
    fn shape(&self, q: f64) -> (f64, f64) {
        if q >= SUPPORT {
            return (0.0, 0.0);
        }
        let x = 0.5 * q;
        // ψ = (1−x)⁵ − 6(2/3−x)₊⁵ + 15(1/3−x)₊⁵, each term written from the edge inwards
        let term = |c: f64, edge: f64| {
            let y = edge - x;
            if y > 0.0 {
                let y2 = y * y;
                (c * y2 * y2 * y, -5.0 * c * y2 * y2)
            } else {
                (0.0, 0.0)
            }
        };
        let (a, da) = term(1.0, 1.0);
        let (b, db) = term(-6.0, 2.0 / 3.0);
        let (c, dc) = term(15.0, 1.0 / 3.0);
        // d/dq = ½ d/dx
        (a + b + c, 0.5 * (da + db + dc))
    }
    fn sigma(&self, dim: usize) -> f64 {
        let native = [243.0 / 40.0, 15309.0 / (478.0 * PI), 2187.0 / (40.0 * PI)];
        stretched_sigma(native[dim - 1], 1.0, dim)
    }
    fn default_eta(&self) -> f64 {
        // n_h = 4 with η_max = 1 (Frontiere, Raskin & Owen (2017) Table D.1): η = η_max·n_h/2
        2.0
    }
    fn name(&self) -> String {
        "PSPH quintic".to_string()
    }
}
