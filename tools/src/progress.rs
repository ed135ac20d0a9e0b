//! Progress on stderr for a person watching a long job. It is written only when stderr is a
//! terminal: redirected to a file or a pipe (a script, CI, a test), stderr carries errors alone
//! and stdout the results.

use std::io::IsTerminal;

/// A progress counter shown as one line rewritten in place (`label: done/total detail`).
#[derive(Debug)]
pub struct Progress {
    label: String,
    shown: bool,
}

impl Progress {
    /// A counter; shown only if stderr is a terminal.
    pub fn new(label: impl Into<String>) -> Self {
        Self::with_terminal(label, std::io::stderr().is_terminal())
    }

    /// A counter shown or not as `shown` says (for callers that already know).
    pub fn with_terminal(label: impl Into<String>, shown: bool) -> Self {
        Self {
            label: label.into(),
            shown,
        }
    }

    /// Whether the counter writes anything.
    pub fn is_shown(&self) -> bool {
        self.shown
    }

    /// Shows `done` of `total` steps, with `detail` after the count; ends the line when
    /// `done` reaches `total`.
    pub fn update(&self, done: usize, total: usize, detail: &str) {
        if !self.shown {
            return;
        }
        eprint!("\r{}: {done}/{total}{detail}", self.label);
        if done >= total {
            eprintln!();
        }
    }

    /// A one-off status line (for example "reading LOG …"), shown under the same condition.
    pub fn note(&self, line: &str) {
        if self.shown {
            eprintln!("{line}");
        }
    }
}

/// A status line on stderr, only when stderr is a terminal.
pub fn note(line: &str) {
    Progress::new("").note(line);
}
