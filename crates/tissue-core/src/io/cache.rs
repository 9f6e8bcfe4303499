//! The cache folder's files, looked at before they are opened and before any work: what is in a
//! file's place ([`place`]), whether the folder can keep a new file ([`check_writable`]), one
//! kept file with its one-line messages ([`KeptFile`]), and a computation's report on standard
//! error ([`StderrReport`]).
//!
//! Each kind of kept answer proves itself (its full key and a checksum in the file, checked by
//! its own module); this module sees that nothing blocks on a special file and that no work is
//! lost to a write that fails: a FIFO, a directory or a loop of links in a file's place is never
//! opened, a folder that cannot keep the answer is found before the work, and an answer that
//! cannot be written is used from memory, said in one line.

use std::path::{Path, PathBuf};
use std::time::Instant;

/// What the computation of a kept answer says to its caller, through one callback that returns
/// whether to go on (read after [`CacheEvent::Progress`] only).
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum CacheEvent<'a> {
    /// The work starts.
    Computing {
        /// The cache folder the answer will be kept in, or `None` where it lives in memory only.
        kept_in: Option<&'a Path>,
    },
    /// A further part of the work starts (its progress counts from 0 again).
    Part {
        /// What it computes.
        what: &'a str,
        /// The cache folder it will be kept in, or `None` where it lives in memory only.
        kept_in: Option<&'a Path>,
    },
    /// This fraction of the work (0 to 1) is done; the callback's `false` stops the work.
    Progress(f64),
    /// One line for the user about the cache (a file refused, a folder that cannot keep the
    /// answer, a write that failed), starting with `tissue-sim:`.
    Warning(&'a str),
}

/// What is in a cache file's place, seen from its metadata only (a FIFO is never opened:
/// opening one blocks until a writer comes).
#[derive(Debug, Clone, PartialEq, Eq)]
pub enum Place {
    /// Nothing: a computed answer goes there.
    Empty,
    /// A regular file (perhaps through symbolic links): read, and used if it proves what it is.
    File,
    /// Something never opened nor replaced, and why, as "the file {why}" reads ("is a FIFO,
    /// not a regular file").
    Other(String),
}

/// What is at `path`, from its metadata only.
pub fn place(path: &Path) -> Place {
    use std::io::ErrorKind::NotFound;
    let own = match std::fs::symlink_metadata(path) {
        Ok(m) => m,
        Err(e) if e.kind() == NotFound => return Place::Empty,
        Err(e) => return Place::Other(format!("cannot be examined ({e})")),
    };
    let meta = if own.file_type().is_symlink() {
        match std::fs::metadata(path) {
            Ok(m) => m,
            Err(e) if e.kind() == NotFound => return Place::Other("is a symbolic link to nothing".into()),
            Err(e) => return Place::Other(format!("is a symbolic link that cannot be followed ({e})")),
        }
    } else {
        own
    };
    let ft = meta.file_type();
    if ft.is_file() { Place::File } else { Place::Other(format!("is {}, not a regular file", kind_name(&ft))) }
}

/// What a file that is not a regular file is, in words.
pub(crate) fn kind_name(ft: &std::fs::FileType) -> &'static str {
    if ft.is_dir() {
        return "a directory";
    }
    #[cfg(unix)]
    {
        use std::os::unix::fs::FileTypeExt as _;
        if ft.is_fifo() {
            return "a FIFO";
        }
        if ft.is_socket() {
            return "a socket";
        }
        if ft.is_block_device() || ft.is_char_device() {
            return "a device";
        }
    }
    "a special file"
}

/// Bytes written to the disk by [`check_writable`]'s trial file: enough that a full disk refuses
/// them.
const TRIAL_BYTES: usize = 4096;

/// Checks, before any work, that the cache folder `dir` can keep a new file: creates it where
/// missing, then creates, writes (`TRIAL_BYTES`, flushed to the disk) and removes a temporary
/// file in it, so that a read-only folder or a full disk is found before minutes of computing.
/// Where it cannot, the reason (as "the folder is not writable ({reason})" reads).
pub fn check_writable(dir: &Path) -> Result<(), String> {
    use std::io::Write as _;
    std::fs::create_dir_all(dir).map_err(|e| format!("cannot create it: {e}"))?;
    if !dir.is_dir() {
        return Err("it is not a directory".into());
    }
    let mut trial = tempfile::Builder::new()
        .prefix(".tissue-sim-")
        .suffix(".trial")
        .tempfile_in(dir)
        .map_err(|e| format!("cannot create a file in it: {e}"))?;
    trial
        .write_all(&[0; TRIAL_BYTES])
        .and_then(|()| trial.as_file().sync_all())
        .map_err(|e| format!("cannot write a file in it: {e}"))?;
    trial.close().map_err(|e| format!("cannot remove a file from it: {e}"))
}

/// One file of the cache folder, between a kind of kept answer and the folder: read only where
/// a regular file is there, checked before the work, written atomically after it; each problem
/// is one line for the user (starting with `tissue-sim:`), never an error that throws the
/// computed answer away.
#[derive(Debug, Clone)]
pub struct KeptFile {
    dir: PathBuf,
    path: PathBuf,
    what: String,
}

impl KeptFile {
    /// The file `name` in the cache folder `dir`, holding `what` ("the surface compliance", as
    /// the messages name it).
    pub fn new(dir: &Path, name: &str, what: &str) -> Self {
        Self { dir: dir.to_path_buf(), path: dir.join(name), what: what.to_owned() }
    }

    /// The file's path.
    pub fn path(&self) -> &Path {
        &self.path
    }

    /// The cache folder.
    pub fn dir(&self) -> &Path {
        &self.dir
    }

    /// The file's bytes (at most `max`) where a regular file is there. `Ok(None)` where there is
    /// nothing, or something other than a regular file (never opened; said by
    /// [`KeptFile::check_writable`] before the work); the line to show where it cannot be read.
    pub fn read(&self, max: u64) -> Result<Option<Vec<u8>>, String> {
        if place(&self.path) != Place::File {
            return Ok(None);
        }
        super::read_bytes(&self.path, max).map(Some).map_err(|e| self.refused(&format!("cannot be read ({e:#})")))
    }

    /// The file's text ([`super::read_text`]), as [`KeptFile::read`].
    pub fn read_text(&self) -> Result<Option<String>, String> {
        if place(&self.path) != Place::File {
            return Ok(None);
        }
        super::read_text(&self.path).map(Some).map_err(|e| self.refused(&format!("cannot be read ({e:#})")))
    }

    /// The line for the file refused because it `why` ("is for another material"): it is not
    /// used, and its answer is computed again.
    pub fn refused(&self, why: &str) -> String {
        format!("tissue-sim: cache file {} {why}; computing it again", self.path.display())
    }

    /// Checks, before the work, that the answer can be kept here: the folder writable
    /// ([`check_writable`]), then the place empty or a regular file that may be replaced. Where
    /// not, the line to show: the answer is then computed in memory and not kept.
    pub fn check_writable(&self) -> Result<(), String> {
        let not_kept = format!("{} is computed in memory and not kept", self.what);
        check_writable(&self.dir).map_err(|why| {
            format!("tissue-sim: the cache folder {} is not writable ({why}): {not_kept}", self.dir.display())
        })?;
        match place(&self.path) {
            Place::Other(why) => Err(format!("tissue-sim: cache file {} {why}: {not_kept}", self.path.display())),
            Place::File if std::fs::metadata(&self.path).is_ok_and(|m| m.permissions().readonly()) => {
                Err(format!("tissue-sim: cache file {} is write-protected: {not_kept}", self.path.display()))
            }
            Place::File | Place::Empty => Ok(()),
        }
    }

    /// Writes `bytes` atomically ([`super::write_atomic`]; never into a special file). Where it
    /// fails, the line to show ([`KeptFile::not_kept`]): the answer is then used from memory.
    pub fn write(&self, bytes: &[u8]) -> Result<(), String> {
        if let Place::Other(why) = place(&self.path) {
            return Err(self.not_kept(&format!("the cache file {} {why}", self.path.display())));
        }
        super::write_atomic(&self.path, bytes).map_err(|e| self.not_kept(&format!("{e:#}")))
    }

    /// The line for an answer computed but not written, because of `why`: it is used from memory.
    pub fn not_kept(&self, why: &str) -> String {
        format!("tissue-sim: {} is not kept ({why}): it is used from memory", self.what)
    }
}

/// A computation's report on standard error, for the commands: each warning as it comes, a line
/// when the work starts (what, about how long, where it is kept) and one at each tenth of the
/// work with the time taken. It never stops the work.
#[derive(Debug)]
pub struct StderrReport {
    what: String,
    about: String,
    /// The part of the work under way ([`CacheEvent::Part`]), else `what`.
    part: String,
    started: Option<Instant>,
    next_tenth: u32,
}

impl StderrReport {
    /// The report of computing `what` ("the material's surface compliance"), which takes about
    /// `about` ("40 s").
    pub fn new(what: &str, about: &str) -> Self {
        Self { what: what.to_owned(), about: about.to_owned(), part: what.to_owned(), started: None, next_tenth: 1 }
    }

    /// Says `event` on standard error; `true`: the work goes on.
    pub fn event(&mut self, event: CacheEvent<'_>) -> bool {
        let warning = matches!(event, CacheEvent::Warning(_));
        if let Some(line) = self.line(event) {
            // A warning is said even where progress is silenced (`crate::io::set_quiet`).
            if warning {
                eprintln!("{line}");
            } else {
                crate::io::progress(&line);
            }
        }
        true
    }

    /// The line `event` shows, if any.
    fn line(&mut self, event: CacheEvent<'_>) -> Option<String> {
        match event {
            CacheEvent::Warning(line) => Some(line.to_owned()),
            CacheEvent::Computing { kept_in } => {
                self.started = Some(Instant::now());
                self.next_tenth = 1;
                self.part.clone_from(&self.what);
                let kept = kept_in.map_or_else(|| "not kept".to_owned(), |d| format!("kept in {}", d.display()));
                Some(format!("computing {} (about {}, {kept})", self.what, self.about))
            }
            CacheEvent::Part { what, kept_in } => {
                self.started = Some(Instant::now());
                self.next_tenth = 1;
                what.clone_into(&mut self.part);
                let kept = kept_in.map_or_else(|| "not kept".to_owned(), |d| format!("kept in {}", d.display()));
                Some(format!("computing {what} ({kept})"))
            }
            CacheEvent::Progress(f) => {
                let tenth = (f.clamp(0.0, 1.0) * 10.0 + 1e-9).floor() as u32;
                if tenth < self.next_tenth {
                    return None;
                }
                self.next_tenth = tenth + 1;
                let s = self.started.map_or(0.0, |t| t.elapsed().as_secs_f64());
                Some(format!("{}: {} %, {s:.0} s", self.part, 10 * tenth))
            }
        }
    }
}

#[cfg(all(test, unix))]
mod tests {
    use super::*;

    fn mkfifo(path: &Path) {
        let made = std::process::Command::new("mkfifo").arg(path).status().expect("mkfifo runs");
        assert!(made.success());
    }

    #[test]
    fn places_are_seen_without_opening_them() {
        let dir = tempfile::tempdir().expect("tempdir");
        let at = |name: &str| dir.path().join(name);
        assert_eq!(place(&at("none")), Place::Empty);
        std::fs::write(at("file"), b"x").expect("write");
        assert_eq!(place(&at("file")), Place::File);
        std::os::unix::fs::symlink(at("file"), at("link")).expect("link");
        assert_eq!(place(&at("link")), Place::File);
        std::fs::create_dir(at("dir")).expect("dir");
        assert_eq!(place(&at("dir")), Place::Other("is a directory, not a regular file".into()));
        mkfifo(&at("fifo"));
        assert_eq!(place(&at("fifo")), Place::Other("is a FIFO, not a regular file".into()));
        std::os::unix::fs::symlink(at("loop"), at("loop")).expect("loop");
        assert!(matches!(place(&at("loop")), Place::Other(w) if w.contains("cannot be followed")));
        std::os::unix::fs::symlink(at("none"), at("dangling")).expect("dangling");
        assert_eq!(place(&at("dangling")), Place::Other("is a symbolic link to nothing".into()));
    }

    #[test]
    fn a_folder_is_created_and_tried_before_the_work() {
        let dir = tempfile::tempdir().expect("tempdir");
        let nested = dir.path().join("a/b/tissue-sim");
        assert_eq!(check_writable(&nested), Ok(()));
        assert!(nested.is_dir());
        assert_eq!(std::fs::read_dir(&nested).expect("read").count(), 0, "the trial file is removed");
        std::fs::write(dir.path().join("file"), b"x").expect("write");
        let why = check_writable(&dir.path().join("file/tissue-sim")).expect_err("under a file");
        assert!(why.starts_with("cannot create it"), "{why}");
    }

    #[test]
    fn a_kept_file_round_trips_and_a_fifo_is_never_opened() {
        let dir = tempfile::tempdir().expect("tempdir");
        let kept = KeptFile::new(dir.path(), "x.bin", "the answer");
        assert_eq!(kept.read(100), Ok(None));
        assert_eq!(kept.check_writable(), Ok(()));
        assert_eq!(kept.write(b"abc"), Ok(()));
        assert_eq!(kept.read(100), Ok(Some(b"abc".to_vec())));
        assert!(kept.read(2).expect_err("above the bound").contains("cannot be read"));
        std::fs::remove_file(kept.path()).expect("remove");
        mkfifo(kept.path());
        // Each returns at once: nothing opens the FIFO.
        assert_eq!(kept.read(100), Ok(None));
        assert_eq!(kept.read_text(), Ok(None));
        let line = kept.check_writable().expect_err("a FIFO");
        assert_eq!(
            line,
            format!(
                "tissue-sim: cache file {} is a FIFO, not a regular file: the answer is computed in memory and not kept",
                kept.path().display()
            )
        );
        assert!(kept.write(b"abc").expect_err("a FIFO").contains("is a FIFO"));
        assert!(kept.refused("is for another material").ends_with("x.bin is for another material; computing it again"));
    }

    #[test]
    fn the_report_says_the_start_and_each_tenth_once() {
        let mut r = StderrReport::new("the thing", "40 s");
        let dir = Path::new("/x");
        assert_eq!(
            r.line(CacheEvent::Computing { kept_in: Some(dir) }).as_deref(),
            Some("computing the thing (about 40 s, kept in /x)")
        );
        let lines: Vec<Option<String>> =
            [0.0, 0.05, 0.12, 0.15, 0.37, 1.0].iter().map(|&f| r.line(CacheEvent::Progress(f))).collect();
        let tenths: Vec<bool> = lines.iter().map(Option::is_some).collect();
        assert_eq!(tenths, [false, false, true, false, true, true]);
        assert!(lines[4].as_deref().is_some_and(|l| l.starts_with("the thing: 30 %, ")), "{lines:?}");
        assert_eq!(r.line(CacheEvent::Warning("tissue-sim: w")).as_deref(), Some("tissue-sim: w"));
        assert_eq!(
            r.line(CacheEvent::Computing { kept_in: None }).as_deref(),
            Some("computing the thing (about 40 s, not kept)")
        );
    }
}
