//! The part of CDR (OMG XCDR1, as ROS 2 serializes messages) that the bag reader needs: a
//! 4-byte encapsulation header (`00 01`: little endian, `00 00`: big endian, then 2 option
//! bytes), then fields aligned to their size counted from the end of the header; strings are a
//! `u32` length that includes a NUL, sequences a `u32` count. Every read is checked: a short or
//! malformed buffer is a [`CdrError`], never a panic.

/// Why a message could not be read.
#[derive(Clone, Debug, PartialEq, Eq)]
pub enum CdrError {
    /// Fewer bytes than the field needs, at this offset (after the header).
    Truncated { at: usize },
    /// The encapsulation header is not plain CDR (e.g. XCDR2 or parameter lists).
    Encapsulation([u8; 2]),
    /// A string without its NUL or not UTF-8, at this offset.
    BadString { at: usize },
    /// A sequence longer than the bytes left could hold, at this offset.
    Length { at: usize, count: u32 },
}

impl std::fmt::Display for CdrError {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        match self {
            Self::Truncated { at } => write!(f, "CDR data ends inside a field at byte {at}"),
            Self::Encapsulation(e) => write!(
                f,
                "CDR encapsulation {:02x} {:02x} is not plain CDR (00 00 or 00 01)",
                e[0], e[1]
            ),
            Self::BadString { at } => write!(f, "malformed CDR string at byte {at}"),
            Self::Length { at, count } => {
                write!(
                    f,
                    "CDR sequence of {count} elements at byte {at} is longer than the data"
                )
            }
        }
    }
}

impl std::error::Error for CdrError {}

/// A reader over one serialized message.
pub struct Cdr<'a> {
    body: &'a [u8],
    at: usize,
    little: bool,
}

impl<'a> Cdr<'a> {
    /// Reads the encapsulation header.
    pub fn new(data: &'a [u8]) -> Result<Self, CdrError> {
        let header = data.get(..4).ok_or(CdrError::Truncated { at: 0 })?;
        let little = match [header[0], header[1]] {
            [0, 1] => true,
            [0, 0] => false,
            other => return Err(CdrError::Encapsulation(other)),
        };
        Ok(Self {
            body: &data[4..],
            at: 0,
            little,
        })
    }

    fn take<const N: usize>(&mut self) -> Result<[u8; N], CdrError> {
        let start = self.at.div_ceil(N) * N;
        let bytes = self
            .body
            .get(start..start + N)
            .ok_or(CdrError::Truncated { at: start })?;
        self.at = start + N;
        let mut out = [0u8; N];
        out.copy_from_slice(bytes);
        if !self.little {
            out.reverse();
        }
        Ok(out)
    }

    pub fn u8(&mut self) -> Result<u8, CdrError> {
        Ok(self.take::<1>()?[0])
    }

    pub fn u32(&mut self) -> Result<u32, CdrError> {
        Ok(u32::from_le_bytes(self.take()?))
    }

    pub fn i32(&mut self) -> Result<i32, CdrError> {
        Ok(i32::from_le_bytes(self.take()?))
    }

    pub fn f32(&mut self) -> Result<f32, CdrError> {
        Ok(f32::from_le_bytes(self.take()?))
    }

    pub fn f64(&mut self) -> Result<f64, CdrError> {
        Ok(f64::from_le_bytes(self.take()?))
    }

    pub fn string(&mut self) -> Result<String, CdrError> {
        let at = self.at;
        let n = self.u32()? as usize;
        let bytes = self
            .body
            .get(self.at..self.at.saturating_add(n))
            .ok_or(CdrError::Truncated { at: self.at })?;
        let (nul, text) = bytes.split_last().ok_or(CdrError::BadString { at })?;
        if *nul != 0 {
            return Err(CdrError::BadString { at });
        }
        let s = std::str::from_utf8(text).map_err(|_| CdrError::BadString { at })?;
        self.at += n;
        Ok(s.to_owned())
    }

    /// A sequence's element count, checked against the bytes left (`min_size` bytes each).
    pub fn count(&mut self, min_size: usize) -> Result<usize, CdrError> {
        let at = self.at;
        let count = self.u32()?;
        let left = self.body.len().saturating_sub(self.at);
        if (count as usize).saturating_mul(min_size) > left {
            return Err(CdrError::Length { at, count });
        }
        Ok(count as usize)
    }

    pub fn f32_seq(&mut self) -> Result<Vec<f32>, CdrError> {
        let n = self.count(4)?;
        (0..n).map(|_| self.f32()).collect()
    }

    pub fn skip_f64(&mut self, n: usize) -> Result<(), CdrError> {
        for _ in 0..n {
            self.f64()?;
        }
        Ok(())
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn aligned_reads_and_refusals() {
        // header LE; u8 7; (pad 3) u32 5; string "ab"; (pad) f64 1.5
        let mut d = vec![
            0, 1, 0, 0, 7, 0, 0, 0, 5, 0, 0, 0, 3, 0, 0, 0, b'a', b'b', 0,
        ];
        d.push(0); // the string ends at body offset 15: one byte to 16, a multiple of 8
        d.extend(1.5f64.to_le_bytes());
        let mut c = Cdr::new(&d).unwrap();
        assert_eq!(c.u8().unwrap(), 7);
        assert_eq!(c.u32().unwrap(), 5);
        assert_eq!(c.string().unwrap(), "ab");
        assert_eq!(c.f64().unwrap(), 1.5);
        assert_eq!(c.u8(), Err(CdrError::Truncated { at: 24 }));
        assert!(matches!(
            Cdr::new(&[0, 7, 0, 0]),
            Err(CdrError::Encapsulation([0, 7]))
        ));
        assert!(matches!(
            Cdr::new(&[0, 1]),
            Err(CdrError::Truncated { at: 0 })
        ));
        // A sequence claiming more elements than bytes.
        let d = [0, 1, 0, 0, 0xff, 0xff, 0xff, 0x0f, 0, 0];
        assert!(matches!(
            Cdr::new(&d).unwrap().f32_seq(),
            Err(CdrError::Length { .. })
        ));
        // A string without its NUL.
        let d = [0, 1, 0, 0, 2, 0, 0, 0, b'a', b'b'];
        assert!(matches!(
            Cdr::new(&d).unwrap().string(),
            Err(CdrError::BadString { .. })
        ));
    }

    #[test]
    fn big_endian() {
        let d = [0, 0, 0, 0, 0, 0, 0, 9];
        assert_eq!(Cdr::new(&d).unwrap().u32().unwrap(), 9);
    }
}
