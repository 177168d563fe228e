//! Property testing of whole graphs (`ctlgraph prop`): draw parameter sets
//! from ranges, run the graph, evaluate its checks, and when a set fails,
//! shrink it toward the graph's own (nominal) values with proptest's value
//! trees, so the report is the smallest failing change.

use crate::accel::Runner;
use crate::suite::{Failure, run_checks_by};
use ctlgraph_core::Diagnostic;
use ctlgraph_core::checks::CheckResult;
use proptest::strategy::{BoxedStrategy, Strategy, ValueTree};
use proptest::test_runner::{Config, RngAlgorithm, TestRng, TestRunner};
use rayon::prelude::*;
use std::path::Path;

/// Resolution of a varied parameter: its range in this many steps.
const GRID_STEPS: f64 = 1048576.0;

/// A parameter to vary over `[lo, hi]`.
#[derive(Clone, Debug, PartialEq)]
pub struct Vary {
    pub name: String,
    pub lo: f64,
    pub hi: f64,
}

impl Vary {
    /// Parses `NAME=LO..HI` (bounds may be expressions-free numbers).
    pub fn parse(arg: &str) -> Result<Vary, Diagnostic> {
        let bad = || Diagnostic::plain(format!("--vary {arg}: expected NAME=LO..HI, e.g. w0=500..2000"));
        let (name, range) = arg.split_once('=').ok_or_else(bad)?;
        let (lo, hi) = range.split_once("..").ok_or_else(bad)?;
        let (lo, hi) = (lo.trim().parse::<f64>().map_err(|_| bad())?, hi.trim().parse::<f64>().map_err(|_| bad())?);
        if !lo.is_finite() || !hi.is_finite() || lo >= hi || !(hi - lo).is_finite() {
            return Err(Diagnostic::plain(format!("--vary {arg}: need finite LO < HI with a finite span")));
        }
        Ok(Vary { name: name.trim().to_string(), lo, hi })
    }
}

/// Settings of a property run.
#[derive(Clone, Debug)]
pub struct PropConfig {
    pub vary: Vec<Vary>,
    /// Also draw the simulation seed (noise realisations).
    pub vary_seed: bool,
    pub cases: u32,
    pub seed: u64,
}

/// One parameter set: values in `vary` order, and the seed if drawn.
#[derive(Clone, Debug, PartialEq)]
pub struct Case {
    pub values: Vec<(String, f64)>,
    pub seed: Option<u64>,
}

impl Case {
    /// `ctlgraph run GRAPH --set a=1 …` reproducing this case.
    pub fn command(&self, graph: &Path) -> String {
        let mut cmd = format!("ctlgraph run {}", graph.display());
        for (n, v) in &self.values {
            cmd.push_str(&format!(" --set {n}={v}"));
        }
        if let Some(s) = self.seed {
            cmd.push_str(&format!(" --seed {s}"));
        }
        cmd
    }
}

/// What a property run found.
pub enum PropOutcome {
    /// Every case passed.
    Held { cases: u32 },
    /// A failing case, shrunk: the minimal set, why it fails, and how many
    /// cases ran before the first failure.
    Failed { minimal: Case, reason: Result<Vec<CheckResult>, Failure>, after: u32, shrink_steps: u32 },
}

/// Runs one case by `runner`: the graph with the case's overrides;
/// `Ok(false)` when a check fails or the run fails.
fn evaluate(runner: &Runner, graph: &Path, case: &Case) -> (bool, Result<Vec<CheckResult>, Failure>) {
    let sets: Vec<(String, String)> = case.values.iter().map(|(n, v)| (n.clone(), v.to_string())).collect();
    let result = crate::compile_file_seeded(graph, &sets, case.seed)
        .map_err(Failure::from)
        .and_then(|model| run_checks_by(runner, model, &sets, case.seed, None).map(|(_, r)| r));
    let passed = matches!(&result, Ok(r) if r.iter().all(|c| c.passed));
    (passed, result)
}

/// Draws `cases` parameter sets, runs them in parallel, and shrinks the
/// first failure (in draw order, so results do not depend on scheduling).
/// Runs the property test by `runner`; `tick` is called after every run of
/// the graph (the drawn cases, then each shrinking step), for progress display.
pub fn run(runner: &Runner, graph: &Path, cfg: &PropConfig, tick: &(dyn Fn() + Sync)) -> Result<PropOutcome, Failure> {
    let evaluate = |graph: &Path, case: &Case| {
        let verdict = evaluate(runner, graph, case);
        tick();
        verdict
    };
    let model = crate::compile_file(graph, &[])?;
    if model.checks.is_empty() {
        return Err(Diagnostic::in_file(&graph.display().to_string(), "has no `checks:` to test").into());
    }
    for (i, v) in cfg.vary.iter().enumerate() {
        if cfg.vary[..i].iter().any(|w| w.name == v.name) {
            return Err(Diagnostic::plain(format!("--vary {}: given twice", v.name)).into());
        }
    }
    let flat = ctlgraph_core::load(graph, &[])?;
    let mut steps_from_nominal: Vec<BoxedStrategy<i64>> = Vec::new();
    let mut grid = Vec::new();
    for v in &cfg.vary {
        let Some(&(_, nom)) = flat.parameters.iter().find(|(n, _)| *n == v.name) else {
            let names = flat.parameters.iter().map(|(n, _)| n.as_str());
            return Err(Diagnostic::plain(format!(
                "--vary {}: {} has no parameter `{}`",
                v.name,
                graph.display(),
                v.name
            ))
            .suggest(&v.name, names)
            .into());
        };
        // Values lie on a fine grid of GRID_STEPS steps over the range,
        // counted from the nominal value: proptest shrinks integers by
        // bisection toward 0, i.e. toward the graph as written (or the
        // nearest bound when that lies outside the range). Its float
        // shrinking only tries the extremes, too coarse for a threshold.
        let q = (v.hi - v.lo) / GRID_STEPS;
        let (lo, hi) = (((v.lo - nom) / q).ceil() as i64, ((v.hi - nom) / q).floor() as i64);
        steps_from_nominal.push((lo..=hi).boxed());
        grid.push((nom, q));
    }
    let seeds = if cfg.vary_seed {
        (0u64..u32::MAX as u64).prop_map(Some).boxed()
    } else {
        proptest::strategy::Just(None).boxed()
    };
    let strategy = (steps_from_nominal, seeds);
    let mut seed_bytes = [0u8; 32];
    seed_bytes[..8].copy_from_slice(&cfg.seed.to_le_bytes());
    let rng = TestRng::from_seed(RngAlgorithm::ChaCha, &seed_bytes);
    let mut runner = TestRunner::new_with_rng(Config::default(), rng);
    let to_case = |(steps, seed): (Vec<i64>, Option<u64>)| Case {
        values: cfg
            .vary
            .iter()
            .zip(&grid)
            .zip(steps)
            .map(|((v, &(nom, q)), k)| (v.name.clone(), (nom + k as f64 * q).clamp(v.lo, v.hi)))
            .collect(),
        seed,
    };
    let mut trees = Vec::with_capacity(cfg.cases as usize);
    for _ in 0..cfg.cases {
        trees.push(strategy.new_tree(&mut runner).map_err(|e| Failure::Run(format!("drawing cases: {e}")))?);
    }
    let drawn: Vec<Case> = trees.iter().map(|t| to_case(t.current())).collect();
    let verdicts: Vec<bool> = drawn.par_iter().map(|case| evaluate(graph, case).0).collect();
    let Some(first) = verdicts.iter().position(|ok| !ok) else {
        return Ok(PropOutcome::Held { cases: cfg.cases });
    };
    // proptest's shrinking loop: simplify while the case still fails,
    // complicate (step back) when it starts passing.
    let mut tree = trees.swap_remove(first);
    let mut minimal = to_case(tree.current());
    let mut steps = 0;
    if tree.simplify() {
        while steps < 500 {
            steps += 1;
            let case = to_case(tree.current());
            if !evaluate(graph, &case).0 {
                minimal = case;
                if !tree.simplify() {
                    break;
                }
            } else if !tree.complicate() {
                break;
            }
        }
    }
    // proptest stops once one parameter's bisection ends; parameters that
    // do not matter for the failure go back to the graph's own values.
    for (i, &(nom, _)) in grid.iter().enumerate() {
        let v = &cfg.vary[i];
        let mut trial = minimal.clone();
        trial.values[i].1 = nom.clamp(v.lo, v.hi);
        if trial != minimal && !evaluate(graph, &trial).0 {
            minimal = trial;
            steps += 1;
        }
    }
    let reason = evaluate(graph, &minimal).1;
    Ok(PropOutcome::Failed { minimal, reason, after: first as u32 + 1, shrink_steps: steps })
}
