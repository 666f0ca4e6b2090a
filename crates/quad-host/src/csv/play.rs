//! The timed setpoint files of `quadctl play`: read whole and checked before anything is sent.
//!
//! Two formats, told apart by the header:
//! - **the motion CSV** (`quadctl motion`'s output, with its `status` column): read by
//!   [`super::motion::MotionCsv`], its one reader; every row must be `ok` (a row without angles
//!   cannot be played);
//! - **a play file**: `t_s` and the columns of one or more kinds: the twelve joint angles
//!   `FL_abduction_rad … RR_knee_rad`, the four feet `FL_x_m … RR_z_m`, the body pose
//!   `roll_rad, pitch_rad, yaw_rad, x_m, y_m, z_m`. Every field must be a number (`nan` is
//!   passed on: the device refuses it, and so does the host's check).
//!
//! In both, the feet are in the world frame of `quadctl motion` (the body frame of the nominal
//! pose), the header's column names are case-insensitive, lines starting with `#` and blank
//! lines are skipped, a comment token `rotation_order=<order>` names the body pose's rotation
//! order, `t_s` must be finite and increase strictly, and a column of no known kind or a kind
//! with a column missing refuses the file.

use super::motion::MotionCsv;
use super::{Error as CsvError, Input, RowError};
use kin_core::{LegId, Pose, RotationOrder, Vec3};
use std::io::Read;
use std::path::Path;

/// The pose columns, in [`Pose::from_array`]'s order.
pub const POSE_COLUMNS: [&str; 6] = ["roll_rad", "pitch_rad", "yaw_rad", "x_m", "y_m", "z_m"];

/// What a column of a setpoint file holds.
#[derive(Debug, Clone, Copy, PartialEq, Eq, serde::Serialize)]
#[serde(rename_all = "snake_case")]
#[non_exhaustive]
pub enum ColumnKind {
    /// Joint angles, rad.
    Joints,
    /// Feet in the world frame, m.
    Feet,
    /// Body pose, rad and m.
    Pose,
}

impl ColumnKind {
    /// Every kind, in the order [`crate::ops::play`] prefers them.
    pub const ALL: [ColumnKind; 3] = [ColumnKind::Joints, ColumnKind::Feet, ColumnKind::Pose];

    /// The kind's name in messages and summaries.
    pub fn name(self) -> &'static str {
        match self {
            ColumnKind::Joints => "joints",
            ColumnKind::Feet => "feet",
            ColumnKind::Pose => "pose",
        }
    }

    /// The kind's columns, in order.
    pub fn columns(self) -> Vec<String> {
        match self {
            ColumnKind::Joints => LegId::ALL
                .iter()
                .flat_map(|l| ["abduction", "hip", "knee"].map(|j| format!("{l}_{j}_rad")))
                .collect(),
            ColumnKind::Feet => LegId::ALL
                .iter()
                .flat_map(|l| ["x", "y", "z"].map(|a| format!("{l}_{a}_m")))
                .collect(),
            ColumnKind::Pose => POSE_COLUMNS.iter().map(|c| (*c).to_owned()).collect(),
        }
    }

    fn of(column: &str) -> Option<ColumnKind> {
        ColumnKind::ALL
            .into_iter()
            .find(|k| k.columns().iter().any(|c| c.eq_ignore_ascii_case(column)))
    }
}

/// Why a setpoint file cannot be played. Every variant names the file and the line.
#[derive(Debug, thiserror::Error)]
#[non_exhaustive]
pub enum Error {
    /// Reading failed, or a row of the motion CSV is malformed.
    #[error(transparent)]
    Csv(#[from] CsvError),
    /// The file has no header.
    #[error("{input}: empty file: expected a header with t_s and joint, foot or pose columns")]
    Empty {
        /// The file.
        input: String,
    },
    /// The header has no `t_s` column.
    #[error("{input}:{line}: header has no `t_s` column (the time of each setpoint, s)")]
    NoTime {
        /// The file.
        input: String,
        /// The header's line.
        line: usize,
    },
    /// A column of no known kind.
    #[error(
        "{input}:{line}: column {field} `{column}` is of no known kind (expected t_s, status, \
         FL_abduction_rad … RR_knee_rad, FL_x_m … RR_z_m or roll_rad, pitch_rad, yaw_rad, x_m, \
         y_m, z_m)"
    )]
    UnknownColumn {
        /// The file.
        input: String,
        /// The header's line.
        line: usize,
        /// 1-based field number.
        field: usize,
        /// The column's name.
        column: String,
    },
    /// A kind with some of its columns.
    #[error("{input}:{line}: header has {kind} columns but no `{column}`")]
    Incomplete {
        /// The file.
        input: String,
        /// The header's line.
        line: usize,
        /// The kind.
        kind: &'static str,
        /// The missing column.
        column: String,
    },
    /// No setpoint columns at all.
    #[error("{input}:{line}: header has no joint, foot or pose columns: nothing to send")]
    NoSetpoint {
        /// The file.
        input: String,
        /// The header's line.
        line: usize,
    },
    /// A column named twice.
    #[error("{input}:{line}: column `{column}` appears twice")]
    Duplicate {
        /// The file.
        input: String,
        /// The header's line.
        line: usize,
        /// The column.
        column: String,
    },
    /// `t_s` is not finite.
    #[error("{input}:{line}: column t_s (field {field}): time is not finite")]
    TimeNotFinite {
        /// The file.
        input: String,
        /// The row's line.
        line: usize,
        /// 1-based field number of `t_s`.
        field: usize,
    },
    /// `t_s` does not increase.
    #[error(
        "{input}:{line}: column t_s (field {field}): {t_s} s does not follow {previous_s} s \
         (times must increase strictly)"
    )]
    NotIncreasing {
        /// The file.
        input: String,
        /// The row's line.
        line: usize,
        /// 1-based field number of `t_s`.
        field: usize,
        /// The row's time, s.
        t_s: f64,
        /// The previous row's time, s.
        previous_s: f64,
    },
    /// A row of the motion CSV whose status is not `ok`.
    #[error(
        "{input}:{line}: column status (field {field}): `{status}`: the sample has no angles \
         to send"
    )]
    NotOk {
        /// The file.
        input: String,
        /// The row's line.
        line: usize,
        /// 1-based field number of `status`.
        field: usize,
        /// The status.
        status: String,
    },
    /// The file has no rows.
    #[error("{input}: no setpoints after the header")]
    NoRows {
        /// The file.
        input: String,
    },
}

/// One row: its time and what it holds.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Frame {
    /// 1-based line.
    pub line: usize,
    /// Time, s.
    pub t_s: f64,
    /// The twelve joint angles, when the file has them.
    pub angles: Option<[f32; 12]>,
    /// The feet in the world frame, when the file has them.
    pub feet: Option<[Vec3; 4]>,
    /// The body pose, when the file has it.
    pub pose: Option<Pose>,
}

/// A whole setpoint file.
#[derive(Debug, Clone, PartialEq)]
pub struct PlayFile {
    /// The file's name in messages.
    pub name: String,
    /// The rotation order named in a comment, if any.
    pub rotation_order: Option<RotationOrder>,
    /// True for `quadctl motion`'s output.
    pub motion_csv: bool,
    /// The rows, times strictly increasing.
    pub frames: Vec<Frame>,
}

impl PlayFile {
    /// The kinds of columns present (the same in every row).
    pub fn kinds(&self) -> Vec<ColumnKind> {
        let Some(f) = self.frames.first() else {
            return Vec::new();
        };
        let mut kinds = Vec::new();
        if f.angles.is_some() {
            kinds.push(ColumnKind::Joints);
        }
        if f.feet.is_some() {
            kinds.push(ColumnKind::Feet);
        }
        if f.pose.is_some() {
            kinds.push(ColumnKind::Pose);
        }
        kinds
    }
}

/// Reads and checks `path` (`-`: stdin) whole.
///
/// # Errors
/// See [`Error`]: the first problem, with the file, line and column.
pub fn read(path: &Path) -> Result<PlayFile, Error> {
    let Input { name, mut reader } = Input::open(path)?;
    let mut bytes = Vec::new();
    reader
        .read_to_end(&mut bytes)
        .map_err(|source| CsvError::Read {
            input: name.clone(),
            source,
        })?;
    parse(&name, bytes)
}

/// Reads and checks the file `name` held in `bytes`.
///
/// # Errors
/// See [`read`].
pub fn parse(name: &str, bytes: Vec<u8>) -> Result<PlayFile, Error> {
    let text = String::from_utf8_lossy(&bytes);
    let mut rotation_order = None;
    let mut header = None;
    let mut lines = text.lines().enumerate();
    for (i, l) in lines.by_ref() {
        let t = l.trim();
        if let Some(comment) = t.strip_prefix('#') {
            for token in comment.split_whitespace() {
                if let Some(o) = token.strip_prefix("rotation_order=") {
                    rotation_order = RotationOrder::parse(o);
                }
            }
        } else if !t.is_empty() {
            header = Some((i + 1, t));
            break;
        }
    }
    let err_input = || name.to_owned();
    let Some((line, header)) = header else {
        return Err(Error::Empty { input: err_input() });
    };
    let cols: Vec<&str> = header.split(',').map(str::trim).collect();
    let at = |c: &str| cols.iter().position(|x| x.eq_ignore_ascii_case(c));
    for (i, c) in cols.iter().enumerate() {
        if cols[..i].iter().any(|x| x.eq_ignore_ascii_case(c)) {
            return Err(Error::Duplicate {
                input: err_input(),
                line,
                column: (*c).to_owned(),
            });
        }
        let known = c.eq_ignore_ascii_case("t_s")
            || c.eq_ignore_ascii_case("status")
            || ColumnKind::of(c).is_some();
        if !known {
            return Err(Error::UnknownColumn {
                input: err_input(),
                line,
                field: i + 1,
                column: (*c).to_owned(),
            });
        }
    }
    let Some(t_col) = at("t_s") else {
        return Err(Error::NoTime {
            input: err_input(),
            line,
        });
    };
    // Each kind: all of its columns, or none.
    let mut index: [Option<Vec<usize>>; 3] = [None, None, None];
    for (k, kind) in ColumnKind::ALL.into_iter().enumerate() {
        let names = kind.columns();
        let found: Vec<Option<usize>> = names.iter().map(|c| at(c)).collect();
        if found.iter().all(Option::is_none) {
            continue;
        }
        if let Some(missing) = found.iter().position(Option::is_none) {
            return Err(Error::Incomplete {
                input: err_input(),
                line,
                kind: kind.name(),
                column: names[missing].clone(),
            });
        }
        index[k] = Some(found.into_iter().flatten().collect());
    }
    if index.iter().all(Option::is_none) {
        return Err(Error::NoSetpoint {
            input: err_input(),
            line,
        });
    }
    let status = at("status");
    let mut frames = Vec::new();
    let motion_csv = status.is_some() && index[0].is_some();
    if motion_csv {
        // `quadctl motion`'s output: its own reader.
        let status_field = status.map_or(0, |s| s + 1);
        let mut csv = MotionCsv::from_input(Input::from_bytes(name, bytes))?;
        while let Some(row) = csv.next_row()? {
            let Some(angles) = row.angles else {
                return Err(Error::NotOk {
                    input: err_input(),
                    line: row.line,
                    field: status_field,
                    status: row.status,
                });
            };
            frames.push(Frame {
                line: row.line,
                t_s: row.t_s,
                angles: Some(angles),
                feet: row.feet,
                pose: row.pose,
            });
        }
    } else {
        if status.is_some() {
            // A status without the angles it describes.
            return Err(Error::Incomplete {
                input: err_input(),
                line,
                kind: "motion CSV (status)",
                column: ColumnKind::Joints.columns()[0].clone(),
            });
        }
        for (i, l) in lines {
            let t = l.trim();
            if t.is_empty() || t.starts_with('#') {
                continue;
            }
            let line = i + 1;
            let fields: Vec<&str> = t.split(',').map(str::trim).collect();
            let row_err = |error| {
                Error::Csv(CsvError::Row {
                    input: err_input(),
                    line,
                    error,
                })
            };
            let num = |i: usize| -> Result<f32, Error> {
                let s = fields.get(i).ok_or_else(|| {
                    row_err(RowError::TooFewFields {
                        needed: i + 1,
                        found: fields.len(),
                    })
                })?;
                s.parse::<f32>().map_err(|_| {
                    row_err(RowError::BadNumber {
                        field: i + 1,
                        text: (*s).to_owned(),
                    })
                })
            };
            let t_s: f64 = fields
                .get(t_col)
                .and_then(|s| s.parse().ok())
                .ok_or_else(|| row_err(RowError::BadTime { field: t_col + 1 }))?;
            let values = |idx: &Option<Vec<usize>>| -> Result<Option<Vec<f32>>, Error> {
                idx.as_ref()
                    .map(|idx| idx.iter().map(|&i| num(i)).collect())
                    .transpose()
            };
            let angles = values(&index[0])?.map(|v| {
                let mut a = [0.0f32; 12];
                a.copy_from_slice(&v);
                a
            });
            let feet = values(&index[1])?.map(|v| {
                let mut f = [Vec3::ZERO; 4];
                for (l, foot) in f.iter_mut().enumerate() {
                    *foot = Vec3::new(v[3 * l], v[3 * l + 1], v[3 * l + 2]);
                }
                f
            });
            let pose = values(&index[2])?.map(|v| {
                let mut p = [0.0f32; 6];
                p.copy_from_slice(&v);
                Pose::from_array(p)
            });
            frames.push(Frame {
                line,
                t_s,
                angles,
                feet,
                pose,
            });
        }
    }
    let mut previous: Option<f64> = None;
    for f in &frames {
        if !f.t_s.is_finite() {
            return Err(Error::TimeNotFinite {
                input: err_input(),
                line: f.line,
                field: t_col + 1,
            });
        }
        if let Some(p) = previous {
            if !(f.t_s > p) {
                return Err(Error::NotIncreasing {
                    input: err_input(),
                    line: f.line,
                    field: t_col + 1,
                    t_s: f.t_s,
                    previous_s: p,
                });
            }
        }
        previous = Some(f.t_s);
    }
    if frames.is_empty() {
        return Err(Error::NoRows { input: err_input() });
    }
    Ok(PlayFile {
        name: name.to_owned(),
        rotation_order,
        motion_csv,
        frames,
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    fn parse_str(text: &str) -> Result<PlayFile, Error> {
        parse("f.csv", text.as_bytes().to_vec())
    }

    #[test]
    fn a_play_file_reads_its_kinds_and_rotation_order() {
        let f = parse_str(
            "# rotation_order=zxy\nT_S,roll_rad,pitch_rad,yaw_rad,x_m,y_m,z_m\n\n0,0.1,0,0,0,0,0\n# c\n0.02,0.2,0,0,0,0,0\n",
        )
        .unwrap();
        assert_eq!(f.rotation_order, Some(RotationOrder::Zxy));
        assert!(!f.motion_csv);
        assert_eq!(f.kinds(), [ColumnKind::Pose]);
        assert_eq!(f.frames.len(), 2);
        assert_eq!((f.frames[1].line, f.frames[1].t_s), (6, 0.02));
        assert_eq!(f.frames[1].pose.unwrap().roll_rad, 0.2);
    }

    #[test]
    fn refusals_name_the_line_and_column() {
        let e = parse_str("t_s,roll_rad,pitch_rad,yaw_rad,x_m,y_m,z_m,t_s\n").unwrap_err();
        assert!(matches!(e, Error::Duplicate { line: 1, .. }), "{e}");
        let e = parse_str("t_s,FL_x_m\n0,1\n").unwrap_err();
        assert!(
            matches!(&e, Error::Incomplete { kind: "feet", column, .. } if column == "FL_y_m"),
            "{e}"
        );
        let e = parse_str(
            "t_s,roll_rad,pitch_rad,yaw_rad,x_m,y_m,z_m\n1,0,0,0,0,0,0\n0.5,0,0,0,0,0,0\n",
        )
        .unwrap_err();
        assert!(
            matches!(
                e,
                Error::NotIncreasing {
                    line: 3,
                    field: 1,
                    ..
                }
            ),
            "{e}"
        );
        let e = parse_str("t_s,roll_rad,pitch_rad,yaw_rad,x_m,y_m,z_m\n").unwrap_err();
        assert!(matches!(e, Error::NoRows { .. }), "{e}");
        let e = parse_str("\n# only\n").unwrap_err();
        assert!(matches!(e, Error::Empty { .. }), "{e}");
    }
}
