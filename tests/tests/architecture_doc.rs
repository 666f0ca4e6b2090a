//! docs/architecture.md says only what is true of the code: every name it writes in backticks
//! exists in the source.
//!
//! The rules, by the text between a pair of backticks (a span):
//! - **Skipped**: spans in the first column of the tables under "Where each paper equation
//!   lives" (the papers' own notation: `A ≥ La`, `RotX`, `math_error_handler`); commands (a
//!   span that starts with `cargo `, `quadctl ` or `python `); attributes (a span that starts
//!   with `#`).
//! - **Paths**: a span with a `/` or ending in a file extension (`.rs`, `.md`, `.toml`, `.csv`,
//!   `.py`, `.sh`, `.json`) must name an existing file or directory, from the repository root or
//!   as the end of an existing path (`app.rs`, `tests/avr_firmware.rs`); a trailing `/` or `/*`
//!   names the directory.
//! - **Hyphenated names** (a package, a directory, a build target: `firmware-avr`, `avr-none`)
//!   must be an existing path as above or a quoted string in one of the repository's `.rs` or
//!   `.toml` files.
//! - **Code**, every other span: string literals and the contents of parentheses (argument
//!   placeholders such as `(pose)`) are dropped; what is left is read as Rust paths
//!   (`a::b::c`, turbofish and generics included). Rust keywords, the std prelude's names and
//!   single-letter names (type parameters) are skipped, and so is `no_std`. Every segment of a
//!   path must be defined in the Rust sources (crates/, quadctl/, tests/, xtask/,
//!   firmware-avr/) — as an item (`fn`, `struct`, `enum`, `trait`, `type`, `const`, `static`,
//!   `mod`, `macro_rules!`), an enum variant or a field, a `let` binding, an assembly symbol
//!   (`.global`), a source file or directory (a module), or a package. In `a::b`, `b` must be
//!   defined in a file that defines the item `a`, holds an `impl` of `a`, or lies in module `a` (its stem or a directory
//!   of its path); when a path starts with a crate's name, its last segment must be defined in that
//!   crate (re-exports at the crate's root).
//!
//! A failure names the missing identifier and its line in docs/architecture.md.

use std::collections::{BTreeMap, BTreeSet};
use std::fs;
use std::path::{Path, PathBuf};

const DOC: &str = "docs/architecture.md";

/// The section whose tables' first column is the papers' notation.
const PAPER_SECTION: &str = "## Where each paper equation lives";

/// Directories that hold the Rust sources.
const SOURCE_DIRS: [&str; 5] = ["crates", "quadctl", "tests", "xtask", "firmware-avr"];

/// Directories never read.
const IGNORED_DIRS: [&str; 5] = [
    "target",
    ".git",
    "node_modules",
    ".venv-twin",
    "__pycache__",
];

/// File extensions that make a span a path.
const PATH_EXTENSIONS: [&str; 7] = [".rs", ".md", ".toml", ".csv", ".py", ".sh", ".json"];

/// Spans that start so are commands.
const COMMANDS: [&str; 3] = ["cargo ", "quadctl ", "python "];

/// Rust keywords and std prelude names that may appear in a code span.
const SKIPPED_NAMES: [&str; 25] = [
    "as", "crate", "dyn", "extern", "fn", "for", "impl", "mut", "pub", "ref", "self", "Self",
    "super", "where", "Box", "Option", "Some", "None", "Result", "Ok", "Err", "Vec", "String",
    "str", "no_std",
];

fn root() -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR"))
        .parent()
        .expect("the tests crate lies in the workspace")
        .to_path_buf()
}

/// Every file and directory of the repository, relative to its root, with `/` separators.
fn walk(dir: &Path, rel: &str, out: &mut Vec<(String, bool)>) {
    let Ok(entries) = fs::read_dir(dir) else {
        return;
    };
    for entry in entries.flatten() {
        let name = entry.file_name().to_string_lossy().into_owned();
        if IGNORED_DIRS.contains(&name.as_str()) {
            continue;
        }
        let path = if rel.is_empty() {
            name.clone()
        } else {
            format!("{rel}/{name}")
        };
        let is_dir = entry.file_type().is_ok_and(|t| t.is_dir());
        out.push((path.clone(), is_dir));
        if is_dir {
            walk(&entry.path(), &path, out);
        }
    }
}

fn is_ident_start(c: char) -> bool {
    c.is_ascii_alphabetic() || c == '_'
}

fn is_ident_char(c: char) -> bool {
    c.is_ascii_alphanumeric() || c == '_'
}

/// The identifier at the start of `s`, if any.
fn leading_ident(s: &str) -> Option<&str> {
    if !s.starts_with(is_ident_start) {
        return None;
    }
    let end = s.find(|c: char| !is_ident_char(c)).unwrap_or(s.len());
    Some(&s[..end])
}

/// The names one line of Rust defines (see the module docs): `items` gets the items (what may
/// hold other names), `out` every name.
fn definitions(line: &str, items: &mut BTreeSet<String>, out: &mut BTreeSet<String>) {
    const KEYWORDS: [(&str, bool); 13] = [
        ("fn ", true),
        ("struct ", true),
        ("enum ", true),
        ("trait ", true),
        ("type ", true),
        ("const ", true),
        ("static ", true),
        ("mod ", true),
        ("union ", true),
        ("macro_rules! ", true),
        ("let ", false),
        ("let mut ", false),
        (".global ", false),
    ];
    for (kw, item) in KEYWORDS {
        let mut rest = line;
        while let Some(i) = rest.find(kw) {
            let before_ok = i == 0 || !rest[..i].ends_with(is_ident_char);
            rest = &rest[i + kw.len()..];
            if let (true, Some(name)) = (before_ok, leading_ident(rest.trim_start())) {
                out.insert(name.to_owned());
                if item {
                    items.insert(name.to_owned());
                }
            }
        }
    }
    // An `impl` block puts its methods within its type (a type's methods may live in another
    // file than the type): `impl Type`, `impl<T> Type<T>`, `impl Trait for Type`.
    if let Some(rest) = line.trim_start().strip_prefix("impl") {
        let rest = match rest.strip_prefix('<') {
            Some(generic) => generic.split_once('>').map_or("", |(_, r)| r),
            None if rest.starts_with(' ') => rest,
            None => "",
        };
        let target = rest.rsplit(" for ").next().unwrap_or(rest).trim_start();
        if let Some(name) = leading_ident(target) {
            items.insert(name.to_owned());
        }
    }
    // Enum variants, fields, assembly labels: a leading name followed by `:`, `(`, `{`, `,`,
    // `=` or nothing; the variants of `wire_enum!` (`2 => Name(...)`).
    let mut t = line.trim_start().trim_start_matches('"');
    for prefix in ["pub(crate) ", "pub(super) ", "pub "] {
        t = t.strip_prefix(prefix).unwrap_or(t);
    }
    if let Some((index, rest)) = t.split_once(" => ") {
        if !index.is_empty() && index.chars().all(|c| c.is_ascii_digit()) {
            t = rest;
        }
    }
    if let Some(name) = leading_ident(t) {
        let after = t[name.len()..].trim_start();
        if after.is_empty() || after.starts_with([':', '(', '{', ',', '=', '"']) {
            out.insert(name.to_owned());
        }
    }
}

/// What the source defines.
struct Source {
    /// Every file and directory, relative to the root.
    paths: Vec<(String, bool)>,
    /// Every name defined anywhere.
    names: BTreeSet<String>,
    /// Names defined in each crate, by the crate's name (`kin_core`).
    by_crate: BTreeMap<String, BTreeSet<String>>,
    /// Per source file: the names it defines, and its items with the names of the modules it
    /// lies in (its stem and its directories).
    files: Vec<(BTreeSet<String>, BTreeSet<String>)>,
    /// Every `.rs` and `.toml` file's text.
    texts: Vec<String>,
}

impl Source {
    fn read(root: &Path) -> Source {
        let mut paths = Vec::new();
        walk(root, "", &mut paths);
        let mut names = BTreeSet::new();
        let mut by_crate: BTreeMap<String, BTreeSet<String>> = BTreeMap::new();
        let mut texts = Vec::new();
        let mut files = Vec::new();
        // The crate of a file: the deepest directory holding a Cargo.toml with a package.
        let mut packages: Vec<(String, String)> = Vec::new();
        for (path, is_dir) in &paths {
            if *is_dir || !path.ends_with("Cargo.toml") {
                continue;
            }
            let text = fs::read_to_string(root.join(path)).unwrap_or_default();
            let name = text
                .split("[package]")
                .nth(1)
                .and_then(|p| p.lines().find_map(|l| l.trim().strip_prefix("name = \"")))
                .and_then(|n| n.strip_suffix('"'));
            if let Some(name) = name {
                let dir = path.trim_end_matches("Cargo.toml").to_owned();
                packages.push((dir, name.replace('-', "_")));
                names.insert(name.replace('-', "_"));
            }
        }
        packages.sort_by_key(|(dir, _)| std::cmp::Reverse(dir.len()));
        for (path, is_dir) in &paths {
            let in_sources = SOURCE_DIRS
                .iter()
                .any(|d| path == d || path.starts_with(&format!("{d}/")));
            let file = path.rsplit('/').next().unwrap_or(path);
            if in_sources && *is_dir {
                names.insert(file.to_owned());
            }
            if *is_dir || !(path.ends_with(".rs") || path.ends_with(".toml")) {
                continue;
            }
            let Ok(text) = fs::read_to_string(root.join(path)) else {
                continue;
            };
            if in_sources && path.ends_with(".rs") {
                let mut defined = BTreeSet::new();
                let mut scopes: BTreeSet<String> = path
                    .trim_end_matches(".rs")
                    .split('/')
                    .map(str::to_owned)
                    .collect();
                defined.insert(file.trim_end_matches(".rs").to_owned());
                for line in text.lines() {
                    definitions(line, &mut scopes, &mut defined);
                }
                if let Some((_, krate)) = packages.iter().find(|(dir, _)| path.starts_with(dir)) {
                    by_crate
                        .entry(krate.clone())
                        .or_default()
                        .extend(defined.iter().cloned());
                }
                names.extend(defined.iter().cloned());
                files.push((defined, scopes));
            }
            texts.push(text);
        }
        Source {
            paths,
            names,
            by_crate,
            files,
            texts,
        }
    }

    /// True when `inner` is defined in a file that defines the item `outer` or lies in module
    /// `outer`.
    fn defined_within(&self, outer: &str, inner: &str) -> bool {
        self.files
            .iter()
            .any(|(defined, scopes)| defined.contains(inner) && scopes.contains(outer))
    }

    /// True when `p` names a file or directory (see the module docs).
    fn path_exists(&self, p: &str) -> bool {
        let p = p.trim_end_matches("/*").trim_end_matches('/');
        self.paths
            .iter()
            .any(|(path, _)| path == p || path.ends_with(&format!("/{p}")))
    }

    /// True when `name` is quoted in a `.rs` or `.toml` file.
    fn quoted(&self, name: &str) -> bool {
        let q = format!("\"{name}\"");
        self.texts.iter().any(|t| t.contains(&q))
    }
}

/// A backticked span and the line of the page it is on (from 1).
struct Span {
    line: usize,
    text: String,
}

/// The spans of the page the rules check.
fn spans(page: &str) -> Vec<Span> {
    let mut out = Vec::new();
    let mut in_paper = false;
    let mut in_fence = false;
    for (i, line) in page.lines().enumerate() {
        if line.starts_with("```") {
            in_fence = !in_fence;
            continue;
        }
        if in_fence {
            continue;
        }
        if line.starts_with("## ") {
            in_paper = line.trim() == PAPER_SECTION;
        }
        let mut text = line;
        if in_paper && line.starts_with('|') {
            // The first column is the papers' notation.
            text = line[1..].split_once('|').map_or("", |(_, rest)| rest);
        }
        for (k, piece) in text.split('`').enumerate() {
            if k % 2 == 1 {
                out.push(Span {
                    line: i + 1,
                    text: piece.to_owned(),
                });
            }
        }
    }
    out
}

/// The Rust paths of a code span (see the module docs).
fn code_paths(span: &str) -> Vec<Vec<String>> {
    // Drop string literals and the contents of parentheses.
    let mut kept = String::new();
    let (mut depth, mut in_str) = (0usize, false);
    for c in span.chars() {
        match c {
            '"' => in_str = !in_str,
            _ if in_str => {}
            '(' => {
                depth += 1;
                kept.push(' ');
            }
            ')' => {
                depth = depth.saturating_sub(1);
                kept.push(' ');
            }
            _ if depth > 0 => {}
            _ => kept.push(c),
        }
    }
    let mut paths = Vec::new();
    let mut rest = kept.as_str();
    while let Some(start) = rest.find(is_ident_start) {
        // A name that continues a number or another token is not one.
        let glued = rest[..start].ends_with(|c: char| c.is_ascii_digit());
        rest = &rest[start..];
        let mut path = Vec::new();
        while let Some(name) = leading_ident(rest) {
            path.push(name.to_owned());
            rest = &rest[name.len()..];
            match rest.strip_prefix("::") {
                Some(r) if r.starts_with(is_ident_start) => rest = r,
                _ => break,
            }
        }
        if !glued {
            paths.push(path);
        }
    }
    paths
}

fn skipped_name(name: &str) -> bool {
    name.len() == 1 || SKIPPED_NAMES.contains(&name)
}

/// Why a span fails the rules, or `None`.
fn check(source: &Source, span: &str) -> Vec<String> {
    if COMMANDS.iter().any(|c| span.starts_with(c)) || span.starts_with('#') {
        return Vec::new();
    }
    if span.contains('/') || PATH_EXTENSIONS.iter().any(|e| span.ends_with(e)) {
        return if source.path_exists(span) {
            Vec::new()
        } else {
            vec![format!("`{span}`: no such file or directory")]
        };
    }
    if span.contains('-') && !span.contains(char::is_whitespace) && !span.contains("->") {
        return if source.path_exists(span) || source.quoted(span) {
            Vec::new()
        } else {
            vec![format!(
                "`{span}`: neither a path nor a quoted name in the sources"
            )]
        };
    }
    let mut missing = Vec::new();
    for path in code_paths(span) {
        let scope = source.by_crate.get(&path[0]).filter(|_| path.len() > 1);
        for (k, name) in path.iter().enumerate() {
            if skipped_name(name) {
                continue;
            }
            let whole = path.join("::");
            let outer = k
                .checked_sub(1)
                .map(|j| path[j].as_str())
                .filter(|o| !skipped_name(o));
            let why = match (scope, outer) {
                _ if !source.names.contains(name) => "is defined nowhere in the source",
                (Some(names), _) if k + 1 == path.len() && !names.contains(name) => {
                    "is not defined in that crate"
                }
                (_, Some(outer))
                    if !source.by_crate.contains_key(outer)
                        && !source.defined_within(outer, name) =>
                {
                    "is not defined beside or within the name before it"
                }
                _ => continue,
            };
            missing.push(if whole == *name {
                format!("`{name}` {why}")
            } else {
                format!("`{name}` (of `{whole}`) {why}")
            });
        }
    }
    missing
}

#[test]
fn every_name_in_the_architecture_page_exists_in_the_source() {
    let root = root();
    let page = fs::read_to_string(root.join(DOC)).expect("docs/architecture.md");
    let source = Source::read(&root);
    let mut failures = Vec::new();
    let all = spans(&page);
    assert!(
        all.len() > 100,
        "{} spans: the page was not read",
        all.len()
    );
    for span in &all {
        for why in check(&source, &span.text) {
            failures.push(format!("{DOC}:{}: {why}", span.line));
        }
    }
    assert!(
        failures.is_empty(),
        "{} names of {DOC} are not in the source:\n{}",
        failures.len(),
        failures.join("\n")
    );
}

/// The rules themselves, on made-up spans.
#[test]
fn the_rules_check_code_paths_and_skip_commands() {
    let source = Source::read(&root());
    assert!(check(&source, "cargo xtask nothing-such").is_empty());
    assert!(check(&source, "#![no_such_attribute]").is_empty());
    assert!(check(&source, "quad_device::sim::VirtualClock::advance_ms").is_empty());
    assert!(check(&source, "Device<O, C, S, M>").is_empty());
    assert!(check(&source, "Request::SetBodyPose(pose)").is_empty());
    assert!(check(&source, "firmware-avr").is_empty());
    assert!(check(&source, "app.rs").is_empty());
    assert_eq!(check(&source, "kin_core::no_such_function").len(), 1);
    // Defined in quad-host, not in kin-core.
    assert_eq!(check(&source, "kin_core::PoseStream").len(), 1);
    assert_eq!(check(&source, "Device::no_such_method").len(), 1);
    // Both exist, but not one within the other.
    assert_eq!(check(&source, "leg::PoseStream").len(), 1);
    assert_eq!(check(&source, "no_such_dir/x.rs").len(), 1);
    // Built so that this file does not quote it.
    assert_eq!(check(&source, concat!("no-such", "-target")).len(), 1);
}
