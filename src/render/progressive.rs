//! Stopping rules and checkpoints for a progressive render: between passes
//! (`render::PassControl`) stop at a time limit, at a target error, or when
//! interrupted, and hand the film to a checkpoint writer every so often, so
//! a long render is never lost.

use crate::film::Film;
use crate::film::passes::PassControl;
use std::sync::atomic::{AtomicBool, Ordering};
use std::time::{Duration, Instant};

/// When to stop before the asked-for spp, and how often to checkpoint.
#[derive(Clone, Debug, Default)]
pub struct StopRules {
    /// Stop at the last pass boundary that keeps the render within this time.
    pub time_limit: Option<Duration>,
    /// Stop once the estimated relative RMS error of the image (the square
    /// root of `Image::estimated_rel_mse`, from the per-pixel variance) is at
    /// most this. With Sobol samples the per-pixel variance is that of
    /// independent samples, an overestimate wherever Sobol does better, so
    /// the render stops late rather than early.
    pub target_error: Option<f64>,
    /// Hand the film to the checkpoint writer at most this often.
    pub checkpoint_every: Option<Duration>,
}

/// Why a progressive render ended.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum StopReason {
    /// Every sample asked for was rendered.
    Finished,
    TimeLimit,
    /// The estimated relative error reached the target; the value reached.
    TargetError(f64),
    /// The interrupt flag was raised (Ctrl-C).
    Interrupted,
}

/// The `PassControl` that applies `StopRules`.
pub struct Progressive<'a> {
    rules: StopRules,
    start: Instant,
    last_pass: Instant,
    last_checkpoint: Instant,
    /// Check the error again at this spp (or after `ERROR_CHECK_INTERVAL`).
    next_error_check: u32,
    last_error_check: Instant,
    interrupt: &'a AtomicBool,
    checkpoint: &'a mut dyn FnMut(&Film, u32) -> anyhow::Result<()>,
    /// Why the render stopped early (`None` while it runs or when it finished).
    pub stopped: Option<StopReason>,
    /// Estimated relative error at the last check.
    pub last_error: Option<f64>,
}

/// Longest wait between two error checks (each may read the film back).
const ERROR_CHECK_INTERVAL: Duration = Duration::from_secs(2);

impl<'a> Progressive<'a> {
    /// `interrupt` is polled between passes; `checkpoint` gets the film and
    /// its spp.
    pub fn new(
        rules: StopRules,
        interrupt: &'a AtomicBool,
        checkpoint: &'a mut dyn FnMut(&Film, u32) -> anyhow::Result<()>,
    ) -> Self {
        let now = Instant::now();
        Progressive {
            rules,
            start: now,
            last_pass: now,
            last_checkpoint: now,
            next_error_check: 2,
            last_error_check: now,
            interrupt,
            checkpoint,
            stopped: None,
            last_error: None,
        }
    }

    /// Why the render ended, once it has.
    pub fn reason(&self) -> StopReason {
        self.stopped.unwrap_or(StopReason::Finished)
    }

    fn stop(&mut self, reason: StopReason) -> anyhow::Result<bool> {
        self.stopped = Some(reason);
        Ok(false)
    }
}

impl PassControl for Progressive<'_> {
    fn after_pass(
        &mut self,
        spp: u32,
        film: &mut dyn FnMut() -> anyhow::Result<Film>,
    ) -> anyhow::Result<bool> {
        let now = Instant::now();
        let pass_time = now - self.last_pass;
        self.last_pass = now;
        if self.interrupt.load(Ordering::Relaxed) {
            return self.stop(StopReason::Interrupted);
        }
        // Stop now if one more pass (as long as the last) would overrun.
        if let Some(limit) = self.rules.time_limit
            && now - self.start + pass_time > limit
        {
            return self.stop(StopReason::TimeLimit);
        }
        let mut current = None;
        if let Some(target) = self.rules.target_error
            && (spp >= self.next_error_check || now - self.last_error_check >= ERROR_CHECK_INTERVAL)
        {
            let f = film()?;
            let error = f.to_image().estimated_rel_error();
            self.last_error = Some(error);
            self.last_error_check = now;
            if error <= target {
                return self.stop(StopReason::TargetError(error));
            }
            // Error falls as 1/sqrt(spp): check again where it should reach
            // the target, but at least every doubling.
            let predicted = spp as f64 * (error / target).powi(2);
            self.next_error_check = (predicted.ceil() as u32).clamp(spp + 1, spp.saturating_mul(2));
            current = Some(f);
        }
        if let Some(every) = self.rules.checkpoint_every
            && now - self.last_checkpoint >= every
        {
            let f = match current {
                Some(f) => f,
                None => film()?,
            };
            (self.checkpoint)(&f, spp)?;
            self.last_checkpoint = Instant::now();
        }
        Ok(true)
    }

    /// A time limit stops before a pass as long as the last would overrun
    /// it, so passes keep their length there.
    fn passes_may_grow(&self) -> bool {
        self.rules.time_limit.is_none()
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn noisy_film(spp: u32, sigma: f32) -> Film {
        let mut film = Film::new(4, 4);
        for p in 0..16 {
            for s in 0..spp {
                let v = 1.0 + if s % 2 == 0 { sigma } else { -sigma };
                film.add_sample(p, [v, v, v]);
            }
        }
        film
    }

    #[test]
    fn passes_keep_their_length_only_under_a_time_limit() {
        let flag = AtomicBool::new(false);
        let mut write = |_: &Film, _: u32| -> anyhow::Result<()> { Ok(()) };
        let limited = StopRules {
            time_limit: Some(Duration::from_secs(5)),
            ..Default::default()
        };
        assert!(!Progressive::new(limited, &flag, &mut write).passes_may_grow());
        let others = StopRules {
            target_error: Some(0.01),
            checkpoint_every: Some(Duration::from_secs(5)),
            ..Default::default()
        };
        assert!(Progressive::new(others, &flag, &mut write).passes_may_grow());
    }

    #[test]
    fn interrupt_stops_at_the_next_pass() {
        let flag = AtomicBool::new(false);
        let mut writes = 0;
        let mut write = |_: &Film, _: u32| -> anyhow::Result<()> {
            writes += 1;
            Ok(())
        };
        let mut p = Progressive::new(StopRules::default(), &flag, &mut write);
        let mut film = || Ok(noisy_film(2, 0.1));
        assert!(p.after_pass(1, &mut film).unwrap());
        flag.store(true, Ordering::Relaxed);
        assert!(!p.after_pass(2, &mut film).unwrap());
        assert_eq!(p.reason(), StopReason::Interrupted);
        assert_eq!(writes, 0);
    }

    #[test]
    fn target_error_stops_once_reached() {
        let flag = AtomicBool::new(false);
        let mut write = |_: &Film, _: u32| -> anyhow::Result<()> { Ok(()) };
        let rules = StopRules {
            target_error: Some(0.05),
            ..Default::default()
        };
        let mut p = Progressive::new(rules, &flag, &mut write);
        // Samples +-0.5 around 1: the error of the mean is 0.5 / sqrt(spp)
        // over a mean of 1 (relMSE denominator 1.01): below 5% from 101 spp.
        let mut stopped_at = None;
        for spp in 1..1000 {
            let mut film = || Ok(noisy_film(spp, 0.5));
            if !p.after_pass(spp, &mut film).unwrap() {
                stopped_at = Some(spp);
                break;
            }
        }
        let spp = stopped_at.expect("the target is reached");
        let StopReason::TargetError(e) = p.reason() else {
            panic!("stopped for {:?}", p.reason());
        };
        assert!(e <= 0.05, "stopped at error {e}");
        // It checks at least every doubling, so it stops before 2x the need.
        assert!((100..=202).contains(&spp), "stopped at {spp} spp");
    }

    #[test]
    fn checkpoints_are_written_when_due() {
        let flag = AtomicBool::new(false);
        let mut written = Vec::new();
        let mut write = |_: &Film, spp: u32| -> anyhow::Result<()> {
            written.push(spp);
            Ok(())
        };
        let rules = StopRules {
            checkpoint_every: Some(Duration::ZERO),
            ..Default::default()
        };
        let mut p = Progressive::new(rules, &flag, &mut write);
        let mut film = || Ok(noisy_film(1, 0.0));
        for spp in 1..=3 {
            assert!(p.after_pass(spp, &mut film).unwrap());
        }
        assert_eq!(written, [1, 2, 3]);
    }
}
