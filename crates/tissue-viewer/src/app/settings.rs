//! What the viewer shows and the user sets: the pure view settings the panel edits directly
//! ([`ViewSettings`]) and the model-side state it displays ([`Shown`]), changed only by
//! `ViewerState::handle`.

use crate::calibrate::{CaseSet, GenerationStats, Method};
use crate::mechanics::cases::LoadCase;
use crate::mechanics::fem::dynamics::Formulation;
use crate::mechanics::material::Material;
use crate::mechanics::msm::{MsmParams, Topology};
use crate::render::scene::ColourMode;
use crate::sim::Integrator;
use crate::sim::Model;

/// What the left mouse button does on the 3D view.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum ToolKind {
    /// Rotates the camera.
    Orbit,
    /// Pulls the picked node.
    Drag,
    /// Presses the spherical probe.
    Probe,
}

/// Which material the viewer runs: one of the paper's objects, or a material file.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Source {
    /// A preset object.
    Object(crate::mechanics::object::Object),
    /// The material file at [`ViewSettings::material_path`].
    File,
}

/// Settings that only change what the UI shows or will ask for; the panel edits them directly.
#[derive(Debug, Clone)]
pub struct ViewSettings {
    /// The material.
    pub object: Source,
    /// The material file for `file`.
    pub material_path: String,
    /// The left-button tool.
    pub tool: ToolKind,
    /// Probe radius, mm.
    pub probe_radius_mm: f64,
    /// Push the probe along the view ray (else along the inward normal where it touches).
    pub probe_along_view: bool,
    /// Colour map.
    pub colour: ColourMode,
    /// Overlays.
    pub show_springs: bool,
    /// Node markers.
    pub show_nodes: bool,
    /// Fixed-face outline.
    pub show_fixed: bool,
    /// Load case to apply: axis (1-3) and force (N).
    pub case_axis: usize,
    /// See `case_axis`.
    pub case_force: f64,
    /// Calibration settings.
    pub calib_method: Method,
    /// Calibration seed.
    pub calib_seed: u64,
    /// Calibration generations.
    pub calib_generations: usize,
    /// Calibration population.
    pub calib_population: usize,
    /// Training cases of the calibration.
    pub calib_cases: CaseSet,
    /// Nodes per edge of the model's grid (the resolution).
    pub nodes: usize,
    /// Where the model's steps are computed.
    pub compute: crate::gpu::Compute,
    /// Where `view --record` writes the recording.
    pub recording: Option<std::path::PathBuf>,
    /// What a hidden lump is drawn from (find the lump).
    pub inclusion_ranges: crate::app::exercise::Ranges,
    /// The next hidden lump's seed.
    pub inclusion_seed: u64,
    /// Colour the top face by the palpation map, once computed.
    pub show_map: bool,
    /// The map's colour is its contrast against the material without its inclusions, not its
    /// force.
    pub map_contrast: bool,
}

impl Default for ViewSettings {
    fn default() -> Self {
        Self {
            object: Source::Object(crate::mechanics::object::Object::A),
            material_path: String::new(),
            tool: ToolKind::Drag,
            probe_radius_mm: crate::sim::press::DEFAULT_RADIUS_M * 1e3,
            probe_along_view: false,
            colour: ColourMode::Displacement,
            show_springs: false,
            show_nodes: false,
            show_fixed: true,
            case_axis: 1,
            case_force: 10.0,
            calib_method: Method::Hybrid,
            calib_seed: 1,
            // The polish reaches the optimum from wherever the search leaves it (10 x 10 found the
            // 50 x 100 run's cost to 1e-12 on both objects and three seeds), so the search only
            // places the start: 2.2 to 6.5 s for a lattice at 8^3 instead of 47 to 70 s.
            calib_generations: 10,
            calib_population: 10,
            calib_cases: CaseSet::Touch,
            nodes: crate::mechanics::grid::Grid::paper().n(),
            compute: crate::gpu::Compute::Cpu,
            recording: None,
            inclusion_ranges: crate::app::exercise::Ranges::default(),
            inclusion_seed: 1,
            show_map: true,
            map_contrast: false,
        }
    }
}

/// The model-side state the panel shows (changed only through `ViewerState::handle`).
#[derive(Debug, Clone)]
pub struct Shown {
    /// The material.
    pub material: Material,
    /// The file the material was read from (none for the paper's objects).
    pub material_file: Option<std::path::PathBuf>,
    /// The probe's contact: what the surface compliance job says (`None`: ready or not asked).
    pub contact_status: Option<String>,
    /// While the material's surface is not the probe's yet: when it will be, for the tag beside
    /// the sphere (`the material's in 12 s`, `the material's: loading`, or why never).
    pub material_contact_in: Option<String>,
    /// The parameters of the running model (the panel edits a copy).
    pub params: MsmParams,
    /// Integrator asked for (`None`: automatic).
    pub integrator: Option<Integrator>,
    /// Time step asked for, s.
    pub dt: f64,
    /// Damping ratio at the fundamental (all models but the paper's axis lattice).
    pub damping_ratio: f64,
    /// The applied load case, if any.
    pub case_active: Option<LoadCase>,
    /// Its FEM answer, once solved.
    pub fem_answer: Option<Vec<[f64; 3]>>,
    /// Calibration progress, one entry a generation.
    pub history: Vec<GenerationStats>,
    /// The calibration's result, to apply.
    pub result: Option<MsmParams>,
    /// The whole of the last calibration's outcome (its genes, cost and box), for the panel.
    pub calibration: Option<Box<crate::calibrate::CalibrationResult>>,
    /// The last Apply of a calibration's result: what ran before it (parameters and touch score).
    pub applied: Option<Applied>,
    /// Whether a calibration runs.
    pub calibrating: bool,
    /// Generations of the running calibration.
    pub calib_generations: usize,
    /// Training cases of the running calibration (its cost's unit).
    pub calib_cases: crate::calibrate::CaseSet,
    /// A note for the user.
    pub note: Option<String>,
    /// Probe force against depth (mm, N).
    pub force_depth: Vec<[f64; 2]>,
    /// The FEM runs instead of the lattice of `params` (kept for switching back).
    pub fem: Option<Formulation>,
    /// The running model's touch-benchmark scores (validation set), once computed, or why not.
    pub validation: Option<Result<crate::sim::shipped::RecordedScores, String>>,
    /// For a material with inclusions, the running model against the material with them
    /// ([`crate::validate::inclusions`]), once computed, or why not.
    pub inclusion_validation: Option<Result<crate::validate::inclusions::InclusionReport, String>>,
    /// The tool held now (drawn over the tissue).
    pub tool: crate::sim::Tool,
    /// The probe's last position (centre, radius; metres), kept after it is let go.
    pub last_probe: Option<([f64; 3], f64)>,
    /// The physics thread's last reading while the probe was pressed in, and the press of its
    /// step (kept after the probe is let go): what a comparison compares.
    pub last_reading: Option<(crate::sim::press::Press, crate::sim::press::ProbeReading)>,
    /// The last press compared with the material's force and the running model's, on request.
    pub comparison: Option<ProbeComparison>,
    /// Whether a comparison is computed.
    pub comparing: bool,
    /// The material file's inclusions: the probe feels them and the model steps them
    /// ([`Shown::modelled_material`]); `material` is their background (its calibrated tissue).
    pub inclusions: Vec<crate::mechanics::inclusion::Inclusion>,
    /// Find the lump, while under way (its lump hidden until marked).
    pub exercise: Option<crate::app::exercise::Exercise>,
    /// The palpation map of the top face, once computed (or why not), for the felt material.
    pub face_map: Option<Result<crate::app::face_map::FaceMap, String>>,
}

impl Shown {
    /// The material the model steps: the background with the file's inclusions (a hidden lump is
    /// felt by the probe, not stepped, so that the view does not show where it is).
    pub fn modelled_material(&self) -> Material {
        let mut m = self.material.clone();
        m.inclusions.clone_from(&self.inclusions);
        m
    }

    /// The material the probe feels: the background with the file's inclusions and the hidden
    /// lump.
    pub fn felt_material(&self) -> Material {
        let mut m = self.material.clone();
        m.inclusions.clone_from(&self.inclusions);
        m.inclusions.extend(self.exercise.iter().map(|e| e.lump.inclusion.clone()));
        m
    }

    /// The lattice of the running parameters.
    pub fn topology(&self) -> Topology {
        self.params.topology()
    }

    /// The running model.
    pub fn model(&self) -> Model {
        match self.fem {
            Some(f) => Model::Fem(f),
            None => Model::Lattice(self.topology()),
        }
    }
}

/// What ran before a calibration's result was applied, to show what changed.
#[derive(Debug, Clone, PartialEq)]
pub struct Applied {
    /// The running parameters before.
    pub from: MsmParams,
    /// Their touch validation scores, where they were computed.
    pub before: Option<crate::sim::shipped::RecordedScores>,
    /// The parameters applied (the score shown after is theirs only while they run).
    pub to: MsmParams,
}

/// One press of the probe set beside the material's force for it and the running model's own:
/// what the person felt, what the material gives, and what the model's nodes alone would give.
#[derive(Debug, Clone, PartialEq)]
pub struct ProbeComparison {
    /// The press compared: where the sphere was, along which direction, how deep.
    pub press: crate::sim::press::Press,
    /// The force shown for it (the physics thread's reading), newtons, and the contact that gave
    /// it.
    pub shown_n: f64,
    /// The contact of the shown force.
    pub shown_contact: crate::sim::press::Contact,
    /// The material's force on the same press at rest: the converged continuum (graded hex8
    /// refined until the force changes by less than 1 %), or why there is none.
    pub material_n: Result<f64, String>,
    /// The running model's static force on the same press with its own surface nodes as the
    /// contact (small displacements), or why there is none.
    pub model_n: Result<f64, String>,
}
