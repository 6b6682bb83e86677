//! The `zenoh.*` parameters of an instance: whether and how it joins a zenoh network for live
//! coupling (see `bridge`). Plain data, compiled with or without the `zenoh` feature, so an
//! FMU built without zenoh has the same variables and refuses `zenoh.mode` other than "off"
//! with a clear message.

use crate::table::Kind;

/// What happens to a live input when its zenoh publisher has gone quiet for longer than
/// `zenoh.staleness` (wall-clock seconds).
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum OnStale {
    /// Keep using the last value received (a warning is logged once).
    Hold,
    /// Fall back to the master's value (a warning is logged once).
    Master,
    /// doStep returns an error (nothing is stepped) until a fresh value arrives.
    Error,
}

#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum ZenohParam {
    Mode,
    Connect,
    Listen,
    Config,
    Prefix,
    Staleness,
    OnStale,
    Remote,
}

#[derive(Debug, Clone, PartialEq)]
pub struct ZenohSettings {
    /// "off" (no bridge), "peer" or "client".
    pub mode: String,
    /// Endpoints to connect to, comma separated (e.g. "tcp/127.0.0.1:7447").
    pub connect: String,
    /// Endpoints to listen on, comma separated.
    pub listen: String,
    /// A zenoh JSON5 configuration file; the other parameters are applied on top of it.
    pub config: String,
    /// Key prefix; empty = "sphfmu/<instance name>".
    pub prefix: String,
    /// Seconds (wall clock) after which a live input counts as stale; 0 = never.
    pub staleness: f64,
    pub on_stale: OnStale,
    /// Key prefix of a running `sphfmu serve` node that this instance forwards its steps,
    /// values and states to (`bridge::proxy`); empty = solve in this process.
    pub remote: String,
}

impl Default for ZenohSettings {
    fn default() -> ZenohSettings {
        ZenohSettings {
            mode: "off".into(),
            connect: String::new(),
            listen: String::new(),
            config: String::new(),
            prefix: String::new(),
            staleness: 1.0,
            on_stale: OnStale::Hold,
            remote: String::new(),
        }
    }
}

/// The parameter rows of the variable table: (name, kind, start, description, which).
pub fn parameter_rows() -> Vec<(&'static str, Kind, &'static str, &'static str, ZenohParam)> {
    use ZenohParam::*;
    vec![
        ("zenoh.mode", Kind::String, "off",
         "Live coupling over zenoh: off, peer (no router needed; multicast scouting off) or client (through a router)", Mode),
        ("zenoh.connect", Kind::String, "",
         "zenoh endpoints to connect to, comma separated (e.g. tcp/127.0.0.1:7447)", Connect),
        ("zenoh.listen", Kind::String, "",
         "zenoh endpoints to listen on, comma separated (e.g. tcp/127.0.0.1:7447)", Listen),
        ("zenoh.config", Kind::String, "",
         "A zenoh JSON5 configuration file (absolute path); zenoh.mode, connect and listen override it", Config),
        ("zenoh.prefix", Kind::String, "",
         "Key prefix: outputs on <prefix>/out/<name>, inputs on <prefix>/in/<name>, particles from <prefix>/snapshot; empty = sphfmu/<instance name>", Prefix),
        ("zenoh.staleness", Kind::Float64, "1.0",
         "Wall-clock seconds after which a live input counts as stale, ≥ 0; 0 = never", Staleness),
        ("zenoh.on_stale", Kind::String, "hold",
         "A stale live input: hold (keep the last value), master (use the master's value again) or error (doStep fails)", OnStale),
        ("remote", Kind::String, "",
         "Key prefix of a running `sphfmu serve` node (reached through zenoh.connect, zenoh.listen or zenoh.config): doStep, values and FMU states are forwarded to it and the solver runs there; empty = solve in this process", Remote),
    ]
}

fn valid_key_prefix(name: &str, p: &str) -> Result<(), String> {
    let ok = !p.is_empty()
        && !p.starts_with('/')
        && !p.ends_with('/')
        && !p.contains("//")
        && !p.contains(['*', '$', '#', '?', ' '])
        && !p.starts_with('@');
    if ok {
        Ok(())
    } else {
        Err(format!(
            "{name}: must be a zenoh key without wildcards: '/'-separated non-empty chunks, none of * $ # ? or spaces, not starting with @ or /, got {p:?}"
        ))
    }
}

impl ZenohSettings {
    pub fn enabled(&self) -> bool {
        self.mode != "off"
    }

    /// The prefix in force for an instance called `instance`.
    pub fn prefix_for(&self, instance: &str) -> String {
        if self.prefix.is_empty() {
            let clean = crate::plain_name(instance);
            format!("sphfmu/{}", if clean.is_empty() { "fmu" } else { &clean })
        } else {
            self.prefix.clone()
        }
    }

    /// Endpoint list of a comma-separated parameter.
    pub fn endpoints(list: &str) -> Vec<String> {
        list.split(',')
            .map(|s| s.trim().to_string())
            .filter(|s| !s.is_empty())
            .collect()
    }

    /// Set a text parameter (checked first: a rejected value changes nothing).
    pub fn set_text(&mut self, which: ZenohParam, value: &str) -> Result<(), String> {
        let v = value.trim();
        match which {
            ZenohParam::Mode => {
                if !["off", "peer", "client"].contains(&v) {
                    return Err(format!(
                        "zenoh.mode: must be off, peer or client, got {value:?}"
                    ));
                }
                self.mode = v.into();
            }
            ZenohParam::Connect | ZenohParam::Listen => {
                for e in Self::endpoints(v) {
                    // <protocol>/<address>, e.g. tcp/127.0.0.1:7447 (zenoh's locator form)
                    let good = e
                        .split_once('/')
                        .is_some_and(|(p, a)| !p.is_empty() && !a.is_empty());
                    if !good {
                        let name = if which == ZenohParam::Connect {
                            "zenoh.connect"
                        } else {
                            "zenoh.listen"
                        };
                        return Err(format!(
                            "{name}: each endpoint must read <protocol>/<address>, e.g. tcp/127.0.0.1:7447, got {e:?}"
                        ));
                    }
                }
                match which {
                    ZenohParam::Connect => self.connect = v.into(),
                    _ => self.listen = v.into(),
                }
            }
            ZenohParam::Config => self.config = v.into(),
            ZenohParam::Prefix => {
                if !v.is_empty() {
                    valid_key_prefix("zenoh.prefix", v)?;
                }
                self.prefix = v.into();
            }
            ZenohParam::OnStale => {
                self.on_stale = match v {
                    "hold" => OnStale::Hold,
                    "master" => OnStale::Master,
                    "error" => OnStale::Error,
                    _ => {
                        return Err(format!(
                            "zenoh.on_stale: must be hold, master or error, got {value:?}"
                        ))
                    }
                }
            }
            ZenohParam::Remote => {
                if !v.is_empty() {
                    valid_key_prefix("remote", v)?;
                }
                self.remote = v.into();
            }
            ZenohParam::Staleness => return Err("zenoh.staleness: is a Float64".into()),
        }
        Ok(())
    }

    pub fn text(&self, which: ZenohParam) -> String {
        match which {
            ZenohParam::Mode => self.mode.clone(),
            ZenohParam::Connect => self.connect.clone(),
            ZenohParam::Listen => self.listen.clone(),
            ZenohParam::Config => self.config.clone(),
            ZenohParam::Prefix => self.prefix.clone(),
            ZenohParam::Staleness => self.staleness.to_string(),
            ZenohParam::Remote => self.remote.clone(),
            ZenohParam::OnStale => match self.on_stale {
                OnStale::Hold => "hold",
                OnStale::Master => "master",
                OnStale::Error => "error",
            }
            .into(),
        }
    }

    pub fn set_staleness(&mut self, s: f64) -> Result<(), String> {
        if !(s.is_finite() && s >= 0.0) {
            return Err(format!(
                "zenoh.staleness: must be a finite number of seconds ≥ 0 (0 = never stale), got {s}"
            ));
        }
        self.staleness = s;
        Ok(())
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn bad_values_name_the_parameter_and_change_nothing() {
        let mut s = ZenohSettings::default();
        let before = s.clone();
        for (which, value, needle) in [
            (ZenohParam::Mode, "router", "zenoh.mode"),
            (ZenohParam::Connect, "127.0.0.1:7447", "zenoh.connect"),
            (ZenohParam::Listen, "tcp/", "zenoh.listen"),
            (ZenohParam::Prefix, "a/*/b", "zenoh.prefix"),
            (ZenohParam::Prefix, "/a", "zenoh.prefix"),
            (ZenohParam::OnStale, "ignore", "zenoh.on_stale"),
        ] {
            let e = s.set_text(which, value).unwrap_err();
            assert!(e.starts_with(needle), "{e}");
        }
        assert!(s.set_staleness(-1.0).unwrap_err().contains("≥ 0"));
        assert!(s.set_staleness(f64::NAN).is_err());
        assert_eq!(s, before);
        s.set_text(ZenohParam::Connect, "tcp/127.0.0.1:1, tcp/[::1]:2")
            .unwrap();
        assert_eq!(
            ZenohSettings::endpoints(&s.connect),
            ["tcp/127.0.0.1:1", "tcp/[::1]:2"]
        );
        assert_eq!(s.prefix_for("tank 1"), "sphfmu/tank_1");
    }
}
