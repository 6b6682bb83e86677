//! The case file's tables besides `[scheme]`, `[eos]`, bodies, ports and probes: `[case]`,
//! `[domain]`, `[kernel]`, `[time]`, `[output]` and the particle regions. Plain serde types;
//! their range checks are in `validate.rs`.

use crate::domain::BoundaryKind;
use crate::integrate::IntegratorKind;
use crate::kernel::KernelName;
use crate::sim::StepControl;
use serde::{Deserialize, Serialize};

#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct CaseInfo {
    pub name: String,
    #[serde(default)]
    pub description: String,
    /// Who wrote the case: the packaged FMU's `author` (empty: "sphfmu").
    #[serde(default)]
    pub author: String,
    /// 1, 2 or 3.
    pub dimension: usize,
}

#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct DomainConfig {
    pub min: Vec<f64>,
    pub max: Vec<f64>,
    /// One per axis: "open", "periodic" or "reflect".
    pub boundary: Vec<BoundaryKind>,
    /// Particles within this distance of a non-periodic face are frozen: they keep their
    /// initial state and position and act as a boundary layer (Rosswog §8.3's noise box).
    #[serde(default)]
    pub frozen_margin: f64,
}

#[derive(Debug, Clone, PartialEq, Default, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct KernelConfig {
    /// Default: the scheme's kernel (cubic spline; Wendland C6 for Rosswog F1–F3).
    pub name: Option<KernelName>,
    /// h = η (m/ρ)^{1/D}; default: the kernel's recommended η.
    pub eta: Option<f64>,
    /// Exponent of the sinc family (3..9).
    pub sinc_n: Option<u32>,
    /// Cap on h; default: a quarter of the largest box side.
    pub h_max: Option<f64>,
}

#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct TimeConfig {
    pub t_end: f64,
    /// Default: the scheme's integrator (leapfrog; SSP-RK3 for Rosswog presets).
    pub integrator: Option<IntegratorKind>,
    /// Default: the scheme's Courant factor (0.3; 0.5 for Rosswog presets).
    pub cfl: Option<f64>,
    #[serde(default = "default_cfl_accel")]
    pub cfl_accel: f64,
    #[serde(default = "default_dt_min")]
    pub dt_min: f64,
    pub dt_max: Option<f64>,
    #[serde(default = "default_max_steps")]
    pub max_steps: u64,
}

fn default_cfl_accel() -> f64 {
    StepControl::default().cfl_accel
}
fn default_dt_min() -> f64 {
    1e-10
}
fn default_max_steps() -> u64 {
    10_000_000
}

/// Snapshot file formats.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "kebab-case")]
pub enum SnapshotFormat {
    Vtu,
    Csv,
}

#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct OutputConfig {
    /// Simulation-time interval between snapshots (0: initial and final only).
    #[serde(default)]
    pub snapshot_every: f64,
    #[serde(default = "default_formats")]
    pub formats: Vec<SnapshotFormat>,
    /// Write a diagnostics row every this many steps (≥ 1).
    #[serde(default = "default_diag_every")]
    pub diagnostics_every: u64,
}

fn default_formats() -> Vec<SnapshotFormat> {
    vec![SnapshotFormat::Vtu, SnapshotFormat::Csv]
}
fn default_diag_every() -> u64 {
    1
}

impl Default for OutputConfig {
    fn default() -> Self {
        Self {
            snapshot_every: 0.0,
            formats: default_formats(),
            diagnostics_every: 1,
        }
    }
}

/// Lattice of a region.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "kebab-case")]
pub enum Lattice {
    /// Simple cubic (square in 2D).
    Cubic,
    /// Hexagonal close packing in 2D; HCP (ABAB stacking of hexagonal layers) in 3D.
    Hexagonal,
    /// 2D, `shape = "sphere"`: concentric rings Δr = `spacing` apart about `center`, ring i at
    /// (i + ½)Δr with round(2πr/Δr) points, masses ρ × the annulus area shared equally (the
    /// Yee vortex's set-up, Frontiere, Raskin & Owen (2017) §4.4.2).
    Rings,
    /// 2D, equal masses (`particle_mass`) in hexagonal rows along x whose spacing follows
    /// `density_profile` (a function of y): row j + 1 sits √3 r_s(y_j) above row j with
    /// round(L_x / 2r_s(y_j)) particles, r_s = √(m / (2√3 ρ)) (Rosswog (2015) §7.7's
    /// "quasi-close-packed" lattice; the rows are stretched to close the box).
    QuasiHexagonal,
}

#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "kebab-case")]
pub enum Shape {
    Box,
    Sphere,
}

/// A uniform region of fluid filled with a lattice. Later regions replace earlier ones where
/// they overlap.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct Region {
    #[serde(default = "default_shape")]
    pub shape: Shape,
    /// Box corners (shape = "box"); default: the whole domain.
    pub min: Option<Vec<f64>>,
    pub max: Option<Vec<f64>>,
    /// Sphere (disk in 2D) centre and radius (shape = "sphere").
    pub center: Option<Vec<f64>>,
    pub radius: Option<f64>,
    #[serde(default = "default_lattice")]
    pub lattice: Lattice,
    /// 2D: the lattice turned by this many degrees about the region's box centre (cubic and
    /// hexagonal lattices), so that no lattice row lies along the flow (Rosswog (2015) §7.6.1
    /// turns the low-density side of its shock tube by 30°). The turned lattice does not tile
    /// a periodic axis exactly.
    #[serde(default)]
    pub lattice_rotation: Option<f64>,
    /// Nearest-neighbour spacing; exactly one of `spacing` and `particle_mass`.
    pub spacing: Option<f64>,
    pub particle_mass: Option<f64>,
    /// ρ (exactly one of `density` and `density_profile`).
    pub density: Option<f64>,
    /// ρ as an expression of position (`x`, `y`, `z`, `r` and its `parameters`). With
    /// `lattice = "quasi-hexagonal"` it places the rows (equal masses); with the other lattices
    /// the masses follow it (equal volumes).
    pub density_profile: Option<super::fields::Formula>,
    /// The region's particles never move: they keep their initial state and take part in
    /// every sum (ghost layers held at the initial state, e.g. the Yee vortex's outer rings).
    #[serde(default)]
    pub frozen: bool,
    /// The region's state is imposed at every stage from expressions of rest position and
    /// time (`boundary::drive`): an analytic boundary such as the Kidder implosion's rind.
    #[serde(default)]
    pub drive: Option<crate::boundary::drive::DriveConfig>,
    /// Exactly one of `pressure` and `internal_energy`.
    pub pressure: Option<f64>,
    pub internal_energy: Option<f64>,
    pub velocity: Option<Vec<f64>>,
    /// Extra radial velocity v_r·(x − radial_center)/|x − radial_center| (e.g. Noh: −1).
    pub radial_velocity: Option<f64>,
    pub radial_center: Option<Vec<f64>>,
    /// Gresho–Chan vortex (2D): adds its velocity and its pressure profile (replacing
    /// `pressure`; ρ stays `density`).
    pub gresho: Option<crate::verify::vortex::Gresho>,
    #[serde(default)]
    pub material: u16,
    /// Add the hydrostatic pressure ρ|g|·depth below the region's top (against `gravity`) to
    /// `pressure`, with the density from the EOS at that pressure (particle masses follow).
    #[serde(default)]
    pub hydrostatic: bool,
}

fn default_shape() -> Shape {
    Shape::Box
}
fn default_lattice() -> Lattice {
    Lattice::Cubic
}

/// A planar interface between regions, smoothed over `width` with a logistic profile
/// f = f_lo + (f_hi − f_lo)/(1 + exp(−(x − position)/width)) (Frontiere, Raskin & Owen (2017) §4.3.1, sign fixed).
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct Interface {
    pub axis: usize,
    pub position: f64,
    pub width: f64,
    /// Also move the particles along `axis` so their masses reproduce the smoothed density
    /// (`interface.rs`); both sides need a uniform `density`.
    #[serde(default)]
    pub stretch: bool,
}

/// Random displacement of every particle by up to `amplitude` × its lattice spacing.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct Perturbation {
    pub amplitude: f64,
    #[serde(default)]
    pub seed: u64,
}
