//! The instance's side of live coupling over zenoh (`bridge`): open the session at the end of
//! initialisation, overlay live inputs on the master's at each communication point, publish
//! the outputs after it. Without the `zenoh` feature only "off" is accepted.

use crate::instance::{CallResult, Instance, Status};
#[cfg(feature = "zenoh")]
use crate::table::{Causality, Kind};

impl Instance {
    /// Open the bridge when `zenoh.mode` asks for it.
    pub(crate) fn open_live(&mut self) -> CallResult<()> {
        if !self.params.zenoh.enabled() {
            return Ok(());
        }
        #[cfg(not(feature = "zenoh"))]
        {
            Err((
                Status::Error,
                "zenoh.mode: this FMU was built without zenoh (cargo feature `zenoh`); set zenoh.mode = off".into(),
            ))
        }
        #[cfg(feature = "zenoh")]
        {
            use crate::bridge::{Bridge, InputSpec};
            let vars = &self.table.variables;
            let inputs = vars
                .iter()
                .enumerate()
                .filter(|(_, v)| v.causality == Causality::Input)
                .map(|(index, v)| InputSpec {
                    index,
                    name: v.name.clone(),
                    size: v.size,
                })
                .collect();
            let outputs = vars
                .iter()
                .enumerate()
                .filter(|(_, v)| v.causality == Causality::Output)
                .map(|(i, v)| (i, v.name.clone()))
                .collect();
            let s = &self.params.zenoh;
            let prefix = s.prefix_for(&self.name);
            let b = Bridge::open(s, &prefix, inputs, outputs, self.table.dimension)
                .map_err(|e| (Status::Error, e))?;
            self.log(
                Status::Ok,
                "logEvents",
                &format!(
                    "zenoh: {} session {}, outputs on {prefix}/out/*, inputs on {prefix}/in/*, particles from {prefix}/snapshot",
                    s.mode,
                    b.session().zid()
                ),
            );
            self.bridge = Some(b);
            Ok(())
        }
    }

    pub(crate) fn close_live(&mut self) {
        #[cfg(feature = "zenoh")]
        {
            self.bridge = None;
        }
    }

    /// Hand the inputs for the coming step to the solver: the master's, overridden by fresh
    /// live values (the rule in `bridge`). The master's values are kept as they were.
    pub(crate) fn apply_inputs_live(&mut self) -> CallResult<()> {
        #[cfg(feature = "zenoh")]
        if let Some(b) = self.bridge.as_mut() {
            let x = b.exchange();
            if self.distributed() {
                // every rank must step with the same inputs, and only rank 0 hears zenoh:
                // a node on several ranks takes its inputs through `<prefix>/set`
                if !x.apply.is_empty() {
                    self.log(
                        Status::Warning,
                        "logStatusWarning",
                        "zenoh input ignored: a node on several ranks takes inputs through <prefix>/set only",
                    );
                }
                return self.apply_inputs();
            }
            for w in &x.warnings {
                self.log(Status::Warning, "logStatusWarning", w);
            }
            for n in &x.notes {
                self.log(Status::Ok, "logEvents", n);
            }
            if let Some(e) = x.error {
                return Err((Status::Error, e));
            }
            let master = self.inputs.clone();
            // the master's values come back whatever happens
            let r = self.overlay_live(x.apply).and_then(|_| self.apply_inputs());
            self.inputs = master;
            return r;
        }
        self.apply_inputs()
    }

    /// Put live values over the master's inputs, each checked like a master's set (ranges,
    /// dimension); a refused value leaves the input as it was (the previous live value, else
    /// the master's).
    #[cfg(feature = "zenoh")]
    fn overlay_live(&mut self, apply: Vec<crate::bridge::LiveValue>) -> CallResult<()> {
        for lv in apply {
            let r = self.set_f64(lv.index, 0, &lv.values);
            if let Err((_, e)) = &r {
                let msg = format!("zenoh input refused, nothing changed: {e}");
                self.log(Status::Warning, "logStatusWarning", &msg);
                if let Some(prev) = self.bridge.as_ref().and_then(|b| b.accepted(lv.index)) {
                    self.set_f64(lv.index, 0, &prev)?;
                }
            }
            if let Some(b) = self.bridge.as_mut() {
                b.settle(&lv, r.is_ok());
            }
        }
        Ok(())
    }

    /// Publish every output and keep the particles for snapshot queries (after
    /// initialisation and after each step). A failed put is a logged warning.
    pub(crate) fn publish_live(&mut self) {
        #[cfg(feature = "zenoh")]
        {
            use ciborium::Value;
            // on a node under mpirun only rank 0 publishes, but every rank reads the outputs
            // (the reads are collectives: they sum or gather over the ranks)
            if self.bridge.is_none() && !self.distributed() {
                return;
            }
            let mut values = std::collections::HashMap::new();
            for i in 0..self.table.variables.len() {
                let v = &self.table.variables[i];
                if v.causality != Causality::Output {
                    continue;
                }
                let value = match v.kind {
                    Kind::Int64 => self.get_i64(i).map(|n| Value::Integer(n.into())),
                    _ => self.get_f64(i).map(|x| crate::bridge::codec::numbers(&x)),
                };
                if let Ok(value) = value {
                    values.insert(i, value);
                }
            }
            let particles = self
                .coupling
                .get()
                .map(|c| c.particles(1))
                .unwrap_or_default();
            let t = self.time();
            let Some(bridge) = self.bridge.as_ref() else {
                return;
            };
            let sent = bridge.publish(t, |i| values.remove(&i), particles);
            if let Err(e) = sent {
                self.log(Status::Warning, "logStatusWarning", &e);
            }
        }
    }

    /// The zenoh session of the bridge (for the node's control queryables).
    #[cfg(feature = "zenoh")]
    pub fn live_session(&self) -> Option<zenoh::Session> {
        self.bridge.as_ref().map(|b| b.session().clone())
    }

    /// The key prefix in force.
    pub fn live_prefix(&self) -> String {
        self.params.zenoh.prefix_for(&self.name)
    }
}
