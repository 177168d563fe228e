//! Model exchange's calls on an instance (FMI 3.0 §3, FMI 2.0.4 §3): time
//! and states in, derivatives and event indicators out, and the event
//! iteration — `updateDiscreteStates` (FMI 2: `fmi2NewDiscreteStates`)
//! until the FMU needs no more, between entering event mode and returning
//! to continuous-time mode.

#![allow(non_snake_case)]

use super::binding::{Instance, get};
use super::description::Version;
use std::ffi::{c_int, c_void};

type Status = c_int;
type Unary = unsafe extern "C" fn(*mut c_void) -> Status;
type SetTime = unsafe extern "C" fn(*mut c_void, f64) -> Status;
type SetArray = unsafe extern "C" fn(*mut c_void, *const f64, usize) -> Status;
type GetArray = unsafe extern "C" fn(*mut c_void, *mut f64, usize) -> Status;
type Count3 = unsafe extern "C" fn(*mut c_void, *mut usize) -> Status;
type Update3 =
    unsafe extern "C" fn(*mut c_void, *mut bool, *mut bool, *mut bool, *mut bool, *mut bool, *mut f64) -> Status;
type Completed3 = unsafe extern "C" fn(*mut c_void, bool, *mut bool, *mut bool) -> Status;
type NewDiscrete2 = unsafe extern "C" fn(*mut c_void, *mut EventInfo2) -> Status;
type Completed2 = unsafe extern "C" fn(*mut c_void, c_int, *mut c_int, *mut c_int) -> Status;

/// `fmi2EventInfo`.
#[repr(C)]
#[derive(Default)]
struct EventInfo2 {
    new_discrete_states_needed: c_int,
    terminate_simulation: c_int,
    nominals_changed: c_int,
    values_changed: c_int,
    next_event_time_defined: c_int,
    next_event_time: f64,
}

/// The functions model exchange calls, by version.
pub(super) struct MeFunctions {
    enter_event_mode: Unary,
    enter_continuous_time_mode: Unary,
    set_time: SetTime,
    set_states: SetArray,
    get_states: GetArray,
    derivatives: GetArray,
    indicators: GetArray,
    iteration: Iteration,
}

enum Iteration {
    V3 { update: Update3, completed: Completed3, n_states: Count3, n_indicators: Count3 },
    V2 { new_discrete: NewDiscrete2, completed: Completed2 },
}

impl MeFunctions {
    pub(super) fn load(lib: &libloading::Library, version: Version) -> Result<MeFunctions, String> {
        Ok(match version {
            Version::Fmi3 => MeFunctions {
                enter_event_mode: get(lib, "fmi3EnterEventMode")?,
                enter_continuous_time_mode: get(lib, "fmi3EnterContinuousTimeMode")?,
                set_time: get(lib, "fmi3SetTime")?,
                set_states: get(lib, "fmi3SetContinuousStates")?,
                get_states: get(lib, "fmi3GetContinuousStates")?,
                derivatives: get(lib, "fmi3GetContinuousStateDerivatives")?,
                indicators: get(lib, "fmi3GetEventIndicators")?,
                iteration: Iteration::V3 {
                    update: get(lib, "fmi3UpdateDiscreteStates")?,
                    completed: get(lib, "fmi3CompletedIntegratorStep")?,
                    n_states: get(lib, "fmi3GetNumberOfContinuousStates")?,
                    n_indicators: get(lib, "fmi3GetNumberOfEventIndicators")?,
                },
            },
            Version::Fmi2 => MeFunctions {
                enter_event_mode: get(lib, "fmi2EnterEventMode")?,
                enter_continuous_time_mode: get(lib, "fmi2EnterContinuousTimeMode")?,
                set_time: get(lib, "fmi2SetTime")?,
                set_states: get(lib, "fmi2SetContinuousStates")?,
                get_states: get(lib, "fmi2GetContinuousStates")?,
                derivatives: get(lib, "fmi2GetDerivatives")?,
                indicators: get(lib, "fmi2GetEventIndicators")?,
                iteration: Iteration::V2 {
                    new_discrete: get(lib, "fmi2NewDiscreteStates")?,
                    completed: get(lib, "fmi2CompletedIntegratorStep")?,
                },
            },
        })
    }
}

/// What an event iteration left: whether the continuous states changed
/// (they must be read back), the next time event, a request to stop.
pub struct Settled {
    pub states_changed: bool,
    pub next_time: Option<f64>,
    pub terminate: bool,
}

/// The most `updateDiscreteStates` calls at one event before the FMU is
/// taken to be iterating without end.
const MAX_ITERATIONS: usize = 1000;

impl Instance {
    fn me(&self) -> Result<&MeFunctions, String> {
        self.binary().me.as_ref().ok_or_else(|| "the FMU was loaded for co-simulation".to_string())
    }

    /// Sets the time and the continuous states (length as the FMU's).
    pub fn set_time_and_states(&mut self, t: f64, x: &[f64]) -> Result<(), String> {
        let f = self.me()?;
        let (set_time, set_states) = (f.set_time, f.set_states);
        // SAFETY: the FMI signatures on this instance; `x` holds `x.len()` numbers.
        self.check("setting the time", unsafe { set_time(self.handle(), t) })?;
        if x.is_empty() {
            return Ok(());
        }
        self.check("setting the continuous states", unsafe { set_states(self.handle(), x.as_ptr(), x.len()) })
    }

    fn get_array(&mut self, what: &str, f: GetArray, out: &mut [f64]) -> Result<(), String> {
        if out.is_empty() {
            return Ok(());
        }
        // SAFETY: `out` holds `out.len()` numbers.
        self.check(what, unsafe { f(self.handle(), out.as_mut_ptr(), out.len()) })
    }

    pub fn derivatives(&mut self, dx: &mut [f64]) -> Result<(), String> {
        let f = self.me()?.derivatives;
        self.get_array("getting the state derivatives", f, dx)
    }

    pub fn event_indicators(&mut self, z: &mut [f64]) -> Result<(), String> {
        let f = self.me()?.indicators;
        self.get_array("getting the event indicators", f, z)
    }

    pub fn states(&mut self, x: &mut [f64]) -> Result<(), String> {
        let f = self.me()?.get_states;
        self.get_array("getting the continuous states", f, x)
    }

    /// FMI 3's counts of states and event indicators, checked against the
    /// description's (FMI 2 has no such call: the description is all).
    pub fn check_counts(&mut self, states: usize, indicators: usize) -> Result<(), String> {
        let Iteration::V3 { n_states, n_indicators, .. } = self.me()?.iteration else { return Ok(()) };
        let (mut ns, mut ni) = (0usize, 0usize);
        // SAFETY: the FMI 3 signatures, with valid out-parameters.
        self.check("counting the states", unsafe { n_states(self.handle(), &mut ns) })?;
        self.check("counting the event indicators", unsafe { n_indicators(self.handle(), &mut ni) })?;
        if (ns, ni) != (states, indicators) {
            return Err(format!(
                "the FMU reports {ns} continuous states and {ni} event indicators, its description {states} and {indicators}"
            ));
        }
        Ok(())
    }

    /// After an accepted step: whether the FMU asks for event mode.
    pub fn completed_integrator_step(&mut self) -> Result<bool, String> {
        let (mut enter, mut terminate) = (false, false);
        let status = match self.me()?.iteration {
            // SAFETY: the FMI signatures, with valid out-parameters.
            Iteration::V3 { completed, .. } => unsafe { completed(self.handle(), true, &mut enter, &mut terminate) },
            Iteration::V2 { completed, .. } => {
                let (mut e, mut t) = (0, 0);
                let s = unsafe { completed(self.handle(), 1, &mut e, &mut t) };
                (enter, terminate) = (e != 0, t != 0);
                s
            }
        };
        self.check("completedIntegratorStep", status)?;
        if terminate {
            return Err("the FMU asked to terminate the simulation".to_string());
        }
        Ok(enter)
    }

    pub fn enter_event_mode(&mut self) -> Result<(), String> {
        let f = self.me()?.enter_event_mode;
        // SAFETY: the FMI signature on this instance.
        self.check("entering event mode", unsafe { f(self.handle()) })
    }

    /// The event iteration, in event mode, then back to continuous time.
    pub fn settle(&mut self) -> Result<Settled, String> {
        let iteration = match &self.me()?.iteration {
            Iteration::V3 { update, .. } => Ok(*update),
            Iteration::V2 { new_discrete, .. } => Err(*new_discrete),
        };
        let mut settled = Settled { states_changed: false, next_time: None, terminate: false };
        for _ in 0..MAX_ITERATIONS {
            let (again, terminate, changed, next) = match iteration {
                Ok(update) => {
                    let (mut again, mut terminate, mut nominals, mut changed, mut defined, mut next) =
                        (false, false, false, false, false, 0.0);
                    // SAFETY: the FMI 3 signature, with valid out-parameters.
                    let s = unsafe {
                        update(
                            self.handle(),
                            &mut again,
                            &mut terminate,
                            &mut nominals,
                            &mut changed,
                            &mut defined,
                            &mut next,
                        )
                    };
                    self.check("updateDiscreteStates", s)?;
                    (again, terminate, changed, defined.then_some(next))
                }
                Err(new_discrete) => {
                    let mut info = EventInfo2::default();
                    // SAFETY: the FMI 2 signature, with a valid event info.
                    self.check("fmi2NewDiscreteStates", unsafe { new_discrete(self.handle(), &mut info) })?;
                    let next = (info.next_event_time_defined != 0).then_some(info.next_event_time);
                    (
                        info.new_discrete_states_needed != 0,
                        info.terminate_simulation != 0,
                        info.values_changed != 0,
                        next,
                    )
                }
            };
            settled.states_changed |= changed;
            settled.terminate |= terminate;
            settled.next_time = next;
            if !again {
                let f = self.me()?.enter_continuous_time_mode;
                // SAFETY: the FMI signature on this instance.
                self.check("entering continuous-time mode", unsafe { f(self.handle()) })?;
                return Ok(settled);
            }
        }
        Err(format!("the event iteration did not settle in {MAX_ITERATIONS} updates of the discrete states"))
    }
}
