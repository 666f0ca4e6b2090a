//! Foot paths: one closed loop per gait cycle, phase in `[0, 1)` → foot offset (m).
//!
//! Every path here shares one layout, with duty factor `d` (the stance fraction of the cycle)
//! and stride length `L`:
//!
//! - **swing**, phase `[0, 1 − d)`: from lift-off at `(−L/2, 0, 0)` through the air to
//!   touch-down at `(+L/2, 0, 0)`; the shape differs per path;
//! - **stance**, phase `[1 − d, 1)`: back along the ground from `(+L/2, 0, 0)` to `(−L/2, 0, 0)`
//!   at constant speed `L/d` per cycle (the speed that keeps a foot still under a body moving
//!   forward at `L/(d·T)`).
//!
//! Offsets are relative to the neutral foothold, in hip-frame axes (x along the stride, z up,
//! y = 0). All paths are C0 everywhere. C1 (same velocity on both sides) at the two
//! swing/stance joins holds only where the shape allows it, reported by
//! [`FootPath::c1_at_joins`]:
//!
//! | path | C1 at joins | why |
//! |---|---|---|
//! | [`Rectangle`] | no | corners by construction (seed 000 Fig. 8) |
//! | [`Semicircle`], [`Ellipse`] | no | the tangent is vertical where the arc meets the ground |
//! | [`Cycloid`] | no (z yes) | zero velocity at the ground, stance moves at `L/d` |
//! | [`Bezier`] | yes | end control points chosen to match the stance velocity |

use super::{finite, non_negative, Contact, Error, Expected, Param, Phase};
use crate::math::Math;
use crate::vec::Vec3;
use core::f32::consts::PI;

/// A closed foot path over one gait cycle.
pub trait FootPath {
    /// Foot offset from the neutral foothold at `phase` (m, x along the stride, z up), on math
    /// backend `M` (`path.offset::<DefaultMath>(phase)` for the default,
    /// [`DefaultMath`](crate::math::DefaultMath)).
    fn offset<M: Math>(&self, phase: Phase) -> Vec3;

    /// Whether the foot is in stance or swing at `phase`.
    fn contact(&self, phase: Phase) -> Contact {
        if phase.value() < 1.0 - self.duty_factor() {
            Contact::Swing
        } else {
            Contact::Stance
        }
    }

    /// Stance fraction of the cycle, in `(0, 1)`.
    fn duty_factor(&self) -> f32;

    /// True when the velocity (d offset / d phase) is continuous at both swing/stance joins.
    fn c1_at_joins(&self) -> bool;
}

/// Stride shared by the paths: length, apex height and duty factor, validated.
#[derive(Debug, Clone, Copy, PartialEq)]
#[cfg_attr(feature = "serde", derive(serde::Serialize, serde::Deserialize))]
pub struct Stride {
    length_m: f32,
    height_m: f32,
    duty_factor: f32,
}

impl Stride {
    /// A stride of `length_m` (≥ 0), apex `height_m` (≥ 0) above the ground and stance fraction
    /// `duty_factor` ∈ (0, 1).
    pub fn new(length_m: f32, height_m: f32, duty_factor: f32) -> Result<Stride, Error> {
        non_negative(length_m, Param::StrideM)?;
        non_negative(height_m, Param::StepHeightM)?;
        let d = finite(duty_factor, Param::DutyFactor)?;
        if !(d > 0.0 && d < 1.0) {
            return Err(Error::OutOfRange {
                parameter: Param::DutyFactor,
                expected: Expected::OpenUnitInterval,
            });
        }
        Ok(Stride {
            length_m,
            height_m,
            duty_factor,
        })
    }

    /// A stride from values the caller has already validated.
    pub(crate) const fn unchecked(length_m: f32, height_m: f32, duty_factor: f32) -> Stride {
        Stride {
            length_m,
            height_m,
            duty_factor,
        }
    }

    /// Stride length, m.
    pub const fn length_m(&self) -> f32 {
        self.length_m
    }

    /// Apex height above the ground, m.
    pub const fn height_m(&self) -> f32 {
        self.height_m
    }

    /// Stance fraction of the cycle.
    pub const fn duty_factor(&self) -> f32 {
        self.duty_factor
    }

    /// Where in the cycle `phase` is: swing progress `s ∈ [0, 1)` or stance progress.
    #[inline]
    fn split(&self, phase: Phase) -> Part {
        let swing = 1.0 - self.duty_factor;
        let p = phase.value();
        if p < swing {
            Part::Swing(p / swing)
        } else {
            Part::Stance((p - swing) / self.duty_factor)
        }
    }

    /// The stance offset at stance progress `u ∈ [0, 1)`.
    #[inline]
    fn stance(&self, u: f32) -> Vec3 {
        Vec3::new(self.length_m * (0.5 - u), 0.0, 0.0)
    }

    /// The offset at `phase`: the stance, or the swing shape `swing` at swing progress `s`.
    fn offset(&self, phase: Phase, swing: impl FnOnce(f32) -> Vec3) -> Vec3 {
        match self.split(phase) {
            Part::Stance(u) => self.stance(u),
            Part::Swing(s) => swing(s),
        }
    }
}

/// Half-ellipse swing at progress `s`: `(−a·cos πs, 0, b·sin πs)` (the semicircle is `a = b`).
fn half_ellipse<M: Math>(a: f32, b: f32, s: f32) -> Vec3 {
    let (sn, cs) = M::sin_cos(PI * s);
    Vec3::new(-(a * cs), 0.0, b * sn)
}

enum Part {
    Swing(f32),
    Stance(f32),
}

/// Seed 000's rectangle (§3.2, Fig. 8): lift straight up, stride forward, lower straight down,
/// return along the ground. The swing's three sides are run at one constant speed.
#[derive(Debug, Clone, Copy, PartialEq)]
#[cfg_attr(feature = "serde", derive(serde::Serialize, serde::Deserialize))]
pub struct Rectangle {
    stride: Stride,
}

impl Rectangle {
    /// A rectangle of the given stride (its height is the lift).
    pub const fn new(stride: Stride) -> Rectangle {
        Rectangle { stride }
    }

    /// Seed 000 Fig. 8: foot height from −0.2 to −0.15 (its plot's x axis, the hip-to-foot
    /// direction) and a travel of 0.1 (its y axis, forward): lift 0.05 m, stride 0.1 m. Duty
    /// factor 1/3, the return's share of the perimeter, so that the foot runs the whole loop at
    /// one speed as in the paper's closed loop. Use with a stance height of 0.2 m.
    pub fn seed000() -> Rectangle {
        Rectangle {
            stride: Stride {
                length_m: 0.1,
                height_m: 0.05,
                duty_factor: 1.0 / 3.0,
            },
        }
    }

    /// The stance height seed 000 Fig. 8 implies (foot 0.2 m below the hip), m.
    pub const SEED000_STANCE_HEIGHT_M: f32 = 0.2;

    /// The stride.
    pub const fn stride(&self) -> Stride {
        self.stride
    }
}

impl Rectangle {
    fn swing(&self, s: f32) -> Vec3 {
        let (l, h) = (self.stride.length_m, self.stride.height_m);
        let total = 2.0 * h + l;
        let a = s * total;
        if a < h {
            Vec3::new(-0.5 * l, 0.0, a)
        } else if a < h + l {
            Vec3::new(-0.5 * l + (a - h), 0.0, h)
        } else {
            let down = a - h - l;
            Vec3::new(0.5 * l, 0.0, if down < h { h - down } else { 0.0 })
        }
    }
}

impl FootPath for Rectangle {
    fn offset<M: Math>(&self, phase: Phase) -> Vec3 {
        self.stride.offset(phase, |s| self.swing(s))
    }

    fn duty_factor(&self) -> f32 {
        self.stride.duty_factor
    }

    fn c1_at_joins(&self) -> bool {
        false
    }
}

/// Semicircle swing of radius `L/2` (apex height `L/2`), run at constant angular speed.
#[derive(Debug, Clone, Copy, PartialEq)]
#[cfg_attr(feature = "serde", derive(serde::Serialize, serde::Deserialize))]
pub struct Semicircle {
    stride: Stride,
}

impl Semicircle {
    /// A semicircle over a stride of `stride_m` (≥ 0) with stance fraction `duty_factor`.
    pub fn new(stride_m: f32, duty_factor: f32) -> Result<Semicircle, Error> {
        non_negative(stride_m, Param::StrideM)?;
        Ok(Semicircle {
            stride: Stride::new(stride_m, 0.5 * stride_m, duty_factor)?,
        })
    }

    /// The stride (its height is `L/2`).
    pub const fn stride(&self) -> Stride {
        self.stride
    }
}

impl Semicircle {
    fn swing<M: Math>(&self, s: f32) -> Vec3 {
        let r = 0.5 * self.stride.length_m;
        half_ellipse::<M>(r, r, s)
    }
}

impl FootPath for Semicircle {
    fn offset<M: Math>(&self, phase: Phase) -> Vec3 {
        self.stride.offset(phase, |s| self.swing::<M>(s))
    }

    fn duty_factor(&self) -> f32 {
        self.stride.duty_factor
    }

    fn c1_at_joins(&self) -> bool {
        false
    }
}

/// Half-ellipse swing with semi-axes `L/2` (along the stride) and `h` (up).
#[derive(Debug, Clone, Copy, PartialEq)]
#[cfg_attr(feature = "serde", derive(serde::Serialize, serde::Deserialize))]
pub struct Ellipse {
    stride: Stride,
}

impl Ellipse {
    /// A half-ellipse over the given stride.
    pub const fn new(stride: Stride) -> Ellipse {
        Ellipse { stride }
    }

    /// The stride.
    pub const fn stride(&self) -> Stride {
        self.stride
    }
}

impl Ellipse {
    fn swing<M: Math>(&self, s: f32) -> Vec3 {
        half_ellipse::<M>(0.5 * self.stride.length_m, self.stride.height_m, s)
    }
}

impl FootPath for Ellipse {
    fn offset<M: Math>(&self, phase: Phase) -> Vec3 {
        self.stride.offset(phase, |s| self.swing::<M>(s))
    }

    fn duty_factor(&self) -> f32 {
        self.stride.duty_factor
    }

    fn c1_at_joins(&self) -> bool {
        false
    }
}

/// Cycloid swing: `x = L·(s − sin(2πs)/2π) − L/2`, `z = h·(1 − cos 2πs)/2` for swing progress
/// `s ∈ [0, 1)`. Lift-off and touch-down with zero velocity (soft landing).
#[derive(Debug, Clone, Copy, PartialEq)]
#[cfg_attr(feature = "serde", derive(serde::Serialize, serde::Deserialize))]
pub struct Cycloid {
    stride: Stride,
}

impl Cycloid {
    /// A cycloid over the given stride.
    pub const fn new(stride: Stride) -> Cycloid {
        Cycloid { stride }
    }

    /// The stride.
    pub const fn stride(&self) -> Stride {
        self.stride
    }
}

impl Cycloid {
    fn swing<M: Math>(&self, s: f32) -> Vec3 {
        let (sn, cs) = M::sin_cos(2.0 * PI * s);
        let l = self.stride.length_m;
        Vec3::new(
            l * (s - sn / (2.0 * PI)) - 0.5 * l,
            0.0,
            0.5 * self.stride.height_m * (1.0 - cs),
        )
    }
}

impl FootPath for Cycloid {
    fn offset<M: Math>(&self, phase: Phase) -> Vec3 {
        self.stride.offset(phase, |s| self.swing::<M>(s))
    }

    fn duty_factor(&self) -> f32 {
        self.stride.duty_factor
    }

    fn c1_at_joins(&self) -> bool {
        false
    }
}

/// Quintic Bézier swing, C1 with the stance at both joins.
///
/// Control points (x; z), with swing fraction `σ = 1 − d` and `c = σ·L/(5·d)`:
/// `x = [−L/2, −L/2 − c, −L/2 − c, L/2 + c, L/2 + c, L/2]`, `z = [0, 0, 1.6·h, 1.6·h, 0, 0]`.
/// The end tangents `5·(P1 − P0)` and `5·(P5 − P4)` divided by `σ` equal the stance velocity
/// `(−L/d, 0, 0)` per cycle, and `z(s) = 16·h·s²(1−s)²` peaks at exactly `h` at mid-swing. The
/// foot keeps moving back for a moment after lift-off and overshoots the touch-down point a
/// little before landing (by less than `c`), like the swing of the MIT Cheetah.
#[derive(Debug, Clone, Copy, PartialEq)]
#[cfg_attr(feature = "serde", derive(serde::Serialize, serde::Deserialize))]
pub struct Bezier {
    stride: Stride,
}

impl Bezier {
    /// A Bézier swing over the given stride.
    pub const fn new(stride: Stride) -> Bezier {
        Bezier { stride }
    }

    /// The stride.
    pub const fn stride(&self) -> Stride {
        self.stride
    }

    /// The six control points `(x, z)`, m.
    pub fn control_points(&self) -> [(f32, f32); 6] {
        let (l, h, d) = (
            self.stride.length_m,
            self.stride.height_m,
            self.stride.duty_factor,
        );
        let c = (1.0 - d) * l / (5.0 * d);
        let a = 1.6 * h;
        [
            (-0.5 * l, 0.0),
            (-0.5 * l - c, 0.0),
            (-0.5 * l - c, a),
            (0.5 * l + c, a),
            (0.5 * l + c, 0.0),
            (0.5 * l, 0.0),
        ]
    }
}

impl Bezier {
    fn swing(&self, s: f32) -> Vec3 {
        let r = 1.0 - s;
        let (s2, r2) = (s * s, r * r);
        let b = [
            r2 * r2 * r,
            5.0 * s * r2 * r2,
            10.0 * s2 * r2 * r,
            10.0 * s2 * s * r2,
            5.0 * s2 * s2 * r,
            s2 * s2 * s,
        ];
        let p = self.control_points();
        let (mut x, mut z) = (0.0, 0.0);
        for (w, (px, pz)) in b.iter().zip(p) {
            x += w * px;
            z += w * pz;
        }
        Vec3::new(x, 0.0, z)
    }
}

impl FootPath for Bezier {
    fn offset<M: Math>(&self, phase: Phase) -> Vec3 {
        self.stride.offset(phase, |s| self.swing(s))
    }

    fn duty_factor(&self) -> f32 {
        self.stride.duty_factor
    }

    fn c1_at_joins(&self) -> bool {
        true
    }
}

/// The shape of a swing, for choosing a path at run time.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash, Default)]
#[cfg_attr(feature = "serde", derive(serde::Serialize, serde::Deserialize))]
#[cfg_attr(feature = "serde", serde(rename_all = "snake_case"))]
pub enum PathKind {
    /// [`Rectangle`].
    Rectangle,
    /// [`Semicircle`]: its apex is `L/2`; the height parameter is not used.
    Semicircle,
    /// [`Ellipse`].
    Ellipse,
    /// [`Cycloid`].
    Cycloid,
    /// [`Bezier`] (the default: the only shape that is C1 at the joins).
    #[default]
    Bezier,
}

impl PathKind {
    /// All kinds.
    pub const ALL: [PathKind; 5] = [
        PathKind::Rectangle,
        PathKind::Semicircle,
        PathKind::Ellipse,
        PathKind::Cycloid,
        PathKind::Bezier,
    ];

    /// Lower-case name: `rectangle`, `semicircle`, `ellipse`, `cycloid`, `bezier`.
    pub const fn name(self) -> &'static str {
        match self {
            PathKind::Rectangle => "rectangle",
            PathKind::Semicircle => "semicircle",
            PathKind::Ellipse => "ellipse",
            PathKind::Cycloid => "cycloid",
            PathKind::Bezier => "bezier",
        }
    }

    /// Parses a name as printed by [`PathKind::name`] (case-insensitive).
    pub fn parse(s: &str) -> Option<PathKind> {
        PathKind::ALL
            .into_iter()
            .find(|k| k.name().eq_ignore_ascii_case(s.trim()))
    }
}

/// Any of the paths, chosen at run time.
#[derive(Debug, Clone, Copy, PartialEq)]
#[cfg_attr(feature = "serde", derive(serde::Serialize, serde::Deserialize))]
pub enum AnyPath {
    /// See [`Rectangle`].
    Rectangle(Rectangle),
    /// See [`Semicircle`].
    Semicircle(Semicircle),
    /// See [`Ellipse`].
    Ellipse(Ellipse),
    /// See [`Cycloid`].
    Cycloid(Cycloid),
    /// See [`Bezier`].
    Bezier(Bezier),
}

impl AnyPath {
    /// A path of `kind` over `stride` ([`PathKind::Semicircle`] uses `L/2` as its height).
    pub fn new(kind: PathKind, stride: Stride) -> AnyPath {
        match kind {
            PathKind::Rectangle => AnyPath::Rectangle(Rectangle::new(stride)),
            PathKind::Semicircle => AnyPath::Semicircle(Semicircle {
                stride: Stride {
                    height_m: 0.5 * stride.length_m,
                    ..stride
                },
            }),
            PathKind::Ellipse => AnyPath::Ellipse(Ellipse::new(stride)),
            PathKind::Cycloid => AnyPath::Cycloid(Cycloid::new(stride)),
            PathKind::Bezier => AnyPath::Bezier(Bezier::new(stride)),
        }
    }

    /// The kind of this path.
    pub const fn kind(&self) -> PathKind {
        match self {
            AnyPath::Rectangle(_) => PathKind::Rectangle,
            AnyPath::Semicircle(_) => PathKind::Semicircle,
            AnyPath::Ellipse(_) => PathKind::Ellipse,
            AnyPath::Cycloid(_) => PathKind::Cycloid,
            AnyPath::Bezier(_) => PathKind::Bezier,
        }
    }

    /// The stride of this path.
    pub const fn stride(&self) -> Stride {
        match self {
            AnyPath::Rectangle(p) => p.stride,
            AnyPath::Semicircle(p) => p.stride,
            AnyPath::Ellipse(p) => p.stride,
            AnyPath::Cycloid(p) => p.stride,
            AnyPath::Bezier(p) => p.stride,
        }
    }
}

impl FootPath for AnyPath {
    fn offset<M: Math>(&self, phase: Phase) -> Vec3 {
        self.stride().offset(phase, |s| match self {
            AnyPath::Rectangle(p) => p.swing(s),
            AnyPath::Semicircle(p) => p.swing::<M>(s),
            AnyPath::Ellipse(p) => p.swing::<M>(s),
            AnyPath::Cycloid(p) => p.swing::<M>(s),
            AnyPath::Bezier(p) => p.swing(s),
        })
    }

    fn duty_factor(&self) -> f32 {
        self.stride().duty_factor
    }

    fn c1_at_joins(&self) -> bool {
        match self {
            AnyPath::Rectangle(p) => p.c1_at_joins(),
            AnyPath::Semicircle(p) => p.c1_at_joins(),
            AnyPath::Ellipse(p) => p.c1_at_joins(),
            AnyPath::Cycloid(p) => p.c1_at_joins(),
            AnyPath::Bezier(p) => p.c1_at_joins(),
        }
    }
}
