//! The source watcher: file-system events in, coalesced and content-checked
//! [`Event::FilesChanged`] batches out.
//!
//! Roots are always watched as directories, recursively, never as single
//! files: editors that save by writing a temporary file and renaming it over
//! the target replace the inode, and a watch on the old inode would go quiet.
//!
//! Raw notify events go to a debounce thread (the rules, free of the file
//! system, in `debounce`) that collects the source paths
//! they name, with what the newest event says about each: the save is
//! *complete* (the writer closed the file, or a finished file was renamed
//! onto the path), the file is *being written* (data changed, not closed
//! yet), or it is *unsettled* (created, removed, renamed away, a directory,
//! lost events). When the batch is flushed, every path is read and hashed
//! and only files whose content actually changed are reported. The batch is
//! flushed:
//!
//! - at once, when every path in it is complete — a save costs no waiting —
//!   unless saves are coming in a burst (this batch began within
//!   [`NotifyWatcher::quiet`] of the previous one's last event): then as
//!   below;
//! - while a file is being written, when the writer closes it: a writer that
//!   pauses between chunks is not read half-way. A writer that keeps a file
//!   open past [`NotifyWatcher::max_delay`] is read then, and again when it
//!   closes it (the trade-off for a batch that always ends);
//! - otherwise once no event came for [`NotifyWatcher::quiet`] (a removal
//!   may be the first half of delete-then-recreate; a directory may be
//!   filling up);
//! - at the latest [`NotifyWatcher::max_delay`] after the batch's first
//!   event, even if events keep coming.
//!
//! Events already queued are taken in before any of these decisions, so the
//! events of one save land in one batch. A file that is missing is given
//! one more chance after [`NotifyWatcher::missing_retry`] (delete-then-
//! recreate and rename saves make files vanish briefly) before it is
//! reported removed.
//!
//! Single files outside the roots (a scene elsewhere and its meshes) can be
//! added while running, through [`WatchedFiles`]: their directories are
//! watched non-recursively and only those files are reported.
//!
//! Paths in batches are absolute, `root.join(relative)` with the root made
//! absolute against the working directory (nothing is canonicalised), as
//! notify names the paths of its events.

use std::collections::{BTreeSet, HashMap};
use std::fmt;
use std::fs;
use std::io;
use std::path::{Path, PathBuf};
use std::sync::Arc;
use std::sync::mpsc::{self, Receiver, RecvTimeoutError, Sender, TryRecvError};
use std::thread::JoinHandle;
use std::time::{Duration, Instant};

use notify::{RecursiveMode, Watcher};

use super::event::{Event, FileBatch, FileChange};
pub use debounce::is_source_file;
use debounce::{Pending, Window};

mod debounce;

/// How deep directory walks go (a guard against symlink loops).
const MAX_WALK_DEPTH: usize = 32;

/// Keeps a watch alive; dropping it stops the watch: the debounce thread
/// exits, dropping the notify watcher it owns, and is joined, so no batch is
/// sent after the drop returns.
#[must_use = "dropping the guard stops watching"]
pub struct WatchGuard {
    control: Sender<Raw>,
    thread: Option<JoinHandle<()>>,
}

impl WatchGuard {
    /// The handle that names the single files watched besides the roots.
    pub fn files(&self) -> WatchedFiles {
        WatchedFiles(Some(self.control.clone()))
    }
}

impl Drop for WatchGuard {
    fn drop(&mut self) {
        let _ = self.control.send(Raw::Stop);
        if let Some(thread) = self.thread.take() {
            join_quietly(thread);
        }
    }
}

impl fmt::Debug for WatchGuard {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.debug_struct("WatchGuard").finish_non_exhaustive()
    }
}

/// Single files to watch besides the roots: what a scene outside the roots
/// depends on (the scene file, its glTF meshes and their buffers). Their
/// directories are watched non-recursively and only the named files in them
/// are reported; files under a root are covered by its watch already.
#[derive(Clone, Default)]
pub struct WatchedFiles(Option<Sender<Raw>>);

impl WatchedFiles {
    /// Replaces the set of single files (a handle from no watcher ignores it).
    pub fn set(&self, files: &[PathBuf]) {
        if let Some(control) = &self.0 {
            let _ = control.send(Raw::Files(files.to_vec()));
        }
    }
}

/// The real watcher: `notify`'s recommended backend (inotify on Linux) plus
/// a debounce thread of our own.
#[derive(Debug, Clone)]
pub struct NotifyWatcher {
    /// Flush a batch that is not evidently complete once no new event
    /// arrived for this long; also how close saves must follow each other to
    /// count as a burst.
    pub quiet: Duration,
    /// Flush a batch at the latest this long after its first event, even if
    /// events keep coming or a file is still open for writing.
    pub max_delay: Duration,
    /// How long to wait before reading a missing file again, before calling
    /// it removed.
    pub missing_retry: Duration,
}

impl Default for NotifyWatcher {
    fn default() -> Self {
        NotifyWatcher { quiet: Duration::from_millis(25), max_delay: Duration::from_millis(250), missing_retry: Duration::from_millis(60) }
    }
}

impl NotifyWatcher {
    /// Starts watching `roots` recursively; content changes arrive on
    /// `events` as [`Event::FilesChanged`].
    pub fn start(&self, roots: &[PathBuf], events: Sender<Event>) -> Result<WatchGuard, String> {
        // notify reports absolute paths; so does everything here.
        let roots: Vec<PathBuf> = roots.iter().map(|r| absolute(r)).collect();
        let roots = &roots[..];
        for root in roots {
            match fs::metadata(root) {
                Ok(meta) if meta.is_dir() => {}
                Ok(_) => return Err(format!("watch {}: not a directory", root.display())),
                Err(err) => return Err(format!("watch {}: {err}", root.display())),
            }
        }

        let (raw_tx, raw_rx) = mpsc::channel::<Raw>();
        let handler_tx = raw_tx.clone();
        let mut watcher = notify::recommended_watcher(move |res: notify::Result<notify::Event>| {
            let msg = match res {
                Ok(event) => Raw::Event(Instant::now(), event),
                Err(err) => Raw::Error(err),
            };
            // The debounce thread is gone only when we are stopping.
            let _ = handler_tx.send(msg);
        })
        .map_err(|err| format!("start file watcher: {err}"))?;

        // Watch first, then record the initial state: a change racing with
        // start-up is then either in the recorded hash or reported later.
        for root in roots {
            watcher.watch(root, RecursiveMode::Recursive).map_err(|err| format!("watch {}: {err}", root.display()))?;
        }
        let mut known = HashMap::new();
        for root in roots {
            let mut files = BTreeSet::new();
            walk_sources(root, 0, &mut files);
            for path in files {
                match hash_file(&path) {
                    Ok(hash) => {
                        known.insert(path, hash);
                    }
                    Err(err) => log::warn!("watch: read {}: {err}", path.display()),
                }
            }
        }

        let debouncer = Debouncer {
            watcher,
            canonical_roots: roots.iter().map(|r| fs::canonicalize(r).unwrap_or_else(|_| r.clone())).collect(),
            single: BTreeSet::new(),
            roots: roots.to_vec(),
            known,
            events,
            window: Window { quiet: self.quiet, max_delay: self.max_delay },
            missing_retry: self.missing_retry,
            pending: None,
            previous_last: None,
        };
        let thread = std::thread::Builder::new()
            .name("loupe-watch".into())
            .spawn(move || debouncer.run(raw_rx))
            .map_err(|err| format!("start watch thread: {err}"))?;

        Ok(WatchGuard { control: raw_tx, thread: Some(thread) })
    }
}

fn join_quietly(thread: JoinHandle<()>) {
    if thread.join().is_err() {
        log::warn!("watch: the debounce thread panicked");
    }
}

/// What the notify callback and the guard hand the debounce thread.
enum Raw {
    Event(Instant, notify::Event),
    Error(notify::Error),
    /// The single files to watch from now on.
    Files(Vec<PathBuf>),
    Stop,
}

struct Debouncer {
    /// Owned here so single files can be added while running.
    watcher: notify::RecommendedWatcher,
    roots: Vec<PathBuf>,
    /// The roots resolved, to tell whether a single file lies under one.
    canonical_roots: Vec<PathBuf>,
    /// Single files outside the roots; their directories are watched
    /// non-recursively.
    single: BTreeSet<PathBuf>,
    /// Content hash of every source file as last seen.
    known: HashMap<PathBuf, blake3::Hash>,
    events: Sender<Event>,
    window: Window,
    missing_retry: Duration,
    pending: Option<Pending>,
    /// The last event of the previous batch: a batch starting soon after it
    /// is part of a burst of saves.
    previous_last: Option<Instant>,
}

/// One read of one candidate path.
enum Check {
    Changed(FileChange),
    Unchanged,
    Missing,
    Skip,
}

impl Debouncer {
    fn run(mut self, raw: Receiver<Raw>) {
        loop {
            // Everything already queued first: one save's events come
            // together and belong in one batch.
            let msg = match raw.try_recv() {
                Ok(msg) => msg,
                Err(TryRecvError::Disconnected) => return,
                Err(TryRecvError::Empty) => match &self.pending {
                    None => match raw.recv() {
                        Ok(msg) => msg,
                        Err(_) => return,
                    },
                    Some(pending) => {
                        let deadline = self.window.deadline(pending, self.previous_last);
                        let now = Instant::now();
                        let result = if now >= deadline { Err(RecvTimeoutError::Timeout) } else { raw.recv_timeout(deadline - now) };
                        match result {
                            Ok(msg) => msg,
                            Err(RecvTimeoutError::Timeout) => {
                                if !self.flush() {
                                    return;
                                }
                                continue;
                            }
                            Err(RecvTimeoutError::Disconnected) => return,
                        }
                    }
                },
            };
            match msg {
                Raw::Stop => return,
                Raw::Error(err) => log::warn!("watch: {err}"),
                Raw::Files(files) => self.watch_single(files),
                Raw::Event(at, event) => self.absorb(at, event),
            }
        }
    }

    /// Adds one raw event to the pending batch (or ignores it).
    fn absorb(&mut self, at: Instant, event: notify::Event) {
        if let Some(named) = debounce::named(event, &self.roots, &self.single) {
            self.pending.get_or_insert_with(|| Pending::new(at)).add(at, named);
        }
    }

    /// Watches `files` besides the roots, from now on instead of the
    /// previous set; their current content is the baseline changes are
    /// reported against.
    fn watch_single(&mut self, files: Vec<PathBuf>) {
        let outside: BTreeSet<PathBuf> = files.iter().map(|f| absolute(f)).filter(|f| !self.under_root(f)).collect();
        let dirs =
            |files: &BTreeSet<PathBuf>| -> BTreeSet<PathBuf> { files.iter().filter_map(|f| f.parent().map(Path::to_path_buf)).collect() };
        let (before, after) = (dirs(&self.single), dirs(&outside));
        for dir in before.difference(&after) {
            let _ = self.watcher.unwatch(dir);
        }
        for dir in after.difference(&before) {
            if let Err(err) = self.watcher.watch(dir, RecursiveMode::NonRecursive) {
                log::warn!("watch {}: {err}", dir.display());
            }
        }
        for gone in self.single.difference(&outside) {
            self.known.remove(gone);
        }
        for new in outside.difference(&self.single) {
            match hash_file(new) {
                Ok(hash) => {
                    self.known.insert(new.clone(), hash);
                }
                Err(err) => log::warn!("watch: read {}: {err}", new.display()),
            }
        }
        self.single = outside;
    }

    /// Whether `file` (absolute) lies under a root, through links too.
    fn under_root(&self, file: &Path) -> bool {
        file.parent()
            .and_then(|dir| fs::canonicalize(dir).ok())
            .is_some_and(|dir| self.canonical_roots.iter().any(|root| dir.starts_with(root)))
    }

    /// Reads every candidate of the pending batch and sends the changes.
    /// Returns false when nobody listens any more.
    fn flush(&mut self) -> bool {
        let Some(pending) = self.pending.take() else {
            return true;
        };
        self.previous_last = Some(pending.last);

        let mut candidates: BTreeSet<PathBuf> = pending.files.into_keys().collect();
        if pending.rescan {
            for root in &self.roots {
                walk_sources(root, 0, &mut candidates);
            }
            candidates.extend(self.known.keys().cloned());
        }
        for dir in &pending.dirs {
            if fs::metadata(dir).is_ok_and(|m| m.is_dir()) {
                // Files created right after their directory can beat the
                // watch notify adds for it: look for them ourselves.
                walk_sources(dir, 0, &mut candidates);
            }
            // A directory deleted or renamed away takes its files along.
            candidates.extend(self.known.keys().filter(|p| p.starts_with(dir)).cloned());
        }

        let mut changes = Vec::new();
        let mut missing = Vec::new();
        for path in candidates {
            match self.check(&path) {
                Check::Changed(change) => changes.push(change),
                Check::Missing => missing.push(path),
                Check::Unchanged | Check::Skip => {}
            }
        }
        if !missing.is_empty() {
            std::thread::sleep(self.missing_retry);
            for path in missing {
                match self.check(&path) {
                    Check::Changed(change) => changes.push(change),
                    Check::Missing => {
                        if self.known.remove(&path).is_some() {
                            changes.push(FileChange::Removed { path });
                        }
                    }
                    Check::Unchanged | Check::Skip => {}
                }
            }
        }
        if changes.is_empty() {
            return true;
        }
        changes.sort_by(|a, b| a.path().cmp(b.path()));
        let batch = FileBatch { changes, first_event: pending.first, ready: Instant::now() };
        self.events.send(Event::FilesChanged(batch)).is_ok()
    }

    /// Reads `path` and compares it with what we knew.
    fn check(&mut self, path: &Path) -> Check {
        match fs::metadata(path) {
            Ok(meta) if meta.is_file() => {}
            // A directory (or a FIFO, socket…) with a source-like name.
            Ok(_) => return Check::Skip,
            Err(err) if is_missing(&err) => return Check::Missing,
            Err(err) => {
                log::warn!("watch: stat {}: {err}", path.display());
                return Check::Skip;
            }
        }
        match fs::read(path) {
            Ok(bytes) => {
                let hash = blake3::hash(&bytes);
                if self.known.get(path) == Some(&hash) {
                    return Check::Unchanged;
                }
                self.known.insert(path.to_path_buf(), hash);
                Check::Changed(FileChange::Written { path: path.to_path_buf(), content: Arc::from(bytes) })
            }
            Err(err) if is_missing(&err) => Check::Missing,
            Err(err) => {
                log::warn!("watch: read {}: {err}", path.display());
                Check::Skip
            }
        }
    }
}

/// `path` made absolute against the working directory, as notify names
/// the paths of its events.
fn absolute(path: &Path) -> PathBuf {
    std::path::absolute(path).unwrap_or_else(|_| path.to_owned())
}

fn is_missing(err: &io::Error) -> bool {
    matches!(err.kind(), io::ErrorKind::NotFound | io::ErrorKind::NotADirectory)
}

fn hash_file(path: &Path) -> io::Result<blake3::Hash> {
    let mut file = fs::File::open(path)?;
    let mut hasher = blake3::Hasher::new();
    hasher.update_reader(&mut file)?;
    Ok(hasher.finalize())
}

/// Adds every source file under `dir` (recursively, skipping hidden
/// directories) to `out`. Unreadable directories are logged and skipped.
fn walk_sources(dir: &Path, depth: usize, out: &mut BTreeSet<PathBuf>) {
    if depth > MAX_WALK_DEPTH {
        log::warn!("watch: {} is nested too deep; not looking further", dir.display());
        return;
    }
    let entries = match fs::read_dir(dir) {
        Ok(entries) => entries,
        Err(err) => {
            if !is_missing(&err) {
                log::warn!("watch: list {}: {err}", dir.display());
            }
            return;
        }
    };
    for entry in entries.flatten() {
        let path = entry.path();
        let Ok(mut file_type) = entry.file_type() else {
            continue;
        };
        if file_type.is_symlink() {
            match fs::metadata(&path) {
                Ok(meta) => file_type = meta.file_type(),
                Err(_) => continue, // dangling link
            }
        }
        if file_type.is_dir() {
            let hidden = entry.file_name().to_str().is_none_or(|n| n.starts_with('.'));
            if !hidden {
                walk_sources(&path, depth + 1, out);
            }
        } else if file_type.is_file() && is_source_file(&path) {
            out.insert(path);
        }
    }
}

#[cfg(test)]
mod tests;
