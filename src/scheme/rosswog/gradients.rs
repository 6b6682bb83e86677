//! Integral-approximation gradient matrices (Rosswog (2015) Eqs. 16–25, Eqs. 20–25):
//! τ_a = Σ_b V_b (r_b − r_a)(r_b − r_a)ᵀ W_ab(h_a), C_a = τ_a⁻¹, and in the same pass the
//! linearly exact fIA velocity gradient (∂v^i/∂x^k)_a = C_a^{kd} Σ_b V_b (v_b − v_a)^i (r_b − r_a)^d W_ab(h_a)
//! that the dissipation triggers use in every formulation (§3.5).
//!
//! Near-singular τ (isolated particles, planar or one-sided neighbourhoods) is not inverted:
//! the particle falls back to the kernel gradient, counted in the diagnostics, never a NaN.
//! The test is det(τ) < ε·(tr τ / D)^D with ε = [`CONDITION_FLOOR`] — the paper gives no guard.

use crate::particles::Vector;
use crate::system::System;
use nalgebra::SMatrix;
use rayon::prelude::*;

/// Relative determinant below which τ counts as singular.
pub const CONDITION_FLOOR: f64 = 1e-6;

/// Per-particle IA data.
#[derive(Debug, Clone, Copy)]
pub struct IaMatrix<const D: usize> {
    /// C = τ⁻¹ (zero when `fallback`).
    pub c: SMatrix<f64, D, D>,
    /// τ was near-singular: use the kernel gradient for this particle.
    pub fallback: bool,
}

/// C and the fallback flag (as 0 or 1), for a distributed run's halo refresh.
impl<const D: usize> crate::parallel::HaloRow for IaMatrix<D> {
    const WIDTH: usize = D * D + 1;
    fn put(&self, out: &mut Vec<f64>) {
        out.extend_from_slice(self.c.as_slice());
        out.push(f64::from(u8::from(self.fallback)));
    }
    fn take(x: &[f64]) -> Self {
        Self {
            c: SMatrix::from_column_slice(&x[..D * D]),
            fallback: x[D * D] != 0.0,
        }
    }
}

/// R C R for the mirror image `code` (R flips the mirrored axes).
pub fn reflect<const D: usize>(c: &SMatrix<f64, D, D>, code: u8) -> SMatrix<f64, D, D> {
    let mut out = *c;
    for i in 0..D {
        for j in 0..D {
            let fi = crate::domain::Domain::<D>::digit(code, i) != 0;
            let fj = crate::domain::Domain::<D>::digit(code, j) != 0;
            if fi != fj {
                out[(i, j)] = -out[(i, j)];
            }
        }
    }
    out
}

/// Invert τ if well conditioned.
pub fn invert<const D: usize>(tau: &SMatrix<f64, D, D>) -> Option<SMatrix<f64, D, D>> {
    let tr = tau.trace() / D as f64;
    if !(tr > 0.0 && tr.is_finite()) {
        return None;
    }
    // Analytic inverse (Rosswog (2015) Eqs. 16–25): C = adj(τ)/det(τ).
    let t = |i: usize, j: usize| tau[(i, j)];
    let mut c = SMatrix::<f64, D, D>::zeros();
    let det = match D {
        1 => {
            c[(0, 0)] = 1.0;
            t(0, 0)
        }
        2 => {
            c[(0, 0)] = t(1, 1);
            c[(1, 1)] = t(0, 0);
            c[(0, 1)] = -t(0, 1);
            c[(1, 0)] = -t(1, 0);
            t(0, 0) * t(1, 1) - t(0, 1) * t(1, 0)
        }
        _ => {
            let c11 = t(1, 1) * t(2, 2) - t(1, 2) * t(2, 1);
            let c22 = t(0, 0) * t(2, 2) - t(0, 2) * t(2, 0);
            let c33 = t(0, 0) * t(1, 1) - t(0, 1) * t(1, 0);
            let c12 = t(0, 2) * t(2, 1) - t(0, 1) * t(2, 2);
            let c13 = t(0, 1) * t(1, 2) - t(0, 2) * t(1, 1);
            let c23 = t(0, 2) * t(1, 0) - t(0, 0) * t(1, 2);
            let c21 = t(1, 2) * t(2, 0) - t(1, 0) * t(2, 2);
            let c31 = t(1, 0) * t(2, 1) - t(1, 1) * t(2, 0);
            let c32 = t(0, 1) * t(2, 0) - t(0, 0) * t(2, 1);
            c[(0, 0)] = c11;
            c[(0, 1)] = c12;
            c[(0, 2)] = c13;
            c[(1, 0)] = c21;
            c[(1, 1)] = c22;
            c[(1, 2)] = c23;
            c[(2, 0)] = c31;
            c[(2, 1)] = c32;
            c[(2, 2)] = c33;
            t(0, 0) * c11 + t(0, 1) * c21 + t(0, 2) * c31
        }
    };
    if det.is_nan() || det <= CONDITION_FLOOR * tr.powi(D as i32) {
        return None;
    }
    Some(c / det)
}

/// One pass: C_a for every particle and the fIA velocity gradient (written to div_v / curl_v,
/// and returned as full tensors). Volumes V_b = m_b/ρ_b.
pub fn ia_pass<const D: usize>(
    sys: &mut System<D>,
) -> (Vec<IaMatrix<D>>, Vec<SMatrix<f64, D, D>>, u64) {
    let acc = super::ia_sums::ia_sums(sys);
    sys.stats.total_pairs += sys.neighbours.total_pairs() as u64;
    let out: Vec<(IaMatrix<D>, SMatrix<f64, D, D>)> = acc
        .par_iter()
        .map(|(tau, iv)| match invert(tau) {
            Some(c) => {
                // ∂v^i/∂x^k = C^{kd} I^{id}  →  grad = I · Cᵀ (C symmetric)
                let grad = iv * c.transpose();
                (IaMatrix { c, fallback: false }, grad)
            }
            None => (
                IaMatrix {
                    c: SMatrix::zeros(),
                    fallback: true,
                },
                SMatrix::zeros(),
            ),
        })
        .collect();
    let fallbacks = out.iter().filter(|o| o.0.fallback).count() as u64;
    let (mats, grads): (Vec<_>, Vec<_>) = out.into_iter().unzip();
    let p = &mut sys.particles;
    for ((dv, cv), g) in p.div_v.iter_mut().zip(p.curl_v.iter_mut()).zip(&grads) {
        *dv = g.trace();
        *cv = super::super::standard::curl_norm(g);
    }
    (mats, grads, fallbacks)
}

/// The gradient estimators of Rosswog (2015) Sec. 3.2–3.6 (Eqs. 6, 10, 11–15, 21, 23–24).
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum GradientEstimator {
    /// Σ_b V_b f_b ∇_a W_ab(h_a)
    Kernel,
    /// constant-exact: Σ_b V_b (f_b − f_a) ∇_a W_ab(h_a)
    ConstantExact,
    /// linearly exact (Price 2004): (Aᵀ)⁻¹ J with A^{ik} = Σ V_b (r_b − r_a)^i ∇^k W
    LinearExact,
    /// full integral approximation: C Σ_b V_b (f_b − f_a)(r_b − r_a) W
    FullIntegral,
    /// antisymmetric integral approximation: Σ_b V_b f_b C (r_b − r_a) W
    Integral,
}

/// Gradient of the per-particle field `f` with estimator `est` at every particle, with
/// V_b = m_b/ρ_b and a's own h. For fields that are not periodic, `f_of(a, b, dx)` gives the
/// value of f at neighbour b as seen from a (dx = x_a − image(x_b)), e.g. f_a − dx for f = x.
/// Particles whose matrix is singular get the kernel gradient (and are counted).
pub fn field_gradient<const D: usize>(
    sys: &System<D>,
    est: GradientEstimator,
    f: &[f64],
    f_of: impl Fn(usize, usize, &Vector<D>) -> f64 + Sync,
) -> (Vec<Vector<D>>, u64) {
    let n = sys.particles.len();
    // per particle: Σ V f ∇W, Σ V (f_b − f_a) ∇W, A, Σ V (f_b − f_a) d W, τ, Σ V f_b d W
    type Sums<const D: usize> = (
        Vector<D>,
        Vector<D>,
        SMatrix<f64, D, D>,
        Vector<D>,
        SMatrix<f64, D, D>,
        Vector<D>,
    );
    let zero = || {
        (
            Vector::zeros(),
            Vector::zeros(),
            SMatrix::zeros(),
            Vector::zeros(),
            SMatrix::zeros(),
            Vector::zeros(),
        )
    };
    let mut acc: Vec<Sums<D>> = (0..n).map(|_| zero()).collect();
    let p = &sys.particles;
    let k = &sys.kernel;
    sys.gather(&mut acc, |a, s, pr| {
        let e = k.eval(pr.r, p.h[a]);
        if e.w == 0.0 && e.dwdr == 0.0 {
            return;
        }
        let vb = p.mass[pr.b] / p.rho[pr.b];
        let fb = f_of(a, pr.b, &pr.dx);
        let d: Vector<D> = -pr.dx; // r_b − r_a
        let gw: Vector<D> = if pr.r > 0.0 {
            pr.dx * (e.dwdr / pr.r)
        } else {
            Vector::zeros()
        };
        s.0 += gw * (vb * fb);
        s.1 += gw * (vb * (fb - f[a]));
        s.2 += d * gw.transpose() * vb;
        s.3 += d * (vb * (fb - f[a]) * e.w);
        s.4 += d * d.transpose() * (vb * e.w);
        s.5 += d * (vb * fb * e.w);
    });
    let mut fallbacks = 0;
    let out = acc
        .iter()
        .map(|s| {
            let kernel = s.0 + Vector::<D>::zeros();
            match est {
                GradientEstimator::Kernel => kernel,
                GradientEstimator::ConstantExact => s.1,
                GradientEstimator::LinearExact => match invert_general(&s.2.transpose()) {
                    Some(m) => m * s.1,
                    None => {
                        fallbacks += 1;
                        kernel
                    }
                },
                GradientEstimator::FullIntegral | GradientEstimator::Integral => match invert(&s.4)
                {
                    Some(c) => {
                        c * if est == GradientEstimator::FullIntegral {
                            s.3
                        } else {
                            s.5
                        }
                    }
                    None => {
                        fallbacks += 1;
                        kernel
                    }
                },
            }
        })
        .collect();
    (out, fallbacks)
}

/// Inverse of a general (not necessarily symmetric) D×D matrix, None when near-singular.
fn invert_general<const D: usize>(m: &SMatrix<f64, D, D>) -> Option<SMatrix<f64, D, D>> {
    // (mᵀ m) is symmetric positive semi-definite: reuse the guarded analytic inverse.
    let mtm = m.transpose() * m;
    invert(&mtm).map(|inv| inv * m.transpose())
}
