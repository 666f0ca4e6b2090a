//! The kernels' tables and the one way to read them.

use core::marker::PhantomData;

/// Whether this target links the fixed-point kernels' tables ([`poly::atan2_fixed`](super::poly::atan2_fixed),
/// [`poly::sin_cos_fixed`](super::poly::sin_cos_fixed)) into program memory: on the AVR, avr-gcc's startup code copies all
/// ordinary read-only data into SRAM, the scarcest memory of the ATmega2560, so there the
/// tables go to flash (`.progmem.data`, which the linker script keeps in the first 64 KB, as
/// `lpm` needs) and must be read with `lpm` by the backend ([`Math::read_table_cell`](super::Math::read_table_cell)). The
/// tables' declaration (`flash_tables!`) is the other place that names the target; elsewhere
/// they are ordinary read-only data.
pub const TABLES_IN_PROGRAM_MEMORY: bool = cfg!(target_arch = "avr");

/// The address of one entry of a fixed-point kernel's table (a cell), for
/// [`Math::read_table_cell`](super::Math::read_table_cell); made only by this crate, from an index checked against the
/// table's length. The tables are reachable through nothing else, and the entry's one plain
/// load ([`Math`](super::Math)'s default read) does not compile where the tables are in program memory: no
/// Rust code loads them there, which would read SRAM at a flash address.
#[derive(Clone, Copy)]
pub struct TableEntry<T: 'static>(&'static T);

/// The address only: formatting the entry must not load it (see [`TableEntry`]).
impl<T: 'static> core::fmt::Debug for TableEntry<T> {
    fn fmt(&self, f: &mut core::fmt::Formatter<'_>) -> core::fmt::Result {
        f.debug_tuple("TableEntry")
            .field(&(self.0 as *const T))
            .finish()
    }
}

impl<T: Copy + 'static> TableEntry<T> {
    /// The entry's address: in program memory when [`TABLES_IN_PROGRAM_MEMORY`], else in data
    /// memory. Valid for the whole program (the tables are immutable statics).
    pub fn addr(self) -> *const T {
        self.0
    }

    /// The plain load of [`Math`](super::Math)'s default table reads, for the backend `M`: refused when
    /// `M` is compiled for a target whose tables are in program memory (a post-monomorphization
    /// error names the fix), so that a backend that forgets the flash read does not build.
    pub(super) fn read_data_memory<M: ?Sized>(self) -> T {
        let () = ReadsDataMemory::<M>::CHECK;
        *self.0
    }
}

/// The compile-time check of [`TableEntry::read_data_memory`], per backend `M` (generic so
/// that it is evaluated only for a backend that uses the plain load).
struct ReadsDataMemory<M: ?Sized>(PhantomData<M>);

impl<M: ?Sized> ReadsDataMemory<M> {
    const CHECK: () = assert!(
        !TABLES_IN_PROGRAM_MEMORY,
        "this target keeps the fixed-point kernels' tables in program memory: the Math backend \
         must read them there (override Math::read_table_cell)"
    );
}

/// A constant table of a fixed-point kernel, readable only through [`Table::entry`] and a
/// backend's [`Math::read_table_cell`](super::Math::read_table_cell) (the array is private, so no code can index it with a
/// plain load).
pub(crate) struct Table<T: 'static, const N: usize>(pub(crate) [T; N]);

impl<T: Copy + 'static, const N: usize> Table<T, N> {
    /// Entry `i` (panics when `i ≥ N`, as indexing does).
    pub(crate) fn entry(&'static self, i: usize) -> TableEntry<T> {
        // Indexing checks the bounds and takes the address, without a load.
        TableEntry(&self.0[i])
    }
}

/// Declares the kernels' tables as [`Table`] statics, in program memory on the AVR
/// ([`TABLES_IN_PROGRAM_MEMORY`]; `.progmem.data` is the section avr-gcc's linker script keeps
/// in flash and its startup code does not copy to SRAM).
macro_rules! flash_tables {
    ($($(#[$doc:meta])* $vis:vis static $name:ident: [$t:ty; $n:expr] = $value:expr;)+) => {
        $(
            $(#[$doc])*
            // `unsafe_code` flags a static's `link_section` because plain loads of data placed
            // in another memory would be wrong: [`Table`] admits only the backend's reads.
            #[cfg_attr(
                target_arch = "avr",
                allow(unsafe_code),
                link_section = ".progmem.data"
            )]
            $vis static $name: Table<$t, $n> = Table($value);
        )+
    };
}
pub(crate) use flash_tables;

#[cfg(test)]
mod tests {
    use crate::math::{poly, Libm, Math, SoftFloat};
    extern crate std;

    /// The default table read is a plain load of the entry, and an entry's `Debug` shows its
    /// address, not its value.
    #[test]
    fn table_entries_read_and_print_without_a_second_path() {
        use std::format;
        let entry = poly::ATAN_CELLS.entry(32);
        assert_eq!(
            Libm::read_table_cell(entry),
            SoftFloat::<Libm>::read_table_cell(entry)
        );
        assert_eq!(Libm::read_table_cell(entry)[2], 16_383);
        let shown = format!("{entry:?}");
        assert!(shown.starts_with("TableEntry(0x"), "{shown}");
    }
}
