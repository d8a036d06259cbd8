//! A flexible retaining wall at rest (issue 15 §1): see [`super`].
