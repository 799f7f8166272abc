//! The criterion benchmarks and development tools of `pluecker` live in `benches/` (see the
//! `[[bench]]` entries of this package's manifest); this library is empty.
