//! The cube's surface as triangles, rebuilt from node positions every frame without allocating.
//!
//! Each of the six faces has its own vertices (so the cube's edges stay sharp) and its normals are
//! recomputed from the deformed positions (area-weighted triangle normals, smooth across a face).
//! The vertices are the model's surface nodes ([`SurfaceMesh::new`]) or a finer lattice's points
//! ([`SurfaceMesh::on_lattice`]: the material's surface compliance's, 2 mm and 1 mm across the
//! edges), placed by the model's nodes (bilinear on the face) and, near the probe's contact, by
//! the material's own displacement there ([`Dent`]).

use crate::mechanics::grid::Grid;
use glam::Vec3;

/// A surface vertex as the GPU reads it.
#[repr(C)]
#[derive(Debug, Clone, Copy, PartialEq, bytemuck::Pod, bytemuck::Zeroable)]
pub struct SurfaceVertex {
    /// Position, metres.
    pub position: [f32; 3],
    /// Unit normal.
    pub normal: [f32; 3],
    /// Colour-map value in [0, 1].
    pub scalar: f32,
}

/// Where a vertex goes near the probe's contact: its position under the material (the surface
/// compliance's displacement, the contact's nodes on the sphere), and how much of it to take
/// (1 at the contact, down to 0 where the model alone shows the tissue).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Dent {
    /// The vertex.
    pub vertex: u32,
    /// Its position under the material, metres.
    pub at: [f32; 3],
    /// The weight of that position against the model's, in [0, 1].
    pub weight: f32,
}

/// The surface of a deforming cube.
#[derive(Debug, Clone)]
pub struct SurfaceMesh {
    /// For each surface vertex, the node of the model nearest it (what a drag picks).
    pub vertex_node: Vec<u32>,
    /// Triangle indices into the vertices (counter-clockwise seen from outside) drawn this frame:
    /// each face's whole lattice where a dent moves its vertices, else every
    /// [`COARSE_STRIDE`]th line of it (what the model's nodes alone place needs no more).
    pub indices: Vec<u32>,
    /// Each face's triangles on its whole lattice and on its coarse one.
    faces: [[Vec<u32>; 2]; 6],
    /// Vertices per face.
    face_vertices: usize,
    /// Current vertices.
    pub vertices: Vec<SurfaceVertex>,
    /// For each vertex, the model's nodes that place it and their weights (bilinear on its face).
    weights: Vec<[(u32, f32); 4]>,
    /// Rest positions of the vertices.
    rest: Vec<[f32; 3]>,
    /// For each surface node of the lattice the mesh was built on, its vertices (one on a face, two
    /// on an edge, three at a corner; `u32::MAX` where fewer).
    lattice_vertices: Vec<[u32; 3]>,
    normals: Vec<[f32; 3]>,
}

/// The model's four nodes around the point at coordinates `(cu, cv)` of the face normal to
/// `axis` (at its high end where `high`), and their bilinear weights.
fn bilinear(grid: &Grid, (axis, high): (usize, bool), [cu, cv]: [f64; 2]) -> [(u32, f32); 4] {
    let (n, h) = (grid.n(), grid.h());
    let (u, v) = ((axis + 1) % 3, (axis + 2) % 3);
    // The model's cell of a coordinate and the weight of its upper node.
    let cell = |c: f64| {
        let t = c / h;
        let i = (t.floor() as usize).min(n - 2);
        (i, ((t - i as f64) as f32).clamp(0.0, 1.0))
    };
    let ((iu, tu), (iv, tv)) = (cell(cu), cell(cv));
    let node = |du: usize, dv: usize| {
        let mut ijk = [0usize; 3];
        ijk[axis] = if high { n - 1 } else { 0 };
        ijk[u] = iu + du;
        ijk[v] = iv + dv;
        grid.node(ijk[0], ijk[1], ijk[2]) as u32
    };
    [
        (node(0, 0), (1.0 - tu) * (1.0 - tv)),
        (node(1, 0), tu * (1.0 - tv)),
        (node(0, 1), (1.0 - tu) * tv),
        (node(1, 1), tu * tv),
    ]
}

/// Lines of a face's lattice kept in its coarse triangles (and the last), where no dent is.
pub const COARSE_STRIDE: usize = 4;

/// The model's node coordinates along an axis, metres: `n` nodes over the cube's side.
fn grid_coordinates(grid: &Grid) -> Vec<f64> {
    (0..grid.n()).map(|i| grid.h() * i as f64).collect()
}

impl SurfaceMesh {
    /// The six faces of `grid`, a vertex at each surface node.
    pub fn new(grid: &Grid) -> Self {
        Self::build(grid, &grid_coordinates(grid), &|_| None, 1)
    }

    /// The six faces of the cube with a vertex at every point of a lattice of the node coordinates
    /// `coords` along each axis (from 0 to the side), placed by `grid`'s nodes; `surface_node`
    /// names the lattice's surface node at a lattice point, where it has one (a dent is given by
    /// those: [`SurfaceMesh::vertices_of`]).
    pub fn on_lattice(grid: &Grid, coords: &[f64], surface_node: &dyn Fn([usize; 3]) -> Option<usize>) -> Self {
        Self::build(grid, coords, surface_node, COARSE_STRIDE)
    }

    /// [`SurfaceMesh::on_lattice`] with a face's coarse triangles on every `stride`th line.
    fn build(grid: &Grid, coords: &[f64], surface_node: &dyn Fn([usize; 3]) -> Option<usize>, stride: usize) -> Self {
        let m = coords.len();
        let mut vertex_node = Vec::with_capacity(6 * m * m);
        let mut weights = Vec::with_capacity(6 * m * m);
        let mut rest = Vec::with_capacity(6 * m * m);
        let mut lattice_vertices: Vec<[u32; 3]> = Vec::new();
        let mut faces: [[Vec<u32>; 2]; 6] = Default::default();
        // The lines of the coarse lattice: every stride-th and the last.
        let coarse: Vec<usize> = (0..m).filter(|&i| i % stride == 0 || i == m - 1).collect();
        for axis in 0..3 {
            let (u, v) = ((axis + 1) % 3, (axis + 2) % 3);
            for high in [false, true] {
                let base = vertex_node.len() as u32;
                for b in 0..m {
                    for a in 0..m {
                        let mut q = [0usize; 3];
                        q[axis] = if high { m - 1 } else { 0 };
                        q[u] = a;
                        q[v] = b;
                        let w = bilinear(grid, (axis, high), [coords[a], coords[b]]);
                        let nearest = w.iter().copied().fold(w[0], |best, x| if x.1 > best.1 { x } else { best });
                        vertex_node.push(nearest.0);
                        weights.push(w);
                        rest.push(q.map(|i| coords[i] as f32));
                        if let Some(s) = surface_node(q) {
                            if lattice_vertices.len() <= s {
                                lattice_vertices.resize(s + 1, [u32::MAX; 3]);
                            }
                            let slot = &mut lattice_vertices[s];
                            if let Some(free) = slot.iter_mut().find(|x| **x == u32::MAX) {
                                *free = base + (a + m * b) as u32;
                            }
                        }
                    }
                }
                let at = |a: usize, b: usize| base + (a + m * b) as u32;
                let face = &mut faces[2 * axis + usize::from(high)];
                let all: Vec<usize> = (0..m).collect();
                let [whole, sparse] = face;
                for (lines, indices) in [(&all, whole), (&coarse, sparse)] {
                    for b in lines.windows(2) {
                        for a in lines.windows(2) {
                            let (p00, p10, p11, p01) = (at(a[0], b[0]), at(a[1], b[0]), at(a[1], b[1]), at(a[0], b[1]));
                            // (u, v, axis) is right-handed: u x v = +axis, so (00, 10, 11) faces +axis.
                            if high {
                                indices.extend_from_slice(&[p00, p10, p11, p00, p11, p01]);
                            } else {
                                indices.extend_from_slice(&[p00, p11, p10, p00, p01, p11]);
                            }
                        }
                    }
                }
            }
        }
        let mut indices = Vec::with_capacity(faces.iter().map(|f| f[0].len()).sum());
        for f in &faces {
            indices.extend_from_slice(&f[1]);
        }
        let count = vertex_node.len();
        Self {
            vertex_node,
            indices,
            faces,
            face_vertices: m * m,
            vertices: vec![SurfaceVertex { position: [0.0; 3], normal: [0.0; 3], scalar: 0.0 }; count],
            weights,
            rest,
            lattice_vertices,
            normals: vec![[0.0; 3]; count],
        }
    }

    /// The most triangle indices drawn in a frame (every face on its whole lattice).
    pub fn index_capacity(&self) -> usize {
        self.indices.capacity()
    }

    /// The vertices standing on the lattice's surface node `q` (none where the mesh was built on
    /// the model's nodes).
    pub fn vertices_of(&self, q: usize) -> impl Iterator<Item = u32> + '_ {
        self.lattice_vertices.get(q).into_iter().flatten().copied().filter(|&v| v != u32::MAX)
    }

    /// The rest position of vertex `v`, metres.
    pub fn rest_of(&self, v: u32) -> [f32; 3] {
        self.rest[v as usize]
    }

    /// Updates positions, normals and colour values from node positions `x` (metres) and a
    /// per-node scalar already normalised to [0, 1] (or `None` for zero).
    pub fn update(&mut self, x: &[[f32; 3]], scalar: Option<&[f32]>) {
        self.update_dented(x, scalar, &[], None);
    }

    /// [`SurfaceMesh::update`] with the vertices of `dent` moved towards their positions there by
    /// its weights; with `per_metre`, their colour value is their displacement times it (at most
    /// 1), else the nodes'.
    pub fn update_dented(&mut self, x: &[[f32; 3]], scalar: Option<&[f32]>, dent: &[Dent], per_metre: Option<f32>) {
        for (v, w) in self.vertices.iter_mut().zip(&self.weights) {
            let mut p = [0.0f32; 3];
            let mut s = 0.0;
            for &(node, weight) in w {
                if weight != 0.0 {
                    let y = x[node as usize];
                    for c in 0..3 {
                        p[c] += weight * y[c];
                    }
                    s += weight * scalar.map_or(0.0, |s| s[node as usize]);
                }
            }
            v.position = p;
            v.scalar = s;
        }
        // Each face on its whole lattice where the dent moves a vertex of it, else its coarse one.
        let mut fine = [false; 6];
        for d in dent {
            fine[(d.vertex as usize / self.face_vertices).min(5)] = true;
        }
        self.indices.clear();
        for (f, whole) in self.faces.iter().zip(fine) {
            self.indices.extend_from_slice(&f[usize::from(!whole)]);
        }
        for d in dent {
            let v = &mut self.vertices[d.vertex as usize];
            for c in 0..3 {
                v.position[c] += d.weight * (d.at[c] - v.position[c]);
            }
            if let Some(k) = per_metre {
                let r = self.rest[d.vertex as usize];
                let moved = Vec3::from(v.position).distance(Vec3::from(r));
                v.scalar = (moved * k).min(1.0);
            }
        }
        self.normals.fill([0.0; 3]);
        for t in self.indices.chunks_exact(3) {
            let [a, b, c] = [t[0], t[1], t[2]].map(|i| self.vertices[i as usize].position);
            let e1 = [b[0] - a[0], b[1] - a[1], b[2] - a[2]];
            let e2 = [c[0] - a[0], c[1] - a[1], c[2] - a[2]];
            let n = [e1[1] * e2[2] - e1[2] * e2[1], e1[2] * e2[0] - e1[0] * e2[2], e1[0] * e2[1] - e1[1] * e2[0]];
            for &i in t {
                let acc = &mut self.normals[i as usize];
                for k in 0..3 {
                    acc[k] += n[k];
                }
            }
        }
        for (v, n) in self.vertices.iter_mut().zip(&self.normals) {
            let len = Vec3::from(*n).length().max(1e-30);
            v.normal = [n[0] / len, n[1] / len, n[2] / len];
        }
    }
}

impl SurfaceMesh {
    /// The nearest intersection of the ray `o + t d` (`t > 0`) with the surface: the hit point
    /// and the node of the hit triangle nearest to it (Moller-Trumbore).
    pub fn pick(&self, o: [f32; 3], d: [f32; 3]) -> Option<([f32; 3], usize)> {
        let sub = |a: [f32; 3], b: [f32; 3]| [a[0] - b[0], a[1] - b[1], a[2] - b[2]];
        let dot = |a: [f32; 3], b: [f32; 3]| Vec3::from(a).dot(Vec3::from(b));
        let cross = |a: [f32; 3], b: [f32; 3]| {
            [a[1] * b[2] - a[2] * b[1], a[2] * b[0] - a[0] * b[2], a[0] * b[1] - a[1] * b[0]]
        };
        let mut best: Option<(f32, [u32; 3])> = None;
        for t in self.indices.chunks_exact(3) {
            let [a, b, c] = [t[0], t[1], t[2]].map(|i| self.vertices[i as usize].position);
            let (e1, e2) = (sub(b, a), sub(c, a));
            let p = cross(d, e2);
            let det = dot(e1, p);
            if det.abs() < 1e-12 {
                continue;
            }
            let s = sub(o, a);
            let u = dot(s, p) / det;
            let q = cross(s, e1);
            let v = dot(d, q) / det;
            let dist = dot(e2, q) / det;
            if u >= 0.0 && v >= 0.0 && u + v <= 1.0 && dist > 0.0 && best.is_none_or(|(bt, _)| dist < bt) {
                best = Some((dist, [t[0], t[1], t[2]]));
            }
        }
        let (dist, tri) = best?;
        let hit = [o[0] + dist * d[0], o[1] + dist * d[1], o[2] + dist * d[2]];
        let vertex = tri
            .into_iter()
            .min_by(|&i, &j| {
                let di = sub(self.vertices[i as usize].position, hit);
                let dj = sub(self.vertices[j as usize].position, hit);
                dot(di, di).total_cmp(&dot(dj, dj))
            })
            .unwrap_or(tri[0]);
        Some((hit, self.vertex_node[vertex as usize] as usize))
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn pick_hits_the_top_face() {
        let g = Grid::paper();
        let mut m = SurfaceMesh::new(&g);
        let x: Vec<[f32; 3]> = g.positions().iter().map(|p| p.map(|c| c as f32)).collect();
        m.update(&x, None);
        let (hit, node) = m.pick([0.044, 0.041, 0.5], [0.0, 0.0, -1.0]).unwrap();
        assert!((hit[2] - 0.1).abs() < 1e-6);
        assert_eq!(node, g.node(3, 3, 7));
        assert!(m.pick([0.5, 0.5, 0.5], [0.0, 0.0, 1.0]).is_none());
    }

    #[test]
    fn normals_point_outwards_at_rest() {
        let g = Grid::new(4).unwrap();
        let mut m = SurfaceMesh::new(&g);
        assert_eq!(m.indices.len(), 6 * 9 * 6);
        let x: Vec<[f32; 3]> = g.positions().iter().map(|p| p.map(|c| c as f32)).collect();
        m.update(&x, None);
        for v in &m.vertices {
            let c = [v.position[0] - 0.05, v.position[1] - 0.05, v.position[2] - 0.05];
            let dot = Vec3::from(c).dot(Vec3::from(v.normal));
            assert!(dot > 0.0, "{v:?}");
        }
    }
}
