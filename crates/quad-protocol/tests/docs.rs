//! `docs/protocol.md` shows what the code does: its size table is exactly the output of `cargo run -p quad-protocol --example wire_examples`.

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

/// The answer-time table of `docs/protocol.md` ("Answer times") as `quad_protocol::timing`
/// prints it.
fn answer_time_rows() -> String {
    use quad_protocol::timing::{Kind, BAUDS};
    let ms = |us: u32| format!("{:.1}", f64::from(us) / 1000.0);
    Kind::ALL
        .iter()
        .map(|k| {
            let [slow, fast] = k.worst_us();
            format!(
                "| {} | {} | {} | {} | {} |\n",
                k.name(),
                ms(slow),
                k.timeout(BAUDS[0]).as_millis(),
                ms(fast),
                k.timeout(BAUDS[1]).as_millis()
            )
        })
        .collect()
}

#[test]
fn protocol_doc_answer_times_are_the_table_of_the_code() {
    let begin = "<!-- answer-times:begin -->\n";
    let end = "<!-- answer-times:end -->";
    let start = DOC.find(begin).expect("the answer-times markers") + begin.len();
    let stop = DOC[start..].find(end).expect("the end marker") + start;
    let section = &DOC[start..stop];
    let rows: String = section.lines().skip(2).map(|l| format!("{l}\n")).collect();
    let expected = answer_time_rows();
    assert_eq!(
        rows, expected,
        "docs/protocol.md's answer-time table differs from quad_protocol::timing; its rows:\n{expected}"
    );
}
