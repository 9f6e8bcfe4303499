//! The JSON files of the headless command line (`shared/spec/benchmark.md`), written atomically.

use std::path::Path;

use serde::{Deserialize, Serialize};

use crate::fem::CaseSolution;

/// One case of a displacement file.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct CaseRecord {
    /// Spec case id.
    pub case_id: String,
    /// Loaded axis, 1-based.
    pub axis: usize,
    /// Applied force, newtons.
    #[serde(rename = "force_N")]
    pub force_n: f64,
    /// Row `n` = displacement of node `n`, metres.
    pub displacements: Vec<[f64; 3]>,
    /// Sum of support reactions, newtons (an extra key).
    #[serde(rename = "reaction_N", default, skip_serializing_if = "Option::is_none")]
    pub reaction_n: Option<[f64; 3]>,
}

/// A node displacement file (FEM or MSM).
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct DisplacementFile {
    /// Object label (`A`, `B`, or a material file's name).
    pub object: String,
    /// `clamped` or `patch`.
    pub bc: String,
    /// `fem` or `msm`.
    pub model: String,
    /// Nodes per axis.
    pub nodes_per_axis: usize,
    /// The cases.
    pub cases: Vec<CaseRecord>,
    /// MSM parameters, for an MSM file (an extra key).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub params: Option<crate::msm::MsmParams>,
}

impl CaseRecord {
    /// The record of a solved case.
    pub fn from_solution(s: &CaseSolution) -> Self {
        Self {
            case_id: s.case_id.clone(),
            axis: s.axis,
            force_n: s.force_n,
            displacements: s.displacements.clone(),
            reaction_n: Some(s.reaction_n),
        }
    }
}

/// Writes `value` as pretty JSON to `path` atomically: a temporary file in the same directory,
/// flushed, then renamed over the target. A failure leaves no partial file behind.
pub fn write_json_atomic<T: Serialize>(path: &Path, value: &T) -> anyhow::Result<()> {
    use anyhow::Context as _;
    let mut text = serde_json::to_string_pretty(value).context("cannot serialise to JSON")?;
    text.push('\n');
    write_atomic(path, text.as_bytes())
}

/// Writes `bytes` to `path` atomically (temporary file in the same directory, then rename).
pub fn write_atomic(path: &Path, bytes: &[u8]) -> anyhow::Result<()> {
    use anyhow::Context as _;
    use std::io::Write as _;
    let dir = match path.parent() {
        Some(d) if !d.as_os_str().is_empty() => d,
        _ => Path::new("."),
    };
    let mut builder = tempfile::Builder::new();
    builder.prefix(".tissue-sim-").suffix(".tmp");
    #[cfg(unix)]
    {
        use std::os::unix::fs::PermissionsExt as _;
        // Like a plain File::create: readable by others (the umask still applies at creation).
        builder.permissions(std::fs::Permissions::from_mode(0o644));
    }
    let mut tmp = builder.tempfile_in(dir).with_context(|| format!("cannot create a file in {}", dir.display()))?;
    tmp.write_all(bytes).with_context(|| format!("cannot write {}", path.display()))?;
    tmp.as_file().sync_all()?;
    tmp.persist(path).with_context(|| format!("cannot write {}", path.display()))?;
    Ok(())
}

/// Reads a JSON file.
pub fn read_json<T: for<'de> Deserialize<'de>>(path: &Path) -> anyhow::Result<T> {
    use anyhow::Context as _;
    let text = std::fs::read_to_string(path).with_context(|| format!("cannot read {}", path.display()))?;
    serde_json::from_str(&text).with_context(|| format!("invalid JSON in {}", path.display()))
}
