//! f32 (the MCU) against f64 (the host) on every thesis scene: the tip within 0.1 mm.

use integration_tests::{tip, weight};
use model_checks::reference::{self, Exp2Mass, csv_rows};
use model_core::{Model, PointLoad, Scalar, TipLoad};

const TOL_M: f64 = 1e-4;

fn exp1<T: Scalar>(grams: f64) -> Model<T> {
    let mut rod = reference::exp1_bench::<T>(reference::EXP1_YOUNGS_MODULUS_PA, 50).unwrap();
    rod.push_load(PointLoad::mass(
        T::lit(reference::EXP1_TRANSITION_M),
        T::lit(grams * 1e-3),
    ))
    .unwrap();
    Model::new(rod).unwrap()
}

#[test]
fn f32_matches_f64_on_table_4_1() {
    let mut worst = 0.0f64;
    for row in csv_rows::<9>(reference::TABLE_4_1_CSV) {
        let g = row.unwrap()[0];
        let err = (tip(&exp1::<f32>(g), &TipLoad::zero()) - tip(&exp1::<f64>(g), &TipLoad::zero()))
            .norm();
        worst = worst.max(err);
    }
    assert!(worst < TOL_M, "worst f32-f64 tip difference {worst:e} m");
}

#[test]
fn f32_matches_f64_on_tables_4_3_and_4_4() {
    for mass in [Exp2Mass::Average, Exp2Mass::Accurate] {
        let m64 = Model::<f64>::new(reference::exp2_bench(mass, 100, 1).unwrap()).unwrap();
        let m32 = Model::<f32>::new(reference::exp2_bench(mass, 100, 1).unwrap()).unwrap();
        let mut worst = 0.0f64;
        for row in csv_rows::<5>(reference::TABLE_4_3_CSV) {
            let g = row.unwrap()[0];
            worst = worst.max((tip(&m32, &weight(g)) - tip(&m64, &weight(g))).norm());
        }
        assert!(
            worst < TOL_M,
            "{mass:?}: worst f32-f64 tip difference {worst:e} m"
        );
    }
}
