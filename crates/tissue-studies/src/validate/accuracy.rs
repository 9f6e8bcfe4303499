//! How far a mass-spring answer is from the FEM reference: the paper's cost (eq. 1) and its error
//! tables (Tables IV and V: average and maximum nodal distance per case, in percent of `h`).

use crate::mechanics::cases::CaseSolution;
use glam::DVec3;

/// Error of one case.
#[derive(Debug, Clone, PartialEq, serde::Serialize)]
pub struct CaseError {
    /// Case id of the reference.
    pub case_id: String,
    /// Loaded axis, 1-based.
    pub axis: usize,
    /// Force, newtons.
    pub force_n: f64,
    /// Average over nodes of `|x_msm - x_fem| / h`, percent.
    pub avg_pct: f64,
    /// Maximum over nodes of `|x_msm - x_fem| / h`, percent.
    pub max_pct: f64,
}

fn distance(a: &[f64; 3], b: &[f64; 3]) -> f64 {
    DVec3::from(*a).distance(DVec3::from(*b))
}

/// The paper's cost, eq. 1: the sum over cases and nodes of `|x_msm - x_fem|`, metres. Both models
/// share rest positions, so this is the distance between displacements.
pub fn cost(msm: &[CaseSolution], fem: &[CaseSolution]) -> f64 {
    msm.iter()
        .zip(fem)
        .map(|(m, f)| m.displacements.iter().zip(&f.displacements).map(|(a, b)| distance(a, b)).sum::<f64>())
        .sum()
}

/// Per-case average and maximum nodal error in percent of the spacing `h`.
pub fn case_errors(h: f64, msm: &[CaseSolution], fem: &[CaseSolution]) -> Vec<CaseError> {
    msm.iter()
        .zip(fem)
        .map(|(m, f)| {
            let d: Vec<f64> = m.displacements.iter().zip(&f.displacements).map(|(a, b)| distance(a, b)).collect();
            let avg = d.iter().sum::<f64>() / d.len() as f64;
            let max = d.iter().copied().fold(0.0, f64::max);
            CaseError {
                case_id: f.case_id.clone(),
                axis: f.axis,
                force_n: f.force_n,
                avg_pct: 100.0 * avg / h,
                max_pct: 100.0 * max / h,
            }
        })
        .collect()
}

/// The paper's Table IV/V layout: one row per force, average and maximum per axis.
pub fn format_table(title: &str, errors: &[CaseError]) -> String {
    let mut forces: Vec<f64> = errors.iter().map(|e| e.force_n).collect();
    forces.sort_by(f64::total_cmp);
    forces.dedup();
    let mut axes: Vec<usize> = errors.iter().map(|e| e.axis).collect();
    axes.sort_unstable();
    axes.dedup();
    let mut s = format!("{title}\nnodal error, % of h\n{:>6}", "Force");
    for a in &axes {
        s += &format!(" | {:^17}", format!("Axis {a}"));
    }
    s += &format!("\n{:>6}", "");
    for _ in &axes {
        s += &format!(" | {:>8} {:>8}", "Avg.", "Max.");
    }
    s += "\n";
    for f in forces {
        s += &format!("{:>4} N", f);
        for a in &axes {
            match errors.iter().find(|e| e.axis == *a && e.force_n == f) {
                Some(e) => s += &format!(" | {:>8.3} {:>8.3}", e.avg_pct, e.max_pct),
                None => s += &format!(" | {:>8} {:>8}", "-", "-"),
            }
        }
        s += "\n";
    }
    s
}

/// The paper's error tables of one MSM parameter set against the FEM on the clamped cases
/// (`tissue-sim errors`).
#[derive(Debug, Clone, PartialEq, serde::Serialize)]
pub struct ErrorsReport {
    /// The material's name.
    pub object: String,
    /// Nodes per axis.
    pub nodes_per_axis: usize,
    /// The MSM's parameters.
    pub params: crate::mechanics::msm::MsmParams,
    /// The paper's cost ([`cost`]), metres.
    pub cost: f64,
    /// Each case's errors ([`case_errors`]).
    pub cases: Vec<CaseError>,
}

impl ErrorsReport {
    /// The paper's Table IV/V layout ([`format_table`]) under a title with the object, the
    /// lattice and the cost.
    pub fn to_text(&self) -> String {
        let title = format!("Object {} ({:?} MSM, cost {:.6e} m)", self.object, self.params.topology(), self.cost);
        format_table(&title, &self.cases)
    }

    /// One line: the mean and largest of the cases' average and maximum errors, and the cost.
    pub fn headline(&self) -> String {
        let n = self.cases.len().max(1) as f64;
        let mean = self.cases.iter().map(|e| e.avg_pct).sum::<f64>() / n;
        let worst = self.cases.iter().map(|e| e.max_pct).fold(0.0, f64::max);
        format!(
            "the {} lattice of material {} at {}^3 on {} clamped cases: average error {mean:.3} % of h, largest \
             {worst:.3} % of h (h the lattice spacing), cost {} m",
            self.params.topology().name(),
            self.object,
            self.nodes_per_axis,
            self.cases.len(),
            crate::io::num(self.cost)
        )
    }
}

/// Solves the paper's clamped cases with the FEM and with the MSM of `params` on `grid`, and
/// compares them. Refuses a grid above the MSM's Newton bound
/// ([`crate::mechanics::msm::statics::check_grid`]) and a cost that is not finite.
pub fn errors_report(
    material: &crate::mechanics::material::Material,
    params: crate::mechanics::msm::MsmParams,
    grid: crate::mechanics::grid::Grid,
) -> anyhow::Result<ErrorsReport> {
    use anyhow::Context as _;

    use crate::mechanics::cases::{Bc, benchmark_cases};
    use crate::mechanics::fem::FemModel;
    use crate::mechanics::msm::{MsmModel, statics};
    statics::check_grid(params.topology(), grid.n(), false).map_err(anyhow::Error::msg)?;
    let cases = benchmark_cases(&grid, &material.name, Bc::Clamped);
    let fem = FemModel::new(grid, material)
        .solve_cases(&cases)
        .with_context(|| format!("solving the FEM stiffness system of material {} at {}^3", material.name, grid.n()))?;
    let model = MsmModel::new(grid, params, material.density)?;
    let msm = statics::solve_cases(&model, &cases).with_context(|| msm_context(material, &params, grid.n()))?;
    let errs = case_errors(grid.h(), &msm, &fem);
    let total = cost(&msm, &fem);
    if !total.is_finite() {
        anyhow::bail!(
            "the MSM-vs-FEM cost of material {} is not finite (cost {total}): the parameters are outside what \
             floating point represents",
            material.name
        );
    }
    Ok(ErrorsReport { object: material.name.clone(), nodes_per_axis: grid.n(), params, cost: total, cases: errs })
}

/// What a failed static MSM solve was solving: the lattice, the material, the grid and the axis
/// stiffnesses.
pub fn msm_context(
    material: &crate::mechanics::material::Material,
    params: &crate::mechanics::msm::MsmParams,
    n: usize,
) -> String {
    format!(
        "solving the static equilibrium of the {:?} MSM of material {} at {n}^3 with k1 = {}, k2 = {}, k3 = {} N/m",
        params.topology(),
        material.name,
        params.k1,
        params.k2,
        params.k3
    )
}
