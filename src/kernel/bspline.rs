//! B-spline kernels M4, M5, M6 and W7 (Rosswog (2015) Eq. 28, Frontiere, Raskin & Owen (2017) eq 81–82), stretched to 2h.
//!
//! Each is written in the mirrored form `Σ_i (−1)^i C(k+1,i) (l − q − i)_+^k` with `l` the
//! native half-support, so the terms near the support edge do not cancel (Frontiere, Raskin & Owen (2017) eq 81–82).

use super::{stretched_sigma, Kernel, SUPPORT};
use std::f64::consts::PI;

/// Binomial coefficient (small arguments, exact in f64).
const fn binomial(n: usize, k: usize) -> f64 {
    let mut r = 1.0;
    let mut i = 0;
    while i < k {
        r = r * (n - i) as f64 / (i + 1) as f64;
        i += 1;
    }
    r
}

/// Polynomial coefficients of the mirrored B-spline of degree `K` per piece: with the edge
/// distance t = l − x, on t ∈ (j, j+1] the active terms are i = 0..=j, and in s = t − j ∈ (0, 1]
/// w = Σ_i (−1)^i C(K+1,i) (s + j − i)^K = Σ_m C[j][m] s^m. The C are the spline's Taylor
/// coefficients at the piece's knot (moderate, integer sums exact in f64), so Horner in
/// s ≤ 1 does not cancel. Built at compile time.
struct Pieces<const K: usize>;

impl<const K: usize> Pieces<K> {
    const C: [[f64; 8]; 5] = {
        let mut c = [[0.0; 8]; 5];
        let mut j = 0;
        while j < 5 {
            let mut i = 0;
            while i <= j && i <= K + 1 {
                let sign = if i % 2 == 0 { 1.0 } else { -1.0 };
                let mut m = 0;
                while m <= K {
                    // (s + j − i)^K = Σ_m C(K, m) s^m (j − i)^{K−m}
                    let mut pw = 1.0;
                    let mut e = 0;
                    while e < K - m {
                        pw *= (j - i) as f64;
                        e += 1;
                    }
                    c[j][m] += sign * binomial(K + 1, i) * binomial(K, m) * pw;
                    m += 1;
                }
                i += 1;
            }
            j += 1;
        }
        c
    };
}

/// Mirrored B-spline of degree `K` (order K+1) on native support `l = (K+1)/2` in units of
/// the native h, evaluated at native argument `x`. Returns (w, dw/dx) without the 1/K! factor.
/// Horner on the piece's polynomial (see [`Pieces`]): near the edge only t^K survives, so there
/// is no cancellation there (Frontiere, Raskin & Owen (2017) eq 81–82), and no powi loop per term (the kernel dominated
/// CRKSPH's run time with the term-by-term sum).
#[inline(always)]
fn mirrored<const K: usize>(x: f64) -> (f64, f64) {
    let half = (K as f64 + 1.0) / 2.0;
    let t = half - x;
    // piece j ∋ t (at a knot both neighbouring pieces agree: the spline is C^{K−1}). Its
    // coefficients are summed up the pieces, C[0] + Σ_{p ≤ j} (C[p] − C[p−1]), rather than read
    // by a table index: an index (or a chain of selects, which the compiler turns back into
    // one) keeps a loop over pair lanes scalar, and this sum lets it become SIMD. The C are
    // integers well below 2^53, so every partial sum is exact: same coefficients, same bits.
    // Only pieces 0..=K/2 are reached: t ≤ (K+1)/2, and where t = (K+1)/2 is a knot (x = 0, K
    // odd) piece K/2 at s = 1 gives the same integer sums as the next piece at s = 0.
    let j = t.max(0.0).floor().min((K / 2) as f64);
    let coef = |m: usize| {
        let c = &Pieces::<K>::C;
        let mut sum = c[0][m];
        for piece in 1..=K / 2 {
            let step = c[piece][m] - c[piece - 1][m];
            sum += if j >= piece as f64 { step } else { 0.0 };
        }
        sum
    };
    let s = t - j;
    let mut w = coef(K);
    let mut dw = K as f64 * coef(K);
    for m in (1..K).rev() {
        w = w * s + coef(m);
        dw = dw * s + m as f64 * coef(m);
    }
    w = w * s + coef(0);
    // dw/dx = −dw/ds
    if t <= 0.0 {
        (0.0, 0.0)
    } else {
        (w, -dw)
    }
}

macro_rules! bspline_kernel {
    ($name:ident, $deg:expr, $fact:expr, $sig:expr, $eta:expr, $label:expr) => {
        #[doc = concat!("B-spline kernel ", $label, " stretched to support 2h.")]
        #[derive(Debug, Clone, Copy, PartialEq, Default)]
        pub struct $name;
        impl Kernel for $name {
            #[inline(always)]
            fn shape(&self, q: f64) -> (f64, f64) {
                const NATIVE: f64 = ($deg as f64 + 1.0) / 2.0;
                const S: f64 = NATIVE / SUPPORT;
                if q >= SUPPORT {
                    return (0.0, 0.0);
                }
                let (w, dw) = mirrored::<$deg>(q * S);
                (w / $fact, dw * S / $fact)
            }
            fn sigma(&self, dim: usize) -> f64 {
                let native: [f64; 3] = $sig;
                stretched_sigma(native[dim - 1], ($deg as f64 + 1.0) / 2.0, dim)
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

// Native normalisations of the 1/K!-scaled shapes on native support (K+1)/2 (Frontiere, Raskin & Owen (2017) eq 81–82
// table; for M5 computed symbolically: 1D 1, 2D 96·24/(1199π), 3D 24/(20π)). Rosswog's M4 shape
// ¼(2−q)³ − (1−q)³ is 3/2 of ours, hence his 2/3, 10/(7π), 1/π. Every value is checked against
// quadrature in tests/kernels.rs.
/// B-spline kernel M4 (cubic) stretched to support 2h (its native support): written out
/// piecewise because it is the default kernel and the generic mirrored sum is slower.
/// Shape (1/6)[(2−q)³ − 4(1−q)³] = Rosswog's w4 × 2/3, so σ = 1, 15/(7π), 3/(2π).
#[derive(Debug, Clone, Copy, PartialEq, Default)]
pub struct CubicSplineM4;

impl Kernel for CubicSplineM4 {
    #[inline(always)]
    fn shape(&self, q: f64) -> (f64, f64) {
        if q >= 2.0 {
            (0.0, 0.0)
        } else if q >= 1.0 {
            let t = 2.0 - q;
            (t * t * t / 6.0, -0.5 * t * t)
        } else {
            // (2−q)³/6 − 4(1−q)³/6 = 2/3 − q² + q³/2
            (2.0 / 3.0 - q * q + 0.5 * q * q * q, q * (1.5 * q - 2.0))
        }
    }
    fn sigma(&self, dim: usize) -> f64 {
        [1.0, 15.0 / (7.0 * PI), 3.0 / (2.0 * PI)][dim - 1]
    }
    fn default_eta(&self) -> f64 {
        1.2
    }
    fn name(&self) -> String {
        "M4 cubic spline".to_string()
    }
}

bspline_kernel!(
    QuarticSplineM5,
    4,
    24.0,
    [1.0, 96.0 / (1199.0 * PI) * 24.0, 1.0 / (20.0 * PI) * 24.0],
    1.4,
    "M5 quartic spline"
);
bspline_kernel!(
    QuinticSplineM6,
    5,
    120.0,
    [1.0, 7.0 / (478.0 * PI) * 120.0, 1.0 / (120.0 * PI) * 120.0],
    1.6,
    "M6 quintic spline"
);
bspline_kernel!(
    SepticSplineW7,
    7,
    5040.0,
    [1.0, 2268.0 / (1487.0 * PI), 3.0 / (4.0 * PI)],
    2.0,
    "W7 septic spline"
);
