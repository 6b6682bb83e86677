//! Cullen & Dehnen (2010) viscosity switch in Hopkins' form (Frontiere, Raskin & Owen (2017) App F, App F, eqs
//! F.3–F.6), usable with compSPH, standard SPH and PSPH: every particle carries a viscosity
//! coefficient α_i that rises when the flow starts to converge (∂t ∇·v < 0) and decays
//! otherwise, limited in shear.
//!
//! Decisions for Frontiere, Raskin & Owen (2017), a point the paper leaves open (decided here), made here:
//! * β_ξ = 1 (Hopkins); ξ_i uses the neighbour's sgn(∇·v_j) (F.4 as Spheral codes it).
//! * F.5's denominator is α_max|∂t∇·v| + β_c c_i² (f_kern h_i)⁻², the paper's c_i² (Spheral
//!   uses v_sig²), with h_i the kernel support (our 2h).
//! * ∂t(∇·v) = (∇·v_now − ∇·v_prev)/Δt between the final-stage evaluations of two steps;
//!   α0 starts at α_min and ∇·v_prev at 0, so a flow converging at t = 0 switches on at once.
//! * α is updated after each step (`end_step`) and held during the next one.
//!
//! ∇v is the linearly corrected SPH gradient (E.4 with E.6), exact for linear fields.

use crate::kernel::{DimKernel, Kernel, KernelVisitor};
use crate::neighbours::lanes::{for_each_row, inverse_h};
use crate::system::System;
use crate::threads::LIGHT;
use measure::{GradientRecord, GradientRows, GradientSums, XiRows};
use nalgebra::SMatrix;
use rayon::prelude::*;

mod measure;

/// Constants of the switch (Frontiere, Raskin & Owen (2017) App F, [P]).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct CullenParams {
    pub alpha_min: f64,
    pub alpha_max: f64,
    pub beta_c: f64,
    pub beta_d: f64,
    pub beta_xi: f64,
    pub f_kern: f64,
}

impl Default for CullenParams {
    fn default() -> Self {
        Self {
            alpha_min: 0.02,
            alpha_max: 2.0,
            beta_c: 0.7,
            beta_d: 0.05,
            beta_xi: 1.0,
            f_kern: 1.0 / 3.0,
        }
    }
}

/// The switch's per-particle fields live in `extra_scalars` so particle reorders carry them.
#[derive(Debug, Clone, Copy)]
pub struct CullenDehnen {
    pub params: CullenParams,
    alpha0: usize,
    div_prev: usize,
    /// ξ_i (F.4) and the shear norm S:S of the latest evaluation
    xi: usize,
    shear2: usize,
    /// v_sig,i = max_j [½(c_i + c_j) − min(0, v_ij·x̂_ij)] of the latest evaluation
    vsig: usize,
}

impl CullenDehnen {
    /// Register the fields; α = α0 = α_min to start.
    pub fn init<const D: usize>(sys: &mut System<D>, params: CullenParams) -> Self {
        let p = &mut sys.particles;
        let s = Self {
            params,
            alpha0: p.add_scalar_field(params.alpha_min),
            div_prev: p.add_scalar_field(0.0),
            xi: p.add_scalar_field(1.0),
            shear2: p.add_scalar_field(0.0),
            vsig: p.add_scalar_field(0.0),
        };
        p.alpha.iter_mut().for_each(|a| *a = params.alpha_min);
        s
    }

    /// The corrected velocity gradient (E.4/E.6) → `div_v`, `curl_v`, S:S; then ξ (F.4) and
    /// v_sig. Needs ρ, h and c of the current state.
    pub fn measure<const D: usize>(&self, sys: &mut System<D>) {
        let t0 = std::time::Instant::now();
        let kernel = sys.kernel;
        kernel.visit(Measure { cd: self, sys });
        sys.stats.total_pairs += 2 * sys.neighbours.total_pairs() as u64;
        sys.stats.seconds_gradients += t0.elapsed().as_secs_f64();
    }

    /// Evolve α0 over the step just taken (F.5, F.6) and set α (F.3).
    pub fn end_step<const D: usize>(&self, sys: &mut System<D>, dt: f64) {
        if dt.is_nan() || dt <= 0.0 {
            return;
        }
        let c = self.params;
        let p = &mut sys.particles;
        for i in 0..p.len() {
            let div = p.div_v[i];
            let ddt = (div - p.extra_scalars[self.div_prev][i]) / dt;
            p.extra_scalars[self.div_prev][i] = div;
            let h_supp = crate::kernel::SUPPORT * p.h[i];
            let alpha_tmp = if ddt >= 0.0 || div >= 0.0 {
                0.0
            } else {
                let a = c.alpha_max * ddt.abs();
                let cs = p.sound_speed[i];
                a / (a + c.beta_c * cs * cs / (c.f_kern * h_supp).powi(2))
            };
            let a0 = p.extra_scalars[self.alpha0][i];
            let vsig = p.extra_scalars[self.vsig][i];
            let a0_new = if alpha_tmp >= a0 {
                alpha_tmp
            } else {
                alpha_tmp
                    + (a0 - alpha_tmp) * (-c.beta_d * dt * vsig / (2.0 * c.f_kern * h_supp)).exp()
            };
            p.extra_scalars[self.alpha0][i] = a0_new;
            let xi = p.extra_scalars[self.xi][i];
            let x = (c.beta_xi * xi.powi(4) * div).powi(2);
            let s2 = p.extra_scalars[self.shear2][i];
            let limiter = if x + s2 > 0.0 { x / (x + s2) } else { 1.0 };
            p.alpha[i] = (a0_new * limiter).max(c.alpha_min);
        }
    }
}

/// [`CullenDehnen::measure`] with the concrete kernel.
struct Measure<'a, const D: usize> {
    cd: &'a CullenDehnen,
    sys: &'a mut System<D>,
}

impl<const D: usize> KernelVisitor<D> for Measure<'_, D> {
    type Output = ();
    fn visit<K: Kernel + Copy>(self, kernel: &DimKernel<D, K>) {
        let (cd, sys) = (self.cd, self.sys);
        let n = sys.particles.len();
        let p = &sys.particles;
        let hinv = inverse_h(&p.h);
        let recs: Vec<GradientRecord<D>> = (0..n)
            .into_par_iter()
            .with_min_len(LIGHT)
            .map(|a| GradientRecord {
                x: p.pos[a],
                v: p.vel[a],
                m: p.mass[a],
                c: p.sound_speed[a],
            })
            .collect();
        let mut sums = vec![GradientSums::<D>::default(); n];
        let rows = GradientRows {
            sys,
            recs: &recs,
            hinv: &hinv,
            kernel: *kernel,
        };
        for_each_row(&rows, &mut sums);
        let grads: Vec<SMatrix<f64, D, D>> = sums
            .par_iter()
            .enumerate()
            .with_min_len(LIGHT)
            .map(|(i, s)| {
                // E.6 makes E.4 exact for linear v. M = Σ m x ⊗ ∇W is negative definite
                // (∂W/∂r ≤ 0), so invert −M and flip the sign; fall back to the plain estimate
                // when M is near-singular (Spheral: |det M| > 1e-10)
                match super::rosswog::gradients::invert(&-s.m) {
                    Some(minv) => -(s.v * minv),
                    None => -s.v / p.rho[i],
                }
            })
            .collect();
        {
            let sync = sys.halo_sync();
            let p = &mut sys.particles;
            let d = D as f64;
            for (i, g) in grads.iter().enumerate() {
                let div = g.trace();
                p.div_v[i] = div;
                p.curl_v[i] = super::standard::curl_norm(g);
                let s = (g + g.transpose()) * 0.5 - SMatrix::<f64, D, D>::identity() * (div / d);
                p.extra_scalars[cd.shear2][i] = (s * s).trace();
            }
            // ξ (F.4) sums the signs of the neighbours' ∇·v
            sync.refresh(vec![crate::parallel::rows(&mut p.div_v)]);
        }
        let p = &sys.particles;
        let weight: Vec<f64> = (0..n).map(|j| p.div_v[j].signum() * p.mass[j]).collect();
        let mut xi = vec![0.0; n];
        let rows = XiRows {
            sys,
            x: &p.pos,
            weight: &weight,
            hinv: &hinv,
            kernel: *kernel,
        };
        for_each_row(&rows, &mut xi);
        let p = &mut sys.particles;
        for i in 0..n {
            let self_term = weight[i] * kernel.w0(p.h[i]);
            p.extra_scalars[cd.xi][i] = 1.0 - (xi[i] + self_term) / p.rho[i];
            p.extra_scalars[cd.vsig][i] = sums[i].vsig.max(p.sound_speed[i]);
        }
    }
}
