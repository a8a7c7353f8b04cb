//! The tendon scenes of the study: the thesis bench with three tendons and the two-section robot
//! with six, each at a few actuations of its golden reference (`tests/data/golden/tendon_*.csv`),
//! and the firmware's tendon robot at its recorded actuation (the MCU join, `mcu.rs`).

use model_checks::reference::{self, csv_rows};
use model_core::{Rod, Scalar, Tendon, TipLoad};
use nalgebra::Vector3;

use host_sim::scene::SceneError;

/// Which robot a tendon scene is built on.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum Robot {
    /// `reference::tendon_bench`: the thesis's exp-2 rod (average mass, gravity), six point guides,
    /// three inextensible tendons at 1 cm ending at the tip.
    Bench,
    /// `reference::tendon_two_section` with gravity: two Nitinol sections, 14 point guides of
    /// 0.25 g, six tendons at 8 mm (three end at the section end, three at the tip).
    TwoSection,
    /// The firmware's tendon robot (`firmware/src/tendon.rs`, `robot(true)`): the bench with steel
    /// tendons of this axial stiffness, N, behind this feed from the spools, m.
    Firmware {
        /// `E_t A_t`, N.
        axial_stiffness_n: f64,
        /// Spool to base plate, m.
        feed_length_m: f64,
    },
}

/// One actuation: the tendons' tensions and a tip force, and what the golden reference says.
#[derive(Clone, Debug, PartialEq)]
pub struct Actuation {
    /// Label for the report.
    pub label: String,
    /// Tensions, N, one per tendon.
    pub tensions_n: Vec<f64>,
    /// Tip force, N, global frame.
    pub force_n: [f64; 3],
    /// The golden tip, m, if the actuation is a golden row.
    pub golden_tip_m: Option<[f64; 3]>,
    /// The golden path lengths, m.
    pub golden_paths_m: Vec<f64>,
}

/// One tendon scene: a robot and its actuations (the cases).
#[derive(Clone, Debug, PartialEq)]
pub struct TendonScene {
    /// Short key (CSV, `--scenes`).
    pub key: String,
    /// What it is, for the report.
    pub title: String,
    /// The robot.
    pub robot: Robot,
    /// The actuations.
    pub cases: Vec<Actuation>,
}

/// Rows of `tendon_bench.csv` studied (all with gravity): an out-of-plane bend (row 1), a large
/// upward bend (row 4: 3, 1.5, 0 N), and two with a tip force (rows 5, 6).
pub const BENCH_ROWS: [usize; 4] = [1, 4, 5, 6];
/// Rows of `tendon_two_section.csv` studied (all with gravity): the distal section alone (row 3),
/// both sections (row 7), both with a tip force (rows 11, 13).
pub const TWO_SECTION_ROWS: [usize; 4] = [3, 7, 11, 13];
/// The quick mode's rows (the first and the last of each list: one without, one with a tip force).
pub const QUICK_ROW_PICKS: [usize; 2] = [0, 3];

/// Key of the bench scene.
pub const BENCH_KEY: &str = "tendon-bench";
/// Key of the two-section scene.
pub const TWO_SECTION_KEY: &str = "tendon-two-section";

fn model_error(what: &str) -> impl Fn(model_core::ModelError) -> SceneError + '_ {
    move |e| SceneError::new(what, e.to_string())
}

fn label(row: usize, tensions: &[f64], force: [f64; 3]) -> String {
    let t: Vec<String> = tensions.iter().map(|t| format!("{t}")).collect();
    let [x, y, z] = force;
    if force == [0.0; 3] {
        format!("row {row}: tau = ({}) N", t.join(", "))
    } else {
        format!(
            "row {row}: tau = ({}) N, F = ({x}, {y}, {z}) N",
            t.join(", ")
        )
    }
}

impl TendonScene {
    /// The thesis bench with three tendons at `rows` of `tendon_bench.csv`.
    pub fn bench(rows: &[usize]) -> Result<Self, SceneError> {
        let all: Vec<[f64; 18]> = csv_rows::<18>(reference::TENDON_BENCH_CSV)
            .collect::<Result<_, _>>()
            .map_err(model_error("tendon_bench.csv"))?;
        let mut cases = Vec::new();
        for &row in rows {
            let v = all
                .get(row)
                .ok_or_else(|| SceneError::new("tendon_bench.csv", format!("no row {row}")))?;
            let tensions_n = v[0..3].to_vec();
            let force_n = [v[3], v[4], v[5]];
            cases.push(Actuation {
                label: label(row, &tensions_n, force_n),
                tensions_n,
                force_n,
                golden_tip_m: Some([v[6], v[7], v[8]]),
                golden_paths_m: v[12..15].to_vec(),
            });
        }
        Ok(Self {
            key: BENCH_KEY.into(),
            title: format!(
                "thesis bench with three tendons (exp. 2 rod, average mass, gravity, six point \
                 guides, tendons at 1 cm), golden rows {}",
                join_rows(rows)
            ),
            robot: Robot::Bench,
            cases,
        })
    }

    /// The two-section, six-tendon robot with gravity at `rows` of `tendon_two_section.csv`.
    pub fn two_section(rows: &[usize]) -> Result<Self, SceneError> {
        let all: Vec<[f64; 25]> = csv_rows::<25>(reference::TENDON_TWO_SECTION_CSV)
            .collect::<Result<_, _>>()
            .map_err(model_error("tendon_two_section.csv"))?;
        let mut cases = Vec::new();
        for &row in rows {
            let v = all.get(row).ok_or_else(|| {
                SceneError::new("tendon_two_section.csv", format!("no row {row}"))
            })?;
            if v[0] != reference::GRAVITY_M_S2 {
                return Err(SceneError::new(
                    "tendon_two_section.csv",
                    format!("row {row} is without gravity; the scene has it"),
                ));
            }
            let tensions_n = v[1..7].to_vec();
            let force_n = [v[7], v[8], v[9]];
            cases.push(Actuation {
                label: label(row, &tensions_n, force_n),
                tensions_n,
                force_n,
                golden_tip_m: Some([v[10], v[11], v[12]]),
                golden_paths_m: v[16..22].to_vec(),
            });
        }
        Ok(Self {
            key: TWO_SECTION_KEY.into(),
            title: format!(
                "two-section robot with six tendons (Nitinol, 14 point guides of 0.25 g, gravity, \
                 tendons at 8 mm ending at 0.15 and 0.27 m), golden rows {}",
                join_rows(rows)
            ),
            robot: Robot::TwoSection,
            cases,
        })
    }

    /// The tendon scenes of the study: every golden row picked, or in quick mode two of each.
    pub fn all(quick: bool) -> Result<Vec<Self>, SceneError> {
        let pick = |rows: &[usize]| -> Vec<usize> {
            if quick {
                QUICK_ROW_PICKS
                    .iter()
                    .filter_map(|&i| rows.get(i).copied())
                    .collect()
            } else {
                rows.to_vec()
            }
        };
        Ok(vec![
            Self::bench(&pick(&BENCH_ROWS))?,
            Self::two_section(&pick(&TWO_SECTION_ROWS))?,
        ])
    }

    /// The same scene with only case `case`.
    pub fn only(&self, case: usize) -> Result<Self, SceneError> {
        let actuation = self
            .cases
            .get(case)
            .ok_or_else(|| SceneError::new(&self.key, format!("no case {case}")))?;
        Ok(Self {
            cases: vec![actuation.clone()],
            ..self.clone()
        })
    }

    /// The rod at `steps` per section and its tendons.
    pub fn rod<T: Scalar>(&self, steps: u16) -> Result<(Rod<T>, Vec<Tendon<T>>), SceneError> {
        let bench = || reference::tendon_bench::<T>(steps).map_err(model_error("tendon bench"));
        Ok(match self.robot {
            Robot::Bench => {
                let (rod, tendons) = bench()?;
                (rod, tendons.to_vec())
            }
            Robot::TwoSection => {
                let (rod, tendons) =
                    reference::tendon_two_section::<T>(steps, reference::GRAVITY_M_S2)
                        .map_err(model_error("two-section robot"))?;
                (rod, tendons.to_vec())
            }
            Robot::Firmware {
                axial_stiffness_n,
                feed_length_m,
            } => {
                let (rod, mut tendons) = bench()?;
                for t in tendons.iter_mut() {
                    t.axial_stiffness_n = Some(T::lit(axial_stiffness_n));
                    t.feed_length_m = T::lit(feed_length_m);
                }
                (rod, tendons.to_vec())
            }
        })
    }

    /// The tip load of case `case`.
    pub fn load<T: Scalar>(&self, case: usize) -> Result<TipLoad<T>, SceneError> {
        let f = self.actuation(case)?.force_n;
        Ok(TipLoad::force(Vector3::new(
            T::lit(f[0]),
            T::lit(f[1]),
            T::lit(f[2]),
        )))
    }

    /// The tensions of case `case`, N.
    pub fn tensions<T: Scalar>(&self, case: usize) -> Result<Vec<T>, SceneError> {
        Ok(self
            .actuation(case)?
            .tensions_n
            .iter()
            .map(|t| T::lit(*t))
            .collect())
    }

    /// Case `case`.
    pub fn actuation(&self, case: usize) -> Result<&Actuation, SceneError> {
        self.cases
            .get(case)
            .ok_or_else(|| SceneError::new(&self.key, format!("no case {case}")))
    }
}

fn join_rows(rows: &[usize]) -> String {
    let rows: Vec<String> = rows.iter().map(usize::to_string).collect();
    rows.join(", ")
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_golden_rows_load_with_their_tensions_and_forces() {
        let bench = TendonScene::bench(&BENCH_ROWS).expect("bench rows");
        assert_eq!(bench.cases.len(), 4);
        assert_eq!(bench.cases[1].tensions_n, [3.0, 1.5, 0.0]);
        assert_eq!(bench.cases[2].force_n, [0.0, -0.2, 0.1]);
        let two = TendonScene::two_section(&TWO_SECTION_ROWS).expect("two-section rows");
        assert!(two.cases.iter().all(|c| c.tensions_n.len() == 6));
        assert_eq!(two.cases[2].force_n, [0.0, -0.05, 0.02]);
        // Rows without gravity do not belong to the scene; rows past the end do not exist.
        assert!(TendonScene::two_section(&[2]).is_err());
        assert!(TendonScene::bench(&[99]).is_err());
        let quick = TendonScene::all(true).expect("quick scenes");
        assert!(quick.iter().all(|s| s.cases.len() == 2));
    }
}
