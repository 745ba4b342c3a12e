//! A settings field's cell text by serde (`cells_of`): a string as it is, a number as Rust prints
//! it, `true`/`false`, an enum's variant by its serde name, empty for none.

use serde::de;
use serde::ser::{self, Impossible, Serialize, SerializeStruct, Serializer};

/// A settings field serialised (`Cell`): its text, or a struct's fields as text.
enum Serialised {
    Text(String),
    Fields(Vec<(&'static str, String)>),
}

/// serde's value of a settings field as a cell's text: a string as it is, a number as Rust prints
/// it (`0.866`, `1`), `true`/`false`, an enum's variant by its serde name, empty for none; a
/// struct as its fields' cells (a field serde skips has none).
struct Cell;

type CellError = de::value::Error;

fn text(t: impl ToString) -> Result<Serialised, CellError> {
    Ok(Serialised::Text(t.to_string()))
}

fn not_a_cell<T>(what: &str) -> Result<T, CellError> {
    Err(ser::Error::custom(format!("{what} in a CSV cell")))
}

impl Serializer for Cell {
    type Ok = Serialised;
    type Error = CellError;
    type SerializeSeq = Impossible<Serialised, CellError>;
    type SerializeTuple = Impossible<Serialised, CellError>;
    type SerializeTupleStruct = Impossible<Serialised, CellError>;
    type SerializeTupleVariant = Impossible<Serialised, CellError>;
    type SerializeMap = Impossible<Serialised, CellError>;
    type SerializeStruct = Fields;
    type SerializeStructVariant = Impossible<Serialised, CellError>;

    fn serialize_bool(self, v: bool) -> Result<Serialised, CellError> {
        text(v)
    }
    fn serialize_i8(self, v: i8) -> Result<Serialised, CellError> {
        text(v)
    }
    fn serialize_i16(self, v: i16) -> Result<Serialised, CellError> {
        text(v)
    }
    fn serialize_i32(self, v: i32) -> Result<Serialised, CellError> {
        text(v)
    }
    fn serialize_i64(self, v: i64) -> Result<Serialised, CellError> {
        text(v)
    }
    fn serialize_u8(self, v: u8) -> Result<Serialised, CellError> {
        text(v)
    }
    fn serialize_u16(self, v: u16) -> Result<Serialised, CellError> {
        text(v)
    }
    fn serialize_u32(self, v: u32) -> Result<Serialised, CellError> {
        text(v)
    }
    fn serialize_u64(self, v: u64) -> Result<Serialised, CellError> {
        text(v)
    }
    fn serialize_f32(self, v: f32) -> Result<Serialised, CellError> {
        text(v)
    }
    fn serialize_f64(self, v: f64) -> Result<Serialised, CellError> {
        text(v)
    }
    fn serialize_char(self, v: char) -> Result<Serialised, CellError> {
        text(v)
    }
    fn serialize_str(self, v: &str) -> Result<Serialised, CellError> {
        text(v)
    }
    fn serialize_bytes(self, _: &[u8]) -> Result<Serialised, CellError> {
        not_a_cell("bytes")
    }
    fn serialize_none(self) -> Result<Serialised, CellError> {
        text("")
    }
    fn serialize_some<T: ?Sized + Serialize>(self, v: &T) -> Result<Serialised, CellError> {
        v.serialize(self)
    }
    fn serialize_unit(self) -> Result<Serialised, CellError> {
        text("")
    }
    fn serialize_unit_struct(self, _: &'static str) -> Result<Serialised, CellError> {
        text("")
    }
    fn serialize_unit_variant(
        self,
        _: &'static str,
        _: u32,
        variant: &'static str,
    ) -> Result<Serialised, CellError> {
        text(variant)
    }
    fn serialize_newtype_struct<T: ?Sized + Serialize>(
        self,
        _: &'static str,
        v: &T,
    ) -> Result<Serialised, CellError> {
        v.serialize(self)
    }
    fn serialize_newtype_variant<T: ?Sized + Serialize>(
        self,
        _: &'static str,
        _: u32,
        _: &'static str,
        _: &T,
    ) -> Result<Serialised, CellError> {
        not_a_cell("an enum with data")
    }
    fn serialize_seq(self, _: Option<usize>) -> Result<Self::SerializeSeq, CellError> {
        not_a_cell("a list")
    }
    fn serialize_tuple(self, _: usize) -> Result<Self::SerializeTuple, CellError> {
        not_a_cell("a tuple")
    }
    fn serialize_tuple_struct(
        self,
        _: &'static str,
        _: usize,
    ) -> Result<Self::SerializeTupleStruct, CellError> {
        not_a_cell("a tuple")
    }
    fn serialize_tuple_variant(
        self,
        _: &'static str,
        _: u32,
        _: &'static str,
        _: usize,
    ) -> Result<Self::SerializeTupleVariant, CellError> {
        not_a_cell("an enum with data")
    }
    fn serialize_map(self, _: Option<usize>) -> Result<Self::SerializeMap, CellError> {
        not_a_cell("a map")
    }
    fn serialize_struct(self, _: &'static str, n: usize) -> Result<Fields, CellError> {
        Ok(Fields(Vec::with_capacity(n)))
    }
    fn serialize_struct_variant(
        self,
        _: &'static str,
        _: u32,
        _: &'static str,
        _: usize,
    ) -> Result<Self::SerializeStructVariant, CellError> {
        not_a_cell("an enum with data")
    }
}

/// A struct's fields as cells, in serialisation order.
struct Fields(Vec<(&'static str, String)>);

impl SerializeStruct for Fields {
    type Ok = Serialised;
    type Error = CellError;
    fn serialize_field<T: ?Sized + Serialize>(
        &mut self,
        key: &'static str,
        v: &T,
    ) -> Result<(), CellError> {
        match v.serialize(Cell)? {
            Serialised::Text(t) => {
                self.0.push((key, t));
                Ok(())
            }
            Serialised::Fields(_) => not_a_cell("a struct"),
        }
    }
    fn end(self) -> Result<Serialised, CellError> {
        Ok(Serialised::Fields(self.0))
    }
}

/// A settings struct's cells by serde name (`Cell`).
pub(super) fn cells_of<T: Serialize>(v: &T) -> Vec<(&'static str, String)> {
    match v.serialize(Cell) {
        Ok(Serialised::Fields(f)) => f,
        _ => panic!("the settings are structs of plain values"),
    }
}
