//! Firmware of the continuum robot's shape estimator (STM32F405, Cortex-M4F).
//!
//! The library is target-agnostic `no_std` and host-tested; the images in `src/bin/` add the
//! runtime (cortex-m-rt or RTIC, semihosting or defmt) through [`target`], which exists only on the
//! MCU.
//!
//! | concern | module |
//! | --- | --- |
//! | angle sensors, AS5047P driver, turn placement | [`encoder`] |
//! | the 1 kHz sampler: turn tracking, stepper cross-check, named cable faults | [`sampler`] |
//! | stepper microsteps <-> sensor counts | [`stepper`] |
//! | why the MCU last started (reset flags), and whether home is known | [`reset`] |
//! | spool calibration (counts <-> metres) | [`spool`] |
//! | reading validation (typed rejections) | [`validate`] |
//! | the estimator loop and its output records | [`control`] |
//! | the live link: each tick's record over a UART (`robot-link`'s frames; feature `link`) | `link` |
//! | the composition root: the robot of the robot file (rod, model), spools, loop settings | [`config`] |
//! | the recorded trajectory and its f64 reference | [`fixture`] |
//! | end-to-end and golden checks run by the images | [`checks`] |
//! | any robot's load path through the loop (the `robot` image, checked by host-sim) | [`robot_check`] |
//! | instruction-count benchmarks | [`bench`] |
//! | the tendon-driven robot: displacement control in f32, its golden and trajectory checks | [`tendon`] |

#![cfg_attr(not(test), no_std)]

pub mod bench;
pub mod checks;
pub mod config;
pub mod control;
pub mod encoder;
pub mod fixture;
#[cfg(any(test, feature = "link"))]
pub mod link;
pub mod reset;
pub mod robot_check;
pub mod sampler;
pub mod spool;
pub mod stepper;
pub mod tendon;
pub mod validate;

#[cfg(test)]
mod scenarios;

#[cfg(target_os = "none")]
pub mod target;
