//! Where the application's bytes come from and where its frames go.

use crate::link::Message;
use crate::pose::Pose;

/// A stream of received bytes, taken one at a time: the consumer end of an interrupt-fed ring
/// on the device ([`heapless::spsc::Consumer`]), a slice on the host ([`SliceSource`]).
pub trait ByteSource {
    /// The next byte, or `None` when none is waiting.
    fn next_byte(&mut self) -> Option<u8>;
}

/// On targets with atomic compare-and-swap (the Cortex-M3/M4/M7 and larger; `heapless` also
/// provides its ring on some targets with atomic loads and stores only, for which this
/// implementation is not compiled: wrap the consumer in a type of your own there).
#[cfg(target_has_atomic = "ptr")]
impl ByteSource for heapless::spsc::Consumer<'_, u8> {
    #[inline]
    fn next_byte(&mut self) -> Option<u8> {
        self.dequeue()
    }
}

/// The bytes of a slice, in order: a recorded stream replayed on the host.
#[derive(Clone, Copy, Debug)]
pub struct SliceSource<'b> {
    bytes: &'b [u8],
    taken: usize,
}

impl<'b> SliceSource<'b> {
    /// A source that hands out `bytes`.
    pub const fn new(bytes: &'b [u8]) -> Self {
        Self { bytes, taken: 0 }
    }

    /// Bytes handed out so far.
    pub fn taken(&self) -> usize {
        self.taken
    }

    /// Whether every byte was handed out.
    pub fn is_empty(&self) -> bool {
        self.taken >= self.bytes.len()
    }
}

impl ByteSource for SliceSource<'_> {
    #[inline]
    fn next_byte(&mut self) -> Option<u8> {
        let b = self.bytes.get(self.taken).copied()?;
        self.taken += 1;
        Some(b)
    }
}

/// An estimate kept across restarts: the pose and its covariance, what
/// [`crate::link::SetInitialPose`] carries without the timestamp. A device keeps the last one in
/// a flash page (or battery-backed RAM) and passes it to [`super::Robot::new`] at the next start.
#[derive(Clone, Copy, Debug, PartialEq, Default)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub struct Seed {
    /// Pose in the map frame, m and rad.
    pub pose: Pose,
    /// Covariance of `(x, y, θ)`, m² and rad².
    pub covariance: [[f32; 3]; 3],
}

/// Where the application's output goes.
pub trait Sink {
    /// One frame to send to the computer: the message and its bytes on the wire (COBS frame
    /// and delimiter, ready for the UART).
    fn send(&mut self, message: &Message, wire: &[u8]);

    /// The last good estimate, after every update that was not part of a global localization.
    /// Called at every update: a store that writes flash should write only when the pose has
    /// moved or some time has passed. The default keeps nothing.
    fn save(&mut self, seed: &Seed) {
        let _ = seed;
    }
}
