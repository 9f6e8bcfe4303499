//! The material's probe forces ([`crate::validate::continuum`]) and fast taps
//! ([`crate::validate::continuum::tap`]), kept: a cache folder with one
//! JSON file per material (its stiffness in the key and in the file), and the answers shipped
//! with the program for the paper's objects (`assets/continuum/`, a few kB) so that a fresh
//! checkout scores without the minutes the first solves take.

use std::path::{Path, PathBuf};

use crate::mechanics::material::Material;
use crate::validate::continuum::tap::{ContinuumTap, continuum_tap};
use crate::validate::continuum::{ContinuumForce, Press, press_force};

/// Version of the computation: a change of method makes old files misses.
const VERSION: u32 = 1;

/// Answers shipped for the paper's objects.
const SHIPPED: [&str; 2] =
    [include_str!("../../../assets/continuum/A.json"), include_str!("../../../assets/continuum/B.json")];

/// One material's kept answers: the file's contents.
#[derive(Debug, Clone, PartialEq, serde::Serialize, serde::Deserialize)]
pub struct CacheFile {
    /// The version of the computation (a change of method makes old files misses).
    pub version: u32,
    /// The material's name.
    pub material: String,
    /// Its stiffness `C` (Voigt, Pa), row by row: the key.
    pub stiffness: Vec<f64>,
    /// The answers.
    pub entries: Vec<Entry>,
}

/// One kept answer.
#[derive(Debug, Clone, PartialEq, serde::Serialize, serde::Deserialize)]
pub struct Entry {
    /// The press.
    pub press: Press,
    /// The convergence tolerance it was computed to.
    pub tolerance: f64,
    /// The answer.
    pub result: ContinuumForce,
}

/// The material's probe forces, read from and written to a cache folder.
#[derive(Debug)]
pub struct ContinuumCache {
    dir: Option<PathBuf>,
    /// The file's name in `dir`.
    name: String,
    file: CacheFile,
    dirty: bool,
}

fn stiffness_key(material: &Material) -> Vec<f64> {
    material.stiffness.transpose().iter().copied().collect()
}

/// The file name of `material`'s answers: a hash of its stiffness and the method's version.
pub fn file_name(material: &Material) -> String {
    format!("continuum-{:016x}.json", crate::io::cache_key(VERSION, material.stiffness.iter()))
}

impl ContinuumCache {
    /// The kept answers of `material`: the shipped ones, and those in `dir` (when given; a file
    /// that cannot be read or is for another material is ignored: it is recomputed).
    pub fn open(material: &Material, dir: Option<&Path>) -> Self {
        let key = stiffness_key(material);
        let mut file = CacheFile {
            version: VERSION,
            material: material.name.clone(),
            stiffness: key.clone(),
            entries: Vec::new(),
        };
        let mut sources: Vec<CacheFile> = SHIPPED.iter().filter_map(|s| serde_json::from_str(s).ok()).collect();
        if let Some(dir) = dir
            && let Ok(f) = crate::io::read_json::<CacheFile>(&dir.join(file_name(material)))
        {
            sources.push(f);
        }
        for source in sources {
            if source.version == VERSION && source.stiffness == key {
                for e in source.entries {
                    if !file.entries.iter().any(|k| k.press == e.press && k.tolerance <= e.tolerance) {
                        file.entries.push(e);
                    }
                }
            }
        }
        Self { dir: dir.map(Path::to_path_buf), name: file_name(material), file, dirty: false }
    }

    /// The kept answer to `press` at `tolerance` or tighter, if any.
    pub fn get(&self, press: &Press, tolerance: f64) -> Option<&ContinuumForce> {
        self.file.entries.iter().find(|e| e.press == *press && e.tolerance <= tolerance).map(|e| &e.result)
    }

    /// The answer to `press`: kept, or computed and kept.
    pub fn force(
        &mut self,
        material: &Material,
        press: &Press,
        tolerance: f64,
        progress: &mut dyn FnMut(f64),
    ) -> anyhow::Result<ContinuumForce> {
        if let Some(found) = self.get(press, tolerance) {
            return Ok(found.clone());
        }
        let result = press_force(material, press, tolerance, progress)?;
        self.file.entries.push(Entry { press: *press, tolerance, result: result.clone() });
        self.dirty = true;
        Ok(result)
    }

    /// Writes the answers computed since opening to the cache folder (atomically; nothing
    /// without a folder or new answers).
    pub fn save(&mut self) -> anyhow::Result<()> {
        let Some(dir) = &self.dir else { return Ok(()) };
        if !self.dirty {
            return Ok(());
        }
        std::fs::create_dir_all(dir)
            .map_err(|e| anyhow::anyhow!("cannot create the cache folder {}: {e}", dir.display()))?;
        crate::io::write_json_atomic(&dir.join(&self.name), &self.file)?;
        self.dirty = false;
        Ok(())
    }

    /// Every kept answer.
    pub fn file(&self) -> &CacheFile {
        &self.file
    }
}

/// Taps shipped for the paper's objects.
const SHIPPED_TAPS: [&str; 2] =
    [include_str!("../../../assets/continuum/tap-A.json"), include_str!("../../../assets/continuum/tap-B.json")];

/// One material's kept taps (one per damping ratio): the file's contents.
#[derive(Debug, Clone, PartialEq, serde::Serialize, serde::Deserialize)]
pub struct TapFile {
    /// The version of the computation.
    pub version: u32,
    /// The material's name.
    pub material: String,
    /// Its stiffness `C` (Voigt, Pa), row by row, and density (kg/m^3): the key.
    pub stiffness: Vec<f64>,
    /// The density, kg/m^3.
    pub density: f64,
    /// The taps.
    pub taps: Vec<ContinuumTap>,
}

/// The file name of `material`'s taps in a cache folder.
pub fn tap_file_name(material: &Material) -> String {
    format!(
        "continuum-tap-{:016x}.json",
        crate::io::cache_key((TAP_VERSION, material.density.to_bits()), material.stiffness.iter())
    )
}

/// Version of the tap's computation.
const TAP_VERSION: u32 = 1;

/// The material's converged tap damped by `zeta`: shipped, kept in `dir`, or computed
/// (minutes; `progress` says what runs) and kept there.
pub fn tap(
    material: &Material,
    zeta: f64,
    dir: Option<&Path>,
    progress: &mut dyn FnMut(&str),
) -> anyhow::Result<ContinuumTap> {
    let key = stiffness_key(material);
    let path = dir.map(|d| d.join(tap_file_name(material)));
    let mut kept: Vec<TapFile> = SHIPPED_TAPS.iter().filter_map(|s| serde_json::from_str(s).ok()).collect();
    if let Some(path) = &path
        && let Ok(f) = crate::io::read_json::<TapFile>(path)
    {
        kept.push(f);
    }
    let mine = |f: &&TapFile| f.version == TAP_VERSION && f.stiffness == key && f.density == material.density;
    if let Some(found) = kept.iter().filter(mine).flat_map(|f| &f.taps).find(|t| t.damping_ratio == zeta) {
        return Ok(found.clone());
    }
    let computed = continuum_tap(material, zeta, progress)?;
    if let (Some(path), Some(dir)) = (&path, dir) {
        let mut file = kept.iter().rfind(mine).cloned().unwrap_or(TapFile {
            version: TAP_VERSION,
            material: material.name.clone(),
            stiffness: key,
            density: material.density,
            taps: Vec::new(),
        });
        file.taps.push(computed.clone());
        std::fs::create_dir_all(dir)
            .map_err(|e| anyhow::anyhow!("cannot create the cache folder {}: {e}", dir.display()))?;
        crate::io::write_json_atomic(path, &file)?;
    }
    Ok(computed)
}
