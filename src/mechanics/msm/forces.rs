//! Spring forces and tangent stiffness of the mass-spring model.
//!
//! A spring between nodes `i` and `j` with stiffness `k` and rest length `l0` pulls `i` towards
//! `j` with `f_i = k (l - l0) d`, `d = (x_j - x_i) / l`, and `f_j = -f_i`. Its tangent stiffness
//! block is `K_s = k [ (1 - l0/l) (I - d d^T) + d d^T ]`.
//!
//! The force loop runs family by family over contiguous node ranges (structure of arrays), which
//! the compiler vectorises; it allocates nothing.

use super::model::{MsmModel, Spring};
use super::reduction::DofMap;
use crate::mechanics::sparse::{SparseError, SpdSystem};
use glam::DVec3;

/// Preallocated per-family pair forces for the force kernels.
///
/// For a family with offset `s`, `t[c][s + p]` holds component `c` of the force on the first node
/// of pair `p` (the pair `(p, p + s)`); the `s` leading and trailing entries stay zero, so that the
/// net force of the family on node `q` is `t[s + q] - t[q]` for every node without a branch.
#[derive(Debug, Clone)]
pub struct ForceScratch {
    t: Vec<[Vec<f64>; 3]>,
}

impl ForceScratch {
    /// Buffers for every family of `model`.
    pub fn new(model: &MsmModel) -> Self {
        let nn = model.grid.num_nodes();
        let t = model.families.iter().map(|f| std::array::from_fn(|_| vec![0.0; nn + f.offset])).collect();
        Self { t }
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

/// Computes every spring's force at positions `x` into `scratch`.
#[inline(always)]
pub(crate) fn pair_forces(model: &MsmModel, x: &[Vec<f64>; 3], scratch: &mut ForceScratch) {
    for (fam, t) in model.families.iter().zip(scratch.t.iter_mut()) {
        let len = fam.stiffness.len();
        let (lo, s, l0) = (fam.lo, fam.offset, fam.rest_length);
        debug_assert_eq!(lo, 0);
        let k = &fam.stiffness[..len];
        let (xa, xb) = (&x[0][lo..lo + len], &x[0][lo + s..lo + s + len]);
        let (ya, yb) = (&x[1][lo..lo + len], &x[1][lo + s..lo + s + len]);
        let (za, zb) = (&x[2][lo..lo + len], &x[2][lo + s..lo + s + len]);
        let [tx, ty, tz] = t;
        let (tx, ty, tz) = (&mut tx[s..s + len], &mut ty[s..s + len], &mut tz[s..s + len]);
        for p in 0..len {
            let dx = xb[p] - xa[p];
            let dy = yb[p] - ya[p];
            let dz = zb[p] - za[p];
            let l = (dx * dx + dy * dy + dz * dz).sqrt().max(f64::MIN_POSITIVE);
            let c = k[p] - k[p] * l0 / l;
            tx[p] = c * dx;
            ty[p] = c * dy;
            tz[p] = c * dz;
        }
    }
}

/// Component `c` of the net spring force: `f[q] (=|+=) sum over families of t[s + q] - t[q]`.
#[inline(always)]
pub(crate) fn gather_forces(model: &MsmModel, scratch: &ForceScratch, c: usize, f: &mut [f64], assign: bool) {
    let nn = f.len();
    if assign {
        f.fill(0.0);
    }
    for (fam, t) in model.families.iter().zip(&scratch.t) {
        let s = fam.offset;
        let (ahead, behind) = (&t[c][s..s + nn], &t[c][..nn]);
        for ((fq, a), b) in f.iter_mut().zip(ahead).zip(behind) {
            *fq += a - b;
        }
    }
}

#[inline(always)]
fn add_spring_forces_generic(model: &MsmModel, x: &[Vec<f64>; 3], f: &mut [Vec<f64>; 3], scratch: &mut ForceScratch) {
    pair_forces(model, x, scratch);
    for (c, fc) in f.iter_mut().enumerate() {
        gather_forces(model, scratch, c, fc, false);
    }
}

/// Adds every spring force at positions `x` to `f` (both structure of arrays, one entry per node).
pub fn add_spring_forces(model: &MsmModel, x: &[Vec<f64>; 3], f: &mut [Vec<f64>; 3], scratch: &mut ForceScratch) {
    dispatch_avx2!(
        add_spring_forces_generic,
        add_spring_forces_avx2,
        (model: &MsmModel, x: &[Vec<f64>; 3], f: &mut [Vec<f64>; 3], scratch: &mut ForceScratch)
    );
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
        let (system, entry_slots) = SpdSystem::new(dofs.n, &entries)?;
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
