//! The one contact of the project: a rigid frictionless sphere against the nodes of a surface,
//! linearised (each node moves onto the sphere along the sphere's normal at rest) and solved by
//! an active set. Whatever knows the body's compliance between the candidate nodes serves it
//! through [`Compliance`]: the model's factorised stiffness (the touch benchmark's probe), the
//! continuum reference's batched solves (`validate::continuum`, static and the tap), the
//! material's surface compliance (the viewer's probe).
//!
//! The solve allocates nothing once its [`ContactScratch`] has room for the contact (the viewer's
//! probe takes its room once): the normal compliance of the active nodes is factorised in place
//! by faer's dense Cholesky.

use faer::dyn_stack::{MemBuffer, MemStack};
use faer::linalg::cholesky::llt;
use faer::{Conj, MatMut, MatRef, Par};
use glam::DVec3;

/// Active-set iterations of one solve; a contact that has not settled then is an error.
pub const MAX_ITERATIONS: usize = 60;

/// Where the sphere (`centre`, `radius`) meets a node at `x`: the outward normal from the centre
/// (`fallback` where `x` is the centre) and the node's depth inside the sphere (`radius -
/// distance`; negative outside). The one rule of the sphere's gap.
pub fn sphere_gap(centre: [f64; 3], radius: f64, x: [f64; 3], fallback: [f64; 3]) -> ([f64; 3], f64) {
    let d = DVec3::from(x) - DVec3::from(centre);
    let dist = d.length();
    let n = if dist > 1e-12 { (d / dist).to_array() } else { fallback };
    (n, radius - dist)
}

/// What the active set needs of the body.
pub trait Compliance {
    /// Makes the responses to forces at the candidates `slots` available (where they are solved
    /// on demand, in one batch).
    fn prepare(&mut self, slots: &[usize]) -> Result<(), ContactError> {
        let _ = slots;
        Ok(())
    }

    /// `n_i . W(i <- j) n_j`, metres per newton: the displacement of candidate `i` along `n_i`
    /// under a unit force at candidate `j` along `n_j` (`j` prepared).
    fn normal(&self, i: usize, n_i: [f64; 3], j: usize, n_j: [f64; 3]) -> f64;
}

/// Errors of a contact solve.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
pub enum ContactError {
    /// The normal compliance of the active nodes is not positive definite.
    #[error("the contact compliance is not positive definite")]
    NotPositiveDefinite,
    /// The active set did not settle.
    #[error("the contact did not settle in {0} active-set iterations")]
    NotSettled(usize),
    /// The body could not answer.
    #[error("{0}")]
    Body(String),
}

/// The contact's memory: the candidates the caller sets, the active set (a warm start in, the
/// contact out) and their forces.
pub struct ContactScratch {
    /// Per candidate: the outward normal from the sphere's centre and the gap to close along it,
    /// metres (its depth inside the sphere less the normal displacement it already has).
    pub candidates: Vec<([f64; 3], f64)>,
    /// Candidates in contact, increasing: a warm start before a solve, the contact after it.
    pub active: Vec<usize>,
    /// Their normal forces, newtons (after a solve).
    pub lambda: Vec<f64>,
    next: Vec<usize>,
    /// The factorised normal compliance of the active set, column-major.
    matrix: Vec<f64>,
    /// After a settled solve: each candidate out of contact's normal displacement under a unit
    /// force at each contact (a row per such candidate, in the candidates' order), so that
    /// [`resolve`] checks the contact without the body.
    outside: Vec<f64>,
    /// Whether `matrix` and `outside` belong to the active set now held (a settled solve).
    settled: bool,
    /// [`resolve`]'s memory: the factorised compliance's inverse times the contacts' normals
    /// (three columns).
    along: Vec<f64>,
    stack: MemBuffer,
    room: usize,
}

impl std::fmt::Debug for ContactScratch {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.debug_struct("ContactScratch")
            .field("candidates", &self.candidates.len())
            .field("active", &self.active)
            .finish()
    }
}

impl ContactScratch {
    /// Room for `n` candidates in contact (more grows it, allocating).
    pub fn with_room(n: usize) -> Self {
        let mut s = Self {
            candidates: Vec::with_capacity(n),
            active: Vec::with_capacity(n),
            lambda: Vec::with_capacity(n),
            next: Vec::with_capacity(n),
            matrix: Vec::new(),
            outside: Vec::new(),
            settled: false,
            along: Vec::new(),
            stack: MemBuffer::new(faer::dyn_stack::StackReq::EMPTY),
            room: 0,
        };
        s.grow(n);
        s
    }

    fn grow(&mut self, n: usize) {
        if n <= self.room {
            return;
        }
        let factor = llt::factor::cholesky_in_place_scratch::<f64>(n, Par::Seq, Default::default());
        let solve = llt::solve::solve_in_place_scratch::<f64>(n, 3, Par::Seq);
        self.stack = MemBuffer::new(factor.or(solve));
        self.matrix.reserve(n * n);
        self.outside.reserve(n * n);
        self.along.reserve(3 * n);
        self.room = n;
    }

    /// No candidates, no contact, nothing to [`resolve`] on.
    pub fn clear(&mut self) {
        self.candidates.clear();
        self.active.clear();
        self.lambda.clear();
        self.settled = false;
    }

    /// The contact force on the sphere, newtons (after a solve): minus the normal forces along
    /// the candidates' normals.
    pub fn force(&self) -> [f64; 3] {
        let mut f = DVec3::ZERO;
        for (&q, &l) in self.active.iter().zip(&self.lambda) {
            f -= DVec3::from(self.candidates[q].0) * l;
        }
        f.to_array()
    }

    /// Solves `S x = b` in place with the active set's factorised normal compliance `S` (after a
    /// solve with contact; `b` as long as the active set).
    pub fn solve_factored(&mut self, b: &mut [f64]) {
        let m = self.active.len();
        if m == 0 || b.len() != m {
            return;
        }
        llt::solve::solve_in_place_with_conj(
            MatRef::from_column_major_slice(&self.matrix[..m * m], m, m),
            Conj::No,
            MatMut::from_column_major_slice_mut(b, m, 1),
            Par::Seq,
            MemStack::new(&mut self.stack),
        );
    }
}

impl Default for ContactScratch {
    fn default() -> Self {
        Self::with_room(0)
    }
}

/// Solves the contact of the candidates in `s` against `body`: every candidate in contact is put
/// on the sphere by normal forces, none pulls, and no other ends inside by more than `tol`
/// (metres). The first active set is `s.active` (a warm start: the last contact, where the sphere
/// moved a little, settles in one or two iterations), or where it is empty every candidate of
/// positive gap (which overshoots the contact: the surface sinks around the sphere).
pub fn solve<C: Compliance + ?Sized>(body: &mut C, s: &mut ContactScratch, tol: f64) -> Result<(), ContactError> {
    s.settled = false;
    let n = s.candidates.len();
    s.active.retain(|&q| q < n);
    if s.active.is_empty() {
        s.active.extend((0..n).filter(|&q| s.candidates[q].1 > 0.0));
    }
    s.active.sort_unstable();
    s.active.dedup();
    for _ in 0..MAX_ITERATIONS {
        s.lambda.clear();
        s.outside.clear();
        if s.active.is_empty() {
            s.settled = true;
            return Ok(());
        }
        body.prepare(&s.active)?;
        factor_active(body, s)?;
        // Keep pushing contacts; add candidates that end inside the sphere.
        s.next.clear();
        for (&q, &l) in s.active.iter().zip(&s.lambda) {
            if l > 0.0 {
                s.next.push(q);
            }
        }
        for q in 0..n {
            if s.active.binary_search(&q).is_ok() {
                continue;
            }
            let (nq, gap) = s.candidates[q];
            let mut moved = 0.0;
            for (&j, &l) in s.active.iter().zip(&s.lambda) {
                let w = body.normal(q, nq, j, s.candidates[j].0);
                s.outside.push(w);
                moved += l * w;
            }
            if moved < gap - tol {
                s.next.push(q);
            }
        }
        s.next.sort_unstable();
        if s.next == s.active {
            s.settled = true;
            return Ok(());
        }
        std::mem::swap(&mut s.next, &mut s.active);
    }
    // The forces solved last belong to the set before the swap: none of them is used.
    s.active.clear();
    s.lambda.clear();
    Err(ContactError::NotSettled(MAX_ITERATIONS))
}

/// Solves the contact again for new gaps (written into `s.candidates`: the same candidates in
/// the same order, their normals and gaps now) on the active set and the compliance of the last
/// settled [`solve`], calling no body: `true` where that active set still holds (every force
/// pushes and no other candidate ends inside by more than `tol`, metres), the forces in
/// `s.lambda`; `false` where it does not (the forces are then not valid: a [`solve`] is owed,
/// warm-started from `s.active`, the set this one points to).
///
/// The compliance is the one the last solve factorised less `n_i . change n_j` (`change`, metres
/// per newton, a 3 x 3 part common to every pair of candidates, such as the material's slow modes
/// read over the patch: exact, by the Woodbury identity, with three more solves on the kept
/// factorisation), at the candidates' normals now in that part and at the last solve's elsewhere:
/// a sphere that moved a little, as between two steps of a moving tool, is answered in
/// microseconds. Allocates nothing.
pub fn resolve(s: &mut ContactScratch, tol: f64, change: &[[f64; 3]; 3]) -> bool {
    if !s.settled {
        return false;
    }
    let m = s.active.len();
    s.lambda.clear();
    if m == 0 {
        // The last solve's start: every candidate of positive gap.
        return s.candidates.iter().all(|&(_, gap)| gap <= 0.0);
    }
    s.lambda.extend(s.active.iter().map(|&q| s.candidates[q].1));
    llt::solve::solve_in_place_with_conj(
        MatRef::from_column_major_slice(&s.matrix[..m * m], m, m),
        Conj::No,
        MatMut::from_column_major_slice_mut(&mut s.lambda[..m], m, 1),
        Par::Seq,
        MemStack::new(&mut s.stack),
    );
    let dot = |a: [f64; 3], d: &[[f64; 3]; 3], b: [f64; 3]| -> f64 {
        (0..3).map(|i| a[i] * (d[i][0] * b[0] + d[i][1] * b[1] + d[i][2] * b[2])).sum()
    };
    let changed = change.iter().flatten().any(|&v| v != 0.0);
    if changed && !woodbury(s, change) {
        s.lambda.clear();
        s.settled = false;
        return false;
    }
    // The contact's net normal push, for the change's part of the check.
    let mut net = [0.0; 3];
    if changed {
        for (a, &q) in s.active.iter().enumerate() {
            let n = s.candidates[q].0;
            for c in 0..3 {
                net[c] += n[c] * s.lambda[a];
            }
        }
    }
    // The next active set as the solve would take it: the contacts that push, and every other
    // candidate that ends inside.
    s.next.clear();
    let mut rows = s.outside.chunks_exact(m);
    let mut a = 0;
    for q in 0..s.candidates.len() {
        if a < m && s.active[a] == q {
            if s.lambda[a] > 0.0 {
                s.next.push(q);
            }
            a += 1;
            continue;
        }
        let row = rows.next().unwrap_or(&[]);
        let mut moved: f64 = row.iter().zip(&s.lambda).map(|(w, l)| w * l).sum();
        if changed {
            moved -= dot(s.candidates[q].0, change, net);
        }
        if moved < s.candidates[q].1 - tol {
            s.next.push(q);
        }
    }
    let holds = s.next == s.active;
    if !holds {
        // Not valid: the solve owed starts from the set this one points to.
        s.lambda.clear();
        std::mem::swap(&mut s.next, &mut s.active);
        s.settled = false;
    }
    holds
}

/// The forces `s.lambda` (solved on the kept factorisation `S`) turned into those of `S - U D
/// U^T`, `D` the `change` and `U` the contacts' normals as rows, by the Woodbury identity: `(S -
/// U D U^T)^-1 g = x + Y (I - D U^T Y)^-1 D U^T x` with `x = S^-1 g` and `Y = S^-1 U` (three more
/// solves). `false` where `I - D U^T Y` is singular.
fn woodbury(s: &mut ContactScratch, change: &[[f64; 3]; 3]) -> bool {
    let m = s.active.len();
    s.along.clear();
    for c in 0..3 {
        s.along.extend(s.active.iter().map(|&q| s.candidates[q].0[c]));
    }
    llt::solve::solve_in_place_with_conj(
        MatRef::from_column_major_slice(&s.matrix[..m * m], m, m),
        Conj::No,
        MatMut::from_column_major_slice_mut(&mut s.along[..3 * m], m, 3),
        Par::Seq,
        MemStack::new(&mut s.stack),
    );
    let mut ut_y = [[0.0; 3]; 3];
    let mut ut_x = [0.0; 3];
    for (a, &q) in s.active.iter().enumerate() {
        let n = s.candidates[q].0;
        for i in 0..3 {
            ut_x[i] += n[i] * s.lambda[a];
            for (j, u) in ut_y[i].iter_mut().enumerate() {
                *u += n[i] * s.along[j * m + a];
            }
        }
    }
    // I - D U^T Y and D U^T x.
    let mut k = [[0.0; 3]; 3];
    let mut rhs = [0.0; 3];
    for i in 0..3 {
        for j in 0..3 {
            k[i][j] = f64::from(u8::from(i == j)) - (0..3).map(|l| change[i][l] * ut_y[l][j]).sum::<f64>();
        }
        rhs[i] = (0..3).map(|l| change[i][l] * ut_x[l]).sum();
    }
    let Some(w) = solve3(k, rhs) else { return false };
    for a in 0..m {
        s.lambda[a] += (0..3).map(|j| s.along[j * m + a] * w[j]).sum::<f64>();
    }
    true
}

/// The solution of the 3 x 3 system `k x = b` (Cramer's rule), or `None` where `k` is singular.
fn solve3(k: [[f64; 3]; 3], b: [f64; 3]) -> Option<[f64; 3]> {
    let det3 = |m: [[f64; 3]; 3]| {
        m[0][0] * (m[1][1] * m[2][2] - m[1][2] * m[2][1]) - m[0][1] * (m[1][0] * m[2][2] - m[1][2] * m[2][0])
            + m[0][2] * (m[1][0] * m[2][1] - m[1][1] * m[2][0])
    };
    let d = det3(k);
    if !(d.is_finite() && d.abs() > 1e-12) {
        return None;
    }
    Some(std::array::from_fn(|c| {
        let mut m = k;
        for r in 0..3 {
            m[r][c] = b[r];
        }
        det3(m) / d
    }))
}

/// Factorises the active set's normal compliance (symmetrised: columns solved in f32, or
/// separately, are symmetric only to their rounding) and solves its forces into `s.lambda`.
fn factor_active<C: Compliance + ?Sized>(body: &C, s: &mut ContactScratch) -> Result<(), ContactError> {
    let m = s.active.len();
    s.grow(m);
    let ContactScratch { candidates, active, lambda, matrix, stack, .. } = s;
    matrix.clear();
    matrix.resize(m * m, 0.0);
    for (j, &wj) in active.iter().enumerate() {
        let nj = candidates[wj].0;
        for (i, &wi) in active.iter().enumerate() {
            matrix[i + m * j] = body.normal(wi, candidates[wi].0, wj, nj);
        }
        lambda.push(candidates[wj].1);
    }
    for j in 0..m {
        for i in 0..j {
            let v = 0.5 * (matrix[i + m * j] + matrix[j + m * i]);
            matrix[i + m * j] = v;
            matrix[j + m * i] = v;
        }
    }
    let mut a = MatMut::from_column_major_slice_mut(&mut matrix[..m * m], m, m);
    llt::factor::cholesky_in_place(a.as_mut(), Default::default(), Par::Seq, MemStack::new(stack), Default::default())
        .map_err(|_| ContactError::NotPositiveDefinite)?;
    llt::solve::solve_in_place_with_conj(
        a.as_ref(),
        Conj::No,
        MatMut::from_column_major_slice_mut(&mut lambda[..m], m, 1),
        Par::Seq,
        MemStack::new(stack),
    );
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Independent springs on a line of candidates (a diagonal compliance) with a coupling.
    struct Chain(Vec<f64>, f64);

    impl Compliance for Chain {
        fn normal(&self, i: usize, _: [f64; 3], j: usize, _: [f64; 3]) -> f64 {
            if i == j { self.0[i] } else { self.1 / (1.0 + (i as f64 - j as f64).abs()) }
        }
    }

    /// Candidates pressed with gaps `g`: the solve puts the contacts on the sphere, no force
    /// pulls, no other candidate ends inside, from any warm start.
    #[test]
    fn no_contact_pulls_and_no_candidate_ends_inside() {
        let gaps = [1e-3, 4e-4, -2e-4, 2e-4, -1e-3, 8e-4];
        let mut body = Chain(vec![1e-4, 2e-4, 1e-4, 3e-4, 1e-4, 1e-4], 5e-5);
        for warm in [vec![], vec![2, 4], vec![0, 1, 2, 3, 4, 5]] {
            let mut s = ContactScratch::with_room(2);
            s.candidates.extend(gaps.iter().map(|&g| ([0.0, 0.0, 1.0], g)));
            s.active = warm;
            solve(&mut body, &mut s, 1e-15).expect("settles");
            assert!(s.lambda.iter().all(|&l| l > 0.0), "{:?}", s.lambda);
            for q in 0..gaps.len() {
                let moved: f64 =
                    s.active.iter().zip(&s.lambda).map(|(&j, l)| l * body.normal(q, [0.0; 3], j, [0.0; 3])).sum();
                if s.active.contains(&q) {
                    assert!((moved - gaps[q]).abs() < 1e-15, "{q}: {moved} against {}", gaps[q]);
                } else {
                    assert!(moved >= gaps[q] - 1e-15, "{q} ends inside");
                }
            }
            assert!(s.force()[2] < 0.0);
        }
    }

    /// Solved again for gaps that moved a little, on the last solve's active set and compliance:
    /// the same forces as a full solve where the contact holds, and a solve owed where a
    /// candidate enters or leaves.
    #[test]
    fn a_resolve_is_the_solve_while_the_contact_holds_and_owes_one_when_it_changes() {
        let gaps = [1e-3, 4e-4, -2e-4, 2e-4, -1e-3, 8e-4];
        let mut body = Chain(vec![1e-4, 2e-4, 1e-4, 3e-4, 1e-4, 1e-4], 5e-5);
        let mut s = ContactScratch::with_room(6);
        s.candidates.extend(gaps.iter().map(|&g| ([0.0, 0.0, 1.0], g)));
        assert!(!resolve(&mut s, 1e-15, &[[0.0; 3]; 3]), "nothing solved yet");
        solve(&mut body, &mut s, 1e-15).expect("settles");
        let active = s.active.clone();
        // Every gap 1 % deeper: the same contact, forces 1 % larger.
        for c in &mut s.candidates {
            c.1 *= 1.01;
        }
        assert!(resolve(&mut s, 1e-15, &[[0.0; 3]; 3]));
        let again = s.lambda.clone();
        let mut full = ContactScratch::with_room(6);
        full.candidates.extend(gaps.iter().map(|&g| ([0.0, 0.0, 1.0], 1.01 * g)));
        solve(&mut body, &mut full, 1e-15).expect("settles");
        assert_eq!(full.active, active);
        for (a, b) in again.iter().zip(&full.lambda) {
            assert!((a - b).abs() < 1e-12 * b.abs(), "{a} {b}");
        }
        // A candidate out of contact pushed deep: the contact changes, a solve is owed.
        let outside = (0..6).find(|q| !active.contains(q)).expect("one out of contact");
        s.candidates[outside].1 = 5e-3;
        assert!(!resolve(&mut s, 1e-15, &[[0.0; 3]; 3]));
        s.clear();
        assert!(!resolve(&mut s, 1e-15, &[[0.0; 3]; 3]), "cleared");
    }

    /// A chain less a common 3 x 3 part read along the candidates' normals (as the material's
    /// slow modes are folded into the surface's contact).
    struct Coupled(Chain, [[f64; 3]; 3]);

    impl Compliance for Coupled {
        fn normal(&self, i: usize, n_i: [f64; 3], j: usize, n_j: [f64; 3]) -> f64 {
            let g = &self.1;
            self.0.normal(i, n_i, j, n_j)
                - (0..3).map(|a| n_i[a] * (g[a][0] * n_j[0] + g[a][1] * n_j[1] + g[a][2] * n_j[2])).sum::<f64>()
        }
    }

    /// The common part changed since the solve: the resolve's forces are the full solve's with
    /// the new part (Woodbury), and its check of the candidates out of contact too.
    #[test]
    fn a_resolve_takes_a_changed_common_part_exactly() {
        let gaps = [1e-3, 4e-4, -2e-4, 2e-4, -1e-3, 8e-4];
        let normals: Vec<[f64; 3]> = (0..6)
            .map(|q| {
                let t = 0.2 * (q as f64 - 2.5);
                [t.sin(), 0.3 * t, -t.cos()]
            })
            .map(|n: [f64; 3]| {
                let l = (n[0] * n[0] + n[1] * n[1] + n[2] * n[2]).sqrt();
                n.map(|c| c / l)
            })
            .collect();
        let chain = || Chain(vec![1e-4, 2e-4, 1e-4, 3e-4, 1e-4, 1e-4], 5e-5);
        let (g1, g2) = ([[2e-5, 1e-6, 0.0], [1e-6, 1e-5, 0.0], [0.0, 0.0, 3e-5]], [
            [2.2e-5, 1.5e-6, 1e-7],
            [1.5e-6, 1.1e-5, 0.0],
            [1e-7, 0.0, 2.7e-5],
        ]);
        let setup = |g| {
            let mut s = ContactScratch::with_room(6);
            s.candidates.extend(gaps.iter().zip(&normals).map(|(&g, &n)| (n, g)));
            (Coupled(chain(), g), s)
        };
        let (mut body, mut s) = setup(g1);
        solve(&mut body, &mut s, 1e-15).expect("settles");
        let change: [[f64; 3]; 3] = std::array::from_fn(|i| std::array::from_fn(|j| g2[i][j] - g1[i][j]));
        assert!(resolve(&mut s, 1e-15, &change), "the contact holds");
        let (mut full_body, mut full) = setup(g2);
        solve(&mut full_body, &mut full, 1e-15).expect("settles");
        assert_eq!(full.active, s.active);
        for (a, b) in s.lambda.iter().zip(&full.lambda) {
            assert!((a - b).abs() < 1e-9 * b.abs(), "{a} {b}");
        }
    }

    #[test]
    fn a_compliance_that_is_not_positive_definite_is_an_error() {
        let mut body = Chain(vec![-1e-4; 2], 0.0);
        let mut s = ContactScratch::default();
        s.candidates.extend([([0.0, 0.0, 1.0], 1e-3), ([0.0, 0.0, 1.0], 1e-3)]);
        assert_eq!(solve(&mut body, &mut s, 0.0), Err(ContactError::NotPositiveDefinite));
    }

    proptest::proptest! {
        /// For any positive definite compliance (diagonally dominant: each node's own compliance
        /// above the sum of its couplings) and any gaps, from any warm start, the solve puts
        /// every contact on the sphere, no contact pulls and no other candidate ends inside.
        #[test]
        fn a_contact_never_pulls(
            own in proptest::collection::vec(1e-5f64..1e-3, 1..12),
            coupling in 0.0f64..0.9,
            gaps in proptest::collection::vec(-1e-3f64..1e-3, 12),
            warm in proptest::collection::vec(proptest::bool::ANY, 12),
        ) {
            let n = own.len();
            let least = own.iter().copied().fold(f64::INFINITY, f64::min);
            // Row sums of the couplings c / (1 + |i - j|) stay below 2 c (1 + ln n): under `least`.
            let c = coupling * least / (2.0 * (1.0 + (n as f64).ln()));
            let mut body = Chain(own, c);
            let mut s = ContactScratch::with_room(n);
            s.candidates.extend(gaps[..n].iter().map(|&g| ([0.0, 0.0, 1.0], g)));
            s.active = (0..n).filter(|&q| warm[q]).collect();
            solve(&mut body, &mut s, 1e-15).expect("settles");
            proptest::prop_assert!(s.lambda.iter().all(|&l| l >= 0.0), "{:?}", s.lambda);
            for q in 0..n {
                let moved: f64 =
                    s.active.iter().zip(&s.lambda).map(|(&j, l)| l * body.normal(q, [0.0; 3], j, [0.0; 3])).sum();
                if s.active.contains(&q) {
                    proptest::prop_assert!((moved - gaps[q]).abs() < 1e-12, "{}: {} against {}", q, moved, gaps[q]);
                } else {
                    proptest::prop_assert!(moved >= gaps[q] - 1e-12, "{} ends inside", q);
                }
            }
            proptest::prop_assert!(s.force()[2] <= 0.0, "the sphere is pushed out, never pulled in");
        }
    }
}
