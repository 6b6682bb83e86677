//! Linear reproducing kernels (Frontiere, Raskin & Owen (2017) §2.1; eqs 8–23; App A; Frontiere, Raskin & Owen 2017, eqs 8–23).
//!
//! Volumes V_i = 1/Σ_j W(x_ij, h_i) (eq 75, gather kernel, self included). With the symmetrised
//! kernel W_ij = ½[W(x_ij, h_i) + W(x_ij, h_j)] and ∇_i W_ij = ½[∇W(h_i) + ∇W(h_j)] the moments
//! m0, m1, m2 and their gradients (eqs 16–21, sums over j including i) give
//! B = −m2⁻¹ m1, A = 1/(m0 + B·m1), ∂A = −A²(∂m0 + 2 B^α ∂m1^α + B^α B^β ∂m2^{αβ}),
//! ∂B^α = −M^{αβ}(∂m1^β + ∂m2^{βψ} B^ψ) (compact forms of eqs 14–15, Frontiere, Raskin & Owen (2017) eqs 12–15; App A; compact forms R; verified), and the
//! corrected kernel W^R_ij = A_i(1 + B_i·x_ij) W_ij with gradient G_ij (eq 9, Frontiere, Raskin & Owen (2017) eqs 8–9).
//! Gradients are with respect to the evaluation point x_i, V_j and h held fixed; every node,
//! including i itself, stays where it is (so the self term contributes V_i W(0) δ^{αγ} to ∂m1).

use super::pair_kernels::PairKernel;
use crate::domain::Domain;
use crate::neighbours::unpack;
use crate::particles::Vector;
use crate::scheme::rosswog::gradients::invert;
use crate::system::System;
use nalgebra::SMatrix;
use rayon::prelude::*;

/// Correction coefficients of one particle.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct RkCoefficients<const D: usize> {
    pub a: f64,
    pub b: Vector<D>,
    pub grad_a: Vector<D>,
    /// grad_b[(α, γ)] = ∂_γ B^α
    pub grad_b: SMatrix<f64, D, D>,
}

/// The coefficients as numbers, for a distributed run's halo refresh between passes.
impl<const D: usize> crate::parallel::HaloRow for RkCoefficients<D> {
    const WIDTH: usize = 1 + 2 * D + D * D;
    fn put(&self, out: &mut Vec<f64>) {
        out.push(self.a);
        out.extend_from_slice(self.b.as_slice());
        out.extend_from_slice(self.grad_a.as_slice());
        out.extend_from_slice(self.grad_b.as_slice());
    }
    fn take(x: &[f64]) -> Self {
        Self {
            a: x[0],
            b: Vector::from_column_slice(&x[1..1 + D]),
            grad_a: Vector::from_column_slice(&x[1 + D..1 + 2 * D]),
            grad_b: SMatrix::from_column_slice(&x[1 + 2 * D..]),
        }
    }
}

/// Reproducing order: linear (the paper's default) or zeroth (B ≡ 0, exact angular momentum).
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum RkOrder {
    Zeroth,
    Linear,
}

impl<const D: usize> RkCoefficients<D> {
    /// The coefficients of particle `i`'s mirror image `code` (vectors reflected, ∂B → R ∂B R).
    pub fn reflected(&self, code: u8) -> Self {
        if code == 0 {
            return *self;
        }
        let flip = |k: usize| Domain::<D>::digit(code, k) != 0;
        let mut out = *self;
        for k in 0..D {
            if flip(k) {
                out.b[k] = -out.b[k];
                out.grad_a[k] = -out.grad_a[k];
            }
        }
        for i in 0..D {
            for j in 0..D {
                if flip(i) != flip(j) {
                    out.grad_b[(i, j)] = -out.grad_b[(i, j)];
                }
            }
        }
        out
    }

    /// W^R_ij and its gradient G_ij for the pair separation x_ij = x_i − x_j with the
    /// symmetrised kernel value `w` and gradient `gw` (Frontiere, Raskin & Owen (2017) eqs 8–9).
    #[inline]
    pub fn corrected(&self, xij: &Vector<D>, w: f64, gw: &Vector<D>) -> (f64, Vector<D>) {
        let lin = 1.0 + self.b.dot(xij);
        let wr = self.a * lin * w;
        // G^γ = A(1 + B·x)∂γW + ∂γA (1 + B·x) W + A(∂γB^α x^α + B^γ) W
        let g = gw * (self.a * lin)
            + self.grad_a * (lin * w)
            + (self.grad_b.transpose() * xij + self.b) * (self.a * w);
        (wr, g)
    }
}

/// V_i = 1 / Σ_j W(x_ij, h_i), self included (eq 75).
pub fn volumes<const D: usize>(sys: &System<D>) -> Vec<f64> {
    let n = sys.particles.len();
    let mut sums = vec![0.0; n];
    let p = &sys.particles;
    let k = &sys.kernel;
    sys.gather(&mut sums, |a, s, pr| *s += k.w(pr.r, p.h[a]));
    sums.iter()
        .enumerate()
        .map(|(a, s)| 1.0 / (s + k.w0(p.h[a])))
        .collect()
}

/// Symmetrised kernel value and gradient (w.r.t. x_i) for a pair at distance r along dx: the
/// plain formula, for checks ([`super::pair_kernels`] computes them for a whole list).
#[inline]
pub fn symmetric_kernel<const D: usize>(
    sys: &System<D>,
    hi: f64,
    hj: f64,
    dx: &Vector<D>,
    r: f64,
) -> (f64, Vector<D>) {
    let k = &sys.kernel;
    let (ei, ej) = (k.eval(r, hi), k.eval(r, hj));
    let w = 0.5 * (ei.w + ej.w);
    let gw = if r > 0.0 {
        dx * (0.5 * (ei.dwdr + ej.dwdr) / r)
    } else {
        Vector::zeros()
    };
    (w, gw)
}

#[derive(Clone, Copy)]
struct Moments<const D: usize> {
    m0: f64,
    m1: Vector<D>,
    m2: SMatrix<f64, D, D>,
    dm0: Vector<D>,
    /// dm1[(α, γ)] = ∂γ m1^α
    dm1: SMatrix<f64, D, D>,
    /// dm2[γ][(α, β)] = ∂γ m2^{αβ}
    dm2: [SMatrix<f64, D, D>; D],
}

/// The pair sums the moments are made of. Every pair kernel gradient lies along the pair,
/// ∇W̄ = ḡ x (see [`PairKernel`]), so with a = V W̄ and b = V ḡ the moments (eqs 16–21) are
///   m0 = Σ a,  m1 = Σ a x,  m2 = Σ a x⊗x,  ∂m0 = Σ b x,
///   ∂_γ m1^α = Σ b x^α x^γ + δ^{αγ} m0,
///   ∂_γ m2^{αβ} = Σ b x^α x^β x^γ + m1^α δ^{βγ} + m1^β δ^{αγ},
/// which takes 15 running sums per particle in 2D and 29 in 3D (the last two tensors are
/// symmetric, so only α ≤ β ≤ γ is summed) where adding the moments pair by pair took 21 and 52
/// (with the identity and unit-vector products that nalgebra builds for each).
#[derive(Clone, Copy)]
struct PairSums<const D: usize> {
    s0: f64,
    s1: [f64; D],
    s2: [[f64; D]; D],
    t1: [f64; D],
    t2: [[f64; D]; D],
    t3: [[[f64; D]; D]; D],
}

impl<const D: usize> PairSums<D> {
    fn zero() -> Self {
        Self {
            s0: 0.0,
            s1: [0.0; D],
            s2: [[0.0; D]; D],
            t1: [0.0; D],
            t2: [[0.0; D]; D],
            t3: [[[0.0; D]; D]; D],
        }
    }

    /// Add node j with volume v at separation x = x_i − x_j and pair kernel (W̄, ḡ).
    #[inline(always)]
    fn add(&mut self, v: f64, x: &Vector<D>, w: f64, g: f64) {
        let (a, b) = (v * w, v * g);
        self.s0 += a;
        for al in 0..D {
            let (ax, bx) = (a * x[al], b * x[al]);
            self.s1[al] += ax;
            self.t1[al] += bx;
            for be in al..D {
                let bxx = bx * x[be];
                self.s2[al][be] += ax * x[be];
                self.t2[al][be] += bxx;
                for ga in be..D {
                    self.t3[al][be][ga] += bxx * x[ga];
                }
            }
        }
    }

    /// The moments and their gradients, the symmetric halves filled in.
    fn moments(&self) -> Moments<D> {
        let m1 = Vector::<D>::from_fn(|al, _| self.s1[al]);
        let sym2 = |t: &[[f64; D]; D], al: usize, be: usize| t[al.min(be)][al.max(be)];
        let m2 = SMatrix::<f64, D, D>::from_fn(|al, be| sym2(&self.s2, al, be));
        let dm1 = SMatrix::<f64, D, D>::from_fn(|al, ga| {
            sym2(&self.t2, al, ga) + if al == ga { self.s0 } else { 0.0 }
        });
        let dm2 = std::array::from_fn(|ga| {
            SMatrix::<f64, D, D>::from_fn(|al, be| {
                let mut k = [al, be, ga];
                k.sort_unstable();
                let mut d = self.t3[k[0]][k[1]][k[2]];
                if be == ga {
                    d += m1[al];
                }
                if al == ga {
                    d += m1[be];
                }
                d
            })
        });
        Moments {
            m0: self.s0,
            m1,
            m2,
            dm0: Vector::from_fn(|al, _| self.t1[al]),
            dm1,
            dm2,
        }
    }
}

impl<const D: usize> Moments<D> {
    fn coefficients(&self, order: RkOrder) -> Option<RkCoefficients<D>> {
        if order == RkOrder::Zeroth || D == 0 {
            let a = 1.0 / self.m0;
            return Some(RkCoefficients {
                a,
                b: Vector::zeros(),
                grad_a: -self.dm0 * (a * a),
                grad_b: SMatrix::zeros(),
            });
        }
        let m = invert(&self.m2)?;
        let b = -(m * self.m1);
        let a = 1.0 / (self.m0 + b.dot(&self.m1));
        let mut grad_a = Vector::<D>::zeros();
        let mut grad_b = SMatrix::<f64, D, D>::zeros();
        for g in 0..D {
            let dm1_g: Vector<D> = self.dm1.column(g).into_owned();
            grad_a[g] = -a * a * (self.dm0[g] + 2.0 * b.dot(&dm1_g) + b.dot(&(self.dm2[g] * b)));
            let col = -(m * (dm1_g + self.dm2[g] * b));
            for al in 0..D {
                grad_b[(al, g)] = col[al];
            }
        }
        Some(RkCoefficients {
            a,
            b,
            grad_a,
            grad_b,
        })
    }
}

/// Correction coefficients for every particle (volumes from [`volumes`] or
/// [`super::pair_kernels::pair_kernels_and_volumes`]) and the fallback count: see
/// [`coefficients_and_density`].
pub fn coefficients<const D: usize>(
    sys: &System<D>,
    vol: &[f64],
    kern: &[PairKernel],
    order: RkOrder,
) -> (Vec<RkCoefficients<D>>, u64) {
    let state = coefficients_and_density(sys, vol, kern, order);
    (state.coef, state.fallbacks)
}

/// What [`coefficients_and_density`] gives.
pub struct CorrectedState<const D: usize> {
    pub coef: Vec<RkCoefficients<D>>,
    /// ρ of eq 76
    pub rho: Vec<f64>,
    /// particles whose second moment was near singular (zeroth order used)
    pub fallbacks: u64,
}

/// Correction coefficients for every particle, and the CRKSPH mass density (Frontiere, Raskin
/// & Owen (2017) eq 76): ρ_i = Σ_j m_ij V_j W^R_ij / Σ_j V_j² W^R_ij with m_ij = m_j for the
/// same material and m_i across materials, sums including j = i. On a uniform lattice this
/// gives exact piecewise-constant densities across a static material boundary.
///
/// W^R_ij needs only i's own coefficients, so ρ_i comes from a second sweep over i's row right
/// after its coefficients, with the separations kept from the first (one pass over the list
/// where a separate density gather cost as much again). A near-singular second moment (too
/// few or one-sided neighbours) falls back to zeroth order, counted.
pub fn coefficients_and_density<const D: usize>(
    sys: &System<D>,
    vol: &[f64],
    kern: &[PairKernel],
    order: RkOrder,
) -> CorrectedState<D> {
    let n = sys.particles.len();
    let p = &sys.particles;
    let dom = &sys.domain;
    let out: Vec<(RkCoefficients<D>, f64, bool)> = (0..n)
        .into_par_iter()
        .with_min_len(64)
        .map_init(Vec::new, |seps: &mut Vec<Vector<D>>, i| {
            let mut sums = PairSums::<D>::zero();
            let w0 = sys.kernel.w0(p.h[i]);
            // self term: x_ii = 0, ∇W_ii = 0
            sums.add(vol[i], &Vector::zeros(), w0, 0.0);
            let first = sys.neighbours.offsets[i];
            let row = sys.neighbours.of(i);
            seps.clear();
            for (k, &e) in row.iter().enumerate() {
                let (j, code) = unpack(e);
                let dx = dom.separation(&p.pos[i], &p.pos[j], code);
                let pk = kern[first + k];
                sums.add(vol[j], &dx, pk.w, pk.g);
                seps.push(dx);
            }
            let mo = sums.moments();
            let (c, fallback) = match mo.coefficients(order) {
                Some(c) => (c, false),
                None => (
                    mo.coefficients(RkOrder::Zeroth).expect("zeroth order"),
                    true,
                ),
            };
            let (mut num, mut den) = (0.0, 0.0);
            for (k, (&e, dx)) in row.iter().zip(seps.iter()).enumerate() {
                let j = unpack(e).0;
                let (wr, _) = c.corrected(dx, kern[first + k].w, &Vector::zeros());
                let mij = if p.material[i] == p.material[j] {
                    p.mass[j]
                } else {
                    p.mass[i]
                };
                num += mij * vol[j] * wr;
                den += vol[j] * vol[j] * wr;
            }
            let (wr0, _) = c.corrected(&Vector::zeros(), w0, &Vector::zeros());
            let rho = (num + p.mass[i] * vol[i] * wr0) / (den + vol[i] * vol[i] * wr0);
            (c, rho, fallback)
        })
        .collect();
    CorrectedState {
        fallbacks: out.iter().filter(|o| o.2).count() as u64,
        rho: out.iter().map(|o| o.1).collect(),
        coef: out.into_iter().map(|o| o.0).collect(),
    }
}
