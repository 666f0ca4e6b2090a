//! The machine-readable schema of the messages: every enum of the protocol with its variants'
//! wire indices, names and fields, taken from their declarations (`wire_enum!` and
//! `wire_index!` emit each enum's `VARIANTS`), and the unit and admissible range of the fields
//! that have them (the unit from the field's name, the range from [`crate::range`]).
//! `docs/protocol-schema.json` is this schema written out (by
//! `cargo run -p quad-protocol --example schema`), with the structs of the messages beside the
//! enums (their fields and types recorded from their own serde implementations by the
//! example's recording serializer), and a test holds it and the message tables of
//! docs/protocol.md to it.
//!
//! Why not postcard-schema's derive: it takes a variant's index from its position in the
//! declaration, while this protocol writes every index beside its variant (`wire_enum!`,
//! and kin-core's enums through the tables of [`crate::wire`], which serde's derive of kin-core
//! would number in kin-core's own order); a derived schema would describe other bytes than
//! those on the wire as soon as the two orders differ. The kin-core types carried (`Pose`,
//! `LegId`, …) would also need the derive in kin-core, a `no_std` crate that knows nothing of
//! the wire. The declarations here are the ones the encoder and decoder are generated from, so
//! the schema cannot describe other bytes than those they write and read.

use crate::range::{self, ParamRange};
use crate::wire::{self, VariantSchema};
use crate::{
    DeviceToHost, Field, LegSet, LinkLossAction, MotionCommand, MotionKind, MotionParam,
    MotionStage, NackReason, ParamProblem, PreflightFault, ReachFault, Request, RobotField,
    RobotPreset, Setting,
};

/// An enum of the protocol and its variants as declared.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct EnumSchema {
    /// The enum's name (kin-core's enums by their own names).
    pub name: &'static str,
    /// Its variants in declaration order.
    pub variants: &'static [VariantSchema],
}

/// Every enum on the wire: the messages' (`Request`, `DeviceToHost`, …) and the kin-core enums
/// the messages carry.
pub const ENUMS: &[EnumSchema] = &[
    EnumSchema {
        name: "Request",
        variants: Request::VARIANTS,
    },
    EnumSchema {
        name: "DeviceToHost",
        variants: DeviceToHost::VARIANTS,
    },
    EnumSchema {
        name: "MotionCommand",
        variants: MotionCommand::VARIANTS,
    },
    EnumSchema {
        name: "NackReason",
        variants: NackReason::VARIANTS,
    },
    EnumSchema {
        name: "Setting",
        variants: Setting::VARIANTS,
    },
    EnumSchema {
        name: "Field",
        variants: Field::VARIANTS,
    },
    EnumSchema {
        name: "LegSet",
        variants: LegSet::VARIANTS,
    },
    EnumSchema {
        name: "MotionKind",
        variants: MotionKind::VARIANTS,
    },
    EnumSchema {
        name: "MotionStage",
        variants: MotionStage::VARIANTS,
    },
    EnumSchema {
        name: "MotionParam",
        variants: MotionParam::VARIANTS,
    },
    EnumSchema {
        name: "ParamProblem",
        variants: ParamProblem::VARIANTS,
    },
    EnumSchema {
        name: "PreflightFault",
        variants: PreflightFault::VARIANTS,
    },
    EnumSchema {
        name: "ReachFault",
        variants: ReachFault::VARIANTS,
    },
    EnumSchema {
        name: "LinkLossAction",
        variants: LinkLossAction::VARIANTS,
    },
    EnumSchema {
        name: "RobotPreset",
        variants: RobotPreset::VARIANTS,
    },
    EnumSchema {
        name: "RobotField",
        variants: RobotField::VARIANTS,
    },
    EnumSchema {
        name: "servo::Error",
        variants: crate::servo::Error::VARIANTS,
    },
    EnumSchema {
        name: "LegId",
        variants: wire::leg_id::VARIANTS,
    },
    EnumSchema {
        name: "Joint",
        variants: wire::joint::VARIANTS,
    },
    EnumSchema {
        name: "RotationOrder",
        variants: wire::rotation_order::VARIANTS,
    },
    EnumSchema {
        name: "ReachPolicy",
        variants: wire::reach_policy::VARIANTS,
    },
    EnumSchema {
        name: "Axis",
        variants: wire::sway_axis::VARIANTS,
    },
    EnumSchema {
        name: "PathKind",
        variants: wire::path_kind::VARIANTS,
    },
    EnumSchema {
        name: "Pattern",
        variants: wire::gait_pattern::VARIANTS,
    },
    EnumSchema {
        name: "KneeBend",
        variants: wire::knee_bend::VARIANTS,
    },
];

/// The unit of a field, read from its name's suffix (the project's rule: units in names);
/// `None` for a field without one.
pub fn unit(field: &str) -> Option<&'static str> {
    const SUFFIXES: [(&str, &str); 8] = [
        ("_rad_s", "rad/s"),
        ("_m_s", "m/s"),
        ("_half_us", "half-µs"),
        ("_ms", "ms"),
        ("_us", "µs"),
        ("_rad", "rad"),
        ("_m", "m"),
        ("_s", "s"),
    ];
    SUFFIXES
        .iter()
        .find(|(suffix, _)| field.ends_with(suffix))
        .map(|&(_, unit)| unit)
}

/// The admissible range of a motion field whose range does not depend on the robot
/// ([`crate::range`]); `None` for the others (lengths are bounded by the robot's reach, see
/// [`crate::Ranges`]).
pub fn range(field: &str) -> Option<ParamRange> {
    Some(match field {
        "amplitude_rad" => range::SWAY_AMPLITUDE_RAD,
        "period_s" | "step_period_s" | "cycle_s" => range::PERIOD_S,
        "duration_s" => range::DURATION_S,
        "yaw_rate_rad_s" => range::YAW_RATE_RAD_S,
        "forward_m_s" | "lateral_m_s" => range::SPEED_M_S,
        "duty_factor" => range::DUTY_FACTOR,
        "joint_speed_limit_rad_s" => range::JOINT_SPEED_LIMIT_RAD_S,
        _ => return None,
    })
}
