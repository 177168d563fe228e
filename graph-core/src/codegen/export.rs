//! The C interface of an accelerated run: what a generated step compiled
//! as a shared library exports, and what `ctlgraph --accelerate` loads.
//!
//! The library holds its own copy of ctlgraph's crates (built from the same
//! source as the program that loads it), so nothing Rust-shaped crosses
//! the boundary: the program hands over the graph as text with its
//! overrides, seed and stop time, the library loads and compiles it with
//! its own registry, checks that the generated step fits it, and runs it
//! through the driver ([`super::Compiled`]) — the same code as the
//! interpreter's time keeping, compiled into the library. Only numbers,
//! byte strings and C function pointers pass: `#[repr(C)]` structs, an
//! [`Api`] table reached through one exported symbol ([`SYMBOL`]), and a
//! version ([`ABI_VERSION`]) checked before anything else is called.
//!
//! No panic crosses the boundary: every entry catches it and reports it as
//! an error; the program's sink is called inside the run and must not
//! unwind (the loader catches its own).

use super::{Compiled, CompiledSnapshot, GeneratedStep};
use crate::registry::Registry;
use crate::sim::RunStats;
use crate::trace::{ColumnBatch, Recorder};
use std::ffi::c_void;
use std::panic::{AssertUnwindSafe, catch_unwind};

/// Bumped whenever [`Api`] or the structs it passes change.
pub const ABI_VERSION: u32 = 6;

/// The exported function returning the library's [`Api`].
pub const SYMBOL: &[u8] = b"ctlgraph_accelerated_v1";

/// Borrowed UTF-8 bytes.
#[repr(C)]
#[derive(Clone, Copy)]
pub struct Str {
    pub ptr: *const u8,
    pub len: usize,
}

impl Str {
    pub fn of(text: &str) -> Str {
        Str { ptr: text.as_ptr(), len: text.len() }
    }

    /// # Safety
    /// `ptr` points to `len` readable bytes for the borrow's lifetime.
    unsafe fn text<'a>(self) -> Result<&'a str, String> {
        if self.len == 0 {
            return Ok("");
        }
        // SAFETY: the caller's promise.
        let bytes = unsafe { std::slice::from_raw_parts(self.ptr, self.len) };
        std::str::from_utf8(bytes).map_err(|e| format!("the loader passed text that is not UTF-8: {e}"))
    }
}

/// What to run: the graph as [`crate::load_str`] takes it, its `--set`
/// overrides as name/value pairs, the seed that replaces
/// `simulation.seed` (when `has_seed`), and the stop time (NaN: the
/// graph's own).
#[repr(C)]
pub struct Spec {
    pub text: Str,
    pub file: Str,
    /// `2 * n_sets` strings: name, value, name, value, …
    pub sets: *const Str,
    pub n_sets: usize,
    pub has_seed: bool,
    pub seed: u64,
    pub stop: f64,
}

/// Receives a message (an error): bytes valid for the call only.
#[repr(C)]
pub struct TextSink {
    pub ctx: *mut c_void,
    pub write: unsafe extern "C" fn(ctx: *mut c_void, text: *const u8, len: usize),
}

impl TextSink {
    fn send(&self, text: &str) {
        // SAFETY: the loader's sink accepts any bytes for the call's duration.
        unsafe { (self.write)(self.ctx, text.as_ptr(), text.len()) }
    }
}

/// Called at every major step with the time and the signal buffer (valid
/// for the call only); returns whether the run goes on.
pub type Sample = unsafe extern "C" fn(ctx: *mut c_void, t: f64, signals: *const f64, len: usize) -> bool;

/// Receives `n` rows of `width` values each — the time and the recorded
/// columns, as [`Recorder`] makes them — column by column: row r's value
/// c at `values[c·stride + r]` (a [`ColumnBatch`], `width·stride` values),
/// valid for the call only; returns whether the run goes on.
pub type Rows =
    unsafe extern "C" fn(ctx: *mut c_void, values: *const f64, n: usize, width: usize, stride: usize) -> bool;

/// [`RunWhile`]'s answer: the run reached its stop time.
pub const FINISHED: i32 = 1;
/// [`RunWhile`]'s answer: the sink ended the run.
pub const CUT: i32 = 0;
/// [`RunWhile`]'s answer (and [`Create`]'s null): see the message.
pub const FAILED: i32 = -1;
/// A host call's answer ([`SetInput`], [`AdvanceTo`], [`Restore`]): done.
pub const DONE: i32 = 0;

/// Loads, compiles and prepares a run; null (and a message) when it cannot.
pub type Create = unsafe extern "C" fn(spec: *const Spec, error: *const TextSink) -> *mut c_void;
pub type Destroy = unsafe extern "C" fn(run: *mut c_void);
/// [`crate::Simulator::reset`]: back to t = 0 with initial states.
pub type Reset = unsafe extern "C" fn(run: *mut c_void);
/// [`crate::Simulator::run_while`]: [`FINISHED`], [`CUT`] or [`FAILED`].
pub type RunWhile =
    unsafe extern "C" fn(run: *mut c_void, sample: Sample, ctx: *mut c_void, error: *const TextSink) -> i32;
/// [`RunWhile`], recording in the library: the graph's rows (every
/// `record_every`-th major step and the last) are handed to `rows`
/// `batch` at a time and the rest at the end, so a major step costs the
/// program nothing; after `max_steps` major steps and one more the run is
/// [`CUT`], as when `rows` answers false.
pub type RunRows = unsafe extern "C" fn(
    run: *mut c_void,
    max_steps: u64,
    batch: usize,
    rows: Rows,
    ctx: *mut c_void,
    error: *const TextSink,
) -> i32;
pub type Time = unsafe extern "C" fn(run: *const c_void) -> f64;
pub type GetStats = unsafe extern "C" fn(run: *const c_void) -> RunStats;
/// [`crate::Simulator::warnings`]: `sink` receives each, one call apiece.
pub type Warnings = unsafe extern "C" fn(run: *const c_void, sink: *const TextSink);
/// [`super::Compiled::set_input`]: `len` values for input block `block`;
/// [`DONE`] or [`FAILED`].
pub type SetInput =
    unsafe extern "C" fn(run: *mut c_void, block: usize, values: *const f64, len: usize, error: *const TextSink) -> i32;
/// [`super::Compiled::advance_to`]: [`DONE`] or [`FAILED`].
pub type AdvanceTo = unsafe extern "C" fn(run: *mut c_void, t: f64, error: *const TextSink) -> i32;
/// [`super::Compiled::signals_now`]: the buffer (valid until the run is
/// next called) and its length in `len`; null when the outputs failed.
pub type SignalsNow = unsafe extern "C" fn(run: *mut c_void, len: *mut usize, error: *const TextSink) -> *const f64;
/// [`super::Compiled::state`]: a snapshot, freed by [`DropSnapshot`].
pub type Save = unsafe extern "C" fn(run: *const c_void) -> *mut c_void;
/// [`super::Compiled::restore`]: [`DONE`] or [`FAILED`].
pub type Restore = unsafe extern "C" fn(run: *mut c_void, snapshot: *const c_void, error: *const TextSink) -> i32;
pub type DropSnapshot = unsafe extern "C" fn(snapshot: *mut c_void);

/// Everything a library offers, behind [`SYMBOL`].
#[repr(C)]
pub struct Api {
    pub abi: u32,
    /// The structure its step was generated for ([`super::fingerprint`]).
    pub fingerprint: u64,
    pub create: Create,
    pub destroy: Destroy,
    pub reset: Reset,
    pub run_while: RunWhile,
    pub run_rows: RunRows,
    pub time: Time,
    pub stats: GetStats,
    pub warnings: Warnings,
    pub set_input: SetInput,
    pub advance_to: AdvanceTo,
    pub signals_now: SignalsNow,
    pub save: Save,
    pub restore: Restore,
    pub drop_snapshot: DropSnapshot,
}

/// A generated step made into a library: its graphs are compiled with
/// this registry. Implemented by [`crate::export_accelerated`].
pub trait Exported: GeneratedStep {
    fn registry() -> Registry;
}

impl Api {
    /// The table for step `G`.
    pub const fn of<G: Exported>() -> Api {
        Api {
            abi: ABI_VERSION,
            fingerprint: G::FINGERPRINT,
            create: create::<G>,
            destroy: destroy::<G>,
            reset: reset::<G>,
            run_while: run_while::<G>,
            run_rows: run_rows::<G>,
            time: time::<G>,
            stats: stats::<G>,
            warnings: warnings::<G>,
            set_input: set_input::<G>,
            advance_to: advance_to::<G>,
            signals_now: signals_now::<G>,
            save: save::<G>,
            restore: restore::<G>,
            drop_snapshot: drop_snapshot::<G>,
        }
    }
}

/// Makes a generated step `$step` a library for `--accelerate`: exports
/// [`SYMBOL`], compiling graphs with the registry `$registry()`.
#[macro_export]
macro_rules! export_accelerated {
    ($step:ty, $registry:path) => {
        impl $crate::codegen::export::Exported for $step {
            fn registry() -> $crate::Registry {
                $registry()
            }
        }

        /// The library's table of entry points.
        #[unsafe(no_mangle)]
        pub extern "C" fn ctlgraph_accelerated_v1() -> *const $crate::codegen::export::Api {
            static API: $crate::codegen::export::Api = $crate::codegen::export::Api::of::<$step>();
            &API
        }
    };
}

/// The panic's message, for an error.
fn panic_text(payload: Box<dyn std::any::Any + Send>) -> String {
    let what = payload
        .downcast_ref::<&str>()
        .map(|s| s.to_string())
        .or_else(|| payload.downcast_ref::<String>().cloned())
        .unwrap_or_else(|| "a panic".to_string());
    format!("internal error in the accelerated run: {what}")
}

/// A run as the library keeps it: the generated step's run, and the
/// recorder that makes its rows ([`RunRows`]) as the program would.
struct LibraryRun<G: GeneratedStep> {
    run: Compiled<G>,
    recorder: Recorder,
    /// Rows waiting to be handed over (allocated by the first `run_rows`
    /// and again when a batch of another size is asked for).
    batch: ColumnBatch,
}

/// The run behind a handle from [`create`].
///
/// # Safety
/// `run` came from `create::<G>` and is not destroyed; the loader calls
/// one entry at a time for it.
unsafe fn library_run<'a, G: Exported>(run: *mut c_void) -> &'a mut LibraryRun<G> {
    // SAFETY: the caller's promise.
    unsafe { &mut *run.cast::<LibraryRun<G>>() }
}

/// [`library_run`], to read.
///
/// # Safety
/// As for [`library_run`].
unsafe fn library_run_ref<'a, G: Exported>(run: *const c_void) -> &'a LibraryRun<G> {
    // SAFETY: the caller's promise.
    unsafe { &*run.cast::<LibraryRun<G>>() }
}

/// # Safety
/// `spec` and `error` point to valid values for the call.
unsafe fn prepare<G: Exported>(spec: &Spec) -> Result<LibraryRun<G>, String> {
    // SAFETY: the loader passes strings it owns for the call.
    let (text, file) = unsafe { (spec.text.text()?, spec.file.text()?) };
    let pairs = if spec.n_sets == 0 {
        &[][..]
    } else {
        // SAFETY: `sets` holds `2 * n_sets` strings.
        unsafe { std::slice::from_raw_parts(spec.sets, 2 * spec.n_sets) }
    };
    let mut sets = Vec::with_capacity(spec.n_sets);
    for pair in pairs.chunks_exact(2) {
        // SAFETY: as above.
        sets.push(unsafe { (pair[0].text()?.to_string(), pair[1].text()?.to_string()) });
    }
    let seed = spec.has_seed.then_some(spec.seed);
    let model = super::template::compile_case(text, file, &sets, seed, &G::registry())?;
    let run = Compiled::<G>::new(&model, (!spec.stop.is_nan()).then_some(spec.stop))?;
    Ok(LibraryRun { run, recorder: Recorder::new(&model), batch: ColumnBatch::default() })
}

unsafe extern "C" fn create<G: Exported>(spec: *const Spec, error: *const TextSink) -> *mut c_void {
    // SAFETY: the loader passes valid pointers for the call.
    let (spec, error) = unsafe { (&*spec, &*error) };
    // SAFETY: as above.
    let result = catch_unwind(AssertUnwindSafe(|| unsafe { prepare::<G>(spec) }));
    answer(result, error, |run| Box::into_raw(Box::new(run)).cast(), std::ptr::null_mut())
}

unsafe extern "C" fn destroy<G: Exported>(run: *mut c_void) {
    if !run.is_null() {
        // SAFETY: `run` came from `create::<G>` and is destroyed once.
        let _ = catch_unwind(AssertUnwindSafe(|| drop(unsafe { Box::from_raw(run.cast::<LibraryRun<G>>()) })));
    }
}

unsafe extern "C" fn reset<G: Exported>(run: *mut c_void) {
    // SAFETY: `run` came from `create::<G>`; the loader owns it alone.
    let run = &mut unsafe { library_run::<G>(run) }.run;
    // Resetting runs the blocks' `initialize`, plain code that does not
    // panic; were one to, the run would be left as it is.
    let _ = catch_unwind(AssertUnwindSafe(|| run.reset()));
}

unsafe extern "C" fn run_while<G: Exported>(
    run: *mut c_void,
    sample: Sample,
    ctx: *mut c_void,
    error: *const TextSink,
) -> i32 {
    // SAFETY: `run` came from `create::<G>`; the loader owns it alone.
    let (run, error) = unsafe { (&mut library_run::<G>(run).run, &*error) };
    let result = catch_unwind(AssertUnwindSafe(|| {
        run.run_while(|t, signals| {
            // SAFETY: the loader's sample accepts the buffer for the call.
            unsafe { sample(ctx, t, signals.as_ptr(), signals.len()) }
        })
    }));
    run_answer(result, error)
}

unsafe extern "C" fn run_rows<G: Exported>(
    run: *mut c_void,
    max_steps: u64,
    batch: usize,
    rows: Rows,
    ctx: *mut c_void,
    error: *const TextSink,
) -> i32 {
    // SAFETY: `run` came from `create::<G>`; the loader owns it alone.
    let (LibraryRun { run, recorder, batch: pending }, error) = unsafe { (library_run::<G>(run), &*error) };
    let mut recorder = recorder.clone();
    // At most 65 536 rows at a time: a batch is allocated once.
    let (width, capacity) = (recorder.width(), batch.clamp(1, 1 << 16));
    if (pending.width(), pending.capacity()) != (width, capacity) {
        match ColumnBatch::new(width, capacity) {
            Ok(fresh) => *pending = fresh,
            Err(_) => {
                error.send(&format!("cannot allocate a batch of {capacity} rows of {width} recorded values"));
                return FAILED;
            }
        }
    }
    pending.clear();
    let result = catch_unwind(AssertUnwindSafe(|| {
        let (mut steps, mut go_on) = (0u64, true);
        // Inlined into the run's loop (the compiler left it a call).
        let outcome = run.run_while_inlined(
            #[inline(always)]
            |t, signals| {
                recorder.sample_onto(t, signals, pending, G::record_row);
                steps += 1;
                if pending.is_full() {
                    go_on = hand_over(rows, ctx, pending);
                }
                go_on && steps <= max_steps
            },
        );
        recorder.flush(&mut |row| pending.push_slice(row));
        if !pending.is_empty() {
            // The run is over: the answer changes nothing.
            hand_over(rows, ctx, pending);
        }
        outcome
    }));
    run_answer(result, error)
}

/// Hands the batch `pending` to the loader's `rows` and empties it; its
/// answer. Out of line and cold: once in 256 steps, so the step's own
/// closure stays small.
#[cold]
#[inline(never)]
fn hand_over(rows: Rows, ctx: *mut c_void, pending: &mut ColumnBatch) -> bool {
    let (values, width, stride, n) = pending.parts();
    // SAFETY: the loader's `rows` accepts the batch for the call.
    let go_on = unsafe { rows(ctx, values.as_ptr(), n, width, stride) };
    pending.clear();
    go_on
}

/// What an entry answers for `result`: `done` of its value, or `failed`
/// with the error's message (or the panic's) sent to `error`.
fn answer<T, E: std::fmt::Display, R>(
    result: std::thread::Result<Result<T, E>>,
    error: &TextSink,
    done: impl FnOnce(T) -> R,
    failed: R,
) -> R {
    match result {
        Ok(Ok(value)) => done(value),
        Ok(Err(e)) => {
            error.send(&e.to_string());
            failed
        }
        Err(payload) => {
            error.send(&panic_text(payload));
            failed
        }
    }
}

/// A run's outcome as [`RunWhile`] answers it.
fn run_answer(result: std::thread::Result<Result<bool, crate::sim::SimError>>, error: &TextSink) -> i32 {
    answer(result, error, |finished| if finished { FINISHED } else { CUT }, FAILED)
}

unsafe extern "C" fn time<G: Exported>(run: *const c_void) -> f64 {
    // SAFETY: `run` came from `create::<G>`.
    unsafe { library_run_ref::<G>(run) }.run.time()
}

unsafe extern "C" fn stats<G: Exported>(run: *const c_void) -> RunStats {
    // SAFETY: `run` came from `create::<G>`.
    unsafe { library_run_ref::<G>(run) }.run.stats()
}

unsafe extern "C" fn warnings<G: Exported>(run: *const c_void, sink: *const TextSink) {
    // SAFETY: `run` came from `create::<G>`; the loader's sink is valid for the call.
    let (run, sink) = unsafe { (&library_run_ref::<G>(run).run, &*sink) };
    for w in run.warnings() {
        sink.send(w);
    }
}

/// `work`'s answer for a host call: [`DONE`] or [`FAILED`].
fn host_call<E: std::fmt::Display>(error: &TextSink, work: impl FnOnce() -> Result<(), E>) -> i32 {
    answer(catch_unwind(AssertUnwindSafe(work)), error, |()| DONE, FAILED)
}

unsafe extern "C" fn set_input<G: Exported>(
    run: *mut c_void,
    block: usize,
    values: *const f64,
    len: usize,
    error: *const TextSink,
) -> i32 {
    // SAFETY: `run` came from `create::<G>`; `values` holds `len` numbers
    // and `error` is valid, for the call.
    let (run, error) = unsafe { (&mut library_run::<G>(run).run, &*error) };
    // SAFETY: as above (a null pointer is allowed for no values).
    let values = if len == 0 { &[][..] } else { unsafe { std::slice::from_raw_parts(values, len) } };
    host_call(error, || run.set_input(block, values))
}

unsafe extern "C" fn advance_to<G: Exported>(run: *mut c_void, t: f64, error: *const TextSink) -> i32 {
    // SAFETY: `run` came from `create::<G>`; `error` is valid for the call.
    let (run, error) = unsafe { (&mut library_run::<G>(run).run, &*error) };
    host_call(error, || run.advance_to(t))
}

unsafe extern "C" fn signals_now<G: Exported>(run: *mut c_void, len: *mut usize, error: *const TextSink) -> *const f64 {
    // SAFETY: `run` came from `create::<G>`; `len` and `error` are valid for the call.
    let (run, error) = unsafe { (&mut library_run::<G>(run).run, &*error) };
    let mut found = (std::ptr::null(), 0);
    let answer = host_call(error, || run.signals_now().map(|signals| found = (signals.as_ptr(), signals.len())));
    // SAFETY: as above.
    unsafe { *len = found.1 };
    if answer == DONE { found.0 } else { std::ptr::null() }
}

unsafe extern "C" fn save<G: Exported>(run: *const c_void) -> *mut c_void {
    // SAFETY: `run` came from `create::<G>`.
    let run = &unsafe { library_run_ref::<G>(run) }.run;
    // Cloning blocks is plain code that does not panic; were one to, there
    // is no snapshot.
    catch_unwind(AssertUnwindSafe(|| Box::into_raw(Box::new(run.state())).cast())).unwrap_or(std::ptr::null_mut())
}

unsafe extern "C" fn restore<G: Exported>(run: *mut c_void, snapshot: *const c_void, error: *const TextSink) -> i32 {
    // SAFETY: `run` came from `create::<G>`, `snapshot` from `save::<G>`
    // (of the same library: the loader keeps them together).
    let (run, snapshot, error) =
        unsafe { (&mut library_run::<G>(run).run, &*snapshot.cast::<CompiledSnapshot<G>>(), &*error) };
    host_call(error, || run.restore(snapshot))
}

unsafe extern "C" fn drop_snapshot<G: Exported>(snapshot: *mut c_void) {
    if !snapshot.is_null() {
        // SAFETY: `snapshot` came from `save::<G>` and is dropped once.
        let _ =
            catch_unwind(AssertUnwindSafe(|| drop(unsafe { Box::from_raw(snapshot.cast::<CompiledSnapshot<G>>()) })));
    }
}
