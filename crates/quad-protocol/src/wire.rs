//! The wire indices, written once: the macros that declare the protocol's enums with an
//! explicit index per variant, and the index tables of the kin-core types the messages carry.
//!
//! postcard writes an enum as its variant index (a varint) followed by the variant's fields in
//! order. serde's derive takes that index from the declaration order, and kin-core's own derive
//! from kin-core's declaration order; here every index is written beside its variant instead:
//!
//! - `wire_enum!` declares an enum of this crate, `0 => Hello { version: u16 }`, and emits it
//!   with its `Serialize`/`Deserialize` using those indices. A field of a foreign type names its
//!   table with `as`: `leg: LegId as wire::leg_id`.
//! - `wire_index!` writes the table of a foreign field-less enum as a module with `index`,
//!   `from_index` and serde's `with` functions ([`leg_id`], [`joint`], [`rotation_order`],
//!   [`reach_policy`]); `wire_fields!` fixes the field order of a foreign struct ([`pose`]).
//! - [`array`](mod@array) and [`shared`] change no byte, only the code that writes and reads
//!   them: the twelve-value arrays in a loop, the varint integers through one out-of-line call
//!   (sizes on the ATmega2560 in docs/benchmark-journal.md).
//!
//! Every table is an exhaustive `match`: a variant or field added to kin-core does not compile
//! until it has its place on the wire.
//!
//! ## The text form
//!
//! With the feature `text`, a `wire_enum!` type has a second form for human-readable formats
//! (JSON: the web panel, the command line's summaries), chosen by serde's
//! `is_human_readable()`: serde's default enum form with snake_case names, from the same
//! declaration: `"stand_up"`, `{"sway": {"axis": "roll", "amplitude_rad": 0.1, "period_s": 2,
//! "duration_s": null}}`, `{"one": "FL"}`; unknown fields are refused. Its fields are written
//! in kin-core's serde form (`kin-core/serde`). postcard is not human-readable: the wire form,
//! and every wire byte, is the same with and without the feature, and the firmware builds
//! without it. The implementations follow serde's data model as the
//! derive does (enum → variant index and name, struct variant → its fields in sequence), so any
//! index-based format reads them; the protocol uses postcard only.

use kin_core::motion::gait::Pattern;
use kin_core::motion::laws::Axis;
use kin_core::motion::path::PathKind;
use kin_core::{Joint, KneeBend, LegId, Pose, ReachPolicy, RotationOrder};

/// One variant of a protocol enum as its declaration writes it (`wire_enum!`, `wire_index!`):
/// the data of the machine-readable schema (`quad_protocol::schema`).
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct VariantSchema {
    /// The wire index (postcard's varint before the fields).
    pub index: u32,
    /// The variant's name as declared (CamelCase).
    pub name: &'static str,
    /// Its fields.
    pub fields: FieldsSchema,
}

/// The fields of a [`VariantSchema`].
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum FieldsSchema {
    /// No fields.
    Unit,
    /// One unnamed field of this type (as written in the declaration).
    Newtype(&'static str),
    /// Named fields in wire order.
    Struct(&'static [FieldSchema]),
}

/// A named field of a [`FieldsSchema::Struct`].
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct FieldSchema {
    /// The field's name.
    pub name: &'static str,
    /// Its type as written in the declaration.
    pub ty: &'static str,
}

/// Serializes the field `$value` (a reference) of type `$ty`, through the table `$with` when one
/// is named.
macro_rules! wire_ser_field {
    ($value:expr, $ty:ty) => {
        $value
    };
    ($value:expr, $ty:ty, $($with:ident)::+) => {
        &{
            struct With<'a>(&'a $ty);
            impl ::serde::Serialize for With<'_> {
                fn serialize<S: ::serde::Serializer>(&self, s: S) -> Result<S::Ok, S::Error> {
                    $($with)::+::serialize(self.0, s)
                }
            }
            With($value)
        }
    };
}

/// Reads the next field (of type `$ty`, through the table `$with` when one is named) from the
/// sequence `$seq`; `$n` counts the fields read, `$exp` is the visitor (for the error).
macro_rules! wire_next_field {
    ($seq:ident, $n:ident, $exp:expr, $ty:ty $(, $($with:ident)::+)?) => {{
        let value = $crate::wire::wire_next_field!(@read $seq, $ty $(, $($with)::+)?);
        match value {
            Some(v) => {
                $n += 1;
                v
            }
            None => return Err(::serde::de::Error::invalid_length($n, $exp)),
        }
    }};
    (@read $seq:ident, $ty:ty) => {
        ::serde::de::SeqAccess::next_element::<$ty>(&mut $seq)?
    };
    (@read $seq:ident, $ty:ty, $($with:ident)::+) => {{
        struct With($ty);
        impl<'de> ::serde::Deserialize<'de> for With {
            fn deserialize<D: ::serde::Deserializer<'de>>(d: D) -> Result<Self, D::Error> {
                $($with)::+::deserialize(d).map(With)
            }
        }
        ::serde::de::SeqAccess::next_element::<With>(&mut $seq)?.map(|w| w.0)
    }};
}

/// Declares an enum of the protocol with an explicit wire index per variant and emits its serde
/// `Serialize`/`Deserialize` with those indices (see the module docs). Variants are unit,
/// one-field tuple or struct variants; each field may name a table (`as path::to::table`).
macro_rules! wire_enum {
    (
        $(#[$attr:meta])*
        $vis:vis enum $name:ident {
            $($body:tt)*
        }
    ) => {
        $crate::wire::wire_enum!(@munch
            [$(#[$attr])* $vis $name]
            [serializer variant place]
            [] [] [] [] [] []
            $($body)*
        );
    };

    // A unit variant.
    (@munch $head:tt [$ser:ident $var_access:ident $place:ident]
        [$($decl:tt)*] [$($ser_arms:tt)*] [$($de_arms:tt)*] [$($place_arms:tt)*] [$($text:tt)*]
        [$($schema:tt)*]
        $(#[$vattr:meta])* $idx:literal => $var:ident
        $(, $($rest:tt)*)?
    ) => {
        $crate::wire::wire_enum!(@munch $head [$ser $var_access $place]
            [$($decl)* $(#[$vattr])* $var,]
            [$($ser_arms)* Self::$var => ($idx, stringify!($var)),]
            [$($de_arms)* $idx => {
                ::serde::de::VariantAccess::unit_variant($var_access)?;
                Ok(Target::$var)
            }]
            [$($place_arms)* $idx => {
                ::serde::de::VariantAccess::unit_variant($var_access)?;
                *$place = Target::$var;
                Ok(())
            }]
            [$($text)* $var,]
            [$($schema)* $crate::wire::VariantSchema {
                index: $idx, name: stringify!($var), fields: $crate::wire::FieldsSchema::Unit },]
            $($($rest)*)?
        );
    };

    // A one-field tuple variant.
    (@munch $head:tt [$ser:ident $var_access:ident $place:ident]
        [$($decl:tt)*] [$($ser_arms:tt)*] [$($de_arms:tt)*] [$($place_arms:tt)*] [$($text:tt)*]
        [$($schema:tt)*]
        $(#[$vattr:meta])* $idx:literal => $var:ident ( $ty:ty $(as $($with:ident)::+)? )
        $(, $($rest:tt)*)?
    ) => {
        $crate::wire::wire_enum!(@munch $head [$ser $var_access $place]
            [$($decl)* $(#[$vattr])* $var($ty),]
            [$($ser_arms)* Self::$var(value) => return ::serde::Serializer::serialize_newtype_variant(
                $ser, NAME, $idx, stringify!($var),
                $crate::wire::wire_ser_field!(value, $ty $(, $($with)::+)?)),]
            [$($de_arms)* $idx => $crate::wire::wire_de_newtype!(
                $var_access, Target::$var, $ty $(, $($with)::+)?),]
            [$($place_arms)* $idx => {
                // The field is read first, then the variant built where it goes.
                let value = $crate::wire::wire_de_newtype!(
                    $var_access, ::core::convert::identity, $ty $(, $($with)::+)?)?;
                *$place = Target::$var(value);
                Ok(())
            }]
            [$($text)* $var($ty),]
            [$($schema)* $crate::wire::VariantSchema {
                index: $idx, name: stringify!($var),
                fields: $crate::wire::FieldsSchema::Newtype(stringify!($ty)) },]
            $($($rest)*)?
        );
    };

    // A struct variant.
    (@munch $head:tt [$ser:ident $var_access:ident $place:ident]
        [$($decl:tt)*] [$($ser_arms:tt)*] [$($de_arms:tt)*] [$($place_arms:tt)*] [$($text:tt)*]
        [$($schema:tt)*]
        $(#[$vattr:meta])* $idx:literal => $var:ident {
            $( $(#[$fattr:meta])* $field:ident : $fty:ty $(as $($with:ident)::+)? ),* $(,)?
        }
        $(, $($rest:tt)*)?
    ) => {
        $crate::wire::wire_enum!(@munch $head [$ser $var_access $place]
            [$($decl)* $(#[$vattr])* $var { $( $(#[$fattr])* $field: $fty, )* },]
            [$($ser_arms)* Self::$var { $($field),* } => {
                let mut fields = ::serde::Serializer::serialize_struct_variant(
                    $ser, NAME, $idx, stringify!($var), <[&str]>::len(&[$(stringify!($field)),*]))?;
                $(
                    $crate::wire::variant_field(
                        &mut fields,
                        stringify!($field),
                        $crate::wire::wire_ser_field!($field, $fty $(, $($with)::+)?),
                    )?;
                )*
                return ::serde::ser::SerializeStructVariant::end(fields);
            }]
            [$($de_arms)* $idx => $crate::wire::wire_de_struct!(
                $var_access, $var, $( $field: $fty $(as $($with)::+)? ),*),]
            [$($place_arms)* $idx => {
                // Built whole, then stored in place: one copy of the enum.
                *$place = $crate::wire::wire_de_struct!(
                    $var_access, $var, $( $field: $fty $(as $($with)::+)? ),*)?;
                Ok(())
            }]
            [$($text)* $var { $($field: $fty,)* },]
            [$($schema)* $crate::wire::VariantSchema {
                index: $idx, name: stringify!($var),
                fields: $crate::wire::FieldsSchema::Struct(&[$($crate::wire::FieldSchema {
                    name: stringify!($field), ty: stringify!($fty) }),*]) },]
            $($($rest)*)?
        );
    };

    // All variants read: the enum and its serde implementations.
    (@munch [$(#[$attr:meta])* $vis:vis $name:ident] [$ser:ident $var_access:ident $place:ident]
        [$($decl:tt)*] [$($ser_arms:tt)*] [$($de_arms:tt)*] [$($place_arms:tt)*] [$($text:tt)*]
        [$($schema:tt)*]
    ) => {
        $(#[$attr])*
        $vis enum $name {
            $($decl)*
        }

        impl $name {
            /// The variants as declared, in declaration order: their wire indices, names and
            /// fields (the machine-readable schema, `quad_protocol::schema`).
            pub const VARIANTS: &'static [$crate::wire::VariantSchema] = &[$($schema)*];
        }

        const _: () = {
            const NAME: &str = stringify!($name);
            type Target = $name;

            // The text form (see the module docs): serde's derive of the same variants and
            // fields, reading and writing this type in place (`remote`), no copy of it.
            #[cfg(feature = "text")]
            #[derive(::serde::Serialize, ::serde::Deserialize)]
            #[serde(remote = "Target", rename_all = "snake_case", deny_unknown_fields)]
            enum Text {
                $($text)*
            }

            impl ::serde::Serialize for $name {
                // The unit variants share one call, their index looked up first: one such call
                // per enum instead of one per variant (an enum without unit variants never
                // gets there).
                #[allow(unreachable_code)]
                fn serialize<S: ::serde::Serializer>(&self, $ser: S) -> Result<S::Ok, S::Error> {
                    #[cfg(feature = "text")]
                    if ::serde::Serializer::is_human_readable(&$ser) {
                        return Text::serialize(self, $ser);
                    }
                    let (index, variant): (u32, &'static str) = match self {
                        $($ser_arms)*
                    };
                    ::serde::Serializer::serialize_unit_variant($ser, NAME, index, variant)
                }
            }

            impl<'de> ::serde::Deserialize<'de> for $name {
                fn deserialize<D: ::serde::Deserializer<'de>>(d: D) -> Result<Self, D::Error> {
                    #[cfg(feature = "text")]
                    if ::serde::Deserializer::is_human_readable(&d) {
                        return Text::deserialize(d);
                    }
                    struct Variants;
                    impl<'de> ::serde::de::Visitor<'de> for Variants {
                        type Value = $name;
                        fn expecting(
                            &self,
                            f: &mut ::core::fmt::Formatter<'_>,
                        ) -> ::core::fmt::Result {
                            f.write_str(concat!("enum ", stringify!($name)))
                        }
                        // Out of line: see `variant_index`.
                        #[inline(never)]
                        fn visit_enum<A: ::serde::de::EnumAccess<'de>>(
                            self,
                            data: A,
                        ) -> Result<$name, A::Error> {
                            let (index, $var_access) = $crate::wire::variant_index(data)?;
                            match index {
                                $($de_arms)*
                                other => Err(::serde::de::Error::invalid_value(
                                    ::serde::de::Unexpected::Unsigned(u64::from(other)),
                                    &self,
                                )),
                            }
                        }
                    }
                    // postcard does not read the names; they serve self-describing formats'
                    // error messages only.
                    ::serde::Deserializer::deserialize_enum(d, NAME, &[], Variants)
                }

                // Into `place`: the variant is built where it goes, not returned through a
                // `Result` and then moved (a newtype variant's field is the only value moved,
                // a struct variant's whole value once). What a receiver that keeps its
                // decoded message in place uses (`frame::Accumulator::feed_in_place`); the
                // bytes read are the same as `deserialize`'s.
                fn deserialize_in_place<D: ::serde::Deserializer<'de>>(
                    d: D,
                    place: &mut Self,
                ) -> Result<(), D::Error> {
                    #[cfg(feature = "text")]
                    if ::serde::Deserializer::is_human_readable(&d) {
                        *place = Text::deserialize(d)?;
                        return Ok(());
                    }
                    struct InPlace<'p>(&'p mut $name);
                    impl<'de> ::serde::de::Visitor<'de> for InPlace<'_> {
                        type Value = ();
                        fn expecting(
                            &self,
                            f: &mut ::core::fmt::Formatter<'_>,
                        ) -> ::core::fmt::Result {
                            f.write_str(concat!("enum ", stringify!($name)))
                        }
                        // Out of line, as `Variants::visit_enum`.
                        #[inline(never)]
                        fn visit_enum<A: ::serde::de::EnumAccess<'de>>(
                            self,
                            data: A,
                        ) -> Result<(), A::Error> {
                            let (index, $var_access) = $crate::wire::variant_index(data)?;
                            let $place = &mut *self.0;
                            match index {
                                $($place_arms)*
                                other => Err(::serde::de::Error::invalid_value(
                                    ::serde::de::Unexpected::Unsigned(u64::from(other)),
                                    &self,
                                )),
                            }
                        }
                    }
                    ::serde::Deserializer::deserialize_enum(d, NAME, &[], InPlace(place))
                }
            }
        };
    };
}

/// Writes the wire table of a foreign field-less enum as a module: `index`, `from_index`, and
/// `serialize`/`deserialize` for serde's `with` and `wire_enum!`'s `as`.
macro_rules! wire_index {
    (
        $(#[$attr:meta])*
        $vis:vis mod $module:ident for $ty:ident {
            $($idx:literal => $var:ident),+ $(,)?
        }
    ) => {
        $(#[$attr])*
        $vis mod $module {
            use super::$ty;

            /// The variants as declared: their wire indices and names (the machine-readable
            /// schema, `quad_protocol::schema`).
            pub const VARIANTS: &[$crate::wire::VariantSchema] = &[$($crate::wire::VariantSchema {
                index: $idx,
                name: stringify!($var),
                fields: $crate::wire::FieldsSchema::Unit,
            }),+];

            /// The wire index of `value`.
            pub const fn index(value: &$ty) -> u32 {
                match value {
                    $($ty::$var => $idx,)+
                }
            }

            /// The value of wire index `index`; `None` when no variant has it.
            pub const fn from_index(index: u32) -> Option<$ty> {
                match index {
                    $($idx => Some($ty::$var),)+
                    _ => None,
                }
            }

            /// Serializes `value` as its wire index (serde's `with`).
            ///
            /// # Errors
            /// The serializer's.
            pub fn serialize<S: ::serde::Serializer>(value: &$ty, s: S) -> Result<S::Ok, S::Error> {
                let name = match value {
                    $($ty::$var => stringify!($var),)+
                };
                s.serialize_unit_variant(stringify!($ty), index(value), name)
            }

            /// Deserializes a value from its wire index (serde's `with`), or from its name in a
            /// human-readable format (feature `text`).
            ///
            /// # Errors
            /// The deserializer's, or an invalid value for an index no variant has.
            pub fn deserialize<'de, D: ::serde::Deserializer<'de>>(d: D) -> Result<$ty, D::Error> {
                // The text form (module docs) reads the name `serialize` writes: kin-core's
                // own serde form of the type.
                #[cfg(feature = "text")]
                if ::serde::Deserializer::is_human_readable(&d) {
                    return <$ty as ::serde::Deserialize>::deserialize(d);
                }
                struct Variants;
                impl<'de> ::serde::de::Visitor<'de> for Variants {
                    type Value = $ty;
                    fn expecting(&self, f: &mut ::core::fmt::Formatter<'_>) -> ::core::fmt::Result {
                        f.write_str(concat!("enum ", stringify!($ty)))
                    }
                    fn visit_enum<A: ::serde::de::EnumAccess<'de>>(
                        self,
                        data: A,
                    ) -> Result<$ty, A::Error> {
                        let (i, variant) = $crate::wire::variant_index(data)?;
                        ::serde::de::VariantAccess::unit_variant(variant)?;
                        from_index(i).ok_or_else(|| {
                            ::serde::de::Error::invalid_value(
                                ::serde::de::Unexpected::Unsigned(u64::from(i)),
                                &self,
                            )
                        })
                    }
                }
                d.deserialize_enum(stringify!($ty), &[], Variants)
            }
        }
    };
}

/// Writes the field order of a foreign struct as a module with `serialize`/`deserialize` for
/// serde's `with` and `wire_enum!`'s `as`: the fields in the listed order.
macro_rules! wire_fields {
    (
        $(#[$attr:meta])*
        $vis:vis mod $module:ident for $ty:ident {
            $($field:ident : $fty:ty),+ $(,)?
        }
    ) => {
        $(#[$attr])*
        $vis mod $module {
            use super::$ty;

            const FIELDS: &[&str] = &[$(stringify!($field)),+];

            /// Serializes `value`'s fields in the wire order (serde's `with`).
            ///
            /// # Errors
            /// The serializer's.
            pub fn serialize<S: ::serde::Serializer>(value: &$ty, s: S) -> Result<S::Ok, S::Error> {
                use ::serde::ser::SerializeStruct;
                // Exhaustive: a field added to the type does not compile here.
                let $ty { $($field),+ } = value;
                let mut out = s.serialize_struct(stringify!($ty), FIELDS.len())?;
                $(out.serialize_field(stringify!($field), $field)?;)+
                out.end()
            }

            /// Deserializes the fields in the wire order (serde's `with`).
            ///
            /// # Errors
            /// The deserializer's.
            pub fn deserialize<'de, D: ::serde::Deserializer<'de>>(d: D) -> Result<$ty, D::Error> {
                struct Fields;
                impl<'de> ::serde::de::Visitor<'de> for Fields {
                    type Value = $ty;
                    fn expecting(&self, f: &mut ::core::fmt::Formatter<'_>) -> ::core::fmt::Result {
                        f.write_str(concat!("struct ", stringify!($ty)))
                    }
                    // The count after the last field is not read.
                    #[allow(unused_assignments)]
                    fn visit_seq<A: ::serde::de::SeqAccess<'de>>(
                        self,
                        mut seq: A,
                    ) -> Result<$ty, A::Error> {
                        let mut n = 0usize;
                        $(let $field = $crate::wire::wire_next_field!(seq, n, &self, $fty);)+
                        Ok($ty { $($field),+ })
                    }
                }
                d.deserialize_struct(stringify!($ty), FIELDS, Fields)
            }
        }
    };
}

/// Reads the field of a one-field tuple variant (of type `$ty`, through the table `$with` when
/// one is named) from the variant access `$access` and wraps it in `$ctor`.
macro_rules! wire_de_newtype {
    ($access:ident, $ctor:path, $ty:ty) => {
        ::serde::de::VariantAccess::newtype_variant::<$ty>($access).map($ctor)
    };
    ($access:ident, $ctor:path, $ty:ty, $($with:ident)::+) => {{
        struct With($ty);
        impl<'de> ::serde::Deserialize<'de> for With {
            fn deserialize<D: ::serde::Deserializer<'de>>(d: D) -> Result<Self, D::Error> {
                $($with)::+::deserialize(d).map(With)
            }
        }
        ::serde::de::VariantAccess::newtype_variant::<With>($access).map(|w| $ctor(w.0))
    }};
}

/// Reads the fields of struct variant `$var` (each through the table `$with` when one is named)
/// from the variant access `$access`: a `Result` of `Target`, the enum `wire_enum!` declares.
macro_rules! wire_de_struct {
    ($access:ident, $var:ident, $( $field:ident : $fty:ty $(as $($with:ident)::+)? ),*) => {{
        struct Fields;
        impl<'de> ::serde::de::Visitor<'de> for Fields {
            type Value = Target;
            fn expecting(&self, f: &mut ::core::fmt::Formatter<'_>) -> ::core::fmt::Result {
                f.write_str(concat!("the fields of ", stringify!($var)))
            }
            // The count after the last field is not read.
            #[allow(unused_assignments)]
            fn visit_seq<A: ::serde::de::SeqAccess<'de>>(
                self,
                mut seq: A,
            ) -> Result<Target, A::Error> {
                let mut n = 0usize;
                $( let $field = $crate::wire::wire_next_field!(seq, n, &self, $fty $(, $($with)::+)?); )*
                Ok(Target::$var { $($field),* })
            }
        }
        ::serde::de::VariantAccess::struct_variant($access, &[$(stringify!($field)),*], Fields)
    }};
}

pub(crate) use {wire_de_newtype, wire_de_struct, wire_enum, wire_next_field, wire_ser_field};

/// [`serde::de::EnumAccess::variant`] with a `u32` index, out of line: inlined, every enum's
/// decoder carried its own copy of the format's index code (postcard's varint). With that
/// code shared, LTO inlines the decoders into one another, and a message's variants, their
/// fields and the enums within them made one function whose stack frame held all of them,
/// beyond the AVR's 63-byte displacement; `wire_enum!` keeps each enum's `visit_enum` out of
/// line for that reason (its variants' fields inlined into it: smaller than each variant out
/// of line, whose field count the callee no longer knows).
#[inline(never)]
pub(crate) fn variant_index<'de, A: serde::de::EnumAccess<'de>>(
    data: A,
) -> Result<(u32, A::Variant), A::Error> {
    data.variant::<u32>()
}

/// [`serde::ser::SerializeStructVariant::serialize_field`], out of line: one instance per
/// field type and format serves every variant that has such a field (the sequence number of
/// every answer, the readback of three of them); inlined, each variant carried its own copy.
/// (The reading side gains nothing from the same: its fields are read in out-of-line
/// `visit_seq`s already, and wrapped they grew.)
#[inline(never)]
pub(crate) fn variant_field<S: serde::ser::SerializeStructVariant, T: serde::Serialize + ?Sized>(
    fields: &mut S,
    key: &'static str,
    value: &T,
) -> Result<(), S::Error> {
    fields.serialize_field(key, value)
}

/// A field's serde code out of line, for serde's `with` and `wire_enum!`'s `as`: the bytes are
/// the field type's own. For the varint integers (`u16`): postcard's varint reader inlined
/// into every struct that has such a field was the larger part of its decoder on the AVR; out
/// of line one copy per type serves them all.
pub mod shared {
    use serde::{Deserialize, Deserializer, Serialize, Serializer};

    /// `value`'s own serialization, out of line (serde's `with`).
    ///
    /// # Errors
    /// The serializer's.
    #[inline(never)]
    pub fn serialize<S: Serializer, T: Serialize>(value: &T, s: S) -> Result<S::Ok, S::Error> {
        value.serialize(s)
    }

    /// `T`'s own deserialization, out of line (serde's `with`).
    ///
    /// # Errors
    /// The deserializer's.
    #[inline(never)]
    pub fn deserialize<'de, D: Deserializer<'de>, T: Deserialize<'de>>(
        d: D,
    ) -> Result<T, D::Error> {
        T::deserialize(d)
    }
}

/// A field at the end of an answer that only a peer of a later minor receives (serde's `with`
/// and `wire_enum!`'s `as`; [`crate::DeviceToHost::MotionAck`]'s `frames` since 2.3): `None`
/// writes no byte at all — the answer is byte for byte the older one — and `Some(value)` writes
/// `value` (no option tag). Reading, the field is `None` when the message ends before it.
///
/// A device sends the field exactly when the negotiated minor has it, so a decoder that knows
/// the minor knows whether the bytes are there; this one does not need to. Only the last field
/// of a message may be trailing.
pub mod trailing {
    use serde::{Deserialize, Deserializer, Serialize, Serializer};

    /// Writes nothing for `None`, the value itself for `Some` (serde's `with`).
    ///
    /// # Errors
    /// The serializer's.
    pub fn serialize<S: Serializer, T: Serialize>(
        value: &Option<T>,
        s: S,
    ) -> Result<S::Ok, S::Error> {
        match value {
            Some(v) => v.serialize(s),
            None => s.serialize_unit(),
        }
    }

    /// Reads the value when the message goes on, `None` when it has ended (serde's `with`).
    ///
    /// # Errors
    /// None from postcard: a message that ends early reads as `None`.
    pub fn deserialize<'de, D: Deserializer<'de>, T: Deserialize<'de>>(
        d: D,
    ) -> Result<Option<T>, D::Error> {
        Ok(T::deserialize(d).ok())
    }
}

/// Arrays on the wire, for serde's `with` and `wire_enum!`'s `as`: a tuple of `N` elements,
/// the data model of serde's own `[T; N]` implementations (postcard: the elements one after
/// the other, no length), so the bytes are the same. serde reads an array with one unrolled
/// copy of the element code per element; here one loop serves all elements, which on the
/// ATmega2560 is a fraction of the flash for the twelve-value arrays.
pub mod array {
    use core::fmt;
    use core::marker::PhantomData;
    use serde::de::{self, Deserializer, SeqAccess, Visitor};
    use serde::ser::{SerializeTuple, Serializer};
    use serde::{Deserialize, Serialize};

    /// Serializes `value` as a tuple of its `N` elements (serde's `with`).
    ///
    /// # Errors
    /// The serializer's.
    pub fn serialize<S: Serializer, T: Serialize, const N: usize>(
        value: &[T; N],
        s: S,
    ) -> Result<S::Ok, S::Error> {
        let mut tuple = s.serialize_tuple(N)?;
        for element in value {
            tuple.serialize_element(element)?;
        }
        tuple.end()
    }

    /// Deserializes a tuple of `N` elements (serde's `with`).
    ///
    /// # Errors
    /// The deserializer's, or an invalid length when the input ends early.
    pub fn deserialize<'de, D, T, const N: usize>(d: D) -> Result<[T; N], D::Error>
    where
        D: Deserializer<'de>,
        T: Deserialize<'de> + Copy + Default,
    {
        struct Elements<T, const N: usize>(PhantomData<T>);
        impl<'de, T: Deserialize<'de> + Copy + Default, const N: usize> Visitor<'de> for Elements<T, N> {
            type Value = [T; N];
            fn expecting(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
                write!(f, "an array of length {N}")
            }
            fn visit_seq<A: SeqAccess<'de>>(self, mut seq: A) -> Result<[T; N], A::Error> {
                let mut out = [T::default(); N];
                for (i, slot) in out.iter_mut().enumerate() {
                    *slot = seq
                        .next_element()?
                        .ok_or_else(|| de::Error::invalid_length(i, &self))?;
                }
                Ok(out)
            }
        }
        d.deserialize_tuple(N, Elements::<T, N>(PhantomData))
    }
}

wire_index! {
    /// [`LegId`] on the wire.
    pub mod leg_id for LegId { 0 => FL, 1 => FR, 2 => RL, 3 => RR }
}

wire_index! {
    /// [`Joint`] on the wire.
    pub mod joint for Joint { 0 => Abduction, 1 => Hip, 2 => Knee }
}

wire_index! {
    /// [`RotationOrder`] on the wire.
    pub mod rotation_order for RotationOrder {
        0 => Xyz, 1 => Xzy, 2 => Yxz, 3 => Yzx, 4 => Zxy, 5 => Zyx,
    }
}

wire_index! {
    /// [`ReachPolicy`] on the wire.
    pub mod reach_policy for ReachPolicy { 0 => Reject, 1 => Clamp }
}

wire_index! {
    /// [`Axis`] of a sway on the wire.
    pub mod sway_axis for Axis { 0 => Roll, 1 => Pitch, 2 => Yaw }
}

wire_index! {
    /// [`PathKind`] on the wire.
    pub mod path_kind for PathKind {
        0 => Rectangle, 1 => Semicircle, 2 => Ellipse, 3 => Cycloid, 4 => Bezier,
    }
}

wire_index! {
    /// A gait [`Pattern`] on the wire.
    pub mod gait_pattern for Pattern { 0 => Trot, 1 => Walk }
}

wire_index! {
    /// [`KneeBend`] on the wire (since 2.4).
    pub mod knee_bend for KneeBend { 0 => Backward, 1 => Forward }
}

/// A kin-core [`kin_core::Robot`] on the wire (since 2.4, in [`crate::RobotDescription`]), for serde's
/// `with`: the fields `d_lat_m`, `d_ax_m`, `femur_m`, `tibia_m`, `body_length_m`,
/// `body_width_m`, the three minima and the three maxima of the joint limits (abduction, hip,
/// knee), all f32, then the knee bend ([`knee_bend`]). In the text form (feature `text`)
/// kin-core's own serde form.
pub mod robot {
    use kin_core::{JointLimits, LegGeometry, Robot};
    use serde::de::{self, Deserializer, SeqAccess, Visitor};
    use serde::ser::{SerializeStruct, Serializer};

    /// The fields in wire order: twelve lengths and limits, the knee bend.
    const FIELDS: [&str; 13] = [
        "d_lat_m",
        "d_ax_m",
        "femur_m",
        "tibia_m",
        "body_length_m",
        "body_width_m",
        "min_abduction_rad",
        "min_hip_rad",
        "min_knee_rad",
        "max_abduction_rad",
        "max_hip_rad",
        "max_knee_rad",
        "knee_bend",
    ];

    /// The twelve numbers in wire order.
    fn numbers(r: &Robot) -> [f32; 12] {
        let (l, lim) = (&r.leg, &r.limits);
        [
            l.d_lat_m,
            l.d_ax_m,
            l.femur_m,
            l.tibia_m,
            r.body_length_m,
            r.body_width_m,
            lim.min_rad[0],
            lim.min_rad[1],
            lim.min_rad[2],
            lim.max_rad[0],
            lim.max_rad[1],
            lim.max_rad[2],
        ]
    }

    /// Serializes `robot` in the wire order (serde's `with`).
    ///
    /// # Errors
    /// The serializer's.
    pub fn serialize<S: Serializer>(robot: &Robot, s: S) -> Result<S::Ok, S::Error> {
        #[cfg(feature = "text")]
        if s.is_human_readable() {
            return ::serde::Serialize::serialize(robot, s);
        }
        let mut t = s.serialize_struct("Robot", FIELDS.len())?;
        for (name, v) in FIELDS.iter().zip(numbers(robot)) {
            t.serialize_field(name, &v)?;
        }
        t.serialize_field(
            FIELDS[12],
            super::wire_ser_field!(&robot.knee_bend, kin_core::KneeBend, super::knee_bend),
        )?;
        t.end()
    }

    /// Deserializes a robot in the wire order (serde's `with`).
    ///
    /// # Errors
    /// The deserializer's, or an invalid length when the input ends early.
    pub fn deserialize<'de, D: Deserializer<'de>>(d: D) -> Result<Robot, D::Error> {
        #[cfg(feature = "text")]
        if d.is_human_readable() {
            return <Robot as ::serde::Deserialize>::deserialize(d);
        }
        struct Fields;
        impl<'de> Visitor<'de> for Fields {
            type Value = Robot;
            fn expecting(&self, f: &mut core::fmt::Formatter<'_>) -> core::fmt::Result {
                f.write_str("a robot")
            }
            fn visit_seq<A: SeqAccess<'de>>(self, mut seq: A) -> Result<Robot, A::Error> {
                let mut v = [0.0f32; 12];
                for (i, slot) in v.iter_mut().enumerate() {
                    *slot = seq
                        .next_element()?
                        .ok_or_else(|| de::Error::invalid_length(i, &self))?;
                }
                let mut n = 12usize;
                let knee_bend =
                    super::wire_next_field!(seq, n, &self, kin_core::KneeBend, super::knee_bend);
                let _ = n;
                Ok(Robot {
                    leg: LegGeometry {
                        d_lat_m: v[0],
                        d_ax_m: v[1],
                        femur_m: v[2],
                        tibia_m: v[3],
                    },
                    body_length_m: v[4],
                    body_width_m: v[5],
                    limits: JointLimits {
                        min_rad: [v[6], v[7], v[8]],
                        max_rad: [v[9], v[10], v[11]],
                    },
                    knee_bend,
                })
            }
        }
        d.deserialize_struct("Robot", &FIELDS, Fields)
    }
}

wire_fields! {
    /// [`Pose`] on the wire: roll, pitch, yaw (rad), then x, y, z (m).
    pub mod pose for Pose {
        roll_rad: f32,
        pitch_rad: f32,
        yaw_rad: f32,
        x_m: f32,
        y_m: f32,
        z_m: f32,
    }
}

#[cfg(test)]
mod tests {
    //! Every variant of every enum nested in the messages, by an exhaustive `match` per enum
    //! (here, inside the crate, the `#[non_exhaustive]` ones too: a variant added without a
    //! case does not compile), has the index written here at its place in the postcard bytes,
    //! round-trips through the frame encoder and the accumulator the device uses, and the
    //! index after the last is refused.
    extern crate std;
    use super::*;
    use crate::frame::{encode_frame, Accumulator, Feed, MAX_DECODED_LEN, MAX_FRAME_LEN};
    use crate::msg::{
        DeviceInfo, DeviceToHost, Field, FirmwareVersion, Flags, HostToDevice, LegSet,
        LinkLossAction, LinkTimeout, MotionCommand, MotionKind, MotionParam, MotionStage,
        MotionStatus, NackReason, ParamProblem, PoseConfig, PreflightFault, ReachFault, Readback,
        Request, RobotPreset, ServoId, Setting,
    };
    use crate::servo;
    use serde::de::DeserializeOwned;
    use serde::Serialize;
    use std::vec::Vec;

    fn nack_index(n: &NackReason) -> u8 {
        match n {
            NackReason::UnknownVersion { .. } => 0,
            NackReason::BadCrc => 1,
            NackReason::BadFrame => 2,
            NackReason::Oversize => 3,
            NackReason::HelloRequired => 4,
            NackReason::Unreachable { .. } => 5,
            NackReason::JointLimit { .. } => 6,
            NackReason::ServoRange { .. } => 7,
            NackReason::NonFinite => 8,
            NackReason::BadCalibration(_) => 9,
            NackReason::Busy => 10,
            NackReason::OutputsDisabled => 11,
            NackReason::Storage => 12,
            NackReason::InvalidArgument => 13,
            NackReason::OutOfRange { .. } => 14,
            NackReason::InvalidParameter { .. } => 15,
            NackReason::Preflight { .. } => 16,
            NackReason::MotionRunning => 17,
            NackReason::NotWalking => 18,
            NackReason::ImuAbsent => 19,
            NackReason::ImuFault(_) => 20,
            NackReason::NotUpright => 21,
            NackReason::BadRobot(_) => 22,
            NackReason::OutputsEnabled => 23,
        }
    }

    fn field_index(f: &Field) -> u8 {
        match f {
            Field::BodyRoll => 0,
            Field::BodyPitch => 1,
            Field::BodyYaw => 2,
            Field::BodyX => 3,
            Field::BodyY => 4,
            Field::BodyZ => 5,
            Field::Foot(_) => 6,
            Field::JointAngle { .. } => 7,
            Field::StanceHeight => 8,
        }
    }

    fn setting_index(s: &Setting) -> u8 {
        match s {
            Setting::LinkTimeout(_) => 0,
            Setting::PoseConfig(_) => 1,
            Setting::Calibration { .. } => 2,
        }
    }

    fn motion_command_index(m: &MotionCommand) -> u8 {
        match m {
            MotionCommand::StandUp => 0,
            MotionCommand::Sit => 1,
            MotionCommand::Rest => 2,
            MotionCommand::Sway { .. } => 3,
            MotionCommand::YawTurn { .. } => 4,
            MotionCommand::FootPath { .. } => 5,
            MotionCommand::Walk { .. } => 6,
            MotionCommand::StableTurn { .. } => 7,
        }
    }

    fn leg_set_index(l: &LegSet) -> u8 {
        match l {
            LegSet::All => 0,
            LegSet::One(_) => 1,
        }
    }

    fn motion_kind_index(k: &MotionKind) -> u8 {
        match k {
            MotionKind::StandUp => 0,
            MotionKind::Sit => 1,
            MotionKind::Rest => 2,
            MotionKind::Sway => 3,
            MotionKind::YawTurn => 4,
            MotionKind::FootPath => 5,
            MotionKind::Walk => 6,
            MotionKind::StableTurn => 7,
        }
    }

    fn motion_stage_index(s: &MotionStage) -> u8 {
        match s {
            MotionStage::Approach => 0,
            MotionStage::Run => 1,
            MotionStage::Stopping => 2,
            MotionStage::Leave => 3,
            MotionStage::Idle => 4,
        }
    }

    fn motion_param_index(p: &MotionParam) -> u8 {
        match p {
            MotionParam::AmplitudeRad => 0,
            MotionParam::PeriodS => 1,
            MotionParam::DurationS => 2,
            MotionParam::YawRateRadS => 3,
            MotionParam::StepPeriodS => 4,
            MotionParam::LiftHeightM => 5,
            MotionParam::StrideM => 6,
            MotionParam::StepHeightM => 7,
            MotionParam::DutyFactor => 8,
            MotionParam::CycleS => 9,
            MotionParam::Path => 10,
            MotionParam::BodyHeightM => 11,
            MotionParam::VelocityTimeoutMs => 12,
            MotionParam::ForwardMS => 13,
            MotionParam::LateralMS => 14,
            MotionParam::Velocity => 15,
            MotionParam::JointSpeedLimitRadS => 16,
            MotionParam::Stance => 17,
            MotionParam::ReachRadiusM => 18,
            MotionParam::Other => 19,
            MotionParam::LevelKp => 20,
            MotionParam::LevelKiPerS => 21,
            MotionParam::MaxCorrectionRad => 22,
            MotionParam::FallAngleRad => 23,
            MotionParam::YawPerCycleRad => 24,
            MotionParam::ShiftFraction => 25,
        }
    }

    fn param_problem_index(p: &ParamProblem) -> u8 {
        match p {
            ParamProblem::NonFinite => 0,
            ParamProblem::NotPositive => 1,
            ParamProblem::Negative => 2,
            ParamProblem::OutOfRange => 3,
            ParamProblem::BeyondReach => 4,
        }
    }

    fn preflight_fault_index(f: &PreflightFault) -> u8 {
        match f {
            PreflightFault::Reach(_) => 0,
            PreflightFault::JointLimit(_) => 1,
            PreflightFault::Singular => 2,
            PreflightFault::NonFinite => 3,
            PreflightFault::Other => 4,
        }
    }

    fn axis_index(a: &Axis) -> u8 {
        match a {
            Axis::Roll => 0,
            Axis::Pitch => 1,
            Axis::Yaw => 2,
        }
    }

    fn path_kind_index(p: &PathKind) -> u8 {
        match p {
            PathKind::Rectangle => 0,
            PathKind::Semicircle => 1,
            PathKind::Ellipse => 2,
            PathKind::Cycloid => 3,
            PathKind::Bezier => 4,
        }
    }

    fn pattern_index(p: &Pattern) -> u8 {
        match p {
            Pattern::Trot => 0,
            Pattern::Walk => 1,
        }
    }

    fn servo_error_index(e: &servo::Error) -> u8 {
        match e {
            servo::Error::NonFiniteAngle => 0,
            servo::Error::BelowMin => 1,
            servo::Error::AboveMax => 2,
            servo::Error::BadZero => 3,
            servo::Error::BadGain => 4,
            servo::Error::BadBounds => 5,
            servo::Error::CenterOutOfBounds => 6,
        }
    }

    fn reach_fault_index(f: &ReachFault) -> u8 {
        match f {
            ReachFault::TooFar => 0,
            ReachFault::TooClose => 1,
            ReachFault::InsideOffset => 2,
            ReachFault::Other => 3,
        }
    }

    fn link_loss_index(a: &LinkLossAction) -> u8 {
        match a {
            LinkLossAction::Hold => 0,
            LinkLossAction::Disable => 1,
        }
    }

    fn preset_index(p: &RobotPreset) -> u8 {
        match p {
            RobotPreset::Shahriar2023 => 0,
            RobotPreset::Fernando2025 => 1,
            RobotPreset::Custom => 2,
        }
    }

    fn leg_index(l: &LegId) -> u8 {
        match l {
            LegId::FL => 0,
            LegId::FR => 1,
            LegId::RL => 2,
            LegId::RR => 3,
        }
    }

    fn joint_index(j: &Joint) -> u8 {
        match j {
            Joint::Abduction => 0,
            Joint::Hip => 1,
            Joint::Knee => 2,
        }
    }

    fn order_index(o: &RotationOrder) -> u8 {
        match o {
            RotationOrder::Xyz => 0,
            RotationOrder::Xzy => 1,
            RotationOrder::Yxz => 2,
            RotationOrder::Yzx => 3,
            RotationOrder::Zxy => 4,
            RotationOrder::Zyx => 5,
        }
    }

    fn policy_index(p: &ReachPolicy) -> u8 {
        match p {
            ReachPolicy::Reject => 0,
            ReachPolicy::Clamp => 1,
        }
    }

    /// `msg` has `index` at byte `at` of its postcard bytes and round-trips through a frame;
    /// with `past` in its place it does not decode (an unknown variant).
    fn check<T: Serialize + DeserializeOwned + PartialEq + core::fmt::Debug>(
        msg: T,
        at: usize,
        index: u8,
        past: u8,
    ) {
        let mut buf = [0u8; MAX_DECODED_LEN];
        let mut bytes = postcard::to_slice(&msg, &mut buf).unwrap().to_vec();
        assert_eq!(bytes[at], index, "index of {msg:?} in {bytes:02x?}");
        let mut out = [0u8; MAX_FRAME_LEN];
        let frame = encode_frame(&msg, &mut out).unwrap();
        match Accumulator::<MAX_DECODED_LEN>::new().feed::<T>(frame) {
            Feed::Frame { msg: back, .. } => assert_eq!(back, msg),
            other => panic!("{msg:?}: {other:?}"),
        }
        bytes[at] = past;
        assert_eq!(
            postcard::from_bytes::<T>(&bytes).err(),
            Some(postcard::Error::SerdeDeCustom),
            "index {past} after the last of {msg:?}"
        );
    }

    fn nack(reason: NackReason) -> DeviceToHost {
        DeviceToHost::Nack { seq: None, reason }
    }

    #[test]
    fn every_nested_variant_has_its_index_and_round_trips() {
        let errors = [
            servo::Error::NonFiniteAngle,
            servo::Error::BelowMin,
            servo::Error::AboveMax,
            servo::Error::BadZero,
            servo::Error::BadGain,
            servo::Error::BadBounds,
            servo::Error::CenterOutOfBounds,
        ];
        let faults = [
            ReachFault::TooFar,
            ReachFault::TooClose,
            ReachFault::InsideOffset,
            ReachFault::Other,
        ];
        let reasons: Vec<NackReason> = [
            NackReason::UnknownVersion { supported: 0x0102 },
            NackReason::BadCrc,
            NackReason::BadFrame,
            NackReason::Oversize,
            NackReason::HelloRequired,
            NackReason::Unreachable {
                leg: LegId::FR,
                fault: ReachFault::TooClose,
            },
            NackReason::JointLimit {
                leg: LegId::RR,
                joint: Joint::Knee,
            },
            NackReason::ServoRange {
                leg: LegId::RL,
                joint: Joint::Hip,
                fault: servo::Error::AboveMax,
            },
            NackReason::NonFinite,
            NackReason::BadCalibration(servo::Error::BadGain),
            NackReason::Busy,
            NackReason::OutputsDisabled,
            NackReason::Storage,
            NackReason::InvalidArgument,
            NackReason::OutOfRange {
                field: Field::BodyZ,
            },
            NackReason::InvalidParameter {
                param: MotionParam::DurationS,
                problem: ParamProblem::NonFinite,
            },
            NackReason::Preflight {
                leg: LegId::RL,
                fault: PreflightFault::Singular,
            },
            NackReason::MotionRunning,
            NackReason::NotWalking,
            NackReason::ImuAbsent,
            NackReason::ImuFault(crate::ImuFaultKind::Nak),
            NackReason::NotUpright,
            NackReason::BadRobot(crate::RobotField::Name),
            NackReason::OutputsEnabled,
        ]
        .into();
        // Nack | seq None (00) | reason ...
        for (i, r) in reasons.iter().enumerate() {
            assert_eq!(usize::from(nack_index(r)), i);
            check(nack(*r), 2, i as u8, reasons.len() as u8);
        }
        for (i, e) in errors.iter().enumerate() {
            assert_eq!(usize::from(servo_error_index(e)), i);
            check(nack(NackReason::BadCalibration(*e)), 3, i as u8, 7);
        }
        for (i, fault) in faults.iter().enumerate() {
            assert_eq!(usize::from(reach_fault_index(fault)), i);
            let leg = LegId::FL;
            check(
                nack(NackReason::Unreachable { leg, fault: *fault }),
                4,
                i as u8,
                4,
            );
        }
        for (i, leg) in LegId::ALL.iter().enumerate() {
            assert_eq!(usize::from(leg_index(leg)), i);
            let r = NackReason::JointLimit {
                leg: *leg,
                joint: Joint::Hip,
            };
            check(nack(r), 3, i as u8, 4);
        }
        for (i, joint) in Joint::ALL.iter().enumerate() {
            assert_eq!(usize::from(joint_index(joint)), i);
            let r = NackReason::JointLimit {
                leg: LegId::RR,
                joint: *joint,
            };
            check(nack(r), 4, i as u8, 3);
        }
        for (i, preset) in [
            RobotPreset::Shahriar2023,
            RobotPreset::Fernando2025,
            RobotPreset::Custom,
        ]
        .iter()
        .enumerate()
        {
            assert_eq!(usize::from(preset_index(preset)), i);
            // HelloAck | seq | version (80 02) | firmware (3 bytes) | robot
            let info = DeviceInfo {
                version: 0x0100,
                firmware: FirmwareVersion::default(),
                robot: *preset,
                max_frame_len: 128,
                pose_config: PoseConfig {
                    stance_height_m: 0.25,
                    order: RotationOrder::Zyx,
                    policy: ReachPolicy::Reject,
                },
                link_timeout: LinkTimeout::default(),
                robot_hash: None,
            };
            check(DeviceToHost::HelloAck { seq: 1, info }, 7, i as u8, 3);
        }
        let h2d = |request| HostToDevice { seq: 5, request };
        for (i, action) in [LinkLossAction::Hold, LinkLossAction::Disable]
            .iter()
            .enumerate()
        {
            assert_eq!(usize::from(link_loss_index(action)), i);
            // seq | SetLinkTimeout (06) | timeout 5 | action
            let t = LinkTimeout {
                timeout_ms: 5,
                action: *action,
            };
            check(h2d(Request::SetLinkTimeout(t)), 3, i as u8, 2);
        }
        let orders = [
            RotationOrder::Xyz,
            RotationOrder::Xzy,
            RotationOrder::Yxz,
            RotationOrder::Yzx,
            RotationOrder::Zxy,
            RotationOrder::Zyx,
        ];
        for (i, order) in orders.iter().enumerate() {
            assert_eq!(usize::from(order_index(order)), i);
            // seq | SetPoseConfig (0a) | height f32 | order | policy
            let p = PoseConfig {
                stance_height_m: 0.25,
                order: *order,
                policy: ReachPolicy::Clamp,
            };
            check(h2d(Request::SetPoseConfig(p)), 6, i as u8, 6);
        }
        for (i, policy) in [ReachPolicy::Reject, ReachPolicy::Clamp].iter().enumerate() {
            assert_eq!(usize::from(policy_index(policy)), i);
            let p = PoseConfig {
                stance_height_m: 0.25,
                order: RotationOrder::Zyx,
                policy: *policy,
            };
            check(h2d(Request::SetPoseConfig(p)), 7, i as u8, 2);
        }
        // The tables agree with the tests' indices.
        for leg in LegId::ALL {
            assert_eq!(leg_id::index(&leg), u32::from(leg_index(&leg)));
            assert_eq!(leg_id::from_index(leg_id::index(&leg)), Some(leg));
        }
        assert_eq!(leg_id::from_index(4), None);
        let servo = ServoId {
            leg: LegId::RL,
            joint: Joint::Knee,
        };
        check(h2d(Request::GetCalibration { servo }), 2, 2, 4);

        let fields = [
            Field::BodyRoll,
            Field::BodyPitch,
            Field::BodyYaw,
            Field::BodyX,
            Field::BodyY,
            Field::BodyZ,
            Field::Foot(LegId::RR),
            Field::JointAngle {
                leg: LegId::FR,
                joint: Joint::Knee,
            },
            Field::StanceHeight,
        ];
        for (i, field) in fields.iter().enumerate() {
            assert_eq!(usize::from(field_index(field)), i);
            // Nack | seq None (00) | OutOfRange (0e) | field
            let r = NackReason::OutOfRange { field: *field };
            check(nack(r), 3, i as u8, fields.len() as u8);
        }
        let readback = Readback {
            angles_rad: [0.5; 12],
            pulses_half_us: [3000; 12],
            flags: Flags(Flags::OUTPUTS_ENABLED),
            frames_ok: 3,
            frames_bad: 0,
        };
        let settings = [
            Setting::LinkTimeout(LinkTimeout::default()),
            Setting::PoseConfig(PoseConfig {
                stance_height_m: 0.25,
                order: RotationOrder::Zyx,
                policy: ReachPolicy::Reject,
            }),
            Setting::Calibration {
                servo,
                calibration: servo::Calibration::default(),
            },
        ];
        for (i, setting) in settings.iter().enumerate() {
            assert_eq!(usize::from(setting_index(setting)), i);
            // Configured (04) | seq | setting
            let answer = DeviceToHost::Configured {
                seq: 9,
                setting: *setting,
                readback,
            };
            check(answer, 2, i as u8, settings.len() as u8);
        }
    }

    #[test]
    fn every_motion_variant_has_its_index_and_round_trips() {
        let h2d = |m| HostToDevice {
            seq: 5,
            request: Request::StartMotion(m),
        };
        let sway = |axis| MotionCommand::Sway {
            axis,
            amplitude_rad: 0.2,
            period_s: 20.0,
            duration_s: None,
        };
        let path = |path, legs| MotionCommand::FootPath {
            path,
            legs,
            stride_m: 0.1,
            step_height_m: 0.05,
            duty_factor: 0.75,
            cycle_s: 3.0,
            duration_s: Some(6.0),
        };
        let walk = |gait| MotionCommand::Walk {
            gait,
            body_height_m: 0.25,
            step_height_m: 0.05,
            cycle_s: 0.6,
            velocity_timeout_ms: 500,
        };
        let commands = [
            MotionCommand::StandUp,
            MotionCommand::Sit,
            MotionCommand::Rest,
            sway(Axis::Roll),
            MotionCommand::YawTurn {
                yaw_rate_rad_s: 0.085,
                step_period_s: 6.0,
                lift_height_m: 0.03,
                duration_s: Some(12.0),
            },
            path(PathKind::Rectangle, LegSet::All),
            walk(Pattern::Trot),
            MotionCommand::StableTurn {
                yaw_per_cycle_rad: 0.2,
                cycle_s: 20.0,
                lift_height_m: 0.06,
                shift_fraction: 0.8,
                duration_s: Some(60.0),
            },
        ];
        // seq (05) | StartMotion (0b) | command | fields
        for (i, m) in commands.iter().enumerate() {
            assert_eq!(usize::from(motion_command_index(m)), i);
            check(h2d(*m), 2, i as u8, commands.len() as u8);
        }
        for (i, a) in [Axis::Roll, Axis::Pitch, Axis::Yaw].iter().enumerate() {
            assert_eq!(usize::from(axis_index(a)), i);
            check(h2d(sway(*a)), 3, i as u8, 3);
        }
        let kinds = [
            PathKind::Rectangle,
            PathKind::Semicircle,
            PathKind::Ellipse,
            PathKind::Cycloid,
            PathKind::Bezier,
        ];
        for (i, k) in kinds.iter().enumerate() {
            assert_eq!(usize::from(path_kind_index(k)), i);
            check(h2d(path(*k, LegSet::All)), 3, i as u8, 5);
        }
        for (i, l) in [LegSet::All, LegSet::One(LegId::RR)].iter().enumerate() {
            assert_eq!(usize::from(leg_set_index(l)), i);
            check(h2d(path(PathKind::Ellipse, *l)), 4, i as u8, 2);
        }
        for (i, p) in [Pattern::Trot, Pattern::Walk].iter().enumerate() {
            assert_eq!(usize::from(pattern_index(p)), i);
            check(h2d(walk(*p)), 3, i as u8, 2);
        }
        let readback = Readback {
            angles_rad: [0.5; 12],
            pulses_half_us: [3000; 12],
            flags: Flags(Flags::OUTPUTS_ENABLED),
            frames_ok: 1,
            frames_bad: 0,
        };
        let ack = |kind, stage| DeviceToHost::MotionAck {
            seq: 9,
            status: MotionStatus {
                kind,
                stage,
                t_s: 1.5,
                phase: 0.5,
                fault: None,
            },
            readback,
            frames: None,
        };
        let kinds = [
            MotionKind::StandUp,
            MotionKind::Sit,
            MotionKind::Rest,
            MotionKind::Sway,
            MotionKind::YawTurn,
            MotionKind::FootPath,
            MotionKind::Walk,
            MotionKind::StableTurn,
        ];
        // MotionAck (05) | seq (09) | Some (01) | kind | stage ...
        for (i, k) in kinds.iter().enumerate() {
            assert_eq!(usize::from(motion_kind_index(k)), i);
            check(ack(Some(*k), MotionStage::Run), 3, i as u8, 8);
        }
        let stages = [
            MotionStage::Approach,
            MotionStage::Run,
            MotionStage::Stopping,
            MotionStage::Leave,
            MotionStage::Idle,
        ];
        // MotionAck (05) | seq (09) | None (00) | stage ...
        for (i, s) in stages.iter().enumerate() {
            assert_eq!(usize::from(motion_stage_index(s)), i);
            check(ack(None, *s), 3, i as u8, 5);
        }
        let params = [
            MotionParam::AmplitudeRad,
            MotionParam::PeriodS,
            MotionParam::DurationS,
            MotionParam::YawRateRadS,
            MotionParam::StepPeriodS,
            MotionParam::LiftHeightM,
            MotionParam::StrideM,
            MotionParam::StepHeightM,
            MotionParam::DutyFactor,
            MotionParam::CycleS,
            MotionParam::Path,
            MotionParam::BodyHeightM,
            MotionParam::VelocityTimeoutMs,
            MotionParam::ForwardMS,
            MotionParam::LateralMS,
            MotionParam::Velocity,
            MotionParam::JointSpeedLimitRadS,
            MotionParam::Stance,
            MotionParam::ReachRadiusM,
            MotionParam::Other,
            MotionParam::LevelKp,
            MotionParam::LevelKiPerS,
            MotionParam::MaxCorrectionRad,
            MotionParam::FallAngleRad,
            MotionParam::YawPerCycleRad,
            MotionParam::ShiftFraction,
        ];
        // Nack (00) | None (00) | InvalidParameter (0f) | param | problem
        for (i, p) in params.iter().enumerate() {
            assert_eq!(usize::from(motion_param_index(p)), i);
            let r = NackReason::InvalidParameter {
                param: *p,
                problem: ParamProblem::OutOfRange,
            };
            check(nack(r), 3, i as u8, params.len() as u8);
        }
        let problems = [
            ParamProblem::NonFinite,
            ParamProblem::NotPositive,
            ParamProblem::Negative,
            ParamProblem::OutOfRange,
            ParamProblem::BeyondReach,
        ];
        for (i, p) in problems.iter().enumerate() {
            assert_eq!(usize::from(param_problem_index(p)), i);
            let r = NackReason::InvalidParameter {
                param: MotionParam::CycleS,
                problem: *p,
            };
            check(nack(r), 4, i as u8, 5);
        }
        let faults = [
            PreflightFault::Reach(ReachFault::InsideOffset),
            PreflightFault::JointLimit(Joint::Hip),
            PreflightFault::Singular,
            PreflightFault::NonFinite,
            PreflightFault::Other,
        ];
        // Nack (00) | None (00) | Preflight (10) | leg | fault ...
        for (i, f) in faults.iter().enumerate() {
            assert_eq!(usize::from(preflight_fault_index(f)), i);
            let r = NackReason::Preflight {
                leg: LegId::FR,
                fault: *f,
            };
            check(nack(r), 4, i as u8, 5);
        }
        for (a, i) in [(Axis::Roll, 0), (Axis::Pitch, 1), (Axis::Yaw, 2)] {
            assert_eq!(sway_axis::index(&a), i);
            assert_eq!(sway_axis::from_index(i), Some(a));
        }
        assert_eq!(sway_axis::from_index(3), None);
        assert_eq!(path_kind::from_index(5), None);
        assert_eq!(gait_pattern::from_index(2), None);
    }

    #[test]
    fn every_balance_variant_has_its_index_and_round_trips() {
        use crate::balance::{
            BalanceConfig, FallKind, FaultAction, ImuFaultKind, ImuHealth, ImuReport, SafeState,
        };
        let kinds = [
            ImuFaultKind::WrongId,
            ImuFaultKind::Nak,
            ImuFaultKind::Stuck,
            ImuFaultKind::BusHeld,
        ];
        // Nack (00) | None (00) | ImuFault (14) | kind
        for (i, k) in kinds.iter().enumerate() {
            check(nack(NackReason::ImuFault(*k)), 3, i as u8, 4);
        }
        let report = |health, fall, safe_state, on_fault| DeviceToHost::Imu {
            seq: 1,
            report: ImuReport {
                health,
                roll_rad: 0.0,
                pitch_rad: 0.0,
                correction_roll_rad: 0.0,
                correction_pitch_rad: 0.0,
                leveling_active: false,
                correction_limited: false,
                fall,
                samples: 0,
                config: BalanceConfig {
                    safe_state,
                    on_fault,
                    ..BalanceConfig::DEFAULT
                },
            },
        };
        let (rest, open) = (SafeState::Rest, FaultAction::OpenLoop);
        // Imu (06) | seq (01) | health ...
        let healths = [
            ImuHealth::Absent,
            ImuHealth::Starting,
            ImuHealth::Ok,
            ImuHealth::Fault(ImuFaultKind::Stuck),
        ];
        for (i, h) in healths.iter().enumerate() {
            check(report(*h, None, rest, open), 2, i as u8, 4);
        }
        // … health (02) | 4 × f32 | 2 bools | fall (01) | kind
        for (i, f) in [FallKind::Tilt, FallKind::FreeFall].iter().enumerate() {
            check(report(ImuHealth::Ok, Some(*f), rest, open), 22, i as u8, 2);
        }
        // … fall (00) | samples (00) | leveling, kp, ki, bound, detection, angle | safe state
        for (i, v) in [SafeState::Rest, SafeState::Off].iter().enumerate() {
            check(report(ImuHealth::Ok, None, *v, open), 41, i as u8, 2);
        }
        for (i, a) in [FaultAction::OpenLoop, FaultAction::Stop]
            .iter()
            .enumerate()
        {
            check(report(ImuHealth::Ok, None, rest, *a), 42, i as u8, 2);
        }
        let set = HostToDevice {
            seq: 2,
            request: Request::SetBalance(BalanceConfig::DEFAULT),
        };
        // The index after the last request (2.4's `SaveRobot`, 20) is refused.
        check(set, 1, 16, 21);
        let get = HostToDevice {
            seq: 2,
            request: Request::GetImu,
        };
        check(get, 1, 17, 21);
    }

    #[test]
    fn every_robot_variant_has_its_index_and_round_trips() {
        use crate::robot::{RobotDescription, RobotField};
        use kin_core::{KneeBend, Robot};
        let fields = [
            RobotField::Name,
            RobotField::FemurM,
            RobotField::TibiaM,
            RobotField::DLatM,
            RobotField::DAxM,
            RobotField::BodyLengthM,
            RobotField::BodyWidthM,
            RobotField::Limit(Joint::Knee),
            RobotField::StanceHeightM,
            RobotField::JointSpeedLimitRadS,
            RobotField::RestPose(Joint::Hip),
            RobotField::Stance(LegId::RL),
        ];
        // Nack (00) | None (00) | BadRobot (16) | field
        for (i, f) in fields.iter().enumerate() {
            let index = match f {
                RobotField::Name => 0,
                RobotField::FemurM => 1,
                RobotField::TibiaM => 2,
                RobotField::DLatM => 3,
                RobotField::DAxM => 4,
                RobotField::BodyLengthM => 5,
                RobotField::BodyWidthM => 6,
                RobotField::Limit(_) => 7,
                RobotField::StanceHeightM => 8,
                RobotField::JointSpeedLimitRadS => 9,
                RobotField::RestPose(_) => 10,
                RobotField::Stance(_) => 11,
            };
            assert_eq!(index, i);
            check(
                nack(NackReason::BadRobot(*f)),
                3,
                i as u8,
                fields.len() as u8,
            );
        }
        let description = |knee_bend| RobotDescription {
            name: RobotDescription::name_bytes("x").unwrap(),
            robot: Robot {
                knee_bend,
                ..Robot::shahriar2023()
            },
            stance_height_m: 0.3,
            order: RotationOrder::Zyx,
            joint_speed_limit_rad_s: 3.0,
        };
        // seq (02) | SetRobot (12) | name (16) | twelve f32 | knee bend
        for (i, k) in [KneeBend::Backward, KneeBend::Forward].iter().enumerate() {
            assert_eq!(knee_bend::index(k), i as u32);
            let set = HostToDevice {
                seq: 2,
                request: Request::SetRobot(description(*k)),
            };
            check(set, 2 + 16 + 48, i as u8, 2);
        }
        for (request, index) in [
            (Request::SetRobot(description(KneeBend::Backward)), 18),
            (Request::GetRobot, 19),
            (Request::SaveRobot, 20),
        ] {
            check(HostToDevice { seq: 2, request }, 1, index, 21);
        }
        let answer = DeviceToHost::Robot {
            seq: 2,
            robot: description(KneeBend::Forward),
        };
        check(answer, 0, 7, 8);
    }
}
