//! Computing a material's surface compliance: per family of faces (the top face, the two faces
//! normal to x, the two normal to y) one FEM mesh factorised once and its columns solved in
//! batches. The families are independent, so they are computed on up to three threads, and each
//! is handed over as it ends (so that the work done survives an interruption: the cache keeps
//! each family in a part file, [`super::file::part_to_bytes`], and a later start takes them back).

use std::sync::atomic::{AtomicBool, AtomicUsize, Ordering};
use std::sync::{Mutex, mpsc};
use std::time::Duration;

use super::lattice::{self, Lattice};
use super::{BATCH_NODES, ComplianceError, SurfaceCompliance, family_mesh, mesh_point};
use crate::mechanics::fem::graded::GradedFem;
use crate::mechanics::material::Material;

/// A family's factorisation counted as this many columns' solves, so that the progress follows
/// the time (measured: about 6 s for a factorisation against 36 ms for a column's solves, one
/// core of the build machine).
const FACTOR_COLUMNS: usize = 170;

/// How often the progress is told while the families are computed.
const PROGRESS_EVERY: Duration = Duration::from_millis(100);

impl SurfaceCompliance {
    /// Computes the compliance of `material` with `divisions` divisions per axis (even) on one
    /// thread; `progress(fraction)` is called about ten times a second and stops the work when it
    /// returns `false`.
    pub fn compute(
        material: &Material,
        divisions: usize,
        progress: &mut dyn FnMut(f64) -> bool,
    ) -> Result<Self, ComplianceError> {
        Self::compute_kept(material, divisions, 1, &mut |_, _| None, &mut |_, _| {}, progress)
    }

    /// [`SurfaceCompliance::compute`] on `threads` threads (a family each, at most three), taking
    /// each family that `kept(family, values)` holds already (the columns of an earlier,
    /// interrupted computation) and handing each family computed to `done(family, columns)` as it
    /// ends. `progress` counts the kept families as done and is called on the calling thread.
    pub fn compute_kept(
        material: &Material,
        divisions: usize,
        threads: usize,
        kept: &mut dyn FnMut(usize, usize) -> Option<Vec<f32>>,
        done: &mut dyn FnMut(usize, &[f32]),
        progress: &mut dyn FnMut(f64) -> bool,
    ) -> Result<Self, ComplianceError> {
        material.require_homogeneous("the surface compliance")?;
        let c = &material.stiffness;
        let coupled = (0..3).any(|i| (3..6).any(|j| c[(i, j)] != 0.0))
            || c[(3, 4)] != 0.0
            || c[(3, 5)] != 0.0
            || c[(4, 5)] != 0.0;
        if coupled || !divisions.is_multiple_of(2) || divisions < 2 {
            return Err(ComplianceError::NotOrthotropic);
        }
        let lattice = Lattice::new(divisions);
        let units = |f: &lattice::Family| FACTOR_COLUMNS + f.columns();
        let total: usize = lattice.families.iter().map(units).sum();
        let mut columns = vec![0.0f32; lattice.values];
        let counted = AtomicUsize::new(0);
        let mut todo = Vec::new();
        for (i, f) in lattice.families.iter().enumerate() {
            let span = f.offset..f.offset + family_len(f);
            match kept(i, span.len()) {
                Some(values) if values.len() == span.len() => {
                    columns[span].copy_from_slice(&values);
                    counted.fetch_add(units(f), Ordering::Relaxed);
                }
                _ => todo.push(i),
            }
        }
        if !progress(counted.load(Ordering::Relaxed) as f64 / total as f64) {
            return Err(ComplianceError::Cancelled);
        }
        let cancel = AtomicBool::new(false);
        let queue = Mutex::new(todo.clone().into_iter());
        let mut failed = None;
        std::thread::scope(|scope| {
            let (tx, rx) = mpsc::channel();
            for _ in 0..threads.clamp(1, todo.len().max(1)) {
                let (tx, queue, lattice, counted, cancel) = (tx.clone(), &queue, &lattice, &counted, &cancel);
                scope.spawn(move || {
                    while let Some(i) = queue.lock().map_or(None, |mut q| q.next()) {
                        let r = family_columns(lattice, i, material, divisions, counted, cancel);
                        let stop = r.is_err();
                        if tx.send((i, r)).is_err() || stop {
                            break;
                        }
                    }
                });
            }
            drop(tx);
            let mut left = todo.len();
            while left > 0 {
                match rx.recv_timeout(PROGRESS_EVERY) {
                    Ok((i, Ok(values))) => {
                        let f = &lattice.families[i];
                        columns[f.offset..f.offset + values.len()].copy_from_slice(&values);
                        done(i, &values);
                        left -= 1;
                    }
                    Ok((_, Err(e))) => {
                        failed.get_or_insert(e);
                        cancel.store(true, Ordering::Relaxed);
                        left -= 1;
                    }
                    Err(mpsc::RecvTimeoutError::Timeout) => {}
                    Err(mpsc::RecvTimeoutError::Disconnected) => break,
                }
                if !cancel.load(Ordering::Relaxed) && !progress(counted.load(Ordering::Relaxed) as f64 / total as f64)
                {
                    cancel.store(true, Ordering::Relaxed);
                    failed.get_or_insert(ComplianceError::Cancelled);
                }
            }
        });
        match failed {
            // A family's own error before the cancel it caused in the others.
            Some(e) => Err(e),
            None => Ok(Self { lattice, columns: columns.into(), correction: None }),
        }
    }
}

/// The values a family's columns hold.
fn family_len(f: &lattice::Family) -> usize {
    f.columns() * 9 * f.targets.len()
}

/// Family `i`'s columns: its mesh factorised once, its columns solved in batches; `counted`
/// grows by the work done ([`FACTOR_COLUMNS`] for the factorisation, one a column), and a set
/// `cancel` stops the work within a batch.
fn family_columns(
    lattice: &Lattice,
    i: usize,
    material: &Material,
    divisions: usize,
    counted: &AtomicUsize,
    cancel: &AtomicBool,
) -> Result<Vec<f32>, ComplianceError> {
    let f = &lattice.families[i];
    let mut values = vec![0.0f32; family_len(f)];
    let mut fem = GradedFem::clamped_bottom(family_mesh(f.axis, &lattice.coords, divisions), material)?;
    counted.fetch_add(FACTOR_COLUMNS, Ordering::Relaxed);
    // Each target as the mesh's two nodes across the graded axis and the weight of the second.
    let at: Vec<(usize, usize, f64)> =
        f.targets.iter().map(|&q| mesh_point(&fem.mesh, f.axis, q, &lattice.coords)).collect();
    let n = fem.fixed.len();
    let nodes: Vec<usize> = (0..f.columns()).collect();
    for batch in nodes.chunks(BATCH_NODES) {
        if cancel.load(Ordering::Relaxed) {
            return Err(ComplianceError::Cancelled);
        }
        let cols = 3 * batch.len();
        let mut rhs = vec![0.0; n * cols];
        for (b, &k) in batch.iter().enumerate() {
            let (p, _, _) = mesh_point(&fem.mesh, f.axis, f.column_point(k, lattice.last()), &lattice.coords);
            for c in 0..3 {
                rhs[(3 * b + c) * n + 3 * p + c] = 1.0;
            }
        }
        fem.solve_columns(&mut rhs, cols)?;
        for (b, &k) in batch.iter().enumerate() {
            let start = k * 9 * at.len();
            for (block, &(lo, hi, w)) in values[start..start + 9 * at.len()].chunks_exact_mut(9).zip(&at) {
                for c in 0..3 {
                    let col = &rhs[(3 * b + c) * n..(3 * b + c + 1) * n];
                    for a in 0..3 {
                        block[3 * c + a] = ((1.0 - w) * col[3 * lo + a] + w * col[3 * hi + a]) as f32;
                    }
                }
            }
        }
        counted.fetch_add(batch.len(), Ordering::Relaxed);
    }
    Ok(values)
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::sim::material_surface::compliance::file::{part_from_bytes, part_to_bytes};

    /// On three threads the same bytes as on one; a family kept is taken, not computed; each
    /// family computed is handed over once; a part file round-trips and is refused for another
    /// family; a stopped computation is an error.
    #[test]
    fn families_on_threads_give_the_same_compliance_and_kept_ones_are_taken() {
        let material = Material::object_a();
        let one = SurfaceCompliance::compute(&material, 4, &mut |_| true).expect("one thread");
        let mut handed = Vec::new();
        let mut seen = Vec::new();
        let three = SurfaceCompliance::compute_kept(
            &material,
            4,
            3,
            &mut |_, _| None,
            &mut |f, values| handed.push((f, values.to_vec())),
            &mut |p| {
                seen.push(p);
                true
            },
        )
        .expect("three threads");
        assert_eq!(one.columns, three.columns);
        handed.sort_by_key(|h| h.0);
        assert_eq!(handed.iter().map(|h| h.0).collect::<Vec<_>>(), vec![0, 1, 2]);
        assert!(seen.windows(2).all(|w| w[0] <= w[1]) && seen.iter().all(|p| (0.0..=1.0).contains(p)), "{seen:?}");
        // Family 1 taken from its part file: not computed again, the same compliance.
        let bytes = part_to_bytes(&material, 4, 1, &handed[1].1);
        let back = part_from_bytes(&bytes, &material, 4, 1, handed[1].1.len()).expect("round trip");
        assert!(part_from_bytes(&bytes, &material, 4, 2, handed[1].1.len()).is_err(), "another family's");
        let mut computed = Vec::new();
        let resumed = SurfaceCompliance::compute_kept(
            &material,
            4,
            2,
            &mut |f, _| (f == 1).then(|| back.clone()),
            &mut |f, _| computed.push(f),
            &mut |_| true,
        )
        .expect("resumed");
        computed.sort_unstable();
        assert_eq!(computed, vec![0, 2]);
        assert_eq!(resumed.columns, one.columns);
        let stopped = SurfaceCompliance::compute_kept(&material, 4, 2, &mut |_, _| None, &mut |_, _| {}, &mut |_| false);
        assert!(matches!(stopped, Err(ComplianceError::Cancelled)), "{stopped:?}");
    }
}
