//! The force history of every body over a run: `bodies.csv` (t, then F_x, F_y[, F_z] per
//! body) and `loads.png` (one panel per body and component), written next to
//! diagnostics.csv when the case has bodies; and the flow history of every port: `ports.csv`
//! (t, then per port its mean pressure, volume flow into the fluid, and the exact mass in and
//! out since the start) and `ports.png` (volume flow per port). Every column header and axis
//! carries its unit (`crate::units`: a 2D case's force is per metre of depth, N/m). For a
//! scheme with dissipation triggers (Rosswog's F1–F3), `triggers.csv`: the largest K and
//! the largest shock, noise-1 and noise-2 targets after each recorded step (dimensionless).

use crate::io::plot::{profile_png, Panel};
use crate::sim::Simulation;
use std::io::Write;
use std::path::Path;

#[derive(Default)]
pub struct LoadHistory {
    names: Vec<String>,
    dim: usize,
    rows: Vec<(f64, Vec<f64>)>,
    ports: Vec<String>,
    port_rows: Vec<(f64, Vec<f64>)>,
    trigger_rows: Vec<(f64, crate::scheme::rosswog::TriggerLevels)>,
}

/// Columns per port in ports.csv, with their units in dimension `d`.
fn port_columns(d: usize) -> [(&'static str, &'static str); 4] {
    let u = crate::units::units(d);
    [
        ("mean_pressure", "Pa"),
        ("volume_flow", u.volume_flow),
        ("mass_in", u.mass),
        ("mass_out", u.mass),
    ]
}

impl LoadHistory {
    pub fn record<const D: usize>(&mut self, sim: &Simulation<D>) {
        if let Some(l) = sim.scheme.trigger_levels() {
            self.trigger_rows.push((sim.time, l));
        }
        if !sim.sys.ports.is_empty() {
            if self.ports.is_empty() {
                self.ports = sim.sys.ports.iter().map(|p| p.name.clone()).collect();
                self.dim = D;
            }
            let row = (0..sim.sys.ports.len())
                .flat_map(|k| {
                    let v = crate::coupling::sampling::port_value(&sim.sys, k);
                    [v.mean_pressure, v.volume_flow, v.mass_in, v.mass_out]
                })
                .collect();
            self.port_rows.push((sim.time, row));
        }
        if sim.sys.bodies.is_empty() {
            return;
        }
        if self.names.is_empty() {
            self.names = sim.sys.bodies.iter().map(|b| b.name.clone()).collect();
            self.dim = D;
        }
        let f = sim
            .sys
            .bodies
            .iter()
            .flat_map(|b| b.force.iter().copied().collect::<Vec<_>>())
            .collect();
        self.rows.push((sim.time, f));
    }

    /// Write bodies.csv and loads.png (with bodies), ports.csv and ports.png (with ports)
    /// into `dir`.
    fn write_triggers(&self, dir: &Path) -> Result<(), String> {
        if self.trigger_rows.is_empty() {
            return Ok(());
        }
        let path = dir.join("triggers.csv");
        let mut text = String::from(
            "t [s],max K,max K_shock,max K_noise1,max K_noise2,mean K_shock,mean K_noise1,mean K_noise2\n",
        );
        for (t, l) in &self.trigger_rows {
            text += &format!(
                "{t:.9e},{:.6e},{:.6e},{:.6e},{:.6e},{:.6e},{:.6e},{:.6e}\n",
                l.k, l.shock, l.noise1, l.noise2, l.mean_shock, l.mean_noise1, l.mean_noise2
            );
        }
        std::fs::write(&path, text).map_err(|e| format!("{}: {e}", path.display()))
    }

    pub fn write(&self, dir: &Path) -> Result<(), String> {
        self.write_ports(dir)?;
        self.write_triggers(dir)?;
        if self.names.is_empty() {
            return Ok(());
        }
        let axes = ["x", "y", "z"];
        let csv = dir.join("bodies.csv");
        let mut w = std::io::BufWriter::new(
            std::fs::File::create(&csv).map_err(|e| format!("{}: {e}", csv.display()))?,
        );
        let force = crate::units::units(self.dim).force;
        let mut header = vec!["t [s]".to_string()];
        for n in &self.names {
            for a in &axes[..self.dim] {
                header.push(format!("{n}.force_{a} [{force}]"));
            }
        }
        let mut text = header.join(",") + "\n";
        for (t, f) in &self.rows {
            text.push_str(&format!("{t:.9e}"));
            for x in f {
                text.push_str(&format!(",{x:.9e}"));
            }
            text.push('\n');
        }
        w.write_all(text.as_bytes())
            .map_err(|e| format!("{}: {e}", csv.display()))?;
        let series: Vec<(String, Vec<(f64, f64)>)> = self
            .names
            .iter()
            .enumerate()
            .flat_map(|(b, n)| (0..self.dim).map(move |k| (b, k, n)))
            .map(|(b, k, n)| {
                let pts = self
                    .rows
                    .iter()
                    .map(|(t, f)| (*t, f[b * self.dim + k]))
                    .collect();
                (format!("force on {n}, {} component", axes[k]), pts)
            })
            .collect();
        let y = format!("force ({force})");
        let caption = if self.dim == 2 {
            "Body loads (from the run; 2D: per metre of depth)"
        } else {
            "Body loads (from the run)"
        };
        time_series_png(&dir.join("loads.png"), caption, &y, &series)
    }

    fn write_ports(&self, dir: &Path) -> Result<(), String> {
        if self.ports.is_empty() {
            return Ok(());
        }
        let csv = dir.join("ports.csv");
        let columns = port_columns(self.dim);
        let mut text = std::iter::once("t [s]".to_string())
            .chain(
                self.ports
                    .iter()
                    .flat_map(|n| columns.map(|(c, u)| format!("{n}.{c} [{u}]"))),
            )
            .collect::<Vec<_>>()
            .join(",")
            + "\n";
        for (t, row) in &self.port_rows {
            text.push_str(&format!("{t:.9e}"));
            row.iter().for_each(|x| text.push_str(&format!(",{x:.9e}")));
            text.push('\n');
        }
        std::fs::write(&csv, text).map_err(|e| format!("{}: {e}", csv.display()))?;
        let series: Vec<(String, Vec<(f64, f64)>)> = (0..self.ports.len())
            .map(|k| {
                let pts = self
                    .port_rows
                    .iter()
                    .map(|(t, r)| (*t, r[4 * k + 1]))
                    .collect();
                (
                    format!("volume flow into the fluid at port {}", self.ports[k]),
                    pts,
                )
            })
            .collect();
        let y = format!("volume flow ({})", columns[1].1);
        time_series_png(
            &dir.join("ports.png"),
            "Port flows (from the run)",
            &y,
            &series,
        )
    }
}

/// One panel per (title, points against t) series.
fn time_series_png(
    path: &Path,
    title: &str,
    y_desc: &str,
    series: &[(String, Vec<(f64, f64)>)],
) -> Result<(), String> {
    let panels: Vec<Panel<'_>> = series
        .iter()
        .map(|(title, pts)| Panel {
            title,
            particles: &[],
            exact: pts,
            x_desc: "t (s)",
            y_desc,
            line_label: "sphfmu",
        })
        .collect();
    profile_png(path, title, &panels)
}
