//! The `.fmu` archive: modelDescription.xml, the binary under `binaries/<platform>/`, the
//! case files under `resources/`, and `documentation/` listing every variable.

use super::xml::{self, MODEL_IDENTIFIER};
use crate::table::{Causality, Start, Table};
use sphfmu::case::Case;
use std::io::Write;
use std::path::Path;

/// `documentation/index.html`: every variable with its type, causality, unit, start and meaning.
pub fn documentation(table: &Table, case: &Case, fmi: &str) -> String {
    let mut rows = String::new();
    for v in &table.variables {
        let start = match &v.start {
            Start::None => String::new(),
            Start::Float(x) => x
                .iter()
                .map(|x| format!("{x}"))
                .collect::<Vec<_>>()
                .join(" "),
            Start::Int(i) => i.to_string(),
            Start::Text(t) => t.clone(),
        };
        let shape = if v.size > 1 {
            if fmi == "3.0" {
                format!("[{}]", v.size)
            } else {
                format!("[1..{}] (scalars)", v.size)
            }
        } else {
            String::new()
        };
        rows.push_str(&format!(
            "<tr><td><code>{}{}</code></td><td>{:?}</td><td>{}</td><td>{}</td><td>{}</td><td>{}</td></tr>\n",
            xml::escape(&v.name),
            shape,
            v.kind,
            match v.causality {
                Causality::Independent => "independent",
                Causality::Parameter => "parameter",
                Causality::Input => "input",
                Causality::Output => "output",
            },
            v.unit.unwrap_or(""),
            xml::escape(&start),
            xml::escape(&v.description)
        ));
    }
    format!(
        "<!DOCTYPE html>\n<html><head><meta charset=\"utf-8\"><title>sphfmu: {name}</title></head><body>\n\
<h1>sphfmu — {name} (FMI {fmi} co-simulation)</h1>\n<p>{desc}</p>\n\
<p>Smoothed-particle hydrodynamics as a co-simulation FMU. Inputs are held over a communication \
step (an externally driven body moves on at the velocity it was given); the FMU sub-steps with \
its own stable time step and lands on the step end exactly. FMU state get/set and serialization \
restore the solver bit for bit. Case files of the repository's <code>models/</code> are under \
<code>resources/</code>; the <code>case</code> parameter selects one with the same bodies, probes \
and markers (or an absolute path).</p>\n\
<table border=\"1\" cellpadding=\"3\"><tr><th>Variable</th><th>Type</th><th>Causality</th><th>Unit</th><th>Start</th><th>Meaning</th></tr>\n{rows}</table>\n</body></html>\n",
        name = xml::escape(&case.case.name),
        desc = xml::escape(&case.case.description),
    )
}

/// Write one `.fmu` (a zip with forward-slash paths and no top folder).
pub fn write_fmu(
    path: &Path,
    md: &str,
    platform: &str,
    lib: &[u8],
    resources: &[(String, Vec<u8>)],
    docs: &[(&str, String)],
) -> Result<(), String> {
    let file = std::fs::File::create(path).map_err(|e| format!("{}: {e}", path.display()))?;
    let mut z = zip::ZipWriter::new(file);
    let opts = zip::write::SimpleFileOptions::default()
        .compression_method(zip::CompressionMethod::Deflated)
        .unix_permissions(0o644);
    let mut put = |name: &str, data: &[u8], mode: u32| -> Result<(), String> {
        z.start_file(name, opts.unix_permissions(mode))
            .map_err(|e| e.to_string())?;
        z.write_all(data).map_err(|e| e.to_string())
    };
    put("modelDescription.xml", md.as_bytes(), 0o644)?;
    put(
        &format!("binaries/{platform}/{MODEL_IDENTIFIER}.so"),
        lib,
        0o755,
    )?;
    for (name, data) in resources {
        put(&format!("resources/{name}"), data, 0o644)?;
    }
    for (name, html) in docs {
        put(&format!("documentation/{name}"), html.as_bytes(), 0o644)?;
    }
    z.finish().map_err(|e| e.to_string())?;
    Ok(())
}
