"""The FMU driven by fmpy as a master would (issue 7). Every session that loads the FMU runs in
its own process (fmu_sessions.py), so a crash fails one test and pytest survives."""
import json
import pathlib
import subprocess
import sys

import pytest

from conftest import run_session
from fmpy import read_model_description
from fmpy.validation import validate_fmu

HERE = pathlib.Path(__file__).resolve().parent
ROOT = HERE.parents[1]
FMU3 = ROOT / "target" / "fmu" / "sphfmu.fmu"
FMU2 = ROOT / "target" / "fmu" / "sphfmu-fmi2.fmu"
TANK3 = ROOT / "target" / "fmu" / "closed-tank2d" / "sphfmu.fmu"
TANK2 = ROOT / "target" / "fmu" / "closed-tank2d" / "sphfmu-fmi2.fmu"
CHANNEL3 = ROOT / "target" / "fmu" / "channel-ports2d" / "sphfmu.fmu"
CHANNEL2 = ROOT / "target" / "fmu" / "channel-ports2d" / "sphfmu-fmi2.fmu"
BOX3 = ROOT / "target" / "fmu" / "box3d-matrix" / "sphfmu.fmu"
BOX2 = ROOT / "target" / "fmu" / "box3d" / "sphfmu-fmi2.fmu"


@pytest.fixture(scope="module", autouse=True)
def packaged():
    if not all(p.exists() for p in (FMU3, TANK3, CHANNEL3, BOX3, BOX2)):
        subprocess.run(["make", "fmu"], cwd=ROOT, check=True)


def session(name, **args):
    return run_session("fmu_sessions.py", name, **args)


@pytest.mark.parametrize("fmu", [FMU3, FMU2, TANK3, TANK2, CHANNEL3, CHANNEL2, BOX3, BOX2],
                         ids=lambda p: "/".join(p.parts[-2:]))
def test_validation_finds_no_problem(fmu):
    assert validate_fmu(str(fmu)) == []


@pytest.mark.parametrize("fmu", [FMU3, FMU2], ids=["fmi3", "fmi2"])
def test_fmpy_info_lists_every_variable(fmu):
    p = subprocess.run([str(pathlib.Path(sys.executable).parent / "fmpy"), "info", str(fmu)],
                       capture_output=True, text=True)
    assert p.returncode == 0, p.stderr
    md = read_model_description(str(fmu))
    names = [v.name for v in md.modelVariables]
    count = len(names)
    assert f"Variables          {count}" in p.stdout
    # every input and output is listed (fmpy shortens long names from the left)
    for v in md.modelVariables:
        if v.causality in ("input", "output"):
            assert v.name[-14:] in p.stdout, v.name
    expected = {"gravity", "piston.position", "piston.velocity", "piston.force", "end.torque",
                "probe.middle.pressure", "marker.face.pressure", "diag.steps", "diag.energy"}
    flat = {n.split("[")[0] for n in names}
    assert expected <= flat
    units = {v.name.split("[")[0]: v.unit for v in md.modelVariables}
    assert units["piston.force"] == "N/m" and units["gravity"] == "m/s2"


@pytest.mark.parametrize("fmu, case, fmi", [(FMU3, "free-piston2d", "3.0"), (FMU2, "free-piston2d", "2.0"),
                                           (TANK3, "closed-tank2d", "3.0")],
                         ids=["fmi3", "fmi2", "tank-fmi3"])
def test_model_description_names_the_case_with_metadata(fmu, case, fmi):
    md = read_model_description(str(fmu))
    assert md.fmiVersion == fmi and md.modelName == case
    assert md.description and md.description != "sphfmu"
    assert md.author and md.license == "MIT OR Apache-2.0"
    assert md.generationTool.startswith("sphfmu-package ")
    # xs:dateTime in UTC
    import datetime
    when = datetime.datetime.strptime(md.generationDateAndTime, "%Y-%m-%dT%H:%M:%SZ")
    assert when.year >= 2026
    by_name = {v.name.split("[")[0]: v for v in md.modelVariables}

    def quantity(v):
        # FMI 2.0: on the variable; FMI 3.0: through its declared type (rust-fmi's reader
        # refuses the attribute on a Float64 variable, see packaging/xml.rs)
        return v.quantity or (v.declaredType.quantity if v.declaredType else None)
    # a 2D force is per metre of depth, in its unit and in its quantity
    force = next(n for n in by_name if n.endswith(".force"))
    assert by_name[force].unit == "N/m" and quantity(by_name[force]) == "ForcePerDepth"
    assert quantity(by_name["gravity"]) == "Acceleration"


def test_packaged_binary_is_stripped():
    import zipfile
    with zipfile.ZipFile(FMU3) as z:
        so = z.read("binaries/x86_64-linux/sphfmu.so")
    # no symbol table (.symtab): the dynamic symbols the master resolves stay (.dynsym)
    names = elf_section_names(so)
    assert ".dynsym" in names and ".symtab" not in names, names


def elf_section_names(b):
    """Section names of a little-endian ELF64 file."""
    import struct
    shoff, = struct.unpack_from("<Q", b, 0x28)
    shentsize, shnum, shstrndx = struct.unpack_from("<HHH", b, 0x3A)
    def section(i):
        return struct.unpack_from("<IIQQQQ", b, shoff + i * shentsize)
    strtab = section(shstrndx)
    names = []
    for i in range(shnum):
        name_off = section(i)[0]
        start = strtab[4] + name_off
        names.append(b[start:b.index(b"\0", start)].decode())
    return names


def test_a_case_packaged_without_out_goes_to_its_own_folder(tmp_path):
    case = tmp_path / "my-tank.toml"
    case.write_text((ROOT / "models" / "closed-tank2d.toml").read_text()
                    .replace('name = "closed-tank2d"', 'name = "my-tank"\nauthor = "A. User"'))
    exe = ROOT / "target" / "release" / "sphfmu-package"
    p = subprocess.run([str(exe), "--case", str(case), "--lib", str(ROOT / "target/release/libsphfmu_fmu.so"),
                        "--models", str(ROOT / "models")], cwd=tmp_path, capture_output=True, text=True)
    assert p.returncode == 0, p.stderr
    md = read_model_description(str(tmp_path / "target" / "fmu" / "my-tank" / "sphfmu.fmu"))
    assert md.modelName == "my-tank" and md.author == "A. User"


def test_tank_force_follows_a_gravity_signal():
    r = session("tank_gravity", fmu_path=str(TANK3))
    print(r)
    # measured: 1.0011 of the weight at 9.81, 1.0018 after doubling g at t = 0.6 (mean over
    # t in (1.0, 1.4]); the issue asks 1 %
    assert abs(r["ratio1"] - 1) < 0.01 and abs(r["ratio2"] - 1) < 0.01
    assert r["finite"] and r["mass_drift"] < 1e-12 and r["particles"] == 1566
    # the floor patch over t in (0.3, 0.6]: measured mean wall pressure −2.05 % (−1.6 % over
    # [0.5, 1] in tests/coupling.rs; the wall layers read low, see tests/bodies.rs), 0.8 m
    assert abs(r["floor_pressure"] - 1) < 0.03 and abs(r["floor_area"] - 0.8) < 1e-12


def test_varying_steps_reach_the_state_of_fixed_steps():
    r = session("step_sizes", fmu_path=str(FMU3))
    fixed, varying = r["fixed"], r["varying"]
    assert abs(fixed[-1] - 1.0) < 1e-12 and abs(varying[-1] - 1.0) < 1e-12
    # force x, probe pressure, marker pressure, energy: measured relative differences 1.25e-6,
    # 1.28e-6, 8.8e-6, 4.5e-8 (the internal steps differ where communication points cut
    # them); tolerances 3× those
    for k, tol in [(0, 4e-6), (3, 4e-6), (4, 3e-5), (5, 1.5e-7)]:
        assert abs(varying[k] / fixed[k] - 1) < tol, (k, fixed[k], varying[k])


@pytest.mark.parametrize("fmi", [3, 2])
def test_rollback_and_serialized_state_are_bit_exact(fmi):
    r = session("rollback", fmu_path=str(FMU3 if fmi == 3 else FMU2), fmi=fmi)
    assert r["first"] == r["again"], "get/set FMU state"
    assert r["first"] == r["restored"], "serialize, free, deserialize into a new instance"
    assert r["bytes"] > 1000


def test_instances_side_by_side_are_independent():
    r = session("two_instances", fmu_path=str(FMU3))
    assert r["alone"] == r["beside"]
    assert r["other"] != r["alone"]


def test_free_piston_master_finds_the_gas_spring_frequency():
    r = session("free_piston", fmu_path=str(FMU3))
    ratio = r["period"] / r["theory"]
    print(f"period {r['period']:.4f} s, theory {r['theory']:.4f} s, ratio {ratio:.4f}")
    # measured: 1.0131 (the gas's own mass, 0.2 against M = 2, accounts for +1.6 %); issue: 3 %
    assert abs(ratio - 1) < 0.03


def test_bad_calls_return_errors_with_a_log_line_and_the_process_survives():
    r = session("bad_calls", fmu_path=str(FMU3))
    for k in ["step_before_init", "threads_out_of_range", "resolution_out_of_range", "nan_gravity",
              "gravity_z_in_2d", "omega_3d_in_2d", "inf_position", "set_output", "param_in_step_mode",
              "negative_step", "wrong_time", "wrong_nvalues", "unknown_vr",
              "step_after_terminate", "unknown_case", "other_interface", "unknown_scheme"]:
        assert r[k] == 3, (k, r[k])
    assert r["alive"]
    assert r["gravity_kept"] == [0.0, 0.0, 0.0], "a rejected input must not change the input"
    assert r["omega_kept"] == [0.0]
    assert abs(r["after_errors"] - 0.2) < 0.01
    log = "\n".join(r["log"])
    for needle in ["doStep: not allowed in state Instantiated", "gravity: must be finite, got NaN",
                   "gravity[3]: must be 0 in a 2D case", "communicationStepSize must be finite and > 0",
                   "currentCommunicationPoint 5 is not the FMU's time 0",
                   "no-such-case.toml: cannot read", "unknown preset \"sph2000\"",
                   "not allowed in state Terminated", "threads: must be in [0, 1024]",
                   "piston.angular_velocity about z only: a 2D body turns about z alone"]:
        assert needle in log, needle


@pytest.mark.parametrize("fmi", [3, 2])
def test_a_blowup_is_an_error_and_restore_or_reset_recovers(fmi):
    r = session("blowup_and_reset", fmu_path=str(FMU3 if fmi == 3 else FMU2), fmi=fmi)
    assert r["blowup"] == 3 and r["step_after_failure"] == 3
    # the blow-up shows as a non-finite field or a collapsed time step, depending on the
    # last bits of the start (both are the solver's "unstable" failure)
    assert any("the solver failed (unstable: " in m for m in r["log"]), r["log"]
    assert abs(r["after_restore"] - 0.2) < 0.01
    assert r["after_reset"] == r["fresh"], "reset must reproduce a fresh instance"


def test_snapshots_from_inside_the_fmu(tmp_path):
    r = session("snapshots", fmu_path=str(FMU3), out_dir=str(tmp_path / "vtu"))
    # t = 0, 0.1, 0.2, 0.3 with communication steps of 0.05
    assert r["files"] == [f"snapshot_{k:05}.vtu" for k in range(4)], r
    assert r["times"] == 4 and r["points"] == 628


def test_a_network_master_drives_a_port_pressure():
    r = session("port_pressure", fmu_path=str(CHANNEL3))
    print(r)
    q_exact = 0.06 / (12 * 0.1 * 2.0)
    # measured at 20 particles across: Q 10.3 % below exact at 0.06 Pa (t = 3…4 s), 5.4 % below
    # at 0.12 Pa (t = 7…8 s), ratio 2.11 (tests/ports.rs at 30 across: 1 % below after the
    # step); Stokes flow doubles with the pressure drop
    assert r["finite"] and abs(r["set_before"] - 0.06) < 1e-12 and abs(r["set_after"] - 0.12) < 1e-12
    assert abs(r["q1"] / q_exact - 1) < 0.15, r["q1"]
    assert 1.9 < r["q2"] / r["q1"] < 2.3, (r["q1"], r["q2"])
    # the exact counters: fluid mass = start + in − out to round-off, as the master sees it
    assert r["balance"] < 1e-12 and r["moved"] > 0 and r["fluid_changes"] > 1


@pytest.mark.parametrize("fmi", [3, 2])
def test_bad_port_pressures_are_errors(fmi):
    r = session("bad_port_pressure", fmu_path=str(CHANNEL3 if fmi == 3 else CHANNEL2), fmi=fmi)
    assert r["codes"] == {"negative": 3, "nan": 3}, r
    assert r["kept"] == [0.06]
    log = "\n".join(r["log"])
    assert "port.inlet.pressure: must be a finite number ≥ 0, got -1" in log, log
    assert "port.inlet.pressure: must be finite, got NaN" in log, log
