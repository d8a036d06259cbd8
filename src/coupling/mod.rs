//! EFG–DE coupling (§2.4 and §3 of the paper).

pub mod interface;
