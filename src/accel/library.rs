//! A step library loaded (`libloading`) and the runs made from it, behind
//! the C interface of [`ctlgraph_core::codegen::export`].

use ctlgraph_core::codegen::export::{self, Api, Spec, Str, TextSink};
use ctlgraph_core::trace::Columns;
use ctlgraph_core::{RunStats, SimError};
use std::ffi::c_void;
use std::panic::{AssertUnwindSafe, catch_unwind, resume_unwind};
use std::path::Path;
use std::sync::Arc;

/// A loaded library: its runs hold it open.
pub struct Library {
    api: &'static Api,
    // Dropped last: `api` points into it.
    _lib: libloading::Library,
}

impl Library {
    /// Opens the library at `path` and checks its interface version and
    /// that its step was generated for `fingerprint`.
    pub fn open(path: &Path, fingerprint: u64) -> Result<Arc<Library>, String> {
        // SAFETY: the library is one ctlgraph built from generated code:
        // its initialisers are Rust's (none run user code).
        let lib =
            unsafe { libloading::Library::new(path) }.map_err(|e| format!("cannot load {}: {e}", path.display()))?;
        // SAFETY: the symbol is the exported `extern "C" fn() -> *const Api`.
        let entry = unsafe { lib.get::<extern "C" fn() -> *const Api>(export::SYMBOL) }
            .map_err(|e| format!("{} is not a ctlgraph step library: {e}", path.display()))?;
        let api = entry();
        // SAFETY: the table is a static in the library, which `_lib` keeps
        // loaded for as long as `api` is used.
        let api: &'static Api = unsafe { &*api };
        if api.abi != export::ABI_VERSION {
            return Err(format!(
                "{} speaks interface version {}, this ctlgraph {}",
                path.display(),
                api.abi,
                export::ABI_VERSION
            ));
        }
        if api.fingerprint != fingerprint {
            return Err(format!("{} was generated for another graph structure", path.display()));
        }
        Ok(Arc::new(Library { api, _lib: lib }))
    }

    /// A run of the graph `text` (read from `file`), as the program
    /// compiled it: the same overrides, seed and stop time.
    pub fn create(
        self: &Arc<Self>,
        text: &str,
        file: &str,
        sets: &[(String, String)],
        seed: Option<u64>,
        stop: Option<f64>,
    ) -> Result<AcceleratedRun, String> {
        let pairs: Vec<Str> = sets.iter().flat_map(|(n, v)| [Str::of(n), Str::of(v)]).collect();
        let spec = Spec {
            text: Str::of(text),
            file: Str::of(file),
            sets: pairs.as_ptr(),
            n_sets: sets.len(),
            has_seed: seed.is_some(),
            seed: seed.unwrap_or(0),
            stop: stop.unwrap_or(f64::NAN),
        };
        let mut message = String::new();
        let sink = text_sink(&mut message);
        // SAFETY: `spec` and `sink` outlive the call.
        let run = unsafe { (self.api.create)(&spec, &sink) };
        if run.is_null() {
            return Err(message);
        }
        Ok(AcceleratedRun { lib: Arc::clone(self), run })
    }
}

/// A run inside a library.
pub struct AcceleratedRun {
    lib: Arc<Library>,
    run: *mut c_void,
}

// SAFETY: the run is a boxed `Compiled` in the library, which owns its
// values (blocks are `Send`) and is reached only through `&mut self` or
// `&self` calls that do not share it between threads at once.
unsafe impl Send for AcceleratedRun {}

/// An accelerated run at one instant ([`AcceleratedRun::state`]).
pub struct AcceleratedSnapshot {
    lib: Arc<Library>,
    snapshot: *mut c_void,
    time: f64,
}

// SAFETY: as for `AcceleratedRun`: a boxed clone of a run, owned here.
unsafe impl Send for AcceleratedSnapshot {}

impl AcceleratedSnapshot {
    /// The time it was taken at.
    pub fn time(&self) -> f64 {
        self.time
    }
}

impl Drop for AcceleratedSnapshot {
    fn drop(&mut self) {
        // SAFETY: `snapshot` came from this library's `save` and is dropped once.
        unsafe { (self.lib.api.drop_snapshot)(self.snapshot) }
    }
}

impl Drop for AcceleratedRun {
    fn drop(&mut self) {
        // SAFETY: `run` came from this library's `create` and is destroyed once.
        unsafe { (self.lib.api.destroy)(self.run) }
    }
}

impl AcceleratedRun {
    /// Back to t = 0 with initial states, as [`ctlgraph_core::Simulator::reset`].
    pub fn reset(&mut self) {
        // SAFETY: `run` is live and owned by this value.
        unsafe { (self.lib.api.reset)(self.run) }
    }

    pub fn time(&self) -> f64 {
        // SAFETY: `run` is live.
        unsafe { (self.lib.api.time)(self.run) }
    }

    pub fn stats(&self) -> RunStats {
        // SAFETY: `run` is live.
        unsafe { (self.lib.api.stats)(self.run) }
    }

    /// [`ctlgraph_core::Simulator::warnings`], from the library.
    pub fn warnings(&self) -> Vec<String> {
        unsafe extern "C" fn push(ctx: *mut c_void, text: *const u8, len: usize) {
            // SAFETY: `ctx` is the `Vec` below; `text` holds `len` bytes.
            let (list, bytes) = unsafe { (&mut *ctx.cast::<Vec<String>>(), std::slice::from_raw_parts(text, len)) };
            list.push(String::from_utf8_lossy(bytes).into_owned());
        }
        let mut list: Vec<String> = Vec::new();
        let sink = TextSink { ctx: (&raw mut list).cast(), write: push };
        // SAFETY: `run` is live; `sink` outlives the call.
        unsafe { (self.lib.api.warnings)(self.run, &sink) };
        list
    }

    /// Sets input block `block` (found and checked by
    /// [`ctlgraph_core::Model::host_input`]) from now on, as
    /// [`ctlgraph_core::Simulator::set_input`].
    pub fn set_input(&mut self, block: usize, value: &[f64]) -> Result<(), String> {
        let set_input = self.lib.api.set_input;
        // SAFETY: `value` outlives the call.
        self.host_call(|run, error| unsafe { set_input(run, block, value.as_ptr(), value.len(), error) })
    }

    /// [`ctlgraph_core::Simulator::advance_to`], in the library.
    pub fn advance_to(&mut self, t: f64) -> Result<(), SimError> {
        let advance_to = self.lib.api.advance_to;
        // SAFETY: as `host_call` promises.
        self.host_call(|run, error| unsafe { advance_to(run, t, error) }).map_err(SimError::Reported)
    }

    /// [`ctlgraph_core::Simulator::signals_now`], in the library.
    pub fn signals_now(&mut self) -> Result<&[f64], SimError> {
        let mut message = String::new();
        let error = text_sink(&mut message);
        let mut len = 0;
        // SAFETY: `run` is live; `len` and `error` outlive the call.
        let signals = unsafe { (self.lib.api.signals_now)(self.run, &mut len, &error) };
        if signals.is_null() {
            return Err(SimError::Reported(message));
        }
        // SAFETY: the run's signal buffer, `len` values, unchanged until
        // the run is next called (which borrowing `self` prevents).
        Ok(unsafe { std::slice::from_raw_parts(signals, len) })
    }

    /// The run as it stands, to return to with [`AcceleratedRun::restore`].
    pub fn state(&self) -> Result<AcceleratedSnapshot, String> {
        // SAFETY: `run` is live.
        let snapshot = unsafe { (self.lib.api.save)(self.run) };
        if snapshot.is_null() {
            return Err("the accelerated run could not be saved".to_string());
        }
        Ok(AcceleratedSnapshot { lib: Arc::clone(&self.lib), snapshot, time: self.time() })
    }

    /// Returns the run to `snapshot`, taken of this run.
    pub fn restore(&mut self, snapshot: &AcceleratedSnapshot) -> Result<(), String> {
        if !Arc::ptr_eq(&self.lib, &snapshot.lib) {
            return Err("the snapshot was taken of another run".to_string());
        }
        let (restore, saved) = (self.lib.api.restore, snapshot.snapshot);
        // SAFETY: `saved` came from the same library's `save`.
        self.host_call(|run, error| unsafe { restore(run, saved, error) })
    }

    /// A host's call into the library: `call` gets the live run and an
    /// error sink that outlives it; its message when it answers other than
    /// [`export::DONE`].
    fn host_call(&mut self, call: impl FnOnce(*mut c_void, &TextSink) -> i32) -> Result<(), String> {
        let mut message = String::new();
        let error = text_sink(&mut message);
        if call(self.run, &error) == export::DONE { Ok(()) } else { Err(message) }
    }

    /// [`ctlgraph_core::Simulator::run_while`], in the library. A panic in
    /// `sink` is carried over the library and resumed here.
    pub fn run_while<S>(&mut self, sink: &mut S) -> Result<bool, SimError>
    where
        S: FnMut(f64, &[f64]) -> bool + ?Sized,
    {
        let run_while = self.lib.api.run_while;
        // SAFETY: as `run_guarded` promises; `sample::<S>` reads a `Guarded<S>`.
        self.run_guarded(sink, |run, ctx, error| unsafe { run_while(run, sample::<S>, ctx, error) })
    }

    /// Runs to the stop time recording in the library, as
    /// [`ctlgraph_core::trace::Recorder`] records: `sink` receives the
    /// rows (`[t, recorded columns…]`, column by column) `batch` rows at a
    /// time and the rest at the end, and ends the run by answering false;
    /// so does reaching `max_steps` major steps and one more. Returns
    /// whether the stop time was reached. A major step costs no call
    /// across the library's interface: this is the fast way to run it
    /// whole.
    pub fn run_rows(&mut self, max_steps: u64, batch: usize, sink: &mut RowsSink<'_>) -> Result<bool, SimError> {
        let run_rows = self.lib.api.run_rows;
        // SAFETY: as `run_guarded` promises.
        self.run_guarded(sink, |run, ctx, error| unsafe { run_rows(run, max_steps, batch, rows, ctx, error) })
    }

    /// A whole run in the library: `start` gets the live run, the context
    /// of `sink` (a [`Guarded`]) for the trampoline it passes, and an error
    /// sink that outlives the call. A panic in `sink` is resumed here.
    fn run_guarded<S: ?Sized>(
        &mut self,
        sink: &mut S,
        start: impl FnOnce(*mut c_void, *mut c_void, &TextSink) -> i32,
    ) -> Result<bool, SimError> {
        let mut guarded = Guarded { sink, panic: None, fault: None };
        let mut message = String::new();
        let error = text_sink(&mut message);
        let answer = start(self.run, (&raw mut guarded).cast::<c_void>(), &error);
        if let Some(payload) = guarded.panic {
            resume_unwind(payload);
        }
        if let Some(fault) = guarded.fault {
            return Err(SimError::Reported(fault.into()));
        }
        match answer {
            export::FINISHED => Ok(true),
            export::CUT => Ok(false),
            _ => Err(SimError::Reported(message)),
        }
    }
}

/// A program's sink called from inside the library, and a panic it
/// raised: caught there (no panic crosses the library) and resumed by
/// [`AcceleratedRun::run_guarded`].
struct Guarded<'a, S: ?Sized> {
    sink: &'a mut S,
    panic: Option<Box<dyn std::any::Any + Send>>,
    /// The library broke the interface's promise (the run ended there).
    fault: Option<&'static str>,
}

impl<S: ?Sized> Guarded<'_, S> {
    /// `call` of the sink, or false (the run ends) when it panicked.
    fn call(&mut self, call: impl FnOnce(&mut S) -> bool) -> bool {
        match catch_unwind(AssertUnwindSafe(|| call(self.sink))) {
            Ok(go_on) => go_on,
            Err(payload) => {
                self.panic = Some(payload);
                false
            }
        }
    }
}

/// What [`AcceleratedRun::run_rows`] hands its batches to.
pub type RowsSink<'a> = dyn FnMut(Columns) -> bool + 'a;

unsafe extern "C" fn rows(ctx: *mut c_void, values: *const f64, n: usize, width: usize, stride: usize) -> bool {
    // SAFETY: `ctx` is the `Guarded` of the `run_rows` call in progress.
    let guarded = unsafe { &mut *ctx.cast::<Guarded<RowsSink<'_>>>() };
    let len = width.saturating_mul(stride);
    // SAFETY: the library passes `width·stride` values for the call.
    let values = if len == 0 { &[][..] } else { unsafe { std::slice::from_raw_parts(values, len) } };
    match Columns::from_parts(values, width, stride, n) {
        Some(batch) => guarded.call(|sink| sink(batch)),
        None => {
            guarded.fault = Some("the step library handed over a batch of rows outside its buffer");
            false
        }
    }
}

/// The trampoline for a sink of type `S`, one per type: the sink's code
/// is inlined into it, so a major step costs the library one call, not a
/// call and then a `dyn` call.
unsafe extern "C" fn sample<S>(ctx: *mut c_void, t: f64, signals: *const f64, len: usize) -> bool
where
    S: FnMut(f64, &[f64]) -> bool + ?Sized,
{
    // SAFETY: `ctx` is the `Guarded<S>` of the `run_while` call in progress.
    let guarded = unsafe { &mut *ctx.cast::<Guarded<S>>() };
    // SAFETY: the library passes its signal buffer for the call.
    let signals = unsafe { std::slice::from_raw_parts(signals, len) };
    guarded.call(|sink| sink(t, signals))
}

/// A sink appending the library's messages to `message`.
fn text_sink(message: &mut String) -> TextSink {
    unsafe extern "C" fn write(ctx: *mut c_void, text: *const u8, len: usize) {
        // SAFETY: `ctx` is the `String` given to `text_sink`; `text` holds `len` bytes.
        let (message, bytes) = unsafe { (&mut *ctx.cast::<String>(), std::slice::from_raw_parts(text, len)) };
        message.push_str(&String::from_utf8_lossy(bytes));
    }
    TextSink { ctx: (message as *mut String).cast(), write }
}
