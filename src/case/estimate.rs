//! What a case will cost before anything is allocated: the particle count of its regions,
//! bodies and ports, the memory the solver will hold for them, and the refusal of a case that
//! overflows a count, exceeds the machine's available memory, or exceeds a limit the user set
//! (`[limits]` in the case, `limits.*` parameters in the FMU). `sphfmu check`, `Case::build`,
//! the FMU's exitInitializationMode and the zenoh node all run it, so a case that asks for
//! 1e8 particles is refused in milliseconds with the estimate in the message instead of
//! growing the process until the operating system kills it.

use super::{Case, CaseError, Lattice, Region, Shape};
use crate::boundary::geometry::Shape as BodyShape;
use crate::domain::BoundaryKind;
use serde::{Deserialize, Serialize};

/// `[limits]`: optional caps on a run's size (the FMU's `limits.max_particles` and
/// `limits.max_memory` parameters override them).
#[derive(Debug, Clone, Copy, PartialEq, Default, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct Limits {
    /// Most particles (fluid, walls and port buffers) the run may have.
    pub max_particles: Option<u64>,
    /// Most memory the solver may hold, in bytes (2e9 = 2 GB).
    pub max_memory: Option<f64>,
}

impl Limits {
    pub fn validate(&self) -> Result<(), CaseError> {
        if self.max_particles == Some(0) {
            return Err(CaseError("limits.max_particles: must be ≥ 1".into()));
        }
        if let Some(m) = self.max_memory {
            if !(m.is_finite() && m > 0.0) {
                return Err(CaseError(format!(
                    "limits.max_memory: must be a finite number of bytes > 0, got {m}"
                )));
            }
        }
        Ok(())
    }
}

/// The size of a case, estimated without allocating.
#[derive(Debug, Clone, Copy, PartialEq, Serialize)]
pub struct SizeEstimate {
    pub fluid: f64,
    pub walls: f64,
    /// Lattice points visited to place the walls (their bounding boxes): the set-up's time.
    pub wall_candidates: f64,
    pub particles: f64,
    /// Neighbours per particle of the kernel at its η (4πη² in 2D).
    pub neighbours: f64,
    /// Bytes the solver holds: particles, neighbour lists, cell grid, integrator stages.
    pub bytes: f64,
}

/// Bytes per particle besides its neighbour lists, by dimension (particle arrays, integrator
/// stage, scheme buffers, cell grid), and bytes per neighbour of each particle (the master list
/// with its skin, the working list, per-pair buffers). Fitted to the growth of the peak
/// resident memory (`/usr/bin/time -f %M sphfmu bench --steps 2`) from 1e5 to 4e5 particles,
/// standard SPH: 2D M4 (20 neighbours) 713 B per particle, 2D Wendland C4 (44) 1155 B, 3D M4
/// (62.8) 1544 B: 18.4 B per neighbour, 345 B (2D) and 389 B (3D) besides. The constants
/// round both up by 15–20 % for the schemes that keep more per particle (CRKSPH's moments).
const BYTES_PER_PARTICLE: [f64; 3] = [400.0, 450.0, 500.0];
const BYTES_PER_PAIR: f64 = 20.0;
/// Wall-placement lattice points beyond which the set-up alone would take minutes.
const MAX_WALL_CANDIDATES: f64 = 1e10;

/// Lattice points a region's box holds at spacing `a` (as `ics::lattice_points` places them).
fn lattice_count(lattice: Lattice, d: usize, lo: &[f64], hi: &[f64], a: f64) -> f64 {
    let n = |l: f64, s: f64| (l / s).round().max(1.0);
    let len = |k: usize| (hi[k] - lo[k]).max(0.0);
    if lattice == Lattice::Cubic || d == 1 {
        return (0..d).map(|k| n(len(k), a)).product();
    }
    let ny = n(len(1), 0.5 * 3f64.sqrt() * a);
    // even row and layer counts (periodic tiling), as ics::lattice_points
    let nz = if d == 3 {
        let nz = n(len(2), (2.0f64 / 3.0).sqrt() * a);
        nz + nz % 2.0
    } else {
        1.0
    };
    n(len(0), a) * (ny + ny % 2.0) * nz
}

impl Case {
    fn region_spacing(&self, r: &Region) -> f64 {
        let d = self.case.dimension;
        match (r.spacing, r.particle_mass) {
            (Some(s), _) => s,
            (_, Some(m)) => {
                // as ics::generate_particles: the volume holding m at the summed density
                let unit = super::ics::volume_per_particle(r.lattice, d, 1.0);
                (m / (self.reference_density(r) * self.density_factor(r.lattice) * unit))
                    .powf(1.0 / d as f64)
            }
            _ => f64::NAN,
        }
    }

    /// The lattice's kernel-sum factor 1 + ε that `ics::generate_particles` applies (1 when
    /// it applies none, or when the kernel or η is invalid: validation reports those).
    fn density_factor(&self, lattice: Lattice) -> f64 {
        use super::ics::lattice_density_factor;
        use crate::kernel::DimKernel;
        if !self.corrects_lattice_density() || self.glass.is_some() {
            return 1.0;
        }
        let (Ok(kernel), Ok(eta)) = (self.kernel(), self.eta()) else {
            return 1.0;
        };
        match self.case.dimension {
            1 => lattice_density_factor::<1>(lattice, &DimKernel::new(kernel), eta),
            2 => lattice_density_factor::<2>(lattice, &DimKernel::new(kernel), eta),
            _ => lattice_density_factor::<3>(lattice, &DimKernel::new(kernel), eta),
        }
    }

    /// The particle count and memory of this case, without allocating. Regions overlap only
    /// where a later one replaces an earlier one, so their sum bounds the fluid from above.
    pub fn estimate(&self) -> SizeEstimate {
        let d = self.case.dimension;
        let mut fluid = 0.0;
        let mut finest = f64::INFINITY;
        let clipped = |r: &Region| {
            let (mut lo, mut hi) = self.region_box(r);
            for k in 0..d.min(lo.len()).min(hi.len()) {
                if self.domain.boundary.get(k) != Some(&BoundaryKind::Open) {
                    lo[k] = lo[k].max(self.domain.min[k]);
                    hi[k] = hi[k].min(self.domain.max[k]);
                }
            }
            (lo, hi)
        };
        let volume =
            |lo: &[f64], hi: &[f64]| -> f64 { (0..d).map(|k| (hi[k] - lo[k]).max(0.0)).product() };
        for (i, r) in self.regions.iter().enumerate() {
            let (lo, hi) = clipped(r);
            let a = self.region_spacing(r);
            finest = finest.min(a);
            let mut share = match r.shape {
                Shape::Box => 1.0,
                // a ball's share of its bounding box
                Shape::Sphere => [1.0, std::f64::consts::FRAC_PI_4, std::f64::consts::PI / 6.0]
                    [d.clamp(1, 3) - 1],
            };
            // later box regions replace this one where they overlap (spheres are left out, so
            // the sum stays an upper bound)
            let own = volume(&lo, &hi).max(1e-300);
            for later in self.regions[i + 1..]
                .iter()
                .filter(|r| r.shape == Shape::Box)
            {
                let (l2, h2) = clipped(later);
                let lo_x: Vec<f64> = (0..d).map(|k| lo[k].max(l2[k])).collect();
                let hi_x: Vec<f64> = (0..d).map(|k| hi[k].min(h2[k])).collect();
                share -= volume(&lo_x, &hi_x) / own;
            }
            fluid += lattice_count(r.lattice, d, &lo, &hi, a) * share.max(0.0);
        }
        let eta = self.eta().unwrap_or(1.2);
        let (mut walls, mut candidates) = (0.0, 0.0);
        for b in &self.bodies {
            let dx = b.spacing.unwrap_or(finest);
            let t = crate::kernel::SUPPORT * eta * dx;
            let (surface, bbox) = body_measures(&b.shape, d, t);
            walls += surface * t / dx.powi(d as i32);
            candidates += bbox / dx.powi(d as i32);
        }
        // port buffers: one layer deeper than the wall behind each opening, bounded by the walls
        let particles = fluid + walls * if self.ports.is_empty() { 1.0 } else { 1.1 };
        let neighbours = crate::kernel::neighbours_for_eta(eta, d);
        let per = BYTES_PER_PARTICLE[d.clamp(1, 3) - 1] + BYTES_PER_PAIR * neighbours;
        SizeEstimate {
            fluid,
            walls,
            wall_candidates: candidates,
            particles,
            neighbours,
            bytes: particles * per,
        }
    }

    /// Refuse a case whose estimate overflows a count, exceeds the memory the machine has
    /// available, or exceeds `limits` (the case's `[limits]` unless the caller overrides it).
    pub fn check_resources(&self, limits: &Limits) -> Result<SizeEstimate, CaseError> {
        let e = self.estimate();
        let gb = |b: f64| b / 1e9;
        if !e.particles.is_finite() || e.particles > crate::neighbours::MAX_PARTICLES as f64 {
            return Err(CaseError(format!(
                "region/body: the case asks for about {:.3e} particles ({:.3e} fluid, {:.3e} wall), beyond the solver's limit of {} (neighbour indices are 27-bit); coarsen the spacing or shrink the regions",
                e.particles, e.fluid, e.walls, crate::neighbours::MAX_PARTICLES
            )));
        }
        if e.wall_candidates.is_nan() || e.wall_candidates > MAX_WALL_CANDIDATES {
            return Err(CaseError(format!(
                "body: placing the wall particles would visit about {:.3e} lattice points (limit {MAX_WALL_CANDIDATES:.0e}); a body's extent is too large for its spacing",
                e.wall_candidates
            )));
        }
        if let Some(max) = limits.max_particles {
            if e.particles > max as f64 {
                return Err(CaseError(format!(
                    "limits.max_particles: the case needs about {:.0} particles, more than the limit of {max}",
                    e.particles
                )));
            }
        }
        if let Some(max) = limits.max_memory {
            if e.bytes > max {
                return Err(CaseError(format!(
                    "limits.max_memory: the case needs about {:.2} GB for {:.3e} particles, more than the limit of {:.2} GB",
                    gb(e.bytes), e.particles, gb(max)
                )));
            }
        }
        if let Some(avail) = available_memory() {
            if e.bytes > avail {
                return Err(CaseError(format!(
                    "region/body: the case needs about {:.2} GB for {:.3e} particles, more than the {:.2} GB this machine has available; coarsen the spacing or shrink the regions",
                    gb(e.bytes), e.particles, gb(avail)
                )));
            }
        }
        Ok(e)
    }
}

/// A body's wall surface (length in 2D, area in 3D) and the volume of the bounding box its
/// walls are placed from (grown by the wall thickness `t`).
fn body_measures(shape: &BodyShape, d: usize, t: f64) -> (f64, f64) {
    let grown = |lo: &[f64], hi: &[f64]| -> f64 {
        (0..d).map(|k| (hi[k] - lo[k]).abs() + 2.0 * t).product()
    };
    // surface of a box with sides s (every face, or all but the top for a tank)
    let box_surface = |lo: &[f64], hi: &[f64], top: bool| -> f64 {
        let s: Vec<f64> = (0..d).map(|k| (hi[k] - lo[k]).abs() + 2.0 * t).collect();
        let faces: f64 = (0..d)
            .map(|k| {
                2.0 * s
                    .iter()
                    .enumerate()
                    .filter(|(j, _)| *j != k)
                    .map(|(_, x)| x)
                    .product::<f64>()
            })
            .sum();
        let top_face: f64 = s[..d - 1].iter().product();
        if top {
            faces
        } else {
            faces - top_face
        }
    };
    match shape {
        BodyShape::Tank { min, max } => (box_surface(min, max, false), grown(min, max)),
        BodyShape::ClosedBox { min, max } | BodyShape::Block { min, max } => {
            (box_surface(min, max, true), grown(min, max))
        }
        BodyShape::Plane { half_width, .. } => {
            let w = 2.0 * (half_width + t);
            (w.powi(d as i32 - 1), (w).powi(d as i32))
        }
        BodyShape::Disk { radius, .. } => {
            let r = radius + t;
            let surface = match d {
                2 => 2.0 * std::f64::consts::PI * r,
                3 => 4.0 * std::f64::consts::PI * r * r,
                _ => 2.0,
            };
            (surface, (2.0 * r).powi(d as i32))
        }
        BodyShape::Polygon { vertices } => {
            let n = vertices.len();
            let perimeter: f64 = (0..n)
                .map(|i| {
                    let (a, b) = (vertices[i], vertices[(i + 1) % n]);
                    (b[0] - a[0]).hypot(b[1] - a[1])
                })
                .sum();
            let (mut lo, mut hi) = ([f64::INFINITY; 2], [f64::NEG_INFINITY; 2]);
            for p in vertices {
                for k in 0..2 {
                    lo[k] = lo[k].min(p[k]);
                    hi[k] = hi[k].max(p[k]);
                }
            }
            (perimeter, grown(&lo, &hi))
        }
    }
}

/// `MemAvailable` of /proc/meminfo in bytes (Linux), None where it cannot be read.
pub fn available_memory() -> Option<f64> {
    let text = std::fs::read_to_string("/proc/meminfo").ok()?;
    let line = text.lines().find(|l| l.starts_with("MemAvailable:"))?;
    let kb: f64 = line.split_whitespace().nth(1)?.parse().ok()?;
    Some(kb * 1024.0)
}
