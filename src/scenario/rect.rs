//! Rectangles in a scenario. Wherever a rectangle is given — a body's
//! `rectangle`, a `[[measure]]` `rectangle`, a packing's `box` — both
//! forms are accepted and mean the same region:
//!
//! ```toml
//! rectangle = { origin = [0.0, 0.0], size = [0.3, 0.1] }   # lower-left corner, width and height
//! rectangle = [[0.0, 0.0], [0.3, 0.1]]                     # corners: lower-left, upper-right
//! ```
//!
//! The corners must be in that order (x1 > x0, y1 > y0): a pair read the
//! other way round is refused, never taken as origin and size.

use serde::Deserialize;
use serde::de::{self, Deserializer, IgnoredAny, MapAccess, SeqAccess, Visitor};
use std::fmt;

/// A rectangle in the form it was written.
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum Rect {
    /// `[[x0, y0], [x1, y1]]`.
    Corners([f64; 2], [f64; 2]),
    /// `{ origin = [x, y], size = [w, h] }`.
    OriginSize([f64; 2], [f64; 2]),
}

impl Rect {
    /// Lower-left and upper-right corners.
    pub fn corners(self) -> [[f64; 2]; 2] {
        match self {
            Rect::Corners(a, b) => [a, b],
            Rect::OriginSize(o, s) => [o, [o[0] + s[0], o[1] + s[1]]],
        }
    }

    /// Lower-left corner and size.
    pub fn origin_size(self) -> crate::continuum::Rectangle {
        match self {
            Rect::Corners(a, b) => crate::continuum::Rectangle {
                origin: a,
                size: [b[0] - a[0], b[1] - a[1]],
            },
            Rect::OriginSize(origin, size) => crate::continuum::Rectangle { origin, size },
        }
    }
}

const EXPECTING: &str =
    "a rectangle: `{ origin = [x, y], size = [w, h] }` or its corners `[[x0, y0], [x1, y1]]`";

struct RectVisitor;

impl<'de> Visitor<'de> for RectVisitor {
    type Value = Rect;

    fn expecting(&self, f: &mut fmt::Formatter) -> fmt::Result {
        f.write_str(EXPECTING)
    }

    fn visit_seq<A: SeqAccess<'de>>(self, mut seq: A) -> Result<Rect, A::Error> {
        let a: [f64; 2] = seq
            .next_element()?
            .ok_or_else(|| de::Error::invalid_length(0, &self))?;
        let b: [f64; 2] = seq
            .next_element()?
            .ok_or_else(|| de::Error::invalid_length(1, &self))?;
        if seq.next_element::<IgnoredAny>()?.is_some() {
            return Err(de::Error::invalid_length(3, &self));
        }
        if !(b[0] > a[0] && b[1] > a[1]) {
            return Err(de::Error::custom(format!(
                "the corners [[x0, y0], [x1, y1]] of a rectangle are its lower-left and upper-right corners: x1 > x0 and y1 > y0 (got [{a:?}, {b:?}]); or write {{ origin = [x, y], size = [w, h] }}"
            )));
        }
        Ok(Rect::Corners(a, b))
    }

    fn visit_map<A: MapAccess<'de>>(self, map: A) -> Result<Rect, A::Error> {
        #[derive(Deserialize)]
        #[serde(deny_unknown_fields)]
        struct OriginSize {
            origin: [f64; 2],
            size: [f64; 2],
        }
        let r = OriginSize::deserialize(de::value::MapAccessDeserializer::new(map))?;
        Ok(Rect::OriginSize(r.origin, r.size))
    }
}

impl<'de> Deserialize<'de> for Rect {
    fn deserialize<D: Deserializer<'de>>(d: D) -> Result<Rect, D::Error> {
        d.deserialize_any(RectVisitor)
    }
}

/// `deserialize_with` for a field of type [`crate::continuum::Rectangle`].
pub fn origin_size<'de, D: Deserializer<'de>>(
    d: D,
) -> Result<crate::continuum::Rectangle, D::Error> {
    Ok(Rect::deserialize(d)?.origin_size())
}

/// `deserialize_with` for an optional field of corners `[[x0, y0], [x1, y1]]`
/// (with `#[serde(default)]`).
pub fn corners<'de, D: Deserializer<'de>>(d: D) -> Result<Option<[[f64; 2]; 2]>, D::Error> {
    Ok(Some(Rect::deserialize(d)?.corners()))
}

#[cfg(test)]
mod tests {
    use super::*;

    #[derive(Deserialize)]
    struct T {
        r: Rect,
    }

    fn parse(s: &str) -> Result<Rect, String> {
        toml::from_str::<T>(s)
            .map(|t| t.r)
            .map_err(|e| e.to_string())
    }

    #[test]
    fn both_forms_give_the_same_region() {
        let a = parse("r = [[0.5, 1.0], [2.5, 1.5]]").unwrap();
        let b = parse("r = { origin = [0.5, 1.0], size = [2.0, 0.5] }").unwrap();
        assert_eq!(a.corners(), b.corners());
        assert_eq!(a.origin_size(), b.origin_size());
    }

    #[test]
    fn corners_the_wrong_way_round_are_refused() {
        // [[origin], [size]] written as corners: not read as origin and size
        let e = parse("r = [[0.65, 0.54], [0.3, 0.1]]").unwrap_err();
        assert!(e.contains("x1 > x0 and y1 > y0"), "{e}");
        assert!(parse("r = [[0.0, 0.0], [1.0, 1.0], [2.0, 2.0]]").is_err());
        assert!(parse("r = { origin = [0.0, 0.0] }").is_err());
        assert!(parse("r = { origin = [0.0, 0.0], size = [1.0, 1.0], x = 1 }").is_err());
    }
}
