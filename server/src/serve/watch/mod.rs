//! The source watcher: file-system events in, coalesced and content-checked
//! [`Event::FilesChanged`] batches out.
//!
//! Roots are always watched as directories, recursively, never as single
//! files: editors that save by writing a temporary file and renaming it over
//! the target replace the inode, and a watch on the old inode would go quiet.
//!
//! Raw notify events go to a debounce thread that collects the source paths
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

use std::collections::{BTreeMap, BTreeSet, HashMap};
use std::fmt;
use std::fs;
use std::io;
use std::path::{Path, PathBuf};
use std::sync::Arc;
use std::sync::mpsc::{self, Receiver, RecvTimeoutError, Sender, TryRecvError};
use std::thread::JoinHandle;
use std::time::{Duration, Instant};

use notify::event::{AccessKind, AccessMode, CreateKind, ModifyKind, RemoveKind, RenameMode};
use notify::{EventKind, RecursiveMode, Watcher};

use super::event::{Event, FileBatch, FileChange};

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

/// Whether `path` names a file the daemon cares about: `.wgsl`, `.toml`
/// (scenes, materials), `.gltf`, `.glb`, `.bin` — and not an editor's
/// temporary or backup file (`*.swp`, `*.swx`, `*~`, `4913`, `.#*`, `*.tmp`,
/// or any name starting with `.`). Looks at the file name only.
pub fn is_source_file(path: &Path) -> bool {
    let Some(name) = path.file_name().and_then(|n| n.to_str()) else {
        return false;
    };
    if is_ignored_name(name) {
        return false;
    }
    match Path::new(name).extension().and_then(|e| e.to_str()) {
        Some(ext) => ["wgsl", "toml", "gltf", "glb", "bin"].iter().any(|want| ext.eq_ignore_ascii_case(want)),
        None => false,
    }
}

/// Editor temporary / swap / backup / hidden names.
fn is_ignored_name(name: &str) -> bool {
    name.is_empty()
        || name.starts_with('.') // hidden, `.#lock` (emacs), `.x.swp` (vim)
        || name.ends_with('~') // backups
        || name == "4913" // vim's "can I create files here" probe
        || [".swp", ".swx", ".tmp"]
            .iter()
            .any(|ext| {
                let (name, ext) = (name.as_bytes(), ext.as_bytes());
                name.len() > ext.len() && name[name.len() - ext.len()..].eq_ignore_ascii_case(ext)
            })
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
            quiet: self.quiet,
            max_delay: self.max_delay,
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

/// What the newest event for a path says about the save it belongs to.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
enum Progress {
    /// The writer closed the file, or a finished file was renamed onto it.
    Complete,
    /// Data changed and the writer has not closed the file yet.
    Writing,
    /// Created, removed, renamed away: more may follow.
    Unsettled,
}

/// What an event of `kind` says about the save of its `index`th path;
/// `None`: nothing (a path already pending keeps its state).
fn progress(kind: &EventKind, index: usize) -> Option<Progress> {
    match kind {
        EventKind::Access(AccessKind::Close(AccessMode::Write)) => Some(Progress::Complete),
        EventKind::Modify(ModifyKind::Data(_)) => Some(Progress::Writing),
        // A touch or chmod, often right after a save: no news about content.
        EventKind::Modify(ModifyKind::Metadata(_)) => None,
        // A finished file arrived at the path (`Both` names from, then to).
        EventKind::Modify(ModifyKind::Name(RenameMode::To)) => Some(Progress::Complete),
        EventKind::Modify(ModifyKind::Name(RenameMode::Both)) if index > 0 => Some(Progress::Complete),
        _ => Some(Progress::Unsettled),
    }
}

/// The batch being collected.
struct Pending {
    first: Instant,
    last: Instant,
    /// Source files named by events, with where their save stands.
    files: BTreeMap<PathBuf, Progress>,
    /// Paths that may be directories (created, renamed, removed): scanned for
    /// source files, and every known file under them is checked.
    dirs: BTreeSet<PathBuf>,
    /// The backend lost events: check everything.
    rescan: bool,
}

impl Pending {
    fn writing(&self) -> bool {
        self.files.values().any(|p| *p == Progress::Writing)
    }

    fn complete(&self) -> bool {
        !self.rescan && self.dirs.is_empty() && self.files.values().all(|p| *p == Progress::Complete)
    }
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
    quiet: Duration,
    max_delay: Duration,
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
                        let deadline = self.deadline(pending);
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

    /// When `pending` is to be flushed (the rules are in the module docs).
    fn deadline(&self, pending: &Pending) -> Instant {
        let latest = pending.first + self.max_delay;
        if pending.writing() {
            // Until the writer closes the file (it is then complete).
            return latest;
        }
        let burst = self.previous_last.is_some_and(|last| pending.first.saturating_duration_since(last) < self.quiet);
        let settled = if pending.complete() && !burst { pending.last } else { pending.last + self.quiet };
        settled.min(latest)
    }

    /// Adds one raw event to the pending batch (or ignores it).
    fn absorb(&mut self, at: Instant, event: notify::Event) {
        let rescan = event.need_rescan();
        // Whether the paths may name directories, whose contents then need
        // looking at; otherwise only source-file paths matter.
        let maybe_dir = match event.kind {
            // Our own reads open files: never let them start a batch.
            EventKind::Access(AccessKind::Close(AccessMode::Write)) => false,
            EventKind::Access(_) => {
                if !rescan {
                    return;
                }
                false
            }
            EventKind::Create(CreateKind::File)
            | EventKind::Remove(RemoveKind::File)
            | EventKind::Modify(ModifyKind::Data(_) | ModifyKind::Metadata(_) | ModifyKind::Any | ModifyKind::Other) => false,
            EventKind::Create(_) | EventKind::Remove(_) | EventKind::Modify(ModifyKind::Name(_)) | EventKind::Any | EventKind::Other => {
                true
            }
        };

        let mut files = Vec::new();
        let mut dirs = Vec::new();
        for (i, path) in event.paths.into_iter().enumerate() {
            if !self.roots.iter().any(|root| path.starts_with(root)) {
                // From a single file's directory: only that file counts.
                if self.single.contains(&path) {
                    files.push((path, progress(&event.kind, i)));
                }
                continue;
            }
            if self.in_hidden_dir(&path) {
                continue;
            }
            if is_source_file(&path) {
                files.push((path, progress(&event.kind, i)));
            } else if maybe_dir && path.file_name().and_then(|n| n.to_str()).is_some_and(|n| !is_ignored_name(n)) {
                dirs.push(path);
            }
        }
        if files.is_empty() && dirs.is_empty() && !rescan {
            return;
        }

        let pending = self.pending.get_or_insert_with(|| Pending {
            first: at,
            last: at,
            files: BTreeMap::new(),
            dirs: BTreeSet::new(),
            rescan: false,
        });
        pending.first = pending.first.min(at);
        pending.last = pending.last.max(at);
        for (path, progress) in files {
            let state = pending.files.entry(path).or_insert(Progress::Unsettled);
            if let Some(progress) = progress {
                *state = progress;
            }
        }
        pending.dirs.extend(dirs);
        pending.rescan |= rescan;
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

    /// Whether `path` lies below a hidden directory of its root (`.git/…`).
    fn in_hidden_dir(&self, path: &Path) -> bool {
        let Some(rel) = self.roots.iter().find_map(|root| path.strip_prefix(root).ok()) else {
            return false;
        };
        let mut components = rel.components().peekable();
        while let Some(component) = components.next() {
            let is_last = components.peek().is_none();
            if !is_last && component.as_os_str().to_str().is_some_and(|name| name.starts_with('.') && name != "." && name != "..") {
                return true;
            }
        }
        // The last component is judged by `is_source_file` / `is_ignored_name`.
        false
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
mod tests {
    use super::*;
    use std::collections::BTreeMap;
    use std::sync::atomic::{AtomicUsize, Ordering};

    /// Generous: a loaded CI machine can be slow, and we never assert timing.
    const WAIT: Duration = Duration::from_secs(5);
    /// For negative checks: long enough for a batch to have been flushed.
    const QUIET_CHECK: Duration = Duration::from_millis(500);

    /// A fresh directory under the system temp dir, removed on drop.
    struct TempDir(PathBuf);

    impl TempDir {
        fn new(name: &str) -> Self {
            static COUNTER: AtomicUsize = AtomicUsize::new(0);
            let n = COUNTER.fetch_add(1, Ordering::Relaxed);
            let dir = std::env::temp_dir().join(format!("loupe-watch-{name}-{}-{n}", std::process::id()));
            let _ = fs::remove_dir_all(&dir);
            fs::create_dir_all(&dir).expect("create temp dir");
            TempDir(dir)
        }

        fn path(&self, rel: &str) -> PathBuf {
            self.0.join(rel)
        }
    }

    impl Drop for TempDir {
        fn drop(&mut self) {
            let _ = fs::remove_dir_all(&self.0);
        }
    }

    struct Session {
        rx: Receiver<Event>,
        guard: Option<WatchGuard>,
        batches: usize,
        /// Everything received so far: path → last content (`None`: removed).
        state: BTreeMap<PathBuf, Option<Vec<u8>>>,
        /// Every change ever received, in order.
        log: Vec<FileChange>,
    }

    fn start(dir: &TempDir) -> Session {
        start_with(dir, NotifyWatcher::default())
    }

    fn start_with(dir: &TempDir, watcher: NotifyWatcher) -> Session {
        let (tx, rx) = mpsc::channel();
        let guard = watcher.start(std::slice::from_ref(&dir.0), tx).expect("start watcher");
        Session { rx, guard: Some(guard), batches: 0, state: BTreeMap::new(), log: Vec::new() }
    }

    impl Session {
        /// Receives one batch, or `None` after `timeout`.
        fn next(&mut self, timeout: Duration) -> Option<FileBatch> {
            match self.rx.recv_timeout(timeout) {
                Ok(Event::FilesChanged(batch)) => {
                    assert!(!batch.changes.is_empty(), "empty batch sent");
                    assert!(batch.ready >= batch.first_event);
                    self.batches += 1;
                    for change in &batch.changes {
                        let content = match change {
                            FileChange::Written { content, .. } => Some(content.to_vec()),
                            FileChange::Removed { .. } => None,
                        };
                        self.state.insert(change.path().to_path_buf(), content);
                        self.log.push(change.clone());
                    }
                    Some(batch)
                }
                Ok(_) => panic!("the watcher sent something other than FilesChanged"),
                Err(_) => None,
            }
        }

        /// Receives batches until `done` holds for the accumulated state.
        fn until(&mut self, what: &str, done: impl Fn(&BTreeMap<PathBuf, Option<Vec<u8>>>) -> bool) {
            let deadline = Instant::now() + WAIT;
            while !done(&self.state) {
                let left = deadline.saturating_duration_since(Instant::now());
                if self.next(left).is_none() {
                    panic!("timed out waiting for {what}; got {:?}", self.state_summary());
                }
            }
        }

        fn until_content(&mut self, path: &Path, content: &[u8]) {
            self.until(&format!("{} = {:?}", path.display(), String::from_utf8_lossy(content)), |s| {
                s.get(path).is_some_and(|c| c.as_deref() == Some(content))
            });
        }

        /// Asserts that nothing arrives for a while.
        fn expect_silence(&mut self) {
            if let Some(batch) = self.next(QUIET_CHECK) {
                panic!("expected no batch, got {:?}", batch.changes);
            }
        }

        fn removed_ever(&self, path: &Path) -> bool {
            self.log.iter().any(|c| matches!(c, FileChange::Removed { path: p } if p == path))
        }

        fn state_summary(&self) -> Vec<(String, Option<String>)> {
            self.state.iter().map(|(p, c)| (p.display().to_string(), c.as_ref().map(|c| String::from_utf8_lossy(c).into_owned()))).collect()
        }
    }

    #[test]
    fn source_file_names() {
        for yes in ["a.wgsl", "dir/b.WGSL", "scene.toml", "m.gltf", "m.glb", "m.bin", "x.y.wgsl"] {
            assert!(is_source_file(Path::new(yes)), "{yes}");
        }
        for no in [
            "a.wgsl.swp",
            ".a.wgsl.swp",
            ".a.wgsl.swx",
            "a.wgsl~",
            "4913",
            ".#a.wgsl",
            "a.wgsl.tmp",
            ".hidden.wgsl",
            "a.png",
            "wgsl",
            "#a.wgsl#",
            "",
            "/",
            "é.wgsl.swp",
            "aé",
        ] {
            assert!(!is_source_file(Path::new(no)), "{no}");
        }
    }

    #[test]
    fn in_place_write() {
        let dir = TempDir::new("inplace");
        let a = dir.path("a.wgsl");
        fs::write(&a, "v1").unwrap();
        let mut s = start(&dir);
        fs::write(&a, "v2").unwrap();
        s.until_content(&a, b"v2");
        s.expect_silence();
        assert!(s.log.iter().all(|c| matches!(c, FileChange::Written { path, .. } if path == &a)), "{:?}", s.log);
    }

    /// A scene outside the roots: its own files are reported, by rename save
    /// too, and nothing else in their directory; a replaced set drops them.
    #[test]
    fn single_files_outside_the_roots() {
        let (root, elsewhere) = (TempDir::new("single-root"), TempDir::new("single-elsewhere"));
        let scene = elsewhere.path("scene.toml");
        let other = elsewhere.path("notes.toml");
        fs::write(&scene, "v1").unwrap();
        let mut s = start(&root);
        s.guard.as_ref().unwrap().files().set(&[scene.clone(), root.path("inside.wgsl")]);
        // Already current: the set's baseline is what is on disk now.
        s.expect_silence();

        fs::write(&other, "not ours").unwrap();
        fs::write(&scene, "v2").unwrap();
        s.until_content(&scene, b"v2");
        let tmp = elsewhere.path("scene.toml.tmp");
        fs::write(&tmp, "v3").unwrap();
        fs::rename(&tmp, &scene).unwrap();
        s.until_content(&scene, b"v3");
        assert!(s.state.keys().all(|p| p == &scene), "{:?}", s.state_summary());

        s.guard.as_ref().unwrap().files().set(&[]);
        // The set is taken in order with the events: wait for the watch to go.
        std::thread::sleep(Duration::from_millis(100));
        fs::write(&scene, "v4").unwrap();
        s.expect_silence();
    }

    #[test]
    fn rename_over_target() {
        let dir = TempDir::new("rename");
        let x = dir.path("x.wgsl");
        fs::write(&x, "v1").unwrap();
        let mut s = start(&dir);

        // VS Code / atomic-write style: a temp file next to the target.
        let tmp = dir.path("x.wgsl.tmp");
        fs::write(&tmp, "v2").unwrap();
        fs::rename(&tmp, &x).unwrap();
        s.until_content(&x, b"v2");

        // vim style (backupcopy=no): a hidden swap-like name renamed over.
        let swp = dir.path(".x.wgsl.swp");
        fs::write(&swp, "v3").unwrap();
        fs::rename(&swp, &x).unwrap();
        s.until_content(&x, b"v3");

        s.expect_silence();
        assert!(!s.removed_ever(&x), "a rename save is not a removal: {:?}", s.log);
        assert!(s.state.keys().all(|p| p == &x), "only x.wgsl: {:?}", s.state_summary());
    }

    #[test]
    fn vim_backup_save() {
        // vim's default on Unix: probe with "4913", rename the file to its
        // backup, write a new file, restore its mode, delete the backup.
        let dir = TempDir::new("vim");
        let x = dir.path("x.wgsl");
        fs::write(&x, "v1").unwrap();
        let mut s = start(&dir);
        fs::write(dir.path("4913"), "").unwrap();
        fs::remove_file(dir.path("4913")).unwrap();
        fs::rename(&x, dir.path("x.wgsl~")).unwrap();
        fs::write(&x, "v2").unwrap();
        let mode = fs::metadata(dir.path("x.wgsl~")).unwrap().permissions();
        fs::set_permissions(&x, mode).unwrap();
        fs::remove_file(dir.path("x.wgsl~")).unwrap();
        s.until_content(&x, b"v2");
        s.expect_silence();
        assert!(!s.removed_ever(&x), "{:?}", s.log);
        assert!(s.state.keys().all(|p| p == &x), "{:?}", s.state_summary());
    }

    #[test]
    fn a_save_right_after_a_completed_save_ends_on_the_second() {
        // The first save is reported as soon as it is complete; the second
        // comes 1 ms later and must not be lost behind it.
        let dir = TempDir::new("twosaves");
        let x = dir.path("x.wgsl");
        fs::write(&x, "v0").unwrap();
        let mut s = start(&dir);
        let tmp = dir.path("x.wgsl.tmp");
        for (i, by_rename) in [false, true].into_iter().enumerate() {
            let (first, second) = (format!("first {i}"), format!("second {i}"));
            for content in [&first, &second] {
                if by_rename {
                    fs::write(&tmp, content).unwrap();
                    fs::rename(&tmp, &x).unwrap();
                } else {
                    fs::write(&x, content).unwrap();
                }
                std::thread::sleep(Duration::from_millis(1));
            }
            s.until_content(&x, second.as_bytes());
            s.expect_silence();
            assert_eq!(s.state[&x].as_deref(), Some(second.as_bytes()));
        }
    }

    #[test]
    fn a_slow_writer_is_read_only_once_it_closes_the_file() {
        // Two chunks with a pause longer than `quiet` between them, in one
        // open file: nobody may see the first chunk alone.
        let dir = TempDir::new("slow");
        let x = dir.path("x.wgsl");
        fs::write(&x, "v0").unwrap();
        let mut s = start(&dir);
        let mut written = Vec::new();
        for (i, pause) in [30, 100].into_iter().enumerate() {
            let full = format!("{i}: the first half, and the rest");
            written.push(full.clone());
            let (half, rest) = full.split_at(full.find("and").unwrap());
            let mut file = fs::File::create(&x).unwrap();
            io::Write::write_all(&mut file, half.as_bytes()).unwrap();
            std::thread::sleep(Duration::from_millis(pause));
            io::Write::write_all(&mut file, rest.as_bytes()).unwrap();
            drop(file);
            s.until_content(&x, full.as_bytes());
            s.expect_silence();
            let partial = s.log.iter().find(|c| match c {
                FileChange::Written { content, .. } => !written.iter().any(|w| w.as_bytes() == &content[..]),
                FileChange::Removed { .. } => true,
            });
            assert!(partial.is_none(), "a half-written file was reported ({pause} ms pause): {:?}", s.log);
        }
    }

    #[test]
    fn delete_then_recreate() {
        let dir = TempDir::new("recreate");
        let x = dir.path("x.wgsl");
        fs::write(&x, "v1").unwrap();
        let mut s = start(&dir);
        fs::remove_file(&x).unwrap();
        fs::write(&x, "v2").unwrap();
        s.until_content(&x, b"v2");
        s.expect_silence();
        assert!(!s.removed_ever(&x), "{:?}", s.log);
    }

    #[test]
    fn disappears_and_comes_back_with_different_content() {
        let dir = TempDir::new("comeback");
        let x = dir.path("x.wgsl");
        fs::write(&x, "v1").unwrap();
        // A long retry window so the gap below is well inside it even on a
        // loaded machine; the gap is longer than `quiet`, so the batch is
        // flushed while the file is gone.
        let mut s = start_with(&dir, NotifyWatcher { missing_retry: Duration::from_millis(800), ..NotifyWatcher::default() });
        fs::remove_file(&x).unwrap();
        std::thread::sleep(Duration::from_millis(100));
        fs::write(&x, "v2 longer").unwrap();
        s.until_content(&x, b"v2 longer");
        s.expect_silence();
        // On a loaded machine the gap can outlast the retry window; then a
        // Removed may come first, but the file must end up Written.
        let last = s.log.iter().rev().find(|c| c.path() == x).expect("a change for x");
        assert!(matches!(last, FileChange::Written { content, .. } if &content[..] == b"v2 longer"), "{:?}", s.log);
    }

    #[test]
    fn removed_file_is_reported() {
        let dir = TempDir::new("removed");
        let x = dir.path("x.wgsl");
        let keep = dir.path("keep.toml");
        fs::write(&x, "v1").unwrap();
        fs::write(&keep, "k").unwrap();
        let mut s = start(&dir);
        fs::remove_file(&x).unwrap();
        let batch = s.next(WAIT).expect("a batch for the removal");
        assert_eq!(batch.changes.len(), 1, "{:?}", batch.changes);
        assert!(matches!(&batch.changes[0], FileChange::Removed { path } if path == &x));
        s.expect_silence();
    }

    #[test]
    fn removed_directory_reports_its_files() {
        let dir = TempDir::new("rmdir");
        let a = dir.path("sub/a.wgsl");
        let b = dir.path("sub/deep/b.wgsl");
        fs::create_dir_all(b.parent().unwrap()).unwrap();
        fs::write(&a, "a").unwrap();
        fs::write(&b, "b").unwrap();
        let mut s = start(&dir);
        fs::remove_dir_all(dir.path("sub")).unwrap();
        s.until("both removed", |st| st.get(&a) == Some(&None) && st.get(&b) == Some(&None));
    }

    #[test]
    fn many_files_at_once() {
        let dir = TempDir::new("many");
        let paths: Vec<PathBuf> = (0..20).map(|i| dir.path(&format!("m{i:02}.wgsl"))).collect();
        // Half exist before (modified, like a checkout), half are new.
        for p in &paths[..10] {
            fs::write(p, "old").unwrap();
        }
        let mut s = start(&dir);
        for (i, p) in paths.iter().enumerate() {
            fs::write(p, format!("new {i}")).unwrap();
        }
        s.until("all 20 files", |st| {
            paths.iter().enumerate().all(|(i, p)| st.get(p).is_some_and(|c| c.as_deref() == Some(format!("new {i}").as_bytes())))
        });
        assert!(s.batches <= 2, "20 quick writes took {} batches", s.batches);
        s.expect_silence();
    }

    #[test]
    fn burst_of_saves_is_coalesced() {
        let dir = TempDir::new("burst");
        let x = dir.path("x.wgsl");
        fs::write(&x, "start").unwrap();
        let mut s = start(&dir);
        let saves = 100;
        for i in 0..saves {
            fs::write(&x, format!("save {i}")).unwrap();
            std::thread::sleep(Duration::from_millis(5));
        }
        let last = format!("save {}", saves - 1);
        s.until_content(&x, last.as_bytes());
        s.expect_silence();
        assert_eq!(s.state.get(&x).cloned().flatten().as_deref(), Some(last.as_bytes()));
        assert!(s.batches < saves, "{} batches for {saves} saves", s.batches);
    }

    #[test]
    fn file_in_new_subfolder() {
        let dir = TempDir::new("subdir");
        let mut s = start(&dir);
        // Created right after its directories: notify's new watch may be late.
        let f = dir.path("new/deeper/f.wgsl");
        fs::create_dir_all(f.parent().unwrap()).unwrap();
        fs::write(&f, "fresh").unwrap();
        s.until_content(&f, b"fresh");
        // And the new directory is watched from now on.
        fs::write(&f, "edited").unwrap();
        s.until_content(&f, b"edited");
        let g = dir.path("new/g.toml");
        fs::write(&g, "g").unwrap();
        s.until_content(&g, b"g");
    }

    #[test]
    fn directory_moved_in_is_scanned() {
        let dir = TempDir::new("movein");
        let outside = TempDir::new("movein-src");
        let src = outside.path("pack");
        fs::create_dir_all(&src).unwrap();
        fs::write(src.join("p.wgsl"), "p").unwrap();
        let mut s = start(&dir);
        let p = dir.path("pack/p.wgsl");
        fs::rename(&src, dir.path("pack")).unwrap();
        s.until_content(&p, b"p");
    }

    #[test]
    fn touch_and_identical_rewrite_are_silent() {
        let dir = TempDir::new("touch");
        let x = dir.path("x.wgsl");
        fs::write(&x, "same").unwrap();
        let mut s = start(&dir);
        // touch: a new mtime, same bytes.
        let file = fs::OpenOptions::new().write(true).open(&x).unwrap();
        file.set_modified(std::time::SystemTime::now() + Duration::from_secs(10)).unwrap();
        drop(file);
        // An identical save, in place and by rename.
        fs::write(&x, "same").unwrap();
        let tmp = dir.path("x.wgsl.tmp");
        fs::write(&tmp, "same").unwrap();
        fs::rename(&tmp, &x).unwrap();
        s.expect_silence();
    }

    #[test]
    fn temp_and_swap_files_alone_are_silent() {
        let dir = TempDir::new("swap");
        let mut s = start(&dir);
        let names = [".x.wgsl.swp", ".x.wgsl.swx", "x.wgsl~", "4913", ".#x.wgsl", "x.wgsl.tmp", ".hidden.wgsl"];
        for name in names {
            fs::write(dir.path(name), "junk").unwrap();
        }
        // Source-named files inside a hidden directory (.git, .vscode) too.
        fs::create_dir_all(dir.path(".git")).unwrap();
        fs::write(dir.path(".git/inner.wgsl"), "junk").unwrap();
        for name in names {
            fs::remove_file(dir.path(name)).unwrap();
        }
        s.expect_silence();
    }

    #[test]
    fn dropping_the_guard_stops_watching() {
        let dir = TempDir::new("drop");
        let x = dir.path("x.wgsl");
        fs::write(&x, "v1").unwrap();
        let mut s = start(&dir);
        drop(s.guard.take());
        fs::write(&x, "v2").unwrap();
        // The debounce thread held the only sender: the channel is closed.
        match s.rx.recv_timeout(WAIT) {
            Err(mpsc::RecvTimeoutError::Disconnected) => {}
            Err(mpsc::RecvTimeoutError::Timeout) => panic!("the debounce thread is still running"),
            Ok(_) => panic!("a batch after the guard was dropped"),
        }
    }

    #[test]
    fn missing_root_is_an_error() {
        let dir = TempDir::new("missing");
        let (tx, _rx) = mpsc::channel();
        let err = NotifyWatcher::default().start(&[dir.path("nope")], tx).expect_err("a missing root");
        assert!(err.contains("nope"), "{err}");
    }
}
