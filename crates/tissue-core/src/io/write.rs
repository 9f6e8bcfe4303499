//! Output files, written atomically and never a hazard: standard output, special files, links,
//! protected files, output directories that appear whole.

use std::path::{Path, PathBuf};

use serde::Serialize;

use super::pending::Pending;

/// Largest file any command writes, bytes: a bound no input can exceed (a result over it is an
/// error naming the bound, and nothing is written).
pub const MAX_OUTPUT_BYTES: usize = 256 << 20;

/// Writes `value` as pretty JSON to `path` with [`write_atomic`].
pub fn write_json_atomic<T: Serialize>(path: &Path, value: &T) -> anyhow::Result<()> {
    use anyhow::Context as _;
    let mut text = serde_json::to_string_pretty(value).context("cannot serialise to JSON")?;
    text.push('\n');
    write_atomic(path, text.as_bytes())
}

/// Writes `value` as compact JSON (one line) to `path` with [`write_atomic`].
pub fn write_json_compact<T: Serialize>(path: &Path, value: &T) -> anyhow::Result<()> {
    use anyhow::Context as _;
    let mut text = serde_json::to_string(value).context("cannot serialise to JSON")?;
    text.push('\n');
    write_atomic(path, text.as_bytes())
}

/// Where an output path leads.
#[derive(Debug, PartialEq)]
enum Target {
    /// Standard output (`-`).
    Stdout,
    /// A device, fifo or socket, or a descriptor alias such as `/dev/stdout`: written in place.
    Special(PathBuf),
    /// A regular file, or nothing yet: written atomically at this path (symlinks followed).
    Regular(PathBuf),
}

/// `/dev/stdout`, `/dev/stderr`, `/dev/fd/N`, `/proc/self/fd/N`: whatever the descriptor is (a
/// terminal, a pipe, or a file the shell opened with `>`), it is written through, never replaced.
fn is_descriptor_alias(p: &Path) -> bool {
    p == Path::new("/dev/stdout")
        || p == Path::new("/dev/stderr")
        || p.starts_with("/dev/fd")
        || p.starts_with("/proc/self/fd")
        || p.starts_with("/proc/thread-self/fd")
}

/// Follows `path` through symbolic links (also dangling ones) to the path that will be written.
fn resolve(path: &Path) -> anyhow::Result<Target> {
    use anyhow::{Context as _, bail};
    if path.as_os_str() == "-" {
        return Ok(Target::Stdout);
    }
    let mut p = path.to_path_buf();
    for _ in 0..40 {
        if ["/dev/stdout", "/dev/fd/1", "/proc/self/fd/1"].iter().any(|a| p == Path::new(a)) {
            // Whatever standard output is (a terminal, a pipe, a file opened with `>` or `>>`).
            return Ok(Target::Stdout);
        }
        if is_descriptor_alias(&p) {
            return Ok(Target::Special(p));
        }
        let meta = match std::fs::symlink_metadata(&p) {
            Ok(m) => m,
            Err(e) if e.kind() == std::io::ErrorKind::NotFound => return Ok(Target::Regular(p)),
            Err(e) => return Err(e).with_context(|| format!("cannot write {}", path.display())),
        };
        let ft = meta.file_type();
        if ft.is_symlink() {
            let link = std::fs::read_link(&p).with_context(|| format!("cannot follow the link {}", p.display()))?;
            p = match p.parent() {
                Some(parent) if link.is_relative() => parent.join(link),
                _ => link,
            };
            continue;
        }
        if ft.is_dir() {
            bail!("cannot write {}: it is a directory", path.display());
        }
        if ft.is_file() {
            return Ok(Target::Regular(p));
        }
        return Ok(Target::Special(p));
    }
    bail!("cannot write {}: too many levels of symbolic links", path.display())
}

/// Checks, before any work, that `path` can be written as [`write_atomic`] will: standard output,
/// a special file, or a regular file (new or replaceable) in an existing directory. A new file's
/// folder must take a file: a trial file is created and removed (a read-only folder, or one
/// under `/proc`, is found here, not after the work).
pub fn check_output(path: &Path) -> anyhow::Result<()> {
    use anyhow::Context as _;
    match resolve(path)? {
        Target::Stdout | Target::Special(_) => Ok(()),
        Target::Regular(target) => {
            let (_, dir) = check_regular(path, &target)?;
            tempfile::Builder::new().prefix(".tissue-sim-").tempfile_in(dir).with_context(|| {
                format!("cannot write {}: the folder {} does not take a new file", path.display(), dir.display())
            })?;
            Ok(())
        }
    }
}

/// The checks on a regular output file `target` (written as `path`): a replaced file must be
/// writable, a new one needs an existing directory. Its metadata, if it exists, and its directory.
fn check_regular<'a>(path: &Path, target: &'a Path) -> anyhow::Result<(Option<std::fs::Metadata>, &'a Path)> {
    use anyhow::{Context as _, bail};
    let existing = match std::fs::metadata(target) {
        Ok(m) => Some(m),
        Err(e) if e.kind() == std::io::ErrorKind::NotFound => None,
        Err(e) => return Err(e).with_context(|| format!("cannot write {}", path.display())),
    };
    if let Some(m) = &existing {
        if m.permissions().readonly() {
            bail!("refusing to overwrite {}: the file is write-protected", path.display());
        }
        // Permission to write the file itself, not only its directory.
        if let Err(e) = std::fs::OpenOptions::new().write(true).open(target) {
            return Err(e).with_context(|| format!("cannot overwrite {}", path.display()));
        }
    }
    let dir = match target.parent() {
        Some(d) if !d.as_os_str().is_empty() => d,
        _ => Path::new("."),
    };
    if !dir.is_dir() {
        bail!("cannot write {}: the directory {} does not exist", path.display(), dir.display());
    }
    Ok((existing, dir))
}

/// Whether standard output was closed when the process started: the Rust runtime then reopens
/// it on the null device, read-write, which a shell's `> /dev/null` (write-only) never does.
fn stdout_was_closed() -> bool {
    #[cfg(target_os = "linux")]
    {
        let null = std::fs::read_link("/proc/self/fd/1").is_ok_and(|p| p == Path::new("/dev/null"));
        let read_write = std::fs::read_to_string("/proc/self/fdinfo/1").is_ok_and(|info| {
            info.lines()
                .find_map(|l| l.strip_prefix("flags:"))
                .and_then(|f| u32::from_str_radix(f.trim(), 8).ok())
                .is_some_and(|flags| flags & 0o3 == 0o2)
        });
        null && read_write
    }
    #[cfg(not(target_os = "linux"))]
    false
}

/// Writes `bytes` to `path` without ever damaging what `path` names:
/// - `-` writes to standard output; a device, fifo or socket (`/dev/null`, say), and a
///   descriptor alias (`/dev/stdout`, `/dev/fd/N`), is opened and written in place;
/// - a symbolic link is followed, and its target written;
/// - a regular file (or a new one) is written atomically: a temporary file in the same
///   directory, flushed, then renamed over the target, so a failure leaves no partial file. A
///   replaced file keeps its permissions (and, where allowed, its owner); a write-protected file
///   is refused, even for root.
pub fn write_atomic(path: &Path, bytes: &[u8]) -> anyhow::Result<()> {
    use anyhow::{Context as _, bail};
    use std::io::Write as _;
    if bytes.len() > MAX_OUTPUT_BYTES {
        bail!(
            "refusing to write {}: the output would be {} MB, above the bound of {} MB",
            path.display(),
            bytes.len() >> 20,
            MAX_OUTPUT_BYTES >> 20
        );
    }
    let target = match resolve(path)? {
        Target::Stdout => {
            // Through a duplicate of the descriptor: the standard handle reports success on a
            // closed descriptor (EBADF), which would lose the output without a word.
            if stdout_was_closed() {
                bail!("cannot write to standard output: it was closed when the program started");
            }
            let stdout = std::io::stdout();
            #[cfg(unix)]
            let (_lock, mut out) = {
                use std::os::fd::AsFd as _;
                let fd = stdout.as_fd().try_clone_to_owned().context("cannot write to standard output")?;
                (stdout.lock(), std::fs::File::from(fd))
            };
            #[cfg(not(unix))]
            let mut out = stdout.lock();
            out.write_all(bytes).and_then(|()| out.flush()).context("cannot write to standard output")?;
            return Ok(());
        }
        Target::Special(p) => {
            let mut f = std::fs::OpenOptions::new()
                .write(true)
                .open(&p)
                .with_context(|| format!("cannot open {} for writing", path.display()))?;
            f.write_all(bytes).with_context(|| format!("cannot write {}", path.display()))?;
            return Ok(());
        }
        Target::Regular(p) => p,
    };
    stage(path, &target, bytes)?.persist()
}

/// A regular file's new content, written and flushed to a temporary file beside its target and
/// not yet in its place ([`Staged::persist`]).
struct Staged {
    path: PathBuf,
    target: PathBuf,
    existed: bool,
    tmp: tempfile::NamedTempFile,
    _pending: Pending,
}

impl Staged {
    /// Renames the staged file over its target.
    fn persist(self) -> anyhow::Result<()> {
        use anyhow::Context as _;
        let Self { path, target, tmp, _pending, .. } = self;
        tmp.persist(&target).map_err(|e| e.error).with_context(|| format!("cannot write {}", path.display()))?;
        Ok(())
    }
}

/// Writes `bytes` for the regular file `target` (written as `path`) into a temporary file in its
/// directory, flushed: a full disk or a refused file fails here, with the target untouched.
fn stage(path: &Path, target: &Path, bytes: &[u8]) -> anyhow::Result<Staged> {
    use anyhow::Context as _;
    use std::io::Write as _;
    let (existing, dir) = check_regular(path, target)?;
    let mut builder = tempfile::Builder::new();
    builder.prefix(".tissue-sim-").suffix(".tmp");
    #[cfg(unix)]
    {
        use std::os::unix::fs::PermissionsExt as _;
        // A new file like a plain File::create (the umask applies); a replaced file keeps its mode.
        let mode = existing.as_ref().map_or(0o644, |m| m.permissions().mode() & 0o7777);
        builder.permissions(std::fs::Permissions::from_mode(mode));
    }
    let mut tmp = builder
        .tempfile_in(dir)
        .with_context(|| format!("cannot write {}: cannot create a file in {}", path.display(), dir.display()))?;
    let pending = Pending::track(tmp.path());
    #[cfg(unix)]
    if let Some(m) = &existing {
        use std::os::unix::fs::{MetadataExt as _, PermissionsExt as _};
        // The umask may have cleared bits at creation: set the mode exactly, and the owner where
        // this process may (root replacing another user's file).
        let _ = tmp.as_file().set_permissions(std::fs::Permissions::from_mode(m.mode() & 0o7777));
        let _ = std::os::unix::fs::fchown(tmp.as_file(), Some(m.uid()), Some(m.gid()));
    }
    tmp.write_all(bytes).with_context(|| format!("cannot write {}", path.display()))?;
    tmp.as_file().sync_all().with_context(|| format!("cannot write {}", path.display()))?;
    Ok(Staged { path: path.to_path_buf(), target: target.to_path_buf(), existed: existing.is_some(), tmp, _pending: pending })
}

/// A set of files for one output directory, written only once all of them exist: into a fresh
/// sibling directory that is then renamed into place (or, when the directory already exists,
/// each file atomically into it). An interrupted command leaves no half-written directory.
#[derive(Debug, Default)]
pub struct OutputDir {
    files: Vec<(String, Vec<u8>)>,
}

impl OutputDir {
    /// Checks, before any work, that `dir` can be written: an existing directory, or a path
    /// whose parent directory exists.
    pub fn check(dir: &Path) -> anyhow::Result<()> {
        use anyhow::bail;
        match std::fs::metadata(dir) {
            Ok(m) if m.is_dir() => Ok(()),
            Ok(_) => bail!("cannot write to {}: it exists and is not a directory", dir.display()),
            Err(_) => {
                let parent = match dir.parent() {
                    Some(p) if !p.as_os_str().is_empty() => p,
                    _ => Path::new("."),
                };
                if parent.is_dir() {
                    Ok(())
                } else {
                    bail!("cannot create {}: its parent directory {} does not exist", dir.display(), parent.display())
                }
            }
        }
    }

    /// Checks, before any work, that the set `names` can be written into `dir` as
    /// [`OutputDir::commit`] will: [`OutputDir::check`], the folder that will hold them writable
    /// (a trial file created and removed), and each name that exists replaceable (a regular
    /// file, not write-protected, or a special file written in place).
    pub fn check_names(dir: &Path, names: &[&str]) -> anyhow::Result<()> {
        use anyhow::Context as _;
        Self::check(dir)?;
        let holder = if dir.is_dir() {
            dir
        } else {
            match dir.parent() {
                Some(p) if !p.as_os_str().is_empty() => p,
                _ => Path::new("."),
            }
        };
        tempfile::Builder::new()
            .prefix(".tissue-sim-")
            .tempfile_in(holder)
            .with_context(|| format!("cannot write to {}: the folder is not writable", holder.display()))?;
        if dir.is_dir() {
            for name in names {
                check_output(&dir.join(name))?;
            }
        }
        Ok(())
    }

    /// Adds a file (a plain name, no directories).
    pub fn add(&mut self, name: impl Into<String>, bytes: impl Into<Vec<u8>>) {
        self.files.push((name.into(), bytes.into()));
    }

    /// Writes every file into `dir`, as a set: a new directory is filled beside it and renamed
    /// into place; into an existing one every file is first written beside its target (a full
    /// disk or a refused name fails there, nothing replaced), then each renamed over it, the old
    /// files kept as hard links until all are in place and put back if a rename fails. Special
    /// files in the folder (a FIFO) are written in place, last.
    pub fn commit(&self, dir: &Path) -> anyhow::Result<()> {
        use anyhow::Context as _;
        Self::check(dir)?;
        if dir.is_dir() {
            return self.commit_into(dir);
        }
        let parent = match dir.parent() {
            Some(p) if !p.as_os_str().is_empty() => p,
            _ => Path::new("."),
        };
        let tmp = tempfile::Builder::new()
            .prefix(".tissue-sim-")
            .tempdir_in(parent)
            .with_context(|| format!("cannot create a directory in {}", parent.display()))?;
        let _pending = Pending::track(tmp.path());
        for (name, bytes) in &self.files {
            write_atomic(&tmp.path().join(name), bytes)?;
        }
        #[cfg(unix)]
        {
            use std::os::unix::fs::PermissionsExt as _;
            let _ = std::fs::set_permissions(tmp.path(), std::fs::Permissions::from_mode(0o755));
        }
        let kept = tmp.keep();
        if let Err(e) = std::fs::rename(&kept, dir) {
            let _ = std::fs::remove_dir_all(&kept);
            return Err(e).with_context(|| format!("cannot create {}", dir.display()));
        }
        Ok(())
    }

    /// [`OutputDir::commit`] into the existing directory `dir`.
    fn commit_into(&self, dir: &Path) -> anyhow::Result<()> {
        use anyhow::{Context as _, bail};
        for (name, bytes) in &self.files {
            if bytes.len() > MAX_OUTPUT_BYTES {
                bail!("refusing to write {}: the output would be {} MB", dir.join(name).display(), bytes.len() >> 20);
            }
        }
        // Every regular file staged first; any failure here leaves the folder as it was.
        let mut staged = Vec::new();
        let mut special = Vec::new();
        for (name, bytes) in &self.files {
            let path = dir.join(name);
            match resolve(&path)? {
                Target::Regular(target) => staged.push(stage(&path, &target, bytes)?),
                Target::Special(_) | Target::Stdout => special.push((path, bytes)),
            }
        }
        // The old files kept under other names until the new ones are all in place.
        let mut backups: Vec<Option<PathBuf>> = Vec::with_capacity(staged.len());
        for s in &staged {
            let backup = if s.existed {
                let b = s.tmp.path().with_extension("old");
                std::fs::hard_link(&s.target, &b)
                    .with_context(|| format!("cannot write {}: cannot keep the old file", s.path.display()))?;
                Some(b)
            } else {
                None
            };
            backups.push(backup);
        }
        let guards: Vec<Pending> = backups.iter().flatten().map(|b| Pending::track(b)).collect();
        let mut placed: Vec<(PathBuf, Option<PathBuf>)> = Vec::new();
        for (s, backup) in staged.into_iter().zip(&backups) {
            let target = s.target.clone();
            if let Err(e) = s.persist() {
                // Put back what was replaced, remove what was new.
                for (t, b) in placed.iter().rev() {
                    match b {
                        Some(b) => drop(std::fs::rename(b, t)),
                        None => drop(std::fs::remove_file(t)),
                    }
                }
                for b in backups.iter().flatten() {
                    let _ = std::fs::remove_file(b);
                }
                return Err(e);
            }
            placed.push((target, backup.clone()));
        }
        for b in backups.iter().flatten() {
            let _ = std::fs::remove_file(b);
        }
        drop(guards);
        for (path, bytes) in special {
            write_atomic(&path, bytes)?;
        }
        Ok(())
    }
}

#[cfg(all(test, unix))]
mod tests {
    use super::*;
    use std::os::unix::fs::PermissionsExt as _;

    #[test]
    fn a_symlink_is_followed_not_replaced() {
        let dir = tempfile::tempdir().expect("tempdir");
        let real = dir.path().join("real.json");
        std::fs::write(&real, "old").expect("write");
        let link = dir.path().join("link.json");
        std::os::unix::fs::symlink(&real, &link).expect("symlink");
        write_atomic(&link, b"new").expect("write through the link");
        assert!(std::fs::symlink_metadata(&link).expect("meta").file_type().is_symlink(), "the link was replaced");
        assert_eq!(std::fs::read_to_string(&real).expect("read"), "new");
        // A dangling link creates its target.
        let target = dir.path().join("later.json");
        let dangling = dir.path().join("dangling.json");
        std::os::unix::fs::symlink("later.json", &dangling).expect("symlink");
        write_atomic(&dangling, b"x").expect("write through a dangling link");
        assert!(std::fs::symlink_metadata(&dangling).expect("meta").file_type().is_symlink());
        assert_eq!(std::fs::read_to_string(&target).expect("read"), "x");
    }

    #[test]
    fn a_fifo_is_written_in_place() {
        let dir = tempfile::tempdir().expect("tempdir");
        let fifo = dir.path().join("out.fifo");
        let made = std::process::Command::new("mkfifo").arg(&fifo).status().expect("mkfifo runs");
        assert!(made.success());
        let reader = {
            let fifo = fifo.clone();
            std::thread::spawn(move || std::fs::read_to_string(fifo).expect("read fifo"))
        };
        write_atomic(&fifo, b"through the pipe").expect("write to a fifo");
        assert_eq!(reader.join().expect("reader"), "through the pipe");
        let meta = std::fs::symlink_metadata(&fifo).expect("meta");
        assert!(!meta.file_type().is_file(), "the fifo was replaced by a regular file");
        // A symlink to a device is followed to the device, which stays a device.
        let null_link = dir.path().join("null");
        std::os::unix::fs::symlink("/dev/null", &null_link).expect("symlink");
        write_atomic(&null_link, b"discarded").expect("write to /dev/null through a link");
        assert!(!std::fs::metadata("/dev/null").expect("meta").is_file(), "/dev/null became a regular file");
    }

    #[test]
    fn a_write_protected_file_is_refused_and_a_replaced_file_keeps_its_mode() {
        let dir = tempfile::tempdir().expect("tempdir");
        let locked = dir.path().join("locked.json");
        std::fs::write(&locked, "keep me").expect("write");
        std::fs::set_permissions(&locked, std::fs::Permissions::from_mode(0o444)).expect("chmod");
        let e = write_atomic(&locked, b"clobbered").expect_err("write-protected");
        assert!(format!("{e:#}").contains("write-protected"), "{e:#}");
        assert_eq!(std::fs::read_to_string(&locked).expect("read"), "keep me");
        let private = dir.path().join("private.json");
        std::fs::write(&private, "old").expect("write");
        std::fs::set_permissions(&private, std::fs::Permissions::from_mode(0o600)).expect("chmod");
        write_atomic(&private, b"new").expect("write");
        let mode = std::fs::metadata(&private).expect("meta").permissions().mode() & 0o777;
        assert_eq!(mode, 0o600);
        assert_eq!(std::fs::read_to_string(&private).expect("read"), "new");
        // A directory is refused by name; an oversized output is refused before writing.
        assert!(format!("{:#}", write_atomic(dir.path(), b"x").expect_err("dir")).contains("directory"));
        let big = vec![b' '; MAX_OUTPUT_BYTES + 1];
        let e = write_atomic(&dir.path().join("big"), &big).expect_err("too big");
        assert!(format!("{e:#}").contains("bound"), "{e:#}");
        assert!(!dir.path().join("big").exists());
    }

    #[test]
    fn an_output_directory_appears_whole() {
        let dir = tempfile::tempdir().expect("tempdir");
        let out = dir.path().join("report");
        let mut files = OutputDir::default();
        files.add("a.md", "a");
        files.add("b.csv", "b");
        assert!(!out.exists());
        files.commit(&out).expect("commit");
        assert_eq!(std::fs::read_to_string(out.join("b.csv")).expect("read"), "b");
        files.commit(&out).expect("commit into an existing directory");
        let names: Vec<_> = std::fs::read_dir(dir.path()).expect("ls").map(|e| e.expect("entry").file_name()).collect();
        assert_eq!(names.len(), 1, "a temporary directory was left behind: {names:?}");
        assert!(OutputDir::check(&dir.path().join("missing/report")).is_err());
    }

    #[test]
    fn a_set_into_an_existing_folder_is_written_whole_or_not_at_all() {
        let dir = tempfile::tempdir().expect("tempdir");
        std::fs::write(dir.path().join("a.txt"), "old a").expect("write");
        std::fs::write(dir.path().join("b.txt"), "old b").expect("write");
        let mut set = OutputDir::default();
        set.add("a.txt", "new a");
        set.add("b.txt", "new b");
        set.add("c.txt", "new c");
        std::fs::set_permissions(dir.path().join("b.txt"), std::fs::Permissions::from_mode(0o444)).expect("chmod");
        let e = set.commit(dir.path()).expect_err("b is write-protected");
        assert!(format!("{e:#}").contains("write-protected"), "{e:#}");
        let listed = |d: &Path| {
            let mut names: Vec<String> =
                std::fs::read_dir(d).expect("listed").map(|e| e.expect("entry").file_name().into_string().expect("utf8")).collect();
            names.sort();
            names
        };
        assert_eq!(listed(dir.path()), ["a.txt", "b.txt"], "nothing new and nothing left behind");
        assert_eq!(std::fs::read_to_string(dir.path().join("a.txt")).expect("read"), "old a");
        std::fs::set_permissions(dir.path().join("b.txt"), std::fs::Permissions::from_mode(0o644)).expect("chmod");
        set.commit(dir.path()).expect("the whole set");
        assert_eq!(listed(dir.path()), ["a.txt", "b.txt", "c.txt"]);
        for n in ["a", "b", "c"] {
            assert_eq!(std::fs::read_to_string(dir.path().join(format!("{n}.txt"))).expect("read"), format!("new {n}"));
        }
        assert!(OutputDir::check_names(dir.path(), &["a.txt", "b.txt"]).is_ok());
    }
}
