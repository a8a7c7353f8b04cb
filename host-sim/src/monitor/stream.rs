//! The byte stream: frames decoded into records, refusals counted.

use robot_link::{Decoder, FrameError, Record};

/// What the monitor made of the bytes so far.
#[derive(Debug, Clone, PartialEq)]
pub enum Event {
    /// A record.
    Record(Box<Record>),
    /// A frame refused, and why.
    Refused(FrameError),
}

/// A byte stream turned into [`Event`]s, with the tally.
#[derive(Debug, Default)]
pub struct Monitor {
    decoder: Decoder,
    /// Records decoded.
    pub records: u64,
    /// Frames refused.
    pub refused: u64,
    /// Bytes read.
    pub bytes: u64,
}

impl Monitor {
    /// A monitor that has read nothing.
    pub fn new() -> Self {
        Self::default()
    }

    /// Takes the next bytes of the stream; returns the frames they completed, in order.
    pub fn feed(&mut self, bytes: &[u8]) -> Vec<Event> {
        let mut events = Vec::new();
        self.bytes += bytes.len() as u64;
        self.decoder.feed(bytes, |result| match result {
            Ok(record) => {
                self.records += 1;
                events.push(Event::Record(Box::new(record)));
            }
            Err(e) => {
                self.refused += 1;
                events.push(Event::Refused(e));
            }
        });
        events
    }

    /// Bytes of an unfinished frame at the end of the stream.
    pub fn pending_bytes(&self) -> usize {
        self.decoder.pending_bytes()
    }
}
