//! Input files, read through one bounded path.

use std::path::Path;

use serde::Deserialize;

/// Reads a JSON file (at most [`MAX_INPUT_BYTES`]).
pub fn read_json<T: for<'de> Deserialize<'de>>(path: &Path) -> anyhow::Result<T> {
    use anyhow::Context as _;
    let text = read_text(path)?;
    serde_json::from_str(&text).with_context(|| format!("invalid JSON in {}", path.display()))
}

/// Largest input file read, bytes.
pub const MAX_INPUT_BYTES: u64 = 16 << 20;

/// Reads a text file of at most [`MAX_INPUT_BYTES`].
pub fn read_text(path: &Path) -> anyhow::Result<String> {
    use anyhow::{Context as _, bail};
    use std::io::Read as _;
    let f = std::fs::File::open(path).with_context(|| format!("cannot read {}", path.display()))?;
    if f.metadata().is_ok_and(|m| m.is_dir()) {
        bail!("cannot read {}: it is a directory", path.display());
    }
    let mut text = String::new();
    f.take(MAX_INPUT_BYTES + 1).read_to_string(&mut text).with_context(|| format!("cannot read {}", path.display()))?;
    if text.len() as u64 > MAX_INPUT_BYTES {
        bail!("{} is larger than the input bound of {} MB", path.display(), MAX_INPUT_BYTES >> 20);
    }
    Ok(text)
}

/// Reads a binary file of at most `max` bytes (a cache file the program wrote).
pub fn read_bytes(path: &Path, max: u64) -> anyhow::Result<Vec<u8>> {
    use anyhow::{Context as _, bail};
    use std::io::Read as _;
    let f = std::fs::File::open(path).with_context(|| format!("cannot read {}", path.display()))?;
    if f.metadata().is_ok_and(|m| m.is_dir()) {
        bail!("cannot read {}: it is a directory", path.display());
    }
    let mut bytes = Vec::new();
    f.take(max + 1).read_to_end(&mut bytes).with_context(|| format!("cannot read {}", path.display()))?;
    if bytes.len() as u64 > max {
        bail!("{} is larger than the bound of {} MB", path.display(), max >> 20);
    }
    Ok(bytes)
}

#[cfg(all(test, unix))]
mod tests {
    use super::*;

    #[test]
    fn endless_inputs_are_refused_at_the_bound() {
        let e = read_text(Path::new("/dev/zero")).unwrap_err();
        assert!(format!("{e:#}").contains("input bound"), "{e:#}");
    }
}
