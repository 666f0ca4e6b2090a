//! Figures, drawn with `plotters` to SVG or PNG (chosen by the file extension):
//!
//! - [`joint_angles`]: the twelve joint angles over time, one panel per joint with the four
//!   legs (seed 001 Fig. 4–6);
//! - [`robot_views`]: the robot in top, side and front views at chosen instants (seed 000
//!   Fig. 6–7), from `kin_core::leg::joint_points`;
//! - [`target_vs_measured`]: target and measured angles per joint (seed 000 Fig. 9–11).
//!
//! Angles are plotted in degrees (figures are for people); lengths in metres.
//!
//! Text needs a TrueType font for its metrics (and, in PNG, its glyphs). Plotters is built with
//! its pure-Rust `ab_glyph` text backend, so nothing links to a system library; the font is read
//! at run time from `$QUADCTL_FONT` or the first of [`FONT_CANDIDATES`] that exists (Debian:
//! package `fonts-dejavu-core`).

use kin_core::body::Pose;
use kin_core::rotation;
use kin_core::{leg, BodyConfig, JointAngles, LegId, Robot, Vec3};
use plotters::coord::Shift;
use plotters::prelude::*;
use std::path::{Path, PathBuf};
use std::sync::OnceLock;

/// Font files tried in order when `$QUADCTL_FONT` is not set.
pub const FONT_CANDIDATES: &[&str] = &[
    "/usr/share/fonts/truetype/dejavu/DejaVuSans.ttf",
    "/usr/share/fonts/TTF/DejaVuSans.ttf",
    "/usr/share/fonts/dejavu/DejaVuSans.ttf",
    "/usr/share/fonts/truetype/liberation/LiberationSans-Regular.ttf",
    "/usr/share/fonts/liberation-sans/LiberationSans-Regular.ttf",
    "/usr/share/fonts/truetype/freefont/FreeSans.ttf",
    "/usr/share/fonts/noto/NotoSans-Regular.ttf",
    "/Library/Fonts/Arial.ttf",
    "C:\\Windows\\Fonts\\arial.ttf",
];

/// At most this many points per curve are drawn; longer series are decimated.
pub const MAX_POINTS: usize = 4000;

/// Why a figure could not be drawn.
#[derive(Debug, Clone, PartialEq, Eq, thiserror::Error)]
#[non_exhaustive]
pub enum Error {
    /// The file extension is neither `.svg` nor `.png`.
    #[error("plot file `{0}` must end in .svg or .png")]
    Format(String),
    /// The font file given by `QUADCTL_FONT` cannot be read.
    #[error("cannot read the font QUADCTL_FONT=`{}`", .0.display())]
    FontUnreadable(PathBuf),
    /// A font file that is not a usable TrueType font.
    #[error("`{}` is not a usable TrueType font", .0.display())]
    NotAFont(PathBuf),
    /// No font was found.
    #[error(
        "plots need a TrueType font and none was found (tried {}); install one (Debian: \
         apt-get install fonts-dejavu-core) or set QUADCTL_FONT=/path/to/font.ttf",
        FONT_CANDIDATES.join(", ")
    )]
    NoFont,
    /// The directory the plot would be written to does not exist (or is not a directory).
    #[error("cannot write the plot `{}`: directory `{}` does not exist", .path.display(), .dir.display())]
    NoDirectory {
        /// The plot file.
        path: PathBuf,
        /// Its directory.
        dir: PathBuf,
    },
    /// Drawing or writing the file failed: the file and the drawing backend's message (its
    /// error types are generic over the backend, so the message is what can be kept).
    #[error("cannot draw the plot `{}`: {message}", .path.display())]
    Draw {
        /// The plot file.
        path: PathBuf,
        /// The backend's message.
        message: String,
    },
    /// Nothing to draw.
    #[error("nothing to plot: {0}")]
    Empty(&'static str),
}

/// A backend error inside a drawing function, which does not know the file: the canvas adds it
/// ([`with_path`]).
fn backend_err<E: std::fmt::Display>(e: E) -> Error {
    Error::Draw {
        path: PathBuf::new(),
        message: e.to_string(),
    }
}

/// Names the file in an [`Error::Draw`] raised by a drawing function.
fn with_path(e: Error, path: &Path) -> Error {
    match e {
        Error::Draw { message, .. } => Error::Draw {
            path: path.to_owned(),
            message,
        },
        other => other,
    }
}

fn draw_err<E: std::fmt::Display>(path: &Path) -> impl Fn(E) -> Error + '_ {
    move |e| Error::Draw {
        path: path.to_owned(),
        message: e.to_string(),
    }
}

/// Registers the font once per process.
fn ensure_font() -> Result<(), Error> {
    static FONT: OnceLock<Result<(), Error>> = OnceLock::new();
    FONT.get_or_init(|| {
        let from_env = std::env::var_os("QUADCTL_FONT");
        let candidates: Vec<std::path::PathBuf> = match &from_env {
            Some(p) => vec![p.into()],
            None => FONT_CANDIDATES.iter().map(Into::into).collect(),
        };
        for path in &candidates {
            if let Ok(bytes) = std::fs::read(path) {
                let bytes: &'static [u8] = Box::leak(bytes.into_boxed_slice());
                return plotters::style::register_font("sans-serif", FontStyle::Normal, bytes)
                    .map_err(|_| Error::NotAFont(path.clone()));
            }
        }
        Err(match from_env {
            Some(p) => Error::FontUnreadable(p.into()),
            None => Error::NoFont,
        })
    })
    .clone()
}

enum Kind {
    Svg,
    Png,
}

/// Checks a plot file name before anything is computed or written: a `.svg` or `.png` name in
/// a directory that exists.
///
/// # Errors
/// [`Error::Format`], [`Error::NoDirectory`].
pub fn check_output(path: &Path) -> Result<(), Error> {
    kind(path).map(|_| ())
}

fn kind(path: &Path) -> Result<Kind, Error> {
    let dir = match path.parent() {
        Some(d) if !d.as_os_str().is_empty() => d,
        _ => Path::new("."),
    };
    if !dir.is_dir() {
        return Err(Error::NoDirectory {
            path: path.to_owned(),
            dir: dir.to_owned(),
        });
    }
    match path
        .extension()
        .and_then(|e| e.to_str())
        .map(str::to_ascii_lowercase)
        .as_deref()
    {
        Some("svg") => Ok(Kind::Svg),
        Some("png") => Ok(Kind::Png),
        _ => Err(Error::Format(path.display().to_string())),
    }
}

/// Draws with the generic function `$draw(&root, args…)` on an SVG or PNG canvas of `$size`
/// pixels at `$path`, chosen by the extension.
macro_rules! on_canvas {
    ($path:expr, $size:expr, $draw:ident ( $($arg:expr),* )) => {{
        let k = kind($path)?;
        ensure_font()?;
        match k {
            Kind::Svg => {
                let root = SVGBackend::new($path, $size).into_drawing_area();
                root.fill(&WHITE).map_err(draw_err($path))?;
                $draw(&root, $($arg),*).map_err(|e| with_path(e, $path))?;
                root.present().map_err(draw_err($path))
            }
            Kind::Png => {
                let root = BitMapBackend::new($path, $size).into_drawing_area();
                root.fill(&WHITE).map_err(draw_err($path))?;
                $draw(&root, $($arg),*).map_err(|e| with_path(e, $path))?;
                root.present().map_err(draw_err($path))
            }
        }
    }};
}

/// Colour of a leg in every figure.
pub fn leg_color(leg: LegId) -> RGBColor {
    match leg {
        LegId::FL => RGBColor(31, 119, 180),
        LegId::FR => RGBColor(214, 39, 40),
        LegId::RL => RGBColor(44, 160, 44),
        LegId::RR => RGBColor(148, 103, 189),
    }
}

/// Line width of a leg's curve in the joint-angle figure, px: widest for FL, narrowest for RR,
/// so that legs with the same curve (a sway's left and right legs) show as nested stripes,
/// every colour visible, where equal widths would hide all but the last drawn.
fn leg_width(leg: LegId) -> u32 {
    match leg {
        LegId::FL => 8,
        LegId::FR => 6,
        LegId::RL => 4,
        LegId::RR => 2,
    }
}

/// A tick label with `decimals` decimals, never `-0.0` (a value that rounds to zero is `0`).
fn tick_label(v: f64, decimals: usize) -> String {
    let s = format!("{v:.decimals$}");
    match s.strip_prefix('-') {
        Some(rest) if rest.chars().all(|c| c == '0' || c == '.') => rest.to_owned(),
        _ => s,
    }
}

/// The legs' legend in a strip of its own above the panels (so that it covers no data): a
/// swatch of each leg's colour (and, with `widths`, its line width) and its name, and the
/// body in black when `body` is set.
fn draw_leg_legend<DB: DrawingBackend>(
    strip: &DrawingArea<DB, Shift>,
    widths: bool,
    body: bool,
) -> Result<(), Error> {
    let (w, h) = strip.dim_in_pixel();
    let y = h as i32 / 2;
    let item = 110;
    let count = 4 + i32::from(body);
    let mut x = (w as i32 - count * item) / 2;
    let font = ("sans-serif", 15).into_font();
    let mut entry = |name: &str, color: RGBColor, width: u32| -> Result<(), Error> {
        strip
            .draw(&PathElement::new(
                vec![(x, y), (x + 36, y)],
                color.stroke_width(width),
            ))
            .map_err(backend_err)?;
        strip
            .draw(&Text::new(
                name.to_owned(),
                (x + 44, y - 8),
                font.clone().color(&BLACK),
            ))
            .map_err(backend_err)?;
        x += item;
        Ok(())
    };
    for leg in LegId::ALL {
        entry(
            leg.name(),
            leg_color(leg),
            if widths { leg_width(leg) } else { 3 },
        )?;
    }
    if body {
        entry("body", BLACK, 3)?;
    }
    Ok(())
}

/// Joint angles over time: `t_s[k]` and the twelve angles (rad, order FL, FR, RL, RR ×
/// abduction, hip, knee) of sample `k`; `None` where the sample was unreachable.
#[derive(Debug, Clone, Default, PartialEq)]
pub struct JointSeries {
    /// Times, s.
    pub t_s: Vec<f64>,
    /// Angles, rad.
    pub angles: Vec<Option<[f32; 12]>>,
}

impl JointSeries {
    /// Appends a sample.
    pub fn push(&mut self, t_s: f64, angles: Option<[f32; 12]>) {
        self.t_s.push(t_s);
        self.angles.push(angles);
    }
}

/// Keeps the elements at even indices.
fn every_other<T>(v: &mut Vec<T>) {
    let mut i = 0usize;
    v.retain(|_| {
        i += 1;
        i % 2 == 1
    });
}

/// Builds a [`JointSeries`] of at most `2·MAX_POINTS` samples from a stream of unknown length:
/// keeps every `stride`-th sample and doubles the stride (dropping every other kept sample)
/// whenever the series fills up.
#[derive(Debug, Clone, Default, PartialEq)]
pub struct Decimator {
    series: JointSeries,
    stride: u64,
    seen: u64,
    last: Option<(f64, Option<[f32; 12]>)>,
}

impl Decimator {
    /// An empty decimator.
    pub fn new() -> Decimator {
        Decimator {
            stride: 1,
            ..Decimator::default()
        }
    }

    /// Offers one sample.
    pub fn push(&mut self, t_s: f64, angles: Option<[f32; 12]>) {
        if self.seen.is_multiple_of(self.stride) {
            self.series.push(t_s, angles);
            if self.series.t_s.len() >= 2 * MAX_POINTS {
                every_other(&mut self.series.t_s);
                every_other(&mut self.series.angles);
                self.stride *= 2;
            }
            self.last = None;
        } else {
            self.last = Some((t_s, angles));
        }
        self.seen += 1;
    }

    /// The series, ending with the last sample offered.
    pub fn finish(mut self) -> JointSeries {
        if let Some((t, a)) = self.last {
            self.series.push(t, a);
        }
        self.series
    }
}

/// Every `step`-th index so that at most [`MAX_POINTS`] remain, plus the last.
fn decimated(n: usize) -> Vec<usize> {
    let step = n.div_ceil(MAX_POINTS).max(1);
    let mut idx: Vec<usize> = (0..n).step_by(step).collect();
    if n > 0 && idx.last() != Some(&(n - 1)) {
        idx.push(n - 1);
    }
    idx
}

/// Splits `(x, y)` points into runs of finite values (a gap where a sample is missing).
fn runs(points: impl Iterator<Item = (f64, Option<f64>)>) -> Vec<Vec<(f64, f64)>> {
    let mut out: Vec<Vec<(f64, f64)>> = vec![Vec::new()];
    for (x, y) in points {
        match y {
            Some(y) if y.is_finite() => out.last_mut().expect("non-empty").push((x, y)),
            _ => {
                if !out.last().expect("non-empty").is_empty() {
                    out.push(Vec::new());
                }
            }
        }
    }
    out.retain(|r| !r.is_empty());
    out
}

fn range(values: impl Iterator<Item = f64>) -> (f64, f64) {
    let (mut lo, mut hi) = (f64::INFINITY, f64::NEG_INFINITY);
    for v in values.filter(|v| v.is_finite()) {
        lo = lo.min(v);
        hi = hi.max(v);
    }
    if !lo.is_finite() {
        return (-1.0, 1.0);
    }
    let pad = ((hi - lo) * 0.08).max(0.5);
    (lo - pad, hi + pad)
}

const JOINT_NAMES: [&str; 3] = ["abduction", "hip", "knee"];

/// The joint angles of a motion over time, one panel per joint (degrees), four legs each.
pub fn joint_angles(path: &Path, title: &str, series: &JointSeries) -> Result<(), Error> {
    if series.t_s.is_empty() {
        return Err(Error::Empty("no samples"));
    }
    let idx = decimated(series.t_s.len());
    on_canvas!(path, (1000, 900), draw_joints(title, series, &idx))
}

fn draw_joints<DB: DrawingBackend>(
    root: &DrawingArea<DB, Shift>,
    title: &str,
    series: &JointSeries,
    idx: &[usize],
) -> Result<(), Error> {
    {
        let root = root
            .titled(title, ("sans-serif", 22))
            .map_err(backend_err)?;
        let (strip, root) = root.split_vertically(26);
        draw_leg_legend(&strip, true, false)?;
        let panels = root.split_evenly((3, 1));
        let (t0, t1) = (series.t_s[0], *series.t_s.last().expect("non-empty"));
        let t1 = if t1 > t0 { t1 } else { t0 + 1.0 };
        for (j, panel) in panels.iter().enumerate() {
            let values = || {
                idx.iter().flat_map(move |&k| {
                    LegId::ALL.map(move |l| {
                        series.angles[k].map(|a| f64::from(a[3 * l.index() + j]).to_degrees())
                    })
                })
            };
            let (lo, hi) = range(values().flatten());
            let mut chart = ChartBuilder::on(panel)
                .margin(8)
                .x_label_area_size(32)
                .y_label_area_size(56)
                .caption(format!("{} angle", JOINT_NAMES[j]), ("sans-serif", 16))
                .build_cartesian_2d(t0..t1, lo..hi)
                .map_err(backend_err)?;
            chart
                .configure_mesh()
                .x_desc("t (s)")
                .y_desc("deg")
                .x_label_formatter(&|v| tick_label(*v, 1))
                .y_label_formatter(&|v| tick_label(*v, 1))
                .draw()
                .map_err(backend_err)?;
            for leg in LegId::ALL {
                let style = leg_color(leg).stroke_width(leg_width(leg));
                let pts = idx.iter().map(|&k| {
                    (
                        series.t_s[k],
                        series.angles[k].map(|a| f64::from(a[3 * leg.index() + j]).to_degrees()),
                    )
                });
                for run in runs(pts) {
                    chart
                        .draw_series(LineSeries::new(run, style))
                        .map_err(backend_err)?;
                }
            }
        }
        Ok(())
    }
}

/// The robot at one instant, for [`robot_views`].
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Snapshot {
    /// Time, s.
    pub t_s: f64,
    /// Body pose in the world frame.
    pub pose: Pose,
    /// Joint angles, order FL, FR, RL, RR.
    pub angles: [JointAngles; 4],
}

/// Points of the drawing in the world frame: body outline and each leg's chain.
struct Drawing {
    body: Vec<Vec3>,
    legs: [Vec<Vec3>; 4],
}

fn drawing(robot: &Robot, config: &BodyConfig, s: &Snapshot) -> Drawing {
    let r = rotation::matrix::<kin_core::DefaultMath>(
        config.order,
        s.pose.roll_rad,
        s.pose.pitch_rad,
        s.pose.yaw_rad,
    );
    let to_world =
        |p_body: Vec3| r.mul_vec(p_body - config.pivot_m) + config.pivot_m + s.pose.translation();
    let mut body: Vec<Vec3> = [LegId::FL, LegId::FR, LegId::RR, LegId::RL]
        .iter()
        .map(|&l| to_world(robot.hip_in_body(l)))
        .collect();
    body.push(body[0]);
    let legs = LegId::ALL.map(|l| {
        let p = leg::joint_points(&robot.leg, l, s.angles[l.index()]);
        let hip = robot.hip_in_body(l);
        [p.hip_mount, p.hip_joint, p.knee, p.foot]
            .iter()
            .map(|&q| to_world(hip + q))
            .collect()
    });
    Drawing { body, legs }
}

/// The robot in top (x–y), side (x–z) and front (y–z) views, one row per snapshot, on a common
/// equal-aspect scale. The ground line is drawn at the lowest foot.
pub fn robot_views(
    path: &Path,
    title: &str,
    robot: &Robot,
    config: &BodyConfig,
    snapshots: &[Snapshot],
) -> Result<(), Error> {
    if snapshots.is_empty() {
        return Err(Error::Empty("no instant to draw"));
    }
    let drawings: Vec<Drawing> = snapshots
        .iter()
        .map(|s| drawing(robot, config, s))
        .collect();
    let all = || {
        drawings
            .iter()
            .flat_map(|d| d.body.iter().chain(d.legs.iter().flatten()).copied())
    };
    let span = |f: fn(&Vec3) -> f32| {
        let (lo, hi) = all().fold((f32::INFINITY, f32::NEG_INFINITY), |(lo, hi), p| {
            (lo.min(f(&p)), hi.max(f(&p)))
        });
        (f64::from(lo), f64::from(hi))
    };
    let (xs, ys, zs) = (span(|p| p.x), span(|p| p.y), span(|p| p.z));
    let half = [xs, ys, zs]
        .iter()
        .map(|(lo, hi)| hi - lo)
        .fold(0.0f64, f64::max)
        * 0.5
        * 1.1
        + 0.02;
    let ground = zs.0;
    let size = (1200u32, 400 * snapshots.len() as u32 + 66);
    let frame = ViewFrame {
        ranges: [xs, ys, zs],
        half,
        ground,
    };
    on_canvas!(path, size, draw_views(title, snapshots, &drawings, &frame))
}

/// Common scale of the views.
struct ViewFrame {
    ranges: [(f64, f64); 3],
    half: f64,
    ground: f64,
}

fn draw_views<DB: DrawingBackend>(
    root: &DrawingArea<DB, Shift>,
    title: &str,
    snapshots: &[Snapshot],
    drawings: &[Drawing],
    frame: &ViewFrame,
) -> Result<(), Error> {
    let views: [(&str, usize, usize); 3] = [
        ("top (x forward, y left)", 0, 1),
        ("side (x forward, z up)", 0, 2),
        ("front (y left, z up)", 1, 2),
    ];
    let half = frame.half;
    let centred = |(lo, hi): (f64, f64)| {
        let c = 0.5 * (lo + hi);
        (c - half)..(c + half)
    };
    let ground = frame.ground;
    let rows = snapshots.len();
    {
        let root = root
            .titled(title, ("sans-serif", 22))
            .map_err(backend_err)?;
        let (strip, root) = root.split_vertically(26);
        draw_leg_legend(&strip, false, true)?;
        let cells = root.split_evenly((rows, 3));
        for (row, (snap, d)) in snapshots.iter().zip(drawings).enumerate() {
            for (col, (name, a, b)) in views.iter().enumerate() {
                let axis = |p: &Vec3| f64::from(p.to_array()[*a]);
                let ord = |p: &Vec3| f64::from(p.to_array()[*b]);
                let ranges = frame.ranges;
                let mut chart = ChartBuilder::on(&cells[row * 3 + col])
                    .margin(6)
                    .x_label_area_size(28)
                    .y_label_area_size(44)
                    .caption(format!("t = {:.2} s, {name}", snap.t_s), ("sans-serif", 14))
                    .build_cartesian_2d(centred(ranges[*a]), centred(ranges[*b]))
                    .map_err(backend_err)?;
                chart
                    .configure_mesh()
                    .x_desc("m")
                    .light_line_style(WHITE)
                    .x_label_formatter(&|v| tick_label(*v, 1))
                    .y_label_formatter(&|v| tick_label(*v, 1))
                    .draw()
                    .map_err(backend_err)?;
                if *b == 2 {
                    let x = centred(ranges[*a]);
                    chart
                        .draw_series(LineSeries::new(
                            [(x.start, ground), (x.end, ground)],
                            BLACK.mix(0.4).stroke_width(1),
                        ))
                        .map_err(backend_err)?;
                }
                chart
                    .draw_series(LineSeries::new(
                        d.body.iter().map(|p| (axis(p), ord(p))),
                        BLACK.stroke_width(3),
                    ))
                    .map_err(backend_err)?;
                for leg in LegId::ALL {
                    let c = leg_color(leg);
                    let pts: Vec<(f64, f64)> = d.legs[leg.index()]
                        .iter()
                        .map(|p| (axis(p), ord(p)))
                        .collect();
                    chart
                        .draw_series(LineSeries::new(pts.clone(), c.stroke_width(3)))
                        .map_err(backend_err)?;
                    chart
                        .draw_series(pts.iter().map(|&p| Circle::new(p, 3, c.filled())))
                        .map_err(backend_err)?;
                }
            }
        }
        Ok(())
    }
}

/// Target and measured angles (rad in, degrees drawn) per joint over the sample index, seed
/// 000 Fig. 9–11. `labels` names the three joints.
pub fn target_vs_measured(
    path: &Path,
    title: &str,
    labels: [&str; 3],
    target: &[[f32; 3]],
    measured: &[[f32; 3]],
) -> Result<(), Error> {
    if target.is_empty() {
        return Err(Error::Empty("no samples"));
    }
    let idx = decimated(target.len());
    on_canvas!(
        path,
        (1000, 900),
        draw_accuracy(title, labels, target, measured, &idx)
    )
}

fn draw_accuracy<DB: DrawingBackend>(
    root: &DrawingArea<DB, Shift>,
    title: &str,
    labels: [&str; 3],
    target: &[[f32; 3]],
    measured: &[[f32; 3]],
    idx: &[usize],
) -> Result<(), Error> {
    {
        let root = root
            .titled(title, ("sans-serif", 22))
            .map_err(backend_err)?;
        let panels = root.split_evenly((3, 1));
        for (j, panel) in panels.iter().enumerate() {
            let deg = |v: f32| f64::from(v).to_degrees();
            let (lo, hi) = range(
                idx.iter()
                    .flat_map(|&k| [deg(target[k][j]), deg(measured[k][j])]),
            );
            let n = target.len() as f64;
            let mut chart = ChartBuilder::on(panel)
                .margin(8)
                .x_label_area_size(32)
                .y_label_area_size(56)
                .caption(labels[j], ("sans-serif", 16))
                .build_cartesian_2d(0.0..(n - 1.0).max(1.0), lo..hi)
                .map_err(backend_err)?;
            chart
                .configure_mesh()
                .x_desc("sample")
                .y_desc("deg")
                .x_label_formatter(&|v| tick_label(*v, 0))
                .y_label_formatter(&|v| tick_label(*v, 1))
                .draw()
                .map_err(backend_err)?;
            for (name, data, color) in [
                ("target", target, RGBColor(31, 119, 180)),
                ("measured", measured, RGBColor(214, 39, 40)),
            ] {
                let pts: Vec<(f64, f64)> =
                    idx.iter().map(|&k| (k as f64, deg(data[k][j]))).collect();
                chart
                    .draw_series(LineSeries::new(pts.clone(), color.stroke_width(2)))
                    .map_err(backend_err)?
                    .label(name)
                    .legend(move |(x, y)| {
                        PathElement::new(vec![(x, y), (x + 18, y)], color.stroke_width(2))
                    });
                chart
                    .draw_series(pts.iter().map(|&p| Circle::new(p, 2, color.filled())))
                    .map_err(backend_err)?;
            }
            chart
                .configure_series_labels()
                .background_style(WHITE.mix(0.8))
                .border_style(BLACK)
                .draw()
                .map_err(backend_err)?;
        }
        Ok(())
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn decimation_keeps_at_most_max_points_plus_the_last() {
        assert_eq!(decimated(3), vec![0, 1, 2]);
        let d = decimated(3_600_001);
        assert!(d.len() <= MAX_POINTS + 1);
        assert_eq!(*d.last().unwrap(), 3_600_000);
    }

    #[test]
    fn the_decimator_bounds_the_series_and_keeps_the_ends() {
        let mut d = Decimator::new();
        for k in 0..1_000_003u32 {
            d.push(f64::from(k), None);
        }
        let s = d.finish();
        assert!(s.t_s.len() <= 2 * MAX_POINTS + 1, "{}", s.t_s.len());
        assert!(s.t_s.len() >= MAX_POINTS);
        assert_eq!(s.t_s[0], 0.0);
        assert_eq!(*s.t_s.last().unwrap(), 1_000_002.0);
        assert!(s.t_s.windows(2).all(|w| w[0] < w[1]));
    }

    #[test]
    fn runs_break_at_missing_samples() {
        let r = runs(
            [
                (0.0, Some(1.0)),
                (1.0, None),
                (2.0, Some(2.0)),
                (3.0, Some(3.0)),
            ]
            .into_iter(),
        );
        assert_eq!(r, vec![vec![(0.0, 1.0)], vec![(2.0, 2.0), (3.0, 3.0)]]);
    }

    #[test]
    fn tick_labels_never_read_minus_zero() {
        assert_eq!(tick_label(-0.0, 1), "0.0");
        assert_eq!(tick_label(-0.04, 1), "0.0");
        assert_eq!(tick_label(-1e-17, 1), "0.0");
        assert_eq!(tick_label(-0.05001, 1), "-0.1");
        assert_eq!(tick_label(-0.4, 0), "0");
        assert_eq!(tick_label(12.25, 1), "12.2");
        assert_eq!(tick_label(-3.0, 1), "-3.0");
    }

    #[test]
    fn each_leg_has_its_own_width_so_equal_curves_stay_visible() {
        let mut w: Vec<u32> = LegId::ALL.iter().map(|&l| leg_width(l)).collect();
        w.dedup();
        assert_eq!(w.len(), 4);
        assert!(
            w.windows(2).all(|p| p[0] > p[1]),
            "drawn widest first: {w:?}"
        );
    }

    #[test]
    fn unknown_extensions_are_refused() {
        let e = joint_angles(
            Path::new("x.pdf"),
            "t",
            &JointSeries {
                t_s: vec![0.0],
                angles: vec![None],
            },
        );
        assert!(matches!(e, Err(Error::Format(_))));
    }
}
