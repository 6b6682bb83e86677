//! What both C faces share: panic containment and C strings.

use crate::instance::{CallResult, Instance, Status};
use std::ffi::{c_char, c_int, CStr, CString};
use std::panic::{catch_unwind, AssertUnwindSafe};

/// Run `f`; a panic becomes `Fatal` instead of unwinding into the master (which would abort
/// its process).
pub fn guard(f: impl FnOnce() -> Status) -> Status {
    catch_unwind(AssertUnwindSafe(f)).unwrap_or(Status::Fatal)
}

/// A C string argument, or None for NULL / invalid UTF-8.
///
/// # Safety
/// `p` is NULL or points to a NUL-terminated string.
pub unsafe fn text<'a>(p: *const c_char) -> Option<&'a str> {
    if p.is_null() {
        None
    } else {
        CStr::from_ptr(p).to_str().ok()
    }
}

/// Turn a file URI (FMI 2.0 `fmuResourceLocation`) into a path: `file:///a/b`,
/// `file:/a/b`, `file://localhost/a/b`, with %XX escapes.
pub fn uri_to_path(uri: &str) -> Option<String> {
    let rest = uri.strip_prefix("file:")?;
    let rest = rest
        .strip_prefix("//localhost")
        .or_else(|| rest.strip_prefix("//"))
        .unwrap_or(rest);
    let mut out = Vec::new();
    let b = rest.as_bytes();
    let mut i = 0;
    while i < b.len() {
        if b[i] == b'%' && i + 2 < b.len() {
            let hex = std::str::from_utf8(&b[i + 1..i + 3]).ok()?;
            out.push(u8::from_str_radix(hex, 16).ok()?);
            i += 3;
        } else {
            out.push(b[i]);
            i += 1;
        }
    }
    String::from_utf8(out).ok()
}

/// A slice from a C array (empty for n = 0, whatever the pointer).
///
/// # Safety
/// `p` points to `n` valid elements when n > 0.
pub unsafe fn slice<'a, T>(p: *const T, n: usize) -> Option<&'a [T]> {
    if n == 0 {
        Some(&[])
    } else if p.is_null() {
        None
    } else {
        Some(std::slice::from_raw_parts(p, n))
    }
}

/// # Safety
/// `p` points to `n` writable elements when n > 0.
pub unsafe fn slice_mut<'a, T>(p: *mut T, n: usize) -> Option<&'a mut [T]> {
    if n == 0 {
        Some(&mut [])
    } else if p.is_null() {
        None
    } else {
        Some(std::slice::from_raw_parts_mut(p, n))
    }
}

/// What a C handle of either FMI version points to: the instance and what the C face keeps
/// beside it.
pub struct Fmu {
    pub inst: Instance,
    /// FMI 2.0's setupExperiment start time (FMI 3.0 passes it to enterInitializationMode).
    pub start_time: f64,
    /// Strings handed out by the string getters stay valid until the next call.
    pub strings: Vec<CString>,
}

impl Fmu {
    pub fn new(inst: Instance) -> Box<Fmu> {
        Box::new(Fmu {
            inst,
            start_time: 0.0,
            strings: vec![],
        })
    }

    /// Point `out` at C copies of `values`, kept until the next call.
    pub fn hand_out(&mut self, values: Vec<String>, out: &mut [*const c_char]) {
        self.strings = values
            .into_iter()
            .map(|s| CString::new(s).unwrap_or_default())
            .collect();
        for (o, s) in out.iter_mut().zip(&self.strings) {
            *o = s.as_ptr();
        }
    }
}

/// A rejected call with status Error.
pub fn bad(msg: impl Into<String>) -> CallResult<()> {
    Err((Status::Error, msg.into()))
}

/// Run `f` on the `Fmu` behind the handle `p` (NULL: Error); a rejected call is logged in
/// `logStatusError` / `logStatusWarning` with the C function's name and becomes its status;
/// a panic becomes Fatal. (fmi2Status and fmi3Status are both C ints with the same codes.)
///
/// # Safety
/// `p` is NULL or a handle made by this crate.
pub unsafe fn with(
    p: *mut std::ffi::c_void,
    call: &str,
    f: impl FnOnce(&mut Fmu) -> CallResult<()>,
) -> c_int {
    if p.is_null() {
        return Status::Error as c_int;
    }
    let h = &mut *(p as *mut Fmu);
    guard(|| match f(h) {
        Ok(()) => Status::Ok,
        Err((status, msg)) => {
            let cat = if status >= Status::Error {
                "logStatusError"
            } else {
                "logStatusWarning"
            };
            h.inst.log(status, cat, &format!("{call}: {msg}"));
            status
        }
    }) as c_int
}

/// A C array of `n` strings (`what` names it in the error).
///
/// # Safety
/// `p` points to `n` pointers, each NULL or to a NUL-terminated string, when n > 0.
pub unsafe fn strings(p: *const *const c_char, n: usize, what: &str) -> CallResult<Vec<String>> {
    let items = slice(p, n).ok_or((Status::Error, format!("{what} is NULL")))?;
    items
        .iter()
        .map(|&c| {
            text(c).map(str::to_string).ok_or((
                Status::Error,
                format!("one of the {what} is NULL or not UTF-8"),
            ))
        })
        .collect()
}

/// Drop the instance behind a handle (NULL: nothing), panic-safe.
///
/// # Safety
/// `p` is NULL or a handle made by this crate, not used afterwards.
pub unsafe fn free_instance(p: *mut std::ffi::c_void) {
    if !p.is_null() {
        let _ = std::panic::catch_unwind(|| drop(Box::from_raw(p as *mut Fmu)));
    }
}
