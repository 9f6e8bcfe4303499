//! Temporary outputs in flight, removed when a signal ends the process.

use std::path::{Path, PathBuf};

/// Temporary files and directories being written, removed by [`remove_pending`] when a signal
/// ends the process before they are renamed into place.
static PENDING: std::sync::Mutex<Vec<PathBuf>> = std::sync::Mutex::new(Vec::new());

/// A temporary path listed in [`PENDING`] while it lives.
pub(super) struct Pending(PathBuf);

impl Pending {
    pub(super) fn track(path: &Path) -> Self {
        if let Ok(mut p) = PENDING.lock() {
            p.push(path.to_path_buf());
        }
        Self(path.to_path_buf())
    }
}

impl Drop for Pending {
    fn drop(&mut self) {
        if let Ok(mut p) = PENDING.lock() {
            p.retain(|q| q != &self.0);
        }
    }
}

/// What takes the first SIGINT or SIGTERM instead of the exit (the viewer, to write its recording
/// and close); a second signal exits.
type Hook = Box<dyn Fn() + Send>;
static HOOK: std::sync::Mutex<Option<Hook>> = std::sync::Mutex::new(None);
static INTERRUPTED: std::sync::atomic::AtomicBool = std::sync::atomic::AtomicBool::new(false);

/// Sets what the first SIGINT or SIGTERM calls instead of ending the process ([`interrupt`]).
pub fn on_interrupt(hook: Hook) {
    if let Ok(mut h) = HOOK.lock() {
        *h = Some(hook);
    }
}

/// What a signal handler calls first: `true` when a hook set by [`on_interrupt`] took the
/// signal (the first one only), `false` when the process should end now.
pub fn interrupt() -> bool {
    if INTERRUPTED.swap(true, std::sync::atomic::Ordering::SeqCst) {
        return false;
    }
    match HOOK.lock().ok().and_then(|mut h| h.take()) {
        Some(hook) => {
            hook();
            true
        }
        None => false,
    }
}

/// Whether a signal asked the process to end.
pub fn interrupted() -> bool {
    INTERRUPTED.load(std::sync::atomic::Ordering::SeqCst)
}

/// Removes every temporary file and directory still being written: what a signal handler calls
/// before the process exits (SIGINT, SIGTERM), so that an interrupted write leaves nothing behind.
pub fn remove_pending() {
    let paths = match PENDING.lock() {
        Ok(mut p) => std::mem::take(&mut *p),
        Err(_) => return,
    };
    for p in paths {
        if p.is_dir() {
            let _ = std::fs::remove_dir_all(&p);
        } else {
            let _ = std::fs::remove_file(&p);
        }
    }
}

#[cfg(all(test, unix))]
mod tests {
    use super::*;

    #[test]
    fn pending_temporaries_are_removed() {
        let dir = tempfile::tempdir().unwrap();
        let file = dir.path().join(".tissue-sim-x.tmp");
        std::fs::write(&file, b"partial").unwrap();
        let sub = dir.path().join(".tissue-sim-d");
        std::fs::create_dir(&sub).unwrap();
        let (_a, _b) = (Pending::track(&file), Pending::track(&sub));
        remove_pending();
        assert!(!file.exists() && !sub.exists());
        drop(_a);
        assert!(PENDING.lock().unwrap().iter().all(|p| p != &file));
    }
}
