//! Benchmarks and probes of `surfmap`: the programs whose output BENCHMARKS.md and
//! `docs/experiments/` quote. Nothing here is part of surfmap's API and the crate is not
//! published; users copy from `crates/surfmap/examples/` instead.
//!
//! Each program is an example of this crate, run from the repository root:
//!
//! ```text
//! cargo run --release -p surfmap-bench --example NAME -- ARGS
//! ```
//!
//! | example | what it measures |
//! |---|---|
//! | `read_bench` | reading mesh files, and reading plus `Topology::new` |
//! | `flatten_bench` | the default flattening of every disc mesh in `../shared/data` |
//! | `flatten_log` | the per-iteration Newton log of one flattening (thesis fig. 4.1 data) |
//! | `hard_discs` | flattening cut closed, higher-genus and holed meshes |
//! | `scale_bench` | a ≥ 1M-face disc: multilevel against single-level start |
//! | `multilevel_probe` | the multilevel start's energy for re-insertion settings |
//! | `decimate_bench` | decimation time and quality |
//! | `initial_maps_bench` | LSCM, mean-value and Tutte start maps |
//! | `element_bench` | per-triangle Newton kernels (energy, projected Hessian, flip-free step) |
//! | `linsolve_bench`, `factor_fill`, `ordering_probe` | the sparse Cholesky: phases, fill, orderings |
//! | `grid_bench` | grid sampling and the Gaussian pyramid |
//! | `images_bench` | geometry images of a face |
//! | `locate_bench` | point location in a flattening |
//! | `flatten_call` | the Rust side of the Python call-overhead benchmark (`crates/surfmap-py/examples/python_bench.py`) |
