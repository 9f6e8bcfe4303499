//! How well a model takes a material's inclusions, against the material: its small-displacement
//! answer to a smooth pressure on the free face over each inclusion, over its rim and away from it
//! (the points of [`crate::validate::probe::presses::inclusion_press_cases`]), against the hex8 FEM
//! of the material with its inclusions on the model's grid refined by a whole factor (its nodes
//! are the model's), as fine as [`REFERENCE_MAX_NODES`] allows; the same at a coarser refinement
//! says how far the reference still moves. Nothing is fitted to a lump.
//!
//! The pressure is a Gaussian of width [`PRESSURE_SIGMA_M`] and total force [`PRESSURE_FORCE_N`]
//! (what the probe's contact spreads over), its nodal forces integrated against each grid's own
//! shape functions. Scores per case, over the model's nodes: the field error `|u - u_ref| /
//! |u_ref|`; the largest nodal distance in percent of the model's spacing; how much less the face
//! sinks under the pressure's centre for the lump (`sink / sink_without - 1`), the model's and the
//! material's; and the error of the lump's effect `|du - du_ref| / |du_ref|`, `du` the change the
//! inclusion makes to the field (with and without it, the same model).

use glam::DVec3;

use crate::mechanics::fem::dynamics::Formulation;
use crate::mechanics::grid::{CUBE_SIDE_M, Grid};
use crate::mechanics::material::Material;
use crate::mechanics::msm::MsmParams;
use crate::sim::Model;
use crate::validate::touch::score::responder;

/// Width (standard deviation) of the pressure, metres.
pub const PRESSURE_SIGMA_M: f64 = 0.006;
/// Total force of the pressure, newtons.
pub const PRESSURE_FORCE_N: f64 = 2.0;
/// The finest reference grid, nodes per axis.
pub const REFERENCE_MAX_NODES: usize = 36;
/// Sub-squares per face element (each way) over which a pressure is integrated.
const LOAD_SUB: usize = 16;

/// One case's scores.
#[derive(Debug, Clone, serde::Serialize)]
pub struct InclusionCaseScore {
    /// e.g. `pressure_lump1_over`.
    pub id: String,
    /// The pressure's centre on the face, metres.
    pub at: [f64; 3],
    /// `|u - u_ref| / |u_ref|` over the model's nodes.
    pub field_error: f64,
    /// The largest nodal distance, percent of the model's spacing.
    pub max_pct_h: f64,
    /// `sink / sink_without - 1` under the centre: the model's.
    pub model_effect: f64,
    /// The same, the material's.
    pub material_effect: f64,
    /// `|du - du_ref| / |du_ref|`, `du` the change the inclusions make.
    pub effect_error: f64,
}

/// The scores of a model of a material with inclusions.
#[derive(Debug, Clone, serde::Serialize)]
pub struct InclusionReport {
    /// What the reference is.
    pub reference: String,
    /// The reference grid's nodes per axis.
    pub reference_nodes: usize,
    /// The largest change of the reference at the model's nodes from the coarser refinement,
    /// relative to its largest displacement.
    pub reference_change: f64,
    /// Per case.
    pub cases: Vec<InclusionCaseScore>,
    /// The worst field error.
    pub worst_field_error: f64,
    /// The worst error of the lump's effect over and at the rim of an inclusion (away from it
    /// the effect is near zero, and its relative error says little).
    pub worst_effect_error: f64,
}

/// The nodal forces on `grid` of the pressure centred at `at` on the free face there, pressing in.
fn pressure_load(grid: &Grid, at: [f64; 3]) -> anyhow::Result<Vec<f64>> {
    let normal =
        crate::sim::press::outward_normal(at).ok_or_else(|| anyhow::anyhow!("{at:?} is not on the surface"))?;
    let axis = (0..3).find(|&a| normal[a].abs() > 0.99).ok_or_else(|| anyhow::anyhow!("{at:?} is not on a face"))?;
    let (t1, t2) = ((axis + 1) % 3, (axis + 2) % 3);
    let step = CUBE_SIDE_M / ((grid.n() - 1) * LOAD_SUB) as f64;
    let peak = PRESSURE_FORCE_N / (2.0 * std::f64::consts::PI * PRESSURE_SIGMA_M * PRESSURE_SIGMA_M);
    let mut f = vec![0.0; 3 * grid.num_nodes()];
    let cells = (grid.n() - 1) * LOAD_SUB;
    for i in 0..cells {
        for j in 0..cells {
            let mut q = at;
            q[t1] = (i as f64 + 0.5) * step;
            q[t2] = (j as f64 + 0.5) * step;
            let r2 = (q[t1] - at[t1]).powi(2) + (q[t2] - at[t2]).powi(2);
            let force = peak * (-0.5 * r2 / (PRESSURE_SIGMA_M * PRESSURE_SIGMA_M)).exp() * step * step;
            for (node, w) in grid.corners(q) {
                f[3 * node + axis] -= normal[axis] * force * w;
            }
        }
    }
    Ok(f)
}

/// The small-displacement answers of `model` (with `params` for a lattice) of `material` on `grid`
/// to `loads`.
fn answers(
    model: Model,
    params: Option<MsmParams>,
    material: &Material,
    grid: Grid,
    points: &[[f64; 3]],
) -> anyhow::Result<Vec<Vec<f64>>> {
    let (mut r, _) = responder(model, params, material, grid)?;
    points
        .iter()
        .map(|&at| {
            let mut f = pressure_load(&grid, at)?;
            r.solver.solve(&mut f)?;
            Ok(f)
        })
        .collect()
}

/// The reference's displacements (`fine`, refined `by` from `grid`) at `grid`'s nodes.
fn at_nodes(fine: &[f64], grid: Grid, by: usize) -> Vec<f64> {
    let nf = (grid.n() - 1) * by + 1;
    let mut out = Vec::with_capacity(3 * grid.num_nodes());
    for p in 0..grid.num_nodes() {
        let [i, j, k] = grid.ijk(p);
        let q = i * by + nf * (j * by + nf * k * by);
        out.extend_from_slice(&fine[3 * q..3 * q + 3]);
    }
    out
}

fn norm(v: impl Iterator<Item = f64>) -> f64 {
    v.map(|x| x * x).sum::<f64>().sqrt()
}

/// The sink along the inward normal at `at` (interpolated on `grid`).
fn sink(u: &[f64], grid: &Grid, at: [f64; 3]) -> f64 {
    let n = crate::sim::press::outward_normal(at).unwrap_or(DVec3::Z);
    -grid.corners(at).iter().map(|&(p, w)| w * DVec3::new(u[3 * p], u[3 * p + 1], u[3 * p + 2]).dot(n)).sum::<f64>()
}

/// How many times the reference refines `grid` (at least 3, within [`REFERENCE_MAX_NODES`]), or
/// why it cannot.
pub fn refinement(grid: Grid) -> anyhow::Result<usize> {
    let by = (REFERENCE_MAX_NODES - 1) / (grid.n() - 1);
    if by < 3 {
        anyhow::bail!(
            "the inclusions' reference refines the model's grid at least 3 times within {REFERENCE_MAX_NODES} nodes \
             per axis: use at most {} nodes",
            (REFERENCE_MAX_NODES - 1) / 3 + 1
        );
    }
    Ok(by)
}

/// Scores `model` of `material` (with inclusions) on `grid`.
pub fn evaluate(
    material: &Material,
    model: Model,
    params: Option<MsmParams>,
    grid: Grid,
) -> anyhow::Result<InclusionReport> {
    evaluate_until(material, model, params, grid, &|| false)
}

/// [`evaluate`], given up between its solves once `stop` says so.
pub fn evaluate_until(
    material: &Material,
    model: Model,
    params: Option<MsmParams>,
    grid: Grid,
    stop: &dyn Fn() -> bool,
) -> anyhow::Result<InclusionReport> {
    let by = refinement(grid)?;
    let cases: Vec<(String, [f64; 3])> = crate::validate::probe::presses::inclusion_press_cases(material)
        .into_iter()
        .filter(|c| c.id.ends_with("_r15_d4"))
        .map(|c| (c.id.replace("press_", "pressure_").replace("_r15_d4", ""), c.press.at))
        .collect();
    let points: Vec<[f64; 3]> = cases.iter().map(|c| c.1).collect();
    let fem = Model::Fem(Formulation::Linear);
    let background = material.background();
    // The model's first: a model that cannot be scored fails before the reference's solves.
    let mine = answers(model, params, material, grid, &points)?;
    let mine_bg = answers(model, params, &background, grid, &points)?;
    let go_on = || if stop() { Err(anyhow::anyhow!("stopped")) } else { Ok(()) };
    // The reference's fields at the model's nodes, and its sinks under the pressures' centres.
    let fine = |by: usize, m: &Material| -> anyhow::Result<(Vec<Vec<f64>>, Vec<f64>)> {
        let g = Grid::new((grid.n() - 1) * by + 1)?;
        let u = answers(fem, None, m, g, &points)?;
        let sinks = u.iter().zip(&points).map(|(u, &at)| sink(u, &g, at)).collect();
        Ok((u.iter().map(|u| at_nodes(u, grid, by)).collect(), sinks))
    };
    go_on()?;
    let (reference, sinks) = fine(by, material)?;
    go_on()?;
    let (coarser, _) = fine(by - 1, material)?;
    go_on()?;
    let (reference_bg, sinks_bg) = fine(by, &background)?;
    let largest = reference.iter().flatten().fold(0.0f64, |a, b| a.max(b.abs()));
    let reference_change =
        reference.iter().flatten().zip(coarser.iter().flatten()).fold(0.0f64, |a, (x, y)| a.max((x - y).abs()))
            / largest;
    let mut scores = Vec::new();
    for (i, (id, at)) in cases.into_iter().enumerate() {
        let (u, r, u0, r0) = (&mine[i], &reference[i], &mine_bg[i], &reference_bg[i]);
        let field_error = norm(u.iter().zip(r).map(|(a, b)| a - b)) / norm(r.iter().copied());
        let max_pct_h =
            (0..grid.num_nodes()).map(|p| norm((0..3).map(|c| u[3 * p + c] - r[3 * p + c]))).fold(0.0, f64::max)
                / grid.h()
                * 100.0;
        let model_effect = sink(u, &grid, at) / sink(u0, &grid, at) - 1.0;
        let du_ref: Vec<f64> = r.iter().zip(r0).map(|(a, b)| a - b).collect();
        let effect_error =
            norm(u.iter().zip(u0).zip(&du_ref).map(|((a, b), d)| a - b - d)) / norm(du_ref.iter().copied());
        scores.push(InclusionCaseScore {
            id,
            at,
            field_error,
            max_pct_h,
            model_effect,
            material_effect: sinks[i] / sinks_bg[i] - 1.0,
            effect_error,
        });
    }
    let worst = |f: &dyn Fn(&InclusionCaseScore) -> f64| scores.iter().map(f).fold(0.0, f64::max);
    Ok(InclusionReport {
        reference: format!(
            "the material with its inclusions: hex8 FEM on the model's grid refined {by} times ({} nodes per axis); a \
             Gaussian pressure of {} mm width and {} N",
            (grid.n() - 1) * by + 1,
            PRESSURE_SIGMA_M * 1e3,
            PRESSURE_FORCE_N
        ),
        reference_nodes: (grid.n() - 1) * by + 1,
        reference_change,
        worst_field_error: worst(&|c| c.field_error),
        worst_effect_error: worst(&|c| if c.id.ends_with("_away") { 0.0 } else { c.effect_error }),
        cases: scores,
    })
}

impl InclusionReport {
    /// The report as a table.
    pub fn to_text(&self) -> String {
        let mut s = format!(
            "The model against the material with its inclusions (small displacements; {}; the reference moves {:.2} % \
             from the coarser refinement)\n{:<24} {:>10} {:>9} {:>15} {:>15} {:>13}\n",
            self.reference,
            100.0 * self.reference_change,
            "case",
            "field err",
            "max %h",
            "lump: model",
            "lump: material",
            "effect err"
        );
        for c in &self.cases {
            s += &format!(
                "{:<24} {:>9.2}% {:>9.2} {:>14.2}% {:>14.2}% {:>12.1}%\n",
                c.id,
                100.0 * c.field_error,
                c.max_pct_h,
                100.0 * c.model_effect,
                100.0 * c.material_effect,
                100.0 * c.effect_error
            );
        }
        s += &format!(
            "(lump: how much less the face sinks under the pressure's centre with the inclusions)\nworst field error \
             {:.2} %, worst error of the inclusions' effect over or at the rim of one {:.1} %\n",
            100.0 * self.worst_field_error,
            100.0 * self.worst_effect_error
        );
        s
    }
}
