//! Initial conditions: lattices filling regions, smoothed interfaces, random perturbations.

use super::{Case, CaseError, Lattice, Region, Shape};
use crate::domain::Domain;
use crate::eos::Eos;
use crate::particles::{Particles, Vector};

/// Deterministic PRNG (SplitMix64) so a seed gives the same case on every platform and version.
pub struct SplitMix64(u64);

impl SplitMix64 {
    pub fn new(seed: u64) -> Self {
        Self(seed)
    }
    pub fn next_u64(&mut self) -> u64 {
        self.0 = self.0.wrapping_add(0x9E37_79B9_7F4A_7C15);
        let mut z = self.0;
        z = (z ^ (z >> 30)).wrapping_mul(0xBF58_476D_1CE4_E5B9);
        z = (z ^ (z >> 27)).wrapping_mul(0x94D0_49BB_1331_11EB);
        z ^ (z >> 31)
    }
    /// Uniform in [0, 1).
    pub fn uniform(&mut self) -> f64 {
        (self.next_u64() >> 11) as f64 * (1.0 / (1u64 << 53) as f64)
    }
}

/// Volume per particle of a lattice with nearest-neighbour spacing a (rings: Δr², the mean
/// over their annuli).
pub(super) fn volume_per_particle(lattice: Lattice, d: usize, a: f64) -> f64 {
    match (lattice, d) {
        (_, 1) | (Lattice::Cubic | Lattice::Rings, _) => a.powi(d as i32),
        (Lattice::Hexagonal | Lattice::QuasiHexagonal, 2) => 0.5 * 3f64.sqrt() * a * a,
        (Lattice::Hexagonal | Lattice::QuasiHexagonal, _) => a * a * a / 2f64.sqrt(),
    }
}

impl Case {
    /// A region's density where one number is needed (its `density`, or the mean of its
    /// `density_profile` over its box: the particle count of an equal-mass lattice, the
    /// default wall density). NaN when the profile does not evaluate (validation says why).
    pub(crate) fn reference_density(&self, r: &Region) -> f64 {
        if let Some(rho) = r.density {
            return rho;
        }
        let d = self.case.dimension;
        let Some(Ok(f)) = r
            .density_profile
            .as_ref()
            .map(|f| f.compile("density_profile", d))
        else {
            return f64::NAN;
        };
        let (lo, hi) = self.region_box(r);
        const N: usize = 32;
        let mut sum = 0.0;
        let total = N.pow(d as u32);
        for lin in 0..total {
            let mut x = vec![0.0; d];
            let mut rest = lin;
            for k in 0..d {
                x[k] = lo[k] + (hi[k] - lo[k]) * ((rest % N) as f64 + 0.5) / N as f64;
                rest /= N;
            }
            sum += f.at(&x).unwrap_or(f64::NAN);
        }
        sum / total as f64
    }
}

/// Concentric rings about `c` out to `radius`, Δr = `dr` apart: ring i at (i + ½)Δr holds
/// max(1, round(2πr/Δr)) points, every other ring turned by half a step; each point's volume
/// is its share of the annulus, 2πrΔr/n (Frontiere, Raskin & Owen (2017) §4.4.2).
fn ring_points<const D: usize>(c: &[f64], radius: f64, dr: f64) -> Vec<(Vector<D>, f64)> {
    let rings = (radius / dr).round().max(1.0) as usize;
    let mut out = Vec::new();
    for i in 0..rings {
        let r = (i as f64 + 0.5) * dr;
        let n = (2.0 * std::f64::consts::PI * r / dr).round().max(1.0) as usize;
        let vol = 2.0 * std::f64::consts::PI * r * dr / n as f64;
        let turn = if i % 2 == 1 { 0.5 } else { 0.0 };
        for j in 0..n {
            let phi = 2.0 * std::f64::consts::PI * (j as f64 + turn) / n as f64;
            let mut x = Vector::<D>::zeros();
            x[0] = c[0] + r * phi.cos();
            x[1] = c[1] + r * phi.sin();
            out.push((x, vol));
        }
    }
    out
}

/// Rosswog (2015) §7.7's equal-mass "quasi-close-packed" lattice in the box [lo, hi]:
/// hexagonal rows along x, n_j = round(L_x / 2r_s(y_j)) evenly spaced points in row j
/// (r_s = √(m/(2√3 ρ)), every other row shifted by half its spacing). The row pitch is
/// m/(ρ Δx_j) at the middle of the pitch, so each row's area per particle is m/ρ exactly (the
/// paper's √3 r_s, corrected for n_j being a whole number: within 1/(2n_j)). The rows are then
/// stretched in y so the stack closes the box (a periodic tiling; the stretch is the last
/// row's mismatch, below one pitch). Each point's volume is its row's share, Δx_j × pitch.
fn quasi_hexagonal_points<const D: usize>(
    lo: &[f64],
    hi: &[f64],
    m: f64,
    rho: &dyn Fn(f64) -> Result<f64, CaseError>,
) -> Result<Vec<(Vector<D>, f64)>, CaseError> {
    let lx = hi[0] - lo[0];
    let r_s = |y: f64| -> Result<f64, CaseError> { Ok((m / (2.0 * 3f64.sqrt() * rho(y)?)).sqrt()) };
    let row = |y: f64| -> Result<(usize, f64), CaseError> {
        let n = (lx / (2.0 * r_s(y)?)).round().max(1.0) as usize;
        Ok((n, lx / n as f64))
    };
    // the pitch above a row at y with spacing dx: m/(ρ dx) with ρ at its middle
    let pitch = |y: f64, dx: f64| -> Result<f64, CaseError> {
        let mut p = m / (rho(y)? * dx);
        for _ in 0..3 {
            p = m / (rho(y + 0.5 * p)? * dx);
        }
        Ok(p)
    };
    // (y, n, dx, pitch) of each row; the first half a pitch above lo, as a lattice's cells
    let (n0, dx0) = row(lo[1])?;
    let mut rows = vec![(lo[1] + 0.5 * pitch(lo[1], dx0)?, n0, dx0, 0.0)];
    loop {
        let (y, n, dx, _) = *rows.last().expect("one row");
        let p = pitch(y, dx)?;
        rows.last_mut().expect("one row").3 = p;
        // the next row, and the half pitch above it, must fit below hi (as a cell)
        let next = y + p;
        let (n1, dx1) = row(next)?;
        let p1 = pitch(next, dx1)?;
        if next + 0.5 * p1 > hi[1] + 0.25 * p1 {
            break;
        }
        let _ = n;
        rows.push((next, n1, dx1, p1));
        if rows.len() > 1 << 24 {
            return Err(CaseError("region: the quasi-hexagonal rows do not fit (density_profile too large for particle_mass)".into()));
        }
    }
    // stretch: the stack from lo to the last row's upper half pitch becomes [lo, hi]
    let (last, _, _, p_last) = *rows.last().expect("one row");
    let scale = (hi[1] - lo[1]) / (last + 0.5 * p_last - lo[1]);
    let mut out = Vec::new();
    for (j, &(y0, n, dx, p)) in rows.iter().enumerate() {
        let y = lo[1] + (y0 - lo[1]) * scale;
        let shift = if j % 2 == 1 { 0.5 } else { 0.0 };
        for i in 0..n {
            let mut x = Vector::<D>::zeros();
            x[0] = lo[0] + (i as f64 + 0.25 + shift) * dx;
            x[1] = y;
            out.push((x, dx * p * scale));
        }
    }
    Ok(out)
}

/// Points of a lattice filling the box [lo, hi], spacings adjusted so the box holds an
/// integer number of cells in each direction (periodic tiling stays exact).
/// Returns the points and the actual volume per particle.
fn lattice_points<const D: usize>(
    lattice: Lattice,
    lo: &[f64],
    hi: &[f64],
    a: f64,
) -> (Vec<Vector<D>>, f64) {
    let len = |k: usize| hi[k] - lo[k];
    let count = |l: f64, s: f64, even: bool| {
        let mut n = (l / s).round().max(1.0) as usize;
        if even && n % 2 == 1 {
            n += 1;
        }
        n
    };
    let mut pts = Vec::new();
    if lattice == Lattice::Cubic || D == 1 {
        let mut n = [1usize; D];
        let mut s = [0.0; D];
        for k in 0..D {
            n[k] = count(len(k), a, false);
            s[k] = len(k) / n[k] as f64;
        }
        let total: usize = n.iter().product();
        pts.reserve(total);
        for lin in 0..total {
            let mut r = lin;
            let mut x = Vector::<D>::zeros();
            for k in 0..D {
                let i = r % n[k];
                r /= n[k];
                x[k] = lo[k] + (i as f64 + 0.5) * s[k];
            }
            pts.push(x);
        }
        return (pts, s.iter().product());
    }
    // Hexagonal rows along x, spaced √3/2·a in y (even row count for periodic tiling);
    // in 3D hexagonal layers spaced a·√(2/3) in z, ABAB stacking (even layer count).
    let nx = count(len(0), a, false);
    let sx = len(0) / nx as f64;
    let ny = count(len(1), 0.5 * 3f64.sqrt() * a, true);
    let sy = len(1) / ny as f64;
    let (nz, sz) = if D == 3 {
        let nz = count(len(2), (2.0f64 / 3.0).sqrt() * a, true);
        (nz, len(2) / nz as f64)
    } else {
        (1, 1.0)
    };
    for kz in 0..nz {
        for jy in 0..ny {
            for ix in 0..nx {
                let mut x = Vector::<D>::zeros();
                let layer_shift_x = if kz % 2 == 1 { 0.5 * sx } else { 0.0 };
                let layer_shift_y = if kz % 2 == 1 { sy / 3.0 } else { 0.0 };
                let row_shift = if jy % 2 == 1 { 0.5 * sx } else { 0.0 };
                x[0] = lo[0] + (ix as f64 + 0.25) * sx + row_shift + layer_shift_x;
                x[0] = lo[0] + (x[0] - lo[0]).rem_euclid(len(0));
                x[1] = lo[1] + (jy as f64 + 0.5) * sy + layer_shift_y;
                x[1] = lo[1] + (x[1] - lo[1]).rem_euclid(len(1));
                if D == 3 {
                    x[2] = lo[2] + (kz as f64 + 0.5) * sz;
                }
                pts.push(x);
            }
        }
    }
    let vol = if D == 3 { sx * sy * sz } else { sx * sy };
    (pts, vol)
}

/// A 2D lattice of spacing `a` turned by `degrees` about the centre of [lo, hi]: laid over the
/// square that holds the box in every orientation, turned, and cut to the box.
fn turned_lattice_points<const D: usize>(
    lattice: Lattice,
    lo: &[f64],
    hi: &[f64],
    a: f64,
    degrees: f64,
) -> (Vec<Vector<D>>, f64) {
    let c = [0.5 * (lo[0] + hi[0]), 0.5 * (lo[1] + hi[1])];
    let half = 0.5 * (hi[0] - lo[0]).hypot(hi[1] - lo[1]) + a;
    let (big_lo, big_hi) = ([c[0] - half, c[1] - half], [c[0] + half, c[1] + half]);
    let (pts, vol) = lattice_points::<D>(lattice, &big_lo, &big_hi, a);
    let (sin, cos) = degrees.to_radians().sin_cos();
    let turned = pts
        .into_iter()
        .map(|p| {
            let (dx, dy) = (p[0] - c[0], p[1] - c[1]);
            let mut q = p;
            q[0] = c[0] + cos * dx - sin * dy;
            q[1] = c[1] + sin * dx + cos * dy;
            q
        })
        .filter(|q| (0..2).all(|k| q[k] >= lo[k] && q[k] < hi[k]))
        .collect();
    (turned, vol)
}

/// The kernel-sum density of an ideal lattice over the density its volume per particle V
/// implies, 1 + ε = V Σ_b W(r_ab, h), at the h where the summation density's h–ρ relation
/// settles: h = η (m/ρ)^{1/D} with ρ = m Σ_b W(r_ab, h).
///
/// A lattice's discrete sum is not exactly 1/V: measured ε = +0.18 % for the cubic spline
/// at η = 1.2 on a square lattice, so a region filled at m = ρV started 0.18 % dense, which
/// stalled the Sod convergence near L1(ρ) = 1.5e-3 and left the acoustic wave's raw error
/// at 1,760× its amplitude (issue 20). ε is scale-free (h ∝ spacing), so it is computed once
/// per lattice, kernel and η on a unit tile whose box is a whole number of lattice periods
/// (no stretch), around the point nearest its centre.
pub fn lattice_density_factor<const D: usize>(
    lattice: Lattice,
    kernel: &crate::kernel::DimKernel<D>,
    eta: f64,
) -> f64 {
    if matches!(lattice, Lattice::Rings | Lattice::QuasiHexagonal) {
        // no periodic tile: their sums are irregular (set P from the summed density, a
        // `[[field]] stage = "density"` entry, where it matters)
        return 1.0;
    }
    // lattice periods per axis for spacing 1 (hexagonal: rows and layers in pairs)
    let period: [f64; 3] = match (lattice, D) {
        (_, 1) | (Lattice::Cubic, _) => [1.0; 3],
        _ => [1.0, 3f64.sqrt(), 2.0 * (2.0f64 / 3.0).sqrt()],
    };
    let v = volume_per_particle(lattice, D, 1.0);
    let h0 = eta * v.powf(1.0 / D as f64);
    // room for the support at up to 1.5 h0 on every side of the centre point
    let half = kernel.radius(1.5 * h0) + 2.0;
    let mut hi = [0.0; D];
    for k in 0..D {
        hi[k] = (2.0 * half / period[k]).ceil() * period[k];
    }
    let (pts, vol) = lattice_points::<D>(lattice, &[0.0; D], &hi, 1.0);
    let mid = Vector::<D>::from_fn(|k, _| 0.5 * hi[k]);
    let centre = pts
        .iter()
        .min_by(|a, b| (*a - mid).norm().total_cmp(&(*b - mid).norm()))
        .copied()
        .unwrap_or(mid);
    let dist: Vec<f64> = pts.iter().map(|x| (x - centre).norm()).collect();
    let sum = |h: f64| dist.iter().map(|&r| kernel.w(r, h)).sum::<f64>();
    let mut h = h0;
    for _ in 0..200 {
        let next = eta * (1.0 / sum(h)).powf(1.0 / D as f64);
        let done = (next - h).abs() <= 1e-15 * h;
        h = next;
        if done {
            break;
        }
    }
    sum(h) * vol
}

fn inside<const D: usize>(case: &Case, r: &Region, x: &Vector<D>) -> bool {
    match r.shape {
        Shape::Box => {
            let (lo, hi) = case.region_box(r);
            (0..D).all(|k| x[k] >= lo[k] && x[k] < hi[k])
        }
        Shape::Sphere => {
            let c = r.center.as_ref().expect("validated");
            let rad = r.radius.expect("validated");
            (0..D).map(|k| (x[k] - c[k]).powi(2)).sum::<f64>() < rad * rad
        }
    }
}

/// Index of the last region containing x (later regions win).
fn region_at<const D: usize>(case: &Case, x: &Vector<D>) -> Option<usize> {
    (0..case.regions.len())
        .rev()
        .find(|&i| inside(case, &case.regions[i], x))
}

/// Primitive state (ρ, P or u, v) a region prescribes at x.
struct State<const D: usize> {
    rho: f64,
    u: f64,
    vel: Vector<D>,
}

fn state_of<const D: usize>(case: &Case, r: &Region, x: &Vector<D>, rho: f64) -> State<D> {
    let eos = case.eos_of(r.material);
    let u = match (r.pressure, r.internal_energy) {
        (Some(p), _) => eos.internal_energy(rho, p),
        (_, Some(u)) => u,
        _ => 0.0,
    };
    let mut vel = Vector::<D>::zeros();
    if let Some(v) = &r.velocity {
        for k in 0..D {
            vel[k] = v[k];
        }
    }
    if let Some(vr) = r.radial_velocity {
        let mut c = Vector::<D>::zeros();
        if let Some(cc) = &r.radial_center {
            for k in 0..D {
                c[k] = cc[k];
            }
        }
        let d = x - c;
        let n = d.norm();
        if n > 0.0 {
            vel += d * (vr / n);
        }
    }
    let mut u = u;
    let mut rho = rho;
    if r.hydrostatic {
        if let (Some(g), Some(p0)) = (&case.gravity, r.pressure) {
            let g = Vector::<D>::from_iterator(g.iter().cloned());
            let (lo, hi) = case.region_box(r);
            // depth below the highest point of the region's box, measured along g
            let top: f64 = (0..D).map(|k| (g[k] * lo[k]).min(g[k] * hi[k])).sum();
            let depth = (g.dot(x) - top) / g.norm().max(1e-300);
            let p = p0 + rho * g.norm() * depth.max(0.0);
            rho = eos.density_at(p, u).unwrap_or(rho);
            u = match eos {
                crate::eos::EosConfig::Tait { .. } | crate::eos::EosConfig::Isothermal { .. } => u,
                _ => eos.internal_energy(rho, p),
            };
        }
    }
    if let Some(g) = &r.gresho {
        let v = g.velocity(x[0], x[1]);
        vel[0] += v[0];
        vel[1] += v[1];
        let rr = (x[0] - g.center[0]).hypot(x[1] - g.center[1]);
        u = eos.internal_energy(rho, g.pressure(rr));
    }
    State { rho, u, vel }
}

/// Fill the regions with particles and set their state; see the case-file reference.
///
/// With `kernel` given (the scheme's, see `Case::corrects_lattice_density`) each lattice region's masses
/// are ρV/(1 + ε) (or, with `particle_mass`, its volume per particle m/(ρ(1 + ε))), so the
/// sum gives the region's density ([`lattice_density_factor`]); not after a glass
/// relaxation, whose sums are its own.
pub fn generate_particles<const D: usize>(
    case: &Case,
    domain: &Domain<D>,
    eta: f64,
    kernel: Option<&crate::kernel::DimKernel<D>>,
) -> Result<(Particles<D>, Vec<crate::boundary::bodies::Body<D>>), CaseError> {
    let mut p = Particles::<D>::default();
    let mut spacing_of = Vec::new();
    let mut region_of = Vec::new();
    let profiles = case
        .regions
        .iter()
        .enumerate()
        .map(|(i, r)| {
            r.density_profile
                .as_ref()
                .map(|f| f.compile(&format!("region[{i}].density_profile"), D))
                .transpose()
        })
        .collect::<Result<Vec<_>, CaseError>>()?;
    let density_at = |ri: usize, x: &Vector<D>| -> Result<f64, CaseError> {
        let r = &case.regions[ri];
        match (&profiles[ri], r.density) {
            (Some(f), _) => {
                let rho = f.at(x.as_slice())?;
                if rho.is_finite() && rho > 0.0 {
                    Ok(rho)
                } else {
                    Err(CaseError(format!(
                        "region[{ri}].density_profile: gives {rho} at x = {:?}; it must be finite and > 0",
                        x.as_slice()
                    )))
                }
            }
            (None, Some(rho)) => Ok(rho),
            (None, None) => unreachable!("validated: density or density_profile"),
        }
    };
    for (ri, r) in case.regions.iter().enumerate() {
        let (mut lo, mut hi) = case.region_box(r);
        // Clip to the domain on bounded axes.
        for k in 0..D {
            if domain.kind[k] != crate::domain::BoundaryKind::Open {
                lo[k] = lo[k].max(domain.lo[k]);
                hi[k] = hi[k].min(domain.hi[k]);
            }
        }
        let factor = match kernel {
            Some(k) if case.glass.is_none() => lattice_density_factor(r.lattice, k, eta),
            _ => 1.0,
        };
        // (point, its volume) and whether the masses are equal (else ρ × volume)
        let (pts, equal_mass): (Vec<(Vector<D>, f64)>, Option<f64>) = match r.lattice {
            Lattice::Rings => {
                let c = r.center.as_deref().expect("validated: rings need a sphere");
                let dr = r.spacing.expect("validated: rings need a spacing");
                (ring_points::<D>(c, r.radius.expect("validated"), dr), None)
            }
            Lattice::QuasiHexagonal => {
                let m = r
                    .particle_mass
                    .expect("validated: quasi-hexagonal needs particle_mass");
                let rho_y = |y: f64| {
                    let mut x = Vector::<D>::zeros();
                    x[0] = 0.5 * (lo[0] + hi[0]);
                    x[1] = y;
                    density_at(ri, &x)
                };
                (quasi_hexagonal_points::<D>(&lo, &hi, m, &rho_y)?, Some(m))
            }
            _ => {
                let reference = case.reference_density(r);
                let a = match (r.spacing, r.particle_mass) {
                    (Some(s), _) => s,
                    (_, Some(m)) => {
                        // spacing whose volume per particle holds mass m at density ρ (as summed)
                        let unit = volume_per_particle(r.lattice, D, 1.0);
                        (m / (reference * factor * unit)).powf(1.0 / D as f64)
                    }
                    _ => unreachable!("validated"),
                };
                let (pts, vol) = match r.lattice_rotation {
                    Some(deg) => turned_lattice_points::<D>(r.lattice, &lo, &hi, a, deg),
                    None => lattice_points::<D>(r.lattice, &lo, &hi, a),
                };
                (pts.into_iter().map(|x| (x, vol)).collect(), None)
            }
        };
        for (x, vol) in pts {
            if region_at(case, &x) != Some(ri) {
                continue;
            }
            let s = state_of(case, r, &x, density_at(ri, &x)?);
            // equal volumes (masses follow the density, as summed) unless the lattice holds
            // equal masses
            let m = equal_mass.unwrap_or(s.rho * vol / factor);
            let h = eta * vol.powf(1.0 / D as f64);
            p.push(m, x, s.vel, s.u, s.rho, h, r.material);
            let last = p.len() - 1;
            p.frozen[last] = r.frozen || r.drive.is_some();
            p.drive[last] = case.drive_tag(ri);
            spacing_of.push(vol.powf(1.0 / D as f64));
            region_of.push(ri);
        }
    }
    if p.is_empty() {
        return Err(CaseError(
            "region: the regions hold no particle inside the domain".into(),
        ));
    }
    if p.len() > crate::neighbours::MAX_PARTICLES {
        return Err(CaseError(format!(
            "region: {} particles exceed the limit of {}",
            p.len(),
            crate::neighbours::MAX_PARTICLES
        )));
    }
    // Smoothed interfaces: blend the states on either side (and with `stretch`, move the
    // particles) with a logistic profile.
    let state = |ri: usize, x: &Vector<D>| -> Result<super::interface::RegionState<D>, CaseError> {
        let s = state_of(case, &case.regions[ri], x, density_at(ri, x)?);
        Ok((s.rho, s.u, s.vel))
    };
    let region = |x: &Vector<D>| region_at(case, x);
    super::interface::apply(
        case,
        &mut p,
        domain,
        &super::interface::RegionLookup {
            region_at: &region,
            state: &state,
        },
    )?;
    let margin = case.domain.frozen_margin;
    if margin > 0.0 {
        for (x, f) in p.pos.iter().zip(p.frozen.iter_mut()) {
            *f |= (0..D).any(|k| {
                domain.kind[k] != crate::domain::BoundaryKind::Periodic
                    && (x[k] - domain.lo[k] < margin || domain.hi[k] - x[k] < margin)
            });
        }
    }
    if let Some(g) = &case.glass {
        super::glass::relax(&mut p, domain, g, &spacing_of);
    }
    if let Some(b) = &case.blast {
        // the particle nearest the centre (the first of equals) takes the whole energy
        let c = Vector::<D>::from_iterator(b.center.iter().cloned());
        let nearest = (0..p.len())
            .min_by(|&i, &j| {
                let (di, dj) = ((p.pos[i] - c).norm(), (p.pos[j] - c).norm());
                di.total_cmp(&dj)
            })
            .expect("particles exist");
        p.u[nearest] += b.energy / p.mass[nearest];
    }
    // bodies after every fluid-placement step (the perturbation moves fluid particles only)
    let bodies_later = !case.bodies.is_empty();
    if let Some(pert) = &case.perturbation {
        let mut rng = SplitMix64::new(pert.seed);
        for (x, &spacing) in p.pos.iter_mut().zip(&spacing_of) {
            let mut v = Vector::<D>::zeros();
            for k in 0..D {
                x[k] += pert.amplitude * spacing * (2.0 * rng.uniform() - 1.0);
            }
            domain.enforce(x, &mut v);
        }
    }
    super::fields::apply(
        &case.fields,
        super::fields::Stage::Initial,
        &mut p,
        &region_of,
        &|m| case.eos_of(m),
        domain,
    )?;
    let bodies = if bodies_later {
        // align the walls with the first region's lattice (cell centres from its lower corner)
        let lo0 = case.regions.first().map(|r| case.region_box(r).0);
        let origin = Vector::<D>::from_fn(|k, _| lo0.as_ref().map_or(domain.lo[k], |l| l[k]));
        // the walls are a cubic lattice at the body's spacing
        let factor = kernel.map_or(1.0, |k| lattice_density_factor(Lattice::Cubic, k, eta));
        super::bodies::add_bodies(case, &mut p, &spacing_of, eta, &origin, factor)?
    } else {
        Vec::new()
    };
    Ok((p, bodies))
}
