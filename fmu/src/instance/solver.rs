//! The instance's solver and the outputs read from it since it last changed. A master (or the
//! zenoh bridge) reads every output after a step; probes, patches, markers and the diagnostics
//! each sweep the particles, and one sweep answers all the outputs of its kind. Every way to
//! change the solver goes through `get_mut` or `put`, which drop what was read, so a getter
//! never answers from before a change.

use sphfmu::coupling::{BodyLoads, Coupling, PatchValue, PortValue, ProbeValue};
use sphfmu::sim::Diagnostics;

/// Outputs of one solver state, each kind computed on its first read.
#[derive(Default)]
pub(crate) struct OutputCache {
    loads: Option<Vec<BodyLoads>>,
    probes: Option<Vec<ProbeValue>>,
    markers: Option<Vec<f64>>,
    patches: Option<Vec<PatchValue>>,
    ports: Option<Vec<PortValue>>,
    diagnostics: Option<Diagnostics>,
}

#[derive(Default)]
pub(crate) struct Solver {
    coupling: Option<Coupling>,
    outputs: OutputCache,
}

impl Solver {
    pub(crate) fn get(&self) -> Option<&Coupling> {
        self.coupling.as_ref()
    }

    /// The solver for a change: what was read from it is dropped.
    pub(crate) fn get_mut(&mut self) -> Option<&mut Coupling> {
        self.outputs = OutputCache::default();
        self.coupling.as_mut()
    }

    /// A new solver, or none (parameters changed, reset).
    pub(crate) fn put(&mut self, coupling: Option<Coupling>) {
        self.outputs = OutputCache::default();
        self.coupling = coupling;
    }

    pub(crate) fn is_some(&self) -> bool {
        self.coupling.is_some()
    }

    /// The outputs of the current state (None without a solver).
    pub(crate) fn outputs(&mut self) -> Option<Outputs<'_>> {
        let c = self.coupling.as_ref()?;
        Some(Outputs {
            c,
            cache: &mut self.outputs,
        })
    }
}

/// Reads of one solver state through its cache.
pub(crate) struct Outputs<'a> {
    c: &'a Coupling,
    cache: &'a mut OutputCache,
}

impl Outputs<'_> {
    pub(crate) fn loads(&mut self) -> &[BodyLoads] {
        self.cache.loads.get_or_insert_with(|| self.c.loads())
    }
    pub(crate) fn probes(&mut self) -> &[ProbeValue] {
        self.cache.probes.get_or_insert_with(|| self.c.probes())
    }
    pub(crate) fn markers(&mut self) -> &[f64] {
        self.cache.markers.get_or_insert_with(|| self.c.markers())
    }
    pub(crate) fn patches(&mut self) -> &[PatchValue] {
        self.cache.patches.get_or_insert_with(|| self.c.patches())
    }
    pub(crate) fn ports(&mut self) -> &[PortValue] {
        self.cache.ports.get_or_insert_with(|| self.c.ports())
    }
    pub(crate) fn diagnostics(&mut self) -> Diagnostics {
        *self
            .cache
            .diagnostics
            .get_or_insert_with(|| self.c.diagnostics())
    }
}
