//! A movie's progress on stderr: one bar redrawn in place (`\r`) on a terminal, a line at each quarter otherwise
//! (a log or a test's captured stderr gets a few readable lines, not hundreds of redraws).

use std::io::{IsTerminal, Write};
use std::time::Instant;

const BAR_WIDTH: usize = 30;

pub struct Progress<W: Write> {
    out: W,
    terminal: bool,
    label: String,
    total: u32,
    start: Instant,
    /// The last quarter a plain line was written for.
    quarter: u32,
}

impl Progress<std::io::Stderr> {
    /// Progress of `total` frames on stderr, redrawn in place when stderr is a terminal.
    pub fn stderr(label: &str, total: u32) -> Self {
        let err = std::io::stderr();
        let terminal = err.is_terminal();
        Progress::new(err, terminal, label, total)
    }
}

impl<W: Write> Progress<W> {
    pub fn new(out: W, terminal: bool, label: &str, total: u32) -> Self {
        Progress {
            out,
            terminal,
            label: label.to_string(),
            total: total.max(1),
            start: Instant::now(),
            quarter: 0,
        }
    }

    /// `done` frames of the total are written. Progress is only shown; a failed write to stderr is ignored.
    pub fn update(&mut self, done: u32) {
        let done = done.min(self.total);
        let seconds = self.start.elapsed().as_secs_f64();
        let total = self.total;
        if self.terminal {
            let filled = done as usize * BAR_WIDTH / total as usize;
            let bar = format!("{}{}", "=".repeat(filled), " ".repeat(BAR_WIDTH - filled));
            let end = if done == total { "\n" } else { "" };
            let _ = write!(
                self.out,
                "\r{} [{bar}] {done}/{total} frames {seconds:.1} s{end}",
                self.label
            );
        } else {
            let quarter = done * 4 / total;
            if quarter > self.quarter {
                self.quarter = quarter;
                let _ = writeln!(
                    self.out,
                    "{}: {done}/{total} frames ({}%), {seconds:.1} s",
                    self.label,
                    u64::from(done) * 100 / u64::from(total)
                );
            }
        }
        let _ = self.out.flush();
    }

    pub fn into_inner(self) -> W {
        self.out
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_terminal_gets_one_line_redrawn_and_a_log_a_few_lines() {
        let mut p = Progress::new(Vec::new(), true, "turntable", 10);
        (1..=10).for_each(|k| p.update(k));
        let text = String::from_utf8(p.into_inner()).unwrap();
        assert_eq!(text.matches('\r').count(), 10);
        assert_eq!(text.matches('\n').count(), 1, "one final newline");
        assert!(
            text.contains(&format!("turntable [{}] 10/10 frames", "=".repeat(30))),
            "{text}"
        );

        let mut p = Progress::new(Vec::new(), false, "turntable", 100);
        (1..=100).for_each(|k| p.update(k));
        let text = String::from_utf8(p.into_inner()).unwrap();
        let lines: Vec<&str> = text.lines().collect();
        assert_eq!(lines.len(), 4, "{text}");
        assert!(lines[0].starts_with("turntable: 25/100 frames (25%)"), "{text}");
        assert!(lines[3].starts_with("turntable: 100/100 frames (100%)"), "{text}");
        assert!(!text.contains('\r'));

        let mut p = Progress::new(Vec::new(), false, "keyframes", 1);
        p.update(1);
        assert_eq!(String::from_utf8(p.into_inner()).unwrap().lines().count(), 1);
    }
}
