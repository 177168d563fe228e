//! An FMU's binary, loaded with `libloading`, and one instance of it behind
//! a version-neutral interface (FMI 3.0 §2.3, §4; FMI 2.0.4 §2.1, §4): the
//! calls both interfaces share and co-simulation's; model exchange's own
//! are `binding_me.rs`. Every status the FMU returns is checked: an error
//! becomes a message with what the FMU logged, never a crash.

#![allow(non_snake_case)]

use super::description::Version;
use std::ffi::{CStr, CString, c_char, c_int, c_void};
use std::path::Path;
use std::sync::{Arc, Mutex};

type Status = c_int;
const OK: Status = 0;
const WARNING: Status = 1;
const DISCARD: Status = 2;

type Logger3 = unsafe extern "C" fn(*mut c_void, Status, *const c_char, *const c_char);
type Instantiate3 = unsafe extern "C" fn(
    *const c_char,
    *const c_char,
    *const c_char,
    bool,
    bool,
    bool,
    bool,
    *const u32,
    usize,
    *mut c_void,
    Option<Logger3>,
    *const c_void,
) -> *mut c_void;
type InstantiateMe3 = unsafe extern "C" fn(
    *const c_char,
    *const c_char,
    *const c_char,
    bool,
    bool,
    *mut c_void,
    Option<Logger3>,
) -> *mut c_void;
type EnterInit3 = unsafe extern "C" fn(*mut c_void, bool, f64, f64, bool, f64) -> Status;
type DoStep3 = unsafe extern "C" fn(*mut c_void, f64, f64, bool, *mut bool, *mut bool, *mut bool, *mut f64) -> Status;
type Values3 = unsafe extern "C" fn(*mut c_void, *const u32, usize, *mut f64, usize) -> Status;
type SetValues3 = unsafe extern "C" fn(*mut c_void, *const u32, usize, *const f64, usize) -> Status;

/// `fmi2CallbackFunctions`. The logger is variadic in the standard; the
/// one given here reads the fixed arguments only (as FMPy's does): on the
/// platforms whose binaries are loaded (x86_64 System V) the fixed
/// arguments are passed alike either way, and the message is shown as
/// the FMU wrote its format.
#[repr(C)]
struct Callbacks2 {
    logger: unsafe extern "C" fn(*mut c_void, *const c_char, Status, *const c_char, *const c_char),
    allocate: unsafe extern "C" fn(usize, usize) -> *mut c_void,
    free: unsafe extern "C" fn(*mut c_void),
    step_finished: *const c_void,
    env: *mut c_void,
}

unsafe extern "C" {
    fn calloc(n: usize, size: usize) -> *mut c_void;
    fn free(p: *mut c_void);
}

type Instantiate2 = unsafe extern "C" fn(
    *const c_char,
    c_int,
    *const c_char,
    *const c_char,
    *const Callbacks2,
    c_int,
    c_int,
) -> *mut c_void;
type Setup2 = unsafe extern "C" fn(*mut c_void, c_int, f64, f64, c_int, f64) -> Status;
type DoStep2 = unsafe extern "C" fn(*mut c_void, f64, f64, c_int) -> Status;
type Values2 = unsafe extern "C" fn(*mut c_void, *const u32, usize, *mut f64) -> Status;
type SetValues2 = unsafe extern "C" fn(*mut c_void, *const u32, usize, *const f64) -> Status;
type RealStatus2 = unsafe extern "C" fn(*mut c_void, c_int, *mut f64) -> Status;

// Shared by both versions (the same C signatures).
type Unary = unsafe extern "C" fn(*mut c_void) -> Status;
type Free = unsafe extern "C" fn(*mut c_void);
type GetState = unsafe extern "C" fn(*mut c_void, *mut *mut c_void) -> Status;
type SetState = unsafe extern "C" fn(*mut c_void, *mut c_void) -> Status;
type StateSize = unsafe extern "C" fn(*mut c_void, *mut c_void, *mut usize) -> Status;
type Serialize = unsafe extern "C" fn(*mut c_void, *mut c_void, *mut u8, usize) -> Status;
type Deserialize = unsafe extern "C" fn(*mut c_void, *const u8, usize, *mut *mut c_void) -> Status;

/// The functions of one version: those both interfaces share, and either
/// co-simulation's or model exchange's (`me`).
enum Functions {
    V3 {
        enter_init: EnterInit3,
        get: Values3,
        set: SetValues3,
        cs: Option<(Instantiate3, DoStep3)>,
        me: Option<InstantiateMe3>,
    },
    V2 {
        instantiate: Instantiate2,
        setup: Setup2,
        enter_init: Unary,
        get: Values2,
        set: SetValues2,
        cs: Option<(DoStep2, RealStatus2)>,
    },
}

/// The state functions, where the FMU has them.
struct StateFunctions {
    get: GetState,
    set: SetState,
    free: unsafe extern "C" fn(*mut c_void, *mut *mut c_void) -> Status,
    size: StateSize,
    serialize: Serialize,
    deserialize: Deserialize,
}

/// A loaded FMU binary: its functions, the library kept open beside them.
pub struct Binary {
    functions: Functions,
    /// Model exchange's functions, when loaded for it.
    pub(super) me: Option<super::binding_me::MeFunctions>,
    exit_init: Unary,
    terminate: Unary,
    free_instance: Free,
    state: Option<StateFunctions>,
    _library: libloading::Library,
}

impl Binary {
    /// Loads the binary at `path` (FMI `version`) and looks up the
    /// functions a co-simulation master (or, with `model_exchange`, an
    /// integrator) calls; a missing one is an error naming it.
    pub fn load(path: &Path, version: Version, with_state: bool, model_exchange: bool) -> Result<Arc<Binary>, String> {
        // SAFETY: loading a shared library runs its initialisers: the FMU's
        // binary is code the user chose to run, as any FMI importer does.
        let library =
            unsafe { libloading::Library::new(path) }.map_err(|e| format!("cannot load {}: {e}", path.display()))?;
        let p = match version {
            Version::Fmi3 => "fmi3",
            Version::Fmi2 => "fmi2",
        };
        let functions = match version {
            Version::Fmi3 => Functions::V3 {
                enter_init: get(&library, "fmi3EnterInitializationMode")?,
                get: get(&library, "fmi3GetFloat64")?,
                set: get(&library, "fmi3SetFloat64")?,
                cs: match model_exchange {
                    false => Some((get(&library, "fmi3InstantiateCoSimulation")?, get(&library, "fmi3DoStep")?)),
                    true => None,
                },
                me: if model_exchange { Some(get(&library, "fmi3InstantiateModelExchange")?) } else { None },
            },
            Version::Fmi2 => Functions::V2 {
                instantiate: get(&library, "fmi2Instantiate")?,
                setup: get(&library, "fmi2SetupExperiment")?,
                enter_init: get(&library, "fmi2EnterInitializationMode")?,
                get: get(&library, "fmi2GetReal")?,
                set: get(&library, "fmi2SetReal")?,
                cs: match model_exchange {
                    false => Some((get(&library, "fmi2DoStep")?, get(&library, "fmi2GetRealStatus")?)),
                    true => None,
                },
            },
        };
        let me = if model_exchange { Some(super::binding_me::MeFunctions::load(&library, version)?) } else { None };
        let state = if with_state {
            let s = if version == Version::Fmi3 { "FMUState" } else { "FMUstate" };
            let deserialize =
                if version == Version::Fmi3 { "fmi3DeserializeFMUState" } else { "fmi2DeSerializeFMUstate" };
            Some(StateFunctions {
                get: get(&library, &format!("{p}Get{s}"))?,
                set: get(&library, &format!("{p}Set{s}"))?,
                free: get(&library, &format!("{p}Free{s}"))?,
                size: get(&library, &format!("{p}Serialized{s}Size"))?,
                serialize: get(&library, &format!("{p}Serialize{s}"))?,
                deserialize: get(&library, deserialize)?,
            })
        } else {
            None
        };
        Ok(Arc::new(Binary {
            exit_init: get(&library, &format!("{p}ExitInitializationMode"))?,
            terminate: get(&library, &format!("{p}Terminate"))?,
            free_instance: get(&library, &format!("{p}FreeInstance"))?,
            functions,
            me,
            state,
            _library: library,
        }))
    }
}

/// The function `name` of `lib`, typed `T`; an error naming it when missing.
pub(super) fn get<T: Copy>(lib: &libloading::Library, name: &str) -> Result<T, String> {
    // SAFETY: `T` is the function's type in the FMI headers.
    unsafe { lib.get::<T>(name.as_bytes()) }.map(|s| *s).map_err(|_| format!("the FMU's binary has no `{name}`"))
}

/// What an instance's logger received, newest last (kept short).
type Messages = Mutex<Vec<String>>;

const KEPT_MESSAGES: usize = 20;

fn keep(messages: &Messages, status: Status, category: *const c_char, message: *const c_char) {
    // SAFETY: the FMU passes NUL-terminated strings (or null).
    let text = |p: *const c_char| {
        if p.is_null() { String::new() } else { unsafe { CStr::from_ptr(p) }.to_string_lossy().into_owned() }
    };
    let line = format!("[{}] {}: {}", status_name(status), text(category), text(message));
    if let Ok(mut m) = messages.lock() {
        if m.len() == KEPT_MESSAGES {
            m.remove(0);
        }
        m.push(line);
    }
}

unsafe extern "C" fn log3(env: *mut c_void, status: Status, category: *const c_char, message: *const c_char) {
    // SAFETY: `env` is the instance's message list, alive while the instance is.
    if let Some(messages) = unsafe { env.cast::<Messages>().as_ref() } {
        keep(messages, status, category, message);
    }
}

unsafe extern "C" fn log2(
    env: *mut c_void,
    _name: *const c_char,
    status: Status,
    category: *const c_char,
    message: *const c_char,
) {
    // SAFETY: as above.
    if let Some(messages) = unsafe { env.cast::<Messages>().as_ref() } {
        keep(messages, status, category, message);
    }
}

unsafe extern "C" fn allocate2(n: usize, size: usize) -> *mut c_void {
    // SAFETY: C's calloc, as FMI 2 asks of `allocateMemory`.
    unsafe { calloc(n, size) }
}

unsafe extern "C" fn free2(p: *mut c_void) {
    // SAFETY: memory `allocate2` gave.
    unsafe { free(p) }
}

fn status_name(s: Status) -> &'static str {
    match s {
        OK => "ok",
        WARNING => "warning",
        DISCARD => "discard",
        3 => "error",
        4 => "fatal",
        _ => "pending",
    }
}

/// One co-simulation instance. Owned by one block of one run; freed when
/// dropped.
pub struct Instance {
    binary: Arc<Binary>,
    handle: *mut c_void,
    messages: Box<Messages>,
    /// FMI 2's callbacks must outlive the instance.
    _callbacks: Option<Box<Callbacks2>>,
}

// SAFETY: an instance is owned by one block of one run, behind a lock
// (the blocks' `Mutex<Run>`), so its calls never overlap — all FMI asks:
// an instance may be called from any thread, one call at a time.
unsafe impl Send for Instance {}

/// Why a call failed: the function, the status, what the FMU logged.
fn failure(what: &str, status: Status, messages: &Messages) -> String {
    let said = messages.lock().map(|m| m.join(" | ")).unwrap_or_default();
    let said = if said.is_empty() { String::new() } else { format!(" (the FMU said: {said})") };
    format!("{what} returned {}{said}", status_name(status))
}

impl Instance {
    /// Instantiates a co-simulation slave named `name` of the FMU whose
    /// resources are in `resources` (a folder).
    pub fn new(binary: &Arc<Binary>, name: &str, token: &str, resources: &Path) -> Result<Instance, String> {
        let messages: Box<Messages> = Box::default();
        let env = (&*messages as *const Messages).cast_mut().cast::<c_void>();
        let c = |s: &str| CString::new(s).map_err(|_| format!("`{s}` holds a NUL"));
        let (c_name, c_token) = (c(name)?, c(token)?);
        let (handle, callbacks) = match binary.functions {
            Functions::V3 { cs, me, .. } => {
                let resources = c(&format!("{}/", resources.display()))?;
                let (n, t, r) = (c_name.as_ptr(), c_token.as_ptr(), resources.as_ptr());
                // SAFETY: the FMI 3 signatures; the strings and the message
                // list outlive the call (the list, the instance).
                let h = match (cs, me) {
                    (Some((instantiate, _)), _) => unsafe {
                        instantiate(
                            n,
                            t,
                            r,
                            false,
                            false,
                            false,
                            false,
                            std::ptr::null(),
                            0,
                            env,
                            Some(log3),
                            std::ptr::null(),
                        )
                    },
                    (None, Some(instantiate)) => unsafe { instantiate(n, t, r, false, false, env, Some(log3)) },
                    (None, None) => std::ptr::null_mut(),
                };
                (h, None)
            }
            Functions::V2 { instantiate, cs, .. } => {
                let uri = c(&file_uri(resources))?;
                let callbacks = Box::new(Callbacks2 {
                    logger: log2,
                    allocate: allocate2,
                    free: free2,
                    step_finished: std::ptr::null(),
                    env,
                });
                let kind: c_int = if cs.is_some() { 1 } else { 0 }; // fmi2CoSimulation, fmi2ModelExchange
                // SAFETY: the FMI 2 signature; the callbacks live as long as the instance.
                let h =
                    unsafe { instantiate(c_name.as_ptr(), kind, c_token.as_ptr(), uri.as_ptr(), &*callbacks, 0, 0) };
                (h, Some(callbacks))
            }
        };
        if handle.is_null() {
            return Err(failure("instantiation", 3, &messages));
        }
        Ok(Instance { binary: binary.clone(), handle, messages, _callbacks: callbacks })
    }

    pub(super) fn binary(&self) -> &Binary {
        &self.binary
    }

    /// The FMU's handle of this instance, for model exchange's calls.
    pub(super) fn handle(&self) -> *mut c_void {
        self.handle
    }

    pub(super) fn check(&self, what: &str, status: Status) -> Result<(), String> {
        match status {
            OK | WARNING => Ok(()),
            s => Err(failure(what, s, &self.messages)),
        }
    }

    /// Initialisation from `start`: parameters and inputs are set with
    /// `set` before `exit_initialization`.
    pub fn enter_initialization(&mut self, start: f64) -> Result<(), String> {
        let status = match self.binary.functions {
            // SAFETY: the FMI signatures, on this instance.
            Functions::V3 { enter_init, .. } => unsafe { enter_init(self.handle, false, 0.0, start, false, 0.0) },
            Functions::V2 { setup, enter_init, .. } => {
                let s = unsafe { setup(self.handle, 0, 0.0, start, 0, 0.0) };
                self.check("fmi2SetupExperiment", s)?;
                unsafe { enter_init(self.handle) }
            }
        };
        self.check("entering initialisation mode", status)
    }

    pub fn exit_initialization(&mut self) -> Result<(), String> {
        // SAFETY: the FMI signature, on this instance.
        let status = unsafe { (self.binary.exit_init)(self.handle) };
        self.check("exiting initialisation mode", status)
    }

    pub fn set(&mut self, references: &[u32], values: &[f64]) -> Result<(), String> {
        let status = match self.binary.functions {
            // SAFETY: arrays of the lengths passed.
            Functions::V3 { set, .. } => unsafe {
                set(self.handle, references.as_ptr(), references.len(), values.as_ptr(), values.len())
            },
            Functions::V2 { set, .. } => unsafe {
                set(self.handle, references.as_ptr(), references.len(), values.as_ptr())
            },
        };
        self.check("setting values", status)
    }

    pub fn get(&mut self, references: &[u32], values: &mut [f64]) -> Result<(), String> {
        let status = match self.binary.functions {
            // SAFETY: arrays of the lengths passed.
            Functions::V3 { get, .. } => unsafe {
                get(self.handle, references.as_ptr(), references.len(), values.as_mut_ptr(), values.len())
            },
            Functions::V2 { get, .. } => unsafe {
                get(self.handle, references.as_ptr(), references.len(), values.as_mut_ptr())
            },
        };
        self.check("getting values", status)
    }

    /// `doStep` from `t` over `h`: an error unless the FMU completed it
    /// (a discarded step, an early return or a request to terminate say
    /// where it stopped).
    pub fn do_step(&mut self, t: f64, h: f64) -> Result<(), String> {
        match self.binary.functions {
            Functions::V3 { cs: Some((_, do_step)), .. } => {
                let (mut event, mut terminate, mut early, mut last) = (false, false, false, t);
                // SAFETY: the FMI 3 signature with valid out-parameters.
                let status =
                    unsafe { do_step(self.handle, t, h, true, &mut event, &mut terminate, &mut early, &mut last) };
                self.check(&format!("doStep from t = {t} over {h} s"), status)?;
                if early || terminate || status == DISCARD {
                    let why = if terminate { "asked to terminate" } else { "returned early" };
                    return Err(format!("doStep from t = {t} over {h} s: the FMU {why} at t = {last}"));
                }
                Ok(())
            }
            Functions::V2 { cs: Some((do_step, real_status)), .. } => {
                // SAFETY: the FMI 2 signature.
                let status = unsafe { do_step(self.handle, t, h, 1) };
                if status == DISCARD {
                    let mut last = f64::NAN;
                    const LAST_SUCCESSFUL_TIME: c_int = 2;
                    // SAFETY: as above.
                    let _ = unsafe { real_status(self.handle, LAST_SUCCESSFUL_TIME, &mut last) };
                    return Err(format!("doStep from t = {t} over {h} s: the FMU discarded the step at t = {last}"));
                }
                self.check(&format!("doStep from t = {t} over {h} s"), status)
            }
            _ => Err("doStep: the FMU was loaded for model exchange".to_string()),
        }
    }

    /// The instance's state, serialised (where the FMU can).
    pub fn serialize(&self) -> Result<Vec<u8>, String> {
        let f = self.binary.state.as_ref().ok_or("the FMU cannot save its state")?;
        let mut state: *mut c_void = std::ptr::null_mut();
        // SAFETY: the FMI state functions on this instance; the state is
        // freed before returning.
        unsafe {
            self.check("getting the FMU state", (f.get)(self.handle, &mut state))?;
            let mut size = 0usize;
            let mut bytes = Vec::new();
            let mut result = self.check("sizing the FMU state", (f.size)(self.handle, state, &mut size));
            if result.is_ok() {
                bytes = vec![0u8; size];
                result = self
                    .check("serialising the FMU state", (f.serialize)(self.handle, state, bytes.as_mut_ptr(), size));
            }
            (f.free)(self.handle, &mut state);
            result.map(|()| bytes)
        }
    }

    /// Returns to a state [`Instance::serialize`] gave (of an instance of the same FMU).
    pub fn deserialize(&mut self, bytes: &[u8]) -> Result<(), String> {
        let f = self.binary.state.as_ref().ok_or("the FMU cannot restore a state")?;
        let mut state: *mut c_void = std::ptr::null_mut();
        // SAFETY: as above.
        unsafe {
            self.check(
                "deserialising the FMU state",
                (f.deserialize)(self.handle, bytes.as_ptr(), bytes.len(), &mut state),
            )?;
            let result = self.check("setting the FMU state", (f.set)(self.handle, state));
            (f.free)(self.handle, &mut state);
            result
        }
    }
}

impl Drop for Instance {
    fn drop(&mut self) {
        // SAFETY: the instance is freed once, after terminating it (the
        // status of a terminate in a failed state does not matter here).
        unsafe {
            let _ = (self.binary.terminate)(self.handle);
            (self.binary.free_instance)(self.handle);
        }
    }
}

/// `resources` as a `file://` URI (FMI 2's `fmuResourceLocation`), its
/// bytes outside the unreserved set percent-encoded.
fn file_uri(resources: &Path) -> String {
    let mut uri = String::from("file://");
    for b in resources.display().to_string().bytes() {
        match b {
            b'A'..=b'Z' | b'a'..=b'z' | b'0'..=b'9' | b'-' | b'.' | b'_' | b'~' | b'/' => uri.push(b as char),
            b => uri.push_str(&format!("%{b:02X}")),
        }
    }
    uri
}
