//! The FEM's answers on the touch cases ([`Reference`]) and a model's scores against them
//! ([`Report`], the JSON of `validate`).

use crate::mechanics::fem::FemModel;
use crate::mechanics::grid::Grid;
use crate::mechanics::material::Material;
use crate::mechanics::msm::{MsmModel, MsmParams, Topology};
use crate::response::linear::{GroupedStiffness, SceneSolver, group_values, scene_fixed_dofs};
use crate::response::modes;
use crate::sim::Model;
use crate::validate::touch::{Kind, Load, MODES, PROBE_RADIUS_M, Set, TouchCase, touch_cases};

/// A model's answer to one case.
#[derive(Debug, Clone, PartialEq)]
pub struct Answer {
    /// Displacements, all dofs, metres.
    pub u: Vec<f64>,
    /// What the user feels: `u . f` at the load (point, shear), or the probe force's magnitude.
    pub feel: f64,
    /// Contact nodes (probe cases).
    pub contacts: Vec<usize>,
}

/// A model's small-displacement response on the scene: its grouped stiffness, factorised.
#[derive(Debug)]
pub struct Responder {
    /// The stiffness groups.
    pub stiffness: GroupedStiffness,
    /// The factorisation at the current parameters.
    pub solver: SceneSolver,
    grid: Grid,
}

impl Responder {
    /// The pattern of `stiffness` on `grid`'s scene, factorised at `theta`.
    pub fn new(
        grid: Grid,
        stiffness: GroupedStiffness,
        theta: &[f64],
    ) -> Result<Self, crate::mechanics::sparse::SparseError> {
        let mut solver = SceneSolver::new(&grid, &stiffness)?;
        solver.factor(&stiffness, theta)?;
        Ok(Self { stiffness, solver, grid })
    }

    /// Refactorises at new parameters.
    pub fn set_theta(&mut self, theta: &[f64]) -> Result<(), crate::mechanics::sparse::SparseError> {
        self.solver.factor(&self.stiffness, theta)
    }

    /// The force of the tissue on a sphere (`centre`, `radius`, metres) held against it at rest,
    /// newtons: the node contact of [`SceneSolver::probe`].
    pub fn press(&mut self, centre: [f64; 3], radius: f64) -> Result<[f64; 3], crate::mechanics::sparse::SparseError> {
        Ok(self.solver.probe(&self.grid, centre, radius)?.force)
    }

    /// The answer to `case`, and for a probe case the adjoint field of its force
    /// ([`crate::response::linear::ProbeAnswer::sensitivity`]).
    pub fn answer(
        &mut self,
        case: &TouchCase,
    ) -> Result<(Answer, Option<Vec<f64>>), crate::mechanics::sparse::SparseError> {
        match &case.load {
            Load::Forces(f) => {
                let mut u = f.clone();
                self.solver.solve(&mut u)?;
                let feel = u.iter().zip(f).map(|(a, b)| a * b).sum();
                Ok((Answer { u, feel, contacts: Vec::new() }, None))
            }
            Load::Probe { centre } => {
                let p = self.solver.probe(&self.grid, *centre, PROBE_RADIUS_M)?;
                let feel = p.force_n();
                let answer = Answer { u: p.u, feel, contacts: p.contacts.iter().map(|c| c.0).collect() };
                Ok((answer, Some(p.sensitivity)))
            }
        }
    }
}

/// The FEM's answers on the touch cases of one material and resolution.
#[derive(Debug, Clone)]
pub struct Reference {
    /// Object label (the material's name).
    pub object: String,
    /// The grid.
    pub grid: Grid,
    /// The cases; probe cases that touch no node are left out.
    pub cases: Vec<TouchCase>,
    /// The FEM's answer to each case.
    pub answers: Vec<Answer>,
    /// The FEM's lowest natural frequencies, Hz (lumped masses).
    pub modes_hz: Vec<f64>,
    /// The material's density, kg/m^3.
    pub density: f64,
}

/// Lumped FEM masses per dof (`density h^3 / 8` from each element at a node), zero on the clamp.
fn fem_masses(grid: &Grid, density: f64) -> Vec<f64> {
    let nodal = crate::mechanics::msm::model::lumped_masses(grid, density);
    let fixed = scene_fixed_dofs(grid);
    fixed.iter().enumerate().map(|(d, &f)| if f { 0.0 } else { nodal[d / 3] }).collect()
}

impl Reference {
    /// Solves every touch case and the modes with the hex8 FEM of `material` on `grid`.
    pub fn new(material: &Material, grid: Grid) -> anyhow::Result<Self> {
        if grid.n() < 4 {
            anyhow::bail!("the touch benchmark needs at least 4 nodes per axis (got {})", grid.n());
        }
        let fem = FemModel::new(grid, material);
        let mut responder = Responder::new(grid, GroupedStiffness::fem(&fem), &[1.0])?;
        let mut cases = Vec::new();
        let mut answers = Vec::new();
        for case in touch_cases(&grid) {
            let (answer, _) = responder.answer(&case)?;
            if case.kind == Kind::Probe && answer.contacts.is_empty() {
                continue;
            }
            cases.push(case);
            answers.push(answer);
        }
        let mass = fem_masses(&grid, material.density);
        let modes_hz = modes::lowest_frequencies_hz(&mut responder.solver, &mass, MODES)?;
        Ok(Self { object: material.name.clone(), grid, cases, answers, modes_hz, density: material.density })
    }
}

/// The grouped stiffness, parameters and lumped masses on `grid` of `model` of `material`: a
/// lattice with `params` (its shipped tissue when `None`), or the hex8 FEM (its rest tangent: the
/// corotational formulation's equals the linear one's; `params` unused).
pub fn responder(
    model: Model,
    params: Option<MsmParams>,
    material: &Material,
    grid: Grid,
) -> anyhow::Result<(Responder, Vec<f64>)> {
    match model {
        Model::Lattice(topology) => {
            let params = match params {
                Some(p) if p.topology() != topology => anyhow::bail!(
                    "the {} lattice was asked for with the parameters of the {} lattice",
                    topology.name(),
                    p.topology().name()
                ),
                Some(p) => p,
                None => crate::sim::shipped::tissue_params(material, topology)?,
            };
            if params.topology() == Topology::Axis {
                anyhow::bail!(
                    "the axis-spring lattice has no shear stiffness at rest: a sideways touch has no \
                     small-displacement answer, so it cannot be scored on the touch benchmark"
                );
            }
            let model = MsmModel::new(grid, params, material.density)?;
            let fixed = scene_fixed_dofs(&grid);
            let mass = fixed.iter().enumerate().map(|(d, &f)| if f { 0.0 } else { model.masses[d / 3] }).collect();
            let stiffness = GroupedStiffness::lattice_in(
                grid,
                params.topology(),
                crate::mechanics::msm::inclusions::SpringRule::new(grid, material).as_ref(),
            );
            Ok((Responder::new(grid, stiffness, &group_values(&params))?, mass))
        }
        Model::Fem(_) => {
            let fem = FemModel::new(grid, material);
            Ok((Responder::new(grid, GroupedStiffness::fem(&fem), &[1.0])?, fem_masses(&grid, material.density)))
        }
    }
}

/// Frequencies as `14.58, 14.80, ...` (Hz, two decimals).
pub fn frequency_list(hz: &[f64]) -> String {
    hz.iter().map(|f| format!("{f:.2}")).collect::<Vec<_>>().join(", ")
}

/// Scores of one case.
#[derive(Debug, Clone, PartialEq, serde::Serialize, serde::Deserialize)]
pub struct CaseScore {
    /// Case id.
    pub id: String,
    /// point, shear or probe.
    pub kind: Kind,
    /// training or validation.
    pub set: Set,
    /// Model over FEM: compliance `u . f` at the load; for the probe, force over force at equal depth.
    pub compliance_ratio: f64,
    /// `|u_model - u_fem| / |u_fem|` over all nodes.
    pub field_error: f64,
    /// Average nodal distance, percent of `h`.
    pub avg_pct_h: f64,
    /// Largest nodal distance, percent of `h`.
    pub max_pct_h: f64,
}

/// A model's touch scores: the JSON of `validate`.
#[derive(Debug, Clone, PartialEq, serde::Serialize, serde::Deserialize)]
pub struct Report {
    /// Object label.
    pub object: String,
    /// The model.
    pub model: Model,
    /// Grid resolution.
    pub nodes_per_axis: usize,
    /// Per case.
    pub cases: Vec<CaseScore>,
    /// The model's lowest six natural frequencies, Hz, ascending.
    pub modes_hz: Vec<f64>,
    /// The FEM's, same scene.
    pub fem_modes_hz: Vec<f64>,
    /// Largest `|1 - compliance_ratio|` over the validation cases (fraction).
    pub worst_force_error: f64,
    /// Median of `|1 - compliance_ratio|` over the validation cases (fraction).
    pub median_force_error: f64,
    /// Largest `|1 - f_model / f_fem|` over the six modes (fraction).
    pub worst_frequency_error: f64,
}

/// Scores `model` of `material` (a lattice with `params`, its shipped tissue when `None`)
/// against `reference`.
pub fn evaluate(
    reference: &Reference,
    material: &Material,
    model: Model,
    params: Option<MsmParams>,
) -> anyhow::Result<Report> {
    let grid = reference.grid;
    let (mut responder, mass) = responder(model, params, material, grid)?;
    let h = grid.h();
    let mut cases = Vec::with_capacity(reference.cases.len());
    for (case, fem) in reference.cases.iter().zip(&reference.answers) {
        let (answer, _) = responder.answer(case)?;
        cases.push(case_score(case, &answer, fem, h));
    }
    let modes_hz = modes::lowest_frequencies_hz(&mut responder.solver, &mass, MODES)?;
    let worst_frequency_error =
        modes_hz.iter().zip(&reference.modes_hz).map(|(m, f)| (1.0 - m / f).abs()).fold(0.0, f64::max);
    let mut errors: Vec<f64> =
        cases.iter().filter(|c| c.set == Set::Validation).map(|c| (1.0 - c.compliance_ratio).abs()).collect();
    errors.sort_by(f64::total_cmp);
    let median_force_error = match errors.len() {
        0 => 0.0,
        n if n % 2 == 1 => errors[n / 2],
        n => 0.5 * (errors[n / 2 - 1] + errors[n / 2]),
    };
    Ok(Report {
        object: reference.object.clone(),
        model,
        nodes_per_axis: grid.n(),
        worst_force_error: errors.last().copied().unwrap_or(0.0),
        median_force_error,
        worst_frequency_error,
        cases,
        modes_hz,
        fem_modes_hz: reference.modes_hz.clone(),
    })
}

/// The scores of one answer against the FEM's.
pub fn case_score(case: &TouchCase, answer: &Answer, fem: &Answer, h: f64) -> CaseScore {
    let mut diff2 = 0.0;
    let mut ref2 = 0.0;
    let mut sum = 0.0;
    let mut max = 0.0f64;
    for (a, b) in answer.u.chunks_exact(3).zip(fem.u.chunks_exact(3)) {
        let d2: f64 = (0..3).map(|c| (a[c] - b[c]).powi(2)).sum();
        diff2 += d2;
        ref2 += b.iter().map(|v| v * v).sum::<f64>();
        sum += d2.sqrt();
        max = max.max(d2.sqrt());
    }
    let nodes = (answer.u.len() / 3) as f64;
    CaseScore {
        id: case.id.clone(),
        kind: case.kind,
        set: case.set,
        compliance_ratio: answer.feel / fem.feel,
        field_error: (diff2 / ref2).sqrt(),
        avg_pct_h: 100.0 * sum / nodes / h,
        max_pct_h: 100.0 * max / h,
    }
}

impl Report {
    /// The table `validate` prints.
    pub fn to_text(&self) -> String {
        let mut s = format!(
            "Touch benchmark: object {}, model {}, {}^3 nodes, face z = 0 clamped; FEM: the project's hex8 on the \
             same mesh\n{:<28} {:<10} {:<7} {:>9} {:>9} {:>9} {:>9}\n",
            self.object, self.model, self.nodes_per_axis, "case", "set", "kind", "ratio", "field", "avg %h", "max %h"
        );
        for c in &self.cases {
            s += &format!(
                "{:<28} {:<10} {:<7} {:>9.4} {:>9.4} {:>9.3} {:>9.3}\n",
                c.id,
                format!("{:?}", c.set).to_lowercase(),
                format!("{:?}", c.kind).to_lowercase(),
                c.compliance_ratio,
                c.field_error,
                c.avg_pct_h,
                c.max_pct_h
            );
        }
        let (model, fem) = (frequency_list(&self.modes_hz), frequency_list(&self.fem_modes_hz));
        s += &format!("modes, Hz: model {model}\n           FEM   {fem}\n");
        s += &format!(
            "validation set: worst force error {:.1} %, median {:.1} %; worst frequency error {:.1} %\n",
            100.0 * self.worst_force_error,
            100.0 * self.median_force_error,
            100.0 * self.worst_frequency_error
        );
        s
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The mirror class of a node of the 8^3 grid (`i -> 7 - i`, `j -> 7 - j`).
    fn class(grid: &Grid, p: usize) -> [usize; 3] {
        let [i, j, k] = grid.ijk(p);
        [i.min(7 - i), j.min(7 - j), k]
    }

    #[test]
    fn sets_share_no_node_nor_mirror_image() {
        let grid = Grid::paper();
        let reference = Reference::new(&Material::object_a(), grid).unwrap();
        let mut seen = std::collections::HashMap::new();
        for (case, answer) in reference.cases.iter().zip(&reference.answers) {
            let nodes: Vec<usize> = match &case.load {
                Load::Forces(f) if case.kind == Kind::Point => vec![f.iter().position(|v| *v != 0.0).unwrap() / 3],
                Load::Forces(_) => continue,
                Load::Probe { .. } => answer.contacts.clone(),
            };
            assert!(!nodes.is_empty(), "{} touches nothing", case.id);
            for p in nodes {
                let set = *seen.entry(class(&grid, p)).or_insert(case.set);
                assert_eq!(set, case.set, "{}: node {p} is (a mirror image of) a node of the other set", case.id);
            }
        }
        // 2 mm at a cell's centre touches no node: 16 of the 18 probe cases remain.
        assert_eq!(reference.cases.iter().filter(|c| c.kind == Kind::Probe).count(), 16);
    }

    #[test]
    fn the_fem_scores_itself_exactly() {
        let grid = Grid::new(5).unwrap();
        let m = Material::object_b();
        let reference = Reference::new(&m, grid).unwrap();
        use crate::mechanics::fem::dynamics::Formulation;
        for f in [Formulation::Linear, Formulation::Corotational] {
            let r = evaluate(&reference, &m, Model::Fem(f), None).unwrap();
            assert!(r.worst_force_error < 1e-9 && r.worst_frequency_error < 1e-9, "{r:?}");
            assert!(r.cases.iter().all(|c| c.field_error < 1e-9));
        }
    }
}
