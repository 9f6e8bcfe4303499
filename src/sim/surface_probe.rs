//! The probe's force from the material's surface compliance
//! ([`crate::response::surface_compliance`]): the rigid sphere against a fine grid of the top
//! face, whatever model shows the tissue. The contact forces are carried to the running model's
//! top-face nodes (bilinear weights) as loads, so the view deforms under the force the hand
//! feels. The compliance is computed once per material (about a minute, 60 MB) and kept in a cache
//! folder.

use std::path::Path;
use std::sync::Arc;

use crate::mechanics::grid::{CUBE_SIDE_M, Grid};
use crate::mechanics::material::Material;
use crate::response::surface_compliance::{
    ComplianceError, ContactScratch, DEFAULT_DIVISIONS, MAX_CONTACT_NODES, SurfaceCompliance,
};

/// Largest compliance file read back, bytes.
const MAX_FILE_BYTES: u64 = crate::io::MAX_OUTPUT_BYTES as u64;

/// The probe of a running model on a surface compliance.
#[derive(Debug)]
pub struct SurfaceProbe {
    compliance: Arc<SurfaceCompliance>,
    scratch: ContactScratch,
    grid: Grid,
    last: Option<([f64; 3], f64)>,
    force: [f64; 3],
    loads: Vec<(usize, [f64; 3])>,
}

impl SurfaceProbe {
    /// The probe of a model on `grid`.
    pub fn new(compliance: Arc<SurfaceCompliance>, grid: Grid) -> Self {
        Self {
            compliance,
            scratch: ContactScratch::default(),
            grid,
            last: None,
            force: [0.0; 3],
            loads: Vec::with_capacity(4 * MAX_CONTACT_NODES),
        }
    }

    /// The force of the tissue on the sphere (`centre`, `radius`), newtons; solved again only
    /// when the sphere moved. Allocates nothing.
    pub fn update(&mut self, centre: [f64; 3], radius: f64) -> Result<[f64; 3], ComplianceError> {
        if self.last == Some((centre, radius)) {
            return Ok(self.force);
        }
        self.last = None;
        self.force = self.compliance.press(centre, radius, &mut self.scratch)?;
        self.loads.clear();
        let h = self.grid.h();
        let n = self.grid.n();
        for (k, &w) in self.scratch.active.iter().enumerate() {
            let (q, normal, _) = self.scratch.window[w];
            let x = self.compliance.position(q);
            let f = normal.map(|c| c * self.scratch.lambda[k]);
            let (u, v) = (x[0] / h, x[1] / h);
            let (i, j) = ((u.floor() as usize).min(n - 2), (v.floor() as usize).min(n - 2));
            let (fu, fv) = (u - i as f64, v - j as f64);
            for (di, dj, wgt) in
                [(0, 0, (1.0 - fu) * (1.0 - fv)), (1, 0, fu * (1.0 - fv)), (0, 1, (1.0 - fu) * fv), (1, 1, fu * fv)]
            {
                if wgt > 0.0 {
                    self.loads.push((self.grid.node(i + di, j + dj, n - 1), f.map(|c| c * wgt)));
                }
            }
        }
        self.last = Some((centre, radius));
        Ok(self.force)
    }

    /// The contact forces on the model's nodes, newtons (a node may appear more than once).
    pub fn loads(&self) -> &[(usize, [f64; 3])] {
        &self.loads
    }

    /// Whether a sphere centred at `centre` presses the top face (the face the compliance
    /// covers): its centre is over the face and in the cube's upper half.
    pub fn covers(centre: [f64; 3]) -> bool {
        (0.0..=CUBE_SIDE_M).contains(&centre[0])
            && (0.0..=CUBE_SIDE_M).contains(&centre[1])
            && centre[2] > CUBE_SIDE_M * 0.5
    }
}

/// The file name of `material`'s surface compliance in a cache folder.
pub fn file_name(material: &Material) -> String {
    format!(
        "surface-compliance-{:016x}.bin",
        crate::io::cache_key((1u32, DEFAULT_DIVISIONS), material.stiffness.iter())
    )
}

/// `material`'s surface compliance: read from `dir` where kept there, else computed
/// (`progress(fraction)`, which stops the work by returning `false`) and written there
/// (atomically) when a folder is given.
pub fn load_or_compute(
    material: &Material,
    dir: Option<&Path>,
    progress: &mut dyn FnMut(f64) -> bool,
) -> anyhow::Result<Arc<SurfaceCompliance>> {
    let path = dir.map(|d| d.join(file_name(material)));
    if let Some(path) = &path
        && path.exists()
        && let Ok(bytes) = crate::io::read_bytes(path, MAX_FILE_BYTES)
        && let Ok(found) = SurfaceCompliance::from_bytes(&bytes)
    {
        return Ok(Arc::new(found));
    }
    let computed = SurfaceCompliance::compute(material, DEFAULT_DIVISIONS, progress)?;
    if let (Some(path), Some(dir)) = (&path, dir) {
        std::fs::create_dir_all(dir)
            .map_err(|e| anyhow::anyhow!("cannot create the cache folder {}: {e}", dir.display()))?;
        crate::io::write_atomic(path, &computed.to_bytes())?;
    }
    Ok(Arc::new(computed))
}
