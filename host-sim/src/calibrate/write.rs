//! The calibrated scene (`--out`): the user's scene file with the fitted values put in its keys,
//! edited with `toml_edit` so that its comments, order and layout stay as they were.
//!
//! What changes, for each fitted parameter:
//!
//! - `E`: every section's `material.youngs_modulus_pa` (and `shear_modulus_pa` when given), or
//!   its `stiffness` arrays, times the fitted scale;
//! - `line_density`: every section's `line_density_kg_per_m` or `density_kg_m3`, times its scale;
//! - `cable_offset`: every `[[tendon]]` and `[[cable]]` `radius_m`, times its scale;
//! - `friction`: every `[[tendon]]` `friction_coefficient` (written when absent);
//! - `base_pose`: the scene is written in the measurement frame, so that `solve` on it gives points
//!   where the data were measured: `base.position_m` (`R p + t`), `base.local_x` and `base.tangent`
//!   (`R` times them), `gravity_m_s2`, and the `[tip]` and `[[load]]` forces and moments (`R` times
//!   them), each written when absent.

use nalgebra::Vector3;
use toml_edit::{Array, DocumentMut, Item, Table, Value};

use super::params::Values;
use crate::scene::{Base, Scene, SceneError};

/// Significant digits of a scaled value (a modulus, a density, a radius): far below any standard
/// deviation the data can give, and short enough to read.
const DIGITS: usize = 10;

/// `x` as a TOML float: rounded to `digits` significant digits when given, plain between 1e-4 and
/// 1e7, else with an exponent (`6.0123e10`).
fn number_text(x: f64, digits: Option<usize>) -> String {
    let y = match digits {
        Some(d) => format!("{:.*e}", d.saturating_sub(1), x)
            .parse()
            .unwrap_or(x),
        None => x,
    };
    if y == 0.0 {
        "0.0".to_string()
    } else if (1e-4..1e7).contains(&y.abs()) {
        format!("{y:?}")
    } else {
        format!("{y:e}")
    }
}

/// A TOML value for `x`, keeping `old`'s decoration (its spacing and trailing comment).
fn number(x: f64, digits: Option<usize>, old: Option<&Value>) -> Result<Value, SceneError> {
    let text = number_text(x, digits);
    let mut v: Value = text
        .parse()
        .map_err(|_| SceneError::new("--out", format!("cannot write the number {x}")))?;
    if let Some(old) = old {
        *v.decor_mut() = old.decor().clone();
    }
    Ok(v)
}

/// Sets `key` of `table` to `x`, keeping the old value's decoration; inserts it when absent.
fn set(
    table: &mut dyn toml_edit::TableLike,
    key: &str,
    x: f64,
    digits: Option<usize>,
) -> Result<(), SceneError> {
    let old = table.get(key).and_then(Item::as_value).cloned();
    let v = number(x, digits, old.as_ref())?;
    table.insert(key, Item::Value(v));
    Ok(())
}

/// Sets `key` of `table` to the vector `x` (full precision), keeping each old element's
/// decoration; inserts it when absent.
fn set_vector(
    table: &mut dyn toml_edit::TableLike,
    key: &str,
    x: &Vector3<f64>,
) -> Result<(), SceneError> {
    match table.get_mut(key).and_then(Item::as_array_mut) {
        Some(array) if array.len() == 3 => {
            for (k, slot) in array.iter_mut().enumerate() {
                let v = number(x[k], None, Some(slot))?;
                *slot = v;
            }
        }
        _ => {
            let mut array = Array::new();
            for k in 0..3 {
                array.push(number(x[k], None, None)?);
            }
            table.insert(key, Item::Value(Value::Array(array)));
        }
    }
    Ok(())
}

/// The `i`th table of the array of tables `name` (`[[section]]`), or an error naming it.
fn nth<'d>(doc: &'d mut DocumentMut, name: &str, i: usize) -> Result<&'d mut Table, SceneError> {
    doc.get_mut(name)
        .and_then(Item::as_array_of_tables_mut)
        .and_then(|a| a.get_mut(i))
        .ok_or_else(|| {
            SceneError::new(
                format!("{name}[{i}]"),
                "not found as a [[table]] in the file: write it as one to have it calibrated",
            )
        })
}

/// A sub-table (`material`, `stiffness`) of `table`, inline or not.
fn sub<'t>(
    table: &'t mut Table,
    key: &str,
    field: &str,
) -> Result<&'t mut dyn toml_edit::TableLike, SceneError> {
    table
        .get_mut(key)
        .and_then(Item::as_table_like_mut)
        .ok_or_else(|| SceneError::new(field, "not found as a table in the file"))
}

/// The scene file `text` (parsed as `scene`) with `values` in the keys of the parameters fitted
/// (`fitted`: the names of [`super::fit::Calibration::fitted`]), and `header` as comment lines on
/// top.
pub fn calibrated_scene(
    text: &str,
    scene: &Scene,
    values: &Values,
    fitted: &[String],
    header: &[String],
) -> Result<String, SceneError> {
    let mut doc: DocumentMut = text
        .parse()
        .map_err(|e| SceneError::new("scene", format!("cannot edit: {e}")))?;
    let fits = |name: &str| fitted.iter().any(|f| f == name);
    for (i, spec) in scene.sections.iter().enumerate() {
        let field = format!("section[{i}]");
        let table = nth(&mut doc, "section", i)?;
        if fits("E") {
            let k = values.stiffness_scale;
            if let Some(m) = &spec.material {
                let material = sub(table, "material", &format!("{field}.material"))?;
                set(
                    material,
                    "youngs_modulus_pa",
                    m.youngs_modulus_pa * k,
                    Some(DIGITS),
                )?;
                if let Some(g) = m.shear_modulus_pa {
                    set(material, "shear_modulus_pa", g * k, Some(DIGITS))?;
                }
            }
            if let Some(s) = &spec.stiffness {
                let stiffness = sub(table, "stiffness", &format!("{field}.stiffness"))?;
                for (key, v) in [
                    ("bending_torsion_nm2", s.bending_torsion_nm2),
                    ("shear_axial_n", s.shear_axial_n),
                ] {
                    let array = stiffness
                        .get_mut(key)
                        .and_then(Item::as_array_mut)
                        .ok_or_else(|| {
                            SceneError::new(format!("{field}.stiffness.{key}"), "not found")
                        })?;
                    for (slot, x) in array.iter_mut().zip(v) {
                        let new = number(x * k, Some(DIGITS), Some(slot))?;
                        *slot = new;
                    }
                }
            }
        }
        if fits("line_density") {
            let rho = values.density_scale;
            if let Some(l) = spec.line_density_kg_per_m {
                set(table, "line_density_kg_per_m", l * rho, Some(DIGITS))?;
            }
            if let Some(d) = spec.density_kg_m3 {
                set(table, "density_kg_m3", d * rho, Some(DIGITS))?;
            }
        }
    }
    for (i, spec) in scene.tendons.iter().enumerate() {
        let table = nth(&mut doc, "tendon", i)?;
        if fits("cable_offset") {
            set(
                table,
                "radius_m",
                spec.radius_m * values.radius_scale,
                Some(DIGITS),
            )?;
        }
        if fits("friction")
            && let Some(mu) = values.friction
        {
            set(table, "friction_coefficient", mu, Some(DIGITS))?;
        }
    }
    if fits("cable_offset") {
        for (i, spec) in scene.cables.iter().enumerate() {
            let table = nth(&mut doc, "cable", i)?;
            set(
                table,
                "radius_m",
                spec.radius_m * values.radius_scale,
                Some(DIGITS),
            )?;
        }
    }
    if fits("base_pose") {
        write_pose(&mut doc, scene, values)?;
    }
    let mut out = String::new();
    for line in header {
        out.push_str("# ");
        out.push_str(line);
        out.push('\n');
    }
    out.push_str(&doc.to_string());
    Ok(out)
}

/// The scene in the measurement frame: base, gravity, tip and point loads carried by the pose.
fn write_pose(doc: &mut DocumentMut, scene: &Scene, values: &Values) -> Result<(), SceneError> {
    let pose = &values.pose;
    let r = pose.rotation();
    let base: &Base = &scene.base;
    let position = pose.to_measurement(&Vector3::from(base.position_m));
    let local_x = r * Vector3::from(base.local_x);
    let tangent = r * Vector3::from(base.tangent);
    if doc.get("base").is_none() {
        doc.insert("base", Item::Table(Table::new()));
    }
    let table = doc
        .get_mut("base")
        .and_then(Item::as_table_like_mut)
        .ok_or_else(|| SceneError::new("base", "not a table in the file"))?;
    set_vector(table, "position_m", &position)?;
    set_vector(table, "local_x", &local_x)?;
    set_vector(table, "tangent", &tangent)?;
    let gravity = r * Vector3::from(scene.gravity_m_s2);
    set_vector(doc.as_table_mut(), "gravity_m_s2", &gravity)?;
    let zero = [0.0; 3];
    if scene.tip.force_n != zero || scene.tip.moment_nm != zero {
        let tip = doc
            .get_mut("tip")
            .and_then(Item::as_table_like_mut)
            .ok_or_else(|| SceneError::new("tip", "not found as a table in the file"))?;
        for (key, v) in [
            ("force_n", scene.tip.force_n),
            ("moment_nm", scene.tip.moment_nm),
        ] {
            if v != zero {
                set_vector(tip, key, &(r * Vector3::from(v)))?;
            }
        }
    }
    for (i, load) in scene.loads.iter().enumerate() {
        for (key, v) in [("force_n", load.force_n), ("moment_nm", load.moment_nm)] {
            if v != zero {
                let table = nth(doc, "load", i)?;
                set_vector(table, key, &(r * Vector3::from(v)))?;
            }
        }
    }
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn numbers_are_short_and_valid_toml() {
        assert_eq!(number_text(60_123_456_789.123, Some(10)), "6.012345679e10");
        assert_eq!(number_text(0.037_251_234_567_89, Some(10)), "0.03725123457");
        assert_eq!(number_text(1e-5, None), "1e-5");
        assert_eq!(number_text(0.0, None), "0.0");
        for t in ["6.012345679e10", "1e-5", "0.0"] {
            assert!(t.parse::<Value>().is_ok(), "{t}");
        }
    }
}
