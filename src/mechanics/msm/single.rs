//! The springs' force of the explicit step in `f32`, from displacements (the lattices'
//! `cpu-f32` step; [`super::Dynamics::set_single_precision`]).
//!
//! Positions in `f32` would carry 6e-9 m of a 0.1 m cube, a tenth of a percent of a spring's
//! stretch at 24^3, so each pair's difference is the family's rest vector `r` plus the
//! displacements' difference `e = u_b - u_a` (`u = x - X`, rounded to `f32`), and the stretch comes
//! without cancellation: `l - l0 = (2 r.e + e.e) / (l + l0)`, `l = |r + e|`. The pair's force is
//! `k (l - l0) / l (r + e)`, the force of [`super::forces`], summed family by family as there.
//! With AVX2 the loops run eight pairs a register (the compiler's vectorisation of plain loops).

use super::forces::dispatch_avx2;
use super::model::MsmModel;

/// One spring family in `f32`.
#[derive(Debug, Clone)]
struct Family {
    offset: usize,
    rest: [f32; 3],
    rest_length: f32,
    stiffness: Vec<f32>,
}

/// The buffers and the families of the `f32` force.
#[derive(Debug, Clone)]
pub struct SingleForce {
    rest: [Vec<f64>; 3],
    families: Vec<Family>,
    u: [Vec<f32>; 3],
    f: [Vec<f32>; 3],
    /// As [`super::forces::ForceScratch`]: the pair forces of one family, `offset` zeros ahead.
    t: [Vec<f32>; 3],
}

impl SingleForce {
    /// The `f32` force of `model` (its stiffness rounded to `f32`).
    pub fn new(model: &MsmModel) -> Self {
        let g = model.grid;
        let (nn, h) = (g.num_nodes(), g.h());
        let families: Vec<Family> = model
            .families
            .iter()
            .map(|f| Family {
                offset: f.offset,
                rest: f.family.offset.map(|o| (f64::from(o) * h) as f32),
                rest_length: f.rest_length as f32,
                stiffness: f.stiffness.iter().map(|&k| k as f32).collect(),
            })
            .collect();
        let widest = families.iter().map(|f| f.offset).max().unwrap_or(0);
        Self {
            rest: std::array::from_fn(|c| (0..nn).map(|p| g.position(p)[c]).collect()),
            families,
            u: std::array::from_fn(|_| vec![0.0; nn]),
            f: std::array::from_fn(|_| vec![0.0; nn]),
            t: std::array::from_fn(|_| vec![0.0; nn + widest]),
        }
    }

    /// The springs' force on every node at positions `x`, in `f32`. Allocation-free.
    pub fn forces(&mut self, x: &[Vec<f64>; 3]) -> &[Vec<f32>; 3] {
        compute(self, x);
        &self.f
    }
}

fn compute(s: &mut SingleForce, x: &[Vec<f64>; 3]) {
    dispatch_avx2!(forces_generic, forces_avx2, (s: &mut SingleForce, x: &[Vec<f64>; 3]));
}

#[inline(always)]
fn forces_generic(s: &mut SingleForce, x: &[Vec<f64>; 3]) {
    let nn = s.rest[0].len();
    for c in 0..3 {
        let (u, x, r) = (&mut s.u[c][..nn], &x[c][..nn], &s.rest[c][..nn]);
        for p in 0..nn {
            u[p] = (x[p] - r[p]) as f32;
        }
        s.f[c].fill(0.0);
    }
    for fam in &s.families {
        let (len, off) = (fam.stiffness.len(), fam.offset);
        debug_assert!(len + off <= nn);
        for t in &mut s.t {
            t[..off].fill(0.0);
            t[off + len..off + nn].fill(0.0);
        }
        pairs(fam, [&s.u[0], &s.u[1], &s.u[2]], &mut s.t);
        for (f, t) in s.f.iter_mut().zip(&s.t) {
            let (f, ahead, behind) = (&mut f[..nn], &t[off..off + nn], &t[..nn]);
            for q in 0..nn {
                f[q] += ahead[q] - behind[q];
            }
        }
    }
}

/// One family's pair forces into `t[c][offset + p]`.
#[inline(always)]
fn pairs(fam: &Family, u: [&[f32]; 3], t: &mut [Vec<f32>; 3]) {
    let (len, off) = (fam.stiffness.len(), fam.offset);
    let k = &fam.stiffness[..len];
    let ([rx, ry, rz], l0) = (fam.rest, fam.rest_length);
    let (xa, xb) = (&u[0][..len], &u[0][off..off + len]);
    let (ya, yb) = (&u[1][..len], &u[1][off..off + len]);
    let (za, zb) = (&u[2][..len], &u[2][off..off + len]);
    let [tx, ty, tz] = t;
    let (tx, ty, tz) = (&mut tx[off..off + len], &mut ty[off..off + len], &mut tz[off..off + len]);
    for p in 0..len {
        let (ex, ey, ez) = (xb[p] - xa[p], yb[p] - ya[p], zb[p] - za[p]);
        let (dx, dy, dz) = (rx + ex, ry + ey, rz + ez);
        let stretch2 = 2.0 * (rx * ex + ry * ey + rz * ez) + (ex * ex + ey * ey + ez * ez);
        let l = (dx * dx + dy * dy + dz * dz).sqrt().max(f32::MIN_POSITIVE);
        let c = k[p] * stretch2 / (l * (l + l0));
        tx[p] = c * dx;
        ty[p] = c * dy;
        tz[p] = c * dz;
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::mechanics::grid::Grid;
    use crate::mechanics::msm::{MsmParams, Topology};

    #[test]
    fn the_f32_force_is_the_f64_one_to_f32_rounding() {
        for topology in [Topology::Axis, Topology::Shear, Topology::Hex] {
            let params = MsmParams::unit(topology);
            let model = MsmModel::new(Grid::new(7).unwrap(), params, 1000.0).unwrap();
            let nn = model.grid.num_nodes();
            // A smooth stretch plus a ripple, 1e-4 of the cube.
            let x: [Vec<f64>; 3] = std::array::from_fn(|c| {
                (0..nn)
                    .map(|p| {
                        let at = model.grid.position(p);
                        at[c] * (1.0 + 1e-3 * (c as f64 + 1.0)) + 1e-5 * ((p * (c + 3)) % 7) as f64
                    })
                    .collect()
            });
            let mut exact: [Vec<f64>; 3] = std::array::from_fn(|_| vec![0.0; nn]);
            let mut scratch = super::super::forces::ForceScratch::new(&model);
            super::super::forces::add_spring_forces(&model, &x, &mut exact, &mut scratch);
            let scale = exact.iter().flatten().fold(0.0f64, |m, v| m.max(v.abs()));
            let mut single = SingleForce::new(&model);
            let f = single.forces(&x);
            for c in 0..3 {
                for p in 0..nn {
                    let off = (f64::from(f[c][p]) - exact[c][p]).abs();
                    assert!(off <= 1e-5 * scale, "{topology:?} node {p} {c}: {off:e} of {scale:e}");
                }
            }
        }
    }
}
