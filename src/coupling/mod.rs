//! The `Coupling` interface (issue 5): what a co-simulation master does with the solver —
//! set gravity, set the pose and velocities of externally driven bodies, step to a time,
//! read forces, torques, probe and marker values, and save / restore the whole state bit for
//! bit. The FMU and the zenoh bridge are thin faces over this type; it knows nothing of FMI
//! or zenoh.
//!
//! Each `Coupling` owns its rayon pool (the FMU lives in someone else's process, beside other
//! instances): every solver call runs inside `pool.install`.
//!
//! Inputs take effect from the current time on: gravity is held constant until the next
//! change, and an external body moves on at the velocities it was given. A changed input
//! makes the next `step_to` re-evaluate the derivatives at the current state first (so the
//! first step after a jump in gravity or a moved wall sees it); an input set to the value it
//! already has changes nothing, so repeating inputs keeps runs identical.

mod engine;
mod integrity;
pub mod orientation;
pub mod sampling;
pub mod state;
mod stepping;

pub use stepping::{StepBudget, StepLimit, StepReport};

use crate::case::{Case, CaseError};
use crate::sim::Diagnostics;
use engine::Engine;
use std::fmt;
use std::path::Path;

/// Why a Coupling call failed. The state is unchanged when an input is rejected; after a
/// solver failure (`step_to`) it is the state where the solver stopped, and `restore` of a
/// saved state makes it usable again.
#[derive(Debug, Clone, PartialEq)]
pub struct CouplingError(pub String);

impl fmt::Display for CouplingError {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.write_str(&self.0)
    }
}

impl std::error::Error for CouplingError {}

impl From<CaseError> for CouplingError {
    fn from(e: CaseError) -> Self {
        CouplingError(e.0)
    }
}

/// Settings a master may change before the run (FMU parameters).
#[derive(Debug, Clone, PartialEq)]
pub struct CouplingOptions {
    /// Another scheme preset (its own kernel and integrator), as `sphfmu run --scheme`.
    pub scheme: Option<String>,
    /// Refinement factor on every particle spacing (2 = twice as fine), in [0.1, 10].
    pub resolution: f64,
    /// Courant factor replacing the case's, in (0, 1].
    pub cfl: Option<f64>,
    /// Worker threads of this instance's pool (0 = one per core).
    pub threads: usize,
    /// Size limits replacing the case's `[limits]` where set (the FMU's `limits.*`).
    pub limits: crate::case::Limits,
}

impl Default for CouplingOptions {
    fn default() -> Self {
        Self {
            scheme: None,
            resolution: 1.0,
            cfl: None,
            threads: 0,
            limits: Default::default(),
        }
    }
}

impl CouplingOptions {
    /// The case with these options applied (and validated).
    pub fn apply(&self, case: &Case) -> Result<Case, CouplingError> {
        let r = self.resolution;
        if !(r.is_finite() && (0.1..=10.0).contains(&r)) {
            return Err(CouplingError(format!(
                "resolution: must be in [0.1, 10], got {r}"
            )));
        }
        let mut case = match &self.scheme {
            Some(s) if !s.trim().is_empty() => case.with_scheme(s.trim())?,
            _ => case.clone(),
        };
        if r != 1.0 {
            let d = case.case.dimension as i32;
            for reg in &mut case.regions {
                reg.spacing = reg.spacing.map(|s| s / r);
                reg.particle_mass = reg.particle_mass.map(|m| m / r.powi(d));
            }
            for b in &mut case.bodies {
                b.spacing = b.spacing.map(|s| s / r);
            }
        }
        if let Some(c) = self.cfl {
            if !(c.is_finite() && c > 0.0 && c <= 1.0) {
                return Err(CouplingError(format!("cfl: must be in (0, 1], got {c}")));
            }
            case.time.cfl = Some(c);
        }
        if let Some(m) = self.limits.max_particles {
            case.limits.max_particles = Some(m);
        }
        if let Some(m) = self.limits.max_memory {
            case.limits.max_memory = Some(m);
        }
        case.validate()?;
        Ok(case)
    }
}

/// Pose and velocities of an externally driven body (`motion = { type = "external" }`):
/// the position of its reference point, its orientation (a unit quaternion [w, x, y, z] that
/// turns body offsets into world offsets, `orientation`; 2D: a rotation about z, 1D: the
/// identity), its velocity and world angular velocity, and the acceleration and angular
/// acceleration it moves on with until the next update (`HeldPose`: zero by default, so the
/// body moves on at constant velocity; a master integrating the body by the trapezoidal rule
/// gives a = (v1 − v0)/H and the body reaches its x1 and v1 exactly). Entries beyond the
/// case's dimension must be 0 (2D: ω and α about z only).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct BodyKinematics {
    pub position: [f64; 3],
    pub orientation: [f64; 4],
    pub velocity: [f64; 3],
    pub angular_velocity: [f64; 3],
    pub acceleration: [f64; 3],
    pub angular_acceleration: [f64; 3],
}

impl Default for BodyKinematics {
    fn default() -> Self {
        Self {
            position: [0.0; 3],
            orientation: orientation::IDENTITY,
            velocity: [0.0; 3],
            angular_velocity: [0.0; 3],
            acceleration: [0.0; 3],
            angular_acceleration: [0.0; 3],
        }
    }
}

impl BodyKinematics {
    /// A 2D body's angle and angular velocity about z.
    pub fn set_planar(&mut self, angle: f64, angular_velocity: f64) {
        self.orientation = orientation::planar(angle);
        self.angular_velocity = [0.0, 0.0, angular_velocity];
    }
}

/// Force and torque of the fluid on one body (torque about its moved reference point; 2D:
/// only z), from the latest evaluation, in world axes and in the body's own axes (Rᵀ F, Rᵀ T,
/// with R the body's orientation).
#[derive(Debug, Clone, Copy, PartialEq, Default)]
pub struct BodyLoads {
    pub force: [f64; 3],
    pub torque: [f64; 3],
    pub force_body: [f64; 3],
    pub torque_body: [f64; 3],
}

/// Fluid state at a probe, Shepard-interpolated: `coverage` = Σ_f V_f W(x − x_f, h_f) is
/// ≈ 1 inside the fluid, below 1 near a free surface and 0 where no fluid reaches (then
/// the values are 0).
#[derive(Debug, Clone, Copy, PartialEq, Default)]
pub struct ProbeValue {
    pub density: f64,
    pub pressure: f64,
    pub velocity: [f64; 3],
    pub coverage: f64,
}

/// Loads on a `[[patch]]`: mean and peak pressure over its surface wall particles, its area
/// (their count × Δx^{D−1}; 2D: per metre of depth) and the force of the fluid on all its
/// wall particles.
#[derive(Debug, Clone, Copy, PartialEq, Default)]
pub struct PatchValue {
    pub mean_pressure: f64,
    pub peak_pressure: f64,
    pub area: f64,
    pub force: [f64; 3],
}

/// Flow through a `[[port]]`, sampled on its opening (Shepard interpolation over fluid and
/// buffer at one point per buffer lattice cell): the port pressure in force now, the mean
/// pressure the fluid shows on the opening, the mean velocity along the port normal (into the
/// fluid: positive = inflow), volume and mass flow into the fluid (2D: per metre of depth),
/// and the exact fluid mass that entered and left through the port since t = 0 (particles
/// counted as they cross, so fluid mass = initial + Σ in − Σ out to round-off).
#[derive(Debug, Clone, Copy, PartialEq, Default)]
pub struct PortValue {
    pub pressure: f64,
    pub mean_pressure: f64,
    pub velocity: f64,
    pub volume_flow: f64,
    pub mass_flow: f64,
    pub mass_in: f64,
    pub mass_out: f64,
}

/// What a particle is: fluid, a wall particle of body b, or a buffer particle of port k.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum ParticleKind {
    Fluid,
    Wall(usize),
    Buffer(usize),
}

/// One particle's state (entries beyond the dimension are 0).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct ParticleState {
    pub kind: ParticleKind,
    pub position: [f64; 3],
    pub velocity: [f64; 3],
    pub density: f64,
    pub pressure: f64,
}

/// Which wall particles (stable ids) make up a patch.
#[derive(Debug, Clone, PartialEq)]
pub(crate) struct PatchMembers {
    pub all: Vec<u32>,
    pub surface: Vec<u32>,
    pub cell_area: f64,
}

pub struct Coupling {
    case: Case,
    engine: Box<dyn Engine>,
    pool: rayon::ThreadPool,
    patches: Vec<PatchMembers>,
}

impl Coupling {
    /// Build the solver for `case` with `options` (particles, first evaluation).
    pub fn new(case: &Case, options: &CouplingOptions) -> Result<Self, CouplingError> {
        Self::new_on(case, options, None)
    }

    /// [`Self::new`], the particles shared among `ranks` when given (`parallel`): every rank
    /// builds it with the same case and options, and from then on makes the same calls in the
    /// same order (inputs, steps, reads, saves), since most of them are collectives. The
    /// outputs and saved states are the whole case's on every rank.
    pub fn new_on(
        case: &Case,
        options: &CouplingOptions,
        ranks: Option<std::sync::Arc<dyn crate::parallel::comm::Comm>>,
    ) -> Result<Self, CouplingError> {
        let case = options.apply(case)?;
        if case.scheme.relativistic() {
            return Err(CouplingError(
                "scheme.name: the rosswog-sr presets (special relativity, c = 1) run in the CLI only (`sphfmu run`); a co-simulation needs a Newtonian scheme".into(),
            ));
        }
        let threads = if options.threads == 0 {
            std::thread::available_parallelism()
                .map(|n| n.get())
                .unwrap_or(1)
        } else {
            options.threads
        };
        let pool = rayon::ThreadPoolBuilder::new()
            .num_threads(threads)
            .build()
            .map_err(|e| CouplingError(format!("threads: cannot start {threads} workers ({e})")))?;
        let engine = pool.install(|| engine::build(&case, ranks))?;
        let specs: Vec<engine::PatchSpec> = case
            .patches
            .iter()
            .map(|pa| {
                let b = case
                    .bodies
                    .iter()
                    .position(|b| b.name == pa.body)
                    .expect("validated: the patch's body exists");
                engine::PatchSpec {
                    body: b,
                    min: pad(&pa.min),
                    max: pad(&pa.max),
                    spacing: case.bodies[b]
                        .spacing
                        .unwrap_or_else(|| case.finest_spacing()),
                    shape: case.bodies[b].shape.clone(),
                }
            })
            .collect();
        let patches = engine.patch_members(&specs);
        if let Some(i) = patches.iter().position(|m| m.surface.is_empty()) {
            return Err(CouplingError(format!(
                "patch[{i}]: the box {:?}..{:?} holds no surface wall particle of body {:?}",
                case.patches[i].min, case.patches[i].max, case.patches[i].body
            )));
        }
        Ok(Self {
            case,
            engine,
            pool,
            patches,
        })
    }

    /// [`Self::new`] for a case file.
    pub fn from_file(path: &Path, options: &CouplingOptions) -> Result<Self, CouplingError> {
        let case = Case::load(path)?;
        Self::new(&case, options)
    }

    /// The case as run (options applied).
    pub fn case(&self) -> &Case {
        &self.case
    }

    pub fn dimension(&self) -> usize {
        self.case.case.dimension
    }

    pub fn time(&self) -> f64 {
        self.engine.time()
    }

    pub fn body_names(&self) -> Vec<&str> {
        self.case.bodies.iter().map(|b| b.name.as_str()).collect()
    }

    /// Index of the body called `name`.
    pub fn body_index(&self, name: &str) -> Result<usize, CouplingError> {
        self.case
            .bodies
            .iter()
            .position(|b| b.name == name)
            .ok_or_else(|| {
                CouplingError(format!(
                    "body: no body named {name:?} (bodies: {:?})",
                    self.body_names()
                ))
            })
    }

    pub fn gravity(&self) -> [f64; 3] {
        self.engine.gravity()
    }

    /// Uniform gravity from now on. Entries must be finite and 0 beyond the dimension.
    pub fn set_gravity(&mut self, g: [f64; 3]) -> Result<(), CouplingError> {
        self.check_gravity(&g)?;
        self.engine.set_gravity(&g);
        Ok(())
    }

    /// Whether [`Self::set_gravity`] would take `g` (it changes nothing).
    pub fn check_gravity(&self, g: &[f64; 3]) -> Result<(), CouplingError> {
        check_vector("gravity", g, self.dimension())
    }

    /// Pose and velocities of body `body` from now on (its motion must be `external`).
    pub fn set_body_kinematics(
        &mut self,
        body: usize,
        k: &BodyKinematics,
    ) -> Result<(), CouplingError> {
        self.check_body_kinematics(body, k)?;
        self.engine.set_body(body, k);
        Ok(())
    }

    /// Whether [`Self::set_body_kinematics`] would take `k` for `body` (it changes nothing).
    pub fn check_body_kinematics(
        &self,
        body: usize,
        k: &BodyKinematics,
    ) -> Result<(), CouplingError> {
        let d = self.dimension();
        let cfg = self.case.bodies.get(body).ok_or_else(|| {
            CouplingError(format!(
                "body: index {body} out of range (the case has {} bodies)",
                self.case.bodies.len()
            ))
        })?;
        if cfg.motion != crate::boundary::kinematics::Motion::External {
            return Err(CouplingError(format!(
                "body {:?}: its motion is prescribed by the case; set motion = {{ type = \"external\" }} to drive it from outside",
                cfg.name
            )));
        }
        check_rigid_motion(&format!("body {:?}", cfg.name), k, d)
    }

    /// Whether the case has a frame driven from outside (`[frame] motion = external`).
    pub fn has_external_frame(&self) -> bool {
        self.case
            .frame
            .as_ref()
            .is_some_and(|f| f.motion == crate::boundary::kinematics::Motion::External)
    }

    /// The pose, velocities and accelerations of the case's frame from now on (its motion
    /// must be external). Its position and velocity do not enter the physics (the frame's
    /// forces are those of its acceleration and rotation); they are kept for the master.
    pub fn set_frame_kinematics(&mut self, k: &BodyKinematics) -> Result<(), CouplingError> {
        self.check_frame_kinematics(k)?;
        self.engine.set_frame(k);
        Ok(())
    }

    /// Whether [`Self::set_frame_kinematics`] would take `k` (it changes nothing).
    pub fn check_frame_kinematics(&self, k: &BodyKinematics) -> Result<(), CouplingError> {
        if !self.has_external_frame() {
            return Err(CouplingError(
                "frame: the case has no [frame] with motion = { type = \"external\" }".into(),
            ));
        }
        check_rigid_motion("frame", k, self.dimension())
    }

    /// The frame's current pose and velocities (`None` without a `[frame]`).
    pub fn frame_kinematics(&self) -> Option<BodyKinematics> {
        self.engine.frame()
    }

    /// Current pose and velocities of body `body` (any motion).
    pub fn body_kinematics(&self, body: usize) -> BodyKinematics {
        self.engine.body(body)
    }

    /// Force and torque on every body, in case order.
    pub fn loads(&self) -> Vec<BodyLoads> {
        self.engine.loads()
    }

    pub fn port_names(&self) -> Vec<&str> {
        self.case.ports.iter().map(|p| p.name.as_str()).collect()
    }

    /// Index of the port called `name`.
    pub fn port_index(&self, name: &str) -> Result<usize, CouplingError> {
        self.case
            .ports
            .iter()
            .position(|p| p.name == name)
            .ok_or_else(|| {
                CouplingError(format!(
                    "port: no port named {name:?} (ports: {:?})",
                    self.port_names()
                ))
            })
    }

    /// Pressure of port `port` from now on (its pressure must be `external`): finite and
    /// ≥ 0 (the solver's gauge: 0 at the EOS reference density). A rejected value changes
    /// nothing.
    pub fn set_port_pressure(&mut self, port: usize, pressure: f64) -> Result<(), CouplingError> {
        self.check_port_pressure(port, pressure)?;
        self.engine.set_port_pressure(port, pressure);
        Ok(())
    }

    /// Whether [`Self::set_port_pressure`] would take `pressure` (it changes nothing).
    pub fn check_port_pressure(&self, port: usize, pressure: f64) -> Result<(), CouplingError> {
        let cfg = self.case.ports.get(port).ok_or_else(|| {
            CouplingError(format!(
                "port: index {port} out of range (the case has {} ports)",
                self.case.ports.len()
            ))
        })?;
        if !matches!(
            cfg.pressure,
            crate::boundary::ports::PortPressure::External { .. }
        ) {
            return Err(CouplingError(format!(
                "port {:?}: its pressure is prescribed by the case; set pressure = {{ type = \"external\" }} to drive it from outside",
                cfg.name
            )));
        }
        if !(pressure.is_finite() && pressure >= 0.0) {
            return Err(CouplingError(format!(
                "port {:?} pressure: must be a finite number ≥ 0, got {pressure}",
                cfg.name
            )));
        }
        Ok(())
    }

    /// Flow and pressure at every `[[port]]`, in case order.
    pub fn ports(&self) -> Vec<PortValue> {
        self.pool.install(|| self.engine.ports())
    }

    /// Every `stride`-th particle's state (stride ≥ 1; 1: all), in storage order.
    pub fn particles(&self, stride: usize) -> Vec<ParticleState> {
        self.engine.particles(stride.max(1))
    }

    /// Values at every `[[probe]]`, in case order.
    pub fn probes(&self) -> Vec<ProbeValue> {
        let points: Vec<[f64; 3]> = self.case.probes.iter().map(|p| pad(&p.point)).collect();
        self.pool.install(|| self.engine.probes(&points))
    }

    /// Wall pressure at every `[[marker]]`, in case order.
    pub fn markers(&self) -> Vec<f64> {
        let markers: Vec<(usize, [f64; 3])> = self
            .case
            .markers
            .iter()
            .map(|m| {
                let b = self.case.bodies.iter().position(|b| b.name == m.body);
                (
                    b.expect("validated: the marker's body exists"),
                    pad(&m.point),
                )
            })
            .collect();
        self.pool.install(|| self.engine.markers(&markers))
    }

    /// Loads on every `[[patch]]`, in case order.
    pub fn patches(&self) -> Vec<PatchValue> {
        self.engine.patches(&self.patches)
    }

    /// Time, steps, particle count, fluid mass, momentum and energy.
    pub fn diagnostics(&self) -> Diagnostics {
        self.pool.install(|| self.engine.diagnostics())
    }

    /// Write the particles as `dir/snapshot_NNNNN.vtu` (NNNNN = `index`) and the ParaView
    /// collection `dir/snapshots.pvd` listing `written` plus this one; returns the entry to
    /// keep for the next call.
    pub fn write_snapshot(
        &self,
        dir: &Path,
        index: usize,
        written: &[(f64, String)],
    ) -> Result<(f64, String), CouplingError> {
        let fail = |p: &Path, e: std::io::Error| CouplingError(format!("{}: {e}", p.display()));
        std::fs::create_dir_all(dir).map_err(|e| fail(dir, e))?;
        let name = format!("snapshot_{index:05}.vtu");
        let path = dir.join(&name);
        self.pool
            .install(|| self.engine.write_vtu(&path))
            .map_err(|e| fail(&path, e))?;
        let entry = (self.time(), name);
        let mut all = written.to_vec();
        all.push(entry.clone());
        let pvd = dir.join("snapshots.pvd");
        crate::io::write_pvd(&pvd, &all).map_err(|e| fail(&pvd, e))?;
        Ok(entry)
    }

    /// The whole solver state as bytes; [`Self::restore`] of them continues bit for bit as
    /// this instance would. In a distributed run a collective, which fails when the ranks
    /// cannot exchange; its bytes are the same on every rank, and restore on any number of
    /// ranks.
    pub fn save(&self) -> Result<Vec<u8>, CouplingError> {
        self.engine
            .save(state::fingerprint(&self.case))
            .map_err(CouplingError)
    }

    /// Return to a state from [`Self::save`] of a Coupling built from the same case and
    /// options. A state that does not fit is rejected and nothing changes.
    pub fn restore(&mut self, bytes: &[u8]) -> Result<(), CouplingError> {
        self.engine
            .restore(bytes, state::fingerprint(&self.case))
            .map_err(CouplingError)
    }
}

fn pad(v: &[f64]) -> [f64; 3] {
    let mut o = [0.0; 3];
    o[..v.len().min(3)].copy_from_slice(&v[..v.len().min(3)]);
    o
}

/// Finite entries, 0 beyond the dimension.
fn check_vector(key: &str, v: &[f64; 3], d: usize) -> Result<(), CouplingError> {
    for (k, x) in v.iter().enumerate() {
        if !x.is_finite() {
            return Err(CouplingError(format!(
                "{key}[{k}]: must be finite, got {x}"
            )));
        }
        if k >= d && *x != 0.0 {
            return Err(CouplingError(format!(
                "{key}[{k}]: must be 0 in a {d}D case, got {x}"
            )));
        }
    }
    Ok(())
}

/// The checks every master-set rigid motion passes (`what` names the body or the frame): finite
/// numbers, 0 beyond the dimension, a quaternion within 1e-6 of unit length, and in 2D a
/// rotation, angular velocity and angular acceleration about z only (none in 1D).
fn check_rigid_motion(what: &str, k: &BodyKinematics, d: usize) -> Result<(), CouplingError> {
    let key = |f: &str| format!("{what} {f}");
    check_vector(&key("position"), &k.position, d)?;
    check_vector(&key("velocity"), &k.velocity, d)?;
    check_vector(&key("acceleration"), &k.acceleration, d)?;
    let q =
        orientation::unit_quaternion(&key("orientation"), &k.orientation).map_err(CouplingError)?;
    for (f, v) in [
        ("angular_velocity", &k.angular_velocity),
        ("angular_acceleration", &k.angular_acceleration),
    ] {
        if let Some(x) = v.iter().find(|x| !x.is_finite()) {
            return Err(CouplingError(format!(
                "{}: entries must be finite, got {x}",
                key(f)
            )));
        }
    }
    let (w, al) = (&k.angular_velocity, &k.angular_acceleration);
    // a 2D body turns about z only, a 1D body not at all
    let (turns, about) = match d {
        1 => (&[][..], "nothing rotates in a 1D case"),
        2 => (&[2][..], "it turns about z only in a 2D case"),
        _ => (&[0, 1, 2][..], ""),
    };
    for c in 0..3 {
        if !turns.contains(&c) && (w[c] != 0.0 || al[c] != 0.0 || q[c + 1] != 0.0) {
            return Err(CouplingError(format!(
                    "{}: {about}: angular velocity {w:?}, angular acceleration {al:?} and quaternion [w, x, y, z] {q:?} must have 0 in {}",
                    key("orientation / angular_velocity / angular_acceleration"),
                    ["x", "y", "z"][c]
                )));
        }
    }
    Ok(())
}
