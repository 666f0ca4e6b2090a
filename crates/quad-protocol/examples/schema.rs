//! Prints `docs/protocol-schema.json`, the machine-readable schema of the messages
//! (`quad_protocol::schema`):
//!
//! ```sh
//! cargo run -p quad-protocol --example schema > docs/protocol-schema.json
//! ```

use quad_protocol::schema::{self, ENUMS};
use quad_protocol::wire::FieldsSchema;
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
    });
    serde_json::to_string_pretty(&doc).expect("JSON") + "\n"
}

#[allow(dead_code)] // unused when included by the schema test
fn main() {
    print!("{}", render());
}
