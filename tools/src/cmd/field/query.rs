//! `beamfield field query`: distances at "x,y" points read on stdin, one answer line per input
//! line, written as they are read; malformed lines are reported on stderr and counted.

use crate::blob::FieldError;
use crate::input::field_file::{parse_field_file, read_field_file};
use beamfield::field::FieldView;
use clap::Args;
use serde::Serialize;
use std::io::{BufRead, Write};
use std::path::PathBuf;

/// Arguments of `beamfield field query`.
#[derive(Args, Debug)]
pub struct QueryArgs {
    /// The blob.
    pub blob: PathBuf,
}

/// Runs `field query` over stdin, stdout and stderr (`json`: JSON lines).
///
/// # Errors
/// [`FieldError::QueryLineTooLong`], [`FieldError::BadLines`] after the reading;
/// [`FieldError::Read`], [`FieldError::Blob`], [`FieldError::Io`].
pub fn run(a: &QueryArgs, json: bool) -> Result<QueryReport, FieldError> {
    let bytes = read_field_file(&a.blob)?;
    let view = parse_field_file(&bytes).map_err(|e| FieldError::Blob(a.blob.clone(), e))?;
    let stdin = std::io::stdin();
    let report = run_query(
        &view,
        stdin.lock(),
        std::io::stdout().lock(),
        std::io::stderr().lock(),
        json,
    )
    .map_err(|e| FieldError::Io(PathBuf::from("<stdio>"), e))?;
    if let Some(n) = report.too_long {
        Err(FieldError::QueryLineTooLong(n))
    } else if report.bad > 0 {
        Err(FieldError::BadLines(report.bad))
    } else {
        Ok(report)
    }
}

/// What `field query` did.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Serialize)]
pub struct QueryReport {
    /// Lines answered.
    pub answered: usize,
    /// Malformed lines reported (not numbers, not UTF-8).
    pub bad: usize,
    /// The 1-based number of a line longer than [`crate::input::limits::MAX_QUERY_LINE_BYTES`], where
    /// reading stopped (the rest of such a line may never end: `/dev/zero`).
    pub too_long: Option<usize>,
}

/// Answers "x,y" lines from `input` on `out`; reports malformed lines (1-based line numbers,
/// the line quoted as an escaped prefix of at most [`crate::input::limits::QUOTE_CHARS`] characters)
/// on `err`. Blank lines and lines starting with `#` are ignored. A line longer than
/// [`crate::input::limits::MAX_QUERY_LINE_BYTES`] stops the reading ([`QueryReport::too_long`]):
/// nothing of it past the limit is read or kept.
///
/// # Errors
/// I/O errors of the streams.
pub fn run_query(
    view: &FieldView<'_>,
    mut input: impl BufRead,
    mut out: impl Write,
    mut err: impl Write,
    json: bool,
) -> std::io::Result<QueryReport> {
    use crate::input::limits::{escaped_prefix, read_bounded_line, BoundedLine, QUOTE_CHARS};
    let mut report = QueryReport::default();
    let mut buf = Vec::new();
    let mut number = 0usize;
    while let Some(line) = read_bounded_line(
        &mut input,
        &mut buf,
        crate::input::limits::MAX_QUERY_LINE_BYTES,
    )? {
        number += 1;
        let t = match line {
            BoundedLine::Text(t) => t.trim(),
            BoundedLine::TooLong => {
                report.too_long = Some(number);
                break;
            }
            BoundedLine::NotUtf8 => {
                report.bad += 1;
                if json {
                    writeln!(
                        err,
                        "{}",
                        serde_json::json!({ "line": number, "error": "not UTF-8 text" })
                    )?;
                } else {
                    writeln!(err, "line {number}: not UTF-8 text")?;
                }
                continue;
            }
        };
        if t.is_empty() || t.starts_with('#') {
            continue;
        }
        match parse_xy(t) {
            Ok((x, y)) => {
                let d = view.distance_m(x, y);
                if json {
                    writeln!(
                        out,
                        "{}",
                        serde_json::json!({ "x": x, "y": y, "distance_m": d })
                    )?;
                } else {
                    writeln!(out, "{x},{y},{d}")?;
                }
                report.answered += 1;
            }
            Err(why) => {
                report.bad += 1;
                let quoted = escaped_prefix(t, QUOTE_CHARS);
                if json {
                    writeln!(
                        err,
                        "{}",
                        serde_json::json!({ "line": number, "error": why, "text": quoted })
                    )?;
                } else {
                    writeln!(err, "line {number}: {why}: \"{quoted}\"")?;
                }
            }
        }
    }
    Ok(report)
}

fn parse_xy(t: &str) -> Result<(f32, f32), &'static str> {
    let mut it = t.split(',');
    let (Some(a), Some(b), None) = (it.next(), it.next(), it.next()) else {
        return Err("expected two comma-separated numbers x,y");
    };
    let x: f32 = a.trim().parse().map_err(|_| "x is not a number")?;
    let y: f32 = b.trim().parse().map_err(|_| "y is not a number")?;
    if !(x.is_finite() && y.is_finite()) {
        return Err("x and y must be finite");
    }
    Ok((x, y))
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn xy_parsing_table() {
        let ok = [("1,2", (1.0, 2.0)), (" -3.5 , 4e-1 ", (-3.5, 0.4))];
        for (s, want) in ok {
            assert_eq!(parse_xy(s), Ok(want), "{s}");
        }
        for bad in ["1", "1,2,3", "a,2", "1,", "nan,1", "inf,0"] {
            assert!(parse_xy(bad).is_err(), "{bad}");
        }
    }
}
