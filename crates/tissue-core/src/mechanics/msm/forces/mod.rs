//! Spring forces and tangent stiffness of the mass-spring model.
//!
//! A spring between nodes `i` and `j` with stiffness `k` and rest length `l0` pulls `i` towards
//! `j` with `f_i = k (l - l0) d`, `d = (x_j - x_i) / l`, and `f_j = -f_i`. Its tangent stiffness
//! block is `K_s = k [ (1 - l0/l) (I - d d^T) + d d^T ]`.
//!
//! The force loop runs family by family over contiguous node ranges (structure of arrays), which
//! the compiler vectorises; it allocates nothing.
//!
//! `pair_loop`: one family's pair forces, in AVX2 or one by one.

use super::model::{MsmModel, Spring};
use super::reduction::DofMap;
use crate::mechanics::sparse::{SparseError, SpdSystem};
use glam::DVec3;

/// The pair forces of one spring family at a time, reused family after family so the force loop
/// stays in cache (a buffer per family is 13 x 3 x 8 bytes a node for the hex lattice: 4.3 MB
/// at 24^3, above a core's L2; one is 0.3 MB).
///
/// For a family with offset `s`, `t[c][s + p]` holds component `c` of the force on the first node
/// of pair `p` (the pair `(p, p + s)`); the `s` leading and trailing entries are zero, so that the
/// net force of the family on node `q` is `t[s + q] - t[q]` for every node without a branch.
#[derive(Debug, Clone)]
pub struct ForceScratch {
    t: [Vec<f64>; 3],
}

impl ForceScratch {
    /// Buffers for the families of `model`.
    pub fn new(model: &MsmModel) -> Self {
        let nn = model.grid.num_nodes();
        let widest = model.families.iter().map(|f| f.offset).max().unwrap_or(0);
        Self { t: std::array::from_fn(|_| vec![0.0; nn + widest]) }
    }
}

/// Calls `$generic` through a copy of it compiled with AVX2 (4 doubles per instruction) when the
/// CPU has it. No fused multiply-add is enabled, so both paths give identical bits.
macro_rules! dispatch_avx2 {
    ($generic:ident, $avx2:ident, ($($arg:ident : $ty:ty),*)) => {
        #[cfg(target_arch = "x86_64")]
        #[target_feature(enable = "avx2")]
        unsafe fn $avx2($($arg: $ty),*) {
            $generic($($arg),*)
        }
        #[cfg(target_arch = "x86_64")]
        {
            if std::arch::is_x86_feature_detected!("avx2") {
                // SAFETY: the CPU supports AVX2, checked just above.
                unsafe { $avx2($($arg),*) };
                return;
            }
        }
        $generic($($arg),*);
    };
}
pub(crate) use dispatch_avx2;

/// Calls `$generic::<true>` through a copy compiled with AVX-512 (and AVX2 and FMA) or with AVX2
/// and FMA, the widest the CPU has, else `$generic::<false>` (the const parameter: whether
/// multiply-adds may be fused). For the `f32` steps, whose bits may differ between the paths.
macro_rules! dispatch_simd {
    ($generic:ident, ($($arg:ident : $ty:ty),*)) => {
        #[cfg(target_arch = "x86_64")]
        {
            #[target_feature(enable = "avx512f,avx2,fma")]
            unsafe fn avx512($($arg: $ty),*) {
                $generic::<true>($($arg),*)
            }
            #[target_feature(enable = "avx2,fma")]
            unsafe fn avx2($($arg: $ty),*) {
                $generic::<true>($($arg),*)
            }
            if std::arch::is_x86_feature_detected!("avx512f")
                && std::arch::is_x86_feature_detected!("avx2")
                && std::arch::is_x86_feature_detected!("fma")
            {
                // SAFETY: the CPU supports AVX-512F, AVX2 and FMA, checked just above.
                unsafe { avx512($($arg),*) };
                return;
            }
            if std::arch::is_x86_feature_detected!("avx2") && std::arch::is_x86_feature_detected!("fma") {
                // SAFETY: the CPU supports AVX2 and FMA, checked just above.
                unsafe { avx2($($arg),*) };
                return;
            }
        }
        $generic::<false>($($arg),*);
    };
}
pub(crate) use dispatch_simd;

/// Adds every spring's force at positions `x` to `f` (x, y, z arrays), family by family: the
/// family's pair forces into `scratch`, then `f[q] += t[s + q] - t[q]`. The same sums in the same
/// order as with a buffer per family. `FAST`: the explicit step's pair loop ([`pair_loop`]), else
/// a square root and a division per spring (statics, calibration, the implicit steps).
#[inline(always)]
pub(crate) fn accumulate_spring_forces<const FAST: bool>(
    model: &MsmModel,
    x: &[Vec<f64>; 3],
    f: &mut [Vec<f64>; 3],
    scratch: &mut ForceScratch,
) {
    let nn = f[0].len();
    for fam in &model.families {
        let len = fam.stiffness.len();
        let (lo, s, l0) = (fam.lo, fam.offset, fam.rest_length);
        debug_assert_eq!(lo, 0);
        debug_assert!(len <= nn && s + nn <= scratch.t[0].len());
        let k = &fam.stiffness[..len];
        let (xa, xb) = (&x[0][lo..lo + len], &x[0][lo + s..lo + s + len]);
        let (ya, yb) = (&x[1][lo..lo + len], &x[1][lo + s..lo + s + len]);
        let (za, zb) = (&x[2][lo..lo + len], &x[2][lo + s..lo + s + len]);
        for t in &mut scratch.t {
            t[..s].fill(0.0);
            t[s + len..s + nn].fill(0.0);
        }
        let [tx, ty, tz] = &mut scratch.t;
        let (tx, ty, tz) = (&mut tx[s..s + len], &mut ty[s..s + len], &mut tz[s..s + len]);
        if FAST {
            pair_loop(k, l0, [xa, xb, ya, yb, za, zb], [tx, ty, tz]);
        } else {
            pair_loop_scalar(k, l0, [xa, xb, ya, yb, za, zb], [tx, ty, tz], 0);
        }
        for (fc, t) in f.iter_mut().zip(&scratch.t) {
            let (ahead, behind) = (&t[s..s + nn], &t[..nn]);
            for ((fq, a), b) in fc.iter_mut().zip(ahead).zip(behind) {
                *fq += a - b;
            }
        }
    }
}

#[inline(always)]
fn add_spring_forces_generic(model: &MsmModel, x: &[Vec<f64>; 3], f: &mut [Vec<f64>; 3], scratch: &mut ForceScratch) {
    accumulate_spring_forces::<false>(model, x, f, scratch);
}

/// Adds every spring force at positions `x` to `f` (both structure of arrays, one entry per node).
pub fn add_spring_forces(model: &MsmModel, x: &[Vec<f64>; 3], f: &mut [Vec<f64>; 3], scratch: &mut ForceScratch) {
    dispatch_avx2!(
        add_spring_forces_generic,
        add_spring_forces_avx2,
        (model: &MsmModel, x: &[Vec<f64>; 3], f: &mut [Vec<f64>; 3], scratch: &mut ForceScratch)
    );
}

/// `out = K_t(x) p` on node arrays: the springs' tangent at positions `x`, each geometric part
/// `(1 - l0 / l)` clamped at zero (the assembled tangent of [`TangentAssembler::assemble`] with
/// `clamp_geometric`, without building it), family by family through `scratch` as the forces are.
/// For the implicit steps' conjugate gradients ([`crate::mechanics::newton_krylov`]).
/// Allocation-free.
pub fn tangent_product(
    model: &MsmModel,
    x: &[Vec<f64>; 3],
    p: &[Vec<f64>; 3],
    out: &mut [Vec<f64>; 3],
    scratch: &mut ForceScratch,
) {
    let nn = out[0].len();
    for o in out.iter_mut() {
        o.fill(0.0);
    }
    for fam in &model.families {
        let len = fam.stiffness.len();
        let (s, l0) = (fam.offset, fam.rest_length);
        debug_assert_eq!(fam.lo, 0);
        for t in &mut scratch.t {
            t[..s].fill(0.0);
            t[s + len..s + nn].fill(0.0);
        }
        for (q, &k) in fam.stiffness.iter().enumerate() {
            let d: [f64; 3] = std::array::from_fn(|c| x[c][q + s] - x[c][q]);
            let l = DVec3::from(d).length().max(f64::MIN_POSITIVE);
            let n = d.map(|v| v / l);
            let g = (1.0 - l0 / l).max(0.0);
            let dp: [f64; 3] = std::array::from_fn(|c| p[c][q + s] - p[c][q]);
            let along = n[0] * dp[0] + n[1] * dp[1] + n[2] * dp[2];
            for (c, t) in scratch.t.iter_mut().enumerate() {
                t[s + q] = k * (g * dp[c] + (1.0 - g) * n[c] * along);
            }
        }
        // `t` is minus the product's share on each pair's first node, as a force would be.
        for (oc, t) in out.iter_mut().zip(&scratch.t) {
            let (ahead, behind) = (&t[s..s + nn], &t[..nn]);
            for ((o, a), b) in oc.iter_mut().zip(ahead).zip(behind) {
                *o -= a - b;
            }
        }
    }
}

/// Tangent-stiffness assembly of a model into a sparse SPD system over reduced unknowns
/// (see [`DofMap`]): `P^T K_t P`.
#[derive(Debug)]
pub struct TangentAssembler {
    /// The sparse system over the reduced unknowns.
    pub system: SpdSystem,
    /// Node dofs -> reduced unknowns.
    pub dofs: DofMap,
    /// One spring per orbit under the map's reflections, with the orbit's size.
    springs: Vec<(Spring, f64)>,
    /// For each spring `(a, b)`: (slot, factor) of the lower (a,a) block (6), the lower (b,b)
    /// block (6) and the full (b,a) block (9); slot `u32::MAX` where a dof is held. The factor is
    /// `s_r s_c`, doubled where an off-diagonal entry folds onto a diagonal one.
    slots: Vec<[(u32, f64); 21]>,
}

/// Lower-triangle index pairs of a 3 x 3 block.
const LOWER: [(usize, usize); 6] = [(0, 0), (1, 0), (1, 1), (2, 0), (2, 1), (2, 2)];

/// One representative per orbit of springs under the reflections of `dofs`, with the orbit size.
/// Reflected springs belong to families of equal stiffness, so each contributes the same `P^T K P`.
fn representative_springs(model: &MsmModel, dofs: &DofMap) -> Vec<(Spring, f64)> {
    let springs = model.springs();
    if dofs.mirrored_axes.is_empty() {
        return springs.into_iter().map(|s| (s, 1.0)).collect();
    }
    let group = 1usize << dofs.mirrored_axes.len();
    springs
        .into_iter()
        .filter_map(|sp| {
            let mut keys: Vec<(usize, usize)> = (0..group)
                .map(|g| {
                    let (a, b) = (dofs.reflect_node(&model.grid, sp.a, g), dofs.reflect_node(&model.grid, sp.b, g));
                    (a.min(b), a.max(b))
                })
                .collect();
            let own = keys[0];
            keys.sort_unstable();
            keys.dedup();
            (keys[0] == own).then_some((sp, keys.len() as f64))
        })
        .collect()
}

impl TangentAssembler {
    /// Builds the pattern of `P^T K P` for `model` over the reduced unknowns `dofs`. The pattern
    /// serves every model of the same grid and topology: stiffness is read at assembly.
    pub fn new(model: &MsmModel, dofs: DofMap) -> Result<Self, SparseError> {
        Self::build(model, dofs, false)
    }

    /// Like [`TangentAssembler::new`], for the rest tangent only: the pattern keeps just the
    /// entries `(r, c)` of a spring's block where its rest direction has both components non-zero
    /// (`k n n^T` at rest). Axis springs then couple one component each, so the paper's lattice
    /// splits into independent chains and its factor has almost no fill.
    pub fn at_rest(model: &MsmModel, dofs: DofMap) -> Result<Self, SparseError> {
        Self::build(model, dofs, true)
    }

    fn build(model: &MsmModel, dofs: DofMap, rest_only: bool) -> Result<Self, SparseError> {
        let springs = representative_springs(model, &dofs);
        let mut entries = Vec::new();
        let mut owners = Vec::new(); // (spring, local entry, factor)
        for (s, (sp, _)) in springs.iter().enumerate() {
            let mut local = 0;
            let o = model.families[sp.family].family.offset;
            let mut push = |r: usize, c: usize, local: usize| {
                let ((ri, rs), (ci, cs)) = (dofs.map[r], dofs.map[c]);
                let structural = !rest_only || (o[r % 3] != 0 && o[c % 3] != 0);
                if ri != u32::MAX && ci != u32::MAX && structural {
                    entries.push((ri as usize, ci as usize));
                    let twice = if r != c && ri == ci { 2.0 } else { 1.0 };
                    owners.push((s, local, rs * cs * twice));
                }
            };
            for node in [sp.a, sp.b] {
                for (r, c) in LOWER {
                    push(3 * node + r, 3 * node + c, local);
                    local += 1;
                }
            }
            for r in 0..3 {
                for c in 0..3 {
                    push(3 * sp.b + r, 3 * sp.a + c, local);
                    local += 1;
                }
            }
        }
        let nodes = model.grid.unknown_nodes(dofs.map.iter().map(|m| m.0), dofs.n);
        let (system, entry_slots) = SpdSystem::on_grid(dofs.n, &entries, &nodes)?;
        let mut slots = vec![[(u32::MAX, 0.0); 21]; springs.len()];
        for ((s, local, factor), slot) in owners.into_iter().zip(entry_slots) {
            slots[s][local] = (slot, factor);
        }
        Ok(Self { system, dofs, springs, slots })
    }

    /// Assembles `diag D + scale P^T K_t(x) P` into the system, `D` the multiplicity of each
    /// unknown (`P^T P`, so `diag` acts like `diag I` on node dofs). With `clamp_geometric`, each
    /// spring's geometric part `(1 - l0/l)` is clamped at zero so that the result is positive
    /// semi-definite (the usual choice for implicit dynamics). When `kv` is given (only without
    /// mirror symmetry), also accumulates `K_t v` (node dofs) into `kv.1`.
    pub fn assemble(
        &mut self,
        model: &MsmModel,
        x: &[Vec<f64>; 3],
        scale: f64,
        diag: f64,
        clamp_geometric: bool,
        mut kv: Option<(&[Vec<f64>; 3], &mut [Vec<f64>; 3])>,
    ) {
        debug_assert!(kv.is_none() || self.dofs.mirrored_axes.is_empty());
        self.system.clear();
        if diag != 0.0 {
            self.system.add_diagonal_scaled(diag, &self.dofs.multiplicity);
        }
        for ((sp, weight), slots) in self.springs.iter().zip(&self.slots) {
            let (a, b) = (sp.a, sp.b);
            let d = [x[0][b] - x[0][a], x[1][b] - x[1][a], x[2][b] - x[2][a]];
            let l = DVec3::from(d).length().max(f64::MIN_POSITIVE);
            let n = d.map(|v| v / l);
            let fam = &model.families[sp.family];
            let k = fam.stiffness[a];
            let mut g = 1.0 - fam.rest_length / l;
            if clamp_geometric {
                g = g.max(0.0);
            }
            let mut block = [[0.0; 3]; 3];
            for (r, row) in block.iter_mut().enumerate() {
                for (c, v) in row.iter_mut().enumerate() {
                    let id = if r == c { 1.0 } else { 0.0 };
                    *v = k * (g * (id - n[r] * n[c]) + n[r] * n[c]);
                }
            }
            let w = scale * weight;
            for (i, (r, c)) in LOWER.iter().enumerate() {
                let v = w * block[*r][*c];
                for (slot, f) in [slots[i], slots[6 + i]] {
                    if slot != u32::MAX {
                        self.system.add(slot, f * v);
                    }
                }
            }
            for r in 0..3 {
                for c in 0..3 {
                    let (slot, f) = slots[12 + 3 * r + c];
                    if slot != u32::MAX {
                        self.system.add(slot, -f * w * block[r][c]);
                    }
                }
            }
            if let Some((v, out)) = kv.as_mut() {
                let dv = [v[0][a] - v[0][b], v[1][a] - v[1][b], v[2][a] - v[2][b]];
                for r in 0..3 {
                    let s: f64 = (0..3).map(|c| block[r][c] * dv[c]).sum();
                    out[r][a] += s;
                    out[r][b] -= s;
                }
            }
        }
    }
}

mod pair_loop;

use pair_loop::{pair_loop, pair_loop_scalar};

#[cfg(test)]
mod tests;
