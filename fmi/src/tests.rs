//! The FMI 3 and FMI 2 functions called in process, as an importer calls
//! them, on FMUs unpacked into temporary folders: the numbers equal
//! ctlgraph's own run, instances are independent, states replay to the
//! bit, and bad use is an error status with a logged message.

use crate::fmi2::{self, CallbackFunctions};
use crate::fmi3::*;
use crate::package::package;
use crate::table::Version;
use std::ffi::{CStr, CString, c_char, c_void};
use std::path::{Path, PathBuf};
use std::sync::Mutex;

/// Messages the logger callbacks received (tests run in parallel: each
/// test keeps the ones naming its instances).
static LOGGED: Mutex<Vec<String>> = Mutex::new(Vec::new());

unsafe extern "C" fn log3(_env: *mut c_void, status: i32, category: *const c_char, message: *const c_char) {
    // SAFETY: the strings the library passes.
    let (c, m) = unsafe { (CStr::from_ptr(category), CStr::from_ptr(message)) };
    LOGGED.lock().unwrap().push(format!("{status} {}: {}", c.to_string_lossy(), m.to_string_lossy()));
}

fn logged(containing: &str) -> Vec<String> {
    LOGGED.lock().unwrap().iter().filter(|m| m.contains(containing)).cloned().collect()
}

fn root() -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).join("..")
}

/// The graph `rel` (from the workspace) unpacked as an FMU under a fresh
/// folder; returns the folder.
fn unpacked(rel: &str, version: Version, tag: &str) -> (PathBuf, String) {
    let dir = std::env::temp_dir().join(format!("ctlgraph-fmi-{tag}-{}", std::process::id()));
    let _ = std::fs::remove_dir_all(&dir);
    let p = package(&root().join(rel), &[], version, "t", "ctlgraph test").expect("packages");
    p.write_to(&dir).unwrap();
    (dir, p.token)
}

struct Fmu3 {
    instance: *mut c_void,
}

impl Fmu3 {
    fn new(dir: &Path, token: &str, name: &str) -> Fmu3 {
        let (name, token) = (CString::new(name).unwrap(), CString::new(token).unwrap());
        let resources = CString::new(format!("{}/resources/", dir.display())).unwrap();
        // SAFETY: valid strings and callback.
        let instance = unsafe {
            fmi3InstantiateCoSimulation(
                name.as_ptr(),
                token.as_ptr(),
                resources.as_ptr(),
                false,
                false,
                false,
                false,
                std::ptr::null(),
                0,
                std::ptr::null_mut(),
                Some(log3),
                std::ptr::null(),
            )
        };
        Fmu3 { instance }
    }

    fn start(&self, stop: f64) {
        assert_eq!(fmi3EnterInitializationMode(self.instance, false, 0.0, 0.0, true, stop), 0);
        assert_eq!(fmi3ExitInitializationMode(self.instance), 0);
    }

    fn get(&self, vr: &[u32], n: usize) -> (i32, Vec<f64>) {
        let mut v = vec![f64::NAN; n];
        // SAFETY: arrays of the lengths given.
        let s = unsafe { fmi3GetFloat64(self.instance, vr.as_ptr(), vr.len(), v.as_mut_ptr(), n) };
        (s, v)
    }

    fn set(&self, vr: &[u32], v: &[f64]) -> i32 {
        // SAFETY: as above.
        unsafe { fmi3SetFloat64(self.instance, vr.as_ptr(), vr.len(), v.as_ptr(), v.len()) }
    }

    fn step(&self, t: f64, h: f64) -> i32 {
        let (mut a, mut b, mut c, mut last) = (true, true, true, f64::NAN);
        // SAFETY: valid out-parameters.
        unsafe { fmi3DoStep(self.instance, t, h, true, &mut a, &mut b, &mut c, &mut last) }
    }
}

impl Drop for Fmu3 {
    fn drop(&mut self) {
        // SAFETY: made by instantiation, freed once.
        unsafe { fmi3FreeInstance(self.instance) };
    }
}

/// The LADRC paper loop's recorded signals at every major step, as
/// ctlgraph's own run gives them.
fn reference(rel: &str) -> ctlgraph_core::trace::Trace {
    let flat = ctlgraph_core::load(&root().join(rel), &[]).unwrap();
    let model = ctlgraph_core::compile(&flat, &ctlgraph_blocks::registry()).unwrap();
    ctlgraph_core::trace::simulate(model, None).unwrap()
}

#[test]
fn the_ladrc_loop_stepped_through_fmi3_gives_ctlgraph_runs_numbers_to_the_bit() {
    let rel = "graphs/fladrc/ladrc.yaml";
    let (dir, token) = unpacked(rel, Version::Fmi3, "ladrc3");
    let trace = reference(rel);
    let fmu = Fmu3::new(&dir, &token, "ladrc-a");
    assert!(!fmu.instance.is_null(), "{:?}", logged("ladrc"));
    fmu.start(2.0);
    // Outputs are the recorded signals (the graph has no outport): r, y, u, e, d.
    let outputs: Vec<u32> = (1..=5).collect();
    let h = 1e-3; // ten of the graph's 1e-4 steps per communication step
    let mut compared = 0;
    for k in 0..=2000usize {
        let t = k as f64 * h;
        if k > 0 {
            assert_eq!(fmu.step((k - 1) as f64 * h, h), 0, "{:?}", logged("ladrc"));
        }
        let (s, values) = fmu.get(&outputs, 5);
        assert_eq!(s, 0);
        let row = k * 10;
        assert!((trace.t()[row] - t).abs() < 1e-12);
        for (c, v) in values.iter().enumerate() {
            assert_eq!(v.to_bits(), trace.columns[c + 1][row].to_bits(), "column {} at t = {t}", c + 1);
        }
        compared += 1;
    }
    assert_eq!(compared, 2001);
    let (_, time) = fmu.get(&[0], 1);
    assert_eq!(time, [2.0]);
}

#[test]
fn two_instances_are_independent_and_a_state_replays_to_the_bit() {
    let rel = "graphs/tutorial/pid_loop.yaml";
    let (dir, token) = unpacked(rel, Version::Fmi3, "pid3");
    let (a, b) = (Fmu3::new(&dir, &token, "pid-a"), Fmu3::new(&dir, &token, "pid-b"));
    // A parameter set on one instance only: `kp` is the first parameter.
    let params = package(&root().join(rel), &[], Version::Fmi3, "t", "x").unwrap();
    let kp = params.variables.iter().find(|v| v.name == "kp").expect("kp").value_reference;
    let y = params.variables.iter().find(|v| v.name == "y").expect("y").value_reference;
    assert_eq!(a.set(&[kp], &[4.0]), 0);
    a.start(10.0);
    b.start(10.0);
    let h = 0.01;
    let run = |f: &Fmu3, from: usize, to: usize| -> Vec<u64> {
        (from..to)
            .map(|k| {
                assert_eq!(f.step(k as f64 * h, h), 0, "{:?}", logged("pid-"));
                f.get(&[y], 1).1[0].to_bits()
            })
            .collect()
    };
    let (ya, yb) = (run(&a, 0, 100), run(&b, 0, 100));
    assert_ne!(ya, yb, "kp = 4 on one instance changes its response only");
    // Save at t = 1, run on, come back, run again: the same bits.
    let mut state: *mut c_void = std::ptr::null_mut();
    // SAFETY: a valid state slot.
    assert_eq!(unsafe { fmi3GetFMUState(a.instance, &mut state) }, 0);
    let first = run(&a, 100, 300);
    // SAFETY: the state made above.
    assert_eq!(unsafe { fmi3SetFMUState(a.instance, state) }, 0);
    assert_eq!(run(&a, 100, 300), first, "restored in place");
    // Serialised, reset, deserialised into the same instance: replayed.
    let mut size = 0usize;
    // SAFETY: valid pointers and a buffer of the size asked.
    unsafe {
        assert_eq!(fmi3SerializedFMUStateSize(a.instance, state, &mut size), 0);
        let mut bytes = vec![0u8; size];
        assert_eq!(fmi3SerializeFMUState(a.instance, state, bytes.as_mut_ptr(), size), 0);
        assert_eq!(fmi3Reset(a.instance), 0);
        let mut back: *mut c_void = std::ptr::null_mut();
        assert_eq!(fmi3DeserializeFMUState(a.instance, bytes.as_ptr(), size, &mut back), 0);
        assert_eq!(fmi3SetFMUState(a.instance, back), 0);
        assert_eq!(fmi3FreeFMUState(a.instance, &mut back), 0);
        assert!(back.is_null());
        assert_eq!(fmi3FreeFMUState(a.instance, &mut state), 0);
    }
    assert_eq!(run(&a, 100, 300), first, "deserialised after a reset");
}

#[test]
fn bad_use_is_an_error_status_with_a_logged_message() {
    let rel = "graphs/tutorial/pid_loop.yaml";
    let (dir, token) = unpacked(rel, Version::Fmi3, "bad3");
    // A wrong token, and resources that are not there.
    assert!(Fmu3::new(&dir, "{nope}", "bad-token").instance.is_null());
    assert!(logged("is not this FMU's").iter().any(|m| m.starts_with("3 logStatusError")));
    let missing = dir.join("elsewhere");
    assert!(Fmu3::new(&missing, &token, "bad-missing").instance.is_null());
    assert!(!logged("ctlgraph.json").is_empty());
    let fmu = Fmu3::new(&dir, &token, "bad-use");
    // Stepping before initialisation, an unknown value reference, too few
    // values, a non-finite input or parameter, setting an output.
    assert_eq!(fmu.step(0.0, 0.1), 3);
    assert!(!logged("cannot do a step in Instantiated mode").is_empty());
    assert_eq!(fmu.get(&[999], 1).0, 3);
    assert!(!logged("no variable has value reference 999").is_empty());
    assert_eq!(fmu.get(&[0, 0], 1).0, 3);
    assert_eq!(fmu.set(&[1], &[f64::NAN]), 3);
    assert!(!logged("NaN is not a finite number").is_empty());
    fmu.start(10.0);
    assert_eq!(fmu.step(0.5, 0.1), 3);
    assert!(!logged("communication point 0.5: the FMU is at t = 0").is_empty());
    let outputs = package(&root().join(rel), &[], Version::Fmi3, "t", "x").unwrap();
    let y = outputs.variables.iter().find(|v| v.name == "y").unwrap().value_reference;
    assert_eq!(fmu.set(&[y], &[1.0]), 3);
    let kp = outputs.variables.iter().find(|v| v.name == "kp").unwrap().value_reference;
    assert_eq!(fmu.set(&[kp], &[1.0]), 3);
    assert!(!logged("parameter `kp` is fixed after initialisation").is_empty());
    // Model exchange is refused; a null instance is an error, not a crash.
    assert_eq!(null_instance_step(), 3);
}

fn null_instance_step() -> i32 {
    // SAFETY: null out-parameters are allowed, the instance is checked.
    unsafe {
        fmi3DoStep(
            std::ptr::null_mut(),
            0.0,
            1.0,
            true,
            std::ptr::null_mut(),
            std::ptr::null_mut(),
            std::ptr::null_mut(),
            std::ptr::null_mut(),
        )
    }
}

#[test]
fn fmi2_steps_the_same_numbers_with_vectors_as_scalars() {
    let rel = "graphs/fladrc/ladrc.yaml";
    let (dir, token) = unpacked(rel, Version::Fmi2, "ladrc2");
    let trace = reference(rel);
    let callbacks = CallbackFunctions {
        logger: None,
        allocate_memory: std::ptr::null(),
        free_memory: std::ptr::null(),
        step_finished: std::ptr::null(),
        component_environment: std::ptr::null_mut(),
    };
    let (name, guid) = (CString::new("ladrc2").unwrap(), CString::new(token).unwrap());
    let uri = CString::new(format!("file://{}/resources", dir.display())).unwrap();
    // SAFETY: valid strings and callbacks; the calls follow the FMI 2 order.
    unsafe {
        let c = fmi2::fmi2Instantiate(name.as_ptr(), 1, guid.as_ptr(), uri.as_ptr(), &callbacks, 0, 0);
        assert!(!c.is_null());
        assert_eq!(fmi2::fmi2SetupExperiment(c, 0, 0.0, 0.0, 1, 2.0), 0);
        assert_eq!(fmi2::fmi2EnterInitializationMode(c), 0);
        assert_eq!(fmi2::fmi2ExitInitializationMode(c), 0);
        let vr = [1u32, 2, 3, 4, 5];
        let mut v = [0.0; 5];
        for k in 0..200usize {
            assert_eq!(fmi2::fmi2DoStep(c, k as f64 * 0.01, 0.01, 1), 0);
            assert_eq!(fmi2::fmi2GetReal(c, vr.as_ptr(), 5, v.as_mut_ptr()), 0);
            let row = (k + 1) * 100;
            for (i, x) in v.iter().enumerate() {
                assert_eq!(x.to_bits(), trace.columns[i + 1][row].to_bits());
            }
        }
        let mut last = 0.0;
        assert_eq!(fmi2::fmi2GetRealStatus(c, 2, &mut last), 0);
        assert_eq!(last, 2.0);
        fmi2::fmi2FreeInstance(c);
    }
}
