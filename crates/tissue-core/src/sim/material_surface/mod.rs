//! The probe on the material's surface, in one folder: [`compliance`] (the free surface's contact
//! compliance of fine FEM meshes, computed once per material and kept, [`compliance::file`] its
//! format), [`modal_lag`] (the material's slow modes) and, here, the probe that joins them.
//!
//! The probe's force comes from the material's surface compliance: the rigid sphere against a
//! fine lattice of the five free faces, whatever model shows the tissue. The contact forces are
//! carried to the running model's nodes (the trilinear weights of their cell, on the surface
//! those of its face) as loads, so the view deforms under the force the hand feels. The
//! compliance is computed once per material (about a minute) and kept in a cache folder.
//!
//! With the material's lowest modes ([`ModalLag`]) the force is dynamic: the sphere meets the
//! surface where the static answer puts it plus the lag of the slow modes behind their static
//! values at the end of the span the force is held over, with that force held. The lag is affine
//! in the contact's net force (`free - G F`, [`ModalLag::response_after`]), so the step's modal
//! response is folded into the contact's compliance and one contact solve per step is exact for
//! the contact and the modes together (no iteration); the modes are then advanced exactly over
//! the span under that force, spread over the patch the lag is read on, so that they exchange no
//! energy with the contact that is not there and a held press is steady.

pub mod compliance;
pub mod modal_lag;

use std::path::Path;
use std::sync::Arc;
use std::sync::atomic::{AtomicUsize, Ordering};

use glam::DVec3;

use crate::io::cache::{CacheEvent, KeptFile, StderrReport};

use crate::mechanics::grid::{CUBE_SIDE_M, Grid};
use crate::mechanics::material::Material;
use compliance::{ComplianceError, SurfaceContactScratch, DEFAULT_DIVISIONS, MAX_CONTACT_NODES, SurfaceCompliance};
use modal_lag::{ModalBasis, ModalLag};

/// Largest compliance file read back, bytes.
const MAX_FILE_BYTES: u64 = crate::io::MAX_OUTPUT_BYTES as u64;

/// The probe of a running model on a surface compliance.
#[derive(Debug)]
pub struct SurfaceProbe {
    compliance: Arc<SurfaceCompliance>,
    scratch: SurfaceContactScratch,
    grid: Grid,
    last: Option<([f64; 3], f64)>,
    force: [f64; 3],
    loads: Vec<(usize, [f64; 3])>,
    lag: Option<ModalLag>,
    /// Simulated time since the contact was last solved, s.
    since_solve_s: f64,
    /// The span the last solve's force is held over, s.
    span: f64,
}

impl SurfaceProbe {
    /// The probe of a model on `grid`.
    pub fn new(compliance: Arc<SurfaceCompliance>, grid: Grid) -> Self {
        Self {
            compliance,
            scratch: SurfaceContactScratch::default(),
            grid,
            last: None,
            force: [0.0; 3],
            loads: Vec::with_capacity(8 * MAX_CONTACT_NODES),
            lag: None,
            since_solve_s: 0.0,
            span: 0.0,
        }
    }

    /// The probe of a model on `grid` on `surface`, with the material's modes damped by the
    /// ratio `zeta` at the fundamental (a force with inertia and damping), or static where `None`.
    pub fn on(surface: &MaterialSurface, grid: Grid, zeta: Option<f64>) -> Self {
        let mut probe = Self::new(Arc::clone(&surface.compliance), grid);
        probe.lag = zeta.map(|z| ModalLag::new(Arc::clone(&surface.modes), z));
        probe
    }

    /// The modes' damping ratio at the fundamental, from now on.
    pub fn set_damping_ratio(&mut self, zeta: f64) {
        if let Some(lag) = &mut self.lag {
            lag.set_damping_ratio(zeta);
        }
    }

    /// Whether the force has the slow modes' dynamics.
    pub fn is_dynamic(&self) -> bool {
        self.lag.is_some()
    }

    /// Advances the slow modes by `dt` under the loads of the last update (none when the sphere
    /// is elsewhere: call [`SurfaceProbe::release`] first).
    pub fn advance(&mut self, dt: f64) {
        self.since_solve_s += dt;
        if let Some(lag) = &mut self.lag {
            lag.advance(dt);
        }
    }

    /// The sphere is not on the face: no loads, no contact (the next press starts afresh where it
    /// lands: its modes read under the sphere, not over the last contact's patch).
    pub fn release(&mut self) {
        self.loads.clear();
        self.force = [0.0; 3];
        self.last = None;
        self.scratch.clear();
        if let Some(lag) = &mut self.lag {
            lag.release();
        }
    }

    /// Back to rest (the modes too).
    pub fn reset(&mut self) {
        self.release();
        if let Some(lag) = &mut self.lag {
            lag.reset();
        }
    }

    /// The force of the tissue on the sphere (`centre`, `radius`), newtons, solved again when
    /// the sphere moved, or with the lag when the time it was solved for has passed. With the
    /// lag, the contact is solved against the lag the material's modes reach at the end of the
    /// span its force is held over (the step `dt` while the sphere moves; a tick,
    /// [`super::TICK_S`], the rate a haptic device reads the force, while it is held still), with
    /// that force held, in one solve ([`ModalLag::response_after`] folded into the contact): the
    /// contact and the modes agree, so they exchange no energy that is not there and a held press
    /// is steady. Allocates nothing.
    pub fn update(&mut self, centre: [f64; 3], radius: f64, dt: f64) -> Result<[f64; 3], ComplianceError> {
        if self.lag.is_none() {
            if self.last == Some((centre, radius)) {
                return Ok(self.force);
            }
            self.last = None;
            self.press(centre, radius, [0.0; 3], &[[0.0; 3]; 3])?;
            self.last = Some((centre, radius));
            return Ok(self.force);
        }
        let still = self.last == Some((centre, radius));
        if still && self.since_solve_s < self.span * (1.0 - 1e-9) {
            return Ok(self.force);
        }
        let span = if still { super::TICK_S.max(dt) } else { dt };
        self.last = None;
        // The modes' response over the span, read over the patch the contact's net force is
        // spread on (the last contact's, weighted by its forces, where the sphere still covers
        // it; before one, or after a jump, the surface point nearest the sphere's centre): the
        // surface moves by `free - G F` there.
        let (free, coupling) = match self.lag.as_mut() {
            Some(lag) => {
                let (scratch, compliance) = (&self.scratch, &self.compliance);
                let (mut sum, mut weight) = (DVec3::ZERO, 0.0);
                for (q, _, l) in scratch.contacts() {
                    sum += DVec3::from(compliance.position(q)) * l.max(0.0);
                    weight += l.max(0.0);
                }
                let reach = radius + compliance.spacing();
                if weight > 0.0 && (sum / weight).distance(DVec3::from(centre)) < reach {
                    lag.set_patch(scratch.contacts().map(|(q, _, l)| (compliance.position(q), l)));
                } else {
                    lag.set_patch(std::iter::once((centre.map(|c| c.clamp(0.0, CUBE_SIDE_M)), 1.0)));
                }
                lag.response_after(span)
            }
            None => ([0.0; 3], [[0.0; 3]; 3]),
        };
        self.press(centre, radius, free, &coupling)?;
        let net =
            self.scratch.contacts().fold([0.0; 3], |f, (_, n, lambda)| std::array::from_fn(|c| f[c] + n[c] * lambda));
        if let Some(lag) = self.lag.as_mut() {
            lag.hold(net);
        }
        self.last = Some((centre, radius));
        self.since_solve_s = 0.0;
        self.span = span;
        Ok(self.force)
    }

    /// One press at `centre` on the compliance, the surface moved by the modes' `shift - coupling
    /// F` (the modes folded in): the force and the model's loads.
    fn press(
        &mut self,
        centre: [f64; 3],
        radius: f64,
        shift: [f64; 3],
        coupling: &[[f64; 3]; 3],
    ) -> Result<(), ComplianceError> {
        self.force = self.compliance.press_coupled(centre, radius, shift, coupling, &mut self.scratch)?;
        self.loads.clear();
        for (q, normal, lambda) in self.scratch.contacts() {
            let f = normal.map(|c| c * lambda);
            for (node, wgt) in self.grid.corners(self.compliance.position(q)) {
                if wgt > 0.0 {
                    self.loads.push((node, f.map(|c| c * wgt)));
                }
            }
        }
        Ok(())
    }

    /// The contact forces on the model's nodes, newtons (a node may appear more than once).
    pub fn loads(&self) -> &[(usize, [f64; 3])] {
        &self.loads
    }

    /// The contact of the last solve on the compliance's surface nodes: node, the sphere's
    /// normal there (away from its centre) and the normal force, newtons (none while the sphere
    /// is clear of the surface). [`SurfaceCompliance::near_contact`] turns it into the
    /// surface's shape under the sphere.
    pub fn contact(&self) -> impl Iterator<Item = (usize, [f64; 3], f64)> + '_ {
        self.scratch.contacts()
    }

}

/// What the probe needs of a material: its surface compliance and its slow modes.
#[derive(Debug, Clone)]
pub struct MaterialSurface {
    /// The free surface's contact compliance.
    pub compliance: Arc<SurfaceCompliance>,
    /// The lowest modes.
    pub modes: Arc<ModalBasis>,
}

impl MaterialSurface {
    /// `material`'s: the compliance as [`load_or_compute`] finds it (`report` hears what it
    /// says), and the modes (a second).
    pub fn load_or_compute(
        material: &Material,
        dir: Option<&Path>,
        report: &mut dyn FnMut(CacheEvent<'_>) -> bool,
    ) -> anyhow::Result<Self> {
        Ok(Self::with_background(material, dir, true, report)?.1)
    }

    /// [`MaterialSurface::load_or_compute`] with the compliance of the material's background
    /// beside it (the same where it has no inclusions, [`with_background`]); the inclusions'
    /// correction kept in `dir` too where `keep_correction` (a lump of a file), or in memory only (a
    /// random lump of an exercise, seldom met again).
    pub fn with_background(
        material: &Material,
        dir: Option<&Path>,
        keep_correction: bool,
        report: &mut dyn FnMut(CacheEvent<'_>) -> bool,
    ) -> anyhow::Result<(Arc<SurfaceCompliance>, Self)> {
        let (background, compliance) = with_background_as(material, dir, keep_correction, report)?;
        // The background's modes: the inclusions change the slow modes little, and the force
        // held still is the compliance's, inclusions and all.
        let modes = Arc::new(ModalBasis::of_material(&material.background()).map_err(anyhow::Error::msg)?);
        Ok((background, Self { compliance, modes }))
    }
}

/// The file name of `material`'s surface compliance in a cache folder: a hash of its key (the
/// method's version, the face divisions, the stiffness), which the file holds in full.
pub fn file_name(material: &Material) -> String {
    format!(
        "surface-compliance-{:016x}.bin",
        crate::io::cache_key(
            (crate::sim::material_surface::compliance::METHOD_VERSION, DEFAULT_DIVISIONS),
            material.stiffness.iter(),
        )
    )
}

/// What the cache's messages call the kept answer.
const KEPT: &str = "the surface compliance";

/// The report on standard error of computing a material's surface compliance, for the commands
/// (`&mut |e| report.event(e)` as [`load_or_compute`]'s `report`).
pub fn stderr_report() -> StderrReport {
    StderrReport::new("the material's surface compliance", "a minute")
}

/// `material`'s surface compliance: read from the cache folder `dir` where the file there proves
/// to be it (its key and checksum, [`SurfaceCompliance::from_bytes`]), else computed and kept
/// there (written atomically). `report` hears, as [`CacheEvent`]s:
/// - a line for a file refused (another material's, damaged, truncated, unreadable): it is not
///   used, and the compliance is computed again;
/// - before the work, a line where the answer cannot be kept (the folder not writable, a
///   directory, FIFO or loop of links in the file's place, never opened): it is computed in
///   memory;
/// - the work's start and progress (its `false` stops the work);
/// - a line where the write after the work fails: the computed answer is used all the same.
///
/// A material with inclusions: its background's compliance so (the file is the background's),
/// then the change its inclusions make ([`compliance::inclusion`], seconds), so too in a file of its
/// own keyed by the whole material ([`compliance::inclusion::file`]; [`CacheEvent::Part`] and its
/// progress where it is computed).
///
/// The errors are the computation's only: never the cache's.
pub fn load_or_compute(
    material: &Material,
    dir: Option<&Path>,
    report: &mut dyn FnMut(CacheEvent<'_>) -> bool,
) -> anyhow::Result<Arc<SurfaceCompliance>> {
    Ok(with_background(material, dir, report)?.1)
}

/// [`load_or_compute`]'s compliance of the material's background (without its inclusions) and
/// of the material (the same where it has none).
pub fn with_background(
    material: &Material,
    dir: Option<&Path>,
    report: &mut dyn FnMut(CacheEvent<'_>) -> bool,
) -> anyhow::Result<(Arc<SurfaceCompliance>, Arc<SurfaceCompliance>)> {
    with_background_as(material, dir, true, report)
}

/// [`with_background`], the inclusions' correction kept in `dir` only where `keep_correction`.
fn with_background_as(
    material: &Material,
    dir: Option<&Path>,
    keep_correction: bool,
    report: &mut dyn FnMut(CacheEvent<'_>) -> bool,
) -> anyhow::Result<(Arc<SurfaceCompliance>, Arc<SurfaceCompliance>)> {
    let background = load_or_compute_background(&material.background(), dir, report)?;
    if material.inclusions.is_empty() {
        return Ok((Arc::clone(&background), background));
    }
    let lump = load_or_compute_correction(material, &background, dir.filter(|_| keep_correction), report)?;
    Ok((Arc::clone(&background), Arc::new((*background).clone().with_correction(lump))))
}

/// The change `material`'s inclusions make to `background` (its background's compliance):
/// from its file in `dir` where one is kept for this material, else computed (and kept there).
fn load_or_compute_correction(
    material: &Material,
    background: &SurfaceCompliance,
    dir: Option<&Path>,
    report: &mut dyn FnMut(CacheEvent<'_>) -> bool,
) -> anyhow::Result<compliance::inclusion::InclusionCorrection> {
    use compliance::inclusion::InclusionCorrection;
    const WHAT: &str = "the change the inclusions make";
    let (divisions, nodes) = background.lattice_size();
    let name = format!(
        "lump-correction-{:016x}.bin",
        crate::io::cache_key((compliance::inclusion::file::INCLUSION_METHOD_VERSION, divisions), material.key().iter())
    );
    kept_or_computed(
        dir.map(|d| KeptFile::new(d, &name, WHAT)),
        report,
        |bytes| InclusionCorrection::from_bytes(bytes, material, divisions, nodes),
        |kept_in, report| {
            report(CacheEvent::Part { what: WHAT, kept_in });
            Ok(background.inclusion_of(material, &mut |f| report(CacheEvent::Progress(f)))?)
        },
        |lump| lump.to_bytes(material, divisions),
    )
}

/// How many threads compute a surface compliance (a family of faces each, at most three): every
/// core unless set ([`set_compute_threads`]).
static COMPUTE_THREADS: AtomicUsize = AtomicUsize::new(0);

/// Computes surface compliances on `threads` threads from now on (the viewer takes one, so that
/// its physics and drawing keep theirs).
pub fn set_compute_threads(threads: usize) {
    COMPUTE_THREADS.store(threads.max(1), Ordering::Relaxed);
}

fn compute_threads() -> usize {
    match COMPUTE_THREADS.load(Ordering::Relaxed) {
        0 => std::thread::available_parallelism().map_or(1, |n| n.get()).min(3),
        n => n,
    }
}

/// The part file of family `family` of `material`'s compliance in a cache folder: a family's
/// columns kept while the others are computed, so that an interrupted computation resumes.
fn part_name(material: &Material, family: usize) -> String {
    file_name(material).replace(".bin", &format!(".part{family}.bin"))
}

/// [`load_or_compute`] for a material without inclusions: the shipped compact form where it is a
/// shipped object's ([`shipped`]), else [`computed`].
fn load_or_compute_background(
    material: &Material,
    dir: Option<&Path>,
    report: &mut dyn FnMut(CacheEvent<'_>) -> bool,
) -> anyhow::Result<Arc<SurfaceCompliance>> {
    match shipped(material) {
        Some(compliance) => Ok(compliance),
        None => computed(material, dir, report),
    }
}

/// The surface compliance shipped in `assets/compliance/` for `material` where its stiffness is a
/// shipped object's to the bit (objects A and B; [`compliance::compact`]: every entry within
/// 5e-4 of its column's largest), read once a process: nothing to compute.
pub fn shipped(material: &Material) -> Option<Arc<SurfaceCompliance>> {
    use std::sync::OnceLock;
    static READ: [OnceLock<Option<Arc<SurfaceCompliance>>>; 2] = [OnceLock::new(), OnceLock::new()];
    ["A", "B"].iter().zip(&READ).find_map(|(name, read)| {
        let bytes = crate::sim::shipped::compact_compliance(name)?;
        // Another material's is refused by its key before anything is read.
        if !compliance::compact::is_for(bytes, material) {
            return None;
        }
        read.get_or_init(|| SurfaceCompliance::from_compact(bytes, material, DEFAULT_DIVISIONS).ok().map(Arc::new))
            .clone()
    })
}

/// [`load_or_compute`] for a material without inclusions, never the shipped compact form: the
/// compliance computed (or kept in `dir` from an earlier computation). While it is computed, each family of
/// faces is kept in a part file as it ends, and a later computation takes the parts back; they
/// are removed once the whole file is kept.
pub fn computed(
    material: &Material,
    dir: Option<&Path>,
    report: &mut dyn FnMut(CacheEvent<'_>) -> bool,
) -> anyhow::Result<Arc<SurfaceCompliance>> {
    use compliance::file::{part_from_bytes, part_to_bytes};
    let part = |d: &Path, f: usize| KeptFile::new(d, &part_name(material, f), "a part of the surface compliance");
    let computed = kept_or_computed(
        dir.map(|d| KeptFile::new(d, &file_name(material), KEPT)),
        report,
        |bytes| SurfaceCompliance::from_bytes(bytes, material, DEFAULT_DIVISIONS),
        |kept_in, report| {
            report(CacheEvent::Computing { kept_in });
            Ok(SurfaceCompliance::compute_kept(
                material,
                DEFAULT_DIVISIONS,
                compute_threads(),
                // A part that cannot be read or is not this material's is computed again.
                &mut |f, len| {
                    let bytes = part(kept_in?, f).read(MAX_FILE_BYTES).ok()??;
                    part_from_bytes(&bytes, material, DEFAULT_DIVISIONS, f, len).ok()
                },
                // A part that cannot be kept is only work that a later start repeats.
                &mut |f, values| {
                    if let Some(d) = kept_in {
                        let _ = part(d, f).write(&part_to_bytes(material, DEFAULT_DIVISIONS, f, values));
                    }
                },
                &mut |f| report(CacheEvent::Progress(f)),
            )?)
        },
        |computed| computed.to_bytes(material),
    )?;
    if let Some(d) = dir
        && KeptFile::new(d, &file_name(material), KEPT).path().is_file()
    {
        for f in 0..3 {
            let _ = std::fs::remove_file(part(d, f).path());
        }
    }
    Ok(Arc::new(computed))
}

/// The answer `kept` holds where its file proves to be it (`read`), else `compute`d (told the
/// folder it will be kept in, checked writable before the work) and written there. A file
/// refused, a folder that cannot keep it or a write that fails is one line through `report`,
/// never an error: the errors are the computation's only.
fn kept_or_computed<T>(
    kept: Option<KeptFile>,
    report: &mut dyn FnMut(CacheEvent<'_>) -> bool,
    read: impl FnOnce(&[u8]) -> Result<T, compliance::file::FileError>,
    compute: impl FnOnce(Option<&Path>, &mut dyn FnMut(CacheEvent<'_>) -> bool) -> anyhow::Result<T>,
    to_bytes: impl FnOnce(&T) -> Vec<u8>,
) -> anyhow::Result<T> {
    if let Some(kept) = &kept {
        match kept.read(MAX_FILE_BYTES) {
            Ok(Some(bytes)) => match read(&bytes) {
                Ok(found) => return Ok(found),
                Err(why) => {
                    report(CacheEvent::Warning(&kept.refused(&why.to_string())));
                }
            },
            Ok(None) => {}
            Err(line) => {
                report(CacheEvent::Warning(&line));
            }
        }
    }
    // Before the work: whether the answer can be kept.
    let keep = kept.filter(|k| match k.check_writable() {
        Ok(()) => true,
        Err(line) => {
            report(CacheEvent::Warning(&line));
            false
        }
    });
    let computed = compute(keep.as_ref().map(KeptFile::dir), report)?;
    if let Some(keep) = &keep
        && let Err(line) = keep.write(&to_bytes(&computed))
    {
        report(CacheEvent::Warning(&line));
    }
    Ok(computed)
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The compliances shipped for objects A and B are read for them (their key, this method's
    /// version and grid: a stale file fails here; `tissue-sim compliance` writes it again), for no
    /// other material, and give the probe's force on the top face.
    #[test]
    fn objects_a_and_b_have_their_compliance_shipped() {
        for material in [Material::object_a(), Material::object_b()] {
            let compliance = shipped(&material).expect("shipped and of this version");
            let mut scratch = SurfaceContactScratch::default();
            let f = compliance.press([0.05, 0.05, 0.111], 0.015, &mut scratch).expect("a press");
            assert!(f[2] > 3.0 && f[2] < 12.0, "{}: {f:?} N", material.name);
        }
        let mut other = Material::object_a();
        other.stiffness *= 2.0;
        assert!(shipped(&other).is_none());
    }

    /// Under a press the material's displacement puts every contact node on the sphere (the
    /// contact's own condition, read back through the compliance's blocks), on the top face, on
    /// a side, across an edge and at 3/4 of the radius deep; nodes beyond the rim stay outside it.
    #[test]
    fn the_displacement_under_a_press_puts_the_contact_on_the_sphere() {
        let compliance = shipped(&Material::object_a()).expect("A's");
        let r = 0.015;
        // The farthest contact node's distance from the sphere, measured: 0.007 mm at 2 mm deep,
        // 0.059 at 4, 0.31 at 8 and 0.57 at 3/4 of the radius on the top face, 0.087 mm 4 mm into
        // +x, 0.007 across the edge (the linear contact lets a node slide along the sphere's
        // normal at rest; the viewer draws the contact nodes on the sphere).
        for (centre, what, within) in [
            ([0.05, 0.05, 0.1 + r - 0.002], "top, 2 mm", 2e-5),
            ([0.05, 0.05, 0.1 + r - 0.004], "top, 4 mm", 1e-4),
            ([0.04, 0.06, 0.1 + r - 0.008], "top, 8 mm", 5e-4),
            ([0.04, 0.06, 0.1 + r - 0.75 * r], "top, 3/4 of the radius", 8e-4),
            ([0.1 + r - 0.004, 0.05, 0.06], "+x, 4 mm", 1.5e-4),
            ([0.1 + 0.6 * r, 0.05, 0.1 + 0.6 * r], "the top/+x edge", 2e-5),
        ] {
            let mut scratch = SurfaceContactScratch::default();
            compliance.press(centre, r, &mut scratch).expect("a press");
            let contact: Vec<(usize, [f64; 3], f64)> = scratch.contacts().collect();
            let contacts: Vec<usize> = contact.iter().map(|c| c.0).collect();
            assert!(contacts.len() > 10, "{what}: {} contact nodes", contacts.len());
            let (mut worst, mut outside, mut held) = (0.0f64, 0, 0);
            compliance.near_contact(&contact, 0.01, |q, x, distance, u| {
                let y: [f64; 3] = std::array::from_fn(|a| x[a] + u[a]);
                let from_centre = (0..3).map(|a| (y[a] - centre[a]).powi(2)).sum::<f64>().sqrt();
                if contacts.contains(&q) {
                    // Frictionless: a contact node also slides along the sphere, off it by a little.
                    assert_eq!(distance, 0.0);
                    worst = worst.max((from_centre - r).abs());
                    held += 1;
                } else {
                    assert!(from_centre > r - within, "{what}: node {q} ends inside the sphere");
                    outside += 1;
                }
            });
            assert_eq!(held, contacts.len(), "{what}: every contact node is near the contact");
            assert!(worst < within, "{what}: a contact node {worst} m off the sphere");
            assert!(outside > 20, "{what}: {outside} nodes near the contact");
        }
    }

    /// One scratch pressed at the same place on two compliances gives each its own force: the
    /// contact followed between solves is never another compliance's.
    #[test]
    fn a_scratch_pressed_on_another_compliance_solves_afresh() {
        let (a, b) = (shipped(&Material::object_a()), shipped(&Material::object_b()));
        let (a, b) = (a.expect("A's"), b.expect("B's"));
        let at = [0.05, 0.05, 0.111];
        let alone = |c: &SurfaceCompliance| c.press(at, 0.015, &mut SurfaceContactScratch::default()).expect("a press");
        let mut shared = SurfaceContactScratch::default();
        let first = a.press(at, 0.015, &mut shared).expect("a press");
        let second = b.press(at, 0.015, &mut shared).expect("a press");
        assert_eq!((first, second), (alone(&a), alone(&b)));
        assert!((first[2] - second[2]).abs() > 0.2 * second[2], "{first:?} {second:?}");
    }
}
