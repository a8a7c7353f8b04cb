//! Firmware of the continuum robot's shape estimator (STM32F405, Cortex-M4F).
//!
//! The library is target-agnostic `no_std` and host-tested; the images in `src/bin/` add the
//! runtime (cortex-m-rt, semihosting or defmt) through [`target`], which exists only on the MCU.
//!
//! | concern | module |
//! | --- | --- |
//! | cable length sources, AS5047P driver, multi-turn tracking | [`encoder`] |
//! | spool calibration (counts <-> metres) | [`spool`] |
//! | reading validation (typed rejections) | [`validate`] |
//! | the estimator loop and its output records | [`control`] |
//! | the composition root: the robot (rod, model), spools, loop settings | [`config`] |
//! | the recorded trajectory and its f64 reference | [`fixture`] |
//! | end-to-end and golden checks run by the images | [`checks`] |
//! | instruction-count benchmarks | [`bench`] |

#![cfg_attr(not(test), no_std)]

pub mod bench;
pub mod checks;
pub mod config;
pub mod control;
pub mod encoder;
pub mod fixture;
pub mod spool;
pub mod validate;

#[cfg(target_os = "none")]
pub mod target;
