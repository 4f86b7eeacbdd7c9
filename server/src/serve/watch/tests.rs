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
    for yes in ["a.wgsl", "dir/b.WGSL", "scene.toml", "paint.mat", "m.gltf", "m.glb", "m.bin", "x.y.wgsl", "rust.png", "sky.EXR"] {
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
        "a.jpg",
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
