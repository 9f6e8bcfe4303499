//! The spec's node displacement file (`shared/spec/benchmark.md`): the answers of the load cases
//! of a FEM or MSM model, as `fem` and `msm` write them.

use serde::{Deserialize, Serialize};

use crate::mechanics::cases::CaseSolution;

/// One case of a displacement file.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct CaseRecord {
    /// Spec case id.
    pub case_id: String,
    /// Loaded axis, 1-based.
    pub axis: usize,
    /// Applied force, newtons.
    #[serde(rename = "force_N")]
    pub force_n: f64,
    /// Row `n` = displacement of node `n`, metres.
    pub displacements: Vec<[f64; 3]>,
    /// Sum of support reactions, newtons (an extra key).
    #[serde(rename = "reaction_N", default, skip_serializing_if = "Option::is_none")]
    pub reaction_n: Option<[f64; 3]>,
}

/// A node displacement file (FEM or MSM).
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct DisplacementFile {
    /// Object label (`A`, `B`, or a material file's name).
    pub object: String,
    /// `clamped` or `patch`.
    pub bc: String,
    /// `fem` or `msm`.
    pub model: String,
    /// Nodes per axis.
    pub nodes_per_axis: usize,
    /// The cases.
    pub cases: Vec<CaseRecord>,
    /// MSM parameters, for an MSM file (an extra key).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub params: Option<crate::mechanics::msm::MsmParams>,
}

impl DisplacementFile {
    /// Checks that every displacement and reaction is finite (before the file is written).
    pub fn check_finite(&self) -> anyhow::Result<()> {
        for c in &self.cases {
            let reaction = c.reaction_n.iter().flatten();
            if !c.displacements.iter().flatten().chain(reaction).all(|v| v.is_finite()) {
                anyhow::bail!(
                    "the {} answer of case {} is not finite (the parameters are outside what floating point can \
                     represent); nothing was written",
                    self.model,
                    c.case_id
                );
            }
        }
        Ok(())
    }
}

impl CaseRecord {
    /// The record of a solved case.
    pub fn from_solution(s: &CaseSolution) -> Self {
        Self {
            case_id: s.case_id.clone(),
            axis: s.axis,
            force_n: s.force_n,
            displacements: s.displacements.clone(),
            reaction_n: Some(s.reaction_n),
        }
    }
}
