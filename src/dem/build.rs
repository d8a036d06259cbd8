//! Building a [`Granular`](super::Granular) from a scenario.
