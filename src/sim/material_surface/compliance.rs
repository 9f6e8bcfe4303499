//! The contact compliance of the material's top face: how every node of a fine, uniform grid on
//! the face z = 0.1 m moves under a unit force at any other, from the hex8 FEM of the clamped cube
//! (face z = 0 held) on a mesh uniform in x and y and graded in z. With it, the force of a rigid
//! frictionless sphere pressed into the top face anywhere is a small dense contact problem on the
//! face nodes under the sphere: the material's force at the tool, whatever coarser model shows
//! the tissue (SOFA's precomputed constraint correction, here of a fine mesh of the material).
//!
//! The cube and its (orthotropic, axis-aligned) material are symmetric under `x -> L - x` and
//! `y -> L - y`, so only the columns of one quadrant's nodes are computed and kept. The contact
//! solve ([`SurfaceCompliance::press`]) allocates nothing: it works in a [`ContactScratch`].

use glam::DVec3;

use crate::response::contact;

use crate::mechanics::fem::graded::{GradedFem, GradedMesh, graded_axis};
use crate::mechanics::grid::CUBE_SIDE_M;
use crate::mechanics::material::Material;
use crate::mechanics::sparse::SparseError;

pub mod file;
pub use file::{FILE_FORMAT, FILE_MAGIC, FileError, METHOD_VERSION};

/// Divisions of the face per axis: 2 mm spacing.
pub const DEFAULT_DIVISIONS: usize = 50;
/// Depth of the fine layer under the face, metres; the mesh grows by [`GROWTH`] below it.
const FINE_DEPTH_M: f64 = 0.01;
/// Growth of the element height below the fine layer.
const GROWTH: f64 = 1.45;
/// Quadrant nodes whose columns are solved in one batch.
const BATCH_NODES: usize = 16;
/// Most face nodes one contact may involve (the window under the sphere).
pub const MAX_CONTACT_NODES: usize = 600;

/// The top face's compliance at the nodes of a uniform face grid.
#[derive(Debug, Clone, PartialEq)]
pub struct SurfaceCompliance {
    divisions: usize,
    /// Per quadrant node `k = i + half j` (`i, j < half`), per force component `b`, per face node
    /// `q`, per displacement component `a`: metres per newton.
    columns: Vec<f32>,
}

/// Errors of the surface compliance.
#[derive(Debug, thiserror::Error)]
pub enum ComplianceError {
    /// The FEM solve failed.
    #[error(transparent)]
    Sparse(#[from] SparseError),
    /// The material couples normal and shear strains: the cube is not mirror-symmetric.
    #[error("the surface compliance needs an orthotropic material aligned with the cube's axes")]
    NotOrthotropic,
    /// More face nodes under the sphere than [`MAX_CONTACT_NODES`].
    #[error("the sphere covers {0} nodes of the face, above the bound of {MAX_CONTACT_NODES}")]
    TooLarge(usize),
    /// The contact solve failed (not settled, not positive definite).
    #[error(transparent)]
    Contact(#[from] contact::ContactError),
    /// A kept file does not match.
    #[error("surface compliance file: {0}")]
    File(String),
    /// The computation was stopped by its caller.
    #[error("the surface compliance was cancelled")]
    Cancelled,
}

impl SurfaceCompliance {
    /// Quadrant nodes per axis.
    fn half(&self) -> usize {
        self.divisions / 2 + 1
    }

    /// A compliance of `divisions` divisions per axis with every entry `value`, metres per newton
    /// (for tests of what uses one).
    #[cfg(test)]
    pub(crate) fn uniform(divisions: usize, value: f32) -> Self {
        let (side, half) = (divisions + 1, divisions / 2 + 1);
        Self { divisions, columns: vec![value; half * half * 3 * side * side * 3] }
    }

    /// Face nodes per axis.
    pub fn side(&self) -> usize {
        self.divisions + 1
    }

    /// Face node spacing, metres.
    pub fn spacing(&self) -> f64 {
        CUBE_SIDE_M / self.divisions as f64
    }

    /// Bytes held.
    pub fn memory_bytes(&self) -> usize {
        self.columns.len() * 4
    }

    /// Computes the compliance of `material` with `divisions` face divisions per axis (even);
    /// `progress(fraction)` is called between batches (about a second apart) and stops the work
    /// when it returns `false`.
    pub fn compute(
        material: &Material,
        divisions: usize,
        progress: &mut dyn FnMut(f64) -> bool,
    ) -> Result<Self, ComplianceError> {
        let c = &material.stiffness;
        let coupled = (0..3).any(|i| (3..6).any(|j| c[(i, j)] != 0.0))
            || c[(3, 4)] != 0.0
            || c[(3, 5)] != 0.0
            || c[(4, 5)] != 0.0;
        if coupled || !divisions.is_multiple_of(2) || divisions < 2 {
            return Err(ComplianceError::NotOrthotropic);
        }
        let l = CUBE_SIDE_M;
        let s = l / divisions as f64;
        let xy: Vec<f64> = (0..=divisions).map(|i| if i == divisions { l } else { i as f64 * s }).collect();
        let z = graded_axis(l, l, s, FINE_DEPTH_M, GROWTH);
        let mesh = GradedMesh { axes: [xy.clone(), xy, z] };
        let top = mesh.dims()[2] - 1;
        if !progress(0.0) {
            return Err(ComplianceError::Cancelled);
        }
        let mut fem = GradedFem::clamped_bottom(mesh, material)?;
        if !progress(0.0) {
            return Err(ComplianceError::Cancelled);
        }
        let side = divisions + 1;
        let half = divisions / 2 + 1;
        let n = fem.fixed.len();
        let face = side * side;
        let mut columns = vec![0.0f32; half * half * 3 * face * 3];
        let quadrant: Vec<[usize; 2]> = (0..half).flat_map(|j| (0..half).map(move |i| [i, j])).collect();
        let mut done = 0;
        for batch in quadrant.chunks(BATCH_NODES) {
            let cols = 3 * batch.len();
            let mut rhs = vec![0.0; n * cols];
            for (b, &[i, j]) in batch.iter().enumerate() {
                let p = fem.mesh.node([i, j, top]);
                for c in 0..3 {
                    rhs[(3 * b + c) * n + 3 * p + c] = 1.0;
                }
            }
            fem.solve_columns(&mut rhs, cols)?;
            for (b, &[i, j]) in batch.iter().enumerate() {
                let k = i + half * j;
                for c in 0..3 {
                    let col = &rhs[(3 * b + c) * n..(3 * b + c + 1) * n];
                    let out = &mut columns[(3 * k + c) * face * 3..(3 * k + c + 1) * face * 3];
                    for q in 0..face {
                        let node = fem.mesh.node([q % side, q / side, top]);
                        for a in 0..3 {
                            out[3 * q + a] = col[3 * node + a] as f32;
                        }
                    }
                }
            }
            done += batch.len();
            if !progress(done as f64 / quadrant.len() as f64) {
                return Err(ComplianceError::Cancelled);
            }
        }
        Ok(Self { divisions, columns })
    }

    /// Rest position of face node `q`, metres.
    pub fn position(&self, q: usize) -> [f64; 3] {
        let s = self.spacing();
        [(q % self.side()) as f64 * s, (q / self.side()) as f64 * s, CUBE_SIDE_M]
    }

    /// The 3 x 3 block `W[a][b]`: displacement `a` of face node `q` under a unit force `b` at
    /// face node `p`, metres per newton.
    #[inline]
    pub fn block(&self, p: usize, q: usize) -> [[f64; 3]; 3] {
        let (side, half) = (self.side(), self.half());
        let (pi, pj) = (p % side, p / side);
        let (qi, qj) = (q % side, q / side);
        // Mirror p into the quadrant; q goes with it.
        let (mi, sx) = if pi < half { (pi, 1.0) } else { (side - 1 - pi, -1.0) };
        let (mj, sy) = if pj < half { (pj, 1.0) } else { (side - 1 - pj, -1.0) };
        let qi = if sx < 0.0 { side - 1 - qi } else { qi };
        let qj = if sy < 0.0 { side - 1 - qj } else { qj };
        let sign = [sx, sy, 1.0];
        let k = mi + half * mj;
        let face = side * side;
        let at = 3 * (qi + side * qj);
        let mut w = [[0.0; 3]; 3];
        for (b, &sb) in sign.iter().enumerate() {
            let col = &self.columns[(3 * k + b) * face * 3 + at..][..3];
            for (a, &sa) in sign.iter().enumerate() {
                w[a][b] = sa * sb * f64::from(col[a]);
            }
        }
        w
    }

    /// The force of the face on a rigid frictionless sphere (`centre`, `radius`, metres) held
    /// against it at rest, newtons: every face node the sphere covers is put on it along the
    /// sphere's normal ([`contact::solve`], warm-started from the last solve's contact where it
    /// is still near the sphere). The contact nodes and their normal forces stay in `scratch`.
    pub fn press(
        &self,
        centre: [f64; 3],
        radius: f64,
        scratch: &mut ContactScratch,
    ) -> Result<[f64; 3], ComplianceError> {
        let ContactScratch { contact: c, nodes, previous } = scratch;
        c.candidates.clear();
        c.active.clear();
        c.lambda.clear();
        nodes.clear();
        if centre[2] - radius >= CUBE_SIDE_M {
            previous.clear();
            return Ok([0.0; 3]);
        }
        let mut too_large = false;
        for_window(self.divisions, centre, radius, |q, d| {
            if nodes.len() == MAX_CONTACT_NODES {
                too_large = true;
                return false;
            }
            nodes.push(q);
            let x = (DVec3::from(centre) + d).to_array();
            c.candidates.push(contact::sphere_gap(centre, radius, x, [0.0, 0.0, -1.0]));
            true
        });
        if too_large {
            return Err(ComplianceError::TooLarge(window_count(self.divisions, centre, radius)));
        }
        for (w, &q) in nodes.iter().enumerate() {
            if previous.binary_search(&q).is_ok() && c.candidates[w].1 > -self.spacing() {
                c.active.push(w);
            }
        }
        let solved = contact::solve(&mut FaceNodes { compliance: self, nodes }, c, 1e-9 * radius);
        previous.clear();
        solved?;
        previous.extend(c.active.iter().map(|&w| nodes[w]));
        previous.sort_unstable();
        Ok(c.force())
    }

    /// `nq . W(q <- p) np`.
    #[inline(always)]
    fn normal_normal(&self, p: usize, np: [f64; 3], q: usize, nq: [f64; 3]) -> f64 {
        let w = self.block(p, q);
        let mut v = 0.0;
        for a in 0..3 {
            v += nq[a] * (w[a][0] * np[0] + w[a][1] * np[1] + w[a][2] * np[2]);
        }
        v
    }
}

/// The face nodes under the sphere as the contact sees them.
struct FaceNodes<'a> {
    compliance: &'a SurfaceCompliance,
    /// Face node of each candidate.
    nodes: &'a [usize],
}

impl contact::Compliance for FaceNodes<'_> {
    #[inline(always)]
    fn normal(&self, i: usize, n_i: [f64; 3], j: usize, n_j: [f64; 3]) -> f64 {
        self.compliance.normal_normal(self.nodes[j], n_j, self.nodes[i], n_i)
    }
}

/// Calls `f(node, node - centre)` for every face node (of a face with `divisions` divisions per
/// axis) that a sphere's contact considers: within a face spacing of the sphere's surface; `f`
/// returns `false` to stop. The one rule of the contact's window.
fn for_window(divisions: usize, centre: [f64; 3], radius: f64, mut f: impl FnMut(usize, DVec3) -> bool) {
    let side = divisions + 1;
    let s = CUBE_SIDE_M / divisions as f64;
    let reach = radius + s;
    let lo = |x: f64| (((x - reach) / s).floor().max(0.0)) as usize;
    let hi = |x: f64| (((x + reach) / s).ceil().max(0.0) as usize).min(side - 1);
    let c = DVec3::from(centre);
    for j in lo(centre[1])..=hi(centre[1]) {
        for i in lo(centre[0])..=hi(centre[0]) {
            let d = DVec3::new(i as f64 * s, j as f64 * s, CUBE_SIDE_M) - c;
            if d.length() < radius + s && !f(i + side * j, d) {
                return;
            }
        }
    }
}

/// How many face nodes a sphere's contact considers ([`SurfaceCompliance::press`]'s window).
pub fn window_count(divisions: usize, centre: [f64; 3], radius: f64) -> usize {
    let mut count = 0;
    for_window(divisions, centre, radius, |_, _| {
        count += 1;
        true
    });
    count
}

/// Preallocated memory of [`SurfaceCompliance::press`].
pub struct ContactScratch {
    /// The contact's memory: the face nodes near the sphere as candidates (outward normal from
    /// the centre, depth inside the sphere), those in contact and their normal forces.
    pub contact: contact::ContactScratch,
    /// The face node of each candidate.
    pub nodes: Vec<usize>,
    /// The face nodes in contact at the last solve, increasing (the next solve's warm start).
    previous: Vec<usize>,
}

impl ContactScratch {
    /// The contact of the last press: face node, outward normal, normal force (newtons).
    pub fn contacts(&self) -> impl Iterator<Item = (usize, [f64; 3], f64)> + '_ {
        let c = &self.contact;
        c.active.iter().zip(&c.lambda).map(|(&w, &l)| (self.nodes[w], c.candidates[w].0, l))
    }
}

impl std::fmt::Debug for ContactScratch {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.debug_struct("ContactScratch").field("active", &self.contact.active.len()).finish()
    }
}

impl Default for ContactScratch {
    fn default() -> Self {
        let m = MAX_CONTACT_NODES;
        Self {
            contact: contact::ContactScratch::with_room(m),
            nodes: Vec::with_capacity(m),
            previous: Vec::with_capacity(m),
        }
    }
}
