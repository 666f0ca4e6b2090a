//! The symbols of a firmware ELF as `avr-nm -S` lists them: which routine a binary links
//! (avr-libc's, avr-libc-math's, compiler-builtins' weak fallbacks).

use std::path::Path;
use std::process::Command;

/// One line of `avr-nm -S`.
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct Symbol {
    /// The symbol's name.
    pub name: String,
    /// `nm`'s type letter (`T` a global in text, `W` weak, `U` undefined, …).
    pub kind: char,
    /// The symbol's size, bytes, when the object file gave one.
    pub size_bytes: Option<u32>,
}

/// Every symbol of `elf`. Panics (the test fails) when `avr-nm` cannot run.
pub fn of_elf(elf: &Path) -> Vec<Symbol> {
    let out = Command::new("avr-nm")
        .arg("-S")
        .arg(elf)
        .output()
        .expect("avr-nm runs (Debian binutils-avr)");
    assert!(out.status.success(), "avr-nm {}", elf.display());
    String::from_utf8_lossy(&out.stdout)
        .lines()
        .filter_map(parse_line)
        .collect()
}

/// The symbols of `symbols` called `name` (several when more than one object defines it).
pub fn named<'a>(symbols: &'a [Symbol], name: &str) -> Vec<&'a Symbol> {
    symbols.iter().filter(|s| s.name == name).collect()
}

/// `address size kind name`, `address kind name` or `kind name` (undefined).
fn parse_line(line: &str) -> Option<Symbol> {
    let fields: Vec<&str> = line.split_whitespace().collect();
    let (name, kind) = match fields[..] {
        [.., kind, name] => (name, kind),
        _ => return None,
    };
    let size_bytes = match fields[..] {
        [_, size, _, _] => u32::from_str_radix(size, 16).ok(),
        _ => None,
    };
    Some(Symbol {
        name: name.to_string(),
        kind: kind.chars().next()?,
        size_bytes,
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn lines_of_every_shape_parse() {
        let sized = parse_line("0000a1b2 0000012c T __addsf3").expect("sized");
        assert_eq!(
            (sized.name.as_str(), sized.kind, sized.size_bytes),
            ("__addsf3", 'T', Some(300))
        );
        let no_size = parse_line("00000a10 T sqrt").expect("unsized");
        assert_eq!((no_size.kind, no_size.size_bytes), ('T', None));
        let undefined = parse_line("         U __fp_round").expect("undefined");
        assert_eq!(
            (undefined.kind, undefined.name.as_str()),
            ('U', "__fp_round")
        );
        assert_eq!(parse_line(""), None);
    }
}
