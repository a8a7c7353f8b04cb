//! A recorded angle sensor: replays a script of reads (angles or errors), for the end-to-end image
//! on QEMU and for host tests.

use super::AngleSensor;

/// Why a replayed read failed.
#[derive(Clone, Copy, Debug, PartialEq, Eq, defmt::Format)]
pub enum ReplayError {
    /// The script has no more reads.
    Exhausted,
    /// The script holds a failed read here (standing in for a bus or sensor fault).
    Injected,
}

/// Replays a script of reads, one per call.
#[derive(Clone, Copy, Debug)]
pub struct ReplaySensor<'a> {
    counts_per_turn: u32,
    script: &'a [Result<u16, ReplayError>],
    next: usize,
}

impl<'a> ReplaySensor<'a> {
    /// A sensor of `counts_per_turn` counts replaying `script`.
    pub fn new(counts_per_turn: u32, script: &'a [Result<u16, ReplayError>]) -> Self {
        Self {
            counts_per_turn,
            script,
            next: 0,
        }
    }
}

impl AngleSensor for ReplaySensor<'_> {
    type Error = ReplayError;

    fn counts_per_turn(&self) -> u32 {
        self.counts_per_turn
    }

    fn read_angle_counts(&mut self) -> Result<u16, ReplayError> {
        let read = self
            .script
            .get(self.next)
            .copied()
            .unwrap_or(Err(ReplayError::Exhausted));
        self.next = self.next.saturating_add(1);
        read
    }
}
