//! Flattening (thesis §2.1, §3.1): an initial free-boundary conformal map, then
//! projected Newton minimization of `E = Σ_T area3D(T) · W(a, d)` with flip-free
//! line search and α-continuation.

pub mod density;
pub mod element;
pub mod flip_free;
