//! The tendon section of `accuracy_cost.md` and its figure `tendon_pareto.svg` / `.png`.

use std::fmt::Write as _;
use std::path::Path;

use plotters::coord::Shift;
use plotters::prelude::*;

use super::super::measure::{self as dead_load, Row};
use super::super::numbers::{sig, us};
use super::super::plot::{Cost, colour, panel, plot_error};
use super::super::variants::{Arithmetic, Family, Reduction};
use super::findings::{self, series};
use super::measure::{
    CHECK_STEPS, GOLDEN_AGREEMENT_M, PREVIOUS_TICK_SCALE, REFERENCE_STEPS, tendon_family,
};
use super::{TendonStudy, actuation};
use host_sim::plots::{FONT, ensure_font};
use host_sim::scene::SceneError;
use model_core::reduction::{PCC_COST, TendonModel, tendon_step_cost};

/// The figure's file name (without extension).
pub const FIGURE: &str = "tendon_pareto";

fn error_cell(r: &Row) -> String {
    match r.error_m() {
        Some(e) if r.converged() => {
            let star = if r.front_time || r.front_work {
                " *"
            } else {
                ""
            };
            format!("{}{star}", sig(e * 1e6))
        }
        _ => r
            .termination
            .split_whitespace()
            .next()
            .unwrap_or("refused")
            .to_string(),
    }
}

fn families(study: &TendonStudy, key: &str) -> Vec<Family> {
    let mut f: Vec<Family> = study
        .rows
        .iter()
        .filter(|r| r.scene == key)
        .map(|r| r.family)
        .collect();
    f.sort();
    f.dedup();
    f
}

fn method(out: &mut String, study: &TendonStudy) {
    let scenes: Vec<String> = study
        .scenes
        .iter()
        .map(|s| format!("`{}`: {}", s.scene.key, s.scene.title))
        .collect();
    let steps: Vec<String> = study.steps.iter().map(u16::to_string).collect();
    let _ = writeln!(
        out,
        "### Method (tendons)\n\n\
         - **Scenes.** {}; each case a golden row's tensions and tip force.\n\
         - **Reference.** Per case, the discrete guides (`Model::solve_tendons`: chords between the \
         guide holes, an implicit jump per guide; the routing the robot has) in f64 at {REFERENCE_STEPS} \
         RK4 steps per section; the {CHECK_STEPS}-step grid must agree with it to {:.0e} m (tip, \
         backbone points, path lengths) and the independent golden solver's tips and path lengths \
         to {GOLDEN_AGREEMENT_M:.0e} m, or the study fails.\n\
         - **Error** of a variant: the worst, over the scene's cases, of the tip distance, the \
         largest distance at {} backbone points and the largest path-length difference, against the \
         reference. A solve that does not converge (a grid refused as `UnderResolved`, say) has no \
         error: no answer.\n\
         - **Cost.** Sweeps per cold forward solve from tensions (load continuation from the \
         unloaded rod), RK4 steps per sweep and host time (median over repeated runs, this \
         machine, all variants timed side by side in one run). *Work* (the figure, the CSV's \
         `tendon_work`): sweeps x RK4 steps x the relative cost of one step of the model \
         (`tendon_step_cost`: discrete {}, continuous {}, a dead-load 3D step = 100, from \
         callgrind counts), PCC its whole closed form ({PCC_COST}).\n\
         - **Variants.** Discrete guides in f64 and f32, continuous routing (Rucker & Webster, \
         `solve_tendons_continuous`) in f64, each on {} steps per section; PCC \
         (`solve_tendons_pcc_ignoring_loads`: gravity and the tip force taken as its error; no grid) in f64. Quaternion frame throughout.\n\
         - **From tensions or displacements.** At {} steps per section, the discrete guides from \
         tensions (`solve_tendons`) and from the spool displacements the reference equilibrium \
         implies (`solve_displacements`: tensions unknown, complementarity with slack), each cold \
         and warm from the previous tick (every tension x {PREVIOUS_TICK_SCALE}, the same tip \
         force; `update_displacements` keeps the previous solve's sensitivity).\n\
         - **Cortex-M4F.** The firmware bench's tendon cases (`firmware/expected/bench.run`, QEMU \
         `-icount`), joined with the same f32 solves on the host (same robot, same actuation).\n",
        scenes.join("; "),
        dead_load::REFERENCE_AGREEMENT_M,
        dead_load::SHAPE_POINTS,
        tendon_step_cost(TendonModel::DiscreteGuides),
        tendon_step_cost(TendonModel::Continuous),
        steps.join(", "),
        actuation::ACTUATION_STEPS,
    );
}

fn scene_tables(out: &mut String, study: &TendonStudy) {
    let _ = writeln!(
        out,
        "### Error and cost by tendon variant\n\n\
         Error in um (worst of tip, backbone, paths; `*`: on a Pareto front of work or host time \
         against error); a name instead of a number is the termination of a solve that gave no \
         answer. Sweeps per cold solve; host time in us per cold solve. PCC has no grid (its own \
         column). Every row is in `accuracy_cost.csv` (the scene key marks the tendon rows; \
         `cable_error_um` holds the path-length error).\n"
    );
    for s in &study.scenes {
        let key = s.scene.key.as_str();
        let head: String = study.steps.iter().map(|n| format!(" {n} |")).collect();
        let rule: String = study.steps.iter().map(|_| " ---: |").collect();
        let _ = writeln!(out, "#### `{key}`: {}\n", s.scene.title);
        let _ = writeln!(
            out,
            "Cases: {}.\n",
            s.scene
                .cases
                .iter()
                .map(|c| c.label.clone())
                .collect::<Vec<_>>()
                .join("; ")
        );
        for (what, cell) in [
            ("error, um", &error_cell as &dyn Fn(&Row) -> String),
            ("sweeps per solve", &|r: &Row| {
                if r.family.reduction == Reduction::TendonPcc {
                    "0".into()
                } else {
                    sig(r.sweeps_per_solve)
                }
            }),
            ("host time, us", &|r: &Row| us(r.host_time_us)),
        ] {
            let _ = writeln!(out, "| {what} \\ steps per section | no grid |{head}");
            let _ = writeln!(out, "| --- | ---: |{rule}");
            for family in families(study, key) {
                let rows = series(study, key, &family);
                let pcc = family.reduction == Reduction::TendonPcc;
                let first = if pcc {
                    rows.first()
                        .map_or(" |".into(), |r| format!(" {} |", cell(r)))
                } else {
                    " |".into()
                };
                let cells: String = study
                    .steps
                    .iter()
                    .map(|n| {
                        rows.iter()
                            .find(|r| !pcc && r.steps_per_section == *n)
                            .map_or(" |".into(), |r| format!(" {} |", cell(r)))
                    })
                    .collect();
                let _ = writeln!(out, "| {} |{first}{cells}", family.label());
            }
            out.push('\n');
        }
        let rk4: Vec<String> = series(
            study,
            key,
            &tendon_family(Arithmetic::F64, TendonModel::DiscreteGuides),
        )
        .iter()
        .map(|r| format!("{}: {}", r.steps_per_section, r.rk4_steps_per_sweep))
        .collect();
        let _ = writeln!(
            out,
            "RK4 steps per sweep (the plan adds a node at every guide), by steps per section: {}.\n",
            rk4.join(", ")
        );
    }
}

fn actuation_table(out: &mut String, study: &TendonStudy) {
    let _ = writeln!(
        out,
        "### From tensions or from displacements\n\n\
         Discrete guides at {} steps per section, per solve (mean sweeps and iterations over the \
         cases, median host time); tip against the converged reference; tensions (displacement \
         control) against the case's.\n\n\
         | scene | precision | mode | sweeps | iterations | host time, us | x tensions cold | tip error, um | tension error, N | termination |\n\
         | --- | --- | --- | ---: | ---: | ---: | ---: | ---: | ---: | --- |",
        actuation::ACTUATION_STEPS
    );
    for a in &study.actuation {
        let base = study
            .actuation
            .iter()
            .find(|b| {
                b.scene == a.scene
                    && b.arithmetic == a.arithmetic
                    && b.mode == actuation::Mode::TensionsCold
            })
            .map_or(f64::NAN, |b| b.host_time_us);
        let _ = writeln!(
            out,
            "| {} | {} | {} | {} | {} | {} | {:.2} | {} | {} | {} |",
            a.scene,
            a.arithmetic.label(),
            a.mode.label(),
            sig(a.sweeps_per_solve),
            a.iterations.map_or(String::new(), sig),
            us(a.host_time_us),
            a.host_time_us / base,
            a.tip_error_m.map_or("n/a".into(), |e| sig(e * 1e6)),
            a.tension_error_n.map_or(String::new(), sig),
            a.termination
        );
    }
    out.push('\n');
}

fn mcu_table(out: &mut String, study: &TendonStudy) {
    let m = &study.mcu;
    let _ = writeln!(
        out,
        "### Cortex-M4F instruction counts (tendons)\n\n\
         `{}`: {}. The firmware's `bench` image on QEMU (f32, discrete guides, {} steps per \
         section): a cold forward solve from tick 0's tensions, a cold displacement-controlled \
         solve of tick 0, and the warm updates of the later ticks (the costliest and the most \
         sweeps of any). The host solves the same f32 model along the same actuation; errors are \
         the tips against the discrete-guide f64 reference at {REFERENCE_STEPS} steps per section \
         (the warm update: its worst tick); the firmware's own `tip_error_nm` is against its f64 \
         trajectory at its own steps.\n\n\
         | case | instructions | sweeps (QEMU / host) | instructions per sweep | ms at 168 MHz, lower bound | host f32, us | host f64, us | f32 error, um | f64 error at the same steps, um | vs the firmware's f64 trajectory (QEMU / host), um |\n\
         | --- | ---: | ---: | ---: | ---: | ---: | ---: | ---: | ---: | ---: |",
        m.scene.key, m.scene.title, m.steps_per_section
    );
    for r in &m.rows {
        let q = &r.qemu;
        let _ = writeln!(
            out,
            "| {} | {} | {} / {} | {:.0} | {:.1} | {} | {} | {} | {} | {} / {} |",
            q.case,
            q.instructions,
            q.sweeps,
            r.host_sweeps,
            q.per_sweep(),
            q.lower_bound_ms(),
            us(r.host_f32_us),
            us(r.host_f64_us),
            sig(r.f32_error_m * 1e6),
            sig(r.f64_error_m * 1e6),
            sig(q.tip_error_m * 1e6),
            sig(r.host_vs_trajectory_m * 1e6),
        );
    }
    out.push('\n');
}

fn two_section_mcu_table(out: &mut String, study: &TendonStudy) {
    let m = &study.two_section_mcu;
    let _ = writeln!(
        out,
        "`two-section`: the two-section, six-tendon robot of `tendon-two-section` (gravity) with \
         the firmware robot's steel tendons behind its feed, along {} ticks of tensions moving by \
         at most 0.1 N a tick, every tendon taut (`model_checks::reference::\
         tendon_two_section_actuation_n`). The firmware's `bench` image built with its \
         `two-section-bench` feature, on QEMU (f32, {} steps per section); the host takes the same \
         path in f32 and f64. Each tick's displacements are those that hold a forward solve at its \
         tensions (in the path's own precision), and the tips are against that solve: what the \
         update must find.\n\n\
         | case | instructions | sweeps (QEMU / host f32 / host f64) | instructions per sweep | ms at 168 MHz, lower bound | host f32, us | host f64, us | tip from the tick's forward solve (QEMU / host f32 / host f64), um |\n\
         | --- | ---: | ---: | ---: | ---: | ---: | ---: | ---: |",
        m.ticks, m.steps_per_section
    );
    for r in &m.rows {
        let q = &r.qemu;
        let _ = writeln!(
            out,
            "| {} | {} | {} / {} / {} | {:.0} | {:.1} | {} | {} | {} / {} / {} |",
            q.case,
            q.instructions,
            q.sweeps,
            r.host_sweeps,
            r.host_f64_sweeps,
            q.per_sweep(),
            q.lower_bound_ms(),
            us(r.host_f32_us),
            us(r.host_f64_us),
            sig(q.tip_error_m * 1e6),
            sig(r.f32_tip_m * 1e6),
            sig(r.f64_tip_m * 1e6),
        );
    }
    out.push('\n');
}

fn picker_table(out: &mut String, study: &TendonStudy) {
    let _ = writeln!(
        out,
        "### `choose_tendons`\n\n\
         `model_core::reduction::choose_tendons(rod, tendons, tensions, load, tolerance)` tries PCC, \
         then continuous routing and the discrete guides on a ladder of steps against its own fine \
         discrete solve, and picks the cheapest by its cost model. Each pick is measured again \
         against this study's reference (tip and paths, as it promises: \"meets\"; and with the \
         backbone), and timed against the discrete guides at their own fewest ladder steps.\n\n\
         | scene | case | tolerance, m | pick | steps | error by `choose_tendons`, um | error here, um | with the backbone, um | cost / discrete cost | host time pick / discrete (steps), us | meets |\n\
         | --- | --- | ---: | --- | ---: | ---: | ---: | ---: | ---: | ---: | --- |"
    );
    for p in &study.picks {
        let (pick, steps) = match p.picked {
            Some((r, _)) if r == Reduction::TendonPcc => (r.label().to_string(), "-".to_string()),
            Some((r, n)) => (r.label().to_string(), n.to_string()),
            None => (
                format!("refused: {}", p.refused.as_deref().unwrap_or("")),
                String::new(),
            ),
        };
        let times = match (&p.pick_row, &p.discrete_row, p.discrete_steps) {
            (Some(a), Some(b), Some(n)) => {
                format!("{} / {} ({n})", us(a.host_time_us), us(b.host_time_us))
            }
            (Some(a), _, _) => format!("{} / none", us(a.host_time_us)),
            _ => String::new(),
        };
        let _ = writeln!(
            out,
            "| {} | {} | {:.0e} | {pick} | {steps} | {} | {} | {} | {} / {} | {times} | {} |",
            p.scene,
            p.case_label,
            p.tolerance_m,
            sig(p.choose_error_m * 1e6),
            sig(p.study_error_m().unwrap_or(f64::NAN) * 1e6),
            sig(p
                .pick_row
                .as_ref()
                .and_then(Row::error_m)
                .unwrap_or(f64::NAN)
                * 1e6),
            p.cost,
            p.discrete_cost,
            if p.meets() { "yes" } else { "NO" }
        );
    }
    out.push('\n');
}

/// The tendon section of the report.
pub fn markdown(study: &TendonStudy) -> String {
    let mut out = String::new();
    let _ = writeln!(
        out,
        "## Tendons that pull: discrete guides, continuous routing, PCC\n\n\
         The tendon models of MODEL.md §6 against the discrete guides on a fine grid: which is \
         fastest at which tolerance, where each fails, what displacement control costs over \
         tensions, and what the Cortex-M4F spends.\n\n\
         ![Tendon variants: error against work and host time per cold forward solve, one panel \
         pair per scene]({FIGURE}.svg)\n"
    );
    let _ = writeln!(out, "### Conclusions (tendons)\n");
    for paragraph in findings::conclusions(study) {
        let _ = writeln!(out, "{paragraph}\n");
    }
    method(&mut out, study);
    scene_tables(&mut out, study);
    actuation_table(&mut out, study);
    mcu_table(&mut out, study);
    two_section_mcu_table(&mut out, study);
    picker_table(&mut out, study);
    out
}

/// The tendon models' colours, with a representative family each.
fn kinds() -> [(&'static str, Family); 3] {
    let f = |m| tendon_family(Arithmetic::F64, m);
    [
        ("discrete guides", f(TendonModel::DiscreteGuides)),
        ("continuous routing", f(TendonModel::Continuous)),
        ("PCC (closed form)", f(TendonModel::ConstantCurvature)),
    ]
}

fn legend<DB: DrawingBackend>(area: &DrawingArea<DB, Shift>) -> Result<(), SceneError>
where
    DB::ErrorType: 'static,
{
    let text = (FONT, 14).into_font().color(&BLACK);
    let (mut x, y) = (20, 22);
    for (label, family) in kinds() {
        area.draw(&PathElement::new(
            vec![(x, y), (x + 22, y)],
            colour(&family).stroke_width(3),
        ))
        .map_err(plot_error)?;
        area.draw(&Text::new(label, (x + 28, y - 8), text.clone()))
            .map_err(plot_error)?;
        x += 40 + 9 * i32::try_from(label.len()).unwrap_or(20);
    }
    let grey = RGBColor(90, 90, 90);
    area.draw(&Circle::new((x + 6, y), 4, grey.filled()))
        .map_err(plot_error)?;
    area.draw(&Text::new("f64", (x + 16, y - 8), text.clone()))
        .map_err(plot_error)?;
    x += 70;
    area.draw(&TriangleMarker::new((x + 6, y), 5, grey.filled()))
        .map_err(plot_error)?;
    area.draw(&Text::new("f32", (x + 16, y - 8), text.clone()))
        .map_err(plot_error)?;
    let y = 56;
    area.draw(&Circle::new((26, y), 8, BLACK.stroke_width(1)))
        .map_err(plot_error)?;
    area.draw(&Text::new(
        "Pareto front (dashed staircase); solves that gave no answer (UnderResolved) are not drawn",
        (40, y - 8),
        text,
    ))
    .map_err(plot_error)?;
    Ok(())
}

fn figure<DB: DrawingBackend>(
    root: &DrawingArea<DB, Shift>,
    study: &TendonStudy,
) -> Result<(), SceneError>
where
    DB::ErrorType: 'static,
{
    root.fill(&WHITE).map_err(plot_error)?;
    let root = root
        .titled(
            "Tendon variants against the discrete guides (error: worst of tip, backbone points, path lengths)",
            (FONT, 20),
        )
        .map_err(plot_error)?;
    let height = root.dim_in_pixel().1;
    let (charts, legend_area) = root.split_vertically(height.saturating_sub(80));
    let scenes = study.scenes.len().max(1);
    let panels = charts.split_evenly((scenes, 2));
    for (s, studied) in study.scenes.iter().enumerate() {
        let key = studied.scene.key.as_str();
        let rows: Vec<&Row> = study.rows.iter().filter(|r| r.scene == key).collect();
        let fams = families(study, key);
        for (c, cost) in [Cost::Work, Cost::Time].into_iter().enumerate() {
            if let Some(area) = panels.get(2 * s + c) {
                panel(area, key, &rows, &fams, cost)?;
            }
        }
    }
    legend(&legend_area)?;
    root.present().map_err(plot_error)
}

/// Draws `tendon_pareto.svg` and `.png` into `dir`.
pub fn plot(study: &TendonStudy, dir: &Path) -> Result<(), SceneError> {
    ensure_font()?;
    let size = (
        1200,
        180 + 400 * u32::try_from(study.scenes.len()).unwrap_or(2),
    );
    let svg = dir.join(format!("{FIGURE}.svg"));
    let png = dir.join(format!("{FIGURE}.png"));
    figure(&SVGBackend::new(&svg, size).into_drawing_area(), study)?;
    figure(&BitMapBackend::new(&png, size).into_drawing_area(), study)
}
