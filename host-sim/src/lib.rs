//! The shape model in f64 on the host: the thesis's experiments, scene files, the inverse on real data,
//! plots and calibration. The command-line tool is `src/main.rs`; everything it prints is computed here,
//! so tests assert on the same numbers.

pub mod calibrate;
pub mod monitor;
pub mod plots;
pub mod report;
pub mod run;
pub use robot_scene as scene;
pub mod scenes;
pub mod thesis;
