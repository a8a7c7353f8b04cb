//! The no_std self-checks (also run on the emulated MCU by the firmware), here on the host in f64 and f32.

use model_checks::selftest::run_all;

fn run<T: model_core::Scalar>(label: &str)
where
    model_core::inverse::Params:
        model_core::inverse::ParamCount<T, 1> + model_core::inverse::ParamCount<T, 3>,
{
    let mut failures = Vec::new();
    let (passed, failed) = run_all::<T>(|name, outcome| {
        println!("{label} {name}: {outcome:?}");
        if let Err(f) = outcome {
            failures.push(format!(
                "{name}: {} = {:e} (limit {:e})",
                f.check, f.value, f.limit
            ));
        }
    });
    println!("{label}: {passed} passed, {failed} failed");
    assert!(
        failures.is_empty(),
        "{label} failures:\n{}",
        failures.join("\n")
    );
    assert!(passed >= 18);
}

#[test]
fn selftest_f64() {
    run::<f64>("f64");
}

#[test]
fn selftest_f32() {
    run::<f32>("f32");
}
