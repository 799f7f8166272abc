//! The integration tests of `pluecker`, one test binary (`cargo test -p pluecker --test it`): one
//! module per topic, each of the kind that used to be its own `tests/*.rs` file. One binary links the
//! crate and its dependencies once instead of once per file, which was most of a cold `make test`'s
//! build. `common` and `pose_oracle` are the helpers and the independent oracles the modules share.
//!
//! A module's tests run as `cargo test -p pluecker --test it MODULE::` (e.g. `pose_global::`).

mod common;
mod pose_oracle;

mod interrupt;
mod pose;
mod pose_certificate_bounds;
mod pose_certificate_region;
mod pose_global;
mod pose_lens;
mod pose_lens_exact;
mod robust_pose;
mod shared_fixture;
mod triangulation_api;
mod triangulation_cheirality;
mod triangulation_fitting;
mod triangulation_lens;
mod triangulation_lens_lines;
mod triangulation_line;
mod triangulation_point;
mod triangulation_quadric;
mod triangulation_robust;
mod triangulation_uncertainty;
