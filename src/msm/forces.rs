//! Spring forces and tangent stiffness of the mass-spring model.
//!
//! A spring between nodes `i` and `j` with stiffness `k` and rest length `l0` pulls `i` towards
//! `j` with `f_i = k (l - l0) d`, `d = (x_j - x_i) / l`, and `f_j = -f_i`. Its tangent stiffness
//! block is `K_s = k [ (1 - l0/l) (I - d d^T) + d d^T ]`.
//!
//! The force loop runs family by family over contiguous node ranges (structure of arrays), which
//! the compiler vectorises; it allocates nothing.

use super::model::MsmModel;
use crate::sparse::{SparseError, SpdSystem};

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
        let t = model
            .families
            .iter()
            .map(|f| std::array::from_fn(|_| vec![0.0; nn + f.offset]))
            .collect();
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

/// Tangent-stiffness assembly of a model into a sparse SPD system over the free degrees of freedom.
#[derive(Debug)]
pub struct TangentAssembler {
    /// The sparse system (free dofs only).
    pub system: SpdSystem,
    /// Node dof -> reduced index, `u32::MAX` where fixed.
    pub reduced: Vec<u32>,
    /// For each spring `(a, b)`: slots of the lower (a,a) block (6), lower (b,b) block (6) and the
    /// full (b,a) block (9), `u32::MAX` where a dof is fixed.
    slots: Vec<[u32; 21]>,
    springs: Vec<super::model::Spring>,
}

/// Lower-triangle index pairs of a 3 x 3 block.
const LOWER: [(usize, usize); 6] = [(0, 0), (1, 0), (1, 1), (2, 0), (2, 1), (2, 2)];

impl TangentAssembler {
    /// Builds the pattern for `model` with the nodes marked in `fixed_node` held.
    pub fn new(model: &MsmModel, fixed_node: &[bool]) -> Result<Self, SparseError> {
        let mut reduced = vec![u32::MAX; 3 * fixed_node.len()];
        let mut next = 0u32;
        for (p, &fixed) in fixed_node.iter().enumerate() {
            if !fixed {
                for c in 0..3 {
                    reduced[3 * p + c] = next;
                    next += 1;
                }
            }
        }
        let springs = model.springs();
        let mut entries = Vec::new();
        let mut owners = Vec::new(); // (spring, local slot) for each entry
        for (s, sp) in springs.iter().enumerate() {
            let mut local = 0;
            let mut push = |r: u32, c: u32, local: usize| {
                if r != u32::MAX && c != u32::MAX {
                    entries.push((r as usize, c as usize));
                    owners.push((s, local));
                }
            };
            for node in [sp.a, sp.b] {
                for (r, c) in LOWER {
                    push(reduced[3 * node + r], reduced[3 * node + c], local);
                    local += 1;
                }
            }
            for r in 0..3 {
                for c in 0..3 {
                    push(reduced[3 * sp.b + r], reduced[3 * sp.a + c], local);
                    local += 1;
                }
            }
        }
        let (system, entry_slots) = SpdSystem::new(next as usize, &entries)?;
        let mut slots = vec![[u32::MAX; 21]; springs.len()];
        for ((s, local), slot) in owners.into_iter().zip(entry_slots) {
            slots[s][local] = slot;
        }
        Ok(Self { system, reduced, slots, springs })
    }

    /// Assembles `diag I + scale K_t(x)` into the system (`K_t` the tangent stiffness). With
    /// `clamp_geometric`, the geometric part `(1 - l0/l)` is clamped at zero so that the result is
    /// positive semi-definite (the usual choice for implicit dynamics). When `kv` is given, also
    /// accumulates `K_t v` (full dofs) into `kv.1`.
    pub fn assemble(
        &mut self,
        x: &[Vec<f64>; 3],
        scale: f64,
        diag: f64,
        clamp_geometric: bool,
        mut kv: Option<(&[Vec<f64>; 3], &mut [Vec<f64>; 3])>,
    ) {
        self.system.clear();
        self.system.add_diagonal(diag);
        for (sp, slots) in self.springs.iter().zip(&self.slots) {
            let (a, b) = (sp.a, sp.b);
            let d = [x[0][b] - x[0][a], x[1][b] - x[1][a], x[2][b] - x[2][a]];
            let l = (d[0] * d[0] + d[1] * d[1] + d[2] * d[2]).sqrt().max(f64::MIN_POSITIVE);
            let n = d.map(|v| v / l);
            let mut g = 1.0 - sp.rest / l;
            if clamp_geometric {
                g = g.max(0.0);
            }
            let mut block = [[0.0; 3]; 3];
            for (r, row) in block.iter_mut().enumerate() {
                for (c, v) in row.iter_mut().enumerate() {
                    let id = if r == c { 1.0 } else { 0.0 };
                    *v = sp.k * (g * (id - n[r] * n[c]) + n[r] * n[c]);
                }
            }
            for (i, (r, c)) in LOWER.iter().enumerate() {
                let v = scale * block[*r][*c];
                if slots[i] != u32::MAX {
                    self.system.add(slots[i], v);
                }
                if slots[6 + i] != u32::MAX {
                    self.system.add(slots[6 + i], v);
                }
            }
            for r in 0..3 {
                for c in 0..3 {
                    let slot = slots[12 + 3 * r + c];
                    if slot != u32::MAX {
                        self.system.add(slot, -scale * block[r][c]);
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
