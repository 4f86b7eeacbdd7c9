//! The debounce rules, free of the file system and of threads: what an
//! event says about the save it belongs to, which of its paths count, and
//! when the batch being collected is flushed (the rules are in the
//! `watch` module's docs). The watcher thread (`super`) feeds events in,
//! asks for the deadline, and reads and hashes the files when it passes.

use std::collections::{BTreeMap, BTreeSet};
use std::path::{Path, PathBuf};
use std::time::{Duration, Instant};

use notify::EventKind;
use notify::event::{AccessKind, AccessMode, CreateKind, ModifyKind, RemoveKind, RenameMode};

/// Whether `path` names a file the daemon cares about: `.wgsl`, `.toml`
/// (scenes), `.mat` (materials), `.gltf`, `.glb`, `.bin` — and not an editor's
/// temporary or backup file (`*.swp`, `*.swx`, `*~`, `4913`, `.#*`, `*.tmp`,
/// or any name starting with `.`). Looks at the file name only.
pub fn is_source_file(path: &Path) -> bool {
    let Some(name) = path.file_name() else {
        return false;
    };
    // A name that is not UTF-8 still counts: the daemon says it cannot load it.
    if is_ignored_name(&name.to_string_lossy()) {
        return false;
    }
    match Path::new(name).extension().and_then(|e| e.to_str()) {
        Some(ext) => ["wgsl", "toml", "mat", "gltf", "glb", "bin", "png", "exr"].iter().any(|want| ext.eq_ignore_ascii_case(want)),
        None => false,
    }
}

/// Editor temporary / swap / backup / hidden names.
pub fn is_ignored_name(name: &str) -> bool {
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

/// What the newest event for a path says about the save it belongs to.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Progress {
    /// The writer closed the file, or a finished file was renamed onto it.
    Complete,
    /// Data changed and the writer has not closed the file yet.
    Writing,
    /// Created, removed, renamed away: more may follow.
    Unsettled,
}

/// What an event of `kind` says about the save of its `index`th path;
/// `None`: nothing (a path already pending keeps its state).
pub fn progress(kind: &EventKind, index: usize) -> Option<Progress> {
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

/// What one event names that matters: source files (with what the event
/// says about their save), paths that may be directories, and whether the
/// backend lost events.
#[derive(Debug, Default, PartialEq)]
pub struct Named {
    pub files: Vec<(PathBuf, Option<Progress>)>,
    pub dirs: Vec<PathBuf>,
    pub rescan: bool,
}

/// The paths of `event` that matter, under `roots` (recursive) or among
/// `single` (files outside them); `None` when the event matters not at all.
pub fn named(event: notify::Event, roots: &[PathBuf], single: &BTreeSet<PathBuf>) -> Option<Named> {
    let rescan = event.need_rescan();
    // Whether the paths may name directories, whose contents then need
    // looking at; otherwise only source-file paths matter.
    let maybe_dir = match event.kind {
        // Our own reads open files: never let them start a batch.
        EventKind::Access(AccessKind::Close(AccessMode::Write)) => false,
        EventKind::Access(_) => {
            if !rescan {
                return None;
            }
            false
        }
        EventKind::Create(CreateKind::File)
        | EventKind::Remove(RemoveKind::File)
        | EventKind::Modify(ModifyKind::Data(_) | ModifyKind::Metadata(_) | ModifyKind::Any | ModifyKind::Other) => false,
        EventKind::Create(_) | EventKind::Remove(_) | EventKind::Modify(ModifyKind::Name(_)) | EventKind::Any | EventKind::Other => true,
    };

    let mut named = Named { rescan, ..Named::default() };
    for (i, path) in event.paths.into_iter().enumerate() {
        if !roots.iter().any(|root| path.starts_with(root)) {
            // From a single file's directory: only that file counts.
            if single.contains(&path) {
                named.files.push((path, progress(&event.kind, i)));
            }
            continue;
        }
        if in_hidden_dir(roots, &path) {
            continue;
        }
        if is_source_file(&path) {
            named.files.push((path, progress(&event.kind, i)));
        } else if maybe_dir && path.file_name().and_then(|n| n.to_str()).is_some_and(|n| !is_ignored_name(n)) {
            named.dirs.push(path);
        }
    }
    (!named.files.is_empty() || !named.dirs.is_empty() || rescan).then_some(named)
}

/// Whether `path` lies below a hidden directory of its root (`.git/…`).
fn in_hidden_dir(roots: &[PathBuf], path: &Path) -> bool {
    let Some(rel) = roots.iter().find_map(|root| path.strip_prefix(root).ok()) else {
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

/// The batch being collected.
pub struct Pending {
    pub first: Instant,
    pub last: Instant,
    /// Source files named by events, with where their save stands.
    pub files: BTreeMap<PathBuf, Progress>,
    /// Paths that may be directories (created, renamed, removed): scanned for
    /// source files, and every known file under them is checked.
    pub dirs: BTreeSet<PathBuf>,
    /// The backend lost events: check everything.
    pub rescan: bool,
}

impl Pending {
    /// A batch begun by an event at `at`.
    pub fn new(at: Instant) -> Self {
        Pending { first: at, last: at, files: BTreeMap::new(), dirs: BTreeSet::new(), rescan: false }
    }

    /// Takes in what one event at `at` named.
    pub fn add(&mut self, at: Instant, named: Named) {
        self.first = self.first.min(at);
        self.last = self.last.max(at);
        for (path, progress) in named.files {
            let state = self.files.entry(path).or_insert(Progress::Unsettled);
            if let Some(progress) = progress {
                *state = progress;
            }
        }
        self.dirs.extend(named.dirs);
        self.rescan |= named.rescan;
    }

    fn writing(&self) -> bool {
        self.files.values().any(|p| *p == Progress::Writing)
    }

    fn complete(&self) -> bool {
        !self.rescan && self.dirs.is_empty() && self.files.values().all(|p| *p == Progress::Complete)
    }
}

/// The two durations the flush rules use.
#[derive(Debug, Clone, Copy)]
pub struct Window {
    /// Quiet needed before an unsettled batch is flushed; also how close
    /// saves must follow each other to count as a burst.
    pub quiet: Duration,
    /// The longest a batch waits after its first event.
    pub max_delay: Duration,
}

impl Window {
    /// When `pending` is to be flushed; `previous_last`: the last event of
    /// the batch flushed before it.
    pub fn deadline(&self, pending: &Pending, previous_last: Option<Instant>) -> Instant {
        let latest = pending.first + self.max_delay;
        if pending.writing() {
            // Until the writer closes the file (it is then complete).
            return latest;
        }
        let burst = previous_last.is_some_and(|last| pending.first.saturating_duration_since(last) < self.quiet);
        let settled = if pending.complete() && !burst { pending.last } else { pending.last + self.quiet };
        settled.min(latest)
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use notify::event::DataChange;

    const WINDOW: Window = Window { quiet: Duration::from_millis(25), max_delay: Duration::from_millis(250) };

    fn root() -> Vec<PathBuf> {
        vec![PathBuf::from("/p/shaders")]
    }

    fn event(kind: EventKind, paths: &[&str]) -> notify::Event {
        paths.iter().fold(notify::Event::new(kind), |e, p| e.add_path(PathBuf::from(p)))
    }

    const CLOSE_WRITE: EventKind = EventKind::Access(AccessKind::Close(AccessMode::Write));
    const DATA: EventKind = EventKind::Modify(ModifyKind::Data(DataChange::Content));

    /// The batch that `events` start at `t0`, one a millisecond apart.
    fn batch(t0: Instant, events: Vec<notify::Event>) -> Pending {
        let mut pending = Pending::new(t0);
        for (i, e) in events.into_iter().enumerate() {
            let named = named(e, &root(), &BTreeSet::new()).expect("the event matters");
            pending.add(t0 + Duration::from_millis(i as u64), named);
        }
        pending
    }

    #[test]
    fn a_completed_save_is_flushed_at_once() {
        let t0 = Instant::now();
        let save = batch(t0, vec![event(DATA, &["/p/shaders/a.wgsl"]), event(CLOSE_WRITE, &["/p/shaders/a.wgsl"])]);
        assert_eq!(WINDOW.deadline(&save, None), save.last, "closed by its writer: no waiting");
        let renamed =
            batch(t0, vec![event(EventKind::Modify(ModifyKind::Name(RenameMode::Both)), &["/p/shaders/a.tmp", "/p/shaders/a.wgsl"])]);
        assert_eq!(WINDOW.deadline(&renamed, None), renamed.last, "a finished file renamed onto the path");
    }

    #[test]
    fn a_save_in_a_burst_waits_for_quiet() {
        let t0 = Instant::now() + Duration::from_secs(1);
        let save = batch(t0, vec![event(CLOSE_WRITE, &["/p/shaders/a.wgsl"])]);
        let previous = Some(t0 - Duration::from_millis(10));
        assert_eq!(WINDOW.deadline(&save, previous), save.last + WINDOW.quiet);
        let long_ago = Some(t0 - Duration::from_secs(1));
        assert_eq!(WINDOW.deadline(&save, long_ago), save.last, "not a burst");
    }

    #[test]
    fn a_file_being_written_waits_for_its_close_up_to_the_longest_delay() {
        let t0 = Instant::now();
        let writing = batch(t0, vec![event(DATA, &["/p/shaders/a.wgsl"])]);
        assert_eq!(WINDOW.deadline(&writing, None), t0 + WINDOW.max_delay);
        let removed = batch(t0, vec![event(EventKind::Remove(RemoveKind::File), &["/p/shaders/a.wgsl"])]);
        assert_eq!(WINDOW.deadline(&removed, None), removed.last + WINDOW.quiet, "a removal may be half a save");
    }

    #[test]
    fn events_that_name_nothing_of_ours_are_dropped() {
        let none = BTreeSet::new();
        let open = EventKind::Access(AccessKind::Open(AccessMode::Read));
        assert_eq!(named(event(open, &["/p/shaders/a.wgsl"]), &root(), &none), None, "our own reads");
        assert_eq!(named(event(DATA, &["/p/shaders/.git/a.wgsl"]), &root(), &none), None, "a hidden directory");
        assert_eq!(named(event(DATA, &["/p/shaders/a.wgsl.swp"]), &root(), &none), None, "a swap file");
        assert_eq!(named(event(DATA, &["/elsewhere/b.glb"]), &root(), &none), None, "outside the roots");
        let single = BTreeSet::from([PathBuf::from("/elsewhere/b.glb")]);
        let b = named(event(DATA, &["/elsewhere/b.glb", "/elsewhere/c.glb"]), &root(), &single).expect("a single file");
        assert_eq!(b.files, [(PathBuf::from("/elsewhere/b.glb"), Some(Progress::Writing))]);
    }
}
