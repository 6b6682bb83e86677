//! Wendland kernels C2, C4, C6 (Frontiere, Raskin & Owen (2017) eq D.1–D.3, Rosswog (2015) Eq. 33), native support 1,
//! stretched to 2h: `w(q) = ψ(q/2)`, σ_2h = σ_1/2^D. In 1D the same polynomials are used
//! (positive definite there too); σ_1D computed symbolically: C2 3/2, C4 27/16, C6 15/8.

use super::{stretched_sigma, Kernel, SUPPORT};
use std::f64::consts::PI;

macro_rules! wendland_kernel {
    ($name:ident, $label:expr, $sig:expr, $eta:expr, |$x:ident, $om:ident| $w:expr, $dw:expr) => {
        #[doc = concat!("Wendland ", $label, " kernel stretched to support 2h.")]
        #[derive(Debug, Clone, Copy, PartialEq, Default)]
        pub struct $name;
        impl Kernel for $name {
            #[inline(always)]
            fn shape(&self, q: f64) -> (f64, f64) {
                if q >= SUPPORT {
                    return (0.0, 0.0);
                }
                let $x = 0.5 * q;
                let $om = 1.0 - $x;
                // d/dq = ½ d/dx
                ($w, 0.5 * $dw)
            }
            fn sigma(&self, dim: usize) -> f64 {
                let native: [f64; 3] = $sig;
                stretched_sigma(native[dim - 1], 1.0, dim)
            }
            fn default_eta(&self) -> f64 {
                $eta
            }
            fn name(&self) -> String {
                $label.to_string()
            }
        }
    };
}

// ψ = (1−x)⁴(1+4x); ψ' = −20x(1−x)³
wendland_kernel!(
    WendlandC2,
    "Wendland C2",
    [1.5, 7.0 / PI, 21.0 / (2.0 * PI)],
    1.6,
    |x, om| {
        let o2 = om * om;
        o2 * o2 * (1.0 + 4.0 * x)
    },
    { -20.0 * x * om * om * om }
);
// ψ = (1−x)⁶(1+6x+35/3 x²); ψ' = −(56/3) x (1+5x)(1−x)⁵
wendland_kernel!(
    WendlandC4,
    "Wendland C4",
    [27.0 / 16.0, 9.0 / PI, 495.0 / (32.0 * PI)],
    1.9,
    |x, om| {
        let o2 = om * om;
        o2 * o2 * o2 * (1.0 + x * (6.0 + x * 35.0 / 3.0))
    },
    {
        let o2 = om * om;
        -(56.0 / 3.0) * x * (1.0 + 5.0 * x) * o2 * o2 * om
    }
);
// ψ = (1−x)⁸(32x³+25x²+8x+1); ψ' = −22x(16x²+7x+1)(1−x)⁷ (Rosswog Eq. 33, [CHECKED])
wendland_kernel!(
    WendlandC6,
    "Wendland C6",
    [15.0 / 8.0, 78.0 / (7.0 * PI), 1365.0 / (64.0 * PI)],
    2.2,
    |x, om| {
        let o2 = om * om;
        let o4 = o2 * o2;
        o4 * o4 * (1.0 + x * (8.0 + x * (25.0 + 32.0 * x)))
    },
    {
        let o2 = om * om;
        let o4 = o2 * o2;
        -22.0 * x * (1.0 + x * (7.0 + 16.0 * x)) * o4 * o2 * om
    }
);
