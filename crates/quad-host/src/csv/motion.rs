//! The motion CSV: what `quadctl motion` writes and `check`, `plot` and `accuracy` read.
//!
//! One row per sample: `t_s`; the twelve joint angles `FL_abduction_rad … RR_knee_rad`; the
//! four feet in the world frame `FL_x_m … RR_z_m`; the body pose `roll_rad … z_m`; `status`
//! (`ok`, or `<leg>:<reason>` with empty angle cells). A comment line before the header,
//! `# quadctl motion <law> robot=… rotation_order=… …`, names the rotation order.

use super::{Error, Input, RowError};
use kin_core::{JointAngles, LegId, Pose, RotationOrder, Vec3};
use std::io::{self, BufRead, Write};
use std::path::{Path, PathBuf};

/// The CSV header of a motion.
pub fn header() -> String {
    let mut cols = vec!["t_s".to_owned()];
    for leg in LegId::ALL {
        for j in ["abduction", "hip", "knee"] {
            cols.push(format!("{leg}_{j}_rad"));
        }
    }
    for leg in LegId::ALL {
        for a in ["x", "y", "z"] {
            cols.push(format!("{leg}_{a}_m"));
        }
    }
    for c in [
        "roll_rad",
        "pitch_rad",
        "yaw_rad",
        "x_m",
        "y_m",
        "z_m",
        "status",
    ] {
        cols.push(c.to_owned());
    }
    cols.join(",")
}

/// Pushes `v` as the shortest decimal that reads back to the same f32 (`ryu`; `-0` as `0`).
pub fn push_num(line: &mut String, buf: &mut ryu::Buffer, v: f32) {
    if v == 0.0 {
        line.push('0');
    } else {
        line.push_str(buf.format(v));
    }
}

/// Where a long CSV goes: a temporary file renamed into place when complete (so that a file
/// appears only when whole), or stdout.
pub struct Output {
    /// The writer.
    pub out: Box<dyn Write>,
    temp: Option<(PathBuf, PathBuf)>,
}

impl Output {
    /// Opens `output` (its temporary file), or stdout when `None`.
    ///
    /// # Errors
    /// [`Error::Create`].
    pub fn open(output: Option<&Path>) -> Result<Output, Error> {
        let Some(path) = output else {
            return Ok(Output {
                out: Box::new(io::BufWriter::with_capacity(1 << 20, io::stdout())),
                temp: None,
            });
        };
        let name = path
            .file_name()
            .map(|n| n.to_string_lossy().into_owned())
            .unwrap_or_else(|| "motion".to_owned());
        let temp = path.with_file_name(format!(".{name}.{}.tmp", std::process::id()));
        let file = std::fs::File::create(&temp).map_err(|source| Error::Create {
            path: temp.clone(),
            source,
        })?;
        Ok(Output {
            out: Box::new(io::BufWriter::with_capacity(1 << 20, file)),
            temp: Some((temp, path.to_owned())),
        })
    }

    /// Flushes and renames into place.
    ///
    /// # Errors
    /// [`Error::Write`].
    pub fn commit(mut self) -> Result<(), Error> {
        let flushed = self.out.flush();
        let temp = self.temp.take();
        drop(self.out);
        match (flushed, temp) {
            (Ok(()), Some((temp, path))) => std::fs::rename(&temp, &path).map_err(|source| {
                let _ = std::fs::remove_file(&temp);
                Error::Write {
                    path: Some(path),
                    source,
                }
            }),
            (Ok(()), None) => Ok(()),
            (Err(source), temp) => {
                if let Some((temp, _)) = temp {
                    let _ = std::fs::remove_file(temp);
                }
                Err(Error::Write { path: None, source })
            }
        }
    }

    /// Removes the temporary file.
    pub fn abandon(self) {
        if let Some((temp, _)) = self.temp {
            drop(self.out);
            let _ = std::fs::remove_file(temp);
        }
    }
}

/// One row of a motion CSV.
#[derive(Debug, Clone, PartialEq)]
pub struct MotionRow {
    /// 1-based line number.
    pub line: usize,
    /// Time, s.
    pub t_s: f64,
    /// The twelve angles, `None` when the row's status is not `ok`.
    pub angles: Option<[f32; 12]>,
    /// Feet in the world frame, when the file has them.
    pub feet: Option<[Vec3; 4]>,
    /// Body pose, when the file has it.
    pub pose: Option<Pose>,
    /// The status cell.
    pub status: String,
}

/// Reader of motion CSVs (the format [`header`] describes; extra columns are ignored, the feet
/// and pose columns are optional).
pub struct MotionCsv {
    /// The rotation order named by a `rotation_order=` token in a comment line before the
    /// header (as `quadctl motion` writes it), if any.
    pub rotation_order: Option<RotationOrder>,
    name: String,
    reader: Box<dyn BufRead>,
    line: usize,
    t: usize,
    angles: [usize; 12],
    feet: Option<[usize; 12]>,
    pose: Option<[usize; 6]>,
    status: usize,
    buf: String,
}

impl MotionCsv {
    /// Opens `path` (`-` for stdin) and reads its header.
    pub fn open(path: &Path) -> Result<MotionCsv, Error> {
        Self::from_input(Input::open(path)?)
    }

    /// Reads the header of `input`.
    pub fn from_input(input: Input) -> Result<MotionCsv, Error> {
        let Input { name, mut reader } = input;
        let mut buf = String::new();
        let mut line = 0;
        let mut rotation_order = None;
        let header = loop {
            buf.clear();
            let n = reader.read_line(&mut buf).map_err(|source| Error::Read {
                input: name.clone(),
                source,
            })?;
            if n == 0 {
                return Err(Error::Empty {
                    input: name,
                    expected: "starting with t_s",
                });
            }
            line += 1;
            let t = buf.trim();
            if let Some(comment) = t.strip_prefix('#') {
                for token in comment.split_whitespace() {
                    if let Some(o) = token.strip_prefix("rotation_order=") {
                        rotation_order = RotationOrder::parse(o);
                    }
                }
            } else if !t.is_empty() {
                break t.to_owned();
            }
        };
        let cols: Vec<&str> = header.split(',').map(str::trim).collect();
        let at = |c: &str| cols.iter().position(|x| x.eq_ignore_ascii_case(c));
        let need = |c: &str| {
            at(c).ok_or_else(|| Error::MissingColumn {
                input: name.clone(),
                line,
                column: c.to_owned(),
                format: "the `quadctl motion` format",
            })
        };
        let t = need("t_s")?;
        let mut angles = [0usize; 12];
        for leg in LegId::ALL {
            for (j, jn) in ["abduction", "hip", "knee"].iter().enumerate() {
                angles[3 * leg.index() + j] = need(&format!("{leg}_{jn}_rad"))?;
            }
        }
        let status = need("status")?;
        let mut feet = Some([0usize; 12]);
        for leg in LegId::ALL {
            for (a, an) in ["x", "y", "z"].iter().enumerate() {
                match (at(&format!("{leg}_{an}_m")), feet.as_mut()) {
                    (Some(i), Some(f)) => f[3 * leg.index() + a] = i,
                    _ => feet = None,
                }
            }
        }
        let mut pose = Some([0usize; 6]);
        for (i, c) in ["roll_rad", "pitch_rad", "yaw_rad", "x_m", "y_m", "z_m"]
            .iter()
            .enumerate()
        {
            match (at(c), pose.as_mut()) {
                (Some(k), Some(p)) => p[i] = k,
                _ => pose = None,
            }
        }
        Ok(MotionCsv {
            rotation_order,
            name,
            reader,
            line,
            t,
            angles,
            feet,
            pose,
            status,
            buf,
        })
    }

    /// The next row, `None` at the end.
    pub fn next_row(&mut self) -> Result<Option<MotionRow>, Error> {
        loop {
            self.buf.clear();
            let n = self
                .reader
                .read_line(&mut self.buf)
                .map_err(|source| Error::Read {
                    input: self.name.clone(),
                    source,
                })?;
            if n == 0 {
                return Ok(None);
            }
            self.line += 1;
            let text = self.buf.trim();
            if text.is_empty() || text.starts_with('#') {
                continue;
            }
            let fields: Vec<&str> = text.split(',').map(str::trim).collect();
            let row_err = |error| Error::Row {
                input: self.name.clone(),
                line: self.line,
                error,
            };
            let get = |i: usize| -> Result<&str, Error> {
                fields.get(i).copied().ok_or_else(|| {
                    row_err(RowError::TooFewFields {
                        needed: i + 1,
                        found: fields.len(),
                    })
                })
            };
            let num = |i: usize| -> Result<f32, Error> {
                let s = get(i)?;
                s.parse::<f32>().map_err(|_| {
                    row_err(RowError::BadNumber {
                        field: i + 1,
                        text: s.to_owned(),
                    })
                })
            };
            let status = get(self.status)?.to_owned();
            let t_s: f64 = get(self.t)?
                .parse()
                .map_err(|_| row_err(RowError::BadTime { field: self.t + 1 }))?;
            let angles = if status == "ok" {
                let mut a = [0.0f32; 12];
                for (slot, &i) in a.iter_mut().zip(&self.angles) {
                    *slot = num(i)?;
                }
                Some(a)
            } else {
                None
            };
            let feet = match self.feet {
                Some(idx) => {
                    let mut f = [Vec3::ZERO; 4];
                    for (l, foot) in f.iter_mut().enumerate() {
                        *foot =
                            Vec3::new(num(idx[3 * l])?, num(idx[3 * l + 1])?, num(idx[3 * l + 2])?);
                    }
                    Some(f)
                }
                None => None,
            };
            let pose = match self.pose {
                Some(idx) => {
                    let mut v = [0.0f32; 6];
                    for (slot, &i) in v.iter_mut().zip(&idx) {
                        *slot = num(i)?;
                    }
                    Some(Pose::from_array(v))
                }
                None => None,
            };
            return Ok(Some(MotionRow {
                line: self.line,
                t_s,
                angles,
                feet,
                pose,
                status,
            }));
        }
    }
}

/// Samples of one file: per row, the legs present with their angles.
#[derive(Debug, Clone, PartialEq)]
pub struct Samples {
    /// The legs in the file (one, or all four).
    pub legs: Vec<LegId>,
    /// Per kept row: its line and the angles of `legs`; `None` for a row whose status is not ok.
    pub rows: Vec<(usize, Option<Vec<JointAngles>>)>,
}

/// Reads a target or measured file.
pub fn read_samples(path: &Path, single_leg: LegId) -> Result<Samples, Error> {
    let input = Input::open(path)?;
    let name = input.name.clone();
    let mut lines = input.reader.lines();
    let mut n = 0usize;
    let io = |source| Error::Read {
        input: name.clone(),
        source,
    };
    let header = loop {
        let Some(line) = lines.next() else {
            return Err(Error::Empty {
                input: name.clone(),
                expected: "naming the angle columns",
            });
        };
        n += 1;
        let line = line.map_err(io)?;
        let t = line.trim();
        if !(t.is_empty() || t.starts_with('#')) {
            break t.to_owned();
        }
    };
    let cols: Vec<&str> = header.split(',').map(str::trim).collect();
    let find = |c: &str| cols.iter().position(|x| x.eq_ignore_ascii_case(c));
    let joints = ["abduction", "hip", "knee"];
    let (legs, idx): (Vec<LegId>, Vec<[usize; 3]>) = if find("FL_abduction_rad").is_some() {
        let mut idx = Vec::new();
        for l in LegId::ALL {
            let mut j3 = [0usize; 3];
            for (k, j) in joints.iter().enumerate() {
                j3[k] = find(&format!("{l}_{j}_rad")).ok_or_else(|| Error::MissingColumn {
                    input: name.clone(),
                    line: n,
                    column: format!("{l}_{j}_rad"),
                    format: "the 12 angle columns, as it has FL_abduction_rad",
                })?;
            }
            idx.push(j3);
        }
        (LegId::ALL.to_vec(), idx)
    } else {
        let mut j3 = [0usize; 3];
        for (k, j) in joints.iter().enumerate() {
            j3[k] = find(&format!("{j}_rad")).ok_or_else(|| Error::MissingColumn {
                input: name.clone(),
                line: n,
                column: format!("{j}_rad"),
                format: "abduction_rad,hip_rad,knee_rad or the 12 FL_abduction_rad … RR_knee_rad \
                         columns",
            })?;
        }
        (vec![single_leg], vec![j3])
    };
    let status = find("status");
    let mut rows = Vec::new();
    for line in lines {
        n += 1;
        let line = line.map_err(io)?;
        let t = line.trim();
        if t.is_empty() || t.starts_with('#') {
            continue;
        }
        let f: Vec<&str> = t.split(',').map(str::trim).collect();
        if let Some(s) = status {
            if f.get(s).copied() != Some("ok") {
                rows.push((n, None));
                continue;
            }
        }
        let mut angles = Vec::with_capacity(legs.len());
        for j3 in &idx {
            let mut v = [0.0f32; 3];
            for (slot, &i) in v.iter_mut().zip(j3) {
                let text = f.get(i).copied().unwrap_or("");
                *slot = text
                    .parse::<f32>()
                    .ok()
                    .filter(|x| x.is_finite())
                    .ok_or_else(|| Error::Row {
                        input: name.clone(),
                        line: n,
                        error: RowError::BadFinite {
                            field: i + 1,
                            text: text.to_owned(),
                        },
                    })?;
            }
            angles.push(JointAngles::from_array(v));
        }
        rows.push((n, Some(angles)));
    }
    Ok(Samples { legs, rows })
}
