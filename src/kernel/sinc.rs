//! The sinc ("harmonic-like") family W_H,n of Cabezón et al. (2008), Rosswog (2015) Eq. 32 (Eq. 32),
//! native support 2: w(q) = [sin(πq/2)/(πq/2)]^n. Normalisations from Rosswog's Table 1
//! (checked there by quadrature to 8 digits; again in tests/kernels.rs).

use super::{Kernel, SUPPORT};
use std::f64::consts::FRAC_PI_2;

/// Table 1 of Rosswog (2015): σ_{H,n} for n = 3..9 in 1D, 2D, 3D.
const SIGMA: [[f64; 3]; 7] = [
    [0.66020338, 0.45073324, 0.31787809],
    [0.75221501, 0.58031218, 0.45891752],
    [0.83435371, 0.71037946, 0.61701265],
    [0.90920480, 0.84070999, 0.79044959],
    [0.97840221, 0.97119717, 0.97794935],
    [1.04305235, 1.10178466, 1.17851074],
    [1.10394401, 1.23244006, 1.39132215],
];

/// Table 3 of Rosswog (2015): the η used with each n.
const ETA: [f64; 7] = [1.2, 1.5, 1.6, 1.7, 1.8, 1.9, 2.2];

/// W_H,n with integer n in 3..=9.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct SincKernel {
    n: u32,
}

impl SincKernel {
    pub fn new(n: u32) -> Result<Self, String> {
        if !(3..=9).contains(&n) {
            return Err(format!(
                "kernel.sinc_n: must be an integer in [3, 9] (Rosswog Table 1), got {n}"
            ));
        }
        Ok(Self { n })
    }
    pub fn n(&self) -> u32 {
        self.n
    }
}

impl Kernel for SincKernel {
    #[inline(always)]
    fn shape(&self, q: f64) -> (f64, f64) {
        if q >= SUPPORT {
            return (0.0, 0.0);
        }
        let z = FRAC_PI_2 * q;
        let n = self.n as i32;
        if z < 1e-4 {
            // series: s = 1 − z²/6, s' = −z/3 (ds/dz)
            let s = 1.0 - z * z / 6.0;
            let sn1 = s.powi(n - 1);
            return (sn1 * s, n as f64 * sn1 * (-z / 3.0) * FRAC_PI_2);
        }
        let (sz, cz) = z.sin_cos();
        let s = sz / z;
        let sn1 = s.powi(n - 1);
        let ds_dz = (z * cz - sz) / (z * z);
        (sn1 * s, n as f64 * sn1 * ds_dz * FRAC_PI_2)
    }
    fn sigma(&self, dim: usize) -> f64 {
        SIGMA[(self.n - 3) as usize][dim - 1]
    }
    fn default_eta(&self) -> f64 {
        ETA[(self.n - 3) as usize]
    }
    fn name(&self) -> String {
        format!("W_H,{} sinc", self.n)
    }
}
