//! The FMI 2.0 C API (co-simulation): all 34 functions fmpy resolves. 3-vectors appear as
//! three scalars (`name[1]`..`name[3]`); Int64 variables as Integer (saturated to i32).
#![allow(non_snake_case, clippy::missing_safety_doc, clippy::too_many_arguments)]

use crate::abi::ffi::{bad, slice, slice_mut, text, uri_to_path, with, Fmu};
use crate::abi::state_ffi;
use crate::instance::{CallResult, Instance, Status};
use crate::table::Kind;
use std::ffi::{c_char, c_int, c_void, CString};
use std::path::Path;

type Comp = *mut c_void;
type Vr = u32;
type Logger2 =
    unsafe extern "C" fn(*mut c_void, *const c_char, c_int, *const c_char, *const c_char, ...);

#[repr(C)]
pub struct Callbacks {
    logger: Option<Logger2>,
    allocate_memory: *mut c_void,
    free_memory: *mut c_void,
    step_finished: *mut c_void,
    component_environment: *mut c_void,
}

/// A message as the logger's format string: '%' doubled so printf-style masters print it.
fn c_message(msg: &str) -> CString {
    CString::new(msg.replace('\0', " ").replace('%', "%%")).unwrap_or_default()
}

#[no_mangle]
pub extern "C" fn fmi2GetTypesPlatform() -> *const c_char {
    c"default".as_ptr()
}

#[no_mangle]
pub extern "C" fn fmi2GetVersion() -> *const c_char {
    c"2.0".as_ptr()
}

#[no_mangle]
pub unsafe extern "C" fn fmi2Instantiate(
    instance_name: *const c_char,
    fmu_type: c_int,
    guid: *const c_char,
    resource_location: *const c_char,
    functions: *const Callbacks,
    _visible: c_int,
    logging_on: c_int,
) -> Comp {
    let (logger, env) = if functions.is_null() {
        (None, std::ptr::null_mut())
    } else {
        ((*functions).logger, (*functions).component_environment)
    };
    let name_c = if instance_name.is_null() {
        c"".as_ptr()
    } else {
        instance_name
    };
    let say = |status: Status, msg: &str| {
        if let Some(cb) = logger {
            let m = c_message(msg);
            cb(
                env,
                name_c,
                status as c_int,
                c"logStatusError".as_ptr(),
                m.as_ptr(),
            );
        }
    };
    let r = std::panic::catch_unwind(|| -> Result<Box<Fmu>, String> {
        let name = text(instance_name).ok_or("instanceName is NULL or not UTF-8")?;
        if fmu_type != 1 {
            return Err("fmuType: sphfmu is a co-simulation FMU only (fmi2CoSimulation)".into());
        }
        let uri = text(resource_location).ok_or(
            "fmuResourceLocation is NULL: the FMU needs its resources folder (case files)",
        )?;
        let dir = uri_to_path(uri)
            .ok_or_else(|| format!("fmuResourceLocation {uri:?}: not a file URI"))?;
        let name_owned = CString::new(name).unwrap_or_default();
        let log: crate::instance::Logger = Box::new(move |status, cat, msg| {
            if let Some(cb) = logger {
                let c = CString::new(cat).unwrap_or_default();
                let m = c_message(msg);
                cb(
                    env,
                    name_owned.as_ptr(),
                    status as c_int,
                    c.as_ptr(),
                    m.as_ptr(),
                );
            }
        });
        let mut inst = Instance::new(name, Path::new(&dir), log)?;
        let want = crate::packaging::xml::token(&inst.table);
        let got = text(guid).unwrap_or("");
        if got != want {
            return Err(format!(
                "fmuGUID {got:?} does not match this binary's {want:?} (modelDescription.xml from another build or case)"
            ));
        }
        inst.set_debug_logging(logging_on != 0, vec![])
            .map_err(|e| e.1)?;
        inst.log(
            Status::Ok,
            "logEvents",
            &format!("instantiated {name:?} (FMI 2.0 co-simulation)"),
        );
        Ok(Fmu::new(inst))
    });
    match r {
        Ok(Ok(b)) => Box::into_raw(b) as Comp,
        Ok(Err(msg)) => {
            say(Status::Error, &format!("fmi2Instantiate: {msg}"));
            std::ptr::null_mut()
        }
        Err(_) => {
            say(Status::Fatal, "fmi2Instantiate: internal error");
            std::ptr::null_mut()
        }
    }
}

#[no_mangle]
pub unsafe extern "C" fn fmi2FreeInstance(p: Comp) {
    crate::abi::ffi::free_instance(p);
}

#[no_mangle]
pub unsafe extern "C" fn fmi2SetDebugLogging(
    p: Comp,
    logging_on: c_int,
    n: usize,
    categories: *const *const c_char,
) -> c_int {
    with(p, "fmi2SetDebugLogging", |f| {
        let names = crate::abi::ffi::strings(categories, n, "categories")?;
        f.inst.set_debug_logging(logging_on != 0, names)
    })
}

#[no_mangle]
pub unsafe extern "C" fn fmi2SetupExperiment(
    p: Comp,
    _tolerance_defined: c_int,
    _tolerance: f64,
    start_time: f64,
    _stop_defined: c_int,
    _stop_time: f64,
) -> c_int {
    with(p, "fmi2SetupExperiment", |f| {
        if f.inst.mode != crate::instance::Mode::Instantiated {
            return bad(format!("not allowed in state {:?}", f.inst.mode));
        }
        if !start_time.is_finite() {
            return bad(format!("startTime must be finite, got {start_time}"));
        }
        f.start_time = start_time;
        Ok(())
    })
}

#[no_mangle]
pub unsafe extern "C" fn fmi2EnterInitializationMode(p: Comp) -> c_int {
    with(p, "fmi2EnterInitializationMode", |f| {
        f.inst.enter_initialization(f.start_time)
    })
}

#[no_mangle]
pub unsafe extern "C" fn fmi2ExitInitializationMode(p: Comp) -> c_int {
    with(p, "fmi2ExitInitializationMode", |f| {
        f.inst.exit_initialization()
    })
}

#[no_mangle]
pub unsafe extern "C" fn fmi2Terminate(p: Comp) -> c_int {
    with(p, "fmi2Terminate", |f| f.inst.terminate())
}

#[no_mangle]
pub unsafe extern "C" fn fmi2Reset(p: Comp) -> c_int {
    with(p, "fmi2Reset", |f| {
        f.inst.reset();
        f.start_time = 0.0;
        Ok(())
    })
}

/// (variable, element) of FMI 2.0 reference `vr`, of kind `kind`.
fn scalar(inst: &Instance, vr: Vr, kind: Kind) -> CallResult<(usize, usize)> {
    let t = &inst.table;
    match t.fmi2.get(vr as usize) {
        Some(s) if vr != 0 && t.variables[s.variable].kind == kind => Ok((s.variable, s.element)),
        Some(s) if vr != 0 => Err((
            Status::Error,
            format!(
                "valueReference {vr} ({}) is not of type {kind:?}",
                t.fmi2_name(s)
            ),
        )),
        _ => Err((
            Status::Error,
            format!(
                "valueReference {vr}: no such variable (1..{})",
                t.fmi2.len()
            ),
        )),
    }
}

#[no_mangle]
pub unsafe extern "C" fn fmi2GetReal(
    p: Comp,
    vrs: *const Vr,
    nvr: usize,
    values: *mut f64,
) -> c_int {
    with(p, "fmi2GetReal", |f| {
        let vrs = slice(vrs, nvr).ok_or((Status::Error, "vr is NULL".into()))?;
        let out = slice_mut(values, nvr).ok_or((Status::Error, "value is NULL".into()))?;
        for (k, &vr) in vrs.iter().enumerate() {
            let (i, e) = scalar(&f.inst, vr, Kind::Float64)?;
            out[k] = f.inst.get_f64(i)?[e];
        }
        Ok(())
    })
}

#[no_mangle]
pub unsafe extern "C" fn fmi2SetReal(
    p: Comp,
    vrs: *const Vr,
    nvr: usize,
    values: *const f64,
) -> c_int {
    with(p, "fmi2SetReal", |f| {
        let vrs = slice(vrs, nvr).ok_or((Status::Error, "vr is NULL".into()))?;
        let vals = slice(values, nvr).ok_or((Status::Error, "value is NULL".into()))?;
        f.inst.atomically(|inst| {
            for (k, &vr) in vrs.iter().enumerate() {
                let (i, e) = scalar(inst, vr, Kind::Float64)?;
                inst.set_f64(i, e, &vals[k..k + 1])?;
            }
            Ok(())
        })
    })
}

#[no_mangle]
pub unsafe extern "C" fn fmi2GetInteger(
    p: Comp,
    vrs: *const Vr,
    nvr: usize,
    values: *mut c_int,
) -> c_int {
    with(p, "fmi2GetInteger", |f| {
        let vrs = slice(vrs, nvr).ok_or((Status::Error, "vr is NULL".into()))?;
        let out = slice_mut(values, nvr).ok_or((Status::Error, "value is NULL".into()))?;
        for (k, &vr) in vrs.iter().enumerate() {
            let (i, _) = scalar(&f.inst, vr, Kind::Int64)?;
            out[k] = f
                .inst
                .get_i64(i)?
                .clamp(c_int::MIN as i64, c_int::MAX as i64) as c_int;
        }
        Ok(())
    })
}

#[no_mangle]
pub unsafe extern "C" fn fmi2SetInteger(
    p: Comp,
    vrs: *const Vr,
    nvr: usize,
    values: *const c_int,
) -> c_int {
    with(p, "fmi2SetInteger", |f| {
        let vrs = slice(vrs, nvr).ok_or((Status::Error, "vr is NULL".into()))?;
        let vals = slice(values, nvr).ok_or((Status::Error, "value is NULL".into()))?;
        f.inst.atomically(|inst| {
            for (k, &vr) in vrs.iter().enumerate() {
                let (i, _) = scalar(inst, vr, Kind::Int64)?;
                inst.set_i64(i, vals[k] as i64)?;
            }
            Ok(())
        })
    })
}

#[no_mangle]
pub unsafe extern "C" fn fmi2GetBoolean(
    p: Comp,
    vrs: *const Vr,
    nvr: usize,
    _values: *mut c_int,
) -> c_int {
    with(p, "fmi2GetBoolean", |_| no_booleans(vrs, nvr))
}

#[no_mangle]
pub unsafe extern "C" fn fmi2SetBoolean(
    p: Comp,
    vrs: *const Vr,
    nvr: usize,
    _values: *const c_int,
) -> c_int {
    with(p, "fmi2SetBoolean", |_| no_booleans(vrs, nvr))
}

unsafe fn no_booleans(vrs: *const Vr, nvr: usize) -> CallResult<()> {
    match slice(vrs, nvr) {
        Some([]) => Ok(()),
        Some(v) => bad(format!(
            "valueReference {} is not a Boolean (sphfmu has none)",
            v[0]
        )),
        None => bad("vr is NULL"),
    }
}

#[no_mangle]
pub unsafe extern "C" fn fmi2GetString(
    p: Comp,
    vrs: *const Vr,
    nvr: usize,
    values: *mut *const c_char,
) -> c_int {
    with(p, "fmi2GetString", |f| {
        let vrs = slice(vrs, nvr).ok_or((Status::Error, "vr is NULL".into()))?;
        let out = slice_mut(values, nvr).ok_or((Status::Error, "value is NULL".into()))?;
        let mut values = vec![];
        for &vr in vrs {
            let (i, _) = scalar(&f.inst, vr, Kind::String)?;
            values.push(f.inst.get_string(i)?);
        }
        f.hand_out(values, out);
        Ok(())
    })
}

#[no_mangle]
pub unsafe extern "C" fn fmi2SetString(
    p: Comp,
    vrs: *const Vr,
    nvr: usize,
    values: *const *const c_char,
) -> c_int {
    with(p, "fmi2SetString", |f| {
        let vrs = slice(vrs, nvr).ok_or((Status::Error, "vr is NULL".into()))?;
        let vals = slice(values, nvr).ok_or((Status::Error, "value is NULL".into()))?;
        f.inst.atomically(|inst| {
            for (k, &vr) in vrs.iter().enumerate() {
                let (i, _) = scalar(inst, vr, Kind::String)?;
                let s = text(vals[k]).ok_or((
                    Status::Error,
                    "a string value is NULL or not UTF-8".to_string(),
                ))?;
                inst.set_string(i, s)?;
            }
            Ok(())
        })
    })
}

#[no_mangle]
pub unsafe extern "C" fn fmi2DoStep(p: Comp, current: f64, step: f64, _no_prior: c_int) -> c_int {
    with(p, "fmi2DoStep", |f| f.inst.do_step(current, step))
}

#[no_mangle]
pub unsafe extern "C" fn fmi2CancelStep(p: Comp) -> c_int {
    with(p, "fmi2CancelStep", |_| {
        bad("doStep never runs asynchronously here: nothing to cancel")
    })
}

#[no_mangle]
pub unsafe extern "C" fn fmi2GetStatus(p: Comp, kind: c_int, value: *mut c_int) -> c_int {
    with(p, "fmi2GetStatus", |_| {
        if kind != 0 || value.is_null() {
            return bad(format!(
                "status kind {kind}: only fmi2DoStepStatus (0) is an fmi2Status"
            ));
        }
        // doStep always completes before returning
        *value = Status::Ok as c_int;
        Ok(())
    })
}

#[no_mangle]
pub unsafe extern "C" fn fmi2GetRealStatus(p: Comp, kind: c_int, value: *mut f64) -> c_int {
    with(p, "fmi2GetRealStatus", |f| {
        if kind != 2 || value.is_null() {
            return bad(format!(
                "status kind {kind}: only fmi2LastSuccessfulTime (2) is Real"
            ));
        }
        *value = f.inst.time();
        Ok(())
    })
}

#[no_mangle]
pub unsafe extern "C" fn fmi2GetIntegerStatus(p: Comp, kind: c_int, _value: *mut c_int) -> c_int {
    with(p, "fmi2GetIntegerStatus", |_| {
        bad(format!("status kind {kind}: no Integer status is defined"))
    })
}

#[no_mangle]
pub unsafe extern "C" fn fmi2GetBooleanStatus(p: Comp, kind: c_int, value: *mut c_int) -> c_int {
    with(p, "fmi2GetBooleanStatus", |_| {
        if kind != 3 || value.is_null() {
            return bad(format!(
                "status kind {kind}: only fmi2Terminated (3) is Boolean"
            ));
        }
        *value = 0;
        Ok(())
    })
}

#[no_mangle]
pub unsafe extern "C" fn fmi2GetStringStatus(
    p: Comp,
    kind: c_int,
    value: *mut *const c_char,
) -> c_int {
    with(p, "fmi2GetStringStatus", |_| {
        if kind != 1 || value.is_null() {
            return bad(format!(
                "status kind {kind}: only fmi2PendingStatus (1) is a String"
            ));
        }
        *value = c"".as_ptr();
        Ok(())
    })
}

#[no_mangle]
pub unsafe extern "C" fn fmi2SetRealInputDerivatives(
    p: Comp,
    _v: *const Vr,
    _n: usize,
    _o: *const c_int,
    _x: *const f64,
) -> c_int {
    with(p, "fmi2SetRealInputDerivatives", |_| {
        bad("input derivatives are not used (inputs are held constant over a step)")
    })
}

#[no_mangle]
pub unsafe extern "C" fn fmi2GetRealOutputDerivatives(
    p: Comp,
    _v: *const Vr,
    _n: usize,
    _o: *const c_int,
    _x: *mut f64,
) -> c_int {
    with(p, "fmi2GetRealOutputDerivatives", |_| {
        bad("output derivatives are not provided")
    })
}

#[no_mangle]
pub unsafe extern "C" fn fmi2GetDirectionalDerivative(
    p: Comp,
    _u: *const Vr,
    _nu: usize,
    _k: *const Vr,
    _nk: usize,
    _dk: *const f64,
    _du: *mut f64,
) -> c_int {
    with(p, "fmi2GetDirectionalDerivative", |_| {
        bad("directional derivatives are not provided")
    })
}

// ---- FMU state (shared logic in state_ffi) ---------------------------------------------------

state_ffi::export_state_functions!(
    Comp,
    c_int,
    fmi2GetFMUstate,
    fmi2SetFMUstate,
    fmi2FreeFMUstate,
    fmi2SerializedFMUstateSize,
    fmi2SerializeFMUstate,
    fmi2DeSerializeFMUstate
);
