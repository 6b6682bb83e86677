//! `sphfmu-package`: write the FMI 3.0 and FMI 2.0 `.fmu` archives for one case.
//!
//!   sphfmu-package --case models/free-piston2d.toml --lib target/release/libsphfmu_fmu.so \
//!                  --models models --out target/fmu
//!
//! Each archive holds modelDescription.xml (written from the variable table of the case),
//! the binary as binaries/<platform>/sphfmu.so, every case file of --models under resources/
//! (with default-case.txt naming the packaged one) and documentation/ listing every variable.

use clap::Parser;
use sphfmu::case::Case;
use sphfmu_fmu::packaging::archive::{documentation, write_fmu};
use sphfmu_fmu::packaging::xml::{self, Experiment};
use sphfmu_fmu::table::Table;
use std::path::{Path, PathBuf};

/// Write the FMI 3.0 and FMI 2.0 co-simulation archives (`sphfmu.fmu`, `sphfmu-fmi2.fmu`) of
/// one case.
#[derive(Parser)]
#[command(
    name = "sphfmu-package",
    version,
    about = "Write the FMI 3.0 and FMI 2.0 co-simulation archives (.fmu) of one case",
    after_help = AFTER_HELP
)]
struct Args {
    /// The case file to package (TOML); its bodies, probes, markers, patches and ports
    /// become the FMU's variables, its name the modelName, its description the description
    #[arg(long)]
    case: PathBuf,
    /// The FMU binary: the FMU crate's cdylib (target/release/libsphfmu_fmu.so)
    #[arg(long, default_value = "target/release/libsphfmu_fmu.so")]
    lib: PathBuf,
    /// Folder whose case files (*.toml) go under resources/, so the `case` parameter can
    /// pick another with the same variables
    #[arg(long, default_value = "models")]
    models: PathBuf,
    /// Output folder [default: target/fmu/<case name>]
    #[arg(long)]
    out: Option<PathBuf>,
    /// The modelDescription's author [default: the case's `author`, else "sphfmu"]
    #[arg(long)]
    author: Option<String>,
    /// Keep the binary's symbol table (it is stripped by default: 18 MB -> 14 MB)
    #[arg(long)]
    no_strip: bool,
    /// Change a key of the case before packaging, as `sphfmu run --set` (e.g.
    /// --set 'body.0.orientation="matrix"'); the changed case goes under resources/ in place
    /// of the file's own text, so the FMU runs what its variables describe
    #[arg(long = "set", value_name = "KEY=VALUE")]
    sets: Vec<String>,
}

const AFTER_HELP: &str = "\
The archives hold modelDescription.xml (written from the case's variable table, with modelName,
description, author, license, generation tool and date, units and quantities), the binary as
binaries/<platform>/sphfmu.so, every case file of --models under resources/ (default-case.txt
names the packaged one) and documentation/index.html listing every variable.
generationDateAndTime is the packaging time, or SOURCE_DATE_EPOCH when that is set.
Example:
  sphfmu-package --case models/closed-tank2d.toml     # -> target/fmu/closed-tank2d/";

/// A case name as a folder name: letters, digits, '-', '_' and '.' kept, the rest '_'.
fn folder_name(name: &str) -> String {
    let s = sphfmu_fmu::plain_name(name);
    if s.is_empty() || s.chars().all(|c| c == '.') {
        "case".into()
    } else {
        s
    }
}

/// The binary with its symbol table removed (`strip --strip-unneeded`, binutils, which gcc
/// and so every Rust toolchain on Linux brings): the dynamic symbols the master resolves
/// (fmi3*, fmi2*) stay. Without `strip` on the PATH the binary goes in as it is, with a note.
fn stripped(lib: &[u8]) -> Vec<u8> {
    let dir = std::env::temp_dir().join(format!("sphfmu-package-{}", std::process::id()));
    let path = dir.join("sphfmu.so");
    let result = std::fs::create_dir_all(&dir)
        .and_then(|_| std::fs::write(&path, lib))
        .and_then(|_| {
            std::process::Command::new("strip")
                .arg("--strip-unneeded")
                .arg(&path)
                .status()
        })
        .and_then(|st| {
            if st.success() {
                std::fs::read(&path)
            } else {
                Err(std::io::Error::other(format!("strip exited with {st}")))
            }
        });
    let _ = std::fs::remove_dir_all(&dir);
    match result {
        Ok(b) => b,
        Err(e) => {
            eprintln!("sphfmu-package: note: binary not stripped ({e})");
            lib.to_vec()
        }
    }
}

/// Seconds since the Unix epoch for generationDateAndTime: SOURCE_DATE_EPOCH when set.
fn generation_time() -> Result<u64, String> {
    match std::env::var("SOURCE_DATE_EPOCH") {
        Ok(v) => v
            .trim()
            .parse()
            .map_err(|_| format!("SOURCE_DATE_EPOCH: {v:?} is not a whole number of seconds")),
        Err(_) => Ok(std::time::SystemTime::now()
            .duration_since(std::time::UNIX_EPOCH)
            .map(|d| d.as_secs())
            .unwrap_or(0)),
    }
}

fn run() -> Result<(), String> {
    let a = Args::parse();
    let case = Case::load_with(&a.case, None, &a.sets).map_err(|e| format!("--case: {}", e.0))?;
    let case_file = a
        .case
        .file_name()
        .and_then(|n| n.to_str())
        .ok_or("--case: not a file name")?
        .to_string();
    let table = Table::new(&case, &case_file);
    let lib = std::fs::read(&a.lib).map_err(|e| format!("--lib {}: {e}", a.lib.display()))?;
    let lib = if a.no_strip { lib } else { stripped(&lib) };
    let out = a
        .out
        .clone()
        .unwrap_or_else(|| Path::new("target/fmu").join(folder_name(&case.case.name)));
    let mut resources = vec![(
        sphfmu_fmu::instance::DEFAULT_CASE_FILE.to_string(),
        format!("{case_file}\n").into_bytes(),
    )];
    let mut names: Vec<_> = std::fs::read_dir(&a.models)
        .map_err(|e| format!("--models {}: {e}", a.models.display()))?
        .filter_map(|e| e.ok().map(|e| e.path()))
        .filter(|p| p.extension().is_some_and(|x| x == "toml"))
        .collect();
    names.sort();
    for p in names {
        let n = p
            .file_name()
            .and_then(|n| n.to_str())
            .unwrap_or_default()
            .to_string();
        resources.push((n, std::fs::read(&p).map_err(|e| e.to_string())?));
    }
    let own = if a.sets.is_empty() {
        std::fs::read(&a.case).map_err(|e| e.to_string())?
    } else {
        let text = case.to_text().map_err(|e| format!("--set: {}", e.0))?;
        let sets = a.sets.join(" ");
        format!("# {case_file} packaged with --set {sets}\n{text}").into_bytes()
    };
    resources.retain(|(n, _)| *n != case_file);
    resources.push((case_file.clone(), own));
    let exp = Experiment {
        model_name: case.case.name.clone(),
        description: if case.case.description.is_empty() {
            case.case.name.clone()
        } else {
            case.case.description.clone()
        },
        author: a.author.clone().unwrap_or_else(|| {
            if case.case.author.is_empty() {
                "sphfmu".into()
            } else {
                case.case.author.clone()
            }
        }),
        license: env!("CARGO_PKG_LICENSE").into(),
        generated: xml::date_time(generation_time()?),
        stop_time: case.time.t_end,
        step_size: case.time.t_end / 200.0,
    };
    std::fs::create_dir_all(&out).map_err(|e| format!("--out {}: {e}", out.display()))?;
    let fmu3 = out.join("sphfmu.fmu");
    write_fmu(
        &fmu3,
        &xml::fmi3(&table, &exp),
        "x86_64-linux",
        &lib,
        &resources,
        &[("index.html", documentation(&table, &case, "3.0"))],
    )?;
    let fmu2 = out.join("sphfmu-fmi2.fmu");
    let doc2 = documentation(&table, &case, "2.0");
    write_fmu(
        &fmu2,
        &xml::fmi2(&table, &exp),
        "linux64",
        &lib,
        &resources,
        &[("_main.html", doc2.clone()), ("index.html", doc2)],
    )?;
    println!(
        "wrote {} and {} ({} variables, case {case_file})",
        fmu3.display(),
        fmu2.display(),
        table.variables.len()
    );
    Ok(())
}

fn main() {
    if let Err(e) = run() {
        eprintln!("sphfmu-package: {e}");
        std::process::exit(2);
    }
}
