//! Bilinear finite elements on the EFG node grid, for the FE–DE comparison
//! of §4.2.1 (the mesh coincides with the EFG background grid).

pub mod q4;
