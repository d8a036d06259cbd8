//! Generators: node grids for bodies, particle packings for the granular assembly.
