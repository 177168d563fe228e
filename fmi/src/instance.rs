//! One FMU instance in Rust terms: the graph loaded from the FMU's
//! resources, its variables, its run, and the FMI state machine of a
//! co-simulation slave (FMI 3.0 §4.2.3, FMI 2.0.4 §4.2.4) — shared by the
//! FMI 3 and FMI 2 entry points, which only translate types.
//!
//! The run is ctlgraph's own: the graph is loaded, compiled and simulated
//! by the same loader, compiler and driver as `ctlgraph run`, and a
//! `doStep` is [`Simulator::advance_to`] the communication point, so a
//! fixed-step graph stepped on its grid gives `ctlgraph run`'s numbers to
//! the bit.

use crate::config::Config;
use crate::replay::{Log, Saved};
use crate::table::{Causality, Place, Variable, Version, variables};
use ctlgraph_core::{Model, Simulator};
use std::path::{Path, PathBuf};
use std::sync::Arc;

/// Where an instance is in the co-simulation state machine.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Mode {
    Instantiated,
    Initialization,
    Step,
    Terminated,
    /// A step failed: only getting values, the state, reset and free remain.
    Failed,
}

/// An instance's run: the simulator, the parameter values and inputs it
/// started from, and what has happened to it since (its replay log).
pub(crate) struct Run {
    pub sim: Simulator,
    pub parameters: Vec<f64>,
    pub initial_inputs: Vec<Vec<f64>>,
    pub log: Log,
}

pub struct Instance {
    pub version: Version,
    graph_text: String,
    graph_file: Arc<str>,
    config: Config,
    variables: Vec<Variable>,
    /// Value reference → index in `variables` (references are dense).
    by_reference: Vec<Option<usize>>,
    input_names: Vec<String>,
    /// The graph's own parameter values, and the present ones.
    defaults: Vec<f64>,
    pub(crate) parameters: Vec<f64>,
    /// The inports' `value`s, and the present inputs.
    input_starts: Vec<Vec<f64>>,
    pub(crate) inputs: Vec<Vec<f64>>,
    pub(crate) stop: Option<f64>,
    pub(crate) run: Option<Run>,
    pub(crate) mode: Mode,
}

impl Instance {
    /// Loads the graph in `resources` (the FMU's `resources/` folder) and
    /// checks that it is the FMU `token` names.
    pub fn new(resources: &Path, token: &str, version: Version) -> Result<Instance, String> {
        let config = Config::read(resources)?;
        if config.token != token {
            return Err(format!(
                "the instantiation token `{token}` is not this FMU's (`{}`): the modelDescription.xml and the \
                 resources belong to different exports",
                config.token
            ));
        }
        let path: PathBuf = resources.join(&config.graph);
        let graph_text = std::fs::read_to_string(&path)
            .map_err(|e| format!("cannot read the graph {} in the FMU's resources: {e}", path.display()))?;
        let graph_file: Arc<str> = path.display().to_string().into();
        let model = compile(&graph_text, &graph_file, &config.sets)?;
        let variables = variables(&model, version)?;
        let top = variables.iter().map(|v| v.value_reference as usize + 1).max().unwrap_or(0);
        let mut by_reference = vec![None; top];
        for (i, v) in variables.iter().enumerate() {
            by_reference[v.value_reference as usize] = Some(i);
        }
        let input_names = model.external_inputs.iter().map(|(n, _)| n.clone()).collect();
        let input_starts: Vec<Vec<f64>> =
            model.external_inputs.iter().map(|(_, b)| crate::table::input_start(&model, *b)).collect();
        let defaults: Vec<f64> = model.parameters.iter().map(|(_, v)| *v).collect();
        Ok(Instance {
            version,
            graph_text,
            graph_file,
            config,
            variables,
            by_reference,
            input_names,
            parameters: defaults.clone(),
            defaults,
            inputs: input_starts.clone(),
            input_starts,
            stop: None,
            run: None,
            mode: Mode::Instantiated,
        })
    }

    /// The experiment (FMI 2's `fmi2SetupExperiment`, FMI 3's arguments
    /// to `fmi3EnterInitializationMode`): ctlgraph's graphs start at t = 0,
    /// and a stop time, when given, is the run's (the adaptive methods'
    /// default largest step follows it, as `ctlgraph run --stop-time` does).
    pub fn setup_experiment(&mut self, start: f64, stop: Option<f64>) -> Result<(), String> {
        self.expect(&[Mode::Instantiated], "set up the experiment")?;
        if start != 0.0 {
            return Err(format!(
                "start time {start}: a ctlgraph graph starts at t = 0 (shift the master's time axis instead)"
            ));
        }
        if let Some(s) = stop.filter(|s| !(s.is_finite() && *s > 0.0)) {
            return Err(format!("stop time {s}: must be a positive number of seconds"));
        }
        self.stop = stop;
        Ok(())
    }

    /// Enters initialisation mode: parameters and inputs may still be set.
    pub fn enter_initialization(&mut self) -> Result<(), String> {
        self.expect(&[Mode::Instantiated], "enter initialisation mode")?;
        self.run = None;
        self.mode = Mode::Initialization;
        Ok(())
    }

    /// Leaves initialisation: the graph is compiled with the parameters
    /// set, and its outputs at t = 0 computed.
    pub fn exit_initialization(&mut self) -> Result<(), String> {
        self.expect(&[Mode::Initialization], "exit initialisation mode")?;
        self.ensure_run()?.sim.signals_now().map_err(|e| e.to_string())?;
        self.mode = Mode::Step;
        Ok(())
    }

    /// `doStep`: from the communication point `t` (the instance's time)
    /// to `t + h`, landing exactly there.
    pub fn do_step(&mut self, t: f64, h: f64) -> Result<f64, String> {
        self.expect(&[Mode::Step], "do a step")?;
        let run = self.run.as_mut().ok_or("no run (internal error)")?;
        let now = run.sim.time();
        if (t - now).abs() > 1e-10 * now.abs().max(1.0) {
            return Err(format!("communication point {t}: the FMU is at t = {now}"));
        }
        if !(h >= 0.0 && h.is_finite()) {
            return Err(format!("communication step size {h}: must be a finite number ≥ 0"));
        }
        let to = now + h;
        run.log.advance(to);
        if let Err(e) = run.sim.advance_to(to) {
            self.mode = Mode::Failed;
            return Err(format!("the step from t = {now} to {to} failed: {e}"));
        }
        Ok(run.sim.time())
    }

    pub fn terminate(&mut self) -> Result<(), String> {
        self.expect(&[Mode::Step, Mode::Failed, Mode::Initialization], "terminate")?;
        self.mode = Mode::Terminated;
        Ok(())
    }

    /// Back to just after instantiation: the file's parameter values and
    /// inport values, no run.
    pub fn reset(&mut self) {
        self.parameters.clone_from(&self.defaults);
        self.inputs.clone_from(&self.input_starts);
        self.stop = None;
        self.run = None;
        self.mode = Mode::Instantiated;
    }

    /// The values of the variables `references`, one number per element,
    /// into `values`.
    pub fn get(&mut self, references: &[u32], values: &mut [f64]) -> Result<(), String> {
        self.check_count(references, values.len())?;
        let needs_run =
            references.iter().any(|&r| matches!(self.variable(r).map(|v| &v.place), Ok(Place::Signal { .. })));
        if needs_run && self.mode == Mode::Instantiated {
            return Err("outputs and recorded signals are computed from initialisation mode on".to_string());
        }
        if needs_run {
            // Outputs computed at the present time, then read in place.
            self.ensure_run()?.sim.signals_now().map_err(|e| e.to_string())?;
        }
        let (time, signals) = self.run.as_ref().map_or((0.0, &[][..]), |r| (r.sim.time(), r.sim.signals()));
        let mut k = 0;
        for &r in references {
            let v = self.variable(r)?;
            let n = v.len();
            let out = &mut values[k..k + n];
            match &v.place {
                Place::Time => out[0] = time,
                Place::Input { index, elements } => out.copy_from_slice(&self.inputs[*index][elements.clone()]),
                Place::Parameter(i) => out[0] = self.parameters[*i],
                Place::Signal { offset, width } => out.copy_from_slice(&signals[*offset..*offset + *width]),
            }
            k += n;
        }
        Ok(())
    }

    /// Sets inputs (any time) and parameters (before the end of
    /// initialisation: they are compiled into the blocks).
    pub fn set(&mut self, references: &[u32], values: &[f64]) -> Result<(), String> {
        self.check_count(references, values.len())?;
        if self.mode == Mode::Terminated {
            return Err("the instance is terminated: reset it first".to_string());
        }
        let mut k = 0;
        for &r in references {
            // The place only (no allocation at a set); the variable again for a message.
            let (place, len) = self.variable(r).map(|v| (v.place.clone(), v.len()))?;
            let given = &values[k..k + len];
            k += len;
            if let Some(bad) = given.iter().find(|x| !x.is_finite()) {
                let v = self.variable(r)?;
                return Err(format!("{} `{}`: {bad} is not a finite number", v.causality.text(), v.name));
            }
            match place {
                Place::Input { index, elements } => {
                    self.inputs[index][elements].copy_from_slice(given);
                    if let Some(run) = self.run.as_mut() {
                        let value = self.inputs[index].clone();
                        run.sim.set_input(&self.input_names[index], &value).map_err(|d| d.to_string())?;
                        run.log.input(index, value);
                    }
                }
                Place::Parameter(i) => {
                    if !matches!(self.mode, Mode::Instantiated | Mode::Initialization) {
                        let v = self.variable(r)?;
                        return Err(format!(
                            "parameter `{}` is fixed after initialisation (it is compiled into the blocks): \
                             set it before exitInitializationMode, or reset the instance",
                            v.name
                        ));
                    }
                    self.parameters[i] = given[0];
                }
                Place::Time | Place::Signal { .. } => {
                    let v = self.variable(r)?;
                    return Err(format!(
                        "`{}` is {} a {}: only inputs and parameters are set",
                        v.name,
                        article(v.causality),
                        v.causality.text()
                    ));
                }
            }
        }
        Ok(())
    }

    /// The run, compiled with the present parameters if it is not.
    fn ensure_run(&mut self) -> Result<&mut Run, String> {
        let stale = self.run.as_ref().is_none_or(|r| r.parameters != self.parameters);
        if stale {
            let sim = self.simulator(&self.parameters)?;
            let mut run = Run {
                sim,
                parameters: self.parameters.clone(),
                initial_inputs: self.inputs.clone(),
                log: Log::default(),
            };
            for (name, value) in self.input_names.iter().zip(&self.inputs) {
                run.sim.set_input(name, value).map_err(|d| d.to_string())?;
            }
            self.run = Some(run);
        }
        self.run.as_mut().ok_or_else(|| "no run (internal error)".to_string())
    }

    /// A simulator of the graph with `parameters`, at t = 0.
    pub(crate) fn simulator(&self, parameters: &[f64]) -> Result<Simulator, String> {
        let mut sets = self.config.sets.clone();
        for (((name, _), value), default) in self.names_and_defaults().zip(parameters).zip(&self.defaults) {
            if value.to_bits() != default.to_bits() {
                // Rust's `{}` of an f64 is its shortest decimal that reads back to the same bits.
                sets.push((name.to_string(), format!("{value}")));
            }
        }
        let model = compile(&self.graph_text, &self.graph_file, &sets)?;
        // The same variables in the same places; parameters' and inputs' starts may differ.
        let shape = |v: &Variable| (v.name.clone(), v.value_reference, v.causality, v.place.clone(), v.dims);
        let same = variables(&model, self.version)
            .map(|v| v.iter().map(shape).eq(self.variables.iter().map(shape)))
            .unwrap_or(false);
        if !same {
            return Err("the parameters set change the graph's inputs, outputs or recorded signals (their widths): \
                        an FMU's variables are fixed at export — export it with these values (`--set`)"
                .to_string());
        }
        Ok(Simulator::new(model, self.stop))
    }

    fn names_and_defaults(&self) -> impl Iterator<Item = (&str, f64)> {
        let params = self.variables.iter().filter(|v| v.causality == Causality::Parameter);
        params.map(|v| (v.name.as_str(), v.start.as_ref().and_then(|s| s.first().copied()).unwrap_or(0.0)))
    }

    fn variable(&self, reference: u32) -> Result<&Variable, String> {
        self.by_reference
            .get(reference as usize)
            .copied()
            .flatten()
            .map(|i| &self.variables[i])
            .ok_or_else(|| format!("no variable has value reference {reference}"))
    }

    fn check_count(&self, references: &[u32], n_values: usize) -> Result<(), String> {
        let mut expected = 0;
        for &r in references {
            expected += self.variable(r)?.len();
        }
        if expected != n_values {
            return Err(format!(
                "{} value reference(s) hold {expected} value(s), given room for {n_values}",
                references.len()
            ));
        }
        Ok(())
    }

    fn expect(&self, modes: &[Mode], what: &str) -> Result<(), String> {
        if modes.contains(&self.mode) { Ok(()) } else { Err(format!("cannot {what} in {:?} mode", self.mode)) }
    }

    /// The instance's state, to come back to ([`Instance::restore`]).
    pub fn save(&self) -> Saved {
        Saved {
            mode: self.mode,
            parameters: self.parameters.clone(),
            inputs: self.inputs.clone(),
            stop: self.stop,
            run: self.run.as_ref().map(|r| crate::replay::SavedRun {
                snapshot: Some(r.sim.state()),
                parameters: r.parameters.clone(),
                initial_inputs: r.initial_inputs.clone(),
                log: r.log.clone(),
            }),
        }
    }

    /// Returns to `saved`: the run's snapshot when it was taken of this
    /// instance's present simulator, else a simulator rebuilt and replayed
    /// from the log (after a reset, or from a deserialised state).
    pub fn restore(&mut self, saved: &Saved) -> Result<(), String> {
        self.mode = saved.mode;
        self.parameters.clone_from(&saved.parameters);
        self.inputs.clone_from(&saved.inputs);
        self.stop = saved.stop;
        let Some(s) = &saved.run else {
            self.run = None;
            return Ok(());
        };
        if let (Some(run), Some(snapshot)) = (self.run.as_mut(), &s.snapshot)
            && run.sim.restore(snapshot).is_ok()
        {
            run.parameters.clone_from(&s.parameters);
            run.initial_inputs.clone_from(&s.initial_inputs);
            run.log.clone_from(&s.log);
            return Ok(());
        }
        self.run = Some(crate::replay::replay(self, s)?);
        Ok(())
    }

    pub(crate) fn input_name(&self, index: usize) -> &str {
        &self.input_names[index]
    }

    pub fn token(&self) -> &str {
        &self.config.token
    }
}

fn article(c: Causality) -> &'static str {
    match c {
        Causality::Independent | Causality::Input | Causality::Output => "an",
        _ => "a",
    }
}

/// The graph `text` (the file `file`) with `sets`, compiled.
fn compile(text: &str, file: &Arc<str>, sets: &[(String, String)]) -> Result<Model, String> {
    let flat = ctlgraph_core::load_str(text, file.clone(), sets).map_err(|d| d.to_string())?;
    ctlgraph_core::compile(&flat, &ctlgraph_blocks::registry()).map_err(|d| d.to_string())
}
