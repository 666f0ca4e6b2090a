//! `docs/protocol.md` shows what the code does: its size table and example frames are exactly
//! the output of `cargo run -p quad-protocol --example wire_examples`.

#[path = "../examples/wire_examples.rs"]
mod wire_examples;

const DOC: &str = include_str!("../../../docs/protocol.md");

#[test]
fn protocol_doc_ends_with_the_generated_tables_and_frames() {
    let generated = wire_examples::render();
    assert!(
        DOC.trim_end().ends_with(generated.trim_end()),
        "docs/protocol.md is out of date: paste the output of \
         `cargo run -p quad-protocol --example wire_examples` at its end"
    );
}

#[test]
fn protocol_doc_states_the_constants_of_the_code() {
    let must = [
        format!(
            "`MAX_DECODED_LEN` = {} bytes",
            quad_protocol::MAX_DECODED_LEN
        ),
        format!("`MAX_FRAME_LEN` = {} bytes", quad_protocol::MAX_FRAME_LEN),
        format!("`0x{:04X}`", quad_protocol::crc::POLY),
        format!("`0x{:04X}`", quad_protocol::crc::INIT),
        format!(
            "**{}.{}** (`0x{:04x}`)",
            quad_protocol::version_major(quad_protocol::PROTOCOL_VERSION),
            quad_protocol::version_minor(quad_protocol::PROTOCOL_VERSION),
            quad_protocol::PROTOCOL_VERSION
        ),
    ];
    let flat: String = DOC.split_whitespace().collect::<Vec<_>>().join(" ");
    for m in must {
        assert!(flat.contains(&m), "docs/protocol.md lacks {m}");
    }
}
