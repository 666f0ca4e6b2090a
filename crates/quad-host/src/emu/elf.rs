//! Section sizes and symbols of a 32-bit little-endian ELF (the AVR firmware's), read directly:
//! flash and static SRAM figures, and the addresses of linker symbols such as `__heap_start`
//! (the end of the static data, where the firmware's stack paint begins).

use std::path::{Path, PathBuf};

/// AVR data addresses in the ELF carry this offset (avr-gcc's `.data` at 0x800000).
pub const DATA_OFFSET: u32 = 0x80_0000;

/// Why an ELF could not be read.
#[derive(Debug, thiserror::Error)]
#[non_exhaustive]
pub enum Error {
    /// The file could not be read.
    #[error("cannot read {}: {source}", path.display())]
    Read {
        /// The file.
        path: PathBuf,
        /// The I/O error.
        source: std::io::Error,
    },
    /// The file is not a 32-bit little-endian ELF, or is cut short.
    #[error("{}: {what}", path.display())]
    Format {
        /// The file.
        path: PathBuf,
        /// What is wrong.
        what: Format,
    },
}

/// What is wrong with the bytes of an ELF.
#[derive(Debug, Clone, Copy, PartialEq, Eq, thiserror::Error)]
#[non_exhaustive]
pub enum Format {
    /// No ELF magic.
    #[error("not an ELF file")]
    NotElf,
    /// Another class or byte order.
    #[error("not a 32-bit little-endian ELF")]
    NotLe32,
    /// A header points past the end of the file.
    #[error("truncated ELF")]
    Truncated,
}

/// Sizes of an ELF's allocated sections, bytes.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct ElfSizes {
    /// `.text` + `.data` (the data's initial values live in flash).
    pub flash_bytes: u64,
    /// `.data` + `.bss` + `.noinit`.
    pub sram_static_bytes: u64,
}

/// A data object in flash ([`Elf::flash_objects`]).
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct FlashObject {
    /// The symbol's name (mangled, as the symbol table has it).
    pub name: String,
    /// Its flash byte address.
    pub addr: u32,
    /// Its size, bytes.
    pub size_bytes: u32,
}

impl FlashObject {
    /// The first byte address past the object.
    pub fn end(&self) -> u32 {
        self.addr + self.size_bytes
    }
}

/// A parsed ELF: its bytes and section headers.
pub struct Elf {
    bytes: Vec<u8>,
    /// (name, offset, size, link) of every section.
    sections: Vec<(String, usize, usize, usize)>,
}

impl Elf {
    /// Reads and checks `path` (32-bit little-endian ELF).
    ///
    /// # Errors
    /// When the file cannot be read or is not such an ELF.
    pub fn read(path: &Path) -> Result<Elf, Error> {
        let bytes = std::fs::read(path).map_err(|source| Error::Read {
            path: path.to_owned(),
            source,
        })?;
        Elf::parse(bytes).map_err(|what| Error::Format {
            path: path.to_owned(),
            what,
        })
    }

    fn parse(bytes: Vec<u8>) -> Result<Elf, Format> {
        if bytes.len() < 0x34 || &bytes[..4] != b"\x7fELF" {
            return Err(Format::NotElf);
        }
        if bytes[4] != 1 || bytes[5] != 1 {
            return Err(Format::NotLe32);
        }
        let b = &bytes;
        let get = |o: usize, n: usize| -> Result<usize, Format> {
            let s = b.get(o..o + n).ok_or(Format::Truncated)?;
            Ok(s.iter()
                .rev()
                .fold(0usize, |acc, &x| (acc << 8) | x as usize))
        };
        let (shoff, shentsize, shnum, shstrndx) =
            (get(0x20, 4)?, get(0x2E, 2)?, get(0x30, 2)?, get(0x32, 2)?);
        let header = |i: usize| -> Result<(usize, usize, usize, usize), Format> {
            let h = shoff + i * shentsize;
            Ok((
                get(h, 4)?,
                get(h + 16, 4)?,
                get(h + 20, 4)?,
                get(h + 24, 4)?,
            ))
        };
        let strtab = header(shstrndx)?.1;
        let mut sections = Vec::with_capacity(shnum);
        for i in 0..shnum {
            let (name_off, off, size, link) = header(i)?;
            let name = cstr(b, strtab + name_off);
            sections.push((name, off, size, link));
        }
        Ok(Elf { bytes, sections })
    }

    /// Flash and static SRAM.
    pub fn sizes(&self) -> ElfSizes {
        let (mut flash, mut sram) = (0u64, 0u64);
        for (name, _, size, _) in &self.sections {
            let size = *size as u64;
            match name.as_str() {
                ".text" => flash += size,
                ".data" => {
                    flash += size;
                    sram += size;
                }
                ".bss" | ".noinit" => sram += size,
                _ => {}
            }
        }
        ElfSizes {
            flash_bytes: flash,
            sram_static_bytes: sram,
        }
    }

    /// The value (address) of the symbol `name` from `.symtab`.
    pub fn symbol(&self, name: &str) -> Option<u32> {
        let (_, symoff, symsize, link) = self.sections.iter().find(|s| s.0 == ".symtab")?;
        let stroff = self.sections.get(*link)?.1;
        let u32_at = |o: usize| {
            self.bytes
                .get(o..o + 4)
                .map(|s| u32::from_le_bytes([s[0], s[1], s[2], s[3]]))
        };
        (0..symsize / 16).find_map(|i| {
            let e = symoff + 16 * i;
            let name_off = u32_at(e)? as usize;
            (cstr(&self.bytes, stroff + name_off) == name)
                .then(|| u32_at(e + 4))
                .flatten()
        })
    }

    /// The data objects that the linker placed in flash (`OBJECT` symbols of `.text`: tables
    /// the firmware reads with `lpm`, such as kin-core's kernel cells), in symbol-table order.
    pub fn flash_objects(&self) -> Vec<FlashObject> {
        const STT_OBJECT: u8 = 1;
        let Some(text) = self.sections.iter().position(|s| s.0 == ".text") else {
            return Vec::new();
        };
        let Some((_, symoff, symsize, link)) = self.sections.iter().find(|s| s.0 == ".symtab")
        else {
            return Vec::new();
        };
        let Some(&(_, stroff, _, _)) = self.sections.get(*link) else {
            return Vec::new();
        };
        let b = &self.bytes;
        let u32_at = |o: usize| {
            b.get(o..o + 4)
                .map(|s| u32::from_le_bytes([s[0], s[1], s[2], s[3]]))
        };
        (0..symsize / 16)
            .filter_map(|i| {
                let e = symoff + 16 * i;
                let info = *b.get(e + 12)?;
                let shndx = b
                    .get(e + 14..e + 16)
                    .map(|s| u16::from_le_bytes([s[0], s[1]]))?;
                (info & 0xf == STT_OBJECT && usize::from(shndx) == text).then(|| {
                    Some(FlashObject {
                        name: cstr(b, stroff + u32_at(e)? as usize),
                        addr: u32_at(e + 4)?,
                        size_bytes: u32_at(e + 8)?,
                    })
                })?
            })
            .collect()
    }

    /// The SRAM address of a data symbol (`.data`/`.bss` or a linker symbol such as
    /// `__heap_start`), without the ELF's [`DATA_OFFSET`].
    pub fn data_symbol(&self, name: &str) -> Option<u16> {
        self.symbol(name)
            .filter(|&a| a >= DATA_OFFSET)
            .map(|a| (a - DATA_OFFSET) as u16)
    }
}

fn cstr(b: &[u8], off: usize) -> String {
    let s = b.get(off..).unwrap_or(&[]);
    let end = s.iter().position(|&c| c == 0).unwrap_or(s.len());
    String::from_utf8_lossy(&s[..end]).into_owned()
}

/// Flash and static SRAM of the ELF at `path`.
///
/// # Errors
/// When it cannot be read.
pub fn sizes(path: &Path) -> Result<ElfSizes, Error> {
    Ok(Elf::read(path)?.sizes())
}
