//! A requested stop: SIGINT (Ctrl-C) or SIGTERM (`kill`, `systemctl stop`) ends the bridge's
//! loop cleanly, and a second one while it is stopping ends the process at once.
//!
//! [`Stop::on_signals`] registers the handlers (signal-hook: they only store to atomics, which
//! is all a signal handler may safely do). The bridge's loop polls [`Stop::requested`] on every
//! turn (at least every 10 ms), stops reading the link, sends what its outboxes hold (one
//! message per topic at most), and returns its report with `ended: signal (SIGINT)` and
//! [`crate::EXIT_STOPPED`]. A second SIGINT or SIGTERM after the first exits the process
//! immediately (`_exit`, no report) with [`EXIT_FORCED_SIGINT`] or [`EXIT_FORCED_SIGTERM`],
//! for a shutdown that hangs.

use std::sync::atomic::{AtomicBool, AtomicUsize, Ordering};
use std::sync::Arc;

use signal_hook::consts::{SIGINT, SIGTERM};

/// Exit code when a second signal, SIGINT, forces the exit during a stop: 128 + 2, the code a
/// shell shows for a process killed by SIGINT.
pub const EXIT_FORCED_SIGINT: u8 = 130;
/// Exit code when a second signal, SIGTERM, forces the exit during a stop: 128 + 15.
pub const EXIT_FORCED_SIGTERM: u8 = 143;

/// A signal that asks the bridge to stop.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum StopSignal {
    /// SIGINT (Ctrl-C in a terminal).
    Interrupt,
    /// SIGTERM (`kill`, systemd's stop).
    Terminate,
}

impl StopSignal {
    /// The signal's name: `SIGINT` or `SIGTERM`.
    pub fn name(self) -> &'static str {
        match self {
            Self::Interrupt => "SIGINT",
            Self::Terminate => "SIGTERM",
        }
    }

    fn number(self) -> i32 {
        match self {
            Self::Interrupt => SIGINT,
            Self::Terminate => SIGTERM,
        }
    }

    fn from_number(n: usize) -> Option<Self> {
        [Self::Interrupt, Self::Terminate]
            .into_iter()
            .find(|s| usize::try_from(s.number()).is_ok_and(|k| k == n))
    }
}

/// Whether a stop was requested, and by which signal. Clones share the request.
#[derive(Clone, Debug, Default)]
pub struct Stop {
    /// Set by the first signal; arms the immediate exit on the next.
    any: Arc<AtomicBool>,
    /// The signal number of the first request (0: none).
    first: Arc<AtomicUsize>,
}

/// Registering a signal handler failed (the OS refused it).
#[derive(Debug)]
pub struct SignalSetupError(pub std::io::Error);

impl std::fmt::Display for SignalSetupError {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        write!(f, "cannot handle SIGINT and SIGTERM: {}", self.0)
    }
}

impl std::error::Error for SignalSetupError {}

impl Stop {
    /// A stop that no signal sets: only [`Stop::request`] does (a bridge run inside another
    /// program or a test).
    pub fn new() -> Self {
        Self::default()
    }

    /// A stop set by SIGINT and SIGTERM for the rest of the process's life. The first signal
    /// sets it; a second one (either) exits the process at once with
    /// [`EXIT_FORCED_SIGINT`] or [`EXIT_FORCED_SIGTERM`]. Call it once per process: the
    /// handlers are never removed.
    pub fn on_signals() -> Result<Self, SignalSetupError> {
        let stop = Self::new();
        for (signal, forced) in [
            (StopSignal::Interrupt, EXIT_FORCED_SIGINT),
            (StopSignal::Terminate, EXIT_FORCED_SIGTERM),
        ] {
            let n = signal.number();
            // The order matters: signal-hook runs a signal's actions in the order registered,
            // so the first signal finds `any` false (no exit) and then sets it.
            signal_hook::flag::register_conditional_shutdown(
                n,
                i32::from(forced),
                Arc::clone(&stop.any),
            )
            .map_err(SignalSetupError)?;
            // Only the first signal's number is kept (a later one exits before this runs).
            signal_hook::flag::register_usize(
                n,
                Arc::clone(&stop.first),
                usize::try_from(n).unwrap_or(0),
            )
            .map_err(SignalSetupError)?;
            signal_hook::flag::register(n, Arc::clone(&stop.any)).map_err(SignalSetupError)?;
        }
        Ok(stop)
    }

    /// Requests a stop as `signal` would (without a signal; a later signal then exits at once
    /// if [`Stop::on_signals`] made this).
    pub fn request(&self, signal: StopSignal) {
        let n = usize::try_from(signal.number()).unwrap_or(0);
        let _ = self
            .first
            .compare_exchange(0, n, Ordering::SeqCst, Ordering::SeqCst);
        self.any.store(true, Ordering::SeqCst);
    }

    /// The signal that requested the stop, if one did.
    pub fn requested(&self) -> Option<StopSignal> {
        if !self.any.load(Ordering::SeqCst) {
            return None;
        }
        // `any` is set after `first` by a signal; a request without a number is SIGTERM's.
        Some(
            StopSignal::from_number(self.first.load(Ordering::SeqCst))
                .unwrap_or(StopSignal::Terminate),
        )
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_request_is_seen_by_every_clone_and_the_first_signal_wins() {
        let stop = Stop::new();
        let seen = stop.clone();
        assert_eq!(seen.requested(), None);
        stop.request(StopSignal::Interrupt);
        stop.request(StopSignal::Terminate);
        assert_eq!(seen.requested(), Some(StopSignal::Interrupt));
        assert_eq!(seen.requested().map(StopSignal::name), Some("SIGINT"));
    }
}
