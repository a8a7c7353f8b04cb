//! The shipped scene files, embedded so `host-sim validate` works from any directory.

use crate::scene::{Scene, SceneError};

/// Thesis experiment 1a (Table 4.1).
pub const EXP1: &str = include_str!("../scenes/thesis_exp1_two_sections.toml");
/// Thesis experiment 2, average-mass model (Tables 4.3, 4.5).
pub const EXP2_AVERAGE: &str = include_str!("../scenes/thesis_exp2_average.toml");
/// Thesis experiment 2, accurate-mass model (Tables 4.4, 4.5).
pub const EXP2_ACCURATE: &str = include_str!("../scenes/thesis_exp2_accurate.toml");
/// The 3D three-cable bench of the golden reference.
pub const BENCH_3D: &str = include_str!("../scenes/bench_3d_cables.toml");

/// Experiment 1a.
pub fn exp1() -> Result<Scene, SceneError> {
    Scene::parse(EXP1, "scenes/thesis_exp1_two_sections.toml")
}

/// Experiment 2, average mass.
pub fn exp2_average() -> Result<Scene, SceneError> {
    Scene::parse(EXP2_AVERAGE, "scenes/thesis_exp2_average.toml")
}

/// Experiment 2, accurate mass.
pub fn exp2_accurate() -> Result<Scene, SceneError> {
    Scene::parse(EXP2_ACCURATE, "scenes/thesis_exp2_accurate.toml")
}

/// The 3D bench.
pub fn bench_3d() -> Result<Scene, SceneError> {
    Scene::parse(BENCH_3D, "scenes/bench_3d_cables.toml")
}

/// The thesis bench with three tendons (the golden `tendon_bench.csv`).
pub const TENDON_BENCH: &str = include_str!("../scenes/tendon_bench.toml");
/// The two-section, six-tendon robot (the golden `tendon_two_section.csv`).
pub const TENDON_TWO_SECTION: &str = include_str!("../scenes/tendon_two_section.toml");

/// The tendon bench.
pub fn tendon_bench() -> Result<Scene, SceneError> {
    Scene::parse(TENDON_BENCH, "scenes/tendon_bench.toml")
}

/// The two-section tendon robot.
pub fn tendon_two_section() -> Result<Scene, SceneError> {
    Scene::parse(TENDON_TWO_SECTION, "scenes/tendon_two_section.toml")
}
