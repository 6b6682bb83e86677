//! Bad input: every malformed or out-of-range case file gives one line naming the key (and the
//! allowed range); the CLI exits 2 without a panic; an unstable run exits 3 keeping snapshots.

use sphfmu::case::Case;
use std::process::Command;

const SOD: &str = include_str!("../models/sod.toml");

fn err_of(text: &str) -> String {
    Case::parse(text).expect_err("must be rejected").0
}

#[test]
fn each_bad_value_names_its_key_and_range() {
    let cases: &[(&str, &str, &[&str])] = &[
        (
            "dimension = 1",
            "dimension = 4",
            &["case.dimension", "1, 2 or 3"],
        ),
        ("gamma = 1.4", "gamma = 0.9", &["eos.gamma", "(1, 10]"]),
        ("eta = 1.2", "eta = 9.0", &["kernel.eta", "[0.5, 5]"]),
        ("alpha = 1.0", "alpha = -1.0", &["scheme.alpha", "[0, 10]"]),
        ("cfl = 0.3", "cfl = 2.0", &["time.cfl", "(0, 1]"]),
        ("t_end = 0.15", "t_end = -1.0", &["time.t_end", "> 0"]),
        (
            "density = 0.125",
            "density = 0.0",
            &["region[1].density", "> 0"],
        ),
        (
            "max = [0.5]\nboundary",
            "max = [-0.7]\nboundary",
            &["domain.max[0]", "greater than"],
        ),
        (
            "min = [0.0]\nmax = [0.5]",
            "min = [0.0, 1.0]\nmax = [0.5]",
            &["region[1].min", "1 entries"],
        ),
        (
            "snapshot_every = 0.05",
            "snapshot_every = -1",
            &["output.snapshot_every", "≥ 0"],
        ),
        (
            "conductivity = 1.0",
            "conductivity = 1.0\nviscocity = 3",
            &["unknown field", "viscocity"],
        ),
        (
            "conductivity = 1.0",
            "conductivity = 1.0\nviscosity = -3",
            &["scheme.viscosity", "[0, 1000]"],
        ),
        (
            "conductivity = 1.0",
            "conductivity = 1.0\ndelta = 0.1",
            &["scheme.delta", "continuity"],
        ),
        (
            "name = \"cubic-spline\"",
            "name = \"gaussian\"",
            &["unknown variant", "gaussian"],
        ),
        (
            "boundary = [\"reflect\"]",
            "boundary = [\"sticky\"]",
            &["sticky"],
        ),
        (
            "t_end = 0.15",
            "t_end = \"soon\"",
            &["line", "invalid type"],
        ),
    ];
    for (from, to, needles) in cases {
        assert!(SOD.contains(from), "fixture lacks {from:?}");
        let msg = err_of(&SOD.replacen(from, to, 1));
        assert!(!msg.contains('\n'), "error must be one line: {msg:?}");
        for n in *needles {
            assert!(msg.contains(n), "error for {to:?} lacks {n:?}: {msg}");
        }
    }
}

#[test]
fn a_stretched_interface_needs_uniform_densities() {
    let interface = "\n[[interface]]\naxis = 0\nposition = 0.5\nwidth = 0.01\nstretch = true\n";
    assert!(Case::parse(&format!("{SOD}{interface}")).is_ok());
    let profiled = SOD.replacen(
        "density = 0.125",
        "density_profile = { expression = \"0.125\" }",
        1,
    );
    assert!(
        Case::parse(&profiled).is_ok(),
        "the fixture with a profile alone is valid"
    );
    let msg = err_of(&format!("{profiled}{interface}"));
    assert!(
        msg.contains("interface[0].stretch") && msg.contains("region[1]"),
        "{msg}"
    );
}

#[test]
fn malformed_toml_and_missing_tables() {
    let m = err_of("[case\nname = 1");
    assert!(m.starts_with("line 1"), "{m}");
    let m = err_of(&SOD.replace("[verify]", "[verify_x]"));
    assert!(m.contains("unknown field") && m.contains("verify_x"), "{m}");
    let no_regions: String = SOD.split("[[region]]").next().unwrap().to_string();
    assert!(err_of(&no_regions).contains("region"));
}

fn bin() -> Command {
    Command::new(env!("CARGO_BIN_EXE_sphfmu"))
}

#[test]
fn cli_exit_code_2_with_one_line_for_bad_cases() {
    let dir = tempfile::tempdir().unwrap();
    let bad = dir.path().join("bad.toml");
    std::fs::write(&bad, SOD.replace("gamma = 1.4", "gamma = 0.5")).unwrap();
    for sub in ["check", "run"] {
        let mut cmd = bin();
        cmd.arg(sub).arg(&bad);
        if sub == "run" {
            cmd.arg("--quiet").arg("--out").arg(dir.path().join("o"));
        }
        let out = cmd.output().unwrap();
        assert_eq!(out.status.code(), Some(2), "{sub}");
        let err = String::from_utf8_lossy(&out.stderr);
        assert_eq!(err.trim().lines().count(), 1, "{sub}: {err}");
        assert!(
            err.contains("eos.gamma") && !err.contains("panicked"),
            "{err}"
        );
    }
    let out = bin()
        .args(["check", "/nonexistent/case.toml"])
        .output()
        .unwrap();
    assert_eq!(out.status.code(), Some(2));
    assert!(String::from_utf8_lossy(&out.stderr).contains("cannot read"));
    let ok = bin()
        .args([
            "check",
            concat!(env!("CARGO_MANIFEST_DIR"), "/models/sod.toml"),
            "--build",
        ])
        .output()
        .unwrap();
    assert_eq!(ok.status.code(), Some(0));
    assert!(String::from_utf8_lossy(&ok.stdout).contains("721 particles"));
}

#[test]
fn unstable_run_exits_3_and_keeps_snapshots() {
    let dir = tempfile::tempdir().unwrap();
    let case = dir.path().join("collapse.toml");
    // A dt floor above the stable step: the first step reports the collapse.
    std::fs::write(&case, SOD.replace("cfl = 0.3", "cfl = 0.3\ndt_min = 0.01")).unwrap();
    let out_dir = dir.path().join("out");
    let out = bin()
        .arg("run")
        .arg(&case)
        .arg("--out")
        .arg(&out_dir)
        .arg("--quiet")
        .output()
        .unwrap();
    assert_eq!(out.status.code(), Some(3));
    let err = String::from_utf8_lossy(&out.stderr);
    assert_eq!(err.trim().lines().count(), 1, "{err}");
    assert!(
        err.contains("time.dt_min") && err.contains("unstable"),
        "{err}"
    );
    assert!(out_dir.join("snapshot_00000.vtu").exists());
    assert!(out_dir.join("diagnostics.csv").exists());
}

#[test]
fn non_finite_state_is_reported_not_propagated() {
    let case = Case::parse(SOD).unwrap();
    let mut sim = case.build::<1>().unwrap();
    sim.sys.particles.u[100] = f64::NAN;
    let e = sim.step(f64::INFINITY).unwrap_err().to_string();
    assert!(e.contains("non-finite") || e.contains("unstable"), "{e}");
}

/// `--set`: a key of the case changed from the command line takes effect (every region's
/// mass halved doubles the particles), and a key or value that is wrong is named.
#[test]
fn set_overrides_a_case_key_and_names_bad_ones() {
    let sod = concat!(env!("CARGO_MANIFEST_DIR"), "/models/sod.toml");
    let check = |sets: &[&str]| {
        let mut cmd = bin();
        cmd.args(["check", sod, "--build"]);
        for s in sets {
            cmd.args(["--set", s]);
        }
        let out = cmd.output().unwrap();
        (
            out.status.code(),
            String::from_utf8_lossy(&out.stdout).to_string()
                + &String::from_utf8_lossy(&out.stderr),
        )
    };
    let (code, text) = check(&["region.*.particle_mass=0.000390625"]);
    assert_eq!(code, Some(0), "{text}");
    assert!(text.contains("1442 particles"), "{text}");
    let (code, text) = check(&["region.1.particle_mass=0.000390625"]);
    assert_eq!(code, Some(0), "{text}");
    assert!(text.contains("801 particles"), "{text}");
    for (set, says) in [
        ("regoin.0.spacing=0.1", "no table \"regoin\""),
        ("region.7.density=1.0", "index 7 out of range 0..2"),
        ("time.t_end=-1", "time.t_end: must be a finite number > 0"),
        ("time.t_end", "expected key=value"),
        ("time.t_end=fast", "is not a TOML value"),
        ("time.t_end.x=1", "is a value, not a table"),
    ] {
        let (code, text) = check(&[set]);
        assert_eq!(code, Some(2), "{set}: {text}");
        assert!(
            text.contains(says) && text.trim().lines().count() == 1,
            "{set}: {text}"
        );
    }
}

/// `--scheme` then `--set`: the preset replaces the file's scheme first and the overrides
/// apply to it (applied the other way round, the preset silently dropped `--set scheme.*`),
/// and every shipped model survives the preset's round trip through TOML.
#[test]
fn scheme_preset_then_overrides_keeps_the_overrides() {
    use sphfmu::scheme::SchemeConfig;
    let models = concat!(env!("CARGO_MANIFEST_DIR"), "/models");
    let sod = std::path::Path::new(models).join("sod.toml");
    let sets = [
        "scheme.limiter=false".to_string(),
        "kernel.eta=2.5".to_string(),
    ];
    let case = Case::load_with(&sod, Some("crksph"), &sets).unwrap();
    match &case.scheme {
        SchemeConfig::Crksph(p) => assert!(!p.limiter, "{p:?}"),
        other => panic!("crksph expected, got {other:?}"),
    }
    assert_eq!(case.kernel.eta, Some(2.5));
    // a key the preset does not have is named
    let e = Case::load_with(&sod, Some("crksph"), &["scheme.balsara=false".to_string()])
        .unwrap_err()
        .0;
    assert!(e.contains("balsara"), "{e}");
    for dir in [models.to_string(), format!("{models}/verify")] {
        for entry in std::fs::read_dir(&dir).unwrap() {
            let path = entry.unwrap().path();
            if path.extension().is_some_and(|x| x == "toml") && !path.ends_with("suite.toml") {
                let plain = Case::load_with(&path, Some("standard"), &[]).unwrap();
                let set = ["case.author=\"x\"".to_string()];
                let mut edited = Case::load_with(&path, Some("standard"), &set)
                    .unwrap_or_else(|e| panic!("{}: {e}", path.display()));
                edited.case.author = plain.case.author.clone();
                assert_eq!(edited, plain, "{}", path.display());
            }
        }
    }
}

#[test]
fn a_driven_region_names_its_bad_expression() {
    let kidder = include_str!("../models/verify/kidder.toml");
    let bad: &[(&str, &str, &[&str])] = &[
        (
            "position = [\"x*(1 - (t/tau)^2)^0.5\"]",
            "position = [\"x\", \"y\"]",
            &["region[0].drive.position", "needs 1 expressions"],
        ),
        (
            "velocity = [\"-(x*t/(tau^2*(1 - (t/tau)^2)^0.5))\"]",
            "velocity = [\"-(x*t/tau2)\"]",
            &["region[0].drive.velocity[0]", "unknown name `tau2`"],
        ),
        (
            "s = 1.0e7, tau",
            "s = 1.0e7, t = 1.0, tau",
            &["region[0].drive", "`t` is the time"],
        ),
        (
            "pressure = \"s*",
            "pressure = \"y*s*",
            &[
                "region[0].drive.pressure",
                "`y` is not a coordinate of a 1D case",
            ],
        ),
    ];
    for (from, to, expect) in bad {
        assert!(kidder.contains(from), "{from}");
        let e = err_of(&kidder.replacen(from, to, 1));
        for w in *expect {
            assert!(e.contains(w), "{to}: {e}");
        }
    }
}

/// A case built in another dimension than its own is an error naming both, not a panic,
/// for any D: the check comes before the library picks its per-dimension build.
#[test]
fn a_case_built_in_another_dimension_is_an_error() {
    let case = Case::parse(SOD).expect("sod.toml parses");
    for e in [
        case.system::<2>().expect_err("1D case in 2D").0,
        case.system::<4>().expect_err("1D case in 4D").0,
        case.build::<3>().err().expect("1D case in 3D").0,
    ] {
        assert!(e.contains("case.dimension = 1 but built in"), "{e}");
    }
}
