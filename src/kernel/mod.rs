//! Smoothing kernels.
//!
//! Convention (Rosswog (2015) Sec. 4): every kernel is stretched to a support of **2h**, so
//! `W(r, h) = σ_D / h^D · w(q)` with `q = r/h ∈ [0, 2]`. A kernel whose native support is
//! `l·h` is stretched with `w(q) = w_native(q·l/2)` and `σ_2h = (l/2)^D σ_lh`.
//!
//! Smoothing lengths are set from `h = η (m/ρ)^{1/D}`; the number of neighbours inside the
//! support on a uniform distribution is then `4η` (1D), `4πη²` (2D), `(32π/3)η³` (3D), see
//! [`neighbours_for_eta`]. Recommended η per kernel (Rosswog Table 3, "η used"): M4 1.2,
//! M5 1.4, M6 1.6, W7 2.0, Wendland C2 1.6, C4 1.9, C6 2.2, W_H,n as in Table 3.
//!
//! CRKSPH's `n_h` convention (Frontiere, Raskin & Owen (2017) §4; Table D.1): `h_crk = Δx·n_h` with the kernel's native
//! support `η_max·h_crk`; the number of *radial* neighbours is `η_max·n_h`. Stretched to our 2h
//! support the same kernel has radial neighbours `2η`, so `η = η_max·n_h/2` (W7 with n_h = 1
//! gives η = 2: 4 radial neighbours, as the paper's comparisons fix).

mod bspline;
mod peaked;
mod psph;
mod sinc;
mod wendland;

pub use bspline::{CubicSplineM4, QuarticSplineM5, QuinticSplineM6, SepticSplineW7};
pub use peaked::{LinearQuartic, QuarticCoreM6};
pub use psph::PsphQuintic;
pub use sinc::SincKernel;
pub use wendland::{WendlandC2, WendlandC4, WendlandC6};

use serde::{Deserialize, Serialize};
use std::f64::consts::PI;

/// Support radius in units of h, shared by every kernel (all stretched to 2h).
pub const SUPPORT: f64 = 2.0;

/// A radial smoothing kernel in the stretched-to-2h convention.
pub trait Kernel: Send + Sync {
    /// Unnormalised shape `w(q)` and its derivative `dw/dq` for `q = r/h ≥ 0` (zero for q ≥ 2).
    fn shape(&self, q: f64) -> (f64, f64);
    /// Normalisation σ_D for the stretched kernel in dimension `dim` (1, 2 or 3).
    fn sigma(&self, dim: usize) -> f64;
    /// The η this kernel is meant to run with (Rosswog Table 3 / CRKSPH Table D.1 mapping).
    fn default_eta(&self) -> f64;
    /// Display name.
    fn name(&self) -> String;
}

/// Stretch factor helper: σ of a kernel natively supported on `l·h`, stretched to 2h.
pub(crate) fn stretched_sigma(sigma_native: f64, native_support: f64, dim: usize) -> f64 {
    sigma_native * (native_support / SUPPORT).powi(dim as i32)
}

/// Kernel selection as it appears in case files (`kernel.name`).
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
#[serde(rename_all = "kebab-case")]
pub enum KernelName {
    /// Cubic B-spline M4.
    CubicSpline,
    /// Quartic B-spline M5.
    QuarticSpline,
    /// Quintic B-spline M6.
    QuinticSpline,
    /// Septic B-spline W7 (CRKSPH default).
    SepticSpline,
    WendlandC2,
    WendlandC4,
    WendlandC6,
    /// Sinc family W_H,n; the exponent comes from `kernel.sinc_n`.
    Sinc,
    /// Peaked linear-quartic kernel (Valcke et al. 2010), for comparison only.
    Liq,
    /// M6 with a quartic core and non-zero central slope, for comparison only.
    Qcm6,
    /// The PSPH quintic of Hopkins (2015), Frontiere, Raskin & Owen (2017) eq G.13.
    PsphQuintic,
}

impl KernelName {
    /// Every kernel: its case-file name (`kernel.name`) and what it is for, for `--help` and
    /// the case reference. A unit test checks that each name parses back to its variant.
    pub const ALL: [(KernelName, &'static str, &'static str); 11] = [
        (KernelName::CubicSpline, "cubic-spline", "M4 B-spline: cheapest; the standard preset's default; pairs beyond eta ~ 1.5; on liquids and slow gases measurably off (README)"),
        (KernelName::QuarticSpline, "quartic-spline", "M5 B-spline"),
        (KernelName::QuinticSpline, "quintic-spline", "M6 B-spline (W5 of the CRKSPH paper): compsph's kernel"),
        (KernelName::SepticSpline, "septic-spline", "W7 B-spline: CRKSPH's kernel"),
        (KernelName::WendlandC2, "wendland-c2", "Wendland C2: does not pair"),
        (KernelName::WendlandC4, "wendland-c4", "Wendland C4: the kernel for liquids and slow gases (sloshing period +0.05 %)"),
        (KernelName::WendlandC6, "wendland-c6", "Wendland C6: Rosswog F1-F3's kernel"),
        (KernelName::Sinc, "sinc", "sinc family W_H,n (Rosswog Eq. 8), exponent kernel.sinc_n = 3..9 (default 5)"),
        (KernelName::Liq, "liq", "peaked linear-quartic (Valcke et al. 2010), for comparison only"),
        (KernelName::Qcm6, "qcm6", "M6 with a quartic core and a non-zero central slope, for comparison only"),
        (KernelName::PsphQuintic, "psph-quintic", "the quintic of Hopkins (2015): PSPH's kernel"),
    ];
}

/// Runtime-chosen kernel. An enum rather than a trait object: the match is perfectly
/// predicted inside a pair loop and lets the compiler inline each shape.
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum AnyKernel {
    M4(CubicSplineM4),
    M5(QuarticSplineM5),
    M6(QuinticSplineM6),
    W7(SepticSplineW7),
    C2(WendlandC2),
    C4(WendlandC4),
    C6(WendlandC6),
    Sinc(SincKernel),
    Liq(LinearQuartic),
    Qcm6(QuarticCoreM6),
    Psph(PsphQuintic),
}

impl AnyKernel {
    /// Build from a case-file name; `sinc_n` is only used by the sinc family.
    pub fn from_name(name: KernelName, sinc_n: u32) -> Result<Self, String> {
        Ok(match name {
            KernelName::CubicSpline => AnyKernel::M4(CubicSplineM4),
            KernelName::QuarticSpline => AnyKernel::M5(QuarticSplineM5),
            KernelName::QuinticSpline => AnyKernel::M6(QuinticSplineM6),
            KernelName::SepticSpline => AnyKernel::W7(SepticSplineW7),
            KernelName::WendlandC2 => AnyKernel::C2(WendlandC2),
            KernelName::WendlandC4 => AnyKernel::C4(WendlandC4),
            KernelName::WendlandC6 => AnyKernel::C6(WendlandC6),
            KernelName::Sinc => AnyKernel::Sinc(SincKernel::new(sinc_n)?),
            KernelName::Liq => AnyKernel::Liq(LinearQuartic),
            KernelName::Qcm6 => AnyKernel::Qcm6(QuarticCoreM6),
            KernelName::PsphQuintic => AnyKernel::Psph(PsphQuintic),
        })
    }

    /// Support in the kernel's native units of h (Frontiere, Raskin & Owen (2017) Table D.1's η_max): the
    /// B-splines W_k have (k+1)/2, Wendland and the PSPH quintic 1. CRKSPH and compSPH measure
    /// their viscosity's η = |x_ij|/h in these units.
    pub fn native_support(&self) -> f64 {
        match self {
            AnyKernel::M4(_) | AnyKernel::Sinc(_) | AnyKernel::Liq(_) => 2.0,
            AnyKernel::M5(_) => 2.5,
            AnyKernel::M6(_) | AnyKernel::Qcm6(_) => 3.0,
            AnyKernel::W7(_) => 4.0,
            AnyKernel::C2(_) | AnyKernel::C4(_) | AnyKernel::C6(_) | AnyKernel::Psph(_) => 1.0,
        }
    }

    /// Display name (for tables).
    pub fn to_string_name(&self) -> String {
        Kernel::name(self)
    }

    /// Every kernel, for tests and tables.
    pub fn all() -> Vec<AnyKernel> {
        let mut v = vec![
            AnyKernel::M4(CubicSplineM4),
            AnyKernel::M5(QuarticSplineM5),
            AnyKernel::M6(QuinticSplineM6),
            AnyKernel::W7(SepticSplineW7),
            AnyKernel::C2(WendlandC2),
            AnyKernel::C4(WendlandC4),
            AnyKernel::C6(WendlandC6),
        ];
        for n in 3..=9 {
            v.push(AnyKernel::Sinc(SincKernel::new(n).expect("3..=9 is valid")));
        }
        v.push(AnyKernel::Liq(LinearQuartic));
        v.push(AnyKernel::Qcm6(QuarticCoreM6));
        v.push(AnyKernel::Psph(PsphQuintic));
        v
    }
}

macro_rules! dispatch {
    ($self:ident, $k:ident => $e:expr) => {
        match $self {
            AnyKernel::M4($k) => $e,
            AnyKernel::M5($k) => $e,
            AnyKernel::M6($k) => $e,
            AnyKernel::W7($k) => $e,
            AnyKernel::C2($k) => $e,
            AnyKernel::C4($k) => $e,
            AnyKernel::C6($k) => $e,
            AnyKernel::Sinc($k) => $e,
            AnyKernel::Liq($k) => $e,
            AnyKernel::Qcm6($k) => $e,
            AnyKernel::Psph($k) => $e,
        }
    };
}

impl Kernel for AnyKernel {
    #[inline(always)]
    fn shape(&self, q: f64) -> (f64, f64) {
        dispatch!(self, k => k.shape(q))
    }
    fn sigma(&self, dim: usize) -> f64 {
        dispatch!(self, k => k.sigma(dim))
    }
    fn default_eta(&self) -> f64 {
        dispatch!(self, k => k.default_eta())
    }
    fn name(&self) -> String {
        dispatch!(self, k => k.name())
    }
}

/// Value, radial derivative and h-derivative of W at one pair distance.
#[derive(Debug, Clone, Copy, Default, PartialEq)]
pub struct KernelEval {
    /// W(r, h)
    pub w: f64,
    /// ∂W/∂r (≤ 0); the gradient with respect to the first particle is `dwdr · r̂_ab`.
    pub dwdr: f64,
    /// ∂W/∂h = −σ/h^{D+1} [D w + q w'] (Rosswog (2015) Sec. 4), needed by the grad-h terms.
    pub dwdh: f64,
}

/// A kernel bound to a dimension, with σ precomputed. `K` is the runtime-chosen
/// [`AnyKernel`] everywhere but in the hottest pair loops, which take the concrete kernel
/// through [`DimKernel::visit`].
#[derive(Debug, Clone, Copy)]
pub struct DimKernel<const D: usize, K = AnyKernel> {
    pub kernel: K,
    sigma: f64,
}

/// A pair loop compiled once per concrete kernel (see [`DimKernel::visit`]).
pub trait KernelVisitor<const D: usize> {
    type Output;
    fn visit<K: Kernel + Copy>(self, kernel: &DimKernel<D, K>) -> Self::Output;
}

impl<const D: usize> DimKernel<D> {
    /// Run `v` with the concrete kernel type, so the shape inlines into the loop with no
    /// match per pair. In a scalar pair loop the enum's match is perfectly predicted and
    /// costs nothing measurable (the standard force pass took the same time either way), but
    /// a match inside a loop keeps the compiler from making the loop SIMD, which the lane
    /// passes ([`crate::neighbours::lanes`]) need.
    pub fn visit<V: KernelVisitor<D>>(&self, v: V) -> V::Output {
        let (sigma, kernel) = (self.sigma, &self.kernel);
        dispatch!(kernel, k => v.visit(&DimKernel::<D, _> { kernel: *k, sigma }))
    }
}

impl<const D: usize, K: Kernel + Copy> DimKernel<D, K> {
    pub fn new(kernel: K) -> Self {
        Self {
            kernel,
            sigma: kernel.sigma(D),
        }
    }

    /// Support radius for smoothing length h.
    #[inline(always)]
    pub fn radius(&self, h: f64) -> f64 {
        SUPPORT * h
    }

    #[inline(always)]
    fn hinv_pow(h: f64) -> f64 {
        let hi = 1.0 / h;
        match D {
            1 => hi,
            2 => hi * hi,
            _ => hi * hi * hi,
        }
    }

    /// W(r, h).
    #[inline(always)]
    pub fn w(&self, r: f64, h: f64) -> f64 {
        let q = r / h;
        if q >= SUPPORT {
            return 0.0;
        }
        self.sigma * Self::hinv_pow(h) * self.kernel.shape(q).0
    }

    /// W, ∂W/∂r and ∂W/∂h at distance r.
    #[inline(always)]
    pub fn eval(&self, r: f64, h: f64) -> KernelEval {
        let q = r / h;
        if q >= SUPPORT {
            return KernelEval::default();
        }
        let (w, dw) = self.kernel.shape(q);
        let norm = self.sigma * Self::hinv_pow(h);
        let hinv = 1.0 / h;
        KernelEval {
            w: norm * w,
            dwdr: norm * hinv * dw,
            dwdh: -norm * hinv * (D as f64 * w + q * dw),
        }
    }

    /// ∂W/∂r only (force loops need no value or h-derivative).
    #[inline(always)]
    pub fn dwdr(&self, r: f64, h: f64) -> f64 {
        let hinv = 1.0 / h;
        let q = r * hinv;
        if q >= SUPPORT {
            return 0.0;
        }
        self.sigma * Self::hinv_pow(h) * hinv * self.kernel.shape(q).1
    }

    /// [`Self::w`] to the bit (q = r/h), with its factor σ/h^D = `norm(1/h)` computed once
    /// per particle by the caller and a select in place of the early return, for lane
    /// passes that must reproduce `w`'s bits (Rosswog's force pass and IA sums).
    #[inline(always)]
    pub fn w_normed(&self, r: f64, h: f64, norm: f64) -> f64 {
        let q = r / h;
        let w = norm * self.kernel.shape(q).0;
        if q >= SUPPORT {
            0.0
        } else {
            w
        }
    }

    /// [`Self::dwdr`] to the bit (q = r·(1/h)), with its factor σ/h^(D+1) = `norm(1/h)·(1/h)`
    /// computed once per particle by the caller (see [`Self::w_normed`]).
    #[inline(always)]
    pub fn dwdr_normed(&self, r: f64, hinv: f64, norm_hinv: f64) -> f64 {
        let q = r * hinv;
        let dw = norm_hinv * self.kernel.shape(q).1;
        if q >= SUPPORT {
            0.0
        } else {
            dw
        }
    }

    /// W(r, h) with a precomputed 1/h (no division in the pair loop).
    #[inline(always)]
    pub fn w_hinv(&self, r: f64, hinv: f64) -> f64 {
        let q = r * hinv;
        if q >= SUPPORT {
            return 0.0;
        }
        self.norm(hinv) * self.kernel.shape(q).0
    }

    /// ∂W/∂r with a precomputed 1/h (no division in the pair loop).
    #[inline(always)]
    pub fn dwdr_hinv(&self, r: f64, hinv: f64) -> f64 {
        let q = r * hinv;
        if q >= SUPPORT {
            return 0.0;
        }
        self.norm(hinv) * hinv * self.kernel.shape(q).1
    }

    /// W and ∂W/∂r with a precomputed 1/h, from one shape evaluation (passes that need both,
    /// such as CRKSPH's pair kernels).
    #[inline(always)]
    pub fn w_dwdr_hinv(&self, r: f64, hinv: f64) -> (f64, f64) {
        let q = r * hinv;
        if q >= SUPPORT {
            return (0.0, 0.0);
        }
        let (w, dw) = self.kernel.shape(q);
        let norm = self.norm(hinv);
        (norm * w, norm * hinv * dw)
    }

    /// σ/h^D from 1/h: the factor W(r, h) = σ/h^D · w(r/h) shares over all r.
    #[inline(always)]
    pub fn norm(&self, hinv: f64) -> f64 {
        let hd = match D {
            1 => hinv,
            2 => hinv * hinv,
            _ => hinv * hinv * hinv,
        };
        self.sigma * hd
    }

    /// W(0, h): the self-contribution.
    #[inline(always)]
    pub fn w0(&self, h: f64) -> f64 {
        self.sigma * Self::hinv_pow(h) * self.kernel.shape(0.0).0
    }

    /// ∂W/∂h at r = 0 (self term of the grad-h sums).
    #[inline(always)]
    pub fn dwdh0(&self, h: f64) -> f64 {
        -(D as f64) * self.w0(h) / h
    }
}

/// Expected neighbours inside the 2h support for `h = η·Δx` on a uniform distribution.
pub fn neighbours_for_eta(eta: f64, dim: usize) -> f64 {
    match dim {
        1 => 2.0 * SUPPORT * eta,
        2 => PI * (SUPPORT * eta).powi(2),
        _ => 4.0 / 3.0 * PI * (SUPPORT * eta).powi(3),
    }
}

#[cfg(test)]
mod name_tests {
    use super::KernelName;

    /// `KernelName::ALL` names every kernel by its case-file name (the `--help` list).
    #[test]
    fn every_listed_kernel_name_parses_to_its_variant() {
        #[derive(serde::Deserialize)]
        struct K {
            name: KernelName,
        }
        for (k, name, _) in KernelName::ALL {
            let parsed: K = toml::from_str(&format!("name = {name:?}")).unwrap();
            assert_eq!(parsed.name, k, "{name}");
        }
    }
}
