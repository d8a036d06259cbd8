//! Strict tables for the scenario format: a struct is read from a table
//! (`{ key = value, … }` or a `[section]`) only, never from an array.
//!
//! Serde's derived `Deserialize` also accepts a struct's fields in order
//! as an array, and the TOML reader offers arrays that way, so
//! `rectangle = [[0.1, 0.1], [0.3, 0.2]]` would silently be read as
//! `{ origin = [0.1, 0.1], size = [0.3, 0.2] }`. [`Strict`] wraps a
//! deserializer so that every struct below it refuses an array ("invalid
//! type: sequence, expected a table"); [`table`] does the same for the
//! struct variants of untagged enums (which serde replays from a buffer
//! that no wrapper sees).

use serde::de::{
    self, DeserializeSeed, Deserializer, EnumAccess, MapAccess, SeqAccess, VariantAccess, Visitor,
};
use std::fmt;

/// A deserializer whose structs, at any depth, refuse arrays.
pub struct Strict<D>(pub D);

/// What a struct is expected as, in messages.
const TABLE: &str = "a table { key = value, … }";

/// Deserialize `T` from `d` with strict tables ([`Strict`]).
pub fn deserialize<'de, T: de::Deserialize<'de>, D: Deserializer<'de>>(
    d: D,
) -> Result<T, D::Error> {
    T::deserialize(Strict(d))
}

/// `#[serde(deserialize_with = "crate::strict::table")]` for a struct
/// variant of an untagged enum: a table only (an array fails the variant),
/// its fields read strictly.
pub fn table<'de, T: de::Deserialize<'de>, D: Deserializer<'de>>(d: D) -> Result<T, D::Error> {
    struct Only<T>(std::marker::PhantomData<T>);
    impl<'de, T: de::Deserialize<'de>> Visitor<'de> for Only<T> {
        type Value = T;
        fn expecting(&self, f: &mut fmt::Formatter) -> fmt::Result {
            f.write_str(TABLE)
        }
        fn visit_map<A: MapAccess<'de>>(self, map: A) -> Result<T, A::Error> {
            T::deserialize(Strict(de::value::MapAccessDeserializer::new(map)))
        }
    }
    d.deserialize_map(Only(std::marker::PhantomData))
}

/// A visitor passed through: nested values stay strict; `table` refuses
/// an array.
struct Visit<V> {
    inner: V,
    table: bool,
}

impl<V> Visit<V> {
    fn plain(inner: V) -> Self {
        Visit {
            inner,
            table: false,
        }
    }
}

macro_rules! forward_deserialize {
    ($($method:ident ( $($arg:ident : $ty:ty),* );)*) => {
        $(
            fn $method<V: Visitor<'de>>(self, $($arg: $ty,)* visitor: V) -> Result<V::Value, D::Error> {
                self.0.$method($($arg,)* Visit::plain(visitor))
            }
        )*
    };
}

impl<'de, D: Deserializer<'de>> Deserializer<'de> for Strict<D> {
    type Error = D::Error;

    forward_deserialize! {
        deserialize_any();
        deserialize_bool();
        deserialize_i8();
        deserialize_i16();
        deserialize_i32();
        deserialize_i64();
        deserialize_i128();
        deserialize_u8();
        deserialize_u16();
        deserialize_u32();
        deserialize_u64();
        deserialize_u128();
        deserialize_f32();
        deserialize_f64();
        deserialize_char();
        deserialize_str();
        deserialize_string();
        deserialize_bytes();
        deserialize_byte_buf();
        deserialize_option();
        deserialize_unit();
        deserialize_unit_struct(name: &'static str);
        deserialize_newtype_struct(name: &'static str);
        deserialize_seq();
        deserialize_tuple(len: usize);
        deserialize_tuple_struct(name: &'static str, len: usize);
        deserialize_map();
        deserialize_enum(name: &'static str, variants: &'static [&'static str]);
        deserialize_identifier();
        deserialize_ignored_any();
    }

    fn deserialize_struct<V: Visitor<'de>>(
        self,
        name: &'static str,
        fields: &'static [&'static str],
        visitor: V,
    ) -> Result<V::Value, D::Error> {
        let v = Visit {
            inner: visitor,
            table: true,
        };
        self.0.deserialize_struct(name, fields, v)
    }

    fn is_human_readable(&self) -> bool {
        self.0.is_human_readable()
    }
}

macro_rules! forward_visit {
    ($($method:ident ( $ty:ty );)*) => {
        $(
            fn $method<E: de::Error>(self, v: $ty) -> Result<V::Value, E> {
                self.inner.$method(v)
            }
        )*
    };
}

impl<'de, V: Visitor<'de>> Visitor<'de> for Visit<V> {
    type Value = V::Value;

    fn expecting(&self, f: &mut fmt::Formatter) -> fmt::Result {
        if self.table {
            f.write_str(TABLE)
        } else {
            self.inner.expecting(f)
        }
    }

    forward_visit! {
        visit_bool(bool);
        visit_i8(i8);
        visit_i16(i16);
        visit_i32(i32);
        visit_i64(i64);
        visit_i128(i128);
        visit_u8(u8);
        visit_u16(u16);
        visit_u32(u32);
        visit_u64(u64);
        visit_u128(u128);
        visit_f32(f32);
        visit_f64(f64);
        visit_char(char);
        visit_str(&str);
        visit_borrowed_str(&'de str);
        visit_string(String);
        visit_bytes(&[u8]);
        visit_borrowed_bytes(&'de [u8]);
        visit_byte_buf(Vec<u8>);
    }

    fn visit_none<E: de::Error>(self) -> Result<V::Value, E> {
        self.inner.visit_none()
    }

    fn visit_unit<E: de::Error>(self) -> Result<V::Value, E> {
        self.inner.visit_unit()
    }

    fn visit_some<D: Deserializer<'de>>(self, d: D) -> Result<V::Value, D::Error> {
        self.inner.visit_some(Strict(d))
    }

    fn visit_newtype_struct<D: Deserializer<'de>>(self, d: D) -> Result<V::Value, D::Error> {
        self.inner.visit_newtype_struct(Strict(d))
    }

    fn visit_seq<A: SeqAccess<'de>>(self, seq: A) -> Result<V::Value, A::Error> {
        if self.table {
            return Err(de::Error::invalid_type(de::Unexpected::Seq, &self));
        }
        self.inner.visit_seq(Seq(seq))
    }

    fn visit_map<A: MapAccess<'de>>(self, map: A) -> Result<V::Value, A::Error> {
        self.inner.visit_map(Map(map))
    }

    fn visit_enum<A: EnumAccess<'de>>(self, data: A) -> Result<V::Value, A::Error> {
        self.inner.visit_enum(Enum(data))
    }
}

/// A seed whose value is read strictly.
struct Seed<S>(S);

impl<'de, S: DeserializeSeed<'de>> DeserializeSeed<'de> for Seed<S> {
    type Value = S::Value;
    fn deserialize<D: Deserializer<'de>>(self, d: D) -> Result<S::Value, D::Error> {
        self.0.deserialize(Strict(d))
    }
}

struct Seq<A>(A);

impl<'de, A: SeqAccess<'de>> SeqAccess<'de> for Seq<A> {
    type Error = A::Error;
    fn next_element_seed<T: DeserializeSeed<'de>>(
        &mut self,
        seed: T,
    ) -> Result<Option<T::Value>, A::Error> {
        self.0.next_element_seed(Seed(seed))
    }
    fn size_hint(&self) -> Option<usize> {
        self.0.size_hint()
    }
}

struct Map<A>(A);

impl<'de, A: MapAccess<'de>> MapAccess<'de> for Map<A> {
    type Error = A::Error;
    fn next_key_seed<K: DeserializeSeed<'de>>(
        &mut self,
        seed: K,
    ) -> Result<Option<K::Value>, A::Error> {
        self.0.next_key_seed(Seed(seed))
    }
    fn next_value_seed<T: DeserializeSeed<'de>>(&mut self, seed: T) -> Result<T::Value, A::Error> {
        self.0.next_value_seed(Seed(seed))
    }
    fn size_hint(&self) -> Option<usize> {
        self.0.size_hint()
    }
}

struct Enum<A>(A);

impl<'de, A: EnumAccess<'de>> EnumAccess<'de> for Enum<A> {
    type Error = A::Error;
    type Variant = Variant<A::Variant>;
    fn variant_seed<S: DeserializeSeed<'de>>(
        self,
        seed: S,
    ) -> Result<(S::Value, Self::Variant), A::Error> {
        self.0
            .variant_seed(Seed(seed))
            .map(|(v, rest)| (v, Variant(rest)))
    }
}

struct Variant<A>(A);

impl<'de, A: VariantAccess<'de>> VariantAccess<'de> for Variant<A> {
    type Error = A::Error;
    fn unit_variant(self) -> Result<(), A::Error> {
        self.0.unit_variant()
    }
    fn newtype_variant_seed<T: DeserializeSeed<'de>>(self, seed: T) -> Result<T::Value, A::Error> {
        self.0.newtype_variant_seed(Seed(seed))
    }
    fn tuple_variant<V: Visitor<'de>>(self, len: usize, v: V) -> Result<V::Value, A::Error> {
        self.0.tuple_variant(len, Visit::plain(v))
    }
    fn struct_variant<V: Visitor<'de>>(
        self,
        fields: &'static [&'static str],
        v: V,
    ) -> Result<V::Value, A::Error> {
        let v = Visit {
            inner: v,
            table: true,
        };
        self.0.struct_variant(fields, v)
    }
}

#[cfg(test)]
mod tests {
    use serde::Deserialize;

    #[derive(Debug, Deserialize, PartialEq)]
    #[serde(deny_unknown_fields)]
    struct Rect {
        origin: [f64; 2],
        size: [f64; 2],
    }

    #[derive(Debug, Deserialize, PartialEq)]
    #[serde(untagged)]
    enum Shape {
        Points(Vec<[f64; 2]>),
        Rect(#[serde(deserialize_with = "super::table")] Rect),
    }

    #[derive(Debug, Deserialize)]
    struct Doc {
        rect: Option<Rect>,
        shape: Option<Shape>,
        list: Option<Vec<Rect>>,
    }

    fn read(text: &str) -> Result<Doc, String> {
        super::deserialize(toml::Deserializer::parse(text).map_err(|e| e.to_string())?)
            .map_err(|e: toml::de::Error| e.to_string())
    }

    #[test]
    fn a_struct_is_read_from_a_table_never_from_an_array() {
        let d = read("rect = { origin = [0.0, 1.0], size = [2.0, 3.0] }").unwrap();
        assert_eq!(d.rect.unwrap().size, [2.0, 3.0]);
        // plain serde reads the array as the fields in order
        let loose: Doc = toml::from_str("rect = [[0.1, 0.1], [0.3, 0.2]]").unwrap();
        assert_eq!(loose.rect.unwrap().size, [0.3, 0.2]);
        let e = read("rect = [[0.1, 0.1], [0.3, 0.2]]").unwrap_err();
        assert!(
            e.contains("invalid type: sequence, expected a table"),
            "{e}"
        );
        // inside arrays, and in an untagged enum's variant
        let e = read("list = [[[0.1, 0.1], [0.3, 0.2]]]").unwrap_err();
        assert!(e.contains("expected a table"), "{e}");
        let d = read("list = [{ origin = [0.0, 1.0], size = [2.0, 3.0] }]").unwrap();
        assert_eq!(d.list.unwrap()[0].origin, [0.0, 1.0]);
        let d = read("shape = { origin = [0.0, 1.0], size = [2.0, 3.0] }").unwrap();
        assert!(matches!(d.shape, Some(Shape::Rect(_))));
        let d = read("shape = [[0.0, 1.0], [2.0, 3.0]]").unwrap();
        assert!(matches!(d.shape, Some(Shape::Points(_))));
        assert!(read("shape = [[0.0, 1.0], 2.0]").is_err());
    }
}
