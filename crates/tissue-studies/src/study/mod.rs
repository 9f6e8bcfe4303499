//! Layer 6, studies: speed against accuracy ([`chart`]: its points, their measurement, Pareto
//! fronts and plots), the stability study of explicit integration ([`stability`]), the choice of
//! the smallest model that meets a scene's error and rate budget ([`choose`]), the paper's tables
//! and figures ([`reproduce`]), timings ([`timing`], [`bench`](mod@bench): its sweep of
//! resolutions and its GPU figures, both on the viewer's scene with the probe pressed) and
//! scripted interaction ([`script`], `simulate`) and palpation maps ([`palpate`]); a rendered
//! picture's colour bar and caption ([`colour_bar`]).
//!
//! May use: calibrate, validate, gpu, sim, response, mechanics, io.

pub mod bench;
pub mod chart;
pub mod choose;
pub mod colour_bar;
pub mod font;
pub mod names;
pub mod palpate;
pub mod reproduce;
pub mod script;
pub mod stability;
pub mod timing;

use std::fmt::Write as _;
use std::path::Path;

use anyhow::Context as _;

use crate::io::OutputDir;
use crate::mechanics::grid::Grid;
use crate::mechanics::material::Material;
use crate::mechanics::msm::{MsmModel, Topology};
use crate::mechanics::object::Object;
use crate::sim::{Integrator, Model};
use chart::plot;
use chart::{ChartOptions, ChartPoint};
use stability::StabilityPoint;

/// The stability study: measured against analytic critical dt across resolution (axis and hex
/// lattices, linear FEM) and stiffness (both lattices at 8^3, x0.01 to x100; FEM x100), object A.
pub fn stability_study(progress: &mut dyn FnMut(&str)) -> anyhow::Result<Vec<StabilityPoint>> {
    let material = Material::object_a();
    let mut out = Vec::new();
    for (topology, resolutions) in [(Topology::Axis, &[4usize, 8, 16, 32][..]), (Topology::Hex, &[4, 8, 16][..])] {
        for &n in resolutions {
            let grid = Grid::new(n)?;
            let params = chart::msm_params_at(&material, topology, &grid)?;
            let scales: &[f64] = if n == 8 { &[0.01, 0.1, 1.0, 10.0, 100.0] } else { &[1.0] };
            for &s in scales {
                progress(&format!("stability: msm-{} at {n}^3, stiffness x{s}", topology.name()));
                let model = MsmModel::new(grid, stability::scaled_undamped(&params, s), material.density)?;
                out.push(stability::msm_point(&model, s));
            }
        }
    }
    for (n, s) in [(4, 1.0), (8, 1.0), (8, 100.0)] {
        progress(&format!("stability: fem-linear at {n}^3, stiffness x{s}"));
        out.push(stability::fem_point(&material, Grid::new(n)?, s));
    }
    Ok(out)
}

/// The table of every point.
fn points_table(md: &mut String, points: &[ChartPoint]) {
    let _ = writeln!(md, "\n## Every point\n");
    let _ = writeln!(
        md,
        "| object | model | n | integrator | dt, ms | step, us | cost per simulated s, s | touch force error, % \
         (validation) | probe force error vs the material, % (own nodes / surface compliance) | avg % of h | max % of \
         h | dynamic error, % | probe tap force error, % | period error, % | damping error, % of critical | Pareto \
         static | Pareto dynamic |\n|---|---|---|---|---|---|---|---|---|---|---|---|---|---|---|---|---|"
    );
    for p in points {
        let _ = writeln!(
            md,
            "| {} | {} | {} | {} | {:.4} | {:.2} | {:.4} | {:.2} | {:.1} / {:.1} | {:.4} | {:.4} | {:.3} | {:.3} | {:.3} | \
             {:.3} | {} | {} |",
            p.object,
            p.model.chart_name(),
            p.n,
            crate::study::chart::integrator_chart_name(p.integrator),
            p.dt_s * 1e3,
            p.step_s * 1e6,
            p.cost_per_sim_s,
            p.force_err_pct,
            p.probe_err_pct,
            p.surface_probe_err_pct,
            p.avg_err_pct,
            p.max_err_pct,
            p.dyn_err_pct,
            p.tap_err_pct,
            p.period_err_pct,
            p.damping_err_pct,
            if p.pareto { "yes" } else { "" },
            if p.pareto_dynamic { "yes" } else { "" }
        );
    }
}

/// Where each model's and integrator's dynamic error crosses 5 %, at the viewer's 8^3.
fn dynamic_crossings(md: &mut String, points: &[ChartPoint]) {
    let _ = writeln!(
        md,
        "## Where the dynamic error crosses 5 %\n\n| object | model | integrator | trajectory error | period error | \
         damping error (% of critical) |\n|---|---|---|---|---|---|"
    );
    let mut keys: Vec<(Object, Model, Integrator)> = Vec::new();
    for p in points.iter().filter(|p| p.dyn_err_pct.is_finite()) {
        let k = (p.object, p.model, p.integrator);
        if !keys.contains(&k) {
            keys.push(k);
        }
    }
    for (object, model, integrator) in keys {
        let series: Vec<&ChartPoint> = points
            .iter()
            .filter(|p| {
                p.object == object && p.model == model && p.integrator == integrator && p.dyn_err_pct.is_finite()
            })
            .collect();
        let _ = writeln!(
            md,
            "| {object} | {} | {} | {} | {} | {} |",
            model.chart_name(),
            chart::integrator_chart_name(integrator),
            chart::crossing(&series, |p| p.dyn_err_pct, 5.0),
            chart::crossing(&series, |p| p.period_err_pct, 5.0),
            chart::crossing(&series, |p| p.damping_err_pct, 5.0)
        );
    }
}

/// A CSV of serialisable rows.
fn csv_bytes<T: serde::Serialize>(rows: &[T]) -> anyhow::Result<Vec<u8>> {
    let mut w = csv::Writer::from_writer(Vec::new());
    for r in rows {
        w.serialize(r)?;
    }
    w.into_inner().map_err(|e| anyhow::anyhow!("csv: {e}"))
}

/// Reads the points of a `chart.csv` (or of `DIR/chart.csv` for a directory), checking every row:
/// a known model and integrator (their types refuse others), a resolution in range, positive
/// finite times, finite non-negative errors.
pub fn read_chart_csv(path: &Path) -> anyhow::Result<Vec<ChartPoint>> {
    let joined;
    let path = if path.is_dir() {
        joined = path.join("chart.csv");
        joined.as_path()
    } else {
        path
    };
    let text = crate::io::read_text(path)?;
    let mut r = csv::Reader::from_reader(text.as_bytes());
    let rows: Result<Vec<ChartPoint>, _> = r.deserialize().collect();
    let rows = rows.with_context(|| format!("{} is not a chart.csv written by `tissue-sim chart`", path.display()))?;
    for (i, p) in rows.iter().enumerate() {
        let row = i + 2; // the header is line 1
        let bad = |what: String| anyhow::anyhow!("{} line {row}: {what}", path.display());
        if !(2..=crate::mechanics::grid::MAX_NODES_PER_AXIS).contains(&p.n) {
            return Err(bad(format!("n = {} nodes per axis is out of range", p.n)));
        }
        for (name, v) in [("step_s", p.step_s), ("static_s", p.static_s)] {
            if !(v.is_finite() && v > 0.0) {
                return Err(bad(format!("{name} = {v} must be a positive time in seconds")));
            }
        }
        if p.dt_max_s.is_nan() || p.dt_max_s <= 0.0 {
            return Err(bad(format!("dt_max_s = {} must be positive (inf for implicit)", p.dt_max_s)));
        }
        for (name, v) in [("dt_s", p.dt_s), ("cost_per_sim_s", p.cost_per_sim_s)] {
            if !(v.is_finite() && v > 0.0) {
                return Err(bad(format!("{name} = {v} must be a positive time in seconds")));
            }
        }
        for (name, v) in [("avg_err_pct", p.avg_err_pct), ("max_err_pct", p.max_err_pct)] {
            if !(v.is_finite() && v >= 0.0) {
                return Err(bad(format!("{name} = {v} must be a finite non-negative percentage")));
            }
        }
        for (name, v) in [
            ("force_err_pct", p.force_err_pct),
            ("dyn_err_pct", p.dyn_err_pct),
            ("tap_err_pct", p.tap_err_pct),
            ("period_err_pct", p.period_err_pct),
            ("damping_err_pct", p.damping_err_pct),
            ("probe_err_pct", p.probe_err_pct),
            ("surface_probe_err_pct", p.surface_probe_err_pct),
        ] {
            if !(v.is_nan() || (v.is_finite() && v >= 0.0)) {
                return Err(bad(format!("{name} = {v} must be a finite non-negative percentage (NaN: not scored)")));
            }
        }
        let t = p.surface_probe_tick_s;
        if !(t.is_nan() || (t.is_finite() && t >= 0.0)) {
            return Err(bad(format!(
                "surface_probe_tick_s = {t} must be a finite non-negative time (NaN: not measured)"
            )));
        }
    }
    if rows.is_empty() {
        anyhow::bail!("{} holds no chart points", path.display());
    }
    Ok(rows)
}

/// `tissue-sim chart --out DIR`: chart.csv/.svg, stability.csv/.svg (unless skipped) and chart.md in `dir`.
pub fn write_chart(
    dir: &Path,
    opts: &ChartOptions,
    with_stability: bool,
    progress: &mut dyn FnMut(&str),
) -> anyhow::Result<Vec<ChartPoint>> {
    let names = ["chart.csv", "chart.svg", "chart_dynamic.svg", "chart.md", "stability.csv", "stability.svg"];
    OutputDir::check_names(dir, &names[..if with_stability { 6 } else { 4 }])?;
    let mut files = OutputDir::default();
    let start = std::time::Instant::now();
    let (points, notes) = chart::compute(opts, progress)?;
    let chart_s = start.elapsed().as_secs_f64();
    let stab = if with_stability { stability_study(progress)? } else { Vec::new() };
    let total_s = start.elapsed().as_secs_f64();
    files.add("chart.csv", csv_bytes(&points)?);
    files.add("chart.svg", plot::speed_accuracy_svg(&points, &chart::CHARTED, plot::Axis::Static)?);
    files.add("chart_dynamic.svg", plot::speed_accuracy_svg(&points, &chart::CHARTED, plot::Axis::Dynamic)?);
    if with_stability {
        files.add("stability.csv", csv_bytes(&stab)?);
        files.add("stability.svg", plot::stability_svg(&stab)?);
    }
    let mut md = String::from(
        "# Speed against accuracy\n\nGenerated by `tissue-sim chart`; see `study::chart` for the definitions.\n\n",
    );
    let _ = writeln!(
        md,
        "Every figure is held out: the shear and hex lattices are calibrated on the touch benchmark's \
         training cases and scored on the paper's cases (avg, max) and on the touch validation set (force); the \
         paper's axis lattice, calibrated on the paper's cases and not scorable by touch, is not charted. Touch \
         force errors are scored at the viewer's {n}^3 scene, against the FEM on the same mesh (which therefore \
         scores 0); at other resolutions a point load's answer depends on the mesh, so they show NaN.\n",
        n = crate::mechanics::grid::Grid::paper().n()
    );
    let _ = writeln!(
        md,
        "Cost is wall time per simulated second (one thread): explicit points step at 0.9 of their critical \
         step, implicit ones (prefactored backward Euler) at each of {} ms. Every model is damped by the ratio {} \
         at its own fundamental (mass-proportional). The dynamic error is the worst trajectory error against the \
         FEM's converged transients on the viewer's scene (a 1 N top-face shear step and its release, first \
         0.2 s, relative L2 in time of the loaded face's displacement); the probe tap force error is the \
         viewer's 15 mm probe tapped 4 mm deep for 20 ms into the top face, run in the viewer's simulation (its \
         projection contact and force readout, the same for every model) against the FEM's converged tap; the period and damping errors are the \
         integrator's on the model's own fundamental, measured by time stepping. Dynamic figures exist at the \
         viewer's 8^3 only.\n",
        chart::IMPLICIT_STEPS_S.map(|s| format!("{:.3}", s * 1e3)).join(", "),
        chart::CHART_DAMPING_RATIO
    );
    let _ = writeln!(md, "![static](chart.svg)\n\n![dynamic](chart_dynamic.svg)\n");
    dynamic_crossings(&mut md, &points);
    points_table(&mut md, &points);
    let _ = writeln!(md, "\n## Reference\n");
    for n in &notes {
        let _ = writeln!(md, "- {n}");
    }
    if with_stability {
        let _ = writeln!(md, "\n## Stability of symplectic Euler\n\n![stability](stability.svg)\n");
        let _ = writeln!(
            md,
            "| model | n | stiffness x | 2/omega_max, s | measured, s | measured / analytic |\n|---|---|---|---|---|---|"
        );
        for p in &stab {
            let _ = writeln!(
                md,
                "| {} | {} | {} | {:.4e} | {:.4e} | {:.5} |",
                p.model.chart_name(),
                p.n,
                p.stiffness_scale,
                p.dt_analytic_s,
                p.dt_measured_s,
                p.ratio
            );
        }
        let _ = writeln!(md, "\nWall time: chart {chart_s:.1} s, with the stability study {total_s:.1} s.");
    } else {
        let _ = writeln!(md, "\nWall time: chart {chart_s:.1} s (stability study skipped).");
    }
    files.add("chart.md", md);
    files.commit(dir)?;
    Ok(points)
}
