//! What the FMI 3 and FMI 2 entry points share: the handle an importer
//! holds, status codes, reading C arrays, and the guard that keeps every
//! error and panic inside the library, turned into a status and a logged
//! message (FMI 3.0 §2.2.4, FMI 2.0.4 §2.1.5: an error is reported by the
//! status and the logger, never by unwinding into the importer).

use crate::instance::{Instance, Mode};
use std::ffi::{CStr, CString, c_char, c_void};
use std::panic::{AssertUnwindSafe, catch_unwind};

/// `fmi3Status` / `fmi2Status`: the same codes in both versions.
pub type Status = i32;
pub const OK: Status = 0;
pub const WARNING: Status = 1;
pub const DISCARD: Status = 2;
pub const ERROR: Status = 3;
pub const FATAL: Status = 4;

/// Hands a message to the importer's logger.
pub trait Log {
    fn log(&self, name: &CStr, status: Status, category: &str, message: &str);
}

/// What the importer's instance pointer points to.
pub struct Handle<L: Log> {
    pub instance: Instance,
    pub name: CString,
    pub logger: L,
    pub logging_on: bool,
}

impl<L: Log> Handle<L> {
    pub fn log(&self, status: Status, message: &str) {
        let category = match status {
            OK => "logEvents",
            WARNING => "logStatusWarning",
            DISCARD => "logStatusDiscard",
            ERROR => "logStatusError",
            _ => "logStatusFatal",
        };
        if status != OK || self.logging_on {
            self.logger.log(&self.name, status, category, message);
        }
    }
}

/// Runs `f` on the instance behind `handle`: `OK` when it succeeds, else
/// the message logged (prefixed by `what`) and `ERROR`; a panic is caught,
/// logged, leaves the instance failed and returns `FATAL`.
pub fn guard<L: Log>(handle: *mut c_void, what: &str, f: impl FnOnce(&mut Handle<L>) -> Result<(), String>) -> Status {
    if handle.is_null() {
        return ERROR;
    }
    // SAFETY: a non-null instance pointer is one this library returned
    // from instantiation and the importer has not freed (the FMI contract).
    let h = unsafe { &mut *handle.cast::<Handle<L>>() };
    match catch_unwind(AssertUnwindSafe(|| f(h))) {
        Ok(Ok(())) => OK,
        Ok(Err(message)) => {
            h.log(ERROR, &format!("{what}: {message}"));
            ERROR
        }
        Err(panic) => {
            h.instance.mode = Mode::Failed;
            let why = panic
                .downcast_ref::<String>()
                .map(String::as_str)
                .or_else(|| panic.downcast_ref::<&str>().copied())
                .unwrap_or("a panic");
            h.log(FATAL, &format!("{what}: internal error ({why}); the instance cannot go on"));
            FATAL
        }
    }
}

/// The C array `p` of `n` items as a slice (empty when `n` is 0).
///
/// # Safety
/// `p` points to `n` readable items, or `n` is 0.
pub unsafe fn slice<'a, T>(p: *const T, n: usize) -> Result<&'a [T], String> {
    match (p.is_null(), n) {
        (_, 0) => Ok(&[]),
        (true, _) => Err(format!("a null array of {n} item(s)")),
        // SAFETY: the caller's promise.
        (false, _) => Ok(unsafe { std::slice::from_raw_parts(p, n) }),
    }
}

/// The C array `p` of `n` items, to write.
///
/// # Safety
/// `p` points to `n` writable items, or `n` is 0.
pub unsafe fn slice_mut<'a, T>(p: *mut T, n: usize) -> Result<&'a mut [T], String> {
    match (p.is_null(), n) {
        (_, 0) => Ok(&mut []),
        (true, _) => Err(format!("a null array of {n} item(s)")),
        // SAFETY: the caller's promise.
        (false, _) => Ok(unsafe { std::slice::from_raw_parts_mut(p, n) }),
    }
}

/// Writes `value` through the importer's out-parameter `p`.
///
/// # Safety
/// `p` is null (an error) or points to a writable `T`.
pub unsafe fn write_out<T>(p: *mut T, value: T) -> Result<(), String> {
    if p.is_null() {
        return Err("a null out-parameter".to_string());
    }
    // SAFETY: the caller's promise.
    unsafe { *p = value };
    Ok(())
}

/// The C string `p` (empty when null or not UTF-8).
///
/// # Safety
/// `p` is null or a NUL-terminated string.
pub unsafe fn text<'a>(p: *const c_char) -> &'a str {
    if p.is_null() {
        return "";
    }
    // SAFETY: the caller's promise.
    unsafe { CStr::from_ptr(p) }.to_str().unwrap_or("")
}

/// A message as a C string (interior NULs replaced).
pub fn c_string(message: &str) -> CString {
    CString::new(message.replace('\0', " ")).unwrap_or_default()
}

/// Saves the instance's state into a new boxed state, or into `*state`
/// when it points to one already (the FMI rule: a non-null state is
/// overwritten, not leaked).
///
/// # Safety
/// `state` is null or points to a state pointer this library made (or null).
pub unsafe fn get_state<L: Log>(h: &mut Handle<L>, state: *mut *mut c_void) -> Result<(), String> {
    if state.is_null() {
        return Err("a null state pointer".to_string());
    }
    let saved = h.instance.save();
    // SAFETY: the caller's promise.
    let slot = unsafe { &mut *state };
    if slot.is_null() {
        *slot = Box::into_raw(Box::new(saved)).cast();
    } else {
        // SAFETY: a non-null state is one of this library's.
        unsafe { *slot.cast::<crate::replay::Saved>() = saved };
    }
    Ok(())
}

/// The state behind a state pointer.
///
/// # Safety
/// `state` is null or a state pointer this library made and did not free.
pub unsafe fn state_ref<'a>(state: *mut c_void) -> Result<&'a crate::replay::Saved, String> {
    if state.is_null() {
        return Err("a null state".to_string());
    }
    // SAFETY: the caller's promise.
    Ok(unsafe { &*state.cast::<crate::replay::Saved>() })
}

/// Frees the state `*state` points to and nulls it.
///
/// # Safety
/// As [`state_ref`], for `*state`.
pub unsafe fn free_state(state: *mut *mut c_void) {
    if state.is_null() {
        return;
    }
    // SAFETY: the caller's promise.
    let slot = unsafe { &mut *state };
    if !slot.is_null() {
        // SAFETY: made by `Box::into_raw` in `get_state` or deserialisation.
        drop(unsafe { Box::from_raw(slot.cast::<crate::replay::Saved>()) });
        *slot = std::ptr::null_mut();
    }
}

/// Writes `saved` serialised into the importer's buffer of `size` bytes.
///
/// # Safety
/// `out` points to `size` writable bytes.
pub unsafe fn serialize_into(bytes: &[u8], out: *mut u8, size: usize) -> Result<(), String> {
    if size < bytes.len() {
        return Err(format!("the buffer holds {size} bytes, the state needs {}", bytes.len()));
    }
    // SAFETY: the caller's promise.
    let out = unsafe { slice_mut(out, bytes.len()) }?;
    out.copy_from_slice(bytes);
    Ok(())
}
