//! modelDescription.xml for FMI 3.0 and FMI 2.0, written from the variable table.

use crate::table::units::{quantity, UNITS};
use crate::table::{Causality, Kind, Start, Table, Variable};
use std::fmt::Write;

pub const MODEL_IDENTIFIER: &str = "sphfmu";
pub const LOG_CATEGORIES: &[(&str, &str)] = &[
    (
        "logEvents",
        "Instantiation, initialisation, parameters, reset, terminate",
    ),
    ("logStatusWarning", "Calls that return a warning"),
    (
        "logStatusError",
        "Calls that return an error, with the cause",
    ),
    (
        "logSolver",
        "Step statistics: internal steps, smallest and largest dt per doStep",
    ),
];

/// What the XML says about the model besides its variables: the root element's attributes
/// and `<DefaultExperiment>`.
pub struct Experiment {
    /// `modelName`: the case's name, so two case FMUs do not look alike in a tool.
    pub model_name: String,
    /// `description`: the case's description (its name when it has none).
    pub description: String,
    /// `author`: the case's author (the `[case] author` key), else "sphfmu".
    pub author: String,
    /// `license` (SPDX expression of the FMU binary).
    pub license: String,
    /// `generationDateAndTime`, xs:dateTime in UTC (`2026-12-01T22:02:16Z`).
    pub generated: String,
    pub stop_time: f64,
    pub step_size: f64,
}

/// `generationDateAndTime` for `seconds` since the Unix epoch (UTC, xs:dateTime); the
/// packager passes SOURCE_DATE_EPOCH when set, so a packaging run can be reproduced byte for
/// byte (reproducible-builds.org's convention).
pub fn date_time(seconds: u64) -> String {
    let (days, rem) = (seconds / 86_400, seconds % 86_400);
    // civil date from days since 1970-01-01 (Howard Hinnant's days_from_civil inverse)
    let z = days as i64 + 719_468;
    let era = z.div_euclid(146_097);
    let doe = z - era * 146_097;
    let yoe = (doe - doe / 1460 + doe / 36_524 - doe / 146_096) / 365;
    let doy = doe - (365 * yoe + yoe / 4 - yoe / 100);
    let mp = (5 * doy + 2) / 153;
    let day = doy - (153 * mp + 2) / 5 + 1;
    let month = if mp < 10 { mp + 3 } else { mp - 9 };
    let year = yoe + era * 400 + i64::from(month <= 2);
    format!(
        "{year:04}-{month:02}-{day:02}T{:02}:{:02}:{:02}Z",
        rem / 3600,
        rem % 3600 / 60,
        rem % 60
    )
}

pub fn escape(s: &str) -> String {
    s.replace('&', "&amp;")
        .replace('<', "&lt;")
        .replace('>', "&gt;")
        .replace('"', "&quot;")
}

/// Instantiation token / GUID: FNV-1a of the variable list, so an FMU binary refuses a
/// modelDescription written for another case.
pub fn token(table: &Table) -> String {
    let mut h: u64 = 0xcbf2_9ce4_8422_2325;
    for v in &table.variables {
        for b in format!(
            "{}|{}|{:?}|{:?}|{};",
            v.name, v.vr, v.kind, v.causality, v.size
        )
        .bytes()
        {
            h = (h ^ b as u64).wrapping_mul(0x0000_0100_0000_01b3);
        }
    }
    let g = h.wrapping_mul(0x9e37_79b9_7f4a_7c15);
    format!(
        "{{{:08x}-{:04x}-{:04x}-{:04x}-{:012x}}}",
        h >> 32,
        (h >> 16) & 0xffff,
        h & 0xffff,
        g >> 48,
        g & 0xffff_ffff_ffff
    )
}

fn num(x: f64) -> String {
    // shortest round-trip form
    format!("{x:?}")
}

fn units_xml(out: &mut String) {
    out.push_str("  <UnitDefinitions>\n");
    for (name, [kg, m, s]) in UNITS {
        let mut attrs = String::new();
        for (k, e) in [("kg", kg), ("m", m), ("s", s)] {
            if *e != 0 {
                write!(attrs, " {k}=\"{e}\"").unwrap();
            }
        }
        writeln!(
            out,
            "    <Unit name=\"{}\"><BaseUnit{attrs}/></Unit>",
            escape(name)
        )
        .unwrap();
    }
    out.push_str("  </UnitDefinitions>\n");
}

fn log_categories(out: &mut String) {
    out.push_str("  <LogCategories>\n");
    for (n, d) in LOG_CATEGORIES {
        writeln!(
            out,
            "    <Category name=\"{n}\" description=\"{}\"/>",
            escape(d)
        )
        .unwrap();
    }
    out.push_str("  </LogCategories>\n");
}

/// The XML declaration and the opening root element (`token_attr`: instantiationToken in
/// 3.0, guid in 2.0).
fn root(table: &Table, exp: &Experiment, version: &str, token_attr: &str, extra: &str) -> String {
    let v = env!("CARGO_PKG_VERSION");
    format!(
        "<?xml version=\"1.0\" encoding=\"UTF-8\"?>\n<fmiModelDescription fmiVersion=\"{version}\" modelName=\"{}\" {token_attr}=\"{}\" description=\"{}\" author=\"{}\" version=\"{v}\" license=\"{}\" generationTool=\"sphfmu-package {v} (sphfmu {v})\" generationDateAndTime=\"{}\"{extra}>\n",
        escape(&exp.model_name),
        token(table),
        escape(&exp.description),
        escape(&exp.author),
        escape(&exp.license),
        escape(&exp.generated),
    )
}

/// `<UnitDefinitions>`, `<LogCategories>` and `<DefaultExperiment>`, the same in both
/// versions (and in the same place of the element order).
fn shared_sections(out: &mut String, exp: &Experiment, types: &str) {
    units_xml(out);
    out.push_str(types);
    log_categories(out);
    writeln!(
        out,
        "  <DefaultExperiment startTime=\"0\" stopTime=\"{}\" stepSize=\"{}\"/>",
        num(exp.stop_time),
        num(exp.step_size)
    )
    .unwrap();
}

/// FMI 3.0 `<TypeDefinitions>`: one Float64Type per quantity the variables have, with its
/// unit, which the variables name as their `declaredType`. The quantity could sit on the
/// variable itself (the standard allows it), but rust-fmi's reader (fmi-schema 0.8) refuses a
/// `quantity` attribute on a Float64 variable, and a type definition says the same to every
/// tool. (FMI 2.0 keeps `quantity` on the `<Real>` element, which every reader takes.)
fn float64_types(table: &Table) -> String {
    let mut seen: Vec<(String, &str)> = vec![];
    for v in table.variables.iter().filter(|v| v.kind == Kind::Float64) {
        if let Some(q) = quantity(&v.binding, table.dimension) {
            if !seen.iter().any(|(n, _)| *n == q) {
                seen.push((q, v.unit.unwrap_or("")));
            }
        }
    }
    if seen.is_empty() {
        return String::new();
    }
    let mut out = String::from("  <TypeDefinitions>\n");
    for (q, unit) in seen {
        let unit = if unit.is_empty() {
            String::new()
        } else {
            format!(" unit=\"{}\"", escape(unit))
        };
        writeln!(
            out,
            "    <Float64Type name=\"{q}\" quantity=\"{q}\"{unit}/>"
        )
        .unwrap();
    }
    out.push_str("  </TypeDefinitions>\n");
    out
}

fn causality(c: Causality) -> &'static str {
    match c {
        Causality::Independent => "independent",
        Causality::Parameter => "parameter",
        Causality::Input => "input",
        Causality::Output => "output",
    }
}

fn variability(v: &Variable) -> &'static str {
    match v.causality {
        Causality::Parameter => "fixed",
        _ if v.is_discrete() => "discrete",
        _ => "continuous",
    }
}

pub fn fmi3(table: &Table, exp: &Experiment) -> String {
    let mut o = root(table, exp, "3.0", "instantiationToken", "");
    writeln!(
        o,
        "  <CoSimulation modelIdentifier=\"{MODEL_IDENTIFIER}\" canHandleVariableCommunicationStepSize=\"true\" canGetAndSetFMUState=\"true\" canSerializeFMUState=\"true\" canReturnEarlyAfterIntermediateUpdate=\"false\" hasEventMode=\"false\" providesIntermediateUpdate=\"false\"/>"
    )
    .unwrap();
    shared_sections(&mut o, exp, &float64_types(table));
    o.push_str("  <ModelVariables>\n");
    for v in &table.variables {
        let tag = match v.kind {
            Kind::Float64 => "Float64",
            Kind::Int64 => "Int64",
            Kind::String => "String",
        };
        let mut attrs = format!(
            "name=\"{}\" valueReference=\"{}\" description=\"{}\" causality=\"{}\" variability=\"{}\"",
            escape(&v.name),
            v.vr,
            escape(&v.description),
            causality(v.causality),
            variability(v)
        );
        if v.causality == Causality::Output {
            attrs.push_str(" initial=\"calculated\"");
        }
        // FMI 3.0: the quantity through a declared type (`float64_types`)
        if let (Kind::Float64, Some(q)) = (v.kind, quantity(&v.binding, table.dimension)) {
            write!(attrs, " declaredType=\"{q}\"").unwrap();
        }
        if let Some(u) = v.unit {
            write!(attrs, " unit=\"{}\"", escape(u)).unwrap();
        }
        let mut children = String::new();
        match &v.start {
            Start::None => {}
            Start::Float(x) => {
                let s: Vec<String> = x.iter().map(|x| num(*x)).collect();
                write!(attrs, " start=\"{}\"", s.join(" ")).unwrap();
            }
            Start::Int(i) => write!(attrs, " start=\"{i}\"").unwrap(),
            Start::Text(t) => write!(children, "<Start value=\"{}\"/>", escape(t)).unwrap(),
        }
        if v.size > 1 {
            write!(children, "<Dimension start=\"{}\"/>", v.size).unwrap();
        }
        if children.is_empty() {
            writeln!(o, "    <{tag} {attrs}/>").unwrap();
        } else {
            writeln!(o, "    <{tag} {attrs}>{children}</{tag}>").unwrap();
        }
    }
    o.push_str("  </ModelVariables>\n  <ModelStructure>\n");
    for v in table
        .variables
        .iter()
        .filter(|v| v.causality == Causality::Output)
    {
        writeln!(o, "    <Output valueReference=\"{}\"/>", v.vr).unwrap();
    }
    for v in table
        .variables
        .iter()
        .filter(|v| v.causality == Causality::Output)
    {
        writeln!(o, "    <InitialUnknown valueReference=\"{}\"/>", v.vr).unwrap();
    }
    o.push_str("  </ModelStructure>\n</fmiModelDescription>\n");
    o
}

pub fn fmi2(table: &Table, exp: &Experiment) -> String {
    let mut o = root(
        table,
        exp,
        "2.0",
        "guid",
        " variableNamingConvention=\"structured\" numberOfEventIndicators=\"0\"",
    );
    writeln!(
        o,
        "  <CoSimulation modelIdentifier=\"{MODEL_IDENTIFIER}\" canHandleVariableCommunicationStepSize=\"true\" canGetAndSetFMUstate=\"true\" canSerializeFMUstate=\"true\" canNotUseMemoryManagementFunctions=\"true\"/>"
    )
    .unwrap();
    shared_sections(&mut o, exp, "");
    o.push_str("  <ModelVariables>\n");
    let mut outputs = vec![];
    for (r, s) in table.fmi2.iter().enumerate() {
        let v = &table.variables[s.variable];
        if v.causality == Causality::Independent {
            // FMI 2.0 has no independent variable: time is the master's
            continue;
        }
        let index = r; // 1-based index below (time, r = 0, is skipped)
        let mut attrs = format!(
            "name=\"{}\" valueReference=\"{r}\" description=\"{}\" causality=\"{}\" variability=\"{}\"",
            escape(&table.fmi2_name(s)),
            escape(&v.description),
            causality(v.causality),
            variability(v)
        );
        match v.causality {
            Causality::Output => {
                attrs.push_str(" initial=\"calculated\"");
                outputs.push(index);
            }
            Causality::Parameter => attrs.push_str(" initial=\"exact\""),
            _ => {}
        }
        let (tag, mut t) = match v.kind {
            Kind::Float64 => ("Real", String::new()),
            Kind::Int64 => ("Integer", String::new()),
            Kind::String => ("String", String::new()),
        };
        match &v.start {
            Start::None => {}
            Start::Float(x) => write!(t, " start=\"{}\"", num(x[s.element])).unwrap(),
            Start::Int(i) => write!(t, " start=\"{i}\"").unwrap(),
            Start::Text(x) => write!(t, " start=\"{}\"", escape(x)).unwrap(),
        }
        if let Some(q) = quantity(&v.binding, table.dimension) {
            write!(t, " quantity=\"{q}\"").unwrap();
        }
        if let Some(u) = v.unit {
            write!(t, " unit=\"{}\"", escape(u)).unwrap();
        }
        writeln!(
            o,
            "    <ScalarVariable {attrs}><{tag}{t}/></ScalarVariable>"
        )
        .unwrap();
    }
    o.push_str("  </ModelVariables>\n  <ModelStructure>\n    <Outputs>\n");
    for i in &outputs {
        writeln!(o, "      <Unknown index=\"{i}\"/>").unwrap();
    }
    o.push_str("    </Outputs>\n    <InitialUnknowns>\n");
    for i in &outputs {
        writeln!(o, "      <Unknown index=\"{i}\"/>").unwrap();
    }
    o.push_str("    </InitialUnknowns>\n  </ModelStructure>\n</fmiModelDescription>\n");
    o
}
