//! `docs/protocol-schema.json` is the schema of the declarations (`quad_protocol::schema`), and
//! docs/protocol.md's message tables (`HostToDevice`, `MotionCommand`, `DeviceToHost`,
//! `NackReason`) agree with it: every variant's index and name, every field's name, a newtype
//! variant's type.

#[path = "../examples/schema.rs"]
mod schema_example;

use quad_protocol::schema::ENUMS;
use quad_protocol::wire::FieldsSchema;

const DOC: &str = include_str!("../../../docs/protocol.md");
const SCHEMA: &str = include_str!("../../../docs/protocol-schema.json");
const COMMAND: &str = "cargo run -p quad-protocol --example schema > docs/protocol-schema.json";

#[test]
fn the_schema_file_is_the_declarations() {
    assert!(
        SCHEMA == schema_example::render(),
        "docs/protocol-schema.json differs from the declarations; regenerate it with `{COMMAND}`"
    );
}

/// The rows of the table of docs/protocol.md whose header line is `header`: (index, name,
/// fields cell).
fn rows(header: &str) -> Vec<(u32, String, String)> {
    let start = DOC
        .find(header)
        .unwrap_or_else(|| panic!("no table {header}"));
    DOC[start..]
        .lines()
        .skip(2)
        .take_while(|l| l.starts_with('|'))
        .map(|l| {
            let cells: Vec<&str> = l.trim_matches('|').split(" | ").map(str::trim).collect();
            let index = cells[0].parse().unwrap_or_else(|e| panic!("{l}: {e}"));
            (
                index,
                cells[1].trim_matches('`').to_owned(),
                cells[2].to_owned(),
            )
        })
        .collect()
}

/// The differences between the table under `header` and the schema of enum `name`.
fn differences(header: &str, name: &str) -> Vec<String> {
    let variants = ENUMS
        .iter()
        .find(|e| e.name == name)
        .expect("the enum")
        .variants;
    let table = rows(header);
    let mut out = Vec::new();
    if table.len() != variants.len() {
        out.push(format!(
            "{name}: {} rows, {} variants",
            table.len(),
            variants.len()
        ));
    }
    for v in variants {
        let Some((_, row_name, cell)) = table.iter().find(|(i, ..)| *i == v.index) else {
            out.push(format!("{name}: no row of index {} ({})", v.index, v.name));
            continue;
        };
        if *row_name != v.name {
            out.push(format!(
                "{name} {}: the table says {row_name}, the schema {}",
                v.index, v.name
            ));
        }
        match v.fields {
            FieldsSchema::Unit => {}
            FieldsSchema::Newtype(ty) => {
                let ty = ty.replace(' ', "");
                let ty = ty.trim_start_matches("crate::");
                if !cell.contains(&format!("`{ty}")) {
                    out.push(format!("{name}::{}: the fields do not name `{ty}`", v.name));
                }
            }
            FieldsSchema::Struct(fields) => {
                for f in fields {
                    let named = [format!("`{}:", f.name), format!("`{}`", f.name)];
                    if !named.iter().any(|n| cell.contains(n.as_str())) {
                        out.push(format!("{name}::{}: no field `{}`", v.name, f.name));
                    }
                }
            }
        }
    }
    out
}

#[test]
fn protocol_doc_message_tables_are_the_schema() {
    let tables = [
        (
            "| index | request | fields after the index | bytes | answer |",
            "Request",
        ),
        ("| index | motion | fields |", "MotionCommand"),
        (
            "| index | answer | fields after the index | bytes |",
            "DeviceToHost",
        ),
        ("| index | reason | fields | `seq` | when |", "NackReason"),
    ];
    let problems: Vec<String> = tables
        .iter()
        .flat_map(|(header, name)| differences(header, name))
        .collect();
    println!("doc tables vs schema: {} differences", problems.len());
    assert!(problems.is_empty(), "{problems:#?}");
}
