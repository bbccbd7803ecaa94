//! Progress display: a kdam bar on a terminal, plain log lines otherwise.
//!
//! kdam draws its bar even when stderr is not a terminal (../shared/spec/dependencies.md),
//! so the bar is built with `disable = !stderr.is_terminal()` and, when disabled, one plain
//! line per finished step is printed instead (readable in CI logs and files).

use kdam::BarExt;
use std::io::IsTerminal;
use std::sync::Mutex;

/// True when standard error is a terminal (then a progress bar is drawn).
pub fn stderr_is_terminal() -> bool {
    std::io::stderr().is_terminal()
}

/// A counter of finished steps shown as a bar (terminal) or as log lines (anything else).
/// Safe to call from several threads.
pub struct Progress {
    bar: Mutex<kdam::Bar>,
    terminal: bool,
    total: usize,
    done: Mutex<usize>,
}

impl Progress {
    /// A progress display for `total` steps described by `desc` (e.g. "recordings").
    pub fn new(desc: &str, total: usize) -> Progress {
        let terminal = stderr_is_terminal();
        let bar = kdam::Bar::builder()
            .total(total)
            .desc(desc)
            .unit(" rec")
            .disable(!terminal)
            .leave(true)
            .build()
            .unwrap_or_else(|_| kdam::Bar::new(total));
        let mut bar = bar;
        bar.disable = !terminal;
        Progress { bar: Mutex::new(bar), terminal, total, done: Mutex::new(0) }
    }

    /// One step finished; `line` describes it (shown as the bar's postfix, or logged).
    pub fn step(&self, line: &str) {
        let n = {
            let mut d = self.done.lock().unwrap_or_else(|e| e.into_inner());
            *d += 1;
            *d
        };
        if self.terminal {
            let mut bar = self.bar.lock().unwrap_or_else(|e| e.into_inner());
            bar.set_postfix(line.to_string());
            let _ = bar.update(1);
        } else {
            eprintln!("[{n}/{}] {line}", self.total);
        }
    }

    /// Print a message without breaking the bar.
    pub fn message(&self, line: &str) {
        if self.terminal {
            let mut bar = self.bar.lock().unwrap_or_else(|e| e.into_inner());
            let _ = bar.write(line.to_string());
        } else {
            eprintln!("{line}");
        }
    }

    /// End the bar's line (no-op for log lines).
    pub fn finish(&self) {
        if self.terminal {
            let mut bar = self.bar.lock().unwrap_or_else(|e| e.into_inner());
            let _ = bar.refresh();
            eprintln!();
        }
    }
}
