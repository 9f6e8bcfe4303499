//! The material's answer to the probe: a rigid frictionless sphere pressed into a free face of the
//! clamped cube (face z = 0 held), from the project's hex8 FEM on tensor-product meshes graded
//! around the contact ([`crate::mechanics::fem::graded`]), refined until the force changes by less
//! than a tolerance. This is the reference a probe's force is scored against: it does not depend
//! on any model's grid.
//!
//! Contact is frictionless and linearised, as the rest of the project's statics: every surface
//! node in contact is put on the sphere along the sphere's normal at rest, with an active set so
//! that no contact pulls and no surface node ends inside. The contact problem is condensed onto
//! the surface nodes near the sphere (their compliance, from batched solves with the factor).
//!
//! [`tap`]: the material's fast tap; [`cache`]: where the answers are kept.

pub mod cache;
pub mod tap;

use std::collections::HashMap;

use crate::mechanics::fem::graded::{GradedFem, GradedMesh};
use crate::mechanics::material::Material;
use crate::response::contact;
pub use crate::sim::press::{Press, free_face_normal};

/// The fine spacings tried, coarsest first, in units of the press's Hertz contact radius
/// `sqrt(R d)` (at 15 mm and 2 mm: 2.0, 1.5, 1.125, 0.84, 0.63 and 0.47 mm; the last two only
/// where a shallow press on an edge or a corner has not converged before).
pub const SPACING_RATIOS: [f64; 6] = [0.365, 0.274, 0.205, 0.154, 0.115, 0.086];
/// Growth of the element size away from the contact.
pub const GROWTH: f64 = 1.45;
/// Default convergence tolerance: relative change of the force between two spacings.
pub const DEFAULT_TOLERANCE: f64 = 0.01;
/// Surface nodes whose contact compliance is solved for in one batch.
const BATCH_NODES: usize = 16;

/// The material's force on one press.
#[derive(Debug, Clone, PartialEq, serde::Serialize, serde::Deserialize)]
pub struct ContinuumForce {
    /// Force of the tissue on the sphere at the finest spacing used, newtons.
    pub force: [f64; 3],
    /// Its component against the pressing direction, newtons.
    pub force_n: f64,
    /// The spacings tried and the `force_n` each gave, metres and newtons.
    pub levels: Vec<(f64, f64)>,
    /// Relative change of `force_n` between the last two spacings.
    pub change: f64,
    /// Surface nodes in contact at the finest spacing.
    pub contacts: usize,
}

/// One press on one mesh: the factor, the surface window and the compliance columns solved so far.
struct PointSolve {
    fem: GradedFem,
    window: Vec<usize>,
    /// Per solved node: displacements of the window's dofs under unit loads along x, y and z.
    columns: HashMap<usize, [Vec<f64>; 3]>,
}

impl PointSolve {
    fn new(material: &Material, press: &Press, fine: f64) -> anyhow::Result<Self> {
        // The fine region covers the sphere's section through the face at rest, and two spacings.
        let reach = (2.0 * press.radius * press.depth).sqrt();
        let mesh = GradedMesh::around(press.at, fine, reach + 2.0 * fine, GROWTH);
        let fem = GradedFem::clamped_bottom(mesh, material)?;
        // Surface nodes a sphere can reach: rest gap above minus the depth (and a spacing).
        let window: Vec<usize> = (0..fem.mesh.num_nodes())
            .filter(|&p| fem.mesh.on_boundary(p) && !fem.fixed[3 * p])
            .filter(|&p| gap(press, fem.mesh.position(p)).1 > -(press.depth + 2.0 * fine))
            .collect();
        Ok(Self { fem, window, columns: HashMap::new() })
    }

    /// Solves the unit-load columns of `nodes` not solved yet, in batches.
    fn ensure(&mut self, nodes: &[usize]) -> anyhow::Result<()> {
        let missing: Vec<usize> = nodes.iter().copied().filter(|p| !self.columns.contains_key(p)).collect();
        let n = self.fixed_len();
        for batch in missing.chunks(BATCH_NODES) {
            let cols = 3 * batch.len();
            let mut rhs = vec![0.0; n * cols];
            for (b, &p) in batch.iter().enumerate() {
                for c in 0..3 {
                    rhs[(3 * b + c) * n + 3 * p + c] = 1.0;
                }
            }
            self.fem.solve_columns(&mut rhs, cols)?;
            for (b, &p) in batch.iter().enumerate() {
                let restrict = |c: usize| {
                    let col = &rhs[(3 * b + c) * n..(3 * b + c + 1) * n];
                    self.window.iter().flat_map(|&q| [col[3 * q], col[3 * q + 1], col[3 * q + 2]]).collect()
                };
                let three = [restrict(0), restrict(1), restrict(2)];
                self.columns.insert(p, three);
            }
        }
        Ok(())
    }

    fn fixed_len(&self) -> usize {
        self.fem.fixed.len()
    }

    /// The contact of one press ([`contact::solve`]): force on the sphere and contact count.
    fn press(&mut self, press: &Press) -> anyhow::Result<([f64; 3], usize)> {
        let mut scratch = contact::ContactScratch::default();
        let back = press.direction().map(|c| -c);
        let mesh = &self.fem.mesh;
        scratch.candidates.extend(
            self.window.iter().map(|&p| contact::sphere_gap(press.centre(), press.radius, mesh.position(p), back)),
        );
        contact::solve(self, &mut scratch, 1e-9 * press.radius)?;
        Ok((scratch.force(), scratch.active.len()))
    }
}

impl contact::Compliance for PointSolve {
    fn prepare(&mut self, slots: &[usize]) -> Result<(), contact::ContactError> {
        let nodes: Vec<usize> = slots.iter().map(|&w| self.window[w]).collect();
        self.ensure(&nodes).map_err(|e| contact::ContactError::Body(format!("{e:#}")))
    }

    fn normal(&self, i: usize, n_i: [f64; 3], j: usize, n_j: [f64; 3]) -> f64 {
        let cols = &self.columns[&self.window[j]];
        (0..3).map(|c| n_j[c] * (0..3).map(|d| n_i[d] * cols[c][3 * i + d]).sum::<f64>()).sum()
    }
}

/// Outward normal from the sphere's centre to `x` and the depth of `x` inside the sphere.
fn gap(press: &Press, x: [f64; 3]) -> ([f64; 3], f64) {
    contact::sphere_gap(press.centre(), press.radius, x, press.direction().map(|c| -c))
}

/// The material's force on `press`, refining the graded mesh through [`SPACING_RATIOS`] until
/// the force changes by less than `tolerance`; `progress(spacing)` is called before each spacing,
/// metres. Fails when the finest spacing has not converged.
pub fn press_force(
    material: &Material,
    press: &Press,
    tolerance: f64,
    progress: &mut dyn FnMut(f64),
) -> anyhow::Result<ContinuumForce> {
    press.check().map_err(anyhow::Error::msg)?;
    let hertz_radius = (press.radius * press.depth).sqrt();
    let mut out =
        ContinuumForce { force: [0.0; 3], force_n: 0.0, levels: Vec::new(), change: f64::INFINITY, contacts: 0 };
    if press.depth == 0.0 {
        out.change = 0.0;
        return Ok(out);
    }
    for ratio in SPACING_RATIOS {
        let fine = ratio * hertz_radius;
        progress(fine);
        let mut solve = PointSolve::new(material, press, fine)?;
        let (force, contacts) = solve.press(press)?;
        let force_n = press.force_along(force);
        if let Some(&(_, last)) = out.levels.last() {
            out.change = (force_n - last).abs() / force_n.abs().max(last.abs()).max(f64::MIN_POSITIVE);
        }
        out.levels.push((fine, force_n));
        (out.force, out.force_n, out.contacts) = (force, force_n, contacts);
        if out.change < tolerance {
            return Ok(out);
        }
    }
    anyhow::bail!(
        "the continuum probe reference did not converge at {:?}, radius {} m, depth {} m: the force still changed \
         by {:.2} % at {:.2} mm spacing (tolerance {:.2} %)",
        press.at,
        press.radius,
        press.depth,
        100.0 * out.change,
        1e3 * out.levels.last().map_or(0.0, |l| l.0),
        100.0 * tolerance
    )
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_press_off_the_free_faces_is_refused() {
        assert!(free_face_normal([0.05, 0.05, 0.1]).is_ok());
        assert!(free_face_normal([0.05, 0.05, 0.0]).is_err(), "face z = 0 is clamped");
        assert!(free_face_normal([0.05, 0.05, 0.05]).is_err());
        let p = Press::normal([0.05, 0.05, 0.1], 0.015).depth(0.013);
        assert!(p.check().is_err());
    }

    #[test]
    fn an_isotropic_press_is_hertz_plus_the_finite_clamped_cube() {
        // Hertz: F = 4/3 E/(1 - nu^2) sqrt(R) d^1.5 on a half-space. The clamped 0.1 m cube is a
        // little stiffer (measured: +4.2 % at 15 mm, 2 mm, converged to 0.17 %).
        let (e, nu) = (100e3, 0.3);
        let g = e / (2.0 * (1.0 + nu));
        let constants = crate::mechanics::material::EngineeringConstants {
            e1: e,
            e2: e,
            e3: e,
            nu12: nu,
            nu13: nu,
            nu23: nu,
            g12: g,
            g13: g,
            g23: g,
        };
        let material = Material::orthotropic("isotropic", constants, 1000.0).unwrap();
        let (r, d) = (0.015, 0.002);
        let press = Press::normal([0.05, 0.05, 0.1], r).depth(d);
        let mut spacings = Vec::new();
        let out = press_force(&material, &press, DEFAULT_TOLERANCE, &mut |s| spacings.push(s)).unwrap();
        let hertz = 4.0 / 3.0 * e / (1.0 - nu * nu) * r.sqrt() * d.powf(1.5);
        let ratio = out.force_n / hertz;
        assert!((1.0..1.05).contains(&ratio), "continuum {} N, Hertz {hertz} N", out.force_n);
        assert!(out.change < DEFAULT_TOLERANCE && spacings.len() >= 2);
        // Frictionless and symmetric: no sideways force.
        assert!(out.force[0].abs() + out.force[1].abs() < 1e-9 * out.force_n);
    }
}
