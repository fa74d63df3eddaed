//! Progress on stderr. On a terminal it is indicatif's bar. Anywhere else (a CI log, a pipe, a
//! file) indicatif draws nothing, and a half-hour study would be silent; there the bar becomes a
//! plain line at most every [`LOG_EVERY`], and lines printed above the bar are always written.

use std::io::{IsTerminal as _, Write as _};
use std::sync::Mutex;
use std::time::{Duration, Instant};

use indicatif::{ProgressBar, ProgressDrawTarget, ProgressStyle, TermLike};

/// How often a log gets the bar's line.
pub const LOG_EVERY: Duration = Duration::from_secs(30);

/// A bar of `len` steps.
pub fn bar(len: u64) -> ProgressBar {
    ProgressBar::with_draw_target(Some(len), target())
}

/// A spinner: a bar of no known length.
pub fn spinner() -> ProgressBar {
    ProgressBar::with_draw_target(None, target()).with_style(ProgressStyle::default_spinner())
}

fn target() -> ProgressDrawTarget {
    if std::io::stderr().is_terminal() {
        ProgressDrawTarget::stderr()
    } else {
        ProgressDrawTarget::term_like_with_hz(Box::new(LogLines::default()), 1)
    }
}

/// A terminal of one line per draw: indicatif writes each line of a draw and then spaces to the
/// width, so a run of spaces ends a line, and the draw's last line is the bar.
#[derive(Debug, Default)]
struct LogLines {
    state: Mutex<Lines>,
}

#[derive(Debug, Default)]
struct Lines {
    line: String,
    lines: Vec<String>,
    /// When the bar's line was last written.
    last: Option<Instant>,
}

impl Lines {
    fn write(&mut self, s: &str) {
        if s.chars().all(|c| c == ' ') {
            let line = std::mem::take(&mut self.line);
            self.lines.push(line.trim().to_string());
        } else {
            self.line.extend(s.chars().filter(|&c| c != '\r'));
        }
    }

    /// The lines of one draw to write at `now`: those above the bar always, the bar's when
    /// [`LOG_EVERY`] has passed since it was last written (or it never was).
    fn take(&mut self, now: Instant) -> Vec<String> {
        if !self.line.is_empty() {
            self.write("");
        }
        let mut lines = std::mem::take(&mut self.lines);
        let bar = lines.pop().filter(|b| !b.is_empty());
        lines.retain(|l| !l.is_empty());
        if let Some(bar) = bar
            && self.last.is_none_or(|t| now.duration_since(t) >= LOG_EVERY)
        {
            self.last = Some(now);
            lines.push(bar);
        }
        lines
    }
}

impl TermLike for LogLines {
    fn width(&self) -> u16 {
        160
    }

    fn height(&self) -> u16 {
        u16::MAX
    }

    fn move_cursor_up(&self, _: usize) -> std::io::Result<()> {
        Ok(())
    }

    fn move_cursor_down(&self, _: usize) -> std::io::Result<()> {
        Ok(())
    }

    fn move_cursor_right(&self, _: usize) -> std::io::Result<()> {
        Ok(())
    }

    fn move_cursor_left(&self, _: usize) -> std::io::Result<()> {
        Ok(())
    }

    fn write_line(&self, s: &str) -> std::io::Result<()> {
        let mut state = self.state.lock().unwrap_or_else(std::sync::PoisonError::into_inner);
        state.write(s);
        state.write("");
        Ok(())
    }

    fn write_str(&self, s: &str) -> std::io::Result<()> {
        self.state.lock().unwrap_or_else(std::sync::PoisonError::into_inner).write(s);
        Ok(())
    }

    fn clear_line(&self) -> std::io::Result<()> {
        Ok(())
    }

    fn flush(&self) -> std::io::Result<()> {
        let lines = self.state.lock().unwrap_or_else(std::sync::PoisonError::into_inner).take(Instant::now());
        let mut err = std::io::stderr().lock();
        lines.iter().try_for_each(|l| writeln!(err, "{l}"))
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn draw(lines: &mut Lines, text: &[&str]) {
        lines.write("\r");
        for t in text {
            lines.write(t);
            lines.write(&" ".repeat(160 - t.len()));
        }
    }

    #[test]
    fn a_log_gets_the_bar_at_first_and_then_once_per_interval_and_every_printed_line() {
        let mut lines = Lines::default();
        let t0 = Instant::now();
        draw(&mut lines, &["walks 1/10"]);
        assert_eq!(lines.take(t0), ["walks 1/10"]);
        draw(&mut lines, &["walks 2/10"]);
        assert!(lines.take(t0 + Duration::from_secs(1)).is_empty(), "too soon for the bar");
        draw(&mut lines, &["warning: slow", "walks 3/10"]);
        assert_eq!(lines.take(t0 + Duration::from_secs(2)), ["warning: slow"]);
        draw(&mut lines, &["walks 9/10"]);
        assert_eq!(lines.take(t0 + LOG_EVERY), ["walks 9/10"]);
        draw(&mut lines, &[]);
        assert!(lines.take(t0 + 3 * LOG_EVERY).is_empty(), "a cleared bar writes nothing");
    }
}
