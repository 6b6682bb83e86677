//! The instance as a proxy of a remote `sphfmu serve` node (`remote` parameter; the transport
//! is `bridge::proxy`). The FMI state machine, the argument checks and the inputs stay here,
//! as in a local instance; the node steps, checks the inputs as a whole (all or nothing),
//! answers the outputs and keeps the solver state. Its replies map onto FMI statuses as the
//! local instance's outcomes do: a refused input is an Error that changes nothing, a solver
//! failure moves to Failed, a step cut short by a limit is a Discard; a node that does not
//! answer is an Error that moves to Failed, from which setFMUState (to a node started anew)
//! or reset recovers.

use super::inputs::Snapshot;
use super::{err, CallResult, Instance, Mode, Status};
use crate::table::Causality;

/// The first words of the local instance's messages for a failed solver and for a step cut
/// short by a limit (`Instance::do_step`), by which the node's replies are told apart.
pub(crate) const SOLVER_FAILED: &str = "the solver failed";
pub(crate) const STEP_STOPPED: &str = "stopped at t =";

impl Instance {
    /// Whether this instance forwards to a remote node.
    pub(crate) fn proxied(&self) -> bool {
        !self.params.zenoh.remote.is_empty()
    }

    #[cfg(not(feature = "zenoh"))]
    pub(crate) fn ensure_remote(&mut self) -> CallResult<()> {
        err("remote: this FMU was built without zenoh (cargo feature `zenoh`); leave remote empty")
    }

    /// Reach the node (once): its state back to the end of its initialisation, this
    /// instance's inputs sent, its outputs read and checked against this table.
    #[cfg(feature = "zenoh")]
    pub(crate) fn ensure_remote(&mut self) -> CallResult<()> {
        use crate::bridge::proxy::RemoteNode;
        if self.remote.is_some() {
            return Ok(());
        }
        if !self.params.output_dir.trim().is_empty() {
            return err(
                "output_dir: with remote set, the node writes the snapshots (start it with --set output_dir=...); leave output_dir empty",
            );
        }
        let prefix = self.params.zenoh.remote.clone();
        let mut node =
            RemoteNode::open(&self.params.zenoh, &prefix).map_err(|m| (Status::Error, m))?;
        let refused = |e: crate::bridge::proxy::RemoteError| {
            (Status::Error, format!("remote {prefix:?}: {}", e.message()))
        };
        node.reset().map_err(refused)?;
        node.origin = node.time;
        node.set(self.input_values()).map_err(refused)?;
        node.read_outputs().map_err(refused)?;
        if let Some(v) = self
            .table
            .variables
            .iter()
            .find(|v| v.causality == Causality::Output && node.output(&v.name).is_none())
        {
            return err(format!(
                "remote {prefix:?}: the node serves another case: it has no output {}",
                v.name
            ));
        }
        self.log(
            Status::Ok,
            "logEvents",
            &format!("remote node {prefix:?} ready at its t = {}", node.time),
        );
        self.remote = Some(node);
        Ok(())
    }

    /// Every input's name and current value, as the master set them.
    #[cfg(feature = "zenoh")]
    fn input_values(&mut self) -> Vec<(String, Vec<f64>)> {
        let inputs: Vec<usize> = (0..self.table.variables.len())
            .filter(|&i| self.table.variables[i].causality == Causality::Input)
            .collect();
        inputs
            .into_iter()
            .filter_map(|i| {
                let name = self.table.variables[i].name.clone();
                self.get_f64(i).ok().map(|x| (name, x))
            })
            .collect()
    }

    /// The solver's own time (from the start of the run), local or remote.
    pub(crate) fn solver_time(&self) -> f64 {
        #[cfg(feature = "zenoh")]
        if let Some(node) = &self.remote {
            return node.time - node.origin;
        }
        self.coupling.get().map_or(0.0, |c| c.time())
    }

    /// doStep on the node, its arguments checked already.
    #[cfg(feature = "zenoh")]
    pub(crate) fn do_step_remote(&mut self, h: f64) -> CallResult<()> {
        use crate::bridge::proxy::RemoteError;
        let inputs = self.input_values();
        let node = self.remote.as_mut().expect("opened at initialisation");
        let prefix = node.prefix.clone();
        let outcome = node.set(inputs).and_then(|_| node.step(h));
        match outcome {
            Ok(()) => Ok(()),
            Err(RemoteError::Refused(m)) if m.contains(STEP_STOPPED) => {
                // the node stopped at a limit: its time and outputs are where it stopped
                let _ = node.read_outputs();
                Err((Status::Discard, format!("remote {prefix:?}: {m}")))
            }
            Err(RemoteError::Refused(m)) if m.starts_with(SOLVER_FAILED) => {
                self.mode = Mode::Failed;
                Err((Status::Error, format!("remote {prefix:?}: {m}")))
            }
            // a refused input or argument: nothing changed on the node
            Err(RemoteError::Refused(m)) => Err((Status::Error, format!("remote {prefix:?}: {m}"))),
            Err(gone) => {
                self.mode = Mode::Failed;
                // the next call that needs a node reaches one anew (e.g. setFMUState to a
                // node started again)
                self.remote = None;
                let what = match gone {
                    RemoteError::Ended(m) => format!("the node replied: {m}"),
                    e => format!("the node did not answer ({})", e.message()),
                };
                Err((
                    Status::Error,
                    format!("remote {prefix:?}: {what}; restore a saved FMU state (to a node started anew) or reset"),
                ))
            }
        }
    }

    /// Output `name` as the node last answered it.
    #[cfg(feature = "zenoh")]
    pub(crate) fn remote_output(&mut self, i: usize) -> CallResult<Vec<f64>> {
        self.ensure_remote()?;
        let name = &self.table.variables[i].name;
        let node = self.remote.as_ref().expect("opened above");
        node.output(name).map(|x| x.to_vec()).ok_or_else(|| {
            (
                Status::Error,
                format!("{name}: the remote node gave no value"),
            )
        })
    }

    /// getFMUState of a proxy: the node's state bytes with this instance's inputs.
    #[cfg(feature = "zenoh")]
    pub(crate) fn get_state_remote(&self) -> CallResult<Snapshot> {
        let Some(node) = self.remote.as_ref() else {
            return err(
                "getFMUState: available once initialisation has ended (no solver state yet)",
            );
        };
        let prefix = node.prefix.clone();
        let solver = node.save().map_err(|e| {
            (
                Status::Error,
                format!("getFMUState: remote {prefix:?}: {}", e.message()),
            )
        })?;
        Ok(Snapshot {
            inputs: self.inputs.clone(),
            start_time: self.start_time,
            solver,
        })
    }

    /// setFMUState of a proxy: the node restored to the state's bytes (any node serving the
    /// same case: one started anew resumes the run).
    #[cfg(feature = "zenoh")]
    pub(crate) fn set_state_remote(&mut self, s: &Snapshot) -> CallResult<()> {
        // the node first (it checks the state's inputs as a set would), then this side
        self.ensure_remote()?;
        let node = self.remote.as_mut().expect("opened above");
        let prefix = node.prefix.clone();
        if let Err(e) = node.restore(&s.solver) {
            if e.node_gone() {
                self.remote = None;
            }
            return err(format!("setFMUState: remote {prefix:?}: {}", e.message()));
        }
        self.inputs = s.inputs.clone();
        self.start_time = s.start_time;
        self.mode = Mode::Step;
        Ok(())
    }
}
