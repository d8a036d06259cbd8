//! What a long run shows while it runs: on a terminal, a bar with the
//! simulated time, the step rate and an ETA from the rate of the last
//! [`WINDOW`] (not the average since the start, which start-up costs and
//! changing contact counts make wrong); elsewhere (CI, pipes, log files)
//! one plain line every [`PLAIN_EVERY`] (or every `EFGDEM_PROGRESS_EVERY`
//! seconds). A spinner while the model is built.

use indicatif::{ProgressBar, ProgressStyle};
use std::collections::VecDeque;
use std::io::IsTerminal;
use std::time::{Duration, Instant};

/// The ETA and rate are measured over this much of the recent past.
pub const WINDOW: Duration = Duration::from_secs(20);
/// Interval of the plain progress lines when stderr is not a terminal.
pub const PLAIN_EVERY: Duration = Duration::from_secs(10);
/// The interval of the plain lines: [`PLAIN_EVERY`], or
/// `EFGDEM_PROGRESS_EVERY` seconds when that is set to a number ≥ 0.
fn plain_every() -> Duration {
    std::env::var("EFGDEM_PROGRESS_EVERY")
        .ok()
        .and_then(|s| s.trim().parse::<f64>().ok())
        .filter(|s| s.is_finite() && *s >= 0.0)
        .map_or(PLAIN_EVERY, Duration::from_secs_f64)
}

/// The display is refreshed at most this often.
const TICK: Duration = Duration::from_millis(200);

enum Display {
    Hidden,
    Bar(ProgressBar),
    /// Lines on stderr; when the last one was written, and how often.
    Plain(Instant, Duration),
}

/// Progress of a time-stepped run of `total` steps.
pub struct Progress {
    display: Display,
    /// What is being stepped, in the plain lines (a run: none).
    label: Option<String>,
    total: usize,
    /// Recent (instant, step) samples, at least [`TICK`] apart.
    samples: VecDeque<(Instant, usize)>,
    last_tick: Instant,
}

/// Show what is being done while nothing can be counted (building the
/// model: generating and depositing discs, assembling bodies); cleared
/// when the returned bar is dropped or finished.
pub fn spinner(msg: &str, quiet: bool) -> ProgressBar {
    if quiet {
        return ProgressBar::hidden();
    }
    if !std::io::stderr().is_terminal() {
        eprintln!("{msg} …");
        return ProgressBar::hidden();
    }
    let s = ProgressBar::new_spinner();
    s.set_style(
        ProgressStyle::with_template("{spinner} {msg} ({elapsed})").expect("static template"),
    );
    s.set_message(msg.to_string());
    s.enable_steady_tick(Duration::from_millis(120));
    s
}

impl Progress {
    /// Progress from step `start` (0, or the step a restart resumes at)
    /// to `total`.
    pub fn new(start: usize, total: usize, quiet: bool) -> Self {
        Self::with_label(None, start, total, quiet)
    }

    /// Progress of a preparation (`what`: e.g. `a gravity deposit`) of
    /// `total` steps; [`update`](Self::update) it with `t` = NaN (no time).
    pub fn labelled(what: &str, total: usize, quiet: bool) -> Self {
        Self::with_label(Some(what.to_string()), 0, total, quiet)
    }

    fn with_label(label: Option<String>, start: usize, total: usize, quiet: bool) -> Self {
        let now = Instant::now();
        let display = if quiet {
            Display::Hidden
        } else if std::io::stderr().is_terminal() {
            let pb = ProgressBar::new(total as u64);
            let prefix = label.as_ref().map_or(String::new(), |l| format!("{l}: "));
            pb.set_style(
                ProgressStyle::with_template(&format!(
                    "{prefix}{{elapsed_precise}} [{{bar:40}}] {{pos}}/{{len}} steps {{msg}}"
                ))
                .expect("static template")
                .progress_chars("=> "),
            );
            pb.set_position(start as u64);
            Display::Bar(pb)
        } else {
            if let Some(l) = &label {
                eprintln!("{l}: {total} steps …");
            }
            Display::Plain(now, plain_every())
        };
        Progress {
            display,
            label,
            total,
            samples: VecDeque::from([(now, start)]),
            last_tick: now,
        }
    }

    /// Steps per second over the recent window (None until measurable).
    fn rate(&self) -> Option<f64> {
        let (&(t0, s0), &(t1, s1)) = (self.samples.front()?, self.samples.back()?);
        let dt = (t1 - t0).as_secs_f64();
        (dt > 0.0 && s1 > s0).then(|| (s1 - s0) as f64 / dt)
    }

    /// Keep the samples of the last [`WINDOW`] (and one before it).
    fn sample(&mut self, now: Instant, step: usize) {
        self.samples.push_back((now, step));
        while self.samples.len() > 2 && now - self.samples[1].0 >= WINDOW {
            self.samples.pop_front();
        }
    }

    /// Print a line on stderr without breaking the progress bar (shown
    /// even with `-q`: warnings are not progress).
    pub fn warn(&self, line: &str) {
        match &self.display {
            Display::Bar(pb) => pb.suspend(|| eprintln!("{line}")),
            _ => eprintln!("{line}"),
        }
    }

    /// `step` steps are done and the model is at time `t` (cheap to call
    /// every step: it only looks at the clock).
    pub fn update(&mut self, step: usize, t: f64) {
        if matches!(self.display, Display::Hidden) {
            return;
        }
        let now = Instant::now();
        if now - self.last_tick < TICK && step < self.total {
            return;
        }
        self.last_tick = now;
        self.sample(now, step);
        let rate = self.rate();
        let eta = rate.map(|r| (self.total - step.min(self.total)) as f64 / r);
        let time = match t.is_nan() {
            true => String::new(),
            false => format!("t = {t:.4e} s, "),
        };
        let msg = format!(
            "{time}{}, eta {}",
            rate.map_or("— steps/s".into(), |r| format!(
                "{} steps/s",
                human_rate(r)
            )),
            eta.map_or("—".into(), human_duration),
        );
        match &mut self.display {
            Display::Hidden => {}
            Display::Bar(pb) => {
                pb.set_position(step as u64);
                pb.set_message(msg);
            }
            Display::Plain(last, every) => {
                if now - *last >= *every {
                    *last = now;
                    eprintln!(
                        "{}step {step}/{} ({:.1} %), {msg}",
                        self.label
                            .as_ref()
                            .map_or(String::new(), |l| format!("{l}: ")),
                        self.total,
                        100.0 * step as f64 / self.total.max(1) as f64
                    );
                }
            }
        }
    }

    /// Remove the bar.
    pub fn finish(&self) {
        if let Display::Bar(pb) = &self.display {
            pb.finish_and_clear();
        }
    }
}

fn human_rate(r: f64) -> String {
    if r >= 100.0 {
        format!("{r:.0}")
    } else {
        format!("{r:.3}")
    }
}

/// `1h 02m`, `3m 05s`, `12s`.
pub fn human_duration(s: f64) -> String {
    let s = s.max(0.0).round() as u64;
    match s {
        0..60 => format!("{s}s"),
        60..3600 => format!("{}m {:02}s", s / 60, s % 60),
        _ => format!("{}h {:02}m", s / 3600, (s % 3600) / 60),
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_rate_is_that_of_the_recent_window() {
        let mut p = Progress::new(0, 1000, true);
        let t0 = p.samples[0].0;
        // 100 steps in the first 60 s (slow start-up), then 10 steps/s
        let at = |s: u64| t0 + Duration::from_secs(s);
        p.sample(at(60), 100);
        for k in 1..=30u64 {
            p.sample(at(60 + k), 100 + 10 * k as usize);
        }
        let r = p.rate().unwrap();
        assert!((r - 10.0).abs() < 1e-9, "rate {r}");
    }

    #[test]
    fn durations_read_like_a_clock() {
        assert_eq!(human_duration(12.4), "12s");
        assert_eq!(human_duration(185.0), "3m 05s");
        assert_eq!(human_duration(3720.0), "1h 02m");
    }
}
