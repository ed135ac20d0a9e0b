//! One topic's outgoing message while the DDS writer cannot take it: a reliable reader that
//! has not acknowledged fills the writer's window and a write would block. The outbox keeps the
//! newest message only (an older pose or transform is of no use once a newer one exists) and
//! retries it on the next [`Outbox::flush`]; a message replaced before it went out is counted.

use serde::Serialize;

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
    pub counters: OutboxCounters,
}

impl<M> Default for Outbox<M> {
    fn default() -> Self {
        Self {
            pending: None,
            counters: OutboxCounters::default(),
        }
    }
}

impl<M> Outbox<M> {
    pub fn new() -> Self {
        Self::default()
    }

    /// A message waiting to be retried.
    pub fn is_pending(&self) -> bool {
        self.pending.is_some()
    }

    /// Replaces any waiting message with `m` and tries to publish it. A failure other than a
    /// full window is returned (the message is dropped).
    pub fn offer(
        &mut self,
        m: M,
        publish: impl FnOnce(M) -> Result<(), PublishError<M>>,
    ) -> Result<(), RosError> {
        if self.pending.replace(m).is_some() {
            self.counters.superseded += 1;
        }
        self.flush(publish)
    }

    /// Tries to publish the waiting message, if any.
    pub fn flush(
        &mut self,
        publish: impl FnOnce(M) -> Result<(), PublishError<M>>,
    ) -> Result<(), RosError> {
        let Some(m) = self.pending.take() else {
            return Ok(());
        };
        match publish(m) {
            Ok(()) => {
                self.counters.published += 1;
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
        let mut o = Outbox::new();
        let mut sent = Vec::new();
        let full = |m: u32| Err(PublishError::WouldBlock(Box::new(m)));
        o.offer(1, full).unwrap();
        o.offer(2, full).unwrap();
        o.offer(3, full).unwrap();
        assert!(o.is_pending());
        o.flush(|m| {
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
        o.flush(|_| panic!("nothing to publish")).unwrap();
    }

    #[test]
    fn other_failures_drop_the_message_and_are_returned() {
        let mut o = Outbox::new();
        let e = o.offer(7u8, |_| {
            Err(PublishError::Failed(RosError("broken".into())))
        });
        assert_eq!(e.unwrap_err().0, "broken");
        assert!(!o.is_pending());
        assert_eq!(o.counters.failed, 1);
    }
}
