//! The tools on the running tissue: the drag (a split step, or inside an implicit solve) and
//! the probe's contact (the material's surface compliance, or the model's own nodes).

use super::Simulation;
use crate::mechanics::anchor::Anchor;
use crate::sim::integrator::Integrator;
use crate::sim::tool::{DRAG_DAMPING, DRAG_STIFFNESS, Tool, drag_velocity_change};
use glam::DVec3;

impl Simulation {
    /// Sets the probe's contact: on the material's surface compliance (`Some`), or the running
    /// model's surface nodes (`None`).
    pub fn set_surface_probe(&mut self, probe: Option<crate::sim::material_surface::SurfaceProbe>) {
        self.surface_probe = probe;
    }

    /// Whether the probe pushes back through the material's surface compliance.
    pub fn has_surface_probe(&self) -> bool {
        self.surface_probe.is_some()
    }

    /// The probe's contact on the material's surface compliance, where it has one: the surface
    /// nodes the sphere holds, the sphere's normal at each and its force.
    pub fn surface_contact(&self) -> impl Iterator<Item = (usize, [f64; 3], f64)> + '_ {
        self.surface_probe.iter().flat_map(|p| p.contact())
    }

    /// Puts the tool's loads on the tissue. A probe takes its force from the material's surface
    /// compliance where the simulation has one; a contact that cannot be
    /// solved there is an error naming its cause (never another contact's force under its name).
    pub(super) fn apply_tool_load(&mut self) -> Result<(), String> {
        if self.tool == Tool::None {
            self.tool_force = [0.0; 3];
        }
        self.probe_on_surface = false;
        let carries = self.tissue.carries_contact_loads();
        // The load is taken only where it changes (a GPU step sends it again when taken).
        if let Some(nodes) = span(self.tool_loaded.nodes().iter().copied()) {
            let f_ext = self.tissue.f_ext_mut_nodes(nodes);
            for &p in self.tool_loaded.nodes() {
                for c in 0..3 {
                    f_ext[c][p] = self.base_load[c][p];
                }
            }
            self.tool_loaded.clear();
        }
        let on_surface = match (self.tool, self.surface_probe.as_mut()) {
            (Tool::Probe { centre, radius }, Some(probe)) => match probe.update(centre, radius, self.dt) {
                Ok(force) => Some(force),
                Err(e) => {
                    probe.release();
                    return Err(format!("the probe's contact on the material's surface failed: {e}"));
                }
            },
            _ => None,
        };
        if let (Some(force), Some(probe)) = (on_surface, self.surface_probe.as_ref()) {
            if carries && let Some(nodes) = span(probe.loads().iter().map(|&(node, _)| node)) {
                let f_ext = self.tissue.f_ext_mut_nodes(nodes);
                for &(node, f) in probe.loads() {
                    for c in 0..3 {
                        f_ext[c][node] += f[c];
                    }
                    self.tool_loaded.mark(node);
                }
            }
            self.tool_force = force;
            self.probe_on_surface = true;
        } else if let Some(probe) = self.surface_probe.as_mut() {
            probe.release();
        }
        Ok(())
    }

    /// Whether the probe's last force came from the material's surface compliance (else, while
    /// it touches, from the model's surface nodes).
    pub fn probe_on_surface(&self) -> bool {
        self.probe_on_surface
    }

    /// Under an implicit scheme, the dragging spring goes inside the tissue's solve
    /// ([`crate::mechanics::anchor`]): its node anchored, its pull at the step's start added to
    /// the node's load. Says whether it did (not under symplectic Euler, on a fixed node or for
    /// a model without implicit steps: then [`Simulation::drag_step`] follows the step).
    pub(super) fn anchor_drag(&mut self) -> bool {
        let held = match self.tool {
            Tool::Drag { node, target }
                if self.integrator != Integrator::Symplectic && self.tissue.free()[node] != 0.0 =>
            {
                Some((node, target))
            }
            _ => None,
        };
        let Some((node, target)) = held else {
            self.tissue.set_anchor(None);
            return false;
        };
        if !self.tissue.set_anchor(Some(Anchor { node, stiffness: DRAG_STIFFNESS, damping: DRAG_DAMPING })) {
            return false;
        }
        let pull: [f64; 3] = std::array::from_fn(|c| DRAG_STIFFNESS * (target[c] - self.tissue.x()[c][node]));
        let f_ext = self.tissue.f_ext_mut_nodes(node..node + 1);
        for c in 0..3 {
            f_ext[c][node] += pull[c];
        }
        self.tool_loaded.mark(node);
        true
    }

    /// The anchored drag's force on the hand: minus the spring and damper's on the node at the
    /// step's end.
    pub(super) fn anchored_drag_force(&mut self) {
        let Tool::Drag { node, target } = self.tool else {
            return;
        };
        let (x, v) = (self.tissue.x(), self.tissue.v());
        self.tool_force =
            std::array::from_fn(|c| -(DRAG_STIFFNESS * (target[c] - x[c][node]) - DRAG_DAMPING * v[c][node]));
    }

    /// The dragging spring's split step on its node after the tissue's symplectic Euler step
    /// ([`drag_velocity_change`]), and its force on the hand. A fixed node does not move: the
    /// hand feels the spring's static pull.
    pub(super) fn drag_step(&mut self) {
        let Tool::Drag { node, target } = self.tool else {
            return;
        };
        let (x, v) = (self.tissue.x(), self.tissue.v());
        let (xn, vn): ([f64; 3], [f64; 3]) = (std::array::from_fn(|c| x[c][node]), std::array::from_fn(|c| v[c][node]));
        if self.tissue.free()[node] == 0.0 {
            self.tool_force = std::array::from_fn(|c| -DRAG_STIFFNESS * (target[c] - xn[c]));
            return;
        }
        let m = self.tissue.node_mass(node);
        let dv = drag_velocity_change(target, xn, vn, m, self.dt);
        let (x, v) = self.tissue.x_v_mut();
        for c in 0..3 {
            v[c][node] += dv[c];
            x[c][node] += self.dt * dv[c];
        }
        self.tool_force = dv.map(|d| -m * d / self.dt);
    }

    /// Whether this step's probe acts by the model's own node contact: with the surface
    /// compliance the hand feels its force, and only a model that cannot carry its loads shows
    /// the press by its own nodes.
    pub(super) fn node_contact(&self) -> bool {
        matches!(self.tool, Tool::Probe { .. }) && !(self.probe_on_surface && self.tissue.carries_contact_loads())
    }

    /// Moves nodes inside the probe sphere onto it (along their normal at the step's start),
    /// gives their velocity that move, removes their inward velocity, and sums the tissue's push
    /// on the probe (the inward part of each contact node's spring force).
    pub(super) fn enforce_contact(&mut self) {
        let Tool::Probe { centre, radius } = self.tool else {
            return;
        };
        if !self.node_contact() {
            return;
        }
        let mut push = [0.0; 3];
        // The force on every node before any is projected, for the push on the probe; not needed
        // where the probe's force comes from the material's surface compliance.
        let reads_push = !self.probe_on_surface;
        if reads_push {
            let computed = self.tissue.forces();
            for c in 0..3 {
                self.contact_forces[c].copy_from_slice(&computed[c]);
            }
        }
        for &p in &self.surface {
            if self.tissue.free()[p] == 0.0 {
                continue;
            }
            let x = self.tissue.x();
            let d = [x[0][p] - centre[0], x[1][p] - centre[1], x[2][p] - centre[2]];
            let dist = DVec3::from(d).length();
            if dist >= radius {
                continue;
            }
            // Moved onto the sphere along its normal at the step's start, not radially (SHAKE's
            // projection), and the velocity given the move over the step: a radial projection
            // scaled the node's slide over the sphere without a matching velocity, which fed
            // energy in (a 16^3 FEM under a held 4 mm press rang at 10 to 15 m/s).
            let start = DVec3::from(std::array::from_fn(|c| self.step_start_x[c][p])) - DVec3::from(centre);
            let n0 = if start.length() > 1e-12 { start / start.length() } else { DVec3::Z };
            let (inside, along) = (DVec3::from(d), DVec3::from(d).dot(n0));
            let mu = -along + (along * along - inside.length_squared() + radius * radius).max(0.0).sqrt();
            let on = inside + mu * n0;
            let n = (on / on.length()).to_array();
            let dt = self.dt;
            let (x, v) = self.tissue.x_v_mut();
            for c in 0..3 {
                let projected = centre[c] + radius * n[c];
                v[c][p] += (projected - x[c][p]) / dt;
                x[c][p] = projected;
            }
            let vn = v[0][p] * n[0] + v[1][p] * n[1] + v[2][p] * n[2];
            if vn < 0.0 {
                for c in 0..3 {
                    v[c][p] -= vn * n[c];
                }
            }
            if reads_push {
                let f = DVec3::from(std::array::from_fn(|c| self.contact_forces[c][p]));
                let fn_ = f.dot(DVec3::from(n));
                if fn_ < 0.0 {
                    for c in 0..3 {
                        push[c] += fn_ * n[c];
                    }
                }
            }
        }
        if reads_push {
            self.tool_force = push;
        }
    }
}

/// The range from the least to the greatest of `nodes` (`None` for none).
fn span(nodes: impl Iterator<Item = usize>) -> Option<std::ops::Range<usize>> {
    nodes.fold(None, |r: Option<std::ops::Range<usize>>, p| {
        Some(r.map_or(p..p + 1, |r| r.start.min(p)..r.end.max(p + 1)))
    })
}

/// A set of nodes, each listed once, that allocates nothing after it is made.
#[derive(Debug)]
pub(super) struct MarkedNodes {
    nodes: Vec<usize>,
    marked: Vec<bool>,
}

impl MarkedNodes {
    pub(super) fn new(num_nodes: usize) -> Self {
        Self { nodes: Vec::with_capacity(num_nodes), marked: vec![false; num_nodes] }
    }

    pub(super) fn mark(&mut self, node: usize) {
        if !std::mem::replace(&mut self.marked[node], true) {
            self.nodes.push(node);
        }
    }

    pub(super) fn nodes(&self) -> &[usize] {
        &self.nodes
    }

    pub(super) fn clear(&mut self) {
        for &p in &self.nodes {
            self.marked[p] = false;
        }
        self.nodes.clear();
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::mechanics::cases::LoadCase;
    use crate::mechanics::fem::dynamics::Formulation;
    use crate::mechanics::material::Material;
    use crate::sim::model::Model;

    /// The drag does not bound the step: the viewer's FEM at its 1 ms tick runs the tissue's own
    /// substeps, prefactored Euler asked for at 1 ms is accepted, and a cube corner dragged at
    /// 16^3 (a 37 mg node, whose damper alone once held the step to 70 us) settles where the
    /// spring's pull balances the tissue's push, which the hand feels.
    #[test]
    pub(super) fn the_drag_does_not_bound_the_step() {
        let material = Material::object_a();
        let tissue = Model::Fem(Formulation::Linear).build(&material, None, 0.2).expect("fem");
        let grid = tissue.grid();
        let case = LoadCase::bottom_clamp(&grid, "A");
        let mut sim = Simulation::with_tissue(tissue, Integrator::Symplectic, 1e-3, Some(&case));
        assert!(sim.try_set_integrator(Some(Integrator::Prefactored), 1e-3).is_ok());
        sim.set_integrator(None, 1e-3);
        assert_eq!(sim.integrator, Integrator::Symplectic);
        assert!(sim.dt <= sim.limit().auto_fraction() * sim.dt_limit() && sim.dt > 0.5 * sim.dt_limit(), "{}", sim.dt);

        let grid = crate::mechanics::grid::Grid::new(16).expect("grid");
        let tissue = Model::Lattice(crate::mechanics::msm::Topology::Hex).build_on(grid, &material, None, 0.2);
        let case = LoadCase::bottom_clamp(&grid, "A");
        let mut sim = Simulation::with_tissue(tissue.expect("hex"), Integrator::Symplectic, 1e-3, Some(&case));
        sim.set_integrator(None, 1e-3);
        let corner = grid.num_nodes() - 1;
        let rest = grid.position(corner);
        let target = [rest[0] + 0.01, rest[1], rest[2]];
        sim.tool = Tool::Drag { node: corner, target };
        let mut forces = Vec::new();
        for _ in 0..(0.4 / sim.dt).round() as usize {
            sim.step().expect("no blow-up");
            forces.push(sim.tool_force[0]);
        }
        let x = sim.tissue.x()[0][corner];
        let pull = DRAG_STIFFNESS * (target[0] - x);
        let last = forces[forces.len() - 1];
        assert!(pull > 0.5 && (last + pull).abs() < 1e-3 * pull, "pull {pull} N, felt {last} N");
        assert!(forces.iter().all(|f| f.abs() <= 1.2 * DRAG_STIFFNESS * 0.01), "{forces:?}");
    }

    /// The probe's loads on the nodes (restored node by node, not copied whole each step) go
    /// when it lifts: the loads are the case's again, bit for bit.
    #[test]
    pub(super) fn the_probes_loads_go_when_it_lifts() {
        let material = Material::object_a();
        let grid = crate::mechanics::grid::Grid::new(6).expect("grid");
        let tissue = Model::Lattice(crate::mechanics::msm::Topology::Hex).build_on(grid, &material, None, 0.2);
        let case = LoadCase::bottom_clamp(&grid, "A");
        let mut sim = Simulation::with_tissue(tissue.expect("hex"), Integrator::Symplectic, 1e-4, Some(&case));
        let base = sim.tissue.f_ext_mut().clone();
        let compliance =
            crate::sim::material_surface::compliance::SurfaceCompliance::compute(&material, 10, &mut |_| true)
                .expect("c");
        let surface = crate::sim::material_surface::MaterialSurface {
            compliance: std::sync::Arc::new(compliance),
            modes: std::sync::Arc::new(
                crate::sim::material_surface::modal_lag::ModalBasis::of_material(&material).expect("modes"),
            ),
        };
        sim.set_surface_probe(Some(crate::sim::material_surface::SurfaceProbe::on(&surface, grid, Some(0.2))));
        for i in 0..20 {
            let centre = [0.03 + 1e-3 * i as f64, 0.05, 0.1 + 0.015 - 0.003];
            sim.tool = Tool::Probe { centre, radius: 0.015 };
            sim.step().expect("step");
            assert!(sim.tissue.f_ext_mut() != &base, "the probe loads the nodes under it");
        }
        sim.tool = Tool::None;
        sim.step().expect("step");
        assert!(sim.tissue.f_ext_mut() == &base, "the case's loads once the probe lifts");
    }

    /// A contact the material's surface compliance cannot solve (here a singular one) stops the
    /// run with its cause and lets the probe go: before, the simulation took the force from the
    /// model's nodes under the surface's name.
    #[test]
    fn a_surface_contact_that_cannot_be_solved_is_an_error_not_a_fallback() {
        use crate::sim::material_surface::compliance::SurfaceCompliance;
        let material = Material::object_a();
        let tissue = Model::Lattice(crate::mechanics::msm::Topology::Hex).build(&material, None, 0.2).expect("hex");
        let grid = tissue.grid();
        let case = LoadCase::bottom_clamp(&grid, "A");
        let mut sim = Simulation::with_tissue(tissue, Integrator::Symplectic, 1e-4, Some(&case));
        let singular = std::sync::Arc::new(SurfaceCompliance::uniform(4, 0.0));
        sim.set_surface_probe(Some(crate::sim::material_surface::SurfaceProbe::new(singular, grid)));
        sim.tool = Tool::Probe { centre: [0.05, 0.05, 0.1 + 0.015 - 0.004], radius: 0.015 };
        let e = sim.step().expect_err("the contact cannot be solved");
        assert!(e.fatal && e.message.contains("contact on the material's surface failed"), "{e:?}");
        assert_eq!(sim.tool, Tool::None);
        assert_eq!(sim.tool_force, [0.0; 3]);
    }
}
