//! The FMU-state calls as both C faces need them (FMI 2.0 `fmi2GetFMUstate` … and FMI 3.0
//! `fmi3GetFMUState` … differ only in names): the state handle is a boxed `Snapshot`.

use crate::abi::ffi::{slice, slice_mut};
use crate::instance::inputs::Snapshot;
use crate::instance::{CallResult, Instance, Status};
use std::ffi::c_void;

fn bad<T>(msg: impl Into<String>) -> CallResult<T> {
    Err((Status::Error, msg.into()))
}

/// Save the instance into `*state` (a new handle, or the master's earlier one overwritten).
///
/// # Safety
/// `state` is NULL or points to a handle slot holding NULL or a handle from this module.
pub unsafe fn get(inst: &Instance, state: *mut *mut c_void) -> CallResult<()> {
    if state.is_null() {
        return bad("FMU state pointer is NULL");
    }
    let snap = inst.get_state()?;
    if (*state).is_null() {
        *state = Box::into_raw(Box::new(snap)) as *mut c_void;
    } else {
        *((*state) as *mut Snapshot) = snap;
    }
    Ok(())
}

/// # Safety
/// `state` is NULL or a handle from this module.
pub unsafe fn set(inst: &mut Instance, state: *mut c_void) -> CallResult<()> {
    if state.is_null() {
        return bad("FMU state is NULL");
    }
    inst.set_state(&*(state as *const Snapshot))
}

/// # Safety
/// `state` is NULL or points to NULL or a handle from this module.
pub unsafe fn free(state: *mut *mut c_void) -> CallResult<()> {
    if !state.is_null() && !(*state).is_null() {
        drop(Box::from_raw((*state) as *mut Snapshot));
        *state = std::ptr::null_mut();
    }
    Ok(())
}

/// # Safety
/// `state` is NULL or a handle from this module; `size` is NULL or writable.
pub unsafe fn size(state: *mut c_void, size: *mut usize) -> CallResult<()> {
    if state.is_null() || size.is_null() {
        return bad("FMU state or size is NULL");
    }
    *size = (*(state as *const Snapshot)).serialize().len();
    Ok(())
}

/// # Safety
/// `state` is NULL or a handle from this module; `bytes` holds `size` writable bytes.
pub unsafe fn serialize(state: *mut c_void, bytes: *mut u8, size: usize) -> CallResult<()> {
    if state.is_null() {
        return bad("FMU state is NULL");
    }
    let data = (*(state as *const Snapshot)).serialize();
    if data.len() != size {
        return bad(format!(
            "size = {size} but the state takes {} bytes",
            data.len()
        ));
    }
    slice_mut(bytes, size)
        .ok_or((Status::Error, "serializedState is NULL".to_string()))?
        .copy_from_slice(&data);
    Ok(())
}

/// # Safety
/// `bytes` holds `size` readable bytes; `state` is NULL or a writable handle slot.
pub unsafe fn deserialize(
    bytes: *const u8,
    size: usize,
    state: *mut *mut c_void,
) -> CallResult<()> {
    let data = slice(bytes, size).ok_or((Status::Error, "serializedState is NULL".to_string()))?;
    if state.is_null() {
        return bad("FMU state pointer is NULL");
    }
    let snap = Snapshot::deserialize(data).map_err(|e| (Status::Error, e))?;
    *state = Box::into_raw(Box::new(snap)) as *mut c_void;
    Ok(())
}

/// The six FMU-state entry points of one FMI version over the functions above (their names
/// differ between 2.0 and 3.0, nothing else does). Expands where `with` and `c_void` are in
/// scope, as in `fmi2.rs` and `fmi3.rs`.
macro_rules! export_state_functions {
    ($handle:ty, $ret:ty, $get:ident, $set:ident, $free:ident, $size:ident, $ser:ident, $de:ident) => {
        #[no_mangle]
        pub unsafe extern "C" fn $get(p: $handle, state: *mut *mut c_void) -> $ret {
            with(p, stringify!($get), |f| {
                $crate::abi::state_ffi::get(&f.inst, state)
            })
        }

        #[no_mangle]
        pub unsafe extern "C" fn $set(p: $handle, state: *mut c_void) -> $ret {
            with(p, stringify!($set), |f| {
                $crate::abi::state_ffi::set(&mut f.inst, state)
            })
        }

        #[no_mangle]
        pub unsafe extern "C" fn $free(p: $handle, state: *mut *mut c_void) -> $ret {
            with(p, stringify!($free), |_| {
                $crate::abi::state_ffi::free(state)
            })
        }

        #[no_mangle]
        pub unsafe extern "C" fn $size(p: $handle, state: *mut c_void, size: *mut usize) -> $ret {
            with(p, stringify!($size), |_| {
                $crate::abi::state_ffi::size(state, size)
            })
        }

        #[no_mangle]
        pub unsafe extern "C" fn $ser(
            p: $handle,
            state: *mut c_void,
            bytes: *mut u8,
            size: usize,
        ) -> $ret {
            with(p, stringify!($ser), |_| {
                $crate::abi::state_ffi::serialize(state, bytes, size)
            })
        }

        #[no_mangle]
        pub unsafe extern "C" fn $de(
            p: $handle,
            bytes: *const u8,
            size: usize,
            state: *mut *mut c_void,
        ) -> $ret {
            with(p, stringify!($de), |_| {
                $crate::abi::state_ffi::deserialize(bytes, size, state)
            })
        }
    };
}
pub(crate) use export_state_functions;
