//! Case files (`models/*.toml`): a scenario as data. Parsed with serde (unknown keys are
//! errors), then validated range by range; every error names the key and the allowed range.

mod bodies;
mod checks;
mod glass;
mod ics;
mod ports;
mod probes;

pub use probes::{MarkerConfig, PatchConfig, ProbeConfig};

pub use bodies::BodyConfig;
pub use checks::{Blast, Verify};
pub use glass::GlassConfig;
pub use ics::generate_particles;
pub use ports::{OpeningConfig, PortConfig};

use crate::domain::{BoundaryKind, Domain};
use crate::eos::EosConfig;
use crate::integrate::IntegratorKind;
use crate::kernel::{AnyKernel, DimKernel, Kernel, KernelName};
use crate::scheme::SchemeConfig;
use crate::sim::{Simulation, SolverError, StepControl};
use crate::system::System;
use serde::{Deserialize, Serialize};
use std::fmt;
use std::path::Path;

/// A case that failed to load or validate: one line naming the key and the allowed range.
#[derive(Debug, Clone, PartialEq)]
pub struct CaseError(pub String);

impl fmt::Display for CaseError {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.write_str(&self.0)
    }
}
impl std::error::Error for CaseError {}

impl From<String> for CaseError {
    fn from(s: String) -> Self {
        CaseError(s)
    }
}

#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct Case {
    pub case: CaseInfo,
    pub domain: DomainConfig,
    pub eos: EosConfig,
    #[serde(default)]
    pub kernel: KernelConfig,
    #[serde(default)]
    pub scheme: SchemeConfig,
    pub time: TimeConfig,
    #[serde(default)]
    pub output: OutputConfig,
    #[serde(default, rename = "region")]
    pub regions: Vec<Region>,
    #[serde(default, rename = "interface")]
    pub interfaces: Vec<Interface>,
    #[serde(default)]
    pub perturbation: Option<Perturbation>,
    /// Relax the initial lattice into a glass (Rosswog spec §8.1).
    #[serde(default)]
    pub glass: Option<GlassConfig>,
    /// Uniform body force per unit mass (length = dimension).
    #[serde(default)]
    pub gravity: Option<Vec<f64>>,
    /// Exact solution to compare with after the run.
    #[serde(default)]
    pub verify: Option<Verify>,
    /// Point energy deposit (Sedov–Taylor blast).
    #[serde(default)]
    pub blast: Option<Blast>,
    /// Rigid boundary bodies made of wall particles.
    #[serde(default, rename = "body")]
    pub bodies: Vec<BodyConfig>,
    /// Points in the fluid where ρ, P and v are reported (Coupling API, FMU outputs).
    #[serde(default, rename = "probe")]
    pub probes: Vec<ProbeConfig>,
    /// Points on body surfaces where the wall pressure is reported.
    #[serde(default, rename = "marker")]
    pub markers: Vec<MarkerConfig>,
    /// Named parts of body surfaces: mean and peak pressure, area, force.
    #[serde(default, rename = "patch")]
    pub patches: Vec<PatchConfig>,
    /// Run in a moving (non-inertial) frame, e.g. a tank's: see `boundary::frame`.
    #[serde(default)]
    pub frame: Option<crate::boundary::frame::FrameConfig>,
    /// Openings in bodies where an outside model sets the pressure (`boundary::ports`).
    #[serde(default, rename = "port")]
    pub ports: Vec<PortConfig>,
}

#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct CaseInfo {
    pub name: String,
    #[serde(default)]
    pub description: String,
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
    /// Nearest-neighbour spacing; exactly one of `spacing` and `particle_mass`.
    pub spacing: Option<f64>,
    pub particle_mass: Option<f64>,
    pub density: f64,
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
/// f = f_lo + (f_hi − f_lo)/(1 + exp(−(x − position)/width)) (CRKSPH spec §9.4, sign fixed).
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct Interface {
    pub axis: usize,
    pub position: f64,
    pub width: f64,
}

/// Random displacement of every particle by up to `amplitude` × its lattice spacing.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct Perturbation {
    pub amplitude: f64,
    #[serde(default)]
    pub seed: u64,
}

fn one_line(s: &str) -> String {
    s.split_whitespace().collect::<Vec<_>>().join(" ")
}

impl Case {
    /// Read and validate a case file.
    pub fn load(path: &Path) -> Result<Case, CaseError> {
        let text = std::fs::read_to_string(path)
            .map_err(|e| CaseError(format!("{}: cannot read: {e}", path.display())))?;
        Self::parse(&text).map_err(|e| CaseError(format!("{}: {}", path.display(), e.0)))
    }

    /// Parse and validate TOML text.
    pub fn parse(text: &str) -> Result<Case, CaseError> {
        let case: Case = toml::from_str(text).map_err(|e| {
            let span = e.span().map(|s| {
                let line = text[..s.start.min(text.len())].matches('\n').count() + 1;
                format!("line {line}: ")
            });
            CaseError(format!(
                "{}{}",
                span.unwrap_or_default(),
                one_line(e.message())
            ))
        })?;
        case.validate()?;
        Ok(case)
    }

    pub fn dimension(&self) -> usize {
        self.case.dimension
    }

    pub(crate) fn vec_len(&self, key: &str, v: &[f64]) -> Result<(), CaseError> {
        let d = self.case.dimension;
        if v.len() != d {
            return Err(CaseError(format!(
                "{key}: must have {d} entries (case.dimension = {d}), got {}",
                v.len()
            )));
        }
        if let Some(x) = v.iter().find(|x| !x.is_finite()) {
            return Err(CaseError(format!("{key}: entries must be finite, got {x}")));
        }
        Ok(())
    }

    fn kernel_name(&self) -> KernelName {
        self.kernel.name.unwrap_or(self.scheme.preferred_kernel().0)
    }

    fn kernel(&self) -> Result<AnyKernel, CaseError> {
        let n = self.kernel.sinc_n.unwrap_or(5);
        if self.kernel.sinc_n.is_some() && self.kernel_name() != KernelName::Sinc {
            return Err(CaseError(
                "kernel.sinc_n: only allowed with kernel.name = \"sinc\"".into(),
            ));
        }
        Ok(AnyKernel::from_name(self.kernel_name(), n)?)
    }

    /// η: as given, else the scheme's (when the scheme also chose the kernel), else the kernel's.
    pub fn eta(&self) -> Result<f64, CaseError> {
        if let Some(e) = self.kernel.eta {
            return Ok(e);
        }
        match (self.kernel.name, self.scheme.preferred_kernel().1) {
            (None, Some(e)) => Ok(e),
            _ => Ok(self.kernel()?.default_eta()),
        }
    }

    pub fn integrator(&self) -> IntegratorKind {
        self.time
            .integrator
            .unwrap_or(self.scheme.preferred_integrator().0)
    }

    pub fn cfl(&self) -> f64 {
        self.time
            .cfl
            .unwrap_or(self.scheme.preferred_integrator().1)
    }

    /// Range checks of every field.
    pub fn validate(&self) -> Result<(), CaseError> {
        let d = self.case.dimension;
        if !(1..=3).contains(&d) {
            return Err(CaseError(format!(
                "case.dimension: must be 1, 2 or 3, got {d}"
            )));
        }
        self.vec_len("domain.min", &self.domain.min)?;
        self.vec_len("domain.max", &self.domain.max)?;
        if self.domain.boundary.len() != d {
            return Err(CaseError(format!(
                "domain.boundary: must have {d} entries (one per axis: open, periodic, reflect), got {}",
                self.domain.boundary.len()
            )));
        }
        for k in 0..d {
            if self.domain.max[k] <= self.domain.min[k] {
                return Err(CaseError(format!(
                    "domain.max[{k}]: must be greater than domain.min[{k}] = {}, got {}",
                    self.domain.min[k], self.domain.max[k]
                )));
            }
        }
        let fm = self.domain.frozen_margin;
        if !(fm.is_finite() && fm >= 0.0) {
            return Err(CaseError(format!(
                "domain.frozen_margin: must be a finite number ≥ 0, got {fm}"
            )));
        }
        self.eos.validate()?;
        let eta = self.eta()?;
        if !(eta.is_finite() && (0.5..=5.0).contains(&eta)) {
            return Err(CaseError(format!(
                "kernel.eta: must be in [0.5, 5], got {eta}"
            )));
        }
        if let Some(h) = self.kernel.h_max {
            if !(h.is_finite() && h > 0.0) {
                return Err(CaseError(format!(
                    "kernel.h_max: must be a finite number > 0, got {h}"
                )));
            }
        }
        self.scheme.validate()?;
        if matches!(self.scheme, SchemeConfig::Psph(_))
            && !matches!(self.eos, EosConfig::IdealGas { .. })
        {
            return Err(CaseError(
                "scheme.name: \"psph\" sums the pressure from u and needs eos.type = \"ideal-gas\""
                    .into(),
            ));
        }
        // rpSPH's force sees pressure differences only (Abel 2011 eq. 4) and is not
        // antisymmetric: the load on a body would miss the ambient pressure and not be the
        // reaction of what the fluid receives (measured: a closed tank read −0.05 of its weight)
        if matches!(self.scheme, SchemeConfig::Rpsph(_)) && !self.bodies.is_empty() {
            return Err(CaseError(
                "scheme.name: \"rpsph\" feels pressure differences only, so it gives no load on a [[body]]; use standard, rosswog-f1…f4, crksph, compsph, compsph-cullen or psph with bodies".into(),
            ));
        }
        let t = &self.time;
        let pos = |key: &str, v: f64| -> Result<(), CaseError> {
            if v.is_finite() && v > 0.0 {
                Ok(())
            } else {
                Err(CaseError(format!(
                    "{key}: must be a finite number > 0, got {v}"
                )))
            }
        };
        pos("time.t_end", t.t_end)?;
        let cfl = self.cfl();
        if !(cfl > 0.0 && cfl <= 1.0) {
            return Err(CaseError(format!(
                "time.cfl: must be in (0, 1], got {}",
                cfl
            )));
        }
        if !(t.cfl_accel > 0.0 && t.cfl_accel <= 1.0) {
            return Err(CaseError(format!(
                "time.cfl_accel: must be in (0, 1], got {}",
                t.cfl_accel
            )));
        }
        pos("time.dt_min", t.dt_min)?;
        if let Some(m) = t.dt_max {
            pos("time.dt_max", m)?;
        }
        if t.max_steps == 0 {
            return Err(CaseError("time.max_steps: must be ≥ 1, got 0".into()));
        }
        let o = &self.output;
        if !(o.snapshot_every.is_finite() && o.snapshot_every >= 0.0) {
            return Err(CaseError(format!(
                "output.snapshot_every: must be ≥ 0 (0 = initial and final only), got {}",
                o.snapshot_every
            )));
        }
        if o.diagnostics_every == 0 {
            return Err(CaseError(
                "output.diagnostics_every: must be ≥ 1, got 0".into(),
            ));
        }
        if self.regions.is_empty() {
            return Err(CaseError(
                "region: at least one [[region]] is required".into(),
            ));
        }
        for (i, r) in self.regions.iter().enumerate() {
            self.validate_region(i, r)?;
        }
        for (i, f) in self.interfaces.iter().enumerate() {
            if f.axis >= d {
                return Err(CaseError(format!(
                    "interface[{i}].axis: must be in [0, {}], got {}",
                    d - 1,
                    f.axis
                )));
            }
            if !f.position.is_finite() {
                return Err(CaseError(format!(
                    "interface[{i}].position: must be finite"
                )));
            }
            pos(&format!("interface[{i}].width"), f.width)?;
        }
        if let Some(p) = &self.perturbation {
            if !(p.amplitude.is_finite() && (0.0..=0.5).contains(&p.amplitude)) {
                return Err(CaseError(format!(
                    "perturbation.amplitude: must be in [0, 0.5] (fraction of the lattice spacing), got {}",
                    p.amplitude
                )));
            }
        }
        if let Some(g) = &self.gravity {
            self.vec_len("gravity", g)?;
        }
        if let Some(g) = &self.glass {
            g.validate()?;
        }
        if let Some(v) = &self.verify {
            v.validate(self)?;
        }
        if let Some(b) = &self.blast {
            b.validate(self)?;
        }
        for (i, b) in self.bodies.iter().enumerate() {
            b.validate(i, self)?;
        }
        for (i, p) in self.ports.iter().enumerate() {
            p.validate(i, self)?;
        }
        if let Some(f) = &self.frame {
            f.validate(self.dimension()).map_err(CaseError)?;
        }
        self.validate_probes()?;
        Ok(())
    }

    fn validate_region(&self, i: usize, r: &Region) -> Result<(), CaseError> {
        let key = |s: &str| format!("region[{i}].{s}");
        if r.hydrostatic && (self.gravity.is_none() || r.pressure.is_none()) {
            return Err(CaseError(format!(
                "{}: needs `gravity` and {} (the pressure at the region's top)",
                key("hydrostatic"),
                key("pressure")
            )));
        }
        let pos = |k: &str, v: f64| -> Result<(), CaseError> {
            if v.is_finite() && v > 0.0 {
                Ok(())
            } else {
                Err(CaseError(format!(
                    "{}: must be a finite number > 0, got {v}",
                    key(k)
                )))
            }
        };
        match r.shape {
            Shape::Box => {
                if r.center.is_some() || r.radius.is_some() {
                    return Err(CaseError(format!(
                        "{}: only for shape = \"sphere\"",
                        key("center/radius")
                    )));
                }
                if let Some(m) = &r.min {
                    self.vec_len(&key("min"), m)?;
                }
                if let Some(m) = &r.max {
                    self.vec_len(&key("max"), m)?;
                }
                let (lo, hi) = self.region_box(r);
                for k in 0..self.case.dimension {
                    if hi[k] <= lo[k] {
                        return Err(CaseError(format!(
                            "{}: must exceed min[{k}] = {}, got {}",
                            key(&format!("max[{k}]")),
                            lo[k],
                            hi[k]
                        )));
                    }
                }
            }
            Shape::Sphere => {
                let c = r.center.as_ref().ok_or_else(|| {
                    CaseError(format!(
                        "{}: required for shape = \"sphere\"",
                        key("center")
                    ))
                })?;
                self.vec_len(&key("center"), c)?;
                pos(
                    "radius",
                    r.radius.ok_or_else(|| {
                        CaseError(format!(
                            "{}: required for shape = \"sphere\"",
                            key("radius")
                        ))
                    })?,
                )?;
            }
        }
        match (r.spacing, r.particle_mass) {
            (Some(s), None) => pos("spacing", s)?,
            (None, Some(m)) => pos("particle_mass", m)?,
            _ => {
                return Err(CaseError(format!(
                    "{}: give exactly one of spacing and particle_mass",
                    key("spacing")
                )))
            }
        }
        pos("density", r.density)?;
        match (r.pressure, r.internal_energy) {
            (Some(p), None) => {
                if !(p.is_finite() && p >= 0.0) {
                    return Err(CaseError(format!(
                        "{}: must be a finite number ≥ 0, got {p}",
                        key("pressure")
                    )));
                }
            }
            (None, Some(u)) => {
                if !(u.is_finite() && u >= 0.0) {
                    return Err(CaseError(format!(
                        "{}: must be a finite number ≥ 0, got {u}",
                        key("internal_energy")
                    )));
                }
            }
            _ => {
                return Err(CaseError(format!(
                    "{}: give exactly one of pressure and internal_energy",
                    key("pressure")
                )))
            }
        }
        if let Some(v) = &r.velocity {
            self.vec_len(&key("velocity"), v)?;
        }
        if let Some(v) = r.radial_velocity {
            if !v.is_finite() {
                return Err(CaseError(format!(
                    "{}: must be finite",
                    key("radial_velocity")
                )));
            }
        }
        if let Some(c) = &r.radial_center {
            self.vec_len(&key("radial_center"), c)?;
        }
        if let Some(g) = &r.gresho {
            if self.case.dimension != 2 {
                return Err(CaseError(format!(
                    "{}: only in 2D (case.dimension = 2)",
                    key("gresho")
                )));
            }
            g.validate(&key("gresho"))?;
        }
        Ok(())
    }

    /// The box a region fills (its own corners, else the domain).
    pub(crate) fn region_box(&self, r: &Region) -> (Vec<f64>, Vec<f64>) {
        match r.shape {
            Shape::Box => (
                r.min.clone().unwrap_or_else(|| self.domain.min.clone()),
                r.max.clone().unwrap_or_else(|| self.domain.max.clone()),
            ),
            Shape::Sphere => {
                let c = r.center.clone().unwrap_or_default();
                let rad = r.radius.unwrap_or(0.0);
                (
                    c.iter().map(|x| x - rad).collect(),
                    c.iter().map(|x| x + rad).collect(),
                )
            }
        }
    }

    pub fn step_control(&self) -> StepControl {
        StepControl {
            cfl: self.cfl(),
            cfl_accel: self.time.cfl_accel,
            dt_min: self.time.dt_min,
            dt_max: self.time.dt_max.unwrap_or(f64::INFINITY),
            ..StepControl::default()
        }
    }

    /// The same case run with another scheme preset (`name` as in `[scheme] name = ...`, with
    /// its default parameters): the case's kernel choice, η, integrator and Courant factor
    /// are dropped so the scheme's own apply (its paper's setup); h_max and everything else stay.
    pub fn with_scheme(&self, name: &str) -> Result<Case, CaseError> {
        let scheme: SchemeConfig = toml::from_str(&format!("name = {:?}", name)).map_err(|e| {
            CaseError(format!(
                "scheme: unknown preset {name:?} ({})",
                one_line(e.message())
            ))
        })?;
        let mut case = self.clone();
        case.scheme = scheme;
        case.kernel = KernelConfig {
            h_max: self.kernel.h_max,
            ..KernelConfig::default()
        };
        case.time.integrator = None;
        case.time.cfl = None;
        case.validate()?;
        Ok(case)
    }

    /// Build the simulation (particles, first evaluation) in dimension D.
    pub fn build<const D: usize>(&self) -> Result<Simulation<D>, CaseError> {
        let sys = self.system::<D>()?;
        self.simulation(sys)
    }

    /// The simulation of this case's scheme, integrator and step control on `sys` (a system
    /// from [`Self::system`], possibly adjusted: tests place particles the lattice cannot).
    pub fn simulation<const D: usize>(&self, sys: System<D>) -> Result<Simulation<D>, CaseError> {
        Simulation::new(
            sys,
            self.scheme.build::<D>(),
            self.integrator(),
            self.step_control(),
        )
        .map_err(|e: SolverError| CaseError(format!("initial state: {e}")))
    }

    /// The particles, box, kernel and EOS of this case in dimension D, before any evaluation.
    pub fn system<const D: usize>(&self) -> Result<System<D>, CaseError> {
        if D != self.case.dimension {
            return Err(CaseError(format!(
                "case.dimension = {} but built in {D}D",
                self.case.dimension
            )));
        }
        let mut lo = [0.0; D];
        let mut hi = [0.0; D];
        let mut kind = [BoundaryKind::Open; D];
        lo.copy_from_slice(&self.domain.min);
        hi.copy_from_slice(&self.domain.max);
        kind.copy_from_slice(&self.domain.boundary);
        let domain = Domain { lo, hi, kind };
        let eta = self.eta()?;
        let kernel = DimKernel::<D>::new(self.kernel()?);
        let (mut particles, bodies) = generate_particles::<D>(self, &domain, eta)?;
        let ports = ports::add_ports(self, &mut particles, &bodies)?;
        let extent = (0..D).map(|k| hi[k] - lo[k]).fold(0.0, f64::max);
        let h_max = self.kernel.h_max.unwrap_or(0.25 * extent);
        // Minimum image needs the search radius below half of every periodic side.
        let hmax0 = particles.h.iter().cloned().fold(0.0, f64::max);
        let reach = kernel.radius(hmax0) * (1.0 + crate::scheme::smoothing::SKIN);
        for k in 0..D {
            if kind[k] != BoundaryKind::Open && reach * 2.0 >= hi[k] - lo[k] {
                return Err(CaseError(format!(
                    "domain: side {k} ({}) must exceed twice the kernel reach 2·2h(1+skin) = {:.4}; enlarge the domain or refine the lattice",
                    hi[k] - lo[k],
                    2.0 * reach
                )));
            }
        }
        let h_max = match (0..D)
            .filter(|&k| kind[k] != BoundaryKind::Open)
            .map(|k| hi[k] - lo[k])
            .reduce(f64::min)
        {
            Some(l) => h_max.min(
                0.99 * l / (2.0 * crate::kernel::SUPPORT * (1.0 + crate::scheme::smoothing::SKIN)),
            ),
            None => h_max,
        };
        let mut gravity = crate::particles::Vector::<D>::zeros();
        if let Some(g) = &self.gravity {
            for k in 0..D {
                gravity[k] = g[k];
            }
        }
        Ok(System {
            particles,
            domain,
            kernel,
            eos: self.eos,
            eta,
            h_max,
            gravity,
            grid: Default::default(),
            verlet: Default::default(),
            neighbours: Default::default(),
            stats: Default::default(),
            bodies,
            evolve_density: false,
            wall_pairs: false,
            frame: self.frame.as_ref().map(|f| f.build::<D>()),
            ports,
            time: 0.0,
        })
    }
}
