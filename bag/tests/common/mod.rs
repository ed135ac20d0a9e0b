//! Shared by the bag's integration tests (`mod common;`): a little-endian CDR message laid out
//! by hand from the message definitions. Not every test file uses every method.
#![allow(dead_code)]

/// A little-endian CDR message being laid out: the 4-byte encapsulation header, then fields
/// aligned to their size.
pub struct Out(pub Vec<u8>);

impl Out {
    pub fn new() -> Self {
        Out(vec![0, 1, 0, 0])
    }
    pub fn align(&mut self, n: usize) {
        while (self.0.len() - 4) % n != 0 {
            self.0.push(0);
        }
    }
    pub fn u32(&mut self, v: u32) -> &mut Self {
        self.align(4);
        self.0.extend(v.to_le_bytes());
        self
    }
    pub fn f32(&mut self, v: f32) -> &mut Self {
        self.align(4);
        self.0.extend(v.to_le_bytes());
        self
    }
    pub fn f64(&mut self, v: f64) -> &mut Self {
        self.align(8);
        self.0.extend(v.to_le_bytes());
        self
    }
    pub fn string(&mut self, s: &str) -> &mut Self {
        self.u32(s.len() as u32 + 1);
        self.0.extend(s.as_bytes());
        self.0.push(0);
        self
    }
    /// A std_msgs/Header: stamp (seconds, 0 ns) and frame id.
    pub fn header(&mut self, t_s: u32, frame: &str) -> &mut Self {
        self.u32(t_s).u32(0).string(frame)
    }
}
