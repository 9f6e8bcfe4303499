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
