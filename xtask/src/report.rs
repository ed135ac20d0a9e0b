//! The host's side of the data the firmware programs send (`beamfield_fixtures::report`): their
//! `frame:` lines decoded by the link's decoder (`beamfield::link::Decoder`), their `report:`
//! lines by `Report::decode`, in the order they came, and taken one at a time by a check that
//! knows what it expects. A line that does not decode, data missing and data more than expected
//! are each an [`Error::Report`].

use crate::error::{Error, ReportFault, Result};
use crate::insncount::without_names;
use beamfield::link::{self, Frame, Message};
use beamfield_fixtures::report::{Report, FRAME_LINE, MAX_REPORT_LEN, REPORT_LINE};

/// One datum the device sent.
#[derive(Clone, Debug)]
pub enum Item {
    /// A frame of the device link.
    Frame(Frame),
    /// A test report.
    Report(Report),
}

impl Item {
    /// What it is, for messages.
    fn describe(&self) -> String {
        match self {
            Item::Frame(f) => format!("link frame {} ({:?})", f.seq, f.message.message_type()),
            Item::Report(r) => format!("report {}", kind_name(r)),
        }
    }
}

/// The name of a report's kind.
fn kind_name(r: &Report) -> &'static str {
    match r {
        Report::TrackStep(_) => "TrackStep",
        Report::TrackSummary(_) => "TrackSummary",
        Report::LidarScan(_) => "LidarScan",
        Report::LidarChunk(_) => "LidarChunk",
        Report::LidarEnd(_) => "LidarEnd",
    }
}

/// The bytes of a hex string, `None` when it is not whole lowercase or uppercase hex pairs.
fn unhex(text: &str) -> Option<Vec<u8>> {
    let t = text.trim_end();
    if t.len() % 2 != 0 {
        return None;
    }
    (0..t.len())
        .step_by(2)
        .map(|i| t.get(i..i + 2).and_then(|p| u8::from_str_radix(p, 16).ok()))
        .collect()
}

/// Every data line of a program's output `out`, decoded, in order.
///
/// # Errors
/// [`ReportFault::Malformed`] for the first line that does not decode: not hex, not one whole
/// link frame (with its delimiter) that the link's decoder accepts with the next sequence
/// number, not one report.
pub fn read(out: &str) -> Result<Vec<Item>> {
    let mut decoder = link::Decoder::new();
    let mut items = Vec::new();
    for (i, line) in out.lines().enumerate() {
        let malformed = |why: String| {
            Error::Report(ReportFault::Malformed {
                line: i + 1,
                why: format!("{why}: {line:?}"),
            })
        };
        if let Some(hex) = line.strip_prefix(FRAME_LINE) {
            let bytes = unhex(hex).ok_or_else(|| malformed("not hex".into()))?;
            if bytes.last() != Some(&link::DELIMITER) {
                return Err(malformed("a link frame without its delimiter".into()));
            }
            let mut got = Vec::new();
            decoder.feed(&bytes, |f| got.push(f));
            let frame = match got.as_slice() {
                [Ok(f)] => *f,
                [Err(e)] => return Err(malformed(format!("the link's decoder refuses it ({e})"))),
                other => {
                    return Err(malformed(format!(
                        "{} link frames on one line, not one",
                        other.len()
                    )))
                }
            };
            if decoder.stats().sequence_gaps != 0 {
                return Err(malformed(format!(
                    "sequence number {} after a gap",
                    frame.seq
                )));
            }
            items.push(Item::Frame(frame));
        } else if let Some(hex) = line.strip_prefix(REPORT_LINE) {
            let bytes = unhex(hex).ok_or_else(|| malformed("not hex".into()))?;
            let r = Report::decode(&bytes).map_err(|e| malformed(e.to_string()))?;
            items.push(Item::Report(r));
        }
    }
    Ok(items)
}

/// A program's output `out` for a person: without its data lines and the lines naming its
/// regions.
pub fn readable(out: &str) -> String {
    without_names(out)
        .lines()
        .filter(|l| !l.starts_with(FRAME_LINE) && !l.starts_with(REPORT_LINE))
        .map(|l| format!("{l}\n"))
        .collect()
}

/// A program's data, taken in order by a check that says what it expects next.
pub struct Items {
    items: std::vec::IntoIter<Item>,
}

impl Items {
    /// The data of the output `out` ([`read`]).
    ///
    /// # Errors
    /// As [`read`].
    pub fn new(out: &str) -> Result<Self> {
        Ok(Self {
            items: read(out)?.into_iter(),
        })
    }

    /// The next datum; `expected` names it for the error when there is none.
    ///
    /// # Errors
    /// [`ReportFault::Missing`].
    pub fn next(&mut self, expected: &str) -> Result<Item> {
        self.items.next().ok_or_else(|| {
            Error::Report(ReportFault::Missing {
                expected: expected.into(),
            })
        })
    }

    /// The next datum, which must be an `Estimate` frame: its sequence number and estimate.
    ///
    /// # Errors
    /// [`ReportFault::Missing`], or [`ReportFault::Unexpected`] for anything else.
    pub fn estimate(&mut self, expected: &str) -> Result<(u16, link::Estimate)> {
        match self.next(expected)? {
            Item::Frame(Frame {
                seq,
                message: Message::Estimate(e),
            }) => Ok((seq, e)),
            other => Err(unexpected(expected, &other)),
        }
    }

    /// The next datum, which must be a report.
    ///
    /// # Errors
    /// [`ReportFault::Missing`], or [`ReportFault::Unexpected`] for a link frame.
    pub fn report(&mut self, expected: &str) -> Result<Report> {
        match self.next(expected)? {
            Item::Report(r) => Ok(r),
            other => Err(unexpected(expected, &other)),
        }
    }

    /// Nothing may follow.
    ///
    /// # Errors
    /// [`ReportFault::Unexpected`] for a datum more than expected.
    pub fn end(mut self) -> Result {
        match self.items.next() {
            None => Ok(()),
            Some(extra) => Err(unexpected("the end of the data", &extra)),
        }
    }
}

/// The error for `got` where the host expected `expected`.
pub fn unexpected(expected: &str, got: &Item) -> Error {
    Error::Report(ReportFault::Unexpected {
        expected: expected.into(),
        got: got.describe(),
    })
}

/// The error for report `got` where the host expected `expected`.
pub fn unexpected_report(expected: &str, got: &Report) -> Error {
    unexpected(expected, &Item::Report(*got))
}

/// True when the two reports are equal bit for bit (their encodings are the same bytes).
pub fn same_bits(a: &Report, b: &Report) -> bool {
    let (mut x, mut y) = ([0u8; MAX_REPORT_LEN], [0u8; MAX_REPORT_LEN]);
    match (a.encode(&mut x), b.encode(&mut y)) {
        (Ok(n), Ok(m)) => x[..n] == y[..m],
        _ => false,
    }
}

/// The bit patterns of an estimate, for comparisons and messages: the timestamp, x, y, θ, the
/// covariance row-major, the ESS, the flags, the quality state and score.
pub fn estimate_bits(e: &link::Estimate) -> Vec<u64> {
    let mut v = vec![e.timestamp_us];
    v.extend(
        [e.pose.x_m, e.pose.y_m, e.pose.theta_rad]
            .iter()
            .chain(e.covariance.iter().flatten())
            .chain([e.ess].iter())
            .map(|f| u64::from(f.to_bits())),
    );
    v.push(u64::from(e.flags.bits()));
    v.push(e.quality.state as u64);
    v.push(u64::from(e.quality.score.to_bits()));
    v
}

/// The line a program prints for a link frame: [`FRAME_LINE`] and the wire bytes in hex.
#[cfg(test)]
pub fn frame_line(seq: u16, message: &Message) -> String {
    let mut wire = [0u8; link::MAX_WIRE_LEN];
    let n = link::encode(seq, message, &mut wire).expect("encodable");
    format!("{FRAME_LINE}{}", hex(&wire[..n]))
}

/// The line a program prints for a report: [`REPORT_LINE`] and its bytes in hex.
#[cfg(test)]
pub fn report_line(r: &Report) -> String {
    let mut bytes = [0u8; MAX_REPORT_LEN];
    let n = r.encode(&mut bytes).expect("encodable");
    format!("{REPORT_LINE}{}", hex(&bytes[..n]))
}

#[cfg(test)]
fn hex(bytes: &[u8]) -> String {
    bytes.iter().map(|b| format!("{b:02x}")).collect()
}

#[cfg(test)]
mod tests {
    use super::*;
    use beamfield::link::WheelTicks;
    use beamfield_fixtures::report::LidarChunk;

    #[test]
    fn data_lines_decode_in_order_and_everything_else_is_ignored() {
        let chunk = Report::LidarChunk(LidarChunk {
            bytes: 10,
            scans: 1,
        });
        let ticks = Message::WheelTicks(WheelTicks {
            timestamp_us: 5,
            left_ticks: 1,
            right_ticks: -1,
        });
        let out = format!(
            "hello\n{}\nchunk 0: words\n{}\n{}\n",
            report_line(&chunk),
            frame_line(0, &ticks),
            frame_line(1, &ticks)
        );
        let items = read(&out).expect("decodes");
        assert_eq!(items.len(), 3);
        assert!(matches!(items[0], Item::Report(r) if same_bits(&r, &chunk)));
        assert!(matches!(items[2], Item::Frame(f) if f.seq == 1 && f.message == ticks));
        let mut it = Items::new(&out).unwrap();
        assert!(it.report("a chunk").is_ok());
        assert!(matches!(
            it.report("a chunk"),
            Err(Error::Report(ReportFault::Unexpected { .. }))
        ));
        assert!(matches!(
            it.end(),
            Err(Error::Report(ReportFault::Unexpected { .. }))
        ));
        let mut it = Items::new(&report_line(&chunk)).unwrap();
        it.next("a chunk").unwrap();
        assert!(matches!(
            it.next("another"),
            Err(Error::Report(ReportFault::Missing { .. }))
        ));
    }

    #[test]
    fn malformed_lines_are_errors_with_their_line_number() {
        let good = report_line(&Report::LidarChunk(LidarChunk { bytes: 1, scans: 0 }));
        let ticks = Message::WheelTicks(WheelTicks {
            timestamp_us: 5,
            left_ticks: 1,
            right_ticks: -1,
        });
        let frame = frame_line(0, &ticks);
        let flipped = {
            let mut b = good.clone().into_bytes();
            let last = b.len() - 1;
            b[last] = if b[last] == b'0' { b'1' } else { b'0' };
            String::from_utf8(b).unwrap()
        };
        for bad in [
            format!("{REPORT_LINE}zz"),
            format!("{REPORT_LINE}abc"),
            flipped,
            frame[..frame.len() - 2].to_string(),
            format!("{frame}{}", &frame[FRAME_LINE.len()..]),
            // A gap in the frames' sequence numbers.
            format!("{frame}\n{}", frame_line(2, &ticks)),
        ] {
            let out = format!("words\n{bad}\n");
            match read(&out) {
                Err(Error::Report(ReportFault::Malformed { line, .. })) => {
                    assert!(line >= 2, "{bad}");
                }
                other => panic!("{bad}: {other:?}"),
            }
        }
    }
}
