//! The FMI 3.0 C functions (FMI 3.0 standard, §2.3 common, §4 co-simulation),
//! declared as `fmi3Functions.h` declares them. A ctlgraph FMU is a
//! co-simulation FMU whose variables are all `Float64`: the functions of
//! model exchange, scheduled execution, clocks and the other types return
//! `fmi3Error` with a message (or `fmi3OK` when asked for nothing). The
//! names are exported (unmangled) only with the `symbols` feature, which
//! the FMU's binary turns on.

#![allow(non_snake_case, clippy::missing_safety_doc, clippy::too_many_arguments)]

use crate::ffi::{self, ERROR, Handle, Log, OK, Status, guard, slice, slice_mut, text};
use crate::instance::Instance;
use crate::replay::Saved;
use crate::table::Version;
use std::ffi::{CStr, c_char, c_void};
use std::path::Path;

type Instance3 = *mut c_void;
type Env = *mut c_void;
type Vr = u32;
type LogMessage = Option<unsafe extern "C" fn(Env, Status, *const c_char, *const c_char)>;

/// The importer's `logMessage` callback and its environment.
pub struct Logger {
    callback: LogMessage,
    env: Env,
}

impl Log for Logger {
    fn log(&self, _name: &CStr, status: Status, category: &str, message: &str) {
        if let Some(cb) = self.callback {
            let (category, message) = (ffi::c_string(category), ffi::c_string(message));
            // SAFETY: the importer's callback, with the environment it gave.
            unsafe { cb(self.env, status, category.as_ptr(), message.as_ptr()) };
        }
    }
}

fn with(instance: Instance3, what: &str, f: impl FnOnce(&mut Handle<Logger>) -> Result<(), String>) -> Status {
    guard::<Logger>(instance, what, f)
}

#[cfg_attr(feature = "symbols", unsafe(no_mangle))]
pub extern "C" fn fmi3GetVersion() -> *const c_char {
    c"3.0".as_ptr()
}

#[cfg_attr(feature = "symbols", unsafe(no_mangle))]
pub extern "C" fn fmi3SetDebugLogging(
    instance: Instance3,
    on: bool,
    _n: usize,
    _categories: *const *const c_char,
) -> Status {
    with(instance, "fmi3SetDebugLogging", |h| {
        h.logging_on = on;
        Ok(())
    })
}

#[cfg_attr(feature = "symbols", unsafe(no_mangle))]
pub unsafe extern "C" fn fmi3InstantiateCoSimulation(
    name: *const c_char,
    token: *const c_char,
    resource_path: *const c_char,
    _visible: bool,
    logging_on: bool,
    _event_mode_used: bool,
    _early_return_allowed: bool,
    _required_intermediate: *const Vr,
    _n_required: usize,
    env: Env,
    log_message: LogMessage,
    _intermediate_update: *const c_void,
) -> Instance3 {
    // SAFETY: the importer passes NUL-terminated strings (or null).
    let (name, token, resources) = unsafe { (text(name), text(token), text(resource_path)) };
    let logger = Logger { callback: log_message, env };
    let c_name = ffi::c_string(name);
    let made = std::panic::catch_unwind(|| Instance::new(Path::new(resources), token, Version::Fmi3));
    match made {
        Ok(Ok(instance)) => {
            let handle = Handle { instance, name: c_name, logger, logging_on };
            Box::into_raw(Box::new(handle)).cast()
        }
        Ok(Err(message)) => {
            logger.log(&c_name, ERROR, "logStatusError", &format!("fmi3InstantiateCoSimulation: {message}"));
            std::ptr::null_mut()
        }
        Err(_) => {
            logger.log(&c_name, ffi::FATAL, "logStatusFatal", "fmi3InstantiateCoSimulation: internal error");
            std::ptr::null_mut()
        }
    }
}

#[cfg_attr(feature = "symbols", unsafe(no_mangle))]
pub unsafe extern "C" fn fmi3InstantiateModelExchange(
    name: *const c_char,
    _token: *const c_char,
    _resource_path: *const c_char,
    _visible: bool,
    _logging_on: bool,
    env: Env,
    log_message: LogMessage,
) -> Instance3 {
    // SAFETY: as above.
    let name = ffi::c_string(unsafe { text(name) });
    let message = "fmi3InstantiateModelExchange: a ctlgraph FMU is for co-simulation only";
    Logger { callback: log_message, env }.log(&name, ERROR, "logStatusError", message);
    std::ptr::null_mut()
}

#[cfg_attr(feature = "symbols", unsafe(no_mangle))]
pub unsafe extern "C" fn fmi3InstantiateScheduledExecution(
    name: *const c_char,
    _token: *const c_char,
    _resource_path: *const c_char,
    _visible: bool,
    _logging_on: bool,
    env: Env,
    log_message: LogMessage,
    _clock_update: *const c_void,
    _lock: *const c_void,
    _unlock: *const c_void,
) -> Instance3 {
    // SAFETY: as above.
    let name = ffi::c_string(unsafe { text(name) });
    let message = "fmi3InstantiateScheduledExecution: a ctlgraph FMU is for co-simulation only";
    Logger { callback: log_message, env }.log(&name, ERROR, "logStatusError", message);
    std::ptr::null_mut()
}

#[cfg_attr(feature = "symbols", unsafe(no_mangle))]
pub unsafe extern "C" fn fmi3FreeInstance(instance: Instance3) {
    if !instance.is_null() {
        // SAFETY: made by `Box::into_raw` at instantiation; freed once (the FMI contract).
        let handle = unsafe { Box::from_raw(instance.cast::<Handle<Logger>>()) };
        let _ = std::panic::catch_unwind(std::panic::AssertUnwindSafe(|| drop(handle)));
    }
}

#[cfg_attr(feature = "symbols", unsafe(no_mangle))]
pub extern "C" fn fmi3EnterInitializationMode(
    instance: Instance3,
    _tolerance_defined: bool,
    _tolerance: f64,
    start: f64,
    stop_defined: bool,
    stop: f64,
) -> Status {
    with(instance, "fmi3EnterInitializationMode", |h| {
        h.instance.setup_experiment(start, stop_defined.then_some(stop))?;
        h.instance.enter_initialization()
    })
}

#[cfg_attr(feature = "symbols", unsafe(no_mangle))]
pub extern "C" fn fmi3ExitInitializationMode(instance: Instance3) -> Status {
    with(instance, "fmi3ExitInitializationMode", |h| h.instance.exit_initialization())
}

#[cfg_attr(feature = "symbols", unsafe(no_mangle))]
pub extern "C" fn fmi3EnterStepMode(instance: Instance3) -> Status {
    // Entered by exitInitializationMode already (no event mode is used).
    with(instance, "fmi3EnterStepMode", |_| Ok(()))
}

#[cfg_attr(feature = "symbols", unsafe(no_mangle))]
pub extern "C" fn fmi3Terminate(instance: Instance3) -> Status {
    with(instance, "fmi3Terminate", |h| h.instance.terminate())
}

#[cfg_attr(feature = "symbols", unsafe(no_mangle))]
pub extern "C" fn fmi3Reset(instance: Instance3) -> Status {
    with(instance, "fmi3Reset", |h| {
        h.instance.reset();
        Ok(())
    })
}

#[cfg_attr(feature = "symbols", unsafe(no_mangle))]
pub unsafe extern "C" fn fmi3GetFloat64(
    instance: Instance3,
    vr: *const Vr,
    nvr: usize,
    values: *mut f64,
    n: usize,
) -> Status {
    with(instance, "fmi3GetFloat64", |h| {
        // SAFETY: the importer's arrays of the lengths it gives.
        let (vr, values) = unsafe { (slice(vr, nvr)?, slice_mut(values, n)?) };
        h.instance.get(vr, values)
    })
}

#[cfg_attr(feature = "symbols", unsafe(no_mangle))]
pub unsafe extern "C" fn fmi3SetFloat64(
    instance: Instance3,
    vr: *const Vr,
    nvr: usize,
    values: *const f64,
    n: usize,
) -> Status {
    with(instance, "fmi3SetFloat64", |h| {
        // SAFETY: as above.
        let (vr, values) = unsafe { (slice(vr, nvr)?, slice(values, n)?) };
        h.instance.set(vr, values)
    })
}

#[cfg_attr(feature = "symbols", unsafe(no_mangle))]
pub unsafe extern "C" fn fmi3DoStep(
    instance: Instance3,
    t: f64,
    h: f64,
    _no_set_prior: bool,
    event_handling_needed: *mut bool,
    terminate: *mut bool,
    early_return: *mut bool,
    last_successful_time: *mut f64,
) -> Status {
    with(instance, "fmi3DoStep", |handle| {
        let result = handle.instance.do_step(t, h);
        let reached = handle.instance.run.as_ref().map_or(t, |r| r.sim.time());
        // SAFETY: the importer's out-parameters (each may be null).
        unsafe {
            for flag in [event_handling_needed, terminate, early_return] {
                if !flag.is_null() {
                    *flag = false;
                }
            }
            if !last_successful_time.is_null() {
                *last_successful_time = reached;
            }
        }
        result.map(|_| ())
    })
}

#[cfg_attr(feature = "symbols", unsafe(no_mangle))]
pub unsafe extern "C" fn fmi3GetFMUState(instance: Instance3, state: *mut *mut c_void) -> Status {
    // SAFETY: the importer's state pointer.
    with(instance, "fmi3GetFMUState", |h| unsafe { ffi::get_state(h, state) })
}

#[cfg_attr(feature = "symbols", unsafe(no_mangle))]
pub unsafe extern "C" fn fmi3SetFMUState(instance: Instance3, state: *mut c_void) -> Status {
    // SAFETY: a state this library made.
    with(instance, "fmi3SetFMUState", |h| h.instance.restore(unsafe { ffi::state_ref(state) }?))
}

#[cfg_attr(feature = "symbols", unsafe(no_mangle))]
pub unsafe extern "C" fn fmi3FreeFMUState(instance: Instance3, state: *mut *mut c_void) -> Status {
    with(instance, "fmi3FreeFMUState", |_| {
        // SAFETY: as above.
        unsafe { ffi::free_state(state) };
        Ok(())
    })
}

#[cfg_attr(feature = "symbols", unsafe(no_mangle))]
pub unsafe extern "C" fn fmi3SerializedFMUStateSize(
    instance: Instance3,
    state: *mut c_void,
    size: *mut usize,
) -> Status {
    with(instance, "fmi3SerializedFMUStateSize", |h| {
        // SAFETY: as above.
        let bytes = unsafe { ffi::state_ref(state) }?.serialize(h.instance.token());
        // SAFETY: the importer's out-parameter.
        unsafe { ffi::write_out(size, bytes.len()) }
    })
}

#[cfg_attr(feature = "symbols", unsafe(no_mangle))]
pub unsafe extern "C" fn fmi3SerializeFMUState(
    instance: Instance3,
    state: *mut c_void,
    out: *mut u8,
    size: usize,
) -> Status {
    with(instance, "fmi3SerializeFMUState", |h| {
        // SAFETY: as above; `out` holds `size` bytes.
        let bytes = unsafe { ffi::state_ref(state) }?.serialize(h.instance.token());
        unsafe { ffi::serialize_into(&bytes, out, size) }
    })
}

#[cfg_attr(feature = "symbols", unsafe(no_mangle))]
pub unsafe extern "C" fn fmi3DeserializeFMUState(
    instance: Instance3,
    bytes: *const u8,
    size: usize,
    state: *mut *mut c_void,
) -> Status {
    with(instance, "fmi3DeserializeFMUState", |h| {
        // SAFETY: the importer's buffer and state pointer.
        let saved = Saved::deserialize(unsafe { slice(bytes, size)? }, h.instance.token())?;
        let slot = unsafe { slice_mut(state, 1)? }.first_mut().ok_or("a null state pointer")?;
        unsafe { ffi::free_state(slot) };
        *slot = Box::into_raw(Box::new(saved)).cast();
        Ok(())
    })
}

/// A function this FMU does not offer: an error naming it, with `why`.
fn refuse(instance: Instance3, name: &str, why: &str) -> Status {
    with(instance, name, |_| Err(why.to_string()))
}

const NOT_CS: &str = "a ctlgraph FMU is a co-simulation FMU: model exchange and scheduled execution are not offered";

/// Typed accessors of the types a ctlgraph FMU has no variable of: asking
/// for no value succeeds, any value reference is an error.
macro_rules! no_variables_of_type {
    ($($name:ident: $t:ty),* $(,)?) => {$(
        #[cfg_attr(feature = "symbols", unsafe(no_mangle))]
        pub extern "C" fn $name(instance: Instance3, _vr: *const Vr, nvr: usize, _values: $t, _n: usize) -> Status {
            match nvr {
                0 => with(instance, stringify!($name), |_| Ok(())),
                _ => refuse(instance, stringify!($name), "this FMU's variables are all Float64"),
            }
        }
    )*};
}

no_variables_of_type!(
    fmi3GetFloat32: *mut f32, fmi3GetInt8: *mut i8, fmi3GetUInt8: *mut u8, fmi3GetInt16: *mut i16,
    fmi3GetUInt16: *mut u16, fmi3GetInt32: *mut i32, fmi3GetUInt32: *mut u32, fmi3GetInt64: *mut i64,
    fmi3GetUInt64: *mut u64, fmi3GetBoolean: *mut bool, fmi3GetString: *mut *const c_char,
    fmi3SetFloat32: *const f32, fmi3SetInt8: *const i8, fmi3SetUInt8: *const u8, fmi3SetInt16: *const i16,
    fmi3SetUInt16: *const u16, fmi3SetInt32: *const i32, fmi3SetUInt32: *const u32, fmi3SetInt64: *const i64,
    fmi3SetUInt64: *const u64, fmi3SetBoolean: *const bool, fmi3SetString: *const *const c_char,
);

#[cfg_attr(feature = "symbols", unsafe(no_mangle))]
pub extern "C" fn fmi3GetBinary(
    i: Instance3,
    _vr: *const Vr,
    nvr: usize,
    _s: *mut usize,
    _v: *mut *const u8,
    _n: usize,
) -> Status {
    if nvr == 0 { OK } else { refuse(i, "fmi3GetBinary", "this FMU's variables are all Float64") }
}

#[cfg_attr(feature = "symbols", unsafe(no_mangle))]
pub extern "C" fn fmi3SetBinary(
    i: Instance3,
    _vr: *const Vr,
    nvr: usize,
    _s: *const usize,
    _v: *const *const u8,
    _n: usize,
) -> Status {
    if nvr == 0 { OK } else { refuse(i, "fmi3SetBinary", "this FMU's variables are all Float64") }
}

/// Functions of the interfaces this FMU does not implement, each with its
/// C signature (the arguments are not read).
macro_rules! not_offered {
    ($why:expr; $($name:ident($($arg:ty),*)),* $(,)?) => {$(
        #[cfg_attr(feature = "symbols", unsafe(no_mangle))]
        pub extern "C" fn $name(instance: Instance3 $(, _: $arg)*) -> Status {
            refuse(instance, stringify!($name), $why)
        }
    )*};
}

const NO_CLOCKS: &str = "this FMU has no clocks";
const NO_PARTIALS: &str = "this FMU provides no partial derivatives (providesDirectionalDerivatives is false)";

not_offered!(NO_CLOCKS;
    fmi3GetClock(*const Vr, usize, *mut bool),
    fmi3SetClock(*const Vr, usize, *const bool),
    fmi3GetIntervalDecimal(*const Vr, usize, *mut f64, *mut i32),
    fmi3GetIntervalFraction(*const Vr, usize, *mut u64, *mut u64, *mut i32),
    fmi3GetShiftDecimal(*const Vr, usize, *mut f64),
    fmi3GetShiftFraction(*const Vr, usize, *mut u64, *mut u64),
    fmi3SetIntervalDecimal(*const Vr, usize, *const f64),
    fmi3SetIntervalFraction(*const Vr, usize, *const u64, *const u64),
    fmi3SetShiftDecimal(*const Vr, usize, *const f64),
    fmi3SetShiftFraction(*const Vr, usize, *const u64, *const u64),
    fmi3EvaluateDiscreteStates(),
    fmi3UpdateDiscreteStates(*mut bool, *mut bool, *mut bool, *mut bool, *mut bool, *mut f64),
    fmi3EnterEventMode(),
    fmi3EnterConfigurationMode(),
    fmi3ExitConfigurationMode(),
    fmi3ActivateModelPartition(Vr, f64),
);

not_offered!(NO_PARTIALS;
    fmi3GetNumberOfVariableDependencies(Vr, *mut usize),
    fmi3GetVariableDependencies(Vr, *mut usize, *mut Vr, *mut usize, *mut i32, usize),
    fmi3GetDirectionalDerivative(*const Vr, usize, *const Vr, usize, *const f64, usize, *mut f64, usize),
    fmi3GetAdjointDerivative(*const Vr, usize, *const Vr, usize, *const f64, usize, *mut f64, usize),
    fmi3GetOutputDerivatives(*const Vr, usize, *const i32, *mut f64, usize),
);

not_offered!(NOT_CS;
    fmi3EnterContinuousTimeMode(),
    fmi3CompletedIntegratorStep(bool, *mut bool, *mut bool),
    fmi3SetTime(f64),
    fmi3SetContinuousStates(*const f64, usize),
    fmi3GetContinuousStateDerivatives(*mut f64, usize),
    fmi3GetEventIndicators(*mut f64, usize),
    fmi3GetContinuousStates(*mut f64, usize),
    fmi3GetNominalsOfContinuousStates(*mut f64, usize),
    fmi3GetNumberOfEventIndicators(*mut usize),
    fmi3GetNumberOfContinuousStates(*mut usize),
);
