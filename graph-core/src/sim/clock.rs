//! How a run keeps time: the fixed-step grid and the discrete rates'
//! clocks, counted in whole ticks (never by adding up floating-point
//! steps), kept by the driver (`driver.rs`) for both back-ends.

use super::SimError;
use crate::block::Breakpoint;
use crate::compile::BlockMeta;

/// The times k·h of a grid with step h. When h is the reciprocal of a
/// whole number n (0.01, 1e-4, 0.5), k/n is used: division is correctly
/// rounded, so 47 steps of 0.01 give 0.47, the double nearest to 47/100,
/// where 47·0.01 gives 0.47000000000000003.
#[derive(Clone, Copy, Debug)]
pub(super) struct Grid {
    pub(super) step: f64,
    per_unit: Option<f64>,
}

/// The whole number n with step = 1/n (to a few ulps), when there is one:
/// then the grid's times are k/n (see [`Grid`]).
pub(crate) fn per_unit(step: f64) -> Option<f64> {
    let n = (1.0 / step).round();
    let exact = step > 0.0 && (1.0..9e15).contains(&n) && (n * step - 1.0).abs() <= 4.0 * f64::EPSILON;
    exact.then_some(n)
}

impl Grid {
    fn new(step: f64) -> Self {
        Grid { step, per_unit: per_unit(step) }
    }

    fn time(&self, k: u64) -> f64 {
        match self.per_unit {
            Some(n) => k as f64 / n,
            None => k as f64 * self.step,
        }
    }
}

/// One discrete rate's (or the fixed-step grid's) position on its time line.
#[derive(Clone, Copy, Debug)]
pub(crate) struct Clock {
    pub(super) grid: Grid,
    pub(super) offset: f64,
    /// Index of the next hit not yet taken, and its time (kept, not
    /// recomputed: the step loop asks for it several times per step).
    tick: u64,
    pub(crate) next: f64,
}

impl Clock {
    pub(super) fn new(step: f64, offset: f64) -> Self {
        Clock { grid: Grid::new(step), offset, tick: 0, next: offset }
    }

    pub(crate) fn set_tick(&mut self, tick: u64) {
        self.tick = tick;
        self.next = self.offset + self.grid.time(tick);
    }

    /// Moves to the next hit, when the step has reached this one (as
    /// [`Clock::pass`] at a time within `tol` of `next`, not of the one after).
    #[inline]
    pub(crate) fn pass_one(&mut self) {
        self.set_tick(self.tick + 1);
    }

    /// Moves past the hits at or before `t` (within `tol`); returns
    /// whether there was one.
    pub(crate) fn pass(&mut self, t: f64, tol: f64) -> bool {
        let due = self.next <= t + tol;
        while self.next <= t + tol {
            self.set_tick(self.tick + 1);
        }
        due
    }
}

/// Takes the clocks whose next hit is (within `tol`) at `t`, marking them
/// in `hit`; returns whether any was.
pub(crate) fn mark_hits(clocks: &mut [Clock], t: f64, tol: f64, hit: &mut [bool]) -> bool {
    let mut any = false;
    for (c, hit) in clocks.iter_mut().zip(hit) {
        *hit = c.next <= t + tol;
        if *hit {
            c.set_tick(c.tick + 1);
            any = true;
        }
    }
    any
}

/// The next major step's time: the earliest of the clocks' next hits, the
/// fixed-step grid's next point (`grid`, when there is one), the block
/// event `next_event` and `stop`. An event within `tol` of another
/// candidate wins, so sources switch exactly at their event time.
#[inline]
pub(crate) fn next_major_time(clocks: &[Clock], grid: Option<&Clock>, stop: f64, next_event: f64, tol: f64) -> f64 {
    let mut next = clocks.iter().fold(stop, |next, c| next.min(c.next));
    if let Some(grid) = grid {
        next = next.min(grid.next);
    }
    if next_event <= next + tol { next_event } else { next }
}

/// The discrete rates counted in fixed steps, for runs where that is exact:
/// the grid's step is 1/n s and every clock's period 1/n_c s (whole n,
/// n_c, as [`Grid`] keeps them) with n_c dividing n, and no offset. A
/// clock's hit times are then the grid's own points, bit for bit
/// (tick/n_c and (tick·n/n_c)/n are the same quotient, each correctly
/// rounded), so a clock is due at every (n/n_c)-th grid point and needs no
/// time of its own: no division, no comparison of times per clock and
/// step. Gives the hits [`mark_hits`] gives. (A period of 0.003 s on a
/// 1 ms grid is not counted: its times k·0.003 may differ from the grid's
/// 3k/1000 in the last bit, and the simulator takes the earlier.)
#[derive(Clone, Debug)]
pub(crate) struct OnGrid {
    clocks: Vec<Countdown>,
}

/// One clock counted in grid points.
#[derive(Clone, Copy, Debug)]
struct Countdown {
    /// Grid steps per period.
    every: u64,
    /// Grid points until the next hit.
    left: u64,
}

impl OnGrid {
    /// `None` when some clock is not on the grid (or there is no grid).
    pub(crate) fn new(grid_step: f64, grid: &Clock, clocks: &[Clock]) -> Option<Self> {
        let n = grid.grid.per_unit.filter(|_| grid_step > 0.0)?;
        let clocks = clocks
            .iter()
            .map(|c| match c.grid.per_unit {
                Some(n_c) if c.offset == 0.0 && n % n_c == 0.0 => {
                    let every = (n / n_c) as u64;
                    Some(Countdown { every, left: every })
                }
                _ => None,
            })
            .collect::<Option<Vec<_>>>()?;
        Some(OnGrid { clocks })
    }

    /// Back to t = 0, where every clock is due.
    pub(crate) fn reset(&mut self, hit: &mut [bool]) {
        self.clocks.iter_mut().for_each(|c| c.left = c.every);
        hit.fill(true);
    }

    /// Marks the clocks due at a major step: at a grid point when
    /// `on_grid` (the step reached the grid's next point), none otherwise
    /// (a block event or the stop time between grid points). Returns
    /// whether any was due.
    #[inline]
    pub(crate) fn mark_hits(&mut self, on_grid: bool, hit: &mut [bool]) -> bool {
        if !on_grid {
            hit.fill(false);
            return false;
        }
        // A clock's every and left side by side, one stream beside the
        // hits: a plain loop over the few clocks (over three streams the
        // compiler vectorised it, checking for overlaps each step).
        let mut any = false;
        for (c, hit) in self.clocks.iter_mut().zip(hit) {
            c.left -= 1;
            *hit = c.left == 0;
            if *hit {
                c.left = c.every;
            }
            any |= *hit;
        }
        any
    }
}

/// Folds one block's next event `e` into the earliest so far, `best`
/// (time and generation): the earlier wins, and of events at one time the
/// lowest generation (a source's own jump before a delay's arrival).
/// `generation` is asked only when it counts.
#[inline]
pub fn earlier(best: (f64, u32), e: f64, generation: impl FnOnce() -> u32) -> (f64, u32) {
    if e < best.0 {
        (e, generation())
    } else if e == best.0 && e < f64::INFINITY {
        (e, best.1.min(generation()))
    } else {
        best
    }
}

/// The breakpoint at a major step, if it is one: reached by a sample hit,
/// a block event (of generation `event_generation`), or a state the step
/// changed (`located`: a zero crossing that ended it, a clamp). A sample
/// hit is the weakest cause: any other sets the generation.
pub(crate) fn breakpoint(hit: bool, block_event: bool, located: bool, event_generation: u32) -> Option<Breakpoint> {
    (hit || block_event || located).then_some(Breakpoint {
        generation: if located || !block_event { 0 } else { event_generation },
        sample_hit_only: !(located || block_event),
    })
}

/// Major steps in a row at which time may stand still (events at one
/// instant passing one another on) before a run stops.
pub(crate) const MAX_STALLED_STEPS: u32 = 1000;

/// The stall rule both drivers follow: counts the major steps in a row
/// that left time at `t0`; past [`MAX_STALLED_STEPS`] the run stops naming
/// the block whose event (the earliest after `t0`, `event_of` a block)
/// holds time there — one asking for steps closer than floating point can
/// tell apart.
#[inline(always)]
pub(crate) fn count_stall(
    stalled: &mut u32,
    t0: f64,
    t: f64,
    meta: &[BlockMeta],
    event_of: impl Fn(usize) -> f64,
) -> Result<(), SimError> {
    *stalled = if t > t0 { 0 } else { *stalled + 1 };
    if *stalled <= MAX_STALLED_STEPS { Ok(()) } else { Err(stall(t0, meta, event_of)) }
}

/// The error of a run that stalled at `t0`.
#[cold]
fn stall(t0: f64, meta: &[BlockMeta], event_of: impl Fn(usize) -> f64) -> SimError {
    let (i, _) = (0..meta.len())
        .map(|i| (i, event_of(i)))
        .fold((0, f64::INFINITY), |best, (i, e)| if e < best.1 { (i, e) } else { best });
    SimError::Stalled { t: t0, block: meta.get(i).map_or_else(|| "?".into(), |m| m.name.clone()) }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::block::SampleTime;
    use crate::compile::Rate;

    fn meta(name: &str) -> BlockMeta {
        BlockMeta {
            name: name.into(),
            type_name: "pulse".into(),
            pos: crate::diag::Pos::new("g.yaml".into(), 1, 1),
            rate: Rate::Continuous,
            sample_time: SampleTime::Continuous,
            inputs: 0..0,
            outputs: 0..0,
            states: 0..0,
            input_names: Vec::new(),
            output_names: Vec::new(),
            exact_zoh: false,
            piecewise_constant: false,
        }
    }

    #[test]
    fn a_stall_stops_the_run_after_the_limit_naming_the_block_whose_event_holds_time() {
        let blocks = [meta("slow"), meta("stuck"), meta("idle")];
        let events = [2.0, 1.0, f64::INFINITY];
        let mut stalled = 0;
        for _ in 0..MAX_STALLED_STEPS {
            assert!(count_stall(&mut stalled, 1.0, 1.0, &blocks, |i| events[i]).is_ok());
        }
        // Time moving on starts the count again.
        assert!(count_stall(&mut stalled, 1.0, 1.5, &blocks, |i| events[i]).is_ok());
        assert_eq!(stalled, 0);
        for _ in 0..MAX_STALLED_STEPS {
            count_stall(&mut stalled, 1.0, 1.0, &blocks, |i| events[i]).unwrap();
        }
        let error = count_stall(&mut stalled, 1.0, 1.0, &blocks, |i| events[i]).unwrap_err();
        assert_eq!(error, SimError::Stalled { t: 1.0, block: "stuck".into() });
    }
}
