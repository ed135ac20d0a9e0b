//! A bounded queue between one producer thread and one consumer: when it is full, the oldest
//! entry is dropped and counted, so a producer faster than the consumer costs entries, never
//! memory beyond the capacity.

use std::collections::VecDeque;
use std::sync::{Condvar, Mutex, MutexGuard};
use std::time::Duration;

/// Entries between the link's reader and the bridge's loop (a flood of the longest frames,
/// 4096 × about 100 bytes of decoded message, stays under a megabyte).
pub const LINK_QUEUE_CAPACITY: usize = 4096;

#[derive(Debug)]
struct State<T> {
    items: VecDeque<T>,
    dropped: u64,
    /// The consumer is gone: the producer may stop.
    abandoned: bool,
}

/// The queue (share it in an `Arc`).
#[derive(Debug)]
pub struct Bounded<T> {
    state: Mutex<State<T>>,
    ready: Condvar,
    capacity: usize,
}

impl<T> Bounded<T> {
    /// A queue of at most `capacity` entries (at least 1).
    pub fn new(capacity: usize) -> Self {
        Self {
            state: Mutex::new(State {
                items: VecDeque::new(),
                dropped: 0,
                abandoned: false,
            }),
            ready: Condvar::new(),
            capacity: capacity.max(1),
        }
    }

    fn lock(&self) -> MutexGuard<'_, State<T>> {
        // A thread that panicked holding the lock left the queue consistent (every change is
        // one VecDeque call): keep using it.
        self.state.lock().unwrap_or_else(|p| p.into_inner())
    }

    /// Appends `item`, dropping the oldest entry when the queue is full. Returns false when the
    /// consumer is gone.
    pub fn push(&self, item: T) -> bool {
        let mut s = self.lock();
        if s.abandoned {
            return false;
        }
        if s.items.len() >= self.capacity {
            s.items.pop_front();
            s.dropped += 1;
        }
        s.items.push_back(item);
        drop(s);
        self.ready.notify_one();
        true
    }

    /// Everything queued, waiting at most `timeout` for the first entry.
    pub fn take_all(&self, timeout: Duration) -> Vec<T> {
        let mut s = self.lock();
        if s.items.is_empty() {
            s = self
                .ready
                .wait_timeout_while(s, timeout, |s| s.items.is_empty())
                .map_or_else(|p| p.into_inner().0, |(g, _)| g);
        }
        s.items.drain(..).collect()
    }

    /// Entries dropped because the queue was full.
    pub fn dropped(&self) -> u64 {
        self.lock().dropped
    }

    /// Entries waiting.
    pub fn len(&self) -> usize {
        self.lock().items.len()
    }

    /// No entry waiting.
    pub fn is_empty(&self) -> bool {
        self.len() == 0
    }

    /// The consumer is gone: further pushes are refused and what is queued is freed.
    pub fn abandon(&self) {
        let mut s = self.lock();
        s.abandoned = true;
        s.items.clear();
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use std::sync::Arc;
    use std::time::Instant;

    #[test]
    fn full_queue_drops_the_oldest_and_counts() {
        let q = Bounded::new(4);
        for k in 0..10 {
            assert!(q.push(k));
        }
        assert_eq!(q.len(), 4);
        assert_eq!(q.dropped(), 6);
        assert_eq!(q.take_all(Duration::ZERO), vec![6, 7, 8, 9]);
        assert!(q.is_empty());
    }

    #[test]
    fn take_all_waits_for_the_first_entry_only_up_to_the_timeout() {
        let q = Arc::new(Bounded::new(8));
        let t = Instant::now();
        assert!(q.take_all(Duration::from_millis(30)).is_empty());
        assert!(t.elapsed() >= Duration::from_millis(30));
        let p = Arc::clone(&q);
        let h = std::thread::spawn(move || {
            std::thread::sleep(Duration::from_millis(20));
            p.push(1u8)
        });
        assert_eq!(q.take_all(Duration::from_secs(10)), vec![1]);
        assert!(h.join().unwrap());
    }

    #[test]
    fn an_abandoned_queue_refuses_pushes() {
        let q = Bounded::new(2);
        assert!(q.push(1));
        q.abandon();
        assert!(!q.push(2));
        assert!(q.is_empty());
    }
}
