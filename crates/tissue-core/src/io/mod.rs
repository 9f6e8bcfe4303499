//! Layer 0, files and numbers: bounded reading ([`read`]), atomic writing and output folders
//! ([`write`](mod@write)), temporary outputs removed on a signal ([`pending`]), the cache folder's
//! files checked before they are opened and before any work ([`cache`]), and numbers and messages
//! as the user reads them ([`message`]). May use nothing else of the crate.

pub mod cache;
pub mod message;
pub mod pending;
pub mod read;
pub mod shape;
pub mod write;

pub use message::{brief_line, length, num, progress, quiet, set_quiet};
pub use pending::{interrupt, interrupted, on_interrupt, remove_pending};
pub use read::{MAX_INPUT_BYTES, read_bytes, read_json, read_text};
pub use write::{MAX_OUTPUT_BYTES, OutputDir, check_output, write_atomic, write_json_atomic, write_json_compact};

/// A stable key of `salt` and `values` (their bits, FxHash) for a file kept in the cache folder:
/// the same inputs give the same name on every run and machine.
pub fn cache_key<'a>(salt: impl std::hash::Hash, values: impl IntoIterator<Item = &'a f64>) -> u64 {
    use std::hash::{Hash as _, Hasher as _};
    let mut hasher = rustc_hash::FxHasher::default();
    salt.hash(&mut hasher);
    values.into_iter().for_each(|v| v.to_bits().hash(&mut hasher));
    hasher.finish()
}

/// The default cache folder: `$XDG_CACHE_HOME/tissue-sim`, else `$HOME/.cache/tissue-sim`.
pub fn cache_dir() -> Option<std::path::PathBuf> {
    let from = |v: &str| std::env::var_os(v).filter(|s| !s.is_empty()).map(std::path::PathBuf::from);
    from("XDG_CACHE_HOME").or_else(|| from("HOME").map(|h| h.join(".cache"))).map(|d| d.join("tissue-sim"))
}
