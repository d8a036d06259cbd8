//! Newmark time integration (Table 1, Eqs. 49/52/55, ERRATA E8–E9).
