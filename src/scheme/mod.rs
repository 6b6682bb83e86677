//! Hydrodynamic formulations. A scheme turns the current (x, v, u) into dv/dt and du/dt; the
//! driver and the integrators never know which scheme runs. Each formulation lives in its own
//! module behind [`Scheme`]; all of them loop over pairs through [`System::gather`].

pub mod compatible;
pub mod compsph;
pub mod crksph;
pub mod cullen;
mod paper_step;
pub mod psph;
pub mod rosswog;
pub mod rpsph;
pub mod smoothing;
pub mod standard;

use crate::system::System;
use serde::{Deserialize, Serialize};

/// Failure inside an evaluation (reported with the step and time by the driver).
#[derive(Debug, Clone, PartialEq)]
pub struct SchemeError(pub String);

pub trait Scheme<const D: usize>: Send + Sync {
    /// Preset name as written in case files.
    fn name(&self) -> &'static str;
    /// Register per-particle fields and set initial switch values.
    fn init(&mut self, sys: &mut System<D>);
    /// Full derivative evaluation: neighbours, density and h, EOS, gradients, forces.
    /// Leaves `acc`, `dudt`, `v_sig` (and the derived fields) in the particles.
    fn evaluate(&mut self, sys: &mut System<D>) -> Result<(), SchemeError>;
    /// Recompute the state (neighbours, ρ, h, P, c) without forces, as after a
    /// predictor-corrector's final update.
    fn refresh(&mut self, sys: &mut System<D>) {
        smoothing::solve_density_and_h(sys);
        // the next step starts from the halo's state (its entropy proxies enter the
        // compatible energy update): as its owners solved it
        smoothing::refresh_halo_after_solve(sys, true);
        sys.update_eos();
    }
    /// The longest step this scheme's own state allows, over the owned particles, on top of
    /// the driver's Courant and force criteria (∞: no limit of its own).
    fn step_limit(&self, _sys: &System<D>) -> f64 {
        f64::INFINITY
    }
    /// Hook after each completed step (switch evolution).
    fn end_step(&mut self, _sys: &mut System<D>, _dt: f64) {}
    /// The dissipation triggers' levels after the latest step, for schemes that have them
    /// (Rosswog's F1–F3): the largest K and the largest shock, noise-1 and noise-2 targets.
    fn trigger_levels(&self) -> Option<rosswog::TriggerLevels> {
        None
    }
    /// Pair accelerations of the latest evaluation, for schemes whose final thermal energy
    /// comes from the compatible update (Frontiere, Raskin & Owen (2017) §3.3; eqs 56–68) rather than from du/dt. The
    /// `crk-rk2` integrator uses them; the others integrate du/dt.
    fn pair_work(&self) -> Option<&compatible::PairWork<D>> {
        None
    }
    /// Whether the `crk-rk2` integrator evolves the total energy E_i = m_i(u_i + ½v_i²) and
    /// recovers u from it (Frontiere, Raskin & Owen (2017) eq 80) instead of integrating du/dt.
    fn total_energy(&self) -> bool {
        false
    }
    /// State the scheme carries from one step to the next outside the particles (saved and
    /// restored by `coupling::state`; per-particle state belongs in `extra_scalars`).
    fn carried_state(&self) -> Vec<f64> {
        vec![]
    }
    /// How many kernel supports deep a distributed run's halo must be for this scheme's
    /// owned particles to come out exactly as on one rank (`parallel::halo`): 1 for a scheme
    /// that refreshes the halo between its passes (`parallel::refresh`), else the length of
    /// its longest chain of passes in which each reads what the previous one computed for
    /// the neighbours, counting the working list's cut (it reads the neighbours' h) as one.
    fn halo_depth(&self) -> usize {
        4
    }
    /// Put back what [`Self::carried_state`] returned.
    fn set_carried_state(&mut self, state: &[f64]) -> Result<(), String> {
        if state.is_empty() {
            Ok(())
        } else {
            Err(format!(
                "{}: carries no state, got {} values",
                self.name(),
                state.len()
            ))
        }
    }
}

/// Every scheme preset (`scheme.name`) with what it is, for `--help` and the case reference.
/// Each preset's kernel, η, integrator and Courant factor come from [`SchemeConfig`] itself
/// (`preferred_kernel`, `preferred_integrator`); a unit test checks each name parses.
pub const PRESETS: [(&str, &str); 14] = [
    ("standard", "traditional grad-h SPH, Monaghan-Gingold viscosity (alpha, beta) with the Balsara switch, optional Price conductivity; density summation or continuity (liquids; delta-SPH), laminar viscosity"),
    ("rpsph", "relative-pressure SPH (Abel 2011): the standard passes with the pressure differences P_b - P_a in the force; gradient = symmetric (default) | own-h, energy = entropy (default) | eq18, shock_switch"),
    ("rosswog-f1", "Rosswog 2015 F1: integral-approximation gradients, volume element X = P^k (k = 0.05), triggered dissipation (shock and noise triggers)"),
    ("rosswog-f2", "as F1 with kernel gradients and grad-h terms"),
    ("rosswog-f3", "as F1 with X = m"),
    ("rosswog-f4", "kernel gradients, X = m, constant dissipation K = 1: 'standard SPH' of the paper"),
    ("rosswog-sr-f1", "special-relativistic F1 (Rosswog 2015 Sec. 6, c = 1): canonical momentum and energy per baryon, primitive recovery, relativistic signal speeds; states given as rest-frame density, pressure and velocity; ideal gas, ssp-rk3, CLI only"),
    ("rosswog-sr-f2", "special-relativistic F2 (kernel gradients, grad-h, X = P^k)"),
    ("rosswog-sr-f3", "special-relativistic F3 (IA gradients, X = baryon number)"),
    ("rosswog-sr-f4", "special-relativistic F4 (kernel gradients, X = baryon number, constant K = 1)"),
    ("crksph", "CRKSPH (Frontiere, Raskin & Owen 2017): linear reproducing kernels, compatible energy, limited viscosity"),
    ("compsph", "compatibly differenced SPH (the CRKSPH paper's App. E): energy conserved to round-off"),
    ("compsph-cullen", "compsph with the Cullen-Dehnen viscosity switch (App. F)"),
    ("psph", "pressure-energy SPH (Hopkins 2015, after Saitoh & Makino) with Cullen-Dehnen viscosity (App. G); ideal gas only"),
];

/// `[scheme]` table of a case file.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
#[serde(tag = "name", rename_all = "kebab-case", deny_unknown_fields)]
pub enum SchemeConfig {
    /// Traditional grad-h SPH with Monaghan–Gingold viscosity (see [`standard`]).
    Standard(standard::StandardParams),
    /// Relative-pressure SPH (Abel 2011), see [`rpsph`].
    Rpsph(rpsph::RpsphParams),
    /// Rosswog (2015) formulations, see [`rosswog`]: the paper's formulations F1–F4 as presets; any key
    /// given overrides the preset.
    #[serde(rename = "rosswog-f1")]
    RosswogF1(rosswog::RosswogOverrides),
    #[serde(rename = "rosswog-f2")]
    RosswogF2(rosswog::RosswogOverrides),
    #[serde(rename = "rosswog-f3")]
    RosswogF3(rosswog::RosswogOverrides),
    #[serde(rename = "rosswog-f4")]
    RosswogF4(rosswog::RosswogOverrides),
    /// The special-relativistic forms of F1–F4 (Rosswog (2015) Sec. 6), see [`rosswog::sr`].
    #[serde(rename = "rosswog-sr-f1")]
    RosswogSrF1(rosswog::RosswogOverrides),
    #[serde(rename = "rosswog-sr-f2")]
    RosswogSrF2(rosswog::RosswogOverrides),
    #[serde(rename = "rosswog-sr-f3")]
    RosswogSrF3(rosswog::RosswogOverrides),
    #[serde(rename = "rosswog-sr-f4")]
    RosswogSrF4(rosswog::RosswogOverrides),
    /// CRKSPH (Frontiere, Raskin & Owen 2017), see [`crksph`].
    Crksph(crksph::CrksphParams),
    /// Compatible SPH (the CRKSPH paper's App E), see [`compsph`].
    Compsph(compsph::CompsphParams),
    /// compSPH with the Cullen–Dehnen switch (App F), see [`cullen`].
    CompsphCullen(compsph::CompsphParams),
    /// Pressure–energy SPH with Cullen–Dehnen viscosity (App G), see [`psph`].
    Psph(psph::PsphParams),
}

impl SchemeConfig {
    pub fn validate(&self) -> Result<(), String> {
        match self {
            SchemeConfig::Standard(p) => p.validate(),
            SchemeConfig::Rpsph(p) => p.validate(),
            SchemeConfig::Crksph(p) => p.validate(),
            SchemeConfig::Compsph(p) | SchemeConfig::CompsphCullen(p) => p.validate(),
            SchemeConfig::Psph(p) => p.validate(),
            _ => {
                if let Some((preset, o)) = self.rosswog_sr() {
                    return rosswog::sr::validate_overrides(preset, &o);
                }
                let (preset, o) = self.rosswog().expect("rosswog variant");
                o.validate(preset)
            }
        }
    }
    /// The scheme this configuration names, in dimension D (compiled in this crate once per
    /// dimension: `crate::monomorphic`).
    pub fn build<const D: usize>(&self) -> Box<dyn Scheme<D>> {
        crate::monomorphic::scheme(self)
    }

    /// [`Self::build`]'s work, generic over D.
    pub(crate) fn build_generic<const D: usize>(&self) -> Box<dyn Scheme<D>> {
        match *self {
            SchemeConfig::Standard(p) => Box::new(standard::StandardSph::new(p)),
            SchemeConfig::Rpsph(p) => Box::new(rpsph::build(p)),
            SchemeConfig::Crksph(p) => Box::new(crksph::Crksph::<D>::new(p)),
            SchemeConfig::Compsph(p) => Box::new(compsph::Compsph::<D>::new(p, false)),
            SchemeConfig::CompsphCullen(p) => Box::new(compsph::Compsph::<D>::new(p, true)),
            SchemeConfig::Psph(p) => Box::new(psph::Psph::new(p)),
            _ => {
                if let Some((preset, o)) = self.rosswog_sr() {
                    return Box::new(rosswog::sr::RosswogSr::new(preset, o.resolve(preset)));
                }
                let (preset, o) = self.rosswog().expect("rosswog variant");
                Box::new(rosswog::Rosswog::new(preset, o.resolve(preset)))
            }
        }
    }

    /// Whether the scheme takes its density (or volume) from a kernel sum at the smoothing
    /// length of the h–ρ relation h = η V^{1/D} — every scheme but standard SPH and rpSPH with
    /// continuity density. Their initial conditions must give that sum the density they ask
    /// for (see `case::ics::lattice_density_factor`).
    pub fn sums_density(&self) -> bool {
        !matches!(
            self,
            SchemeConfig::Standard(standard::StandardParams {
                density: standard::DensityMode::Continuity,
                ..
            })
        )
    }

    /// Why this scheme cannot run a case with `[[port]]`s, naming the setting that can.
    /// Measured on models/drain2d.toml (a tank draining through a bottom port, Tait liquid):
    /// rosswog-f1, f2 and f3 stop with a collapsed time step at t = 0.25, 0.095 and 0.47 s,
    /// and all three finish with `triggers = false` (K = 1), as F4 (constant K) does with the
    /// same Wendland kernel: the triggers let K fall in the liquid next to the buffer. CRKSPH
    /// ends with a non-finite density at t = 0.40 s with its viscosity limiter on linear
    /// reproducing kernels, and finishes with `limiter = false` or `order = "zeroth"`.
    pub fn port_refusal(&self) -> Option<String> {
        if let SchemeConfig::Crksph(p) = self {
            if p.limiter && p.order == crksph::OrderName::Linear {
                return Some("scheme.limiter: crksph with its viscosity limiter on linear reproducing kernels is unstable next to a [[port]]'s buffer (a tank draining through a port reached a non-finite density at t = 0.40 s); set scheme.limiter = false or scheme.order = \"zeroth\", or use standard, compsph or rosswog-f4".into());
            }
        }
        if let Some((preset, o)) = self.rosswog() {
            if o.resolve(preset).triggers {
                let name = match preset {
                    rosswog::Preset::F1 => "rosswog-f1",
                    rosswog::Preset::F2 => "rosswog-f2",
                    rosswog::Preset::F3 => "rosswog-f3",
                    rosswog::Preset::F4 => "rosswog-f4",
                };
                return Some(format!("scheme.triggers: {name} with triggered dissipation is unstable next to a [[port]]'s buffer (a tank draining through a port lost its time step at t = 0.1-0.5 s); set scheme.triggers = false (constant K), or use rosswog-f4, standard or compsph"));
            }
        }
        None
    }

    /// One of the CRKSPH paper's schemes (CRKSPH, compSPH, compSPH+Cullen, PSPH).
    fn crksph_paper(&self) -> bool {
        matches!(
            self,
            SchemeConfig::Crksph(_)
                | SchemeConfig::Compsph(_)
                | SchemeConfig::CompsphCullen(_)
                | SchemeConfig::Psph(_)
        )
    }

    pub fn rosswog(&self) -> Option<(rosswog::Preset, rosswog::RosswogOverrides)> {
        use rosswog::Preset;
        match *self {
            SchemeConfig::RosswogF1(o) => Some((Preset::F1, o)),
            SchemeConfig::RosswogF2(o) => Some((Preset::F2, o)),
            SchemeConfig::RosswogF3(o) => Some((Preset::F3, o)),
            SchemeConfig::RosswogF4(o) => Some((Preset::F4, o)),
            _ => None,
        }
    }

    /// One of the special-relativistic presets `rosswog-sr-f1` … `rosswog-sr-f4`.
    pub fn rosswog_sr(&self) -> Option<(rosswog::Preset, rosswog::RosswogOverrides)> {
        use rosswog::Preset;
        match *self {
            SchemeConfig::RosswogSrF1(o) => Some((Preset::F1, o)),
            SchemeConfig::RosswogSrF2(o) => Some((Preset::F2, o)),
            SchemeConfig::RosswogSrF3(o) => Some((Preset::F3, o)),
            SchemeConfig::RosswogSrF4(o) => Some((Preset::F4, o)),
            _ => None,
        }
    }

    /// Whether the scheme is special-relativistic (c = 1; a CLI capability only).
    pub fn relativistic(&self) -> bool {
        self.rosswog_sr().is_some()
    }

    /// Kernel and η a scheme runs with when the case has no `[kernel]` table.
    pub fn preferred_kernel(&self) -> (crate::kernel::KernelName, Option<f64>) {
        use crate::kernel::KernelName;
        // Frontiere, Raskin & Owen (2017) Table D.1, η = η_max·n_h/2: W7 with n_h = 1 → η = 2.
        match self {
            SchemeConfig::Crksph(_) => return (KernelName::SepticSpline, Some(2.0)),
            // W5 (our M6, native support 3) with n_h = 4/3
            SchemeConfig::Compsph(_) | SchemeConfig::CompsphCullen(_) => {
                return (KernelName::QuinticSpline, Some(2.0))
            }
            // the PSPH quintic (native support 1) with n_h = 4
            SchemeConfig::Psph(_) => return (KernelName::PsphQuintic, Some(2.0)),
            // Decision (Abel 2011 runs rpSPH with 30 to 100 neighbours: 30 in the lattice and
            // shear tests, 35 Mach 100, 80 Sod and Sedov, 100 KH, and says it is stable "once
            // N_ngb is large enough to keep force noise minimal"): the cubic spline at 30
            // neighbours, η = √(30/4π) = 1.545 in 2D. Measured on the McNally KH at 64²: with
            // standard SPH's 18 (η = 1.2) the pressure noise grew to ±20 % by t = 1 and the
            // run diverged at t = 1.85 (energy ×5); at η = 1.545, 2.0 and 2.82 it runs and the
            // mode grows at 1.04, 1.02 and 1.05 times the linear rate.
            SchemeConfig::Rpsph(_) => return (KernelName::CubicSpline, Some(1.545)),
            _ => {}
        }
        match self.rosswog().or(self.rosswog_sr()) {
            Some((preset, _)) => {
                let (k, eta) = preset.kernel();
                (k, Some(eta))
            }
            None => (KernelName::CubicSpline, None),
        }
    }

    /// Integrator and Courant factor a scheme runs with when `[time]` does not say.
    pub fn preferred_integrator(&self) -> (crate::integrate::IntegratorKind, f64) {
        // Frontiere, Raskin & Owen (2017) §4: the modified RK2 with CFL 0.25 for every scheme of that paper.
        if self.crksph_paper() {
            return (crate::integrate::IntegratorKind::CrkRk2, 0.25);
        }
        match self.rosswog().or(self.rosswog_sr()) {
            // Rosswog (2015) Sec. 6.5: SSP-RK3 with C = 0.5.
            Some(_) => (crate::integrate::IntegratorKind::SspRk3, 0.5),
            None => (crate::integrate::IntegratorKind::Leapfrog, 0.3),
        }
    }
}

impl Default for SchemeConfig {
    fn default() -> Self {
        SchemeConfig::Standard(standard::StandardParams::default())
    }
}

#[cfg(test)]
mod preset_tests {
    /// Every preset `--help` lists is a scheme a case can name.
    #[test]
    fn every_listed_preset_parses() {
        for (name, _) in super::PRESETS {
            let c: Result<super::SchemeConfig, _> = toml::from_str(&format!("name = {name:?}"));
            assert!(c.is_ok(), "{name}: {:?}", c.err());
        }
    }
}
