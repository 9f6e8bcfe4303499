//! Input files, read through one bounded path.

use std::path::Path;

use anyhow::Context as _;
use serde::Deserialize;

/// Reads a JSON file (at most [`MAX_INPUT_BYTES`]).
pub fn read_json<T: for<'de> Deserialize<'de>>(path: &Path) -> anyhow::Result<T> {
    let text = read_text(path)?;
    // The key an error is at, trailing data refused ([`crate::io::shape`]).
    crate::io::shape::from_json(&text).map_err(|e| anyhow::anyhow!("invalid JSON in {}: {e}", path.display()))
}

/// Largest input file read, bytes.
pub const MAX_INPUT_BYTES: u64 = 16 << 20;

/// Reads a text file of at most [`MAX_INPUT_BYTES`].
pub fn read_text(path: &Path) -> anyhow::Result<String> {
    use std::io::Read as _;
    let mut text = String::new();
    open_bounded(path, MAX_INPUT_BYTES)?.read_to_string(&mut text).with_context(|| cannot_read(path))?;
    check_len(path, text.len(), MAX_INPUT_BYTES, "the input bound")?;
    Ok(text)
}

/// Reads a binary file of at most `max` bytes (a cache file the program wrote).
pub fn read_bytes(path: &Path, max: u64) -> anyhow::Result<Vec<u8>> {
    use std::io::Read as _;
    let mut bytes = Vec::new();
    open_bounded(path, max)?.read_to_end(&mut bytes).with_context(|| cannot_read(path))?;
    check_len(path, bytes.len(), max, "the bound")?;
    Ok(bytes)
}

fn cannot_read(path: &Path) -> String {
    format!("cannot read {}", path.display())
}

/// The one bounded opening: a file (a directory refused by name), read to at most `max + 1`
/// bytes so that a longer one is seen.
fn open_bounded(path: &Path, max: u64) -> anyhow::Result<std::io::Take<std::fs::File>> {
    use std::io::Read as _;
    // Looked at before it is opened: opening a FIFO would wait for a writer.
    let kind = std::fs::metadata(path).with_context(|| cannot_read(path))?.file_type();
    if !kind.is_file() {
        anyhow::bail!("cannot read {}: it is {}, not a regular file", path.display(), crate::io::cache::kind_name(&kind));
    }
    let f = std::fs::File::open(path).with_context(|| cannot_read(path))?;
    Ok(f.take(max + 1))
}

/// Refuses what was read beyond `max` bytes, naming the `bound`.
fn check_len(path: &Path, len: usize, max: u64, bound: &str) -> anyhow::Result<()> {
    if len as u64 > max {
        anyhow::bail!("{} is larger than {bound} of {} MB", path.display(), max >> 20);
    }
    Ok(())
}

#[cfg(all(test, unix))]
mod tests {
    use super::*;

    #[test]
    fn endless_inputs_are_refused_before_they_are_opened() {
        let e = read_text(Path::new("/dev/zero")).unwrap_err();
        assert!(format!("{e:#}").contains("is a device, not a regular file"), "{e:#}");
    }
}
