//! The dent under the probe, drawn at the material's resolution: the cube's surface is drawn on
//! the lattice of the material's surface compliance (2 mm, 1 mm across the edges), placed by the
//! running model's nodes, and near the probe's contact by the material's own displacement under
//! the contact's forces ([`SurfaceCompliance::near_contact`]), so that the dent has the
//! sphere's shape whatever model runs. The contact's nodes are drawn on the sphere (the linear
//! contact puts them there to 0.06 mm at 4 mm deep, 0.6 mm at 3/4 of the radius) and no drawn
//! point is inside it; the material's shape is taken whole within [`FULL_M`] of the contact and
//! blends into the model's by [`REACH_M`].

use glam::DVec3;

use crate::mechanics::grid::Grid;
use crate::render::mesh::{Dent, SurfaceMesh};
use crate::sim::material_surface::compliance::lattice::Lattice;
use crate::sim::material_surface::compliance::{DEFAULT_DIVISIONS, SurfaceCompliance};

/// Distance from the contact's nodes within which the material's shape is drawn whole, metres.
pub const FULL_M: f64 = 0.003;
/// Distance from the contact's nodes beyond which the model alone is drawn, metres.
pub const REACH_M: f64 = 0.015;
/// Most vertices a dent moves (the capacity reserved once: a 50 mm sphere 3/4 of its radius deep
/// and its blend fit).
pub const MAX_DENT: usize = 16_384;

/// The surface as drawn: on the lattice of the material's surface compliance, placed by `grid`'s
/// nodes.
pub fn display_mesh(grid: &Grid) -> SurfaceMesh {
    let lattice = Lattice::new(DEFAULT_DIVISIONS);
    SurfaceMesh::on_lattice(grid, &lattice.coords, &|q| lattice.index(q))
}

/// The weight of the material's shape at `distance` from the contact's nodes: 1 within
/// [`FULL_M`], 0 from [`REACH_M`], smooth between.
fn weight(distance: f64) -> f32 {
    let t = ((distance - FULL_M) / (REACH_M - FULL_M)).clamp(0.0, 1.0);
    (1.0 - t * t * (3.0 - 2.0 * t)) as f32
}

/// Fills `dent` (cleared first; at most its capacity) with the vertices of `mesh` near `contact`
/// on `compliance` (a press's contact: surface node, the sphere's normal, force) and where the
/// material puts them, the sphere (`centre`, `radius`) kept out.
pub fn fill(
    dent: &mut Vec<Dent>,
    mesh: &SurfaceMesh,
    compliance: &SurfaceCompliance,
    contact: &[(usize, [f64; 3], f64)],
    (centre, radius): ([f64; 3], f64),
) {
    dent.clear();
    // The mesh stands on the lattice of DEFAULT_DIVISIONS: another's nodes are not its vertices.
    if contact.is_empty() || compliance.lattice_size().0 != DEFAULT_DIVISIONS {
        return;
    }
    let c = DVec3::from(centre);
    compliance.near_contact(contact, REACH_M, |q, x, distance, u| {
        let mut y = DVec3::from(x) + DVec3::from(u);
        // A contact node on the sphere; any other outside it.
        let from = y - c;
        if distance == 0.0 || from.length() < radius {
            y = c + from.normalize_or_zero() * radius;
        }
        let at = y.as_vec3().to_array();
        for vertex in mesh.vertices_of(q) {
            if dent.len() < dent.capacity() {
                dent.push(Dent { vertex, at, weight: weight(distance) });
            }
        }
    });
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::mechanics::material::Material;
    use crate::sim::material_surface::compliance::SurfaceContactScratch;

    /// The drawn surface meets the sphere: on the rim of a press (4 mm deep and 3/4 of the radius,
    /// the top face, a side, across an edge) no drawn vertex near the contact is inside the sphere
    /// or more than 0.5 mm off it where the material's shape is drawn whole and the surface
    /// touches it (the contact's nodes), whatever the model's nodes do.
    #[test]
    fn the_drawn_dent_has_the_spheres_shape() {
        let material = Material::object_a();
        let compliance = crate::sim::material_surface::shipped(&material).expect("A's");
        let grid = Grid::paper();
        let mut mesh = display_mesh(&grid);
        let rest: Vec<[f32; 3]> = grid.positions().iter().map(|p| p.map(|c| c as f32)).collect();
        let r = 0.015;
        for (touch, n, depth, what) in [
            ([0.05, 0.05, 0.1], [0.0, 0.0, 1.0], 0.004, "top, 4 mm"),
            ([0.05, 0.05, 0.1], [0.0, 0.0, 1.0], 0.75 * r, "top, 3/4 of the radius"),
            ([0.05, 0.0, 0.05], [0.0, -1.0, 0.0], 0.004, "-y, 4 mm"),
            (
                [0.1, 0.05, 0.1],
                [std::f64::consts::FRAC_1_SQRT_2, 0.0, std::f64::consts::FRAC_1_SQRT_2],
                0.003,
                "across the top/+x edge",
            ),
        ] {
            let centre: [f64; 3] = std::array::from_fn(|a| touch[a] + n[a] * (r - depth));
            let mut scratch = SurfaceContactScratch::default();
            compliance.press(centre, r, &mut scratch).expect("a press");
            let contact: Vec<(usize, [f64; 3], f64)> = scratch.contacts().collect();
            let mut dent = Vec::with_capacity(MAX_DENT);
            fill(&mut dent, &mesh, &compliance, &contact, (centre, r));
            assert!(dent.len() > contact.len(), "{what}: {} vertices dented", dent.len());
            // The model at rest: the dent alone makes the shape.
            mesh.update_dented(&rest, None, &dent, None);
            let c = DVec3::from(centre);
            let inward = -DVec3::from(n);
            let contact_rest: Vec<DVec3> =
                contact.iter().map(|&(q, _, _)| DVec3::from(compliance.position(q))).collect();
            let (mut on, mut deepest, mut widest) = (0, 0.0f64, 0.0f64);
            for d in &dent {
                let p = DVec3::from(mesh.vertices[d.vertex as usize].position.map(f64::from));
                let rest = DVec3::from(mesh.rest_of(d.vertex).map(f64::from));
                let off = p.distance(c) - r;
                assert!(off > -1e-5, "{what}: vertex {} {:.3} mm inside the sphere", d.vertex, -1e3 * off);
                let near = contact_rest.iter().map(|x| x.distance(rest)).fold(f64::INFINITY, f64::min);
                if near < 1e-6 {
                    // The contact's own vertices: on the sphere, the material's shape whole.
                    assert!(off < 1e-5 && d.weight == 1.0, "{what}: a contact vertex {:.3} mm off", 1e3 * off);
                    on += 1;
                } else if near < 1.1e-3 {
                    // The rim: the surface leaves the sphere gradually (no step).
                    widest = widest.max(off);
                }
                deepest = deepest.max((p - rest).dot(inward));
            }
            assert!(on >= contact.len(), "{what}: {on} vertices on the sphere");
            // Across an edge the faces leave the sphere by the edge's own shape (a side node 1 mm
            // down from the edge is 0.7 mm off a sphere at 45 degrees): on a face only.
            assert!(
                widest < 5e-4 || n.iter().filter(|c| **c != 0.0).count() > 1,
                "{what}: {:.3} mm between the sphere and the rim",
                1e3 * widest
            );
            // The dent is as deep as the press (the old drawing on the model's nodes: 3.07 mm at 4).
            assert!(
                (deepest - depth).abs() < 0.05 * depth,
                "{what}: the dent {:.2} mm deep for {:.2}",
                1e3 * deepest,
                1e3 * depth
            );
        }
    }

    #[test]
    fn the_weight_is_whole_at_the_contact_and_none_beyond_the_reach() {
        assert_eq!(weight(0.0), 1.0);
        assert_eq!(weight(FULL_M), 1.0);
        assert_eq!(weight(REACH_M), 0.0);
        assert!(weight(0.5 * (FULL_M + REACH_M)) > 0.4 && weight(0.5 * (FULL_M + REACH_M)) < 0.6);
    }
}
