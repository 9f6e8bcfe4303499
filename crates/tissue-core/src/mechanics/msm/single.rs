//! The springs' force of the explicit step in `f32`, from displacements (the lattices'
//! `cpu-f32` step; [`super::Dynamics::set_single_precision`]).
//!
//! Positions in `f32` would carry 6e-9 m of a 0.1 m cube, a tenth of a percent of a spring's
//! stretch at 24^3, so each pair's difference is the family's rest vector `r` plus the
//! displacements' difference `e = u_b - u_a` (`u = x - X`, rounded to `f32`), and the stretch comes
//! without cancellation: `l - l0 = e.(2 r + e) / (l + l0)`, `l = |r + e|`. The pair's force is
//! `k (l - l0) / l (r + e)`, the force of [`super::forces`].
//!
//! The nodes go in chunks of sixteen, in node order: a chunk sums the pairs of every family that
//! start on its nodes in registers, and takes each pair's force from its second node ahead, so
//! the displacements and forces it touches lie within the widest family's reach (601 nodes at
//! 24^3, about 15 KB, in the L1 cache). Family by family over the whole grid (each family's pair
//! forces stored, then summed onto the nodes in a second pass, as [`super::forces`] does in
//! `f64`), every buffer went through the L2 cache thirteen times a step for the hex lattice, and
//! the step took 185 us at 24^3 where it takes about 137 now. The chunks run in AVX-512 or AVX2
//! registers where the CPU has them (the compiler's vectorisation of plain loops over
//! fixed-length arrays), with fused multiply-adds there.

use super::forces::dispatch_simd;
use super::model::MsmModel;

/// Nodes a chunk takes ([`SingleForce::compute`]): one AVX-512 register of `f32`, two of AVX2
/// (eight nodes a chunk, one AVX2 register, took 177 us a step at 24^3 against 137).
const LANES: usize = 16;

type Lanes = [f32; LANES];

/// One spring family in `f32`.
#[derive(Debug, Clone)]
struct Family {
    offset: usize,
    rest: [f32; 3],
    rest_length: f32,
    /// Each pair's stiffness by its first node, zero past the last pair up to a whole chunk.
    stiffness: Vec<f32>,
}

/// The buffers and the families of the `f32` force.
#[derive(Debug, Clone)]
pub struct SingleForce {
    rest: [Vec<f64>; 3],
    families: Vec<Family>,
    /// The displacements `x - X`, rounded; zeros past the last node, as far as the last chunk's
    /// springs reach.
    u: [Vec<f32>; 3],
    /// The springs' forces on the nodes (past the last node, as `u`: unused).
    f: [Vec<f32>; 3],
}

impl SingleForce {
    /// The `f32` force of `model` (its stiffness rounded to `f32`).
    pub fn new(model: &MsmModel) -> Self {
        let g = model.grid;
        let (nn, h) = (g.num_nodes(), g.h());
        let chunks = nn.div_ceil(LANES) * LANES;
        let families: Vec<Family> = model
            .families
            .iter()
            .map(|f| {
                let mut stiffness: Vec<f32> = f.stiffness.iter().map(|&k| k as f32).collect();
                stiffness.resize(chunks, 0.0);
                Family {
                    offset: f.offset,
                    rest: f.family.offset.map(|o| (f64::from(o) * h) as f32),
                    rest_length: f.rest_length as f32,
                    stiffness,
                }
            })
            .collect();
        // The last chunk's widest spring reaches this far.
        let padded = chunks + families.iter().map(|f| f.offset).max().unwrap_or(0);
        Self {
            rest: std::array::from_fn(|c| (0..nn).map(|p| g.position(p)[c]).collect()),
            families,
            u: std::array::from_fn(|_| vec![0.0; padded]),
            f: std::array::from_fn(|_| vec![0.0; padded]),
        }
    }

    /// The springs' force on every node at positions `x`, in `f32` (an entry per node, then
    /// unused ones). Allocation-free.
    pub fn forces(&mut self, x: &[Vec<f64>; 3]) -> &[Vec<f32>; 3] {
        compute(self, x);
        &self.f
    }

    /// [`SingleForce::forces`] inlined into the caller, so that it runs in the caller's
    /// instruction set; `FMA`: whether that set fuses multiply-adds. Chunk by chunk, as the
    /// module says.
    #[inline(always)]
    pub fn compute<const FMA: bool>(&mut self, x: &[Vec<f64>; 3]) -> &[Vec<f32>; 3] {
        let nn = self.rest[0].len();
        for c in 0..3 {
            let (u, x, r) = (&mut self.u[c][..nn], &x[c][..nn], &self.rest[c][..nn]);
            for p in 0..nn {
                u[p] = (x[p] - r[p]) as f32;
            }
            self.f[c].fill(0.0);
        }
        let mut p = 0;
        while p < nn {
            let ua: [Lanes; 3] = std::array::from_fn(|c| lanes(&self.u[c], p));
            let mut own = [[0.0f32; LANES]; 3];
            for fam in &self.families {
                let ub: [Lanes; 3] = std::array::from_fn(|c| lanes(&self.u[c], p + fam.offset));
                let t = pair_forces::<FMA>(fam, &ua, &ub, &lanes(&fam.stiffness, p));
                for c in 0..3 {
                    own[c] = std::array::from_fn(|i| own[c][i] + t[c][i]);
                    let second = lanes(&self.f[c], p + fam.offset);
                    set_lanes(&mut self.f[c], p + fam.offset, std::array::from_fn(|i| second[i] - t[c][i]));
                }
            }
            for c in 0..3 {
                let f = lanes(&self.f[c], p);
                set_lanes(&mut self.f[c], p, std::array::from_fn(|i| f[i] + own[c][i]));
            }
            p += LANES;
        }
        &self.f
    }
}

/// The [`LANES`] values of `s` from `at`.
#[inline(always)]
fn lanes(s: &[f32], at: usize) -> Lanes {
    let s = &s[at..at + LANES];
    std::array::from_fn(|i| s[i])
}

/// Writes `v` over the [`LANES`] values of `s` from `at`.
#[inline(always)]
fn set_lanes(s: &mut [f32], at: usize, v: Lanes) {
    s[at..at + LANES].copy_from_slice(&v);
}

fn compute(s: &mut SingleForce, x: &[Vec<f64>; 3]) {
    dispatch_simd!(compute_generic, (s: &mut SingleForce, x: &[Vec<f64>; 3]));
}

#[inline(always)]
fn compute_generic<const FMA: bool>(s: &mut SingleForce, x: &[Vec<f64>; 3]) {
    s.compute::<FMA>(x);
}

/// One family's forces on the first nodes of [`LANES`] pairs, from the displacements of their
/// first (`ua`) and second (`ub`) nodes: `e = ub - ua`, `d = r + e`, `l = |d|`, and the stretch
/// without cancellation, `l - l0 = (l^2 - l0^2) / (l + l0)`, `l^2 - l0^2 = e.(2 r + e)`; the
/// force is `k (l - l0) / l d`.
#[inline(always)]
fn pair_forces<const FMA: bool>(fam: &Family, ua: &[Lanes; 3], ub: &[Lanes; 3], k: &Lanes) -> [Lanes; 3] {
    // `a b + c`, fused where the caller's instruction set has it.
    let fma = |a: f32, b: f32, c: f32| if FMA { a.mul_add(b, c) } else { a * b + c };
    let ([rx, ry, rz], l0) = (fam.rest, fam.rest_length);
    let mut t = [[0.0f32; LANES]; 3];
    for i in 0..LANES {
        let (ex, ey, ez) = (ub[0][i] - ua[0][i], ub[1][i] - ua[1][i], ub[2][i] - ua[2][i]);
        let (dx, dy, dz) = (rx + ex, ry + ey, rz + ez);
        let stretch2 = fma(ez, rz + dz, fma(ey, ry + dy, ex * (rx + dx)));
        let l = fma(dz, dz, fma(dy, dy, dx * dx)).sqrt().max(f32::MIN_POSITIVE);
        let c = k[i] * stretch2 / (l * (l + l0));
        t[0][i] = c * dx;
        t[1][i] = c * dy;
        t[2][i] = c * dz;
    }
    t
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
            // The CPU's path, and both kinds of arithmetic in any instruction set (343 nodes:
            // the last chunk is partial).
            let paths: [(&str, fn(&mut SingleForce, &[Vec<f64>; 3]) -> Vec<Vec<f32>>); 3] = [
                ("dispatched", |s, x| s.forces(x).to_vec()),
                ("fused", |s, x| s.compute::<true>(x).to_vec()),
                ("plain", |s, x| s.compute::<false>(x).to_vec()),
            ];
            for (path, force) in paths {
                let f = force(&mut single, &x);
                for c in 0..3 {
                    for p in 0..nn {
                        let off = (f64::from(f[c][p]) - exact[c][p]).abs();
                        assert!(off <= 1e-5 * scale, "{topology:?} {path} node {p} {c}: {off:e} of {scale:e}");
                    }
                }
            }
        }
    }
}
