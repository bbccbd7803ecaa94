//! Progress display: a kdam bar on a terminal, plain log lines otherwise.

use std::io::IsTerminal;

/// True when standard error is a terminal (then a progress bar is drawn).
pub fn stderr_is_terminal() -> bool {
    std::io::stderr().is_terminal()
}
