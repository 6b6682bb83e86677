//! Peaked kernels of Rosswog's comparison (Rosswog (2015) Sec. 4), both performing poorly by design:
//! LIQ (linear quartic, Valcke et al. 2010; Eq. 34) and QCM6 (quartic-core M6; Eq. 35).
//! Their printed normalisations are rounded (LIQ's coefficients too), so σ is computed here
//! by quadrature of the stretched shape (Rosswog (2015) Sec. 4: "compute the normalisation numerically").

use super::{Kernel, SUPPORT};
use std::f64::consts::PI;

/// σ such that ∫ σ w(q) dV = 1 over the support 2 (unit h), by composite Simpson in q.
fn numeric_sigma(shape: impl Fn(f64) -> f64, dim: usize) -> f64 {
    let n = 40_000;
    let dq = SUPPORT / n as f64;
    let measure = |q: f64| match dim {
        1 => 2.0,
        2 => 2.0 * PI * q,
        _ => 4.0 * PI * q * q,
    };
    let mut s = 0.0;
    for i in 0..=n {
        let q = i as f64 * dq;
        let wgt = if i == 0 || i == n {
            1.0
        } else if i % 2 == 1 {
            4.0
        } else {
            2.0
        };
        s += wgt * shape(q) * measure(q);
    }
    1.0 / (s * dq / 3.0)
}

/// LIQ with u = q/2: F − u for u ≤ x_s, A u⁴ + B u³ + C u² + D u + E up to u = 1.
#[derive(Debug, Clone, Copy, PartialEq, Default)]
pub struct LinearQuartic;

impl LinearQuartic {
    const XS: f64 = 0.3;
    const A: f64 = -1.458;
    const B: f64 = 3.790;
    const C: f64 = -2.624;
    const D: f64 = -0.2915;
    const E: f64 = 0.5831;
    const F: f64 = 0.6500;
}

impl Kernel for LinearQuartic {
    #[inline(always)]
    fn shape(&self, q: f64) -> (f64, f64) {
        if q >= SUPPORT {
            return (0.0, 0.0);
        }
        let u = 0.5 * q;
        if u <= Self::XS {
            (Self::F - u, -0.5)
        } else {
            let w = (((Self::A * u + Self::B) * u + Self::C) * u + Self::D) * u + Self::E;
            let dw = ((4.0 * Self::A * u + 3.0 * Self::B) * u + 2.0 * Self::C) * u + Self::D;
            (w.max(0.0), 0.5 * dw)
        }
    }
    fn sigma(&self, dim: usize) -> f64 {
        numeric_sigma(|q| self.shape(q).0, dim)
    }
    fn default_eta(&self) -> f64 {
        2.2
    }
    fn name(&self) -> String {
        "LIQ linear quartic".to_string()
    }
}

/// QCM6: M6 (native support 3) with its core q' < q_c replaced by A q'⁴ + B q'² + C q' + D,
/// matching w6 and three derivatives at q_c = 0.759298; stretched to 2h (q' = 1.5 q).
#[derive(Debug, Clone, Copy, PartialEq, Default)]
pub struct QuarticCoreM6;

impl Kernel for QuarticCoreM6 {
    #[inline(always)]
    fn shape(&self, q: f64) -> (f64, f64) {
        const QC: f64 = 0.759298;
        const A: f64 = 11.017537;
        const B: f64 = -38.111922;
        const C: f64 = -16.619585;
        const D: f64 = 69.785768;
        if q >= SUPPORT {
            return (0.0, 0.0);
        }
        let x = 1.5 * q;
        if x < QC {
            let w = ((A * x * x + B) * x + C) * x + D;
            let dw = (4.0 * A * x * x + 2.0 * B) * x + C;
            (w, 1.5 * dw)
        } else {
            // unnormalised M6: (3−x)⁵ − 6(2−x)⁵ + 15(1−x)⁵ with (·)₊
            let (mut w, mut dw) = (0.0, 0.0);
            for (c, s) in [(1.0, 3.0), (-6.0, 2.0), (15.0, 1.0)] {
                let t: f64 = s - x;
                if t > 0.0 {
                    let t4 = t * t * t * t;
                    w += c * t4 * t;
                    dw -= 5.0 * c * t4;
                }
            }
            (w, 1.5 * dw)
        }
    }
    fn sigma(&self, dim: usize) -> f64 {
        numeric_sigma(|q| self.shape(q).0, dim)
    }
    fn default_eta(&self) -> f64 {
        2.2
    }
    fn name(&self) -> String {
        "QCM6 quartic-core M6".to_string()
    }
}
