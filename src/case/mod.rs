//! Case files (`models/*.toml`): a scenario as data. Parsed with serde (unknown keys are
//! errors), then validated range by range; every error names the key and the allowed range.

pub mod bodies;
mod checks;
mod estimate;
pub mod fields;
mod glass;
mod ics;
mod interface;
mod overrides;
mod ports;
mod probes;
mod sections;
mod validate;

pub use sections::*;

pub use probes::{MarkerConfig, PatchConfig, ProbeConfig};

pub use bodies::BodyConfig;
pub use checks::{Blast, Verify};
pub use estimate::{available_memory, Limits, SizeEstimate};
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
    /// Initial-state fields as expressions of position (`fields.rs`).
    #[serde(default, rename = "field")]
    pub fields: Vec<fields::FieldExpr>,
    /// Relax the initial lattice into a glass (Rosswog (2015) Sec. 7.1).
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
    /// Equations of state of their own for materials other than 0 (`[eos]`).
    #[serde(default, rename = "material")]
    pub materials: Vec<crate::eos::MaterialConfig>,
    /// Openings in bodies where an outside model sets the pressure (`boundary::ports`).
    #[serde(default, rename = "port")]
    pub ports: Vec<PortConfig>,
    /// Caps on the run's size, checked before anything is allocated (`estimate.rs`).
    #[serde(default)]
    pub limits: Limits,
}

/// Most evaluations spent settling `[[field]] stage = "density"` entries: one suffices where
/// the density does not depend on the pressure; X = P^k (k = 0.05) moves it by about 5 % of
/// the pressure change per pass.
const MAX_DENSITY_STAGE_PASSES: usize = 20;

fn one_line(s: &str) -> String {
    s.split_whitespace().collect::<Vec<_>>().join(" ")
}

impl Case {
    /// The case as TOML text that [`Self::parse`] reads back to the same case (how the FMU
    /// packager stores a case changed by `--set`).
    pub fn to_text(&self) -> Result<String, CaseError> {
        toml::to_string(self).map_err(|e| CaseError(format!("cannot write the case: {e}")))
    }

    /// Read and validate a case file.
    pub fn load(path: &Path) -> Result<Case, CaseError> {
        Self::load_with(path, None, &[])
    }

    /// Read a case file, set `key=value` overrides in it (`--set`), then validate it. A key is
    /// a dotted path into the file's tables (`time.t_end`, `region.0.spacing`); `*` in place of
    /// an index sets every entry of an array of tables (`region.*.spacing`). The value is a TOML
    /// value (`0.01`, `"crksph"`, `[1.0, 2.0]`). A key must already exist, unless its last
    /// segment is new in an existing table, so that a typo cannot pass unnoticed as a new table.
    ///
    /// A `scheme` preset (`--scheme`) replaces the file's scheme first ([`Self::with_scheme`]),
    /// and the overrides apply to the result: `--scheme crksph --set scheme.limiter=false`
    /// runs CRKSPH without its limiter (the preset applied after the overrides would drop them).
    pub fn load_with(
        path: &Path,
        scheme: Option<&str>,
        sets: &[String],
    ) -> Result<Case, CaseError> {
        let text = std::fs::read_to_string(path)
            .map_err(|e| CaseError(format!("{}: cannot read: {e}", path.display())))?;
        let at = |e: CaseError| CaseError(format!("{}: {}", path.display(), e.0));
        // parsed as written, so errors keep the file's line numbers
        let mut table: toml::Table = match scheme {
            None if sets.is_empty() => return Self::parse(&text).map_err(at),
            None => toml::from_str(&text).map_err(|e| at(CaseError(one_line(e.message()))))?,
            Some(name) => {
                let case = Self::parse(&text)
                    .and_then(|c| c.with_scheme(name))
                    .map_err(at)?;
                if sets.is_empty() {
                    return Ok(case);
                }
                toml::Table::try_from(&case).map_err(|e| {
                    at(CaseError(format!(
                        "--scheme: cannot write the case back: {e}"
                    )))
                })?
            }
        };
        // `[kernel]` is optional and every key of it too: an absent one is the empty table, so
        // `--set kernel.eta=…` works on a case that takes its scheme's kernel
        table
            .entry("kernel")
            .or_insert_with(|| toml::Value::Table(toml::Table::new()));
        for s in sets {
            overrides::apply(&mut table, s).map_err(at)?;
        }
        let text = toml::to_string(&table)
            .map_err(|e| at(CaseError(format!("--set: cannot write the case back: {e}"))))?;
        Self::parse(&text).map_err(|e| at(CaseError(format!("after --set: {}", e.0))))
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

    pub fn step_control(&self) -> StepControl {
        StepControl {
            cfl: self.cfl(),
            cfl_accel: self.time.cfl_accel,
            dt_min: self.time.dt_min,
            dt_max: self.time.dt_max.unwrap_or(f64::INFINITY),
            ..StepControl::default()
        }
    }

    /// Whether the lattices' masses carry their kernel-sum factor
    /// (`ics::lattice_density_factor`): for a gas whose scheme sums its density.
    ///
    /// Our decision for liquids (an EOS with a pressure offset: Tait, stiffened gas): they
    /// keep m = ρV. A liquid fills its container, whose volume then fixes the mass at ρV, and
    /// with a stiff EOS a mass error shows as a pressure error of ρc² times it. Measured in
    /// the closed tank (`closed-tank2d.toml`, ε = −2.4e-4 for its square lattice): the
    /// mid-depth pressure settles at +0.87 % of hydrostatic with the factor and +0.01 %
    /// without.
    pub fn corrects_lattice_density(&self) -> bool {
        self.scheme.sums_density() && self.eos.pressure_offset() == 0.0
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
        let sim = Simulation::new(
            sys,
            self.scheme.build::<D>(),
            self.integrator(),
            self.step_control(),
        )
        .map_err(initial_state)?;
        self.density_stage(sim)
    }

    /// This case on the ranks of `comm` (`parallel`): every rank builds the whole system and
    /// keeps its own region's particles.
    pub fn distributed<const D: usize>(
        &self,
        comm: std::sync::Arc<dyn crate::parallel::comm::Comm>,
    ) -> Result<Simulation<D>, CaseError> {
        let sim = crate::parallel::start(
            self.system::<D>()?,
            self.scheme.build::<D>(),
            self.integrator(),
            self.step_control(),
            comm,
        )
        .map_err(initial_state)?;
        self.density_stage(sim)
    }

    /// `[[field]] stage = "density"`: set from the scheme's density, then evaluate again;
    /// repeated while the density moves (X = P^k volume elements make it depend on P).
    fn density_stage<const D: usize>(
        &self,
        mut sim: Simulation<D>,
    ) -> Result<Simulation<D>, CaseError> {
        for _ in 0..MAX_DENSITY_STAGE_PASSES {
            let before = sim.sys.particles.rho.clone();
            if !fields::apply_after_density(&self.fields, &mut sim.sys)? {
                break;
            }
            sim.reevaluate().map_err(initial_state)?;
            let own = sim.sys.owned();
            let mut moved = before[..own]
                .iter()
                .zip(&sim.sys.particles.rho)
                .map(|(a, b)| ((a - b) / b).abs())
                .fold(0.0, f64::max);
            if let Some(layout) = &sim.layout {
                // every rank stops at the same pass: the largest change over the ranks
                moved = -layout
                    .agree_dt(-moved)
                    .map_err(|e| CaseError(format!("initial state: {e}")))?;
            }
            if moved < 1e-13 {
                break;
            }
        }
        Ok(sim)
    }

    /// The EOS of material `m`: its `[[material]]` entry, else `[eos]`.
    pub fn eos_of(&self, m: u16) -> EosConfig {
        self.materials
            .iter()
            .find(|e| e.id == m)
            .map_or(self.eos, |e| e.eos)
    }

    /// EOS by material id up to the largest id with an entry (empty without `[[material]]`).
    fn material_table(&self) -> Vec<EosConfig> {
        let top = self.materials.iter().map(|e| e.id).max();
        top.map_or(vec![], |t| (0..=t).map(|m| self.eos_of(m)).collect())
    }

    /// Driven regions in region order: region `ri`'s particles carry `drive_tag(ri)`.
    fn drives<const D: usize>(&self) -> Result<Vec<crate::boundary::drive::Drive<D>>, CaseError> {
        self.regions
            .iter()
            .enumerate()
            .filter_map(|(i, r)| {
                r.drive
                    .as_ref()
                    .map(|d| d.build::<D>(&format!("region[{i}].drive")))
            })
            .collect()
    }

    /// 0 for an evolved region, k + 1 for the k-th driven one.
    pub fn drive_tag(&self, ri: usize) -> u16 {
        if self.regions[ri].drive.is_none() {
            return 0;
        }
        self.regions[..=ri]
            .iter()
            .filter(|r| r.drive.is_some())
            .count() as u16
    }

    /// The particles, box, kernel and EOS of this case in dimension D, before any evaluation
    /// (compiled in this crate once per dimension: `crate::monomorphic`).
    pub fn system<const D: usize>(&self) -> Result<System<D>, CaseError> {
        // checked before the dispatch, so that any other D is this error, not a panic
        if D != self.case.dimension {
            return Err(CaseError(format!(
                "case.dimension = {} but built in {D}D",
                self.case.dimension
            )));
        }
        crate::monomorphic::system(self)
    }

    /// [`Self::system`]'s work, generic over D (which [`Self::system`] checked).
    pub(crate) fn system_generic<const D: usize>(&self) -> Result<System<D>, CaseError> {
        // the size first: nothing is allocated for a case that cannot fit
        self.check_resources(&self.limits)?;
        let mut lo = [0.0; D];
        let mut hi = [0.0; D];
        let mut kind = [BoundaryKind::Open; D];
        lo.copy_from_slice(&self.domain.min);
        hi.copy_from_slice(&self.domain.max);
        kind.copy_from_slice(&self.domain.boundary);
        let domain = Domain { lo, hi, kind };
        let eta = self.eta()?;
        let kernel = DimKernel::<D>::new(self.kernel()?);
        let summed = self.corrects_lattice_density().then_some(&kernel);
        let (mut particles, bodies) = generate_particles::<D>(self, &domain, eta, summed)?;
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
            relativistic: None,
            canonical_order: true,
            halo: 0,
            ranks: None,
            scratch: Default::default(),
            frame: self.frame.as_ref().map(|f| f.build::<D>()),
            ports,
            drives: self.drives::<D>()?,
            material_eos: self.material_table(),
            time: 0.0,
        })
    }
}

/// A failure while building the initial state, as a case error.
fn initial_state(e: SolverError) -> CaseError {
    CaseError(format!("initial state: {e}"))
}
