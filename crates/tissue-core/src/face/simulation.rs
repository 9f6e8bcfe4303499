//! The simulation as a program drives it: built with the viewer's defaults, pressed, dragged,
//! run, read.

use std::path::PathBuf;

use crate::mechanics::cases::LoadCase;
use crate::mechanics::grid::Grid;
use crate::response::damping::{DEFAULT_DAMPING_RATIO, check_ratio};
use crate::sim::material_surface::{MaterialSurface, SurfaceProbe};
use crate::sim::press::{Contact, Press, ProbeReading};
use crate::sim::{Integrator, Model, Tool};

use super::{Error, Material};

/// The step asked for unless one is given, seconds: the viewer's and the scripts' (the automatic
/// choice may substep it).
pub const DEFAULT_DT_S: f64 = 1e-4;

/// How a [`Simulation`] is built; each choice has the viewer's default.
///
/// | choice | default |
/// |---|---|
/// | [`model`](SimulationBuilder::model) | the default tissue: the hex lattice calibrated for the material (`Model::Lattice(Topology::Hex)`) |
/// | [`nodes`](SimulationBuilder::nodes) | 8 nodes per edge (the paper's grid), 4 to 64 |
/// | [`integrator`](SimulationBuilder::integrator) | automatic: the step policy's choice for the model at the step |
/// | [`dt`](SimulationBuilder::dt) | [`DEFAULT_DT_S`] (0.1 ms) |
/// | [`damping_ratio`](SimulationBuilder::damping_ratio) | 0.2 at the fundamental (not for the paper's axis lattice, which keeps its nodal damping) |
/// | [`contact`](SimulationBuilder::contact) | [`Contact::Surface`]: the probe's force is the material's (its surface compliance and slow modes) |
/// | [`cache_dir`](SimulationBuilder::cache_dir) | the user's cache folder (`$XDG_CACHE_HOME/tissue-sim`, else `~/.cache/tissue-sim`) |
///
/// The bottom face (z = 0) is held, as in the viewer. With the surface contact, the material's
/// surface compliance is read from the cache folder, or computed there the first time for a
/// material (about a minute on one core) and kept.
#[derive(Debug, Clone)]
pub struct SimulationBuilder {
    material: Material,
    model: Model,
    nodes: usize,
    integrator: Option<Integrator>,
    dt: f64,
    damping_ratio: Option<f64>,
    contact: Contact,
    cache_dir: Option<PathBuf>,
}

impl SimulationBuilder {
    /// The model that shows the tissue ([`Model`]: a lattice or the FEM).
    #[must_use]
    pub fn model(mut self, model: Model) -> Self {
        self.model = model;
        self
    }

    /// Nodes per edge of the model's grid.
    #[must_use]
    pub fn nodes(mut self, nodes: usize) -> Self {
        self.nodes = nodes;
        self
    }

    /// The integrator, in place of the automatic choice (refused by [`SimulationBuilder::build`]
    /// where the step policy refuses it at the step).
    #[must_use]
    pub fn integrator(mut self, integrator: Integrator) -> Self {
        self.integrator = Some(integrator);
        self
    }

    /// The step asked for, seconds.
    #[must_use]
    pub fn dt(mut self, dt: f64) -> Self {
        self.dt = dt;
        self
    }

    /// The damping ratio at the model's fundamental, 0 (undamped) to 2.
    #[must_use]
    pub fn damping_ratio(mut self, zeta: f64) -> Self {
        self.damping_ratio = Some(zeta);
        self
    }

    /// The probe's contact.
    #[must_use]
    pub fn contact(mut self, contact: Contact) -> Self {
        self.contact = contact;
        self
    }

    /// Where the material's surface compliance is kept.
    #[must_use]
    pub fn cache_dir(mut self, dir: impl Into<PathBuf>) -> Self {
        self.cache_dir = Some(dir.into());
        self
    }

    /// The simulation at rest, or why it cannot be built (a choice out of range, a step the
    /// policy refuses, a model or compliance that cannot be computed).
    pub fn build(self) -> Result<Simulation, Error> {
        let grid = Grid::new(self.nodes).map_err(|e| Error::Input(e.to_string()))?;
        if self.damping_ratio.is_some() && !self.model.takes_damping_ratio() {
            return Err(Error::Input(format!(
                "a damping ratio is not for the axis lattice: {}",
                crate::response::modal::AXIS_HAS_NO_MODES
            )));
        }
        let zeta = check_ratio(self.damping_ratio.unwrap_or(DEFAULT_DAMPING_RATIO)).map_err(Error::Input)?;
        crate::sim::check_dt(self.dt).map_err(Error::Input)?;
        let material = self.material.constants_ref();
        let tissue = self.model.build_on(grid, material, None, zeta).map_err(Error::compute)?;
        let case = LoadCase::bottom_clamp(&grid, &material.name);
        let mut sim = crate::sim::Simulation::with_tissue(tissue, Integrator::Symplectic, self.dt, Some(&case));
        sim.try_set_integrator(self.integrator, self.dt).map_err(Error::Input)?;
        if self.contact == Contact::Surface {
            let dir = self.cache_dir.or_else(crate::io::cache_dir);
            let surface = MaterialSurface::load_or_compute(material, dir.as_deref(), &mut |_| true)
                .map_err(|e| Error::compute(format_args!("the material's surface compliance: {e:#}")))?;
            let ratio = sim.tissue.damping().ratio();
            sim.set_surface_probe(Some(SurfaceProbe::on(&surface, grid, ratio)));
        }
        let positions = vec![[0.0; 3]; grid.num_nodes()];
        Ok(Simulation { sim, model: self.model, contact: self.contact, press: None, refused: None, positions })
    }
}

/// The running tissue: a model of the material stepped in real time under the step policy, with
/// a probe (a rigid sphere) or a drag (a stiff spring on a node), and a guard that undoes a
/// blow-up.
///
/// ```
/// use tissue_core::prelude::*;
///
/// let material = Material::object(Object::B);
/// // The model's own nodes take the probe here (no surface compliance to compute).
/// let mut sim = Simulation::builder(&material).contact(Contact::Nodes).build()?;
/// assert_eq!(sim.positions().len(), 8 * 8 * 8);
/// sim.drag(511, [0.104, 0.1, 0.1]); // the top corner pulled 4 mm along x
/// sim.run_for(0.3)?;
/// let corner = sim.positions()[511];
/// assert!(corner[0] > 0.1 && corner[0] < 0.104, "{corner:?}");
/// assert!(sim.tool_force()[0] < 0.0); // the tissue pulls the hand back
/// sim.release();
/// sim.run_for(0.5)?;
/// assert!(sim.positions()[511][0] < corner[0]);
/// # Ok::<(), Error>(())
/// ```
#[derive(Debug)]
pub struct Simulation {
    sim: crate::sim::Simulation,
    model: Model,
    contact: Contact,
    press: Option<Press>,
    /// A press or drag refused at the next step (checked when it was given).
    refused: Option<String>,
    positions: Vec<[f64; 3]>,
}

impl Simulation {
    /// A builder with the viewer's defaults ([`SimulationBuilder`]).
    pub fn builder(material: &Material) -> SimulationBuilder {
        SimulationBuilder {
            material: material.clone(),
            model: Model::Lattice(crate::sim::shipped::DEFAULT_TOPOLOGY),
            nodes: Grid::paper().n(),
            integrator: None,
            dt: DEFAULT_DT_S,
            damping_ratio: None,
            contact: Contact::Surface,
            cache_dir: None,
        }
    }

    /// Presses the probe: from the next step the sphere is where `press` puts it (tangent to
    /// the undeformed surface at its point, moved its depth along its direction). A press the
    /// contact cannot resolve (radius 5 to 50 mm, depth at most 3/4 of the radius, from on or
    /// outside the surface into it, not into the held bottom face) is refused by the next
    /// [`Simulation::step`] or [`Simulation::run_for`]. Move the sphere gradually by pressing
    /// again between steps.
    pub fn press(&mut self, press: Press) {
        let surface = self.contact == Contact::Surface;
        let held = |p: [f64; 3]| p[2] < 1e-9;
        let d = press.direction();
        self.refused = crate::sim::press::check(press.at, d, press.radius, press.depth, surface, &held)
            .err()
            .map(|why| format!("press: {why}"));
        if self.refused.is_none() {
            self.sim.tool = press.tool();
            self.press = Some(press);
        }
    }

    /// Pulls `node` (an index on the grid, x fastest, then y, then z, as in `assets/CONVENTIONS.md`) towards
    /// `target` (metres) by a stiff spring (1000 N/m); a node not on the grid is refused by the
    /// next step.
    pub fn drag(&mut self, node: usize, target: [f64; 3]) {
        let n = self.sim.tissue.grid().num_nodes();
        if node >= n || target.iter().any(|v| !v.is_finite()) {
            self.refused = Some(format!("drag: node {node} to {target:?}: the grid's nodes are 0 to {}", n - 1));
            return;
        }
        self.refused = None;
        self.press = None;
        self.sim.tool = Tool::Drag { node, target };
    }

    /// Lets go of the probe or the drag.
    pub fn release(&mut self) {
        self.sim.tool = Tool::None;
        self.sim.tool_force = [0.0; 3];
        self.press = None;
        self.refused = None;
    }

    /// One step. A blow-up the guard recovers from is undone (the last good state back) and the
    /// run goes on; one it gives up on is an [`Error::BlowUp`].
    pub fn step(&mut self) -> Result<(), Error> {
        if let Some(why) = self.refused.take() {
            return Err(Error::Input(why));
        }
        match self.sim.step() {
            Err(b) if b.fatal => {
                self.press = None;
                Err(Error::BlowUp(b))
            }
            _ => Ok(()),
        }
    }

    /// Steps for `seconds` of simulated time (rounded to whole steps).
    pub fn run_for(&mut self, seconds: f64) -> Result<(), Error> {
        if !(seconds.is_finite() && (0.0..=3600.0).contains(&seconds)) {
            return Err(Error::Input(format!("run_for: {seconds} s is not a time from 0 to 3600 s")));
        }
        let steps = (seconds / self.sim.dt).round() as u64;
        for _ in 0..steps {
            self.step()?;
        }
        Ok(())
    }

    /// The probe's reading of the last step while pressed, else `None`.
    pub fn probe(&self) -> Option<ProbeReading> {
        self.press.as_ref().map(|p| ProbeReading::of(&self.sim, p))
    }

    /// The tissue's force on the tool of the last step (probe or drag), newtons.
    pub fn tool_force(&self) -> [f64; 3] {
        self.sim.tool_force
    }

    /// Node positions now, metres, one row a node (the grid's order).
    pub fn positions(&mut self) -> &[[f64; 3]] {
        let x = self.sim.tissue.x();
        for (p, row) in self.positions.iter_mut().enumerate() {
            *row = [x[0][p], x[1][p], x[2][p]];
        }
        &self.positions
    }

    /// Simulated time, seconds.
    pub fn time_s(&self) -> f64 {
        self.sim.time_s
    }

    /// The step the policy runs, seconds.
    pub fn dt(&self) -> f64 {
        self.sim.dt
    }

    /// The integrator the policy runs.
    pub fn integrator(&self) -> Integrator {
        self.sim.integrator
    }

    /// The model that shows the tissue.
    pub fn model(&self) -> Model {
        self.model
    }

    /// Nodes per edge of the model's grid.
    pub fn nodes(&self) -> usize {
        self.sim.tissue.grid().n()
    }

    /// Back to rest, nothing held.
    pub fn reset(&mut self) {
        self.release();
        self.sim.reset();
    }
}
