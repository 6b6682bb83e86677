//! The FMI 3.0 C API (co-simulation). Every function fmpy resolves is exported; those of
//! model exchange, scheduled execution, clocks and configuration mode answer fmi3Error with a
//! log line saying so. Every entry point runs under `ffi::guard` (no panic crosses into the
//! master) and checks its pointers.
#![allow(non_snake_case, clippy::missing_safety_doc, clippy::too_many_arguments)]

use crate::abi::ffi::{bad, slice, slice_mut, text, with, Fmu};
use crate::abi::state_ffi;
use crate::instance::{CallResult, Instance, Status};
use crate::table::{Binding, Kind, MotionInput};
use std::ffi::{c_char, c_void, CString};
use std::path::Path;

type Inst = *mut c_void;
type Vr = u32;
type LogFn = unsafe extern "C" fn(*mut c_void, i32, *const c_char, *const c_char);

/// The Float64 variables of `vrs` and where each one's elements sit in a flat buffer of
/// `n_values` (arrays take `size` consecutive values); nValues must be their total.
fn float_spans(
    inst: &Instance,
    vrs: &[Vr],
    n_values: usize,
) -> CallResult<Vec<(usize, std::ops::Range<usize>)>> {
    let mut at = 0;
    let mut spans = Vec::with_capacity(vrs.len());
    for &vr in vrs {
        let i = inst.var3(vr, Kind::Float64)?;
        let size = inst.table.variables[i].size;
        spans.push((i, at..at + size));
        at += size;
    }
    if at != n_values {
        // a master that speaks 3-vectors may hand a 2D body a 3D angular velocity: say why
        // the variable is a scalar
        let planar: Vec<&str> = spans
            .iter()
            .map(|(i, _)| &inst.table.variables[*i])
            .filter(|v| {
                v.size == 1
                    && matches!(
                        v.binding,
                        Binding::Motion(
                            _,
                            MotionInput::AngularVelocity | MotionInput::AngularAcceleration
                        )
                    )
            })
            .map(|v| v.name.as_str())
            .collect();
        let hint = if planar.is_empty() {
            String::new()
        } else {
            format!(
                " ({} about z only: a {}D body turns about z alone, so x/y components cannot be given)",
                planar.join(", "),
                inst.table.dimension
            )
        };
        return Err((
            Status::Error,
            format!("nValues = {n_values} but the variables hold {at}{hint}"),
        ));
    }
    Ok(spans)
}

/// Value references and values of a get on scalar variables (nValues must equal nvr).
unsafe fn scalars_out<'a, T>(
    vrs: *const Vr,
    nvr: usize,
    values: *mut T,
    n_values: usize,
) -> CallResult<(&'a [Vr], &'a mut [T])> {
    let vrs = slice(vrs, nvr).ok_or((Status::Error, "valueReferences is NULL".to_string()))?;
    let out = slice_mut(values, n_values).ok_or((Status::Error, "values is NULL".to_string()))?;
    if nvr != n_values {
        return Err((
            Status::Error,
            format!("nValues = {n_values} but {nvr} scalar variables"),
        ));
    }
    Ok((vrs, out))
}

/// Value references and values of a set on scalar variables (nValues must equal nvr).
unsafe fn scalars_in<'a, T>(
    vrs: *const Vr,
    nvr: usize,
    values: *const T,
    n_values: usize,
) -> CallResult<(&'a [Vr], &'a [T])> {
    let vrs = slice(vrs, nvr).ok_or((Status::Error, "valueReferences is NULL".to_string()))?;
    let vals = slice(values, n_values).ok_or((Status::Error, "values is NULL".to_string()))?;
    if nvr != n_values {
        return Err((
            Status::Error,
            format!("nValues = {n_values} but {nvr} scalar variables"),
        ));
    }
    Ok((vrs, vals))
}

#[no_mangle]
pub extern "C" fn fmi3GetVersion() -> *const c_char {
    c"3.0".as_ptr()
}

#[no_mangle]
pub unsafe extern "C" fn fmi3SetDebugLogging(
    p: Inst,
    logging_on: bool,
    n: usize,
    categories: *const *const c_char,
) -> i32 {
    with(p, "fmi3SetDebugLogging", |f| {
        let names = crate::abi::ffi::strings(categories, n, "categories")?;
        f.inst.set_debug_logging(logging_on, names)
    })
}

unsafe fn log_now(env: *mut c_void, cb: Option<LogFn>, status: Status, msg: &str) {
    if let Some(cb) = cb {
        let m = CString::new(msg.replace('\0', " ")).unwrap_or_default();
        cb(env, status as i32, c"logStatusError".as_ptr(), m.as_ptr());
    }
}

#[no_mangle]
pub unsafe extern "C" fn fmi3InstantiateCoSimulation(
    instance_name: *const c_char,
    token: *const c_char,
    resource_path: *const c_char,
    _visible: bool,
    logging_on: bool,
    event_mode_used: bool,
    _early_return_allowed: bool,
    _required_intermediate: *const Vr,
    _n_required: usize,
    env: *mut c_void,
    log_message: Option<LogFn>,
    _intermediate_update: *mut c_void,
) -> Inst {
    let r = std::panic::catch_unwind(|| -> Result<Box<Fmu>, String> {
        let name = text(instance_name).ok_or("instanceName is NULL or not UTF-8")?;
        let res = text(resource_path)
            .ok_or("resourcePath is NULL: the FMU needs its resources folder (case files)")?;
        if event_mode_used {
            return Err("eventModeUsed: sphfmu has no event mode (it has no events)".into());
        }
        let logger: crate::instance::Logger = Box::new(move |status, cat, msg| {
            if let Some(cb) = log_message {
                let c = CString::new(cat).unwrap_or_default();
                let m = CString::new(msg.replace('\0', " ")).unwrap_or_default();
                cb(env, status as i32, c.as_ptr(), m.as_ptr());
            }
        });
        let mut inst = Instance::new(name, Path::new(res), logger)?;
        let want = crate::packaging::xml::token(&inst.table);
        let got = text(token).unwrap_or("");
        if got != want {
            return Err(format!(
                "instantiationToken {got:?} does not match this binary's {want:?} (modelDescription.xml from another build or case)"
            ));
        }
        inst.set_debug_logging(logging_on, vec![])
            .map_err(|e| e.1)?;
        inst.log(
            Status::Ok,
            "logEvents",
            &format!("instantiated {name:?} (FMI 3.0 co-simulation)"),
        );
        Ok(Fmu::new(inst))
    });
    match r {
        Ok(Ok(b)) => Box::into_raw(b) as Inst,
        Ok(Err(msg)) => {
            log_now(
                env,
                log_message,
                Status::Error,
                &format!("fmi3InstantiateCoSimulation: {msg}"),
            );
            std::ptr::null_mut()
        }
        Err(_) => {
            log_now(
                env,
                log_message,
                Status::Fatal,
                "fmi3InstantiateCoSimulation: internal error",
            );
            std::ptr::null_mut()
        }
    }
}

#[no_mangle]
pub unsafe extern "C" fn fmi3InstantiateModelExchange(
    _name: *const c_char,
    _token: *const c_char,
    _res: *const c_char,
    _visible: bool,
    _logging_on: bool,
    env: *mut c_void,
    log_message: Option<LogFn>,
) -> Inst {
    log_now(
        env,
        log_message,
        Status::Error,
        "fmi3InstantiateModelExchange: sphfmu is a co-simulation FMU only",
    );
    std::ptr::null_mut()
}

#[no_mangle]
pub unsafe extern "C" fn fmi3InstantiateScheduledExecution(
    _name: *const c_char,
    _token: *const c_char,
    _res: *const c_char,
    _visible: bool,
    _logging_on: bool,
    env: *mut c_void,
    log_message: Option<LogFn>,
    _clock_update: *mut c_void,
    _lock: *mut c_void,
    _unlock: *mut c_void,
) -> Inst {
    log_now(
        env,
        log_message,
        Status::Error,
        "fmi3InstantiateScheduledExecution: sphfmu is a co-simulation FMU only",
    );
    std::ptr::null_mut()
}

#[no_mangle]
pub unsafe extern "C" fn fmi3FreeInstance(p: Inst) {
    crate::abi::ffi::free_instance(p);
}

#[no_mangle]
pub unsafe extern "C" fn fmi3EnterInitializationMode(
    p: Inst,
    _tolerance_defined: bool,
    _tolerance: f64,
    start_time: f64,
    _stop_time_defined: bool,
    _stop_time: f64,
) -> i32 {
    with(p, "fmi3EnterInitializationMode", |f| {
        f.inst.enter_initialization(start_time)
    })
}

#[no_mangle]
pub unsafe extern "C" fn fmi3ExitInitializationMode(p: Inst) -> i32 {
    with(p, "fmi3ExitInitializationMode", |f| {
        f.inst.exit_initialization()
    })
}

#[no_mangle]
pub unsafe extern "C" fn fmi3Terminate(p: Inst) -> i32 {
    with(p, "fmi3Terminate", |f| f.inst.terminate())
}

#[no_mangle]
pub unsafe extern "C" fn fmi3Reset(p: Inst) -> i32 {
    with(p, "fmi3Reset", |f| {
        f.inst.reset();
        Ok(())
    })
}

#[no_mangle]
pub unsafe extern "C" fn fmi3DoStep(
    p: Inst,
    current: f64,
    step: f64,
    _no_set_state_prior: bool,
    event_handling_needed: *mut bool,
    terminate_simulation: *mut bool,
    early_return: *mut bool,
    last_successful_time: *mut f64,
) -> i32 {
    with(p, "fmi3DoStep", |f| {
        let r = f.inst.do_step(current, step);
        for b in [event_handling_needed, terminate_simulation, early_return] {
            if !b.is_null() {
                *b = false;
            }
        }
        if !last_successful_time.is_null() {
            *last_successful_time = f.inst.time();
        }
        r
    })
}

// ---- values --------------------------------------------------------------------------------

#[no_mangle]
pub unsafe extern "C" fn fmi3GetFloat64(
    p: Inst,
    vrs: *const Vr,
    nvr: usize,
    values: *mut f64,
    n_values: usize,
) -> i32 {
    with(p, "fmi3GetFloat64", |f| {
        let vrs = slice(vrs, nvr).ok_or((Status::Error, "valueReferences is NULL".into()))?;
        let out = slice_mut(values, n_values).ok_or((Status::Error, "values is NULL".into()))?;
        for (i, span) in float_spans(&f.inst, vrs, n_values)? {
            out[span].copy_from_slice(&f.inst.get_f64(i)?);
        }
        Ok(())
    })
}

#[no_mangle]
pub unsafe extern "C" fn fmi3SetFloat64(
    p: Inst,
    vrs: *const Vr,
    nvr: usize,
    values: *const f64,
    n_values: usize,
) -> i32 {
    with(p, "fmi3SetFloat64", |f| {
        let vrs = slice(vrs, nvr).ok_or((Status::Error, "valueReferences is NULL".into()))?;
        let vals = slice(values, n_values).ok_or((Status::Error, "values is NULL".into()))?;
        f.inst.atomically(|inst| {
            for (i, span) in float_spans(inst, vrs, n_values)? {
                inst.set_f64(i, 0, &vals[span])?;
            }
            Ok(())
        })
    })
}

#[no_mangle]
pub unsafe extern "C" fn fmi3GetInt64(
    p: Inst,
    vrs: *const Vr,
    nvr: usize,
    values: *mut i64,
    n_values: usize,
) -> i32 {
    with(p, "fmi3GetInt64", |f| {
        let (vrs, out) = scalars_out(vrs, nvr, values, n_values)?;
        for (k, &vr) in vrs.iter().enumerate() {
            let i = f.inst.var3(vr, Kind::Int64)?;
            out[k] = f.inst.get_i64(i)?;
        }
        Ok(())
    })
}

#[no_mangle]
pub unsafe extern "C" fn fmi3SetInt64(
    p: Inst,
    vrs: *const Vr,
    nvr: usize,
    values: *const i64,
    n_values: usize,
) -> i32 {
    with(p, "fmi3SetInt64", |f| {
        let (vrs, vals) = scalars_in(vrs, nvr, values, n_values)?;
        f.inst.atomically(|inst| {
            for (k, &vr) in vrs.iter().enumerate() {
                let i = inst.var3(vr, Kind::Int64)?;
                inst.set_i64(i, vals[k])?;
            }
            Ok(())
        })
    })
}

#[no_mangle]
pub unsafe extern "C" fn fmi3GetString(
    p: Inst,
    vrs: *const Vr,
    nvr: usize,
    values: *mut *const c_char,
    n_values: usize,
) -> i32 {
    with(p, "fmi3GetString", |f| {
        let (vrs, out) = scalars_out(vrs, nvr, values, n_values)?;
        let mut values = vec![];
        for &vr in vrs {
            let i = f.inst.var3(vr, Kind::String)?;
            values.push(f.inst.get_string(i)?);
        }
        f.hand_out(values, out);
        Ok(())
    })
}

#[no_mangle]
pub unsafe extern "C" fn fmi3SetString(
    p: Inst,
    vrs: *const Vr,
    nvr: usize,
    values: *const *const c_char,
    n_values: usize,
) -> i32 {
    with(p, "fmi3SetString", |f| {
        let (vrs, vals) = scalars_in(vrs, nvr, values, n_values)?;
        f.inst.atomically(|inst| {
            for (k, &vr) in vrs.iter().enumerate() {
                let i = inst.var3(vr, Kind::String)?;
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

/// Getters and setters of types sphfmu has no variables of: fine for zero references, an
/// error naming the reference otherwise.
macro_rules! no_variables_of_type {
    ($($get:ident, $set:ident, $t:ty);* $(;)?) => {$(
        #[no_mangle]
        pub unsafe extern "C" fn $get(p: Inst, vrs: *const Vr, nvr: usize, _values: *mut $t, _n: usize) -> i32 {
            with(p, stringify!($get), |_| none_of_type(vrs, nvr))
        }
        #[no_mangle]
        pub unsafe extern "C" fn $set(p: Inst, vrs: *const Vr, nvr: usize, _values: *const $t, _n: usize) -> i32 {
            with(p, stringify!($set), |_| none_of_type(vrs, nvr))
        }
    )*};
}

unsafe fn none_of_type(vrs: *const Vr, nvr: usize) -> CallResult<()> {
    match slice(vrs, nvr) {
        Some([]) => Ok(()),
        Some(v) => bad(format!(
            "valueReference {} is not a variable of this type",
            v[0]
        )),
        None => bad("valueReferences is NULL"),
    }
}

no_variables_of_type! {
    fmi3GetFloat32, fmi3SetFloat32, f32;
    fmi3GetInt8, fmi3SetInt8, i8;
    fmi3GetUInt8, fmi3SetUInt8, u8;
    fmi3GetInt16, fmi3SetInt16, i16;
    fmi3GetUInt16, fmi3SetUInt16, u16;
    fmi3GetInt32, fmi3SetInt32, i32;
    fmi3GetUInt32, fmi3SetUInt32, u32;
    fmi3GetUInt64, fmi3SetUInt64, u64;
    fmi3GetBoolean, fmi3SetBoolean, bool;
}

#[no_mangle]
pub unsafe extern "C" fn fmi3GetBinary(
    p: Inst,
    vrs: *const Vr,
    nvr: usize,
    _sizes: *mut usize,
    _values: *mut *const u8,
    _n: usize,
) -> i32 {
    with(p, "fmi3GetBinary", |_| none_of_type(vrs, nvr))
}

#[no_mangle]
pub unsafe extern "C" fn fmi3SetBinary(
    p: Inst,
    vrs: *const Vr,
    nvr: usize,
    _sizes: *const usize,
    _values: *const *const u8,
    _n: usize,
) -> i32 {
    with(p, "fmi3SetBinary", |_| none_of_type(vrs, nvr))
}

#[no_mangle]
pub unsafe extern "C" fn fmi3GetClock(p: Inst, vrs: *const Vr, nvr: usize, _v: *mut bool) -> i32 {
    with(p, "fmi3GetClock", |_| none_of_type(vrs, nvr))
}

#[no_mangle]
pub unsafe extern "C" fn fmi3SetClock(p: Inst, vrs: *const Vr, nvr: usize, _v: *const bool) -> i32 {
    with(p, "fmi3SetClock", |_| none_of_type(vrs, nvr))
}

// ---- FMU state (shared logic in state_ffi) ---------------------------------------------------

state_ffi::export_state_functions!(
    Inst,
    i32,
    fmi3GetFMUState,
    fmi3SetFMUState,
    fmi3FreeFMUState,
    fmi3SerializedFMUStateSize,
    fmi3SerializeFMUState,
    fmi3DeserializeFMUState
);

// ---- what a co-simulation FMU without events, clocks or structural parameters lacks ------

macro_rules! unsupported {
    ($($name:ident ( $($arg:ident : $t:ty),* ) => $why:expr;)*) => {$(
        #[no_mangle]
        pub unsafe extern "C" fn $name(p: Inst $(, $arg: $t)*) -> i32 {
            $(let _ = $arg;)*
            with(p, stringify!($name), |_| bad($why))
        }
    )*};
}

const ME: &str = "model exchange is not supported (co-simulation FMU)";
const CLOCKS: &str = "sphfmu has no clocks";

unsupported! {
    fmi3EnterEventMode() => "sphfmu has no event mode";
    fmi3EnterStepMode() => "no event mode: the FMU is in step mode after initialisation";
    fmi3EnterConfigurationMode() => "sphfmu has no structural parameters";
    fmi3ExitConfigurationMode() => "sphfmu has no structural parameters";
    fmi3GetNumberOfVariableDependencies(_vr: Vr, _n: *mut usize) => "dependencies are not provided (outputs depend on all inputs)";
    fmi3GetVariableDependencies(_d: Vr, _e: *mut usize, _i: *mut Vr, _ei: *mut usize, _k: *mut i32, _n: usize) => "dependencies are not provided (outputs depend on all inputs)";
    fmi3GetDirectionalDerivative(_u: *const Vr, _nu: usize, _k: *const Vr, _nk: usize, _s: *const f64, _ns: usize, _o: *mut f64, _no: usize) => "directional derivatives are not provided";
    fmi3GetAdjointDerivative(_u: *const Vr, _nu: usize, _k: *const Vr, _nk: usize, _s: *const f64, _ns: usize, _o: *mut f64, _no: usize) => "adjoint derivatives are not provided";
    fmi3GetOutputDerivatives(_v: *const Vr, _nv: usize, _o: *const i32, _x: *mut f64, _n: usize) => "output derivatives are not provided";
    fmi3GetIntervalDecimal(_v: *const Vr, _n: usize, _i: *mut f64, _q: *mut i32) => CLOCKS;
    fmi3GetIntervalFraction(_v: *const Vr, _n: usize, _c: *mut u64, _r: *mut u64, _q: *mut i32) => CLOCKS;
    fmi3GetShiftDecimal(_v: *const Vr, _n: usize, _s: *mut f64) => CLOCKS;
    fmi3GetShiftFraction(_v: *const Vr, _n: usize, _c: *mut u64, _r: *mut u64) => CLOCKS;
    fmi3SetIntervalDecimal(_v: *const Vr, _n: usize, _i: *const f64) => CLOCKS;
    fmi3SetIntervalFraction(_v: *const Vr, _n: usize, _c: *const u64, _r: *const u64) => CLOCKS;
    fmi3SetShiftDecimal(_v: *const Vr, _n: usize, _s: *const f64) => CLOCKS;
    fmi3SetShiftFraction(_v: *const Vr, _n: usize, _c: *const u64, _r: *const u64) => CLOCKS;
    fmi3EvaluateDiscreteStates() => CLOCKS;
    fmi3UpdateDiscreteStates(_a: *mut bool, _b: *mut bool, _c: *mut bool, _d: *mut bool, _e: *mut bool, _t: *mut f64) => "sphfmu has no event mode";
    fmi3EnterContinuousTimeMode() => ME;
    fmi3CompletedIntegratorStep(_n: bool, _e: *mut bool, _t: *mut bool) => ME;
    fmi3SetTime(_t: f64) => ME;
    fmi3SetContinuousStates(_x: *const f64, _n: usize) => ME;
    fmi3GetContinuousStateDerivatives(_x: *mut f64, _n: usize) => ME;
    fmi3GetEventIndicators(_x: *mut f64, _n: usize) => ME;
    fmi3GetContinuousStates(_x: *mut f64, _n: usize) => ME;
    fmi3GetNominalsOfContinuousStates(_x: *mut f64, _n: usize) => ME;
    fmi3GetNumberOfEventIndicators(_n: *mut usize) => ME;
    fmi3GetNumberOfContinuousStates(_n: *mut usize) => ME;
    fmi3ActivateModelPartition(_c: Vr, _t: f64) => "scheduled execution is not supported (co-simulation FMU)";
}
