//! The FMI 2.0 C functions (FMI 2.0.4 standard, §2.1 common, §4
//! co-simulation), declared as `fmi2Functions.h` declares them: a
//! co-simulation FMU with `Real` variables only, vectors as `name[k]`
//! scalars. Model exchange and the other types return `fmi2Error` with a
//! message. Exported unmangled only with the `symbols` feature.

#![allow(non_snake_case, clippy::missing_safety_doc)]

use crate::ffi::{self, ERROR, Handle, Log, OK, Status, guard, slice, slice_mut, text, write_out};
use crate::instance::Instance;
use crate::replay::Saved;
use crate::table::Version;
use std::ffi::{CStr, c_char, c_int, c_void};
use std::path::PathBuf;

type Component = *mut c_void;
type Env = *mut c_void;
type Vr = u32;
type Boolean = c_int;
/// `fmi2CallbackLogger`: printf-like, so the message goes in as `%s`.
type LoggerFn = Option<unsafe extern "C" fn(Env, *const c_char, Status, *const c_char, *const c_char, ...)>;

/// `fmi2CallbackFunctions`.
#[repr(C)]
pub struct CallbackFunctions {
    pub logger: LoggerFn,
    pub allocate_memory: *const c_void,
    pub free_memory: *const c_void,
    pub step_finished: *const c_void,
    pub component_environment: Env,
}

pub struct Logger {
    callback: LoggerFn,
    env: Env,
}

impl Log for Logger {
    fn log(&self, name: &CStr, status: Status, category: &str, message: &str) {
        if let Some(cb) = self.callback {
            let (category, message) = (ffi::c_string(category), ffi::c_string(message));
            // SAFETY: the importer's callback; the message is an argument
            // of the format "%s", never a format itself.
            unsafe { cb(self.env, name.as_ptr(), status, category.as_ptr(), c"%s".as_ptr(), message.as_ptr()) };
        }
    }
}

fn with(c: Component, what: &str, f: impl FnOnce(&mut Handle<Logger>) -> Result<(), String>) -> Status {
    guard::<Logger>(c, what, f)
}

/// The folder a `file:` URI names (FMI 2.0.4 §2.1.5: `fmuResourceLocation`).
fn resource_folder(uri: &str) -> Result<PathBuf, String> {
    let rest = uri
        .strip_prefix("file://")
        .or_else(|| uri.strip_prefix("file:"))
        .ok_or_else(|| format!("fmuResourceLocation `{uri}` is not a file: URI"))?;
    // `file:///path` and `file://localhost/path` name the path; `file:/path` too.
    let path = rest.strip_prefix("localhost").unwrap_or(rest);
    let mut bytes = Vec::with_capacity(path.len());
    let raw = path.as_bytes();
    let mut i = 0;
    while i < raw.len() {
        let hex = |b: u8| (b as char).to_digit(16);
        match (raw[i], raw.get(i + 1).copied().and_then(hex), raw.get(i + 2).copied().and_then(hex)) {
            (b'%', Some(h), Some(l)) => {
                bytes.push((h * 16 + l) as u8);
                i += 3;
            }
            (b, ..) => {
                bytes.push(b);
                i += 1;
            }
        }
    }
    String::from_utf8(bytes).map(PathBuf::from).map_err(|_| format!("fmuResourceLocation `{uri}` is not UTF-8"))
}

#[cfg_attr(feature = "symbols", unsafe(no_mangle))]
pub extern "C" fn fmi2GetTypesPlatform() -> *const c_char {
    c"default".as_ptr()
}

#[cfg_attr(feature = "symbols", unsafe(no_mangle))]
pub extern "C" fn fmi2GetVersion() -> *const c_char {
    c"2.0".as_ptr()
}

#[cfg_attr(feature = "symbols", unsafe(no_mangle))]
pub extern "C" fn fmi2SetDebugLogging(
    c: Component,
    on: Boolean,
    _n: usize,
    _categories: *const *const c_char,
) -> Status {
    with(c, "fmi2SetDebugLogging", |h| {
        h.logging_on = on != 0;
        Ok(())
    })
}

#[cfg_attr(feature = "symbols", unsafe(no_mangle))]
pub unsafe extern "C" fn fmi2Instantiate(
    name: *const c_char,
    kind: c_int,
    guid: *const c_char,
    resource_location: *const c_char,
    functions: *const CallbackFunctions,
    _visible: Boolean,
    logging_on: Boolean,
) -> Component {
    // SAFETY: the importer passes NUL-terminated strings (or null) and its
    // callback functions (or null).
    let (name, guid, location) = unsafe { (text(name), text(guid), text(resource_location)) };
    let logger = match unsafe { functions.as_ref() } {
        Some(f) => Logger { callback: f.logger, env: f.component_environment },
        None => Logger { callback: None, env: std::ptr::null_mut() },
    };
    let c_name = ffi::c_string(name);
    const CO_SIMULATION: c_int = 1;
    let made = std::panic::catch_unwind(|| {
        if kind != CO_SIMULATION {
            return Err("a ctlgraph FMU is for co-simulation only (fmuType fmi2CoSimulation)".to_string());
        }
        Instance::new(&resource_folder(location)?, guid, Version::Fmi2)
    });
    match made {
        Ok(Ok(instance)) => {
            Box::into_raw(Box::new(Handle { instance, name: c_name, logger, logging_on: logging_on != 0 })).cast()
        }
        Ok(Err(message)) => {
            logger.log(&c_name, ERROR, "logStatusError", &format!("fmi2Instantiate: {message}"));
            std::ptr::null_mut()
        }
        Err(_) => {
            logger.log(&c_name, ffi::FATAL, "logStatusFatal", "fmi2Instantiate: internal error");
            std::ptr::null_mut()
        }
    }
}

#[cfg_attr(feature = "symbols", unsafe(no_mangle))]
pub unsafe extern "C" fn fmi2FreeInstance(c: Component) {
    if !c.is_null() {
        // SAFETY: made by `Box::into_raw` at instantiation; freed once.
        let handle = unsafe { Box::from_raw(c.cast::<Handle<Logger>>()) };
        let _ = std::panic::catch_unwind(std::panic::AssertUnwindSafe(|| drop(handle)));
    }
}

#[cfg_attr(feature = "symbols", unsafe(no_mangle))]
pub extern "C" fn fmi2SetupExperiment(
    c: Component,
    _tolerance_defined: Boolean,
    _tolerance: f64,
    start: f64,
    stop_defined: Boolean,
    stop: f64,
) -> Status {
    with(c, "fmi2SetupExperiment", |h| h.instance.setup_experiment(start, (stop_defined != 0).then_some(stop)))
}

#[cfg_attr(feature = "symbols", unsafe(no_mangle))]
pub extern "C" fn fmi2EnterInitializationMode(c: Component) -> Status {
    with(c, "fmi2EnterInitializationMode", |h| h.instance.enter_initialization())
}

#[cfg_attr(feature = "symbols", unsafe(no_mangle))]
pub extern "C" fn fmi2ExitInitializationMode(c: Component) -> Status {
    with(c, "fmi2ExitInitializationMode", |h| h.instance.exit_initialization())
}

#[cfg_attr(feature = "symbols", unsafe(no_mangle))]
pub extern "C" fn fmi2Terminate(c: Component) -> Status {
    with(c, "fmi2Terminate", |h| h.instance.terminate())
}

#[cfg_attr(feature = "symbols", unsafe(no_mangle))]
pub extern "C" fn fmi2Reset(c: Component) -> Status {
    with(c, "fmi2Reset", |h| {
        h.instance.reset();
        Ok(())
    })
}

#[cfg_attr(feature = "symbols", unsafe(no_mangle))]
pub unsafe extern "C" fn fmi2GetReal(c: Component, vr: *const Vr, nvr: usize, values: *mut f64) -> Status {
    with(c, "fmi2GetReal", |h| {
        // SAFETY: the importer's arrays of `nvr` items.
        let (vr, values) = unsafe { (slice(vr, nvr)?, slice_mut(values, nvr)?) };
        h.instance.get(vr, values)
    })
}

#[cfg_attr(feature = "symbols", unsafe(no_mangle))]
pub unsafe extern "C" fn fmi2SetReal(c: Component, vr: *const Vr, nvr: usize, values: *const f64) -> Status {
    with(c, "fmi2SetReal", |h| {
        // SAFETY: as above.
        let (vr, values) = unsafe { (slice(vr, nvr)?, slice(values, nvr)?) };
        h.instance.set(vr, values)
    })
}

#[cfg_attr(feature = "symbols", unsafe(no_mangle))]
pub extern "C" fn fmi2DoStep(c: Component, t: f64, h: f64, _no_set_prior: Boolean) -> Status {
    with(c, "fmi2DoStep", |handle| handle.instance.do_step(t, h).map(|_| ()))
}

#[cfg_attr(feature = "symbols", unsafe(no_mangle))]
pub extern "C" fn fmi2CancelStep(c: Component) -> Status {
    // Steps complete before `fmi2DoStep` returns: nothing is pending.
    with(c, "fmi2CancelStep", |_| Err("no step is pending (doStep runs to completion)".to_string()))
}

/// `fmi2StatusKind`.
const LAST_SUCCESSFUL_TIME: c_int = 2;
const TERMINATED: c_int = 3;

#[cfg_attr(feature = "symbols", unsafe(no_mangle))]
pub unsafe extern "C" fn fmi2GetRealStatus(c: Component, kind: c_int, value: *mut f64) -> Status {
    with(c, "fmi2GetRealStatus", |h| {
        if kind != LAST_SUCCESSFUL_TIME {
            return Err(format!("status kind {kind} is not a Real status (fmi2LastSuccessfulTime is)"));
        }
        let time = h.instance.run.as_ref().map_or(0.0, |r| r.sim.time());
        // SAFETY: the importer's out-parameter.
        unsafe { write_out(value, time) }
    })
}

#[cfg_attr(feature = "symbols", unsafe(no_mangle))]
pub unsafe extern "C" fn fmi2GetBooleanStatus(c: Component, kind: c_int, value: *mut Boolean) -> Status {
    with(c, "fmi2GetBooleanStatus", |_| {
        if kind != TERMINATED {
            return Err(format!("status kind {kind} is not a Boolean status (fmi2Terminated is)"));
        }
        // SAFETY: the importer's out-parameter. The FMU never ends a run by itself.
        unsafe { write_out(value, 0) }
    })
}

#[cfg_attr(feature = "symbols", unsafe(no_mangle))]
pub unsafe extern "C" fn fmi2GetStatus(c: Component, _kind: c_int, value: *mut Status) -> Status {
    with(c, "fmi2GetStatus", |_| {
        // SAFETY: the importer's out-parameter: steps are never pending.
        unsafe { write_out(value, OK) }
    })
}

#[cfg_attr(feature = "symbols", unsafe(no_mangle))]
pub unsafe extern "C" fn fmi2GetFMUstate(c: Component, state: *mut *mut c_void) -> Status {
    // SAFETY: the importer's state pointer.
    with(c, "fmi2GetFMUstate", |h| unsafe { ffi::get_state(h, state) })
}

#[cfg_attr(feature = "symbols", unsafe(no_mangle))]
pub unsafe extern "C" fn fmi2SetFMUstate(c: Component, state: *mut c_void) -> Status {
    // SAFETY: a state this library made.
    with(c, "fmi2SetFMUstate", |h| h.instance.restore(unsafe { ffi::state_ref(state) }?))
}

#[cfg_attr(feature = "symbols", unsafe(no_mangle))]
pub unsafe extern "C" fn fmi2FreeFMUstate(c: Component, state: *mut *mut c_void) -> Status {
    with(c, "fmi2FreeFMUstate", |_| {
        // SAFETY: as above.
        unsafe { ffi::free_state(state) };
        Ok(())
    })
}

#[cfg_attr(feature = "symbols", unsafe(no_mangle))]
pub unsafe extern "C" fn fmi2SerializedFMUstateSize(c: Component, state: *mut c_void, size: *mut usize) -> Status {
    with(c, "fmi2SerializedFMUstateSize", |h| {
        // SAFETY: as above, and the importer's out-parameter.
        let bytes = unsafe { ffi::state_ref(state) }?.serialize(h.instance.token());
        unsafe { write_out(size, bytes.len()) }
    })
}

#[cfg_attr(feature = "symbols", unsafe(no_mangle))]
pub unsafe extern "C" fn fmi2SerializeFMUstate(c: Component, state: *mut c_void, out: *mut u8, size: usize) -> Status {
    with(c, "fmi2SerializeFMUstate", |h| {
        // SAFETY: as above; `out` holds `size` bytes.
        let bytes = unsafe { ffi::state_ref(state) }?.serialize(h.instance.token());
        unsafe { ffi::serialize_into(&bytes, out, size) }
    })
}

#[cfg_attr(feature = "symbols", unsafe(no_mangle))]
pub unsafe extern "C" fn fmi2DeSerializeFMUstate(
    c: Component,
    bytes: *const u8,
    size: usize,
    state: *mut *mut c_void,
) -> Status {
    with(c, "fmi2DeSerializeFMUstate", |h| {
        // SAFETY: the importer's buffer and state pointer.
        let saved = Saved::deserialize(unsafe { slice(bytes, size)? }, h.instance.token())?;
        let slot = unsafe { slice_mut(state, 1)? }.first_mut().ok_or("a null state pointer")?;
        unsafe { ffi::free_state(slot) };
        *slot = Box::into_raw(Box::new(saved)).cast();
        Ok(())
    })
}

fn refuse(c: Component, name: &str, why: &str) -> Status {
    with(c, name, |_| Err(why.to_string()))
}

/// Functions this FMU does not implement, each with its C signature.
macro_rules! not_offered {
    ($why:expr; $($name:ident($($arg:ty),*)),* $(,)?) => {$(
        #[cfg_attr(feature = "symbols", unsafe(no_mangle))]
        pub extern "C" fn $name(c: Component $(, _: $arg)*) -> Status {
            refuse(c, stringify!($name), $why)
        }
    )*};
}

/// Typed accessors of the types a ctlgraph FMU has no variable of.
macro_rules! no_variables_of_type {
    ($($name:ident: $t:ty),* $(,)?) => {$(
        #[cfg_attr(feature = "symbols", unsafe(no_mangle))]
        pub extern "C" fn $name(c: Component, _vr: *const Vr, nvr: usize, _values: $t) -> Status {
            match nvr {
                0 => with(c, stringify!($name), |_| Ok(())),
                _ => refuse(c, stringify!($name), "this FMU's variables are all Real"),
            }
        }
    )*};
}

no_variables_of_type!(
    fmi2GetInteger: *mut c_int, fmi2GetBoolean: *mut Boolean, fmi2GetString: *mut *const c_char,
    fmi2SetInteger: *const c_int, fmi2SetBoolean: *const Boolean, fmi2SetString: *const *const c_char,
);

const NOT_ME: &str = "a ctlgraph FMU is a co-simulation FMU: model exchange is not offered";
const NO_PARTIALS: &str = "this FMU provides no partial derivatives (providesDirectionalDerivative is false)";

not_offered!(NO_PARTIALS;
    fmi2GetDirectionalDerivative(*const Vr, usize, *const Vr, usize, *const f64, *mut f64),
    fmi2SetRealInputDerivatives(*const Vr, usize, *const c_int, *const f64),
    fmi2GetRealOutputDerivatives(*const Vr, usize, *const c_int, *mut f64),
);

not_offered!("no Integer or String status is defined for co-simulation steps that never pend";
    fmi2GetIntegerStatus(c_int, *mut c_int),
    fmi2GetStringStatus(c_int, *mut *const c_char),
);

not_offered!(NOT_ME;
    fmi2EnterEventMode(),
    fmi2NewDiscreteStates(*mut c_void),
    fmi2EnterContinuousTimeMode(),
    fmi2CompletedIntegratorStep(Boolean, *mut Boolean, *mut Boolean),
    fmi2SetTime(f64),
    fmi2SetContinuousStates(*const f64, usize),
    fmi2GetDerivatives(*mut f64, usize),
    fmi2GetEventIndicators(*mut f64, usize),
    fmi2GetContinuousStates(*mut f64, usize),
    fmi2GetNominalsOfContinuousStates(*mut f64, usize),
);

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn resource_uris_name_their_folder() {
        let p = |u: &str| resource_folder(u).unwrap();
        assert_eq!(p("file:///tmp/a%20b/resources"), PathBuf::from("/tmp/a b/resources"));
        assert_eq!(p("file:/tmp/r"), PathBuf::from("/tmp/r"));
        assert_eq!(p("file://localhost/tmp/r"), PathBuf::from("/tmp/r"));
        assert!(resource_folder("http://x/r").is_err());
    }
}
