//! Prints `docs/protocol-schema.json`, the machine-readable schema of the messages
//! (`quad_protocol::schema`):
//!
//! ```sh
//! cargo run -p quad-protocol --example schema > docs/protocol-schema.json
//! ```

#[path = "support/shape.rs"]
mod schema_shape;

use kin_core::{Pose, ReachPolicy, RotationOrder};
use quad_protocol::schema::{self, ENUMS};
use quad_protocol::wire::FieldsSchema;
use quad_protocol::{
    servo, DeviceInfo, FirmwareVersion, Flags, HostToDevice, LinkTimeout, MotionFrames, MotionKind,
    MotionStage, MotionStatus, NackReason, PoseConfig, Readback, Request, RobotDescription,
    RobotPreset, ServoId,
};
use schema_shape::Shape;
use serde_json::{json, Map, Value};

fn field(name: &str, ty: &str) -> Value {
    let mut f = Map::new();
    f.insert("name".into(), json!(name));
    f.insert("type".into(), json!(ty));
    if let Some(unit) = schema::unit(name) {
        f.insert("unit".into(), json!(unit));
    }
    if let Some(r) = schema::range(name) {
        f.insert(
            "range".into(),
            json!({"min": r.min, "max": r.max, "below_min": format!("{:?}", r.below)}),
        );
    }
    Value::Object(f)
}

/// The structs of the messages, each from a sample value (its `Option` fields `Some`) through
/// its own serde implementation: their fields as the wire writes them.
fn structs() -> Vec<Value> {
    let pose_config = PoseConfig {
        stance_height_m: 0.2,
        order: RotationOrder::Zyx,
        policy: ReachPolicy::Reject,
    };
    let flags = Flags::default();
    let shapes = [
        schema_shape::shape(&HostToDevice {
            seq: 0,
            request: Request::GetState,
        }),
        quad_protocol::wire::pose::serialize(&Pose::default(), schema_shape::Recorder),
        schema_shape::shape(&ServoId::ALL[0]),
        schema_shape::shape(&servo::Calibration::default()),
        schema_shape::shape(&LinkTimeout::default()),
        schema_shape::shape(&pose_config),
        schema_shape::shape(&FirmwareVersion::default()),
        schema_shape::shape(&DeviceInfo {
            version: 0,
            firmware: FirmwareVersion::default(),
            robot: RobotPreset::Custom,
            max_frame_len: 0,
            pose_config,
            link_timeout: LinkTimeout::default(),
            robot_hash: Some(0),
        }),
        schema_shape::shape(&RobotDescription {
            name: [0; 16],
            robot: kin_core::Robot::shahriar2023(),
            stance_height_m: 0.2,
            order: RotationOrder::Zyx,
            joint_speed_limit_rad_s: 1.0,
        }),
        schema_shape::shape(&Readback {
            angles_rad: [0.0; 12],
            pulses_half_us: [0; 12],
            flags,
            frames_ok: 0,
            frames_bad: 0,
        }),
        schema_shape::shape(&MotionStatus {
            kind: Some(MotionKind::Sway),
            stage: MotionStage::Run,
            t_s: 0.0,
            phase: 0.0,
            fault: Some(NackReason::Busy),
        }),
        schema_shape::shape(&MotionFrames {
            frame: 0,
            stop_frame: Some(0),
        }),
    ];
    let mut out: Vec<Value> = shapes
        .into_iter()
        .map(|s| match s.expect("a struct's shape") {
            Shape::Struct(name, fields) => json!({
                "name": name,
                "fields": fields.iter().map(|(n, t)| field(n, t)).collect::<Vec<_>>(),
            }),
            Shape::Type(t) => panic!("not a struct: {t}"),
        })
        .collect();
    match schema_shape::shape(&flags).expect("Flags' shape") {
        Shape::Type(t) => out.push(json!({"name": "Flags", "newtype": t})),
        Shape::Struct(..) => panic!("Flags is a newtype"),
    }
    out
}

/// The schema as JSON text, one trailing newline.
pub fn render() -> String {
    let enums: Vec<Value> = ENUMS
        .iter()
        .map(|e| {
            let variants: Vec<Value> = e
                .variants
                .iter()
                .map(|v| {
                    let mut o = Map::new();
                    o.insert("index".into(), json!(v.index));
                    o.insert("name".into(), json!(v.name));
                    match v.fields {
                        FieldsSchema::Unit => {}
                        FieldsSchema::Newtype(ty) => {
                            o.insert("newtype".into(), json!(ty));
                        }
                        FieldsSchema::Struct(fields) => {
                            let fields: Vec<Value> =
                                fields.iter().map(|f| field(f.name, f.ty)).collect();
                            o.insert("fields".into(), Value::Array(fields));
                        }
                    }
                    Value::Object(o)
                })
                .collect();
            json!({"name": e.name, "variants": variants})
        })
        .collect();
    let doc = json!({
        "protocol_version": quad_protocol::PROTOCOL_VERSION,
        "generated_by": "cargo run -p quad-protocol --example schema > docs/protocol-schema.json",
        "enums": enums,
        "structs": structs(),
    });
    serde_json::to_string_pretty(&doc).expect("JSON") + "\n"
}

#[allow(dead_code)] // unused when included by the schema test
fn main() {
    print!("{}", render());
}
