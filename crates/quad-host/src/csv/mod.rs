//! The line-oriented CSV of the batch commands: reading rows with their line numbers, reporting
//! malformed rows, and printing f32 numbers so that they read back to the same value.
//!
//! Input rules, shared by every batch command:
//! - one record per line, fields separated by `,`, surrounding spaces ignored, no quoting;
//! - blank lines and lines starting with `#` (after optional spaces) are skipped;
//! - the header row is optional: the first record is taken as a header when its first field is
//!   not a value of the first column (not a number, or for `leg` columns not a leg name). A
//!   header must then name exactly the expected columns (case-insensitive), otherwise the whole
//!   input is refused — a different header usually means a different file format;
//! - a malformed record (wrong field count, a field that is not a number or not a leg) is
//!   reported on stderr as `<input>:<line>: <what is wrong>` and produces no output row; the
//!   other records are still answered.
//!
//! Numbers are written with Rust's shortest round-trip formatting of `f32` (`{}`), so parsing a
//! printed value as `f32` gives back the same value; `-0` is printed as `0`.
//!
//! The motion CSV (`quadctl motion`'s output, read by `check`, `plot` and `accuracy`)
//! has its own reader and writer in [`motion`].

pub mod motion;

use kin_core::LegId;
use std::fmt;
use std::io::{self, BufRead, Write};
use std::path::{Path, PathBuf};

/// An `f32` printed with the shortest decimal that parses back to the same value (`-0` as `0`).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Num(pub f32);

impl fmt::Display for Num {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        if self.0 == 0.0 {
            f.write_str("0")
        } else {
            write!(f, "{}", self.0)
        }
    }
}

/// The value expected in the first column, used to tell a header from a record.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum FirstColumn {
    /// A leg name (`FL`, `FR`, `RL`, `RR`).
    Leg,
    /// A number.
    Number,
}

/// The columns of an input format.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct Schema {
    /// Column names, in order; also the expected header.
    pub columns: &'static [&'static str],
    /// What the first column holds.
    pub first: FirstColumn,
}

impl Schema {
    /// The header line, e.g. `leg,x_m,y_m,z_m`.
    pub fn header(&self) -> String {
        self.columns.join(",")
    }
}

/// What is wrong with one record. Field numbers are 1-based.
#[derive(Debug, Clone, PartialEq, Eq)]
#[non_exhaustive]
pub enum RowError {
    /// The record does not have one field per column.
    FieldCount {
        /// Number of columns expected.
        expected: usize,
        /// Number of fields found.
        found: usize,
        /// The expected header, for the message.
        header: String,
    },
    /// A field is empty.
    Empty {
        /// 1-based field number.
        field: usize,
        /// Column name.
        column: &'static str,
    },
    /// A field is not a number.
    NotANumber {
        /// 1-based field number.
        field: usize,
        /// Column name.
        column: &'static str,
        /// The text found.
        text: String,
    },
    /// A number that must be finite is NaN or infinite.
    NotFinite {
        /// 1-based field number.
        field: usize,
        /// Column name.
        column: &'static str,
        /// The text found.
        text: String,
    },
    /// Fewer fields than a column the header names needs.
    TooFewFields {
        /// Fields needed.
        needed: usize,
        /// Fields found.
        found: usize,
    },
    /// A field of a header-addressed file (motion, angles) is not a number.
    BadNumber {
        /// 1-based field number.
        field: usize,
        /// The text found.
        text: String,
    },
    /// A field of a header-addressed file must be a finite number.
    BadFinite {
        /// 1-based field number.
        field: usize,
        /// The text found.
        text: String,
    },
    /// The `t_s` field is not a number.
    BadTime {
        /// 1-based field number.
        field: usize,
    },
    /// A field is not one of `FL`, `FR`, `RL`, `RR`.
    NotALeg {
        /// 1-based field number.
        field: usize,
        /// Column name.
        column: &'static str,
        /// The text found.
        text: String,
    },
}

impl fmt::Display for RowError {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match self {
            RowError::FieldCount {
                expected,
                found,
                header,
            } => write!(f, "expected {expected} fields ({header}), found {found}"),
            RowError::Empty { field, column } => write!(f, "field {field} ({column}) is empty"),
            RowError::NotANumber {
                field,
                column,
                text,
            } => write!(f, "field {field} ({column}): `{text}` is not a number"),
            RowError::NotFinite {
                field,
                column,
                text,
            } => write!(
                f,
                "field {field} ({column}): `{text}` is not a finite number"
            ),
            RowError::TooFewFields { needed, found } => {
                write!(f, "expected at least {needed} fields, found {found}")
            }
            RowError::BadNumber { field, text } => {
                write!(f, "field {field}: `{text}` is not a number")
            }
            RowError::BadFinite { field, text } => {
                write!(f, "field {field}: `{text}` is not a finite number")
            }
            RowError::BadTime { field } => write!(f, "field {field}: t_s is not a number"),
            RowError::NotALeg {
                field,
                column,
                text,
            } => write!(
                f,
                "field {field} ({column}): `{text}` is not a leg (FL, FR, RL, RR)"
            ),
        }
    }
}

impl std::error::Error for RowError {}

/// Errors that stop a whole batch.
#[derive(Debug)]
#[non_exhaustive]
pub enum Error {
    /// The input file could not be opened.
    Open {
        /// The path given.
        path: PathBuf,
        /// The I/O error.
        source: io::Error,
    },
    /// Reading the input or writing the output failed.
    Io(io::Error),
    /// The header row does not name the expected columns.
    Header {
        /// Input name (file path or `<stdin>`).
        input: String,
        /// 1-based line number.
        line: usize,
        /// The header found.
        found: String,
        /// The header expected.
        expected: String,
    },
    /// Reading a named input failed.
    Read {
        /// Input name.
        input: String,
        /// The I/O error.
        source: io::Error,
    },
    /// A header-addressed file (motion, angles) has no header.
    Empty {
        /// Input name.
        input: String,
        /// What the header must hold.
        expected: &'static str,
    },
    /// The header lacks a column.
    MissingColumn {
        /// Input name.
        input: String,
        /// 1-based line of the header.
        line: usize,
        /// The column.
        column: String,
        /// The format expected.
        format: &'static str,
    },
    /// A record of a header-addressed file that cannot be used (such files stop at the first).
    Row {
        /// Input name.
        input: String,
        /// 1-based line.
        line: usize,
        /// What is wrong.
        error: RowError,
    },
    /// An output file could not be created.
    Create {
        /// The file.
        path: PathBuf,
        /// The I/O error.
        source: io::Error,
    },
    /// Writing an output failed.
    Write {
        /// The file; `None` for stdout.
        path: Option<PathBuf>,
        /// The I/O error.
        source: io::Error,
    },
}

impl fmt::Display for Error {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match self {
            Error::Open { path, source } => {
                write!(f, "cannot open input `{}`: {source}", path.display())
            }
            Error::Io(e) => write!(f, "I/O error: {e}"),
            Error::Header {
                input,
                line,
                found,
                expected,
            } => write!(
                f,
                "{input}:{line}: header `{found}` does not match the expected `{expected}` \
                 (nothing was processed)"
            ),
            Error::Read { input, source } => write!(f, "cannot read `{input}`: {source}"),
            Error::Empty { input, expected } => {
                write!(f, "{input}: empty file: expected a header {expected}")
            }
            Error::MissingColumn {
                input,
                line,
                column,
                format,
            } => write!(
                f,
                "{input}:{line}: header has no `{column}` column (expected {format})"
            ),
            Error::Row { input, line, error } => write!(f, "{input}:{line}: {error}"),
            Error::Create { path, source } => {
                write!(f, "cannot create `{}`: {source}", path.display())
            }
            Error::Write {
                path: Some(p),
                source,
            } => {
                write!(f, "cannot write `{}`: {source}", p.display())
            }
            Error::Write { path: None, source } => write!(f, "cannot write the output: {source}"),
        }
    }
}

impl std::error::Error for Error {
    fn source(&self) -> Option<&(dyn std::error::Error + 'static)> {
        match self {
            Error::Open { source, .. }
            | Error::Io(source)
            | Error::Read { source, .. }
            | Error::Create { source, .. }
            | Error::Write { source, .. } => Some(source),
            Error::Row { error, .. } => Some(error),
            _ => None,
        }
    }
}

impl From<io::Error> for Error {
    fn from(e: io::Error) -> Self {
        Error::Io(e)
    }
}

/// An input stream with the name used in messages.
pub struct Input {
    /// `<stdin>` or the file path.
    pub name: String,
    /// The buffered reader.
    pub reader: Box<dyn BufRead>,
}

impl Input {
    /// Opens `path`, or standard input when `path` is `-`.
    pub fn open(path: &Path) -> Result<Input, Error> {
        if path.as_os_str() == "-" {
            return Ok(Input {
                name: "<stdin>".to_owned(),
                reader: Box::new(io::BufReader::new(io::stdin())),
            });
        }
        let file = std::fs::File::open(path).map_err(|source| Error::Open {
            path: path.to_owned(),
            source,
        })?;
        Ok(Input {
            name: path.display().to_string(),
            reader: Box::new(io::BufReader::new(file)),
        })
    }

    /// An in-memory input (for tests and embedding).
    pub fn from_bytes(name: &str, bytes: Vec<u8>) -> Input {
        Input {
            name: name.to_owned(),
            reader: Box::new(io::Cursor::new(bytes)),
        }
    }
}

/// One record: its line number and its trimmed fields.
#[derive(Debug, Clone, PartialEq)]
pub struct Row {
    /// 1-based line number in the input.
    pub line: usize,
    /// The fields, trimmed.
    pub fields: Vec<String>,
    schema: Schema,
}

impl Row {
    /// Checks that there is one field per column.
    pub fn check_count(&self) -> Result<(), RowError> {
        let expected = self.schema.columns.len();
        if self.fields.len() == expected {
            Ok(())
        } else {
            Err(RowError::FieldCount {
                expected,
                found: self.fields.len(),
                header: self.schema.header(),
            })
        }
    }

    fn field(&self, i: usize) -> Result<(&str, &'static str), RowError> {
        let column = self.schema.columns[i];
        match self.fields.get(i).map(String::as_str) {
            Some("") | None => Err(RowError::Empty {
                field: i + 1,
                column,
            }),
            Some(text) => Ok((text, column)),
        }
    }

    /// Field `i` (0-based) as an `f32`; `nan` and `inf` are accepted (see [`Row::finite`]).
    pub fn number(&self, i: usize) -> Result<f32, RowError> {
        let (text, column) = self.field(i)?;
        text.parse::<f32>().map_err(|_| RowError::NotANumber {
            field: i + 1,
            column,
            text: text.to_owned(),
        })
    }

    /// Field `i` (0-based) as a finite `f32`.
    pub fn finite(&self, i: usize) -> Result<f32, RowError> {
        let v = self.number(i)?;
        if v.is_finite() {
            Ok(v)
        } else {
            Err(RowError::NotFinite {
                field: i + 1,
                column: self.schema.columns[i],
                text: self.fields[i].clone(),
            })
        }
    }

    /// Field `i` (0-based) as a leg name (case-insensitive).
    pub fn leg(&self, i: usize) -> Result<LegId, RowError> {
        let (text, column) = self.field(i)?;
        LegId::parse(text).ok_or_else(|| RowError::NotALeg {
            field: i + 1,
            column,
            text: text.to_owned(),
        })
    }
}

/// Why one record produced no output row.
#[derive(Debug)]
#[non_exhaustive]
pub enum AnswerError {
    /// The record is malformed: reported, and the batch goes on.
    Row(RowError),
    /// Writing the output failed: the batch stops.
    Io(io::Error),
}

impl From<RowError> for AnswerError {
    fn from(e: RowError) -> Self {
        AnswerError::Row(e)
    }
}

impl From<io::Error> for AnswerError {
    fn from(e: io::Error) -> Self {
        AnswerError::Io(e)
    }
}

/// Counts of a finished batch.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
pub struct Summary {
    /// Records answered with an output row (reachable or not).
    pub answered: usize,
    /// Malformed records, reported on stderr, without an output row.
    pub malformed: usize,
}

/// Runs `answer` on every record of `input`, writing its output rows to `out` after `header`.
///
/// `answer` parses and answers one record; when it returns [`AnswerError::Row`] nothing must have
/// been written for that record, and the error is reported on `diag` as
/// `<input>:<line>: <error>`.
pub fn for_each_row(
    input: Input,
    schema: Schema,
    out: &mut dyn Write,
    diag: &mut dyn Write,
    header: Option<&str>,
    mut answer: impl FnMut(&Row, &mut dyn Write) -> Result<(), AnswerError>,
) -> Result<Summary, Error> {
    let Input { name, mut reader } = input;
    if let Some(h) = header {
        writeln!(out, "{h}")?;
    }
    let mut summary = Summary::default();
    let mut buf = String::new();
    let mut line = 0usize;
    let mut first_record = true;
    loop {
        buf.clear();
        if reader.read_line(&mut buf)? == 0 {
            break;
        }
        line += 1;
        let text = buf.trim();
        if text.is_empty() || text.starts_with('#') {
            continue;
        }
        let row = Row {
            line,
            fields: text.split(',').map(|f| f.trim().to_owned()).collect(),
            schema,
        };
        if std::mem::take(&mut first_record) && is_header(&row, schema) {
            let matches = row.fields.len() == schema.columns.len()
                && row
                    .fields
                    .iter()
                    .zip(schema.columns)
                    .all(|(f, c)| f.eq_ignore_ascii_case(c));
            if matches {
                continue;
            }
            return Err(Error::Header {
                input: name,
                line,
                found: text.to_owned(),
                expected: schema.header(),
            });
        }
        let result = row
            .check_count()
            .map_err(AnswerError::Row)
            .and_then(|()| answer(&row, out));
        match result {
            Ok(()) => summary.answered += 1,
            Err(AnswerError::Row(e)) => {
                summary.malformed += 1;
                writeln!(diag, "{name}:{line}: {e}")?;
            }
            Err(AnswerError::Io(e)) => return Err(Error::Io(e)),
        }
    }
    out.flush()?;
    Ok(summary)
}

fn is_header(row: &Row, schema: Schema) -> bool {
    let first = row.fields[0].as_str();
    match schema.first {
        FirstColumn::Leg => LegId::parse(first).is_none(),
        FirstColumn::Number => first.parse::<f32>().is_err(),
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    const SCHEMA: Schema = Schema {
        columns: &["leg", "x_m"],
        first: FirstColumn::Leg,
    };

    fn run(text: &str) -> (Result<Summary, Error>, String, String) {
        let mut out = Vec::new();
        let mut diag = Vec::new();
        let r = for_each_row(
            Input::from_bytes("in.csv", text.as_bytes().to_vec()),
            SCHEMA,
            &mut out,
            &mut diag,
            Some("leg,twice_x_m"),
            |row, out| {
                let leg = row.leg(0)?;
                let x = row.finite(1)?;
                writeln!(out, "{leg},{}", Num(2.0 * x))?;
                Ok(())
            },
        );
        (
            r,
            String::from_utf8(out).expect("utf8"),
            String::from_utf8(diag).expect("utf8"),
        )
    }

    #[test]
    fn num_round_trips_and_hides_negative_zero() {
        for v in [
            0.1f32,
            -0.557,
            1.0e-7,
            3.4028235e38,
            f32::MIN_POSITIVE,
            0.9294,
        ] {
            let s = Num(v).to_string();
            assert_eq!(s.parse::<f32>().expect("number"), v, "{s}");
        }
        assert_eq!(Num(-0.0).to_string(), "0");
        assert_eq!(Num(0.0).to_string(), "0");
    }

    #[test]
    fn header_is_optional_and_comments_are_skipped() {
        let with = run("leg,x_m\n# c\n\nfl,1.5\n");
        let without = run("  # c\nFL , 1.5\r\n");
        for (r, out, diag) in [with, without] {
            assert_eq!(r.expect("ok").answered, 1);
            assert_eq!(out, "leg,twice_x_m\nFL,3\n");
            assert_eq!(diag, "");
        }
    }

    #[test]
    fn malformed_rows_are_reported_with_their_line_and_skipped() {
        let (r, out, diag) = run("leg,x_m\nFL,1\nXX,2\nFR\nRL,abc\nRR,nan\nRR,\nRR,4\n");
        let s = r.expect("batch runs");
        assert_eq!((s.answered, s.malformed), (2, 5));
        assert_eq!(out, "leg,twice_x_m\nFL,2\nRR,8\n");
        let lines: Vec<&str> = diag.lines().collect();
        assert_eq!(
            lines,
            [
                "in.csv:3: field 1 (leg): `XX` is not a leg (FL, FR, RL, RR)",
                "in.csv:4: expected 2 fields (leg,x_m), found 1",
                "in.csv:5: field 2 (x_m): `abc` is not a number",
                "in.csv:6: field 2 (x_m): `nan` is not a finite number",
                "in.csv:7: field 2 (x_m) is empty",
            ]
        );
    }

    #[test]
    fn a_foreign_header_stops_the_batch() {
        let (r, _, _) = run("\nleg,abduction_rad\nFL,1\n");
        match r {
            Err(Error::Header { line, expected, .. }) => {
                assert_eq!(line, 2);
                assert_eq!(expected, "leg,x_m");
            }
            other => panic!("expected a header error, got {other:?}"),
        }
    }
}
