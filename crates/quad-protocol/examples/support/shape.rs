//! The fields of the protocol's structs as their serde implementation writes them on the wire:
//! a serializer that records, instead of bytes, each field's name and type (used by the
//! `schema` example; the structs are plain serde derives, so their fields come from the same
//! declaration as their bytes).

use serde::ser::{self, Serialize};
use std::fmt;

/// What a value serializes as: a struct's fields, or a type's name.
pub enum Shape {
    /// A struct: its name and its fields (name, type) in wire order.
    Struct(&'static str, Vec<(&'static str, String)>),
    /// Anything else, by the name of its type.
    Type(String),
}

impl Shape {
    fn ty(self) -> String {
        match self {
            Shape::Struct(name, _) => name.to_owned(),
            Shape::Type(t) => t,
        }
    }
}

/// A shape that cannot be recorded (never for the protocol's structs).
#[derive(Debug)]
pub struct Error(String);

impl fmt::Display for Error {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.write_str(&self.0)
    }
}

impl std::error::Error for Error {}

impl ser::Error for Error {
    fn custom<T: fmt::Display>(msg: T) -> Self {
        Error(msg.to_string())
    }
}

/// The shape of `value` as its wire form (not human-readable) writes it.
///
/// # Errors
/// A shape serde's data model has that this recorder does not (maps).
pub fn shape<T: Serialize>(value: &T) -> Result<Shape, Error> {
    value.serialize(Recorder)
}

/// The recording serializer (for a serde `with` function: `wire::pose::serialize(&p, Recorder)`).
pub struct Recorder;

/// The elements of a sequence or tuple: `[T; n]`.
pub struct Elements(Vec<String>);

/// The fields of a struct.
pub struct Fields(&'static str, Vec<(&'static str, String)>);

fn prim(name: &str) -> Result<Shape, Error> {
    Ok(Shape::Type(name.to_owned()))
}

impl ser::Serializer for Recorder {
    type Ok = Shape;
    type Error = Error;
    type SerializeSeq = Elements;
    type SerializeTuple = Elements;
    type SerializeTupleStruct = Elements;
    type SerializeTupleVariant = ser::Impossible<Shape, Error>;
    type SerializeMap = ser::Impossible<Shape, Error>;
    type SerializeStruct = Fields;
    type SerializeStructVariant = ser::Impossible<Shape, Error>;

    fn is_human_readable(&self) -> bool {
        false
    }
    fn serialize_bool(self, _: bool) -> Result<Shape, Error> {
        prim("bool")
    }
    fn serialize_i8(self, _: i8) -> Result<Shape, Error> {
        prim("i8")
    }
    fn serialize_i16(self, _: i16) -> Result<Shape, Error> {
        prim("i16")
    }
    fn serialize_i32(self, _: i32) -> Result<Shape, Error> {
        prim("i32")
    }
    fn serialize_i64(self, _: i64) -> Result<Shape, Error> {
        prim("i64")
    }
    fn serialize_u8(self, _: u8) -> Result<Shape, Error> {
        prim("u8")
    }
    fn serialize_u16(self, _: u16) -> Result<Shape, Error> {
        prim("u16")
    }
    fn serialize_u32(self, _: u32) -> Result<Shape, Error> {
        prim("u32")
    }
    fn serialize_u64(self, _: u64) -> Result<Shape, Error> {
        prim("u64")
    }
    fn serialize_f32(self, _: f32) -> Result<Shape, Error> {
        prim("f32")
    }
    fn serialize_f64(self, _: f64) -> Result<Shape, Error> {
        prim("f64")
    }
    fn serialize_char(self, _: char) -> Result<Shape, Error> {
        prim("char")
    }
    fn serialize_str(self, _: &str) -> Result<Shape, Error> {
        prim("str")
    }
    fn serialize_bytes(self, _: &[u8]) -> Result<Shape, Error> {
        prim("bytes")
    }
    fn serialize_none(self) -> Result<Shape, Error> {
        Err(Error("a None has no inner type: record a Some".into()))
    }
    fn serialize_some<T: Serialize + ?Sized>(self, value: &T) -> Result<Shape, Error> {
        Ok(Shape::Type(format!(
            "Option<{}>",
            value.serialize(Recorder)?.ty()
        )))
    }
    fn serialize_unit(self) -> Result<Shape, Error> {
        prim("()")
    }
    fn serialize_unit_struct(self, name: &'static str) -> Result<Shape, Error> {
        prim(name)
    }
    fn serialize_unit_variant(
        self,
        name: &'static str,
        _: u32,
        _: &'static str,
    ) -> Result<Shape, Error> {
        prim(name)
    }
    fn serialize_newtype_struct<T: Serialize + ?Sized>(
        self,
        name: &'static str,
        value: &T,
    ) -> Result<Shape, Error> {
        Ok(Shape::Type(format!(
            "{name}({})",
            value.serialize(Recorder)?.ty()
        )))
    }
    fn serialize_newtype_variant<T: Serialize + ?Sized>(
        self,
        name: &'static str,
        _: u32,
        _: &'static str,
        _: &T,
    ) -> Result<Shape, Error> {
        prim(name)
    }
    fn serialize_seq(self, _: Option<usize>) -> Result<Elements, Error> {
        Ok(Elements(Vec::new()))
    }
    fn serialize_tuple(self, _: usize) -> Result<Elements, Error> {
        Ok(Elements(Vec::new()))
    }
    fn serialize_tuple_struct(self, _: &'static str, _: usize) -> Result<Elements, Error> {
        Ok(Elements(Vec::new()))
    }
    fn serialize_tuple_variant(
        self,
        name: &'static str,
        _: u32,
        _: &'static str,
        _: usize,
    ) -> Result<Self::SerializeTupleVariant, Error> {
        Err(Error(format!("tuple variant of {name}")))
    }
    fn serialize_map(self, _: Option<usize>) -> Result<Self::SerializeMap, Error> {
        Err(Error("a map".into()))
    }
    fn serialize_struct(self, name: &'static str, _: usize) -> Result<Fields, Error> {
        Ok(Fields(name, Vec::new()))
    }
    fn serialize_struct_variant(
        self,
        name: &'static str,
        _: u32,
        _: &'static str,
        _: usize,
    ) -> Result<Self::SerializeStructVariant, Error> {
        Err(Error(format!(
            "struct variant of {name} (a wire_enum!: its VARIANTS)"
        )))
    }
}

impl Elements {
    fn push<T: Serialize + ?Sized>(&mut self, value: &T) -> Result<(), Error> {
        self.0.push(value.serialize(Recorder)?.ty());
        Ok(())
    }
    fn done(self) -> Result<Shape, Error> {
        let first = self.0.first().cloned().unwrap_or_default();
        if self.0.iter().any(|t| *t != first) {
            return Err(Error(format!("mixed elements {:?}", self.0)));
        }
        Ok(Shape::Type(format!("[{first}; {}]", self.0.len())))
    }
}

impl ser::SerializeSeq for Elements {
    type Ok = Shape;
    type Error = Error;
    fn serialize_element<T: Serialize + ?Sized>(&mut self, value: &T) -> Result<(), Error> {
        self.push(value)
    }
    fn end(self) -> Result<Shape, Error> {
        self.done()
    }
}

impl ser::SerializeTuple for Elements {
    type Ok = Shape;
    type Error = Error;
    fn serialize_element<T: Serialize + ?Sized>(&mut self, value: &T) -> Result<(), Error> {
        self.push(value)
    }
    fn end(self) -> Result<Shape, Error> {
        self.done()
    }
}

impl ser::SerializeTupleStruct for Elements {
    type Ok = Shape;
    type Error = Error;
    fn serialize_field<T: Serialize + ?Sized>(&mut self, value: &T) -> Result<(), Error> {
        self.push(value)
    }
    fn end(self) -> Result<Shape, Error> {
        self.done()
    }
}

impl ser::SerializeStruct for Fields {
    type Ok = Shape;
    type Error = Error;
    fn serialize_field<T: Serialize + ?Sized>(
        &mut self,
        key: &'static str,
        value: &T,
    ) -> Result<(), Error> {
        self.1.push((key, value.serialize(Recorder)?.ty()));
        Ok(())
    }
    fn end(self) -> Result<Shape, Error> {
        Ok(Shape::Struct(self.0, self.1))
    }
}
