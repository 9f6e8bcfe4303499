//! The calibrated tissues shipped in `assets/`: the mass-spring parameters of the preset objects
//! `A` and `B` for each lattice topology, and the scores each was measured to have on the touch
//! benchmark's validation set (cases its calibration never saw).
//!
//! The shear and hex lattices are calibrated on the touch benchmark's training cases
//! (`calibrate --cases touch`), the paper's axis lattice on the paper's nine face loads (it has no
//! shear stiffness at rest, so no touch case can train it). The default tissue is the lattice
//! that scores best on the validation set: the hex lattice, for both objects.

use anyhow::Context as _;

use crate::mechanics::grid::{CUBE_SIDE_M, Grid};
use crate::mechanics::material::Material;
use crate::mechanics::msm::{MsmParams, Topology};

/// The topology of the default tissue (the viewer's, `simulate`'s and `validate`'s): the lattice
/// with the smallest validation force error (see [`shipped`] and `assets/`).
pub const DEFAULT_TOPOLOGY: Topology = Topology::Hex;

/// The validation scores recorded in a shipped tissue file (`validate --json`, validation set).
#[derive(Debug, Clone, Copy, PartialEq, serde::Serialize, serde::Deserialize)]
pub struct RecordedScores {
    /// Largest `|1 - compliance ratio|` over the validation touches.
    pub worst_force_error: f64,
    /// Median over the validation touches.
    pub median_force_error: f64,
    /// Largest `|1 - f / f_fem|` over the lowest six modes.
    pub worst_frequency_error: f64,
}

/// A shipped tissue: its parameters, the training cases of its calibration, and its recorded
/// validation scores (none for the axis lattice, which the touch benchmark cannot score).
#[derive(Debug, Clone, PartialEq, serde::Deserialize)]
pub struct Shipped {
    /// The parameters.
    pub params: MsmParams,
    /// `paper` or `touch`.
    #[serde(default = "paper_cases")]
    pub cases: CaseSet,
    /// Scores on the touch benchmark's validation set.
    #[serde(default)]
    pub validation: Option<RecordedScores>,
}

fn paper_cases() -> CaseSet {
    CaseSet::Paper
}

/// The training cases of a calibration (the static cost's), and of a shipped tissue.
#[derive(Debug, Clone, Copy, PartialEq, Eq, serde::Serialize, serde::Deserialize)]
#[serde(rename_all = "lowercase")]
pub enum CaseSet {
    /// The paper's nine clamped face loads (eq. 1), the default.
    Paper,
    /// The touch benchmark's training cases (point loads, top shear, probe).
    Touch,
    /// Both: the touch cost plus the paper's cost relative to the FEM's displacements.
    Both,
    /// The continuum's training presses: the material's probe force (`validate`'s 24 training
    /// presses), the model's node contact at its resolution.
    Presses,
}

impl CaseSet {
    /// The lower-case name used on the command line and in files.
    pub fn name(self) -> &'static str {
        match self {
            CaseSet::Paper => "paper",
            CaseSet::Touch => "touch",
            CaseSet::Both => "both",
            CaseSet::Presses => "presses",
        }
    }
}

/// The calibrated tissue parameters shipped in `assets/` for object `A` or `B` (see [`shipped`]).
pub fn tissue_params(material: &Material, topology: Topology) -> anyhow::Result<MsmParams> {
    Ok(shipped(material, topology)?.params)
}

/// The default tissue of a preset material ([`DEFAULT_TOPOLOGY`]).
pub fn default_params(material: &Material) -> anyhow::Result<MsmParams> {
    tissue_params(material, DEFAULT_TOPOLOGY)
}

/// The shipped tissue of object `A` or `B` for `topology`: the shear and hex lattices calibrated
/// on the touch benchmark's training cases, the axis lattice on the paper's cases (hybrid GA+SA,
/// seed 1, static cost, then the L-BFGS polish; see each file's `note`).
pub fn shipped(material: &Material, topology: Topology) -> anyhow::Result<Shipped> {
    // A preset's tissue wherever its constants are (a material file of them, a lump's background
    // among them), whatever the name.
    let preset = ["A", "B"].into_iter().find(|name| {
        Material::preset(name).is_some_and(|p| {
            p.symmetry == material.symmetry && p.constants == material.constants && p.density == material.density
        })
    });
    let Some(name) = preset else {
        anyhow::bail!(
            "no calibrated tissue is shipped for material {:?} (only the presets A and B); calibrate one",
            material.name
        );
    };
    let text = match (name, topology) {
        ("A", Topology::Shear) => include_str!("../../../../assets/tissue_A_shear.json"),
        ("B", Topology::Shear) => include_str!("../../../../assets/tissue_B_shear.json"),
        ("A", Topology::Axis) => include_str!("../../../../assets/tissue_A_axis.json"),
        ("B", Topology::Axis) => include_str!("../../../../assets/tissue_B_axis.json"),
        ("A", Topology::Hex) => include_str!("../../../../assets/tissue_A_hex.json"),
        ("B", Topology::Hex) => include_str!("../../../../assets/tissue_B_hex.json"),
        (other, _) => anyhow::bail!("no calibrated tissue is shipped for object {other:?}; calibrate one"),
    };
    serde_json::from_str(text).context("assets: invalid tissue file")
}

/// The compact surface compliance shipped for preset object `name` (A or B) in
/// `assets/compliance/` (`tissue-sim compliance --object NAME --out assets/compliance/NAME.bin`
/// wrote it), or `None` for another name.
pub fn compact_compliance(name: &str) -> Option<&'static [u8]> {
    match name {
        "A" => Some(include_bytes!("../../../../assets/compliance/A.bin")),
        "B" => Some(include_bytes!("../../../../assets/compliance/B.bin")),
        _ => None,
    }
}

/// The shipped 8^3 parameters carried to `grid` by their stiffness scale: `k ~ E L^2 / (n^2 h)`
/// per chain for the axis and shear lattices, `k ~ E h` per element for the hex lattice; the
/// nodal damping `d` with the node mass.
pub fn msm_params_at(material: &Material, topology: Topology, grid: &Grid) -> anyhow::Result<MsmParams> {
    let p = tissue_params(material, topology)?;
    let paper = Grid::paper();
    let chain = |g: &Grid| CUBE_SIDE_M * CUBE_SIDE_M / ((g.n() * g.n()) as f64 * g.h());
    let s = if topology == Topology::Hex { grid.h() / paper.h() } else { chain(grid) / chain(&paper) };
    let mass = (paper.num_nodes() as f64) / grid.num_nodes() as f64;
    let sc = |v: Option<f64>| v.map(|v| v * s);
    Ok(MsmParams {
        k1: p.k1 * s,
        k2: p.k2 * s,
        k3: p.k3 * s,
        d: p.d * mass,
        c12: sc(p.c12),
        c13: sc(p.c13),
        c23: sc(p.c23),
        b: sc(p.b),
    })
}
