//! The time a long solve has left, estimated from what its steps have taken so far: reported
//! with every Levenberg–Marquardt step of [`Method::IntegrableLm`] and [`Method::NestedLm`]
//! (seconds to minutes at 512² and more), never used to decide anything.
//!
//! A level (a grid of the nested pyramid, or integrable-lm's one grid) has taken its steps in
//! the time measured; the steps it has left are extrapolated from how fast its largest change
//! has been falling toward its tolerance ([`steps_to`]). A finer level not begun yet is
//! expected to take as many steps as the current level needed (or is expected to need) to
//! reach that finer level's tolerance, each costing what a step of the last level cost times the growth of a
//! step's cost from one level to the next: measured between the last two levels once there
//! are two, the ratio of their unknowns before. The estimate thus changes as the solve goes,
//! and on the finest grid rests on that grid's own steps only.
//!
//! [`Method::IntegrableLm`]: super::Method::IntegrableLm
//! [`Method::NestedLm`]: super::Method::NestedLm

use super::Progress;

/// How many of the last steps' falls of the largest change the extrapolation averages.
const RATE_WINDOW: usize = 3;

/// The steps an iteration whose largest changes were `updates` (one per step, in order) still
/// needs to bring its change below `tol`, at most `cap` in all (steps done included): 0 once
/// the last change is below `tol`; else the steps its change's geometric fall over the last
/// few steps takes to reach `tol`; `None` where it has not been falling (nothing to extrapolate
/// yet). A change that is not a number gives the cap.
pub(crate) fn steps_to(updates: &[f64], tol: f64, cap: usize) -> Option<usize> {
    let done = updates.len();
    let left = cap.saturating_sub(done);
    let &last = updates.last()?;
    if last < tol {
        return Some(0);
    }
    if !last.is_finite() || tol.is_nan() || tol <= 0.0 {
        return Some(left);
    }
    let window = RATE_WINDOW.min(done - 1);
    let first = updates[done - 1 - window];
    let fall = if window > 0 && first.is_finite() && first > last && last > 0.0 {
        (first / last).ln() / window as f64
    } else {
        0.0
    };
    (fall > 1e-3).then(|| ((((last / tol).ln() / fall).ceil().max(1.0)) as usize).min(left))
}

/// The steps in all that an iteration like the one whose largest changes were `updates`
/// takes to bring its change below `tol` (at most `cap`): those it took, or those it took and
/// [`steps_to`] the rest; `None` where that is not known.
fn expected(updates: &[f64], tol: f64, cap: usize) -> Option<usize> {
    match updates.iter().position(|&u| u < tol) {
        Some(i) => Some((i + 1).min(cap)),
        None => steps_to(updates, tol, cap).map(|left| (updates.len() + left).min(cap)),
    }
}

/// One grid of a solve, as the estimate sees it.
#[derive(Debug, Clone, Copy)]
pub(crate) struct Level {
    /// Its unknown pixels.
    pub(crate) unknowns: usize,
    /// The tolerance its steps are taken to.
    pub(crate) tol: f64,
    /// The most steps it takes.
    pub(crate) cap: usize,
}

/// The estimate of a solve over `levels` (coarsest first), fed the time of each step.
#[derive(Debug, Clone)]
pub(crate) struct TimeLeft {
    levels: Vec<Level>,
    /// The level now stepping (an index into `levels`).
    current: usize,
    /// When the current level began (seconds on the caller's clock).
    began: f64,
    /// The largest change of each step of the current level.
    updates: Vec<f64>,
    /// The seconds per step of the levels done, in order.
    per_step: Vec<f64>,
    /// The largest changes of the last level done.
    last_updates: Vec<f64>,
}

impl TimeLeft {
    /// An estimate for `levels`, coarsest first, the first beginning at `now` seconds.
    pub(crate) fn new(levels: Vec<Level>, now: f64) -> TimeLeft {
        TimeLeft {
            levels,
            current: 0,
            began: now,
            updates: Vec::new(),
            per_step: Vec::new(),
            last_updates: Vec::new(),
        }
    }

    /// The next level begins at `now`.
    pub(crate) fn next_level(&mut self, now: f64) {
        if !self.updates.is_empty() {
            let steps = self.updates.len() as f64;
            self.per_step.push((now - self.began).max(0.0) / steps);
            self.last_updates = std::mem::take(&mut self.updates);
        }
        self.current = (self.current + 1).min(self.levels.len().saturating_sub(1));
        self.began = now;
    }

    /// A step of the current level ended at `now` with largest change `update`: the seconds
    /// the solve has left (finite, not negative), or `None` where the steps so far give no
    /// estimate (a first grid whose change has not yet fallen).
    pub(crate) fn step(&mut self, update: f64, now: f64) -> Option<f64> {
        self.updates.push(update);
        let level = self.levels[self.current];
        let done = self.updates.len();
        let per_step = (now - self.began).max(0.0) / done as f64;
        // The level before models this one while this one's own fall says nothing (a level just
        // begun, or one whose change has not been falling).
        let before = (!self.last_updates.is_empty()).then_some(&self.last_updates[..]);
        let borrowed = || {
            before
                .and_then(|b| expected(b, level.tol, level.cap))
                .map(|steps| steps.saturating_sub(done))
        };
        let own = if done < 2 && update >= level.tol {
            borrowed()
        } else {
            steps_to(&self.updates, level.tol, level.cap).or_else(borrowed)
        }?;
        let mut left = own as f64 * per_step;
        // Each step's cost grows from one level to the next by the growth measured between the
        // last two levels, or by the growth of the unknowns before two are measured.
        let measured_growth = match self.per_step.last() {
            Some(&before) if before > 0.0 => Some(per_step / before),
            _ => None,
        };
        // The steps of a finer level: those this level needed (or will need) to reach its
        // tolerance; those of the level before where this one says nothing yet.
        let (mut cost, mut unknowns) = (per_step, level.unknowns.max(1));
        for finer in &self.levels[self.current + 1..] {
            let growth = measured_growth.unwrap_or(finer.unknowns as f64 / unknowns as f64);
            cost *= growth.max(0.0);
            unknowns = finer.unknowns.max(1);
            let own = (done >= 2)
                .then(|| expected(&self.updates, finer.tol, finer.cap))
                .flatten();
            let steps = own.or_else(|| before.and_then(|b| expected(b, finer.tol, finer.cap)))?;
            left += steps as f64 * cost;
        }
        Some(if left.is_finite() { left.max(0.0) } else { 0.0 })
    }
}

/// Seconds since the clock was made, where the platform has a clock (not in the browser's
/// WebAssembly, where the estimate is then not made).
#[derive(Debug, Clone, Copy)]
pub(crate) struct Clock {
    #[cfg(not(all(target_arch = "wasm32", target_os = "unknown")))]
    started: std::time::Instant,
}

impl Clock {
    /// A clock started now.
    pub(crate) fn start() -> Clock {
        Clock {
            #[cfg(not(all(target_arch = "wasm32", target_os = "unknown")))]
            started: std::time::Instant::now(),
        }
    }

    /// Seconds since [`Clock::start`]; `None` without a clock.
    pub(crate) fn seconds(&self) -> Option<f64> {
        #[cfg(not(all(target_arch = "wasm32", target_os = "unknown")))]
        return Some(self.started.elapsed().as_secs_f64());
        #[cfg(all(target_arch = "wasm32", target_os = "unknown"))]
        None
    }
}

/// [`TimeLeft`] on the platform's clock: fills in the level and the estimate of each step's
/// [`Progress`].
pub(crate) struct Estimate {
    clock: Clock,
    time_left: TimeLeft,
    level: usize,
}

impl Estimate {
    /// An estimate for `levels`, coarsest first (the finest the image's own grid), starting now.
    pub(crate) fn new(levels: Vec<Level>) -> Estimate {
        let clock = Clock::start();
        let level = levels.len().saturating_sub(1);
        Estimate {
            time_left: TimeLeft::new(levels, clock.seconds().unwrap_or(0.0)),
            clock,
            level,
        }
    }

    /// The next finer level begins now.
    pub(crate) fn next_level(&mut self) {
        if let Some(now) = self.clock.seconds() {
            self.time_left.next_level(now);
        }
        self.level = self.level.saturating_sub(1);
    }

    /// The report of a step of the current level: `step` with its level and estimate.
    pub(crate) fn report(&mut self, step: &Progress) -> Progress {
        let seconds_left = self
            .clock
            .seconds()
            .and_then(|now| self.time_left.step(step.last_update, now));
        Progress {
            level: self.level,
            seconds_left,
            ..*step
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn steps_follow_the_geometric_fall_of_the_change() {
        // Falling tenfold per step: 1e-2 → 1e-6 takes four more.
        assert_eq!(steps_to(&[1.0, 0.1, 0.01], 1e-6, 100), Some(4));
        // Below the tolerance: none.
        assert_eq!(steps_to(&[1.0, 0.1, 1e-7], 1e-6, 100), Some(0));
        // The cap bounds the steps done and left together.
        assert_eq!(steps_to(&[1.0, 0.1, 0.01], 1e-6, 5), Some(2));
        // Not falling, or nothing done yet: nothing to extrapolate.
        assert_eq!(steps_to(&[0.5, 0.5, 0.6], 1e-6, 100), None);
        assert_eq!(steps_to(&[0.5], 1e-6, 100), None);
        assert_eq!(steps_to(&[], 1e-6, 100), None);
        // A change that is not a number: the cap.
        assert_eq!(steps_to(&[1.0, f64::NAN], 1e-6, 10), Some(8));
    }

    /// Two levels, the coarse one with a quarter of the unknowns, each step of it 1 s: the
    /// fine level is expected to take the steps the coarse one needed to reach the fine
    /// tolerance, each 4 s; once the fine level runs, its own steps set the estimate.
    #[test]
    fn the_estimate_follows_the_steps_measured() {
        let near = |a: f64, b: f64| (a - b).abs() < 1e-9;
        let levels = vec![
            Level {
                unknowns: 100,
                tol: 5e-5,
                cap: 200,
            },
            Level {
                unknowns: 400,
                tol: 5e-3,
                cap: 200,
            },
        ];
        let mut t = TimeLeft::new(levels, 0.0);
        // One step, nothing fallen yet and no level before: no estimate.
        assert_eq!(t.step(1.0, 1.0), None);
        // Falling tenfold a step at 1 s a step: four more coarse steps (to below 5e-5), and the
        // fine level expects the four steps the coarse one takes to below 5e-3, at 4 s each.
        let second = t.step(0.1, 2.0).unwrap();
        assert!(near(second, 4.0 * 1.0 + 4.0 * 4.0), "{second}");
        t.step(0.01, 3.0).unwrap();
        let coarse_done = t.step(1e-5, 4.0).unwrap();
        // The coarse level is done: the fine level's four steps at 4 s.
        assert!(near(coarse_done, 4.0 * 4.0), "{coarse_done}");
        t.next_level(4.0);
        // The fine level's first step took 5 s: the coarse level's count models it (three
        // more); then its own fall (tenfold: two more to below 5e-3), then nothing.
        let fine = t.step(1.0, 9.0).unwrap();
        assert!(near(fine, 3.0 * 5.0), "{fine}");
        let fine = t.step(0.1, 14.0).unwrap();
        assert!(near(fine, 2.0 * 5.0), "{fine}");
        assert_eq!(t.step(0.001, 19.0), Some(0.0));
    }
}
