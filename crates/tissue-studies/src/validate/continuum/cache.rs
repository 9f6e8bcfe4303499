//! The material's probe forces ([`crate::validate::continuum`]) and fast taps
//! ([`crate::validate::continuum::tap`]), kept: a cache folder with one
//! JSON file per material (its stiffness in the key and in the file), and the answers shipped
//! with the program for the paper's objects (`assets/continuum/`, a few kB) so that a fresh
//! checkout scores without the minutes the first solves take.
//!
//! A file of the cache folder proves what it is: it holds its full key (the method's version,
//! the stiffness `C`, and for a tap the density; the press forces are static and depend on `C`
//! alone) and a checksum, the crc32 of its canonical form (its compact JSON without the
//! checksum). A file whose checksum or key does not match, or that is not a regular file, is
//! never used: its answers are computed again, said in one line on standard error. The shipped
//! files are compiled in, not cache files: they carry no checksum and are trusted. The folder is
//! checked before any computation ([`crate::io::cache::KeptFile`]); an answer that cannot be kept
//! is used from memory, said in one line, never an error.

use std::path::Path;

use crate::io::cache::KeptFile;
use crate::mechanics::material::Material;
use crate::validate::continuum::tap::{ContinuumTap, continuum_tap};
use crate::validate::continuum::{ContinuumForce, Press, press_force};

/// Version of the computation: a change of method makes old files misses.
const VERSION: u32 = 1;

/// Answers shipped for the paper's objects.
const SHIPPED: [&str; 2] =
    [include_str!("../../../../../assets/continuum/A.json"), include_str!("../../../../../assets/continuum/B.json")];

/// One material's kept answers: the file's contents.
#[derive(Debug, Clone, PartialEq, serde::Serialize, serde::Deserialize)]
pub struct CacheFile {
    /// The version of the computation (a change of method makes old files misses).
    pub version: u32,
    /// The material's name.
    pub material: String,
    /// Its stiffness `C` (Voigt, Pa), row by row, and its inclusions' ([`Material::key`]): the key.
    pub stiffness: Vec<f64>,
    /// The answers.
    pub entries: Vec<Entry>,
    /// The crc32 of the file's canonical form (its compact JSON without the checksum); none in
    /// the shipped files, which are trusted.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub checksum: Option<u32>,
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
    /// The file in the cache folder, while the answers may be kept there.
    kept: Option<KeptFile>,
    file: CacheFile,
    /// Answers to write: computed since opening, or a refused file to replace.
    dirty: bool,
    /// Whether the folder was checked before a computation.
    checked: bool,
}

/// What the messages call the kept press forces.
const KEPT_FORCES: &str = "the material's probe forces";
/// What the messages call a kept tap.
const KEPT_TAP: &str = "the material's tap";

/// Says a line about the cache on standard error (a file refused, a folder or a write that
/// failed).
fn warn(line: &str) {
    eprintln!("{line}");
}

/// A kept JSON file that proves it is intact: the crc32 of its canonical form in `checksum`.
trait Sealed: serde::Serialize + serde::de::DeserializeOwned + Clone {
    /// The file's checksum.
    fn checksum(&mut self) -> &mut Option<u32>;
}

impl Sealed for CacheFile {
    fn checksum(&mut self) -> &mut Option<u32> {
        &mut self.checksum
    }
}

impl Sealed for TapFile {
    fn checksum(&mut self) -> &mut Option<u32> {
        &mut self.checksum
    }
}

/// The crc32 of `file`'s canonical form: its compact JSON without the checksum (`None` where it
/// cannot be serialised).
fn canonical_crc<T: Sealed>(file: &T) -> Option<u32> {
    let mut bare = file.clone();
    *bare.checksum() = None;
    serde_json::to_vec(&bare).ok().map(|b| crc32fast::hash(&b))
}

/// Reads the kept file `kept` as a `T` whose checksum matches: `Ok(None)` where there is none
/// (or something never opened, said before the work), the line to show where it is refused.
fn read_sealed<T: Sealed>(kept: &KeptFile) -> Result<Option<T>, String> {
    let Some(text) = kept.read_text()? else { return Ok(None) };
    let mut file: T = serde_json::from_str(&text).map_err(|e| kept.refused(&format!("cannot be parsed ({e})")))?;
    let claimed = *file.checksum();
    match claimed {
        None => Err(kept.refused("has no checksum (an older version wrote it)")),
        Some(c) if Some(c) != canonical_crc(&file) => Err(kept.refused("is damaged (its checksum does not match)")),
        Some(_) => Ok(Some(file)),
    }
}

/// Writes `file` into `kept` as pretty JSON with its checksum; the line to show where it fails.
fn write_sealed<T: Sealed>(kept: &KeptFile, file: &T) -> Result<(), String> {
    let mut sealed = file.clone();
    *sealed.checksum() = canonical_crc(file);
    let mut text = serde_json::to_string_pretty(&sealed).map_err(|e| kept.not_kept(&e.to_string()))?;
    text.push('\n');
    kept.write(text.as_bytes())
}

/// Reads the kept press forces of the material whose key is `stiffness` from `kept`, as
/// [`read_sealed`], refusing another version's or another material's.
fn read_forces(kept: &KeptFile, stiffness: &[f64]) -> Result<Option<CacheFile>, String> {
    let Some(f) = read_sealed::<CacheFile>(kept)? else { return Ok(None) };
    if f.version != VERSION {
        return Err(kept.refused("was computed by another version of the method"));
    }
    if f.stiffness != stiffness {
        return Err(kept.refused("is for another material"));
    }
    Ok(Some(f))
}

fn stiffness_key(material: &Material) -> Vec<f64> {
    material.key()
}

/// The file name of `material`'s answers: a hash of its stiffness (its inclusions' too) and the
/// method's version.
pub fn file_name(material: &Material) -> String {
    format!("continuum-{:016x}.json", crate::io::cache_key(VERSION, material.key().iter()))
}

impl ContinuumCache {
    /// The kept answers of `material`: the shipped ones, and those in the cache folder `dir`
    /// (when given) where its file proves to be `material`'s (a file refused is said in one line
    /// on standard error and replaced at [`ContinuumCache::save`]; its answers are computed
    /// again where needed).
    pub fn open(material: &Material, dir: Option<&Path>) -> Self {
        let key = stiffness_key(material);
        let mut file = CacheFile {
            version: VERSION,
            material: material.name.clone(),
            stiffness: key.clone(),
            entries: Vec::new(),
            checksum: None,
        };
        let mut sources: Vec<CacheFile> = SHIPPED.iter().filter_map(|s| serde_json::from_str(s).ok()).collect();
        let kept = dir.map(|d| KeptFile::new(d, &file_name(material), KEPT_FORCES));
        let mut refused = false;
        if let Some(kept) = &kept {
            match read_forces(kept, &key) {
                Ok(found) => sources.extend(found),
                Err(line) => {
                    warn(&line);
                    refused = true;
                }
            }
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
        Self { kept, file, dirty: refused, checked: false }
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
        self.check_before_work();
        let result = press_force(material, press, tolerance, progress)?;
        self.file.entries.push(Entry { press: *press, tolerance, result: result.clone() });
        self.dirty = true;
        Ok(result)
    }

    /// Before the first computation: whether its answers can be kept in the cache folder (where
    /// not, one line on standard error, and they live in memory).
    fn check_before_work(&mut self) {
        if std::mem::replace(&mut self.checked, true) {
            return;
        }
        if let Some(kept) = &self.kept
            && let Err(line) = kept.check_writable()
        {
            warn(&line);
            self.kept = None;
        }
    }

    /// Writes the answers computed since opening (or in place of a refused file) to the cache
    /// folder, atomically, with their checksum; nothing without a folder or anything new. A
    /// write that fails is one line on standard error, never an error: the answers stay in
    /// memory, and no later save tries again.
    pub fn save(&mut self) {
        let Some(kept) = &self.kept else { return };
        if !self.dirty {
            return;
        }
        if let Err(line) = write_sealed(kept, &self.file) {
            warn(&line);
            self.kept = None;
        }
        self.dirty = false;
    }

    /// Every kept answer.
    pub fn file(&self) -> &CacheFile {
        &self.file
    }
}

/// Taps shipped for the paper's objects.
const SHIPPED_TAPS: [&str; 2] = [
    include_str!("../../../../../assets/continuum/tap-A.json"),
    include_str!("../../../../../assets/continuum/tap-B.json"),
];

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
    /// The crc32 of the file's canonical form (its compact JSON without the checksum); none in
    /// the shipped files, which are trusted.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub checksum: Option<u32>,
}

/// The file name of `material`'s taps in a cache folder.
pub fn tap_file_name(material: &Material) -> String {
    format!(
        "continuum-tap-{:016x}.json",
        crate::io::cache_key((TAP_VERSION, material.density.to_bits()), material.key().iter())
    )
}

/// Version of the tap's computation.
const TAP_VERSION: u32 = 1;

/// Reads `material`'s kept taps from `kept`, as [`read_sealed`], refusing another version's or
/// another material's (stiffness and density).
fn read_taps(kept: &KeptFile, material: &Material) -> Result<Option<TapFile>, String> {
    let Some(f) = read_sealed::<TapFile>(kept)? else { return Ok(None) };
    if f.version != TAP_VERSION {
        return Err(kept.refused("was computed by another version of the method"));
    }
    if f.stiffness != stiffness_key(material) || f.density.to_bits() != material.density.to_bits() {
        return Err(kept.refused("is for another material"));
    }
    Ok(Some(f))
}

/// The material's converged tap damped by `zeta`: shipped, kept in the cache folder `dir` (a
/// file that does not prove to be `material`'s is refused in one line on standard error), or
/// computed (minutes; `progress` says what runs) and kept there: the folder is checked before
/// the work, and a folder or write that fails is one line, the tap then used from memory.
pub fn tap(
    material: &Material,
    zeta: f64,
    dir: Option<&Path>,
    progress: &mut dyn FnMut(&str),
) -> anyhow::Result<ContinuumTap> {
    let key = stiffness_key(material);
    let file = dir.map(|d| KeptFile::new(d, &tap_file_name(material), KEPT_TAP));
    let mut kept: Vec<TapFile> = SHIPPED_TAPS.iter().filter_map(|s| serde_json::from_str(s).ok()).collect();
    if let Some(file) = &file {
        match read_taps(file, material) {
            Ok(found) => kept.extend(found),
            Err(line) => warn(&line),
        }
    }
    let mine = |f: &&TapFile| f.version == TAP_VERSION && f.stiffness == key && f.density == material.density;
    if let Some(found) = kept.iter().filter(mine).flat_map(|f| &f.taps).find(|t| t.damping_ratio == zeta) {
        return Ok(found.clone());
    }
    // Before the work: whether the tap can be kept.
    let keep = file.filter(|f| f.check_writable().map_err(|line| warn(&line)).is_ok());
    let computed = continuum_tap(material, zeta, progress)?;
    if let Some(keep) = &keep {
        let mut out = kept.iter().rfind(mine).cloned().unwrap_or(TapFile {
            version: TAP_VERSION,
            material: material.name.clone(),
            stiffness: key,
            density: material.density,
            taps: Vec::new(),
            checksum: None,
        });
        out.taps.push(computed.clone());
        if let Err(line) = write_sealed(keep, &out) {
            warn(&line);
        }
    }
    Ok(computed)
}

#[cfg(test)]
mod tests {
    use super::*;

    /// An answer to a press no shipped file holds (made up: the file does not care).
    fn entry() -> Entry {
        Entry {
            press: Press::normal([0.05, 0.05, 0.1], 0.0123).depth(0.001),
            tolerance: 0.01,
            result: ContinuumForce {
                force: [0.0, 0.0, 1.25],
                force_n: 1.25,
                levels: vec![(0.002, 1.2), (0.001, 1.25)],
                change: 0.04,
                contacts: 7,
            },
        }
    }

    fn forces_of(material: &Material) -> CacheFile {
        CacheFile {
            version: VERSION,
            material: material.name.clone(),
            stiffness: stiffness_key(material),
            entries: vec![entry()],
            checksum: None,
        }
    }

    #[test]
    fn a_sealed_file_is_read_back_and_used() {
        let dir = tempfile::tempdir().expect("tempdir");
        let a = Material::object_a();
        let kept = KeptFile::new(dir.path(), &file_name(&a), KEPT_FORCES);
        write_sealed(&kept, &forces_of(&a)).expect("written");
        let read = read_forces(&kept, &stiffness_key(&a)).expect("accepted").expect("there");
        assert_eq!(read.entries, vec![entry()]);
        assert!(read.checksum.is_some());
        let cache = ContinuumCache::open(&a, Some(dir.path()));
        assert_eq!(cache.get(&entry().press, 0.01), Some(&entry().result));
    }

    #[test]
    fn a_changed_foreign_cut_or_unsealed_file_is_refused_and_replaced() {
        let dir = tempfile::tempdir().expect("tempdir");
        let (a, b) = (Material::object_a(), Material::object_b());
        let kept = KeptFile::new(dir.path(), &file_name(&a), KEPT_FORCES);
        let read = || read_forces(&kept, &stiffness_key(&a));
        // B's answers under A's name.
        write_sealed(&kept, &forces_of(&b)).expect("written");
        assert_eq!(read(), Err(kept.refused("is for another material")));
        // A number changed after the write.
        write_sealed(&kept, &forces_of(&a)).expect("written");
        let text = std::fs::read_to_string(kept.path()).expect("read");
        assert!(text.contains("\"force_n\": 1.25"), "{text}");
        std::fs::write(kept.path(), text.replace("\"force_n\": 1.25", "\"force_n\": 1.35")).expect("write");
        assert_eq!(read(), Err(kept.refused("is damaged (its checksum does not match)")));
        // Cut in the middle.
        std::fs::write(kept.path(), &text[..text.len() / 2]).expect("write");
        assert!(read().is_err_and(|line| line.contains("cannot be parsed")));
        // Written before files carried a checksum.
        crate::io::write_json_atomic(kept.path(), &forces_of(&a)).expect("written");
        assert_eq!(read(), Err(kept.refused("has no checksum (an older version wrote it)")));
        // Not used, and replaced by a sealed file at the save.
        let mut cache = ContinuumCache::open(&a, Some(dir.path()));
        assert_eq!(cache.get(&entry().press, 0.01), None);
        cache.save();
        let replaced = read().expect("a sealed file").expect("there");
        assert_eq!(replaced.entries, cache.file().entries);
    }

    #[test]
    fn a_kept_tap_proves_its_material_and_density() {
        let dir = tempfile::tempdir().expect("tempdir");
        let a = Material::object_a();
        let kept = KeptFile::new(dir.path(), &tap_file_name(&a), KEPT_TAP);
        let made_up = ContinuumTap {
            damping_ratio: 0.123,
            omega_1: 100.0,
            dt: 1e-4,
            spacing: 0.002,
            force_n: vec![0.0, 0.5, 0.25],
            history: vec![(1e-4, 0.002, None)],
        };
        let mut file = TapFile {
            version: TAP_VERSION,
            material: a.name.clone(),
            stiffness: stiffness_key(&a),
            density: a.density,
            taps: vec![made_up.clone()],
            checksum: None,
        };
        write_sealed(&kept, &file).expect("written");
        // Found without computing.
        let found = tap(&a, 0.123, Some(dir.path()), &mut |s| panic!("computing: {s}")).expect("kept");
        assert_eq!(found, made_up);
        file.density *= 2.0;
        write_sealed(&kept, &file).expect("written");
        assert_eq!(read_taps(&kept, &a), Err(kept.refused("is for another material")));
    }
}
