//! The cube's surface as triangles, rebuilt from node positions every frame without allocating.
//!
//! Each of the six faces has its own `n x n` vertices (so the cube's edges stay sharp) and its
//! normals are recomputed from the deformed positions (area-weighted triangle normals).

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

/// The surface of a deforming cube.
#[derive(Debug, Clone)]
pub struct SurfaceMesh {
    /// For each surface vertex, the node it shows.
    pub vertex_node: Vec<u32>,
    /// Triangle indices into the vertices (counter-clockwise seen from outside).
    pub indices: Vec<u32>,
    /// Current vertices.
    pub vertices: Vec<SurfaceVertex>,
    normals: Vec<[f32; 3]>,
}

impl SurfaceMesh {
    /// The six faces of `grid`.
    pub fn new(grid: &Grid) -> Self {
        let n = grid.n();
        let mut vertex_node = Vec::with_capacity(6 * n * n);
        let mut indices = Vec::with_capacity(6 * (n - 1) * (n - 1) * 6);
        for axis in 0..3 {
            let (u, v) = ((axis + 1) % 3, (axis + 2) % 3);
            for high in [false, true] {
                let base = vertex_node.len() as u32;
                for b in 0..n {
                    for a in 0..n {
                        let mut ijk = [0usize; 3];
                        ijk[axis] = if high { n - 1 } else { 0 };
                        ijk[u] = a;
                        ijk[v] = b;
                        vertex_node.push(grid.node(ijk[0], ijk[1], ijk[2]) as u32);
                    }
                }
                let at = |a: usize, b: usize| base + (a + n * b) as u32;
                for b in 0..n - 1 {
                    for a in 0..n - 1 {
                        let (p00, p10, p11, p01) = (at(a, b), at(a + 1, b), at(a + 1, b + 1), at(a, b + 1));
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
        let count = vertex_node.len();
        Self {
            vertex_node,
            indices,
            vertices: vec![SurfaceVertex { position: [0.0; 3], normal: [0.0; 3], scalar: 0.0 }; count],
            normals: vec![[0.0; 3]; count],
        }
    }

    /// Updates positions, normals and colour values from node positions `x` (metres) and a
    /// per-node scalar already normalised to [0, 1] (or `None` for zero).
    pub fn update(&mut self, x: &[[f32; 3]], scalar: Option<&[f32]>) {
        for (v, &node) in self.vertices.iter_mut().zip(&self.vertex_node) {
            v.position = x[node as usize];
            v.scalar = scalar.map_or(0.0, |s| s[node as usize]);
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
