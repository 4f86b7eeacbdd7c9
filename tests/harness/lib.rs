//! Harness for end-to-end tests of the built `loupe` binary: runs it as a
//! user would and, on any failed expectation, prints the command line, exit
//! code, stdout and stderr. `ws` is a blocking WebSocket client for `/ws`;
//! `reload` drives edits and measures them (shared by the e2e tests and the
//! `bench-reload` benchmark); `protocol` reads PROTOCOL.md's key table;
//! `xvfb` runs a virtual display for `loupe view` and screenshots it.

pub mod protocol;
pub mod reload;
pub mod ws;
pub mod xvfb;

use std::io::{BufRead, BufReader};
use std::path::{Path, PathBuf};
use std::process::{Child, Command, Stdio};
use std::sync::atomic::{AtomicU32, Ordering};
use std::time::{Duration, Instant};

/// The repository root.
pub fn repo() -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).parent().expect("tests/ is inside the repo").to_owned()
}

/// One of OIDN's weights files as the repository ships them (the files
/// `loupe` embeds, `server/assets/weights/oidn/`).
pub fn oidn_weights(name: &str) -> PathBuf {
    let path = repo().join("server/assets/weights/oidn").join(name);
    assert!(path.is_file(), "OIDN's weights file {} is missing from the repository", path.display());
    path
}

/// The CPU model and core count, for benchmark output.
pub fn machine() -> String {
    let cpuinfo = std::fs::read_to_string("/proc/cpuinfo").unwrap_or_default();
    let model = cpuinfo.lines().find_map(|l| l.strip_prefix("model name")).map(|m| m.trim_start_matches([' ', '\t', ':']).to_owned());
    let cores = std::thread::available_parallelism().map(|n| n.get()).unwrap_or(0);
    format!("{} ({cores} cores)", model.unwrap_or_else(|| "unknown CPU".into()))
}

/// For benchmarks: `LOUPE_BIN`, else the release build (built now if
/// needed).
pub fn release_bin() -> PathBuf {
    if let Some(p) = std::env::var_os("LOUPE_BIN") {
        return p.into();
    }
    let status = Command::new(env!("CARGO"))
        .args(["build", "--release", "-p", "loupe", "--bin", "loupe"])
        .current_dir(repo())
        .status()
        .expect("cargo runs");
    assert!(status.success(), "building the release loupe failed");
    let target = std::env::var_os("CARGO_TARGET_DIR").map(PathBuf::from).unwrap_or_else(|| repo().join("target"));
    target.join("release/loupe")
}

/// The built binary: `LOUPE_BIN`, else the workspace's debug build.
pub fn loupe_bin() -> PathBuf {
    if let Some(p) = std::env::var_os("LOUPE_BIN") {
        return p.into();
    }
    let p = repo().join("target/debug/loupe");
    assert!(p.exists(), "{} does not exist: run `cargo build --bins` first (tests/run does)", p.display());
    p
}

/// The result of one run, with everything needed to explain a failure.
#[derive(Debug)]
pub struct Run {
    pub cmd: String,
    pub code: i32,
    pub stdout: String,
    pub stderr: String,
}

impl Run {
    fn context(&self) -> String {
        format!(
            "\n--- command ---\n{}\n--- exit code: {} ---\n--- stdout ---\n{}\n--- stderr ---\n{}\n",
            self.cmd, self.code, self.stdout, self.stderr
        )
    }

    #[track_caller]
    pub fn code(&self, expected: i32) -> &Self {
        assert_eq!(self.code, expected, "unexpected exit code{}", self.context());
        self
    }

    #[track_caller]
    pub fn stdout_has(&self, needle: &str) -> &Self {
        assert!(self.stdout.contains(needle), "stdout lacks {needle:?}{}", self.context());
        self
    }

    #[track_caller]
    pub fn stderr_has(&self, needle: &str) -> &Self {
        assert!(self.stderr.contains(needle), "stderr lacks {needle:?}{}", self.context());
        self
    }

    /// Panics with the full context when `ok` is false.
    #[track_caller]
    pub fn check(&self, ok: bool, what: &str) -> &Self {
        assert!(ok, "{what}{}", self.context());
        self
    }
}

/// Runs `loupe args...` in `dir` to completion.
pub fn loupe(dir: &Path, args: &[&str]) -> Run {
    loupe_at(&loupe_bin(), dir, args)
}

/// Runs `loupe args...` in `dir` to completion with `env` set besides.
pub fn loupe_with_env(dir: &Path, args: &[&str], env: &[(&str, &str)]) -> Run {
    run_loupe(&loupe_bin(), dir, args, env)
}

/// Runs the loupe binary `bin` with `args` in `dir` to completion.
pub fn loupe_at(bin: &Path, dir: &Path, args: &[&str]) -> Run {
    run_loupe(bin, dir, args, &[])
}

fn run_loupe(bin: &Path, dir: &Path, args: &[&str], env: &[(&str, &str)]) -> Run {
    let mut cmd = Command::new(bin);
    cmd.args(args).current_dir(dir).env("NO_COLOR", "1").envs(env.iter().copied());
    let shown: Vec<String> = env.iter().map(|(k, v)| format!("{k}={v} ")).collect();
    run(cmd, format!("(cd {} && {}loupe {})", dir.display(), shown.concat(), args.join(" ")))
}

/// Runs `cmd` to completion; `shown` is how a failure names it.
pub fn run(mut cmd: Command, shown: String) -> Run {
    let out = cmd.output().unwrap_or_else(|e| panic!("{shown} starts: {e}"));
    Run {
        cmd: shown,
        code: out.status.code().unwrap_or(-1),
        stdout: String::from_utf8_lossy(&out.stdout).into_owned(),
        stderr: String::from_utf8_lossy(&out.stderr).into_owned(),
    }
}

/// A throwaway project directory, removed on drop.
pub struct Project {
    pub root: PathBuf,
}

impl Project {
    /// An empty project.
    pub fn empty(name: &str) -> Self {
        static N: AtomicU32 = AtomicU32::new(0);
        let root = std::env::temp_dir().join(format!("loupe-e2e-{name}-{}-{}", std::process::id(), N.fetch_add(1, Ordering::Relaxed)));
        let _ = std::fs::remove_dir_all(&root);
        std::fs::create_dir_all(&root).expect("temp dir");
        Project { root }
    }

    /// A copy of the repository's shaders/ and scenes/.
    pub fn copy_of_repo(name: &str) -> Self {
        let p = Self::empty(name);
        for dir in ["shaders", "scenes"] {
            copy_dir(&repo().join(dir), &p.root.join(dir));
        }
        p
    }

    pub fn path(&self, rel: &str) -> PathBuf {
        self.root.join(rel)
    }

    /// Writes a file the way most editors do: whole content, in place.
    pub fn write(&self, rel: &str, content: impl AsRef<[u8]>) {
        let p = self.path(rel);
        std::fs::create_dir_all(p.parent().expect("has parent")).expect("mkdir");
        std::fs::write(&p, content).expect("write");
    }

    /// Saves like vim / VS Code / JetBrains: write a temp file, rename over.
    pub fn save_by_rename(&self, rel: &str, content: impl AsRef<[u8]>) {
        let p = self.path(rel);
        let tmp = p.with_extension("wgsl.tmp~");
        std::fs::write(&tmp, content).expect("write temp");
        std::fs::rename(&tmp, &p).expect("rename over");
    }

    pub fn read(&self, rel: &str) -> String {
        std::fs::read_to_string(self.path(rel)).expect("read")
    }

    pub fn run(&self, args: &[&str]) -> Run {
        loupe(&self.root, args)
    }
}

impl Drop for Project {
    fn drop(&mut self) {
        let _ = std::fs::remove_dir_all(&self.root);
    }
}

pub fn copy_dir(from: &Path, to: &Path) {
    std::fs::create_dir_all(to).expect("mkdir");
    for e in std::fs::read_dir(from).expect("read dir").flatten() {
        let p = e.path();
        if p.is_dir() {
            copy_dir(&p, &to.join(e.file_name()));
        } else {
            std::fs::copy(&p, to.join(e.file_name())).expect("copy");
        }
    }
}

/// A running `loupe serve`, killed on drop. Its stderr is kept for failure
/// messages.
pub struct Server {
    child: Child,
    pub addr: String,
    log: std::sync::Arc<std::sync::Mutex<String>>,
}

impl Server {
    /// Starts `loupe serve --port 0 ...extra` in `dir` and waits for the
    /// `listening on http://ADDR` line.
    pub fn start(dir: &Path, extra: &[&str]) -> Server {
        Self::start_on(dir, 0, extra)
    }

    /// Starts `loupe serve --port PORT ...extra` (0 picks a free port).
    pub fn start_on(dir: &Path, port: u16, extra: &[&str]) -> Server {
        Self::start_with(&loupe_bin(), dir, port, extra)
    }

    /// Starts `BIN serve --port PORT ...extra` in `dir`.
    pub fn start_with(bin: &Path, dir: &Path, port: u16, extra: &[&str]) -> Server {
        Self::start_command(bin, dir, "serve", port, extra, &[])
    }

    /// Starts `BIN COMMAND --port PORT ...extra` in `dir` with `env` set:
    /// `serve`, or `view`, which runs the same daemon.
    pub fn start_command(bin: &Path, dir: &Path, command: &str, port: u16, extra: &[&str], env: &[(&str, &str)]) -> Server {
        // Run in `dir`: a relative binary path is relative to here.
        let bin = std::path::absolute(bin).expect("an absolute path");
        // The daemon's tests want frames quickly on lavapipe: unless a test
        // names a scene, serve the test pattern, the lightest scene.
        let scene: &[&str] = if extra.contains(&"--scene") { &[] } else { &["--scene", "scenes/pattern.toml"] };
        let mut child = Command::new(bin)
            .args([command, "--port", &port.to_string()])
            .args(scene)
            .args(extra)
            .envs(env.iter().copied())
            .current_dir(dir)
            .stdout(Stdio::piped())
            .stderr(Stdio::piped())
            .spawn()
            .expect("loupe serve starts");
        let log = std::sync::Arc::new(std::sync::Mutex::new(String::new()));
        let err = child.stderr.take().expect("piped");
        let sink = log.clone();
        std::thread::spawn(move || {
            for line in BufReader::new(err).lines().map_while(Result::ok) {
                sink.lock().expect("log").push_str(&(line + "\n"));
            }
        });
        let out = child.stdout.take().expect("piped");
        let (tx, rx) = std::sync::mpsc::channel();
        let sink = log.clone();
        std::thread::spawn(move || {
            for line in BufReader::new(out).lines().map_while(Result::ok) {
                if let Some(addr) = line.split("listening on http://").nth(1) {
                    // Bound to every interface: this machine reaches it on
                    // loopback.
                    let _ = tx.send(addr.trim().replace("0.0.0.0:", "127.0.0.1:"));
                }
                sink.lock().expect("log").push_str(&(line + "\n"));
            }
        });
        let addr = match rx.recv_timeout(Duration::from_secs(120)) {
            Ok(a) => a,
            Err(_) => {
                let _ = child.kill();
                panic!("loupe serve did not start; its output:\n{}", log.lock().expect("log"));
            }
        };
        Server { child, addr, log }
    }

    pub fn url(&self, path: &str) -> String {
        format!("http://{}{}", self.addr, path)
    }

    pub fn port(&self) -> u16 {
        self.addr.rsplit(':').next().and_then(|p| p.parse().ok()).expect("ADDR ends in :PORT")
    }

    /// The server process's resident memory, from /proc/PID/status (VmRSS).
    pub fn rss_kib(&self) -> u64 {
        let status = std::fs::read_to_string(format!("/proc/{}/status", self.child.id())).expect("/proc/PID/status");
        status
            .lines()
            .find_map(|l| l.strip_prefix("VmRSS:"))
            .and_then(|v| v.split_whitespace().next())
            .and_then(|v| v.parse().ok())
            .expect("VmRSS in /proc/PID/status")
    }

    /// Stops the server the hard way (as a crash or `kill -9` would) and
    /// waits for it to be gone.
    pub fn kill(mut self) {
        let _ = self.child.kill();
        let _ = self.child.wait();
    }

    /// A WebSocket connection to `/ws`.
    pub fn ws(&self) -> ws::Ws {
        ws::Ws::connect(&self.addr).unwrap_or_else(|e| panic!("cannot connect to /ws: {e}\n{}", self.log()))
    }

    /// POST a path with an empty body; returns status and body.
    pub fn post(&self, path: &str) -> (u16, Vec<u8>) {
        self.answer(&format!("POST {path}"), agent().post(&self.url(path)).send_empty())
    }

    /// POST a JSON body to a path; returns status and body. `via`: another
    /// address of this server to send it to (its `Host` still names the
    /// loopback address), as a client on another machine would.
    pub fn post_json(&self, path: &str, body: &serde_json::Value, via: Option<std::net::SocketAddr>) -> (u16, Vec<u8>) {
        let url = match via {
            Some(addr) => format!("http://{addr}{path}"),
            None => self.url(path),
        };
        let request = agent().post(&url).header("content-type", "application/json").header("host", &self.addr);
        self.answer(&format!("POST {path}"), request.send(body.to_string()))
    }

    /// Status and body of a request's reply; panics, with the server's
    /// log, when there was none.
    fn answer(&self, what: &str, reply: Result<ureq::http::Response<ureq::Body>, ureq::Error>) -> (u16, Vec<u8>) {
        let mut resp = reply.unwrap_or_else(|e| panic!("{what}: {e}\n{}", self.log()));
        let status = resp.status().as_u16();
        let body = resp.body_mut().read_to_vec().expect("body");
        (status, body)
    }

    /// The capture `pass/output` as exact RGBA f32 values, with its frame
    /// number; `None` while there is none.
    pub fn capture_f32(&self, key: &str) -> Option<Capture> {
        let mut resp = agent().get(&self.url(&format!("/api/captures/{key}.f32"))).call().ok()?;
        if resp.status() != 200 {
            return None;
        }
        let num = |name: &str| resp.headers().get(name)?.to_str().ok()?.parse::<u64>().ok();
        let (frame, width, height) = (num("x-loupe-frame")?, num("x-loupe-width")? as u32, num("x-loupe-height")? as u32);
        let body = resp.body_mut().with_config().limit(1 << 30).read_to_vec().ok()?;
        let data = body.chunks_exact(4).map(|b| f32::from_le_bytes(b.try_into().expect("4 bytes"))).collect();
        Some(Capture { frame, width, height, data })
    }

    pub fn log(&self) -> String {
        self.log.lock().expect("log").clone()
    }

    /// GET a path; returns status and body.
    pub fn get(&self, path: &str) -> (u16, Vec<u8>) {
        self.answer(&format!("GET {path}"), agent().get(&self.url(path)).call())
    }

    /// GET a path; returns status and its `X-Loupe-State` (PROTOCOL.md,
    /// "States"), if any.
    pub fn get_state(&self, path: &str) -> (u16, Option<String>) {
        let resp = agent().get(&self.url(path)).call().unwrap_or_else(|e| panic!("GET {path}: {e}\n{}", self.log()));
        (resp.status().as_u16(), resp.headers().get("x-loupe-state").and_then(|v| v.to_str().ok()).map(str::to_owned))
    }

    pub fn get_json(&self, path: &str) -> serde_json::Value {
        let (status, body) = self.get(path);
        assert_eq!(status, 200, "GET {path}: {}\n{}", String::from_utf8_lossy(&body), self.log());
        serde_json::from_slice(&body).unwrap_or_else(|e| panic!("GET {path}: not JSON: {e}"))
    }

    /// Polls `f` until it returns Some, up to `limit`; panics with the log.
    pub fn wait_for<T>(&self, what: &str, limit: Duration, mut f: impl FnMut() -> Option<T>) -> T {
        let start = Instant::now();
        loop {
            if let Some(v) = f() {
                return v;
            }
            if start.elapsed() > limit {
                panic!("timed out waiting for {what}\n--- server log ---\n{}", self.log());
            }
            std::thread::sleep(Duration::from_millis(50));
        }
    }
}

/// An HTTP client that returns error statuses as replies.
fn agent() -> ureq::Agent {
    ureq::Agent::config_builder().http_status_as_error(false).build().new_agent()
}

/// A capture read back as f32 RGBA.
#[derive(Debug, Clone)]
pub struct Capture {
    pub frame: u64,
    pub width: u32,
    pub height: u32,
    pub data: Vec<f32>,
}

impl Capture {
    pub fn pixel(&self, x: u32, y: u32) -> [f32; 4] {
        let i = ((y * self.width + x) * 4) as usize;
        [self.data[i], self.data[i + 1], self.data[i + 2], self.data[i + 3]]
    }
}

impl Drop for Server {
    fn drop(&mut self) {
        let _ = self.child.kill();
        let _ = self.child.wait();
    }
}

/// The RGBA pixels of an OpenEXR file `loupe render` wrote, row by row.
pub fn exr_rgba(path: &Path) -> Vec<[f32; 4]> {
    use exr::prelude::*;
    let image = read_first_rgba_layer_from_file(
        path,
        |size, _| (size.width(), vec![[0.0f32; 4]; size.width() * size.height()]),
        |(w, px): &mut (usize, Vec<[f32; 4]>), at, (r, g, b, a): (f32, f32, f32, f32)| px[at.y() * *w + at.x()] = [r, g, b, a],
    )
    .unwrap_or_else(|e| panic!("{}: {e}", path.display()));
    image.layer_data.channel_data.pixels.1
}
