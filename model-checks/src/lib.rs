//! Reference scenes and self-checks of the rod model, kept out of the product crate.
//!
//! - [`reference`]: the thesis's benches and the independent golden 3D bench in SI units, with the
//!   committed reference data they are checked against (`tests/data/`).
//! - [`selftest`]: checks that need neither std nor allocation, so the same checks run on the host (in
//!   f64 and f32, `cargo test`) and on the emulated Cortex-M4 (in f32, the firmware's `selftest` image).

#![cfg_attr(not(test), no_std)]
#![cfg_attr(
    not(test),
    deny(clippy::unwrap_used, clippy::expect_used, clippy::panic)
)]

pub mod reference;
pub mod selftest;
