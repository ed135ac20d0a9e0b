//! One topic's outgoing message while the DDS writer cannot take it: a reliable reader that
//! has not acknowledged fills the writer's window and a write would block. The outbox keeps the
//! newest message only (an older pose or transform is of no use once a newer one exists) and
//! retries it on the next [`Outbox::flush`]; a message replaced before it went out is counted.
//!
//! It also publishes at most once per [`MIN_INTERVAL`]: a device that floods the link with
//! estimates costs superseded messages, not a DDS writer history that grows faster than the
//! middleware cleans it (a transient-local writer with no reader keeps what it was given until
//! its periodic cleanup).

use std::time::{Duration, Instant};

use serde::Serialize;

/// The shortest time between two messages of one topic: 5 ms, 200 Hz, twenty times the
/// LiDAR's rate of estimates.
pub const MIN_INTERVAL: Duration = Duration::from_millis(5);

use crate::ros::{PublishError, RosError};

/// What one topic's outbox did, counts of messages.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Serialize)]
pub struct OutboxCounters {
    /// Published.
    pub published: u64,
    /// Write attempts refused because the writer's window was full (the message was kept).
    pub would_block: u64,
    /// Messages replaced by a newer one before they could be published.
    pub superseded: u64,
    /// Messages the middleware refused for another reason (dropped).
    pub failed: u64,
}

/// The newest unpublished message of one topic.
#[derive(Debug)]
pub struct Outbox<M> {
    pending: Option<M>,
    /// When the last message went out.
    last: Option<Instant>,
    interval: Duration,
    pub counters: OutboxCounters,
}

impl<M> Default for Outbox<M> {
    fn default() -> Self {
        Self::new(MIN_INTERVAL)
    }
}

impl<M> Outbox<M> {
    /// An outbox that publishes at most once per `interval`.
    pub fn new(interval: Duration) -> Self {
        Self {
            pending: None,
            last: None,
            interval,
            counters: OutboxCounters::default(),
        }
    }

    /// A message waiting to be retried.
    pub fn is_pending(&self) -> bool {
        self.pending.is_some()
    }

    /// Replaces any waiting message with `m` and tries to publish it at `now`. A failure
    /// other than a full window is returned (the message is dropped).
    pub fn offer(
        &mut self,
        m: M,
        now: Instant,
        publish: impl FnOnce(M) -> Result<(), PublishError<M>>,
    ) -> Result<(), RosError> {
        if self.pending.replace(m).is_some() {
            self.counters.superseded += 1;
        }
        self.flush(now, publish)
    }

    /// Tries to publish the waiting message, if any, unless the last one went out less than
    /// the interval before `now`.
    pub fn flush(
        &mut self,
        now: Instant,
        publish: impl FnOnce(M) -> Result<(), PublishError<M>>,
    ) -> Result<(), RosError> {
        if self
            .last
            .is_some_and(|l| now.saturating_duration_since(l) < self.interval)
        {
            return Ok(());
        }
        let Some(m) = self.pending.take() else {
            return Ok(());
        };
        match publish(m) {
            Ok(()) => {
                self.counters.published += 1;
                self.last = Some(now);
                Ok(())
            }
            Err(PublishError::WouldBlock(m)) => {
                self.counters.would_block += 1;
                self.pending = Some(*m);
                Ok(())
            }
            Err(PublishError::Failed(e)) => {
                self.counters.failed += 1;
                Err(e)
            }
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_full_window_keeps_the_newest_and_retries() {
        let mut o = Outbox::new(MIN_INTERVAL);
        let mut sent = Vec::new();
        let full = |m: u32| Err(PublishError::WouldBlock(Box::new(m)));
        let t = Instant::now();
        o.offer(1, t, full).unwrap();
        o.offer(2, t, full).unwrap();
        o.offer(3, t, full).unwrap();
        assert!(o.is_pending());
        o.flush(t, |m| {
            sent.push(m);
            Ok(())
        })
        .unwrap();
        assert_eq!(sent, vec![3]);
        assert!(!o.is_pending());
        assert_eq!(
            o.counters,
            OutboxCounters {
                published: 1,
                would_block: 3,
                superseded: 2,
                failed: 0
            }
        );
        // Nothing waiting: nothing is published.
        o.flush(t + Duration::from_secs(1), |_| panic!("nothing to publish"))
            .unwrap();
    }

    #[test]
    fn at_most_one_message_per_interval() {
        let mut o = Outbox::new(Duration::from_millis(5));
        let mut sent = Vec::new();
        let t = Instant::now();
        let ms = |n: u64| t + Duration::from_millis(n);
        for (k, at) in [(1, 0), (2, 1), (3, 4), (4, 5), (5, 6)] {
            o.offer(k, ms(at), |m| {
                sent.push(m);
                Ok(())
            })
            .unwrap();
        }
        // 1 at 0 ms; 2 and 3 wait and are superseded; 4 at 5 ms; 5 waits.
        assert_eq!(sent, vec![1, 4]);
        assert!(o.is_pending());
        o.flush(ms(10), |m| {
            sent.push(m);
            Ok(())
        })
        .unwrap();
        assert_eq!(sent, vec![1, 4, 5]);
        assert_eq!(o.counters.superseded, 2);
        assert_eq!(o.counters.published, 3);
    }

    #[test]
    fn other_failures_drop_the_message_and_are_returned() {
        let mut o = Outbox::new(MIN_INTERVAL);
        let e = o.offer(7u8, Instant::now(), |_| {
            Err(PublishError::Failed(RosError("broken".into())))
        });
        assert_eq!(e.unwrap_err().0, "broken");
        assert!(!o.is_pending());
        assert_eq!(o.counters.failed, 1);
    }
}
