//! The contact compliance of the material's free surface: how every node of a lattice on the top
//! face and the four side faces (2 mm, 1 mm across the edges) moves under a unit force at another, from the
//! hex8 FEM of the clamped cube (face z = 0 held) on meshes uniform along a face and graded away
//! from it ([`lattice`]: the top face's mesh, the x faces', the y faces'). With it, the force of a
//! rigid frictionless sphere pressed anywhere into the free surface, across an edge or into a
//! corner, is a small dense contact problem on the surface nodes under the sphere: the material's
//! force at the tool, whatever coarser model shows the tissue (SOFA's precomputed constraint
//! correction, here of a fine mesh of the material).
//!
//! The cube and its (orthotropic, axis-aligned) material are mirror-symmetric in x and y, and
//! away from the edges the compliance barely changes along a face, so only about a twentieth of
//! the nodes' columns are solved and kept ([`lattice`]). The contact's normal compliance of two
//! nodes is the mean of what either's column says (the two differ where a column is shifted or
//! another face's mesh holds it), so that it is symmetric. The contact solve
//! ([`SurfaceCompliance::press`]) allocates nothing: it works in a [`SurfaceContactScratch`].

use glam::DVec3;

use crate::response::contact;

use crate::mechanics::fem::graded::{GradedMesh, graded_axis};
use crate::mechanics::grid::CUBE_SIDE_M;
use crate::mechanics::material::Material;
use crate::mechanics::sparse::SparseError;

pub mod compact;
pub mod compute;
pub mod file;
pub mod lattice;
pub mod inclusion;
pub use file::{FILE_FORMAT, FILE_MAGIC, FileError, METHOD_VERSION};
use lattice::{Lattice, Source};
use inclusion::InclusionCorrection;

/// Divisions of a face per axis: 2 mm spacing.
pub const DEFAULT_DIVISIONS: usize = 50;
/// Depth of the fine layer under a face (the lattice's rows), metres; the mesh grows by
/// [`GROWTH`] below it.
const FINE_DEPTH_M: f64 = 0.01;
/// Growth of the element size away from the fine layer.
const GROWTH: f64 = 1.45;
/// Column nodes solved in one batch (three right-hand sides each: about 200 MB of them at 2 mm,
/// and 15 % fewer seconds than batches of 16).
const BATCH_NODES: usize = 64;
/// Most surface nodes one contact may involve (the window under the sphere).
pub const MAX_CONTACT_NODES: usize = 600;

/// The free surface's compliance at the nodes of a surface lattice.
#[derive(Debug, Clone, PartialEq)]
pub struct SurfaceCompliance {
    lattice: Lattice,
    /// Per family, per solved column node, per target, per force component `b`, per displacement
    /// component `a`: metres per newton (a target's 3 x 3 block in one place: a contact reads
    /// blocks of many columns at a few targets); shared by a material's compliance with its
    /// background's.
    columns: std::sync::Arc<[f32]>,
    /// What the material's inclusions change, near them (none for a homogeneous material).
    correction: Option<InclusionCorrection>,
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
    /// The material has inclusions, which the surface compliance does not model yet.
    #[error(transparent)]
    Material(#[from] crate::mechanics::material::MaterialError),
    /// The inclusions reach more surface nodes than their correction may hold.
    #[error(
        "the inclusions reach {0} nodes of the surface (within 20 mm of them), above the bound of {max}: keep them \
         closer together",
        max = inclusion::MAX_NODES
    )]
    TooSpread(usize),
    /// The computation was stopped by its caller.
    #[error("the surface compliance was cancelled")]
    Cancelled,
}

impl SurfaceCompliance {
    /// A compliance of `divisions` divisions per axis with every entry `value`, metres per newton
    /// (for tests of what uses one).
    #[cfg(test)]
    pub(crate) fn uniform(divisions: usize, value: f32) -> Self {
        let lattice = Lattice::new(divisions);
        Self { columns: vec![value; lattice.values].into(), lattice, correction: None }
    }

    /// Which compliance this is while it lives where it is: its columns' and its inclusions'
    /// correction's addresses (a material with inclusions shares its background's columns).
    fn identity(&self) -> (usize, usize) {
        (self.columns.as_ptr() as usize, self.correction.as_ref().map_or(0, |c| std::ptr::from_ref(c) as usize))
    }

    /// Lattice spacing (away from the edges), metres.
    pub fn spacing(&self) -> f64 {
        CUBE_SIDE_M / self.lattice.divisions as f64
    }

    /// Bytes held.
    pub fn memory_bytes(&self) -> usize {
        self.columns.len() * 4 + self.correction.as_ref().map_or(0, InclusionCorrection::memory_bytes)
    }

    /// The compliance of `material`, whose background's this is: with the change its inclusions
    /// make ([`inclusion`]; none where it has none); `progress` as [`SurfaceCompliance::compute`]'s.
    pub fn with_inclusions(
        mut self,
        material: &Material,
        progress: &mut dyn FnMut(f64) -> bool,
    ) -> Result<Self, ComplianceError> {
        self.correction = if material.inclusions.is_empty() {
            None
        } else {
            Some(InclusionCorrection::compute(&self.lattice, material, progress)?)
        };
        Ok(self)
    }

    /// The compliance with `lump` as its inclusions' correction (one computed for this lattice,
    /// [`InclusionCorrection::compute`], or read from its file).
    pub fn with_correction(mut self, lump: InclusionCorrection) -> Self {
        self.correction = Some(lump);
        self
    }

    /// Its lattice's face divisions per axis and surface nodes.
    pub fn lattice_size(&self) -> (usize, usize) {
        (self.lattice.divisions, self.lattice.len())
    }

    /// The inclusions' correction of `material` on this compliance's lattice.
    pub fn inclusion_of(
        &self,
        material: &Material,
        progress: &mut dyn FnMut(f64) -> bool,
    ) -> Result<InclusionCorrection, ComplianceError> {
        InclusionCorrection::compute(&self.lattice, material, progress)
    }

    /// The inclusions' correction, where the material has inclusions.
    pub fn correction(&self) -> Option<&InclusionCorrection> {
        self.correction.as_ref()
    }

    /// Rest position of surface node `q`, metres.
    pub fn position(&self, q: usize) -> [f64; 3] {
        self.lattice.point(q).map(|c| self.lattice.coords[c])
    }

    /// `n_q . W(q <- p) n_p` from the column `p`'s `source` finds, or `None` where it does not
    /// hold `q`.
    #[inline(always)]
    fn along(&self, source: &Source, n_p: [f64; 3], q: [usize; 3], n_q: [f64; 3]) -> Option<f64> {
        let t = self.lattice.target(source, q)?;
        let f = &self.lattice.families[source.family as usize];
        let sign =
            [f64::from(u8::from(!source.flip[0])) * 2.0 - 1.0, f64::from(u8::from(!source.flip[1])) * 2.0 - 1.0, 1.0];
        let base = f.offset + 9 * (source.column as usize * f.targets.len() + t);
        let block = &self.columns[base..base + 9];
        let mut v = 0.0;
        for b in 0..3 {
            let col = &block[3 * b..3 * b + 3];
            let w = col[0] as f64 * n_q[0] * sign[0] + col[1] as f64 * n_q[1] * sign[1] + col[2] as f64 * n_q[2];
            v += w * n_p[b] * sign[b];
        }
        Some(v)
    }

    /// The 3 x 3 block `W(q <- p)` (metres per newton: the displacement of surface node `q`, row,
    /// under a unit force at `p`, column) from `p`'s column (`source`), or from `q`'s transposed
    /// (the compliance is symmetric) where `p`'s does not hold `q`; `None` where neither does.
    fn block(&self, (p, source): ([usize; 3], &Source), q: [usize; 3]) -> Option<[[f64; 3]; 3]> {
        let read = |source: &Source, at: [usize; 3]| -> Option<[[f64; 3]; 3]> {
            let t = self.lattice.target(source, at)?;
            let f = &self.lattice.families[source.family as usize];
            let sign = [f64::from(u8::from(!source.flip[0])) * 2.0 - 1.0, f64::from(u8::from(!source.flip[1])) * 2.0 - 1.0, 1.0];
            let base = f.offset + 9 * (source.column as usize * f.targets.len() + t);
            let block = &self.columns[base..base + 9];
            // block[3 b + a]: displacement component a under force component b, mirrored.
            Some(std::array::from_fn(|a| std::array::from_fn(|b| f64::from(block[3 * b + a]) * sign[a] * sign[b])))
        };
        read(source, q).or_else(|| {
            let w = read(&self.lattice.source(q), p)?;
            Some(std::array::from_fn(|a| std::array::from_fn(|b| w[b][a])))
        })
    }

    /// Every surface node within `reach` of `contact`'s nodes (a press's contact:
    /// [`SurfaceContactScratch::contacts`], each node pushed along the sphere's normal there, away
    /// from its centre, by its force) with `f(node, rest position, distance to the nearest contact
    /// node, the material's static displacement there)`, metres: what the surface does under the
    /// sphere at the compliance's resolution (the inclusions' correction left out; zero where no
    /// column holds the node, far from the contact on another face). At most
    /// [`MAX_CONTACT_NODES`] contact nodes are read; allocates nothing.
    pub fn near_contact(
        &self,
        contact: &[(usize, [f64; 3], f64)],
        reach: f64,
        mut f: impl FnMut(usize, [f64; 3], f64, [f64; 3]),
    ) {
        let contact = &contact[..contact.len().min(MAX_CONTACT_NODES)];
        let mut points = [[0usize; 3]; MAX_CONTACT_NODES];
        let mut sources = [Source::default(); MAX_CONTACT_NODES];
        let mut at = [[0.0f64; 3]; MAX_CONTACT_NODES];
        let mut lo = [f64::INFINITY; 3];
        let mut hi = [f64::NEG_INFINITY; 3];
        for (i, &(p, _, _)) in contact.iter().enumerate() {
            points[i] = self.lattice.point(p);
            sources[i] = self.lattice.source(points[i]);
            at[i] = self.position(p);
            for a in 0..3 {
                lo[a] = lo[a].min(at[i][a] - reach);
                hi[a] = hi[a].max(at[i][a] + reach);
            }
        }
        if contact.is_empty() {
            return;
        }
        let coords = &self.lattice.coords;
        let range = |a: usize| coords.partition_point(|&c| c < lo[a])..coords.partition_point(|&c| c <= hi[a]);
        for k in range(2) {
            for j in range(1) {
                for i in range(0) {
                    let q = [i, j, k];
                    let Some(node) = self.lattice.index(q) else { continue };
                    let x = self.position(node);
                    let d2 = at[..contact.len()]
                        .iter()
                        .map(|y| (0..3).map(|a| (x[a] - y[a]).powi(2)).sum::<f64>())
                        .fold(f64::INFINITY, f64::min);
                    if d2 > reach * reach {
                        continue;
                    }
                    let mut u = [0.0; 3];
                    for (c, &(_, n, force)) in contact.iter().enumerate() {
                        let Some(w) = self.block((points[c], &sources[c]), q) else { continue };
                        for (a, row) in w.iter().enumerate() {
                            u[a] += force * (row[0] * n[0] + row[1] * n[1] + row[2] * n[2]);
                        }
                    }
                    f(node, x, d2.sqrt(), u);
                }
            }
        }
    }

    /// The force of the surface on a rigid frictionless sphere (`centre`, `radius`, metres) held
    /// against it at rest, newtons: every surface node the sphere covers is put on it along the
    /// sphere's normal ([`contact::solve`], warm-started from the last solve's contact where it
    /// is still near the sphere). The contact nodes and their normal forces stay in `scratch`.
    pub fn press(
        &self,
        centre: [f64; 3],
        radius: f64,
        scratch: &mut SurfaceContactScratch,
    ) -> Result<[f64; 3], ComplianceError> {
        self.press_coupled(centre, radius, [0.0; 3], &[[0.0; 3]; 3], scratch)
    }

    /// [`SurfaceCompliance::press`] with every contact node also moving by `shift - G F` under
    /// the net force `F` of the contact on the tissue (`coupling` is `G`, metres per newton: the
    /// response of the material's slow modes folded into the contact,
    /// [`super::modal_lag::ModalLag::response_after`]), so that one solve is exact for the
    /// contact and the modes together. Like the contact, the shift is linear: it moves each node
    /// along its normal.
    pub fn press_coupled(
        &self,
        centre: [f64; 3],
        radius: f64,
        shift: [f64; 3],
        coupling: &[[f64; 3]; 3],
        scratch: &mut SurfaceContactScratch,
    ) -> Result<[f64; 3], ComplianceError> {
        if scratch.follows(centre, radius, self.identity()) && self.follow(centre, radius, shift, coupling, scratch) {
            return Ok(scratch.contact.force());
        }
        scratch.factored = None;
        let SurfaceContactScratch { contact: c, nodes, points, sources, previous, .. } = scratch;
        c.clear();
        nodes.clear();
        points.clear();
        sources.clear();
        let outside = (0..3).map(|a| (-centre[a]).max(centre[a] - CUBE_SIDE_M).max(0.0).powi(2)).sum::<f64>().sqrt();
        if outside >= radius {
            previous.clear();
            return Ok([0.0; 3]);
        }
        let d = self.lattice.last();
        let mut too_large = false;
        for_window(&self.lattice.coords, centre, radius, |q, x| {
            let Some(index) = self.lattice.index(q) else { return true };
            if nodes.len() == MAX_CONTACT_NODES {
                too_large = true;
                return false;
            }
            nodes.push(index);
            points.push(q);
            sources.push(self.lattice.source(q));
            let (n, depth) = contact::sphere_gap(centre, radius, x, outward(q, d));
            c.candidates.push((n, depth - (n[0] * shift[0] + n[1] * shift[1] + n[2] * shift[2])));
            true
        });
        if too_large {
            return Err(ComplianceError::TooLarge(window_count(self.lattice.divisions, centre, radius)));
        }
        for (w, &q) in nodes.iter().enumerate() {
            if previous.binary_search(&q).is_ok() && c.candidates[w].1 > -self.spacing() {
                c.active.push(w);
            }
        }
        let mut body = SurfaceNodes { compliance: self, nodes, points, sources, coupling };
        let solved = contact::solve(&mut body, c, 1e-9 * radius);
        previous.clear();
        solved?;
        previous.extend(c.active.iter().map(|&w| nodes[w]));
        previous.sort_unstable();
        scratch.factored = Some(Factored { centre, radius, coupling: *coupling, compliance: self.identity() });
        Ok(scratch.contact.force())
    }

    /// The last solve's contact followed to the sphere at `centre` (the same radius, the
    /// candidates' window the same nodes): the gaps there with the surface's `shift`, solved on
    /// the last solve's active set and compliance with the modes' `coupling` now in place of the
    /// one it was factorised with ([`contact::resolve`]). `false` where the window or the contact
    /// changed: a solve is owed.
    fn follow(
        &self,
        centre: [f64; 3],
        radius: f64,
        shift: [f64; 3],
        coupling: &[[f64; 3]; 3],
        scratch: &mut SurfaceContactScratch,
    ) -> bool {
        let SurfaceContactScratch { contact: c, nodes, window, previous, factored, .. } = scratch;
        let Some(factored) = factored else { return false };
        let change: [[f64; 3]; 3] = std::array::from_fn(|i| std::array::from_fn(|j| coupling[i][j] - factored.coupling[i][j]));
        window.clear();
        let d = self.lattice.last();
        let mut same = true;
        for_window(&self.lattice.coords, centre, radius, |q, x| {
            let Some(index) = self.lattice.index(q) else { return true };
            if nodes.get(window.len()) != Some(&index) {
                same = false;
                return false;
            }
            let (n, depth) = contact::sphere_gap(centre, radius, x, outward(q, d));
            window.push((n, depth - (n[0] * shift[0] + n[1] * shift[1] + n[2] * shift[2])));
            true
        });
        if !same || window.len() != nodes.len() {
            return false;
        }
        c.candidates.clear();
        c.candidates.extend_from_slice(window);
        if contact::resolve(c, 1e-9 * radius, &change) {
            return true;
        }
        // The solve owed starts from the contact the followed one points to.
        previous.clear();
        previous.extend(c.active.iter().map(|&w| nodes[w]));
        previous.sort_unstable();
        false
    }
}

/// Where the compliance of the last solve's active set was factorised: the sphere, the modes'
/// coupling folded in, and which compliance ([`SurfaceCompliance::identity`]: a scratch pressed
/// on another, a material's and its background's say, is solved afresh).
#[derive(Debug, Clone, Copy)]
struct Factored {
    centre: [f64; 3],
    radius: f64,
    coupling: [[f64; 3]; 3],
    compliance: (usize, usize),
}

/// How far the sphere may move from where its contact's compliance was factorised before the
/// contact is solved afresh, metres (the sphere's normals at the contact nodes, and so the
/// contact's compliance, turn by about this over the radius).
pub const FOLLOW_M: f64 = 2e-4;



/// The outward normal of the surface at lattice point `q` (the sum of its faces' on an edge).
fn outward(q: [usize; 3], d: usize) -> [f64; 3] {
    let n = DVec3::from_array(q.map(|c| {
        if c == d {
            1.0
        } else if c == 0 {
            -1.0
        } else {
            0.0
        }
    }));
    n.try_normalize().unwrap_or(DVec3::Z).to_array()
}

/// The mesh of a family's faces: the lattice's rows along them (`coords`, of `divisions`
/// intervals before halving), graded across (the lattice's rows within [`FINE_DEPTH_M`] of the
/// face at `axis = L`, growing below).
fn family_mesh(axis: usize, coords: &[f64], divisions: usize) -> GradedMesh {
    let l = CUBE_SIDE_M;
    let s = l / divisions as f64;
    // Fine under the kept face (at `axis = L`; its mirror image's columns are its own mirrored).
    let fine_from = l - FINE_DEPTH_M - 1e-9;
    let mut graded: Vec<f64> =
        graded_axis(l, l, s, FINE_DEPTH_M, GROWTH).into_iter().filter(|&x| x < fine_from).collect();
    graded.extend(coords.iter().filter(|&&x| x >= fine_from));
    let mut axes = [coords.to_vec(), coords.to_vec(), coords.to_vec()];
    axes[axis] = graded;
    GradedMesh { axes }
}

/// Lattice point `q` on a family's mesh: the nodes on either side of it across the graded `axis`
/// and the second's weight (0 where `q` is a node).
fn mesh_point(mesh: &GradedMesh, axis: usize, q: [usize; 3], coords: &[f64]) -> (usize, usize, f64) {
    let x = coords[q[axis]];
    let line = &mesh.axes[axis];
    let hi = line.partition_point(|&y| y < x - 1e-12).clamp(1, line.len() - 1);
    let (a, b) = (line[hi - 1], line[hi]);
    let (lo, w) = if (x - b).abs() <= 1e-12 { (hi, 0.0) } else { (hi - 1, (x - a) / (b - a)) };
    let node = |i: usize| {
        let mut ijk = q;
        ijk[axis] = i;
        mesh.node(ijk)
    };
    (node(lo), node((lo + 1).min(line.len() - 1)), w)
}

/// The surface nodes under the sphere as the contact sees them.
struct SurfaceNodes<'a> {
    compliance: &'a SurfaceCompliance,
    /// Surface node of each candidate.
    nodes: &'a [usize],
    /// Lattice point of each candidate.
    points: &'a [[usize; 3]],
    /// How each candidate's column is found.
    sources: &'a [Source],
    /// The slow modes' response to the contact's net force, subtracted (metres per newton).
    coupling: &'a [[f64; 3]; 3],
}

impl contact::Compliance for SurfaceNodes<'_> {
    #[inline(always)]
    fn normal(&self, i: usize, n_i: [f64; 3], j: usize, n_j: [f64; 3]) -> f64 {
        let c = self.compliance;
        let g = self.coupling;
        let modes: f64 = (0..3).map(|a| n_i[a] * (g[a][0] * n_j[0] + g[a][1] * n_j[1] + g[a][2] * n_j[2])).sum();
        let by_j = c.along(&self.sources[j], n_j, self.points[i], n_i);
        let w = if i == j {
            by_j.unwrap_or(0.0)
        } else {
            match (by_j, c.along(&self.sources[i], n_i, self.points[j], n_j)) {
                (Some(a), Some(b)) => 0.5 * (a + b),
                (Some(a), None) | (None, Some(a)) => a,
                (None, None) => 0.0,
            }
        };
        let lump = c.correction.as_ref().map_or(0.0, |l| l.normal(self.nodes[j], n_j, self.nodes[i], n_i));
        w - lump - modes
    }
}

/// Calls `f(point, position)` for every lattice point of the free surface (node coordinates
/// `coords` along every axis; and of the clamped bottom, which the caller leaves out) within the
/// lattice's widest spacing of the sphere's surface, or inside it; `f` returns `false` to stop.
/// The one rule of the contact's window.
fn for_window(coords: &[f64], centre: [f64; 3], radius: f64, mut f: impl FnMut([usize; 3], [f64; 3]) -> bool) {
    let d = coords.len() - 1;
    let s = coords.windows(2).map(|w| w[1] - w[0]).fold(0.0, f64::max);
    let reach = radius + s;
    let lo = |x: f64| coords.partition_point(|&c| c < x - reach).min(d);
    let hi = |x: f64| coords.partition_point(|&c| c <= x + reach).clamp(1, d + 1) - 1;
    let c = DVec3::from(centre);
    let at = |i: usize| coords[i];
    let (ilo, ihi) = (lo(centre[0]), hi(centre[0]));
    for k in lo(centre[2])..=hi(centre[2]) {
        for j in lo(centre[1])..=hi(centre[1]) {
            // A row on a face of the cube is surface throughout; any other only at its two ends.
            let whole = k == d || j == 0 || j == d;
            let ends = [0, d].into_iter().filter(|&i| (ilo..=ihi).contains(&i));
            let mut row = (ilo..=ihi).filter(|_| whole).chain(ends.filter(|_| !whole));
            if !row.all(|i| {
                let x = [at(i), at(j), at(k)];
                (DVec3::from(x) - c).length() >= reach || f([i, j, k], x)
            }) {
                return;
            }
        }
    }
}

/// How many surface nodes a sphere's contact considers ([`SurfaceCompliance::press`]'s window).
pub fn window_count(divisions: usize, centre: [f64; 3], radius: f64) -> usize {
    let mut count = 0;
    for_window(&lattice::coordinates(divisions), centre, radius, |q, _| {
        count += usize::from(q[2] > 0);
        true
    });
    count
}

/// Preallocated memory of [`SurfaceCompliance::press`].
pub struct SurfaceContactScratch {
    /// The contact's memory: the surface nodes near the sphere as candidates (outward normal from
    /// the centre, depth inside the sphere), those in contact and their normal forces.
    pub contact: contact::ContactScratch,
    /// The surface node of each candidate.
    pub nodes: Vec<usize>,
    /// Its lattice point.
    points: Vec<[usize; 3]>,
    /// How its column is found.
    sources: Vec<Source>,
    /// The surface nodes in contact at the last solve, increasing (the next solve's warm start).
    previous: Vec<usize>,
    /// The candidates' normals and gaps where the sphere is now (a followed contact's).
    window: Vec<([f64; 3], f64)>,
    /// Where the last solve factorised its compliance, while it can be followed.
    factored: Option<Factored>,
}

impl SurfaceContactScratch {
    /// Whether the sphere (`centre`, `radius`) is near enough to the last solve's, on the same
    /// compliance, for its contact to be followed ([`FOLLOW_M`]).
    fn follows(&self, centre: [f64; 3], radius: f64, compliance: (usize, usize)) -> bool {
        let Some(f) = &self.factored else { return false };
        f.compliance == compliance
            && f.radius == radius
            && DVec3::from(centre).distance(DVec3::from(f.centre)) <= FOLLOW_M
    }

    /// No contact, and no warm start for the next press.
    pub fn clear(&mut self) {
        self.contact.clear();
        self.factored = None;
        self.nodes.clear();
        self.points.clear();
        self.sources.clear();
        self.previous.clear();
    }

    /// The contact of the last press: surface node, outward normal, normal force (newtons).
    pub fn contacts(&self) -> impl Iterator<Item = (usize, [f64; 3], f64)> + '_ {
        let c = &self.contact;
        c.active.iter().zip(&c.lambda).map(|(&w, &l)| (self.nodes[w], c.candidates[w].0, l))
    }
}

impl std::fmt::Debug for SurfaceContactScratch {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.debug_struct("SurfaceContactScratch").field("active", &self.contact.active.len()).finish()
    }
}

impl Default for SurfaceContactScratch {
    fn default() -> Self {
        let m = MAX_CONTACT_NODES;
        Self {
            contact: contact::ContactScratch::with_room(m),
            nodes: Vec::with_capacity(m),
            points: Vec::with_capacity(m),
            sources: Vec::with_capacity(m),
            previous: Vec::with_capacity(m),
            window: Vec::with_capacity(m),
            factored: None,
        }
    }
}
