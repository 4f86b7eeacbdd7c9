//! What the "against reference" thread (`references`) and the rest of the
//! daemon share: the way to ask it for a comparison (latest wins), and the
//! newest comparison with its images.

use std::collections::BTreeMap;
use std::path::PathBuf;
use std::sync::{Arc, Condvar, Mutex, MutexGuard};

use crate::gpu::Gpu;
use crate::protocol::ReferenceReport;
use crate::render::capture::CapturedImage;
use crate::shader::Library;

/// The images of one output, as PNG: the actual output, its reference and
/// FLIP's map (the last two when they compared), and the capture a bless
/// writes.
pub struct Images {
    pub actual: Vec<u8>,
    pub reference: Option<Vec<u8>>,
    pub flip: Option<Vec<u8>>,
    pub capture: Arc<CapturedImage>,
}

/// The newest comparison: the report and, by case and output index, the
/// images.
#[derive(Clone, Default)]
pub struct State {
    pub report: ReferenceReport,
    pub images: BTreeMap<(String, usize), Arc<Images>>,
    /// Where the cases' references are.
    pub references: PathBuf,
}

/// A comparison to run: the daemon's device and sources now.
#[derive(Clone)]
pub struct Job {
    pub gpu: Gpu,
    pub lib: Arc<Library>,
}

/// The way to the comparison thread, shared by the daemon (new sources)
/// and the HTTP side (compare again after a bless).
#[derive(Default)]
pub struct Queue {
    slot: Mutex<Slot>,
    ready: Condvar,
}

#[derive(Default)]
struct Slot {
    waiting: Option<Job>,
    /// The newest job taken, to run again.
    last: Option<Job>,
    stopped: bool,
}

impl Queue {
    fn lock(&self) -> MutexGuard<'_, Slot> {
        self.slot.lock().unwrap_or_else(|e| e.into_inner())
    }

    /// Asks for a comparison with `job`'s sources, replacing one waiting.
    pub fn submit(&self, job: Job) {
        self.lock().waiting = Some(job);
        self.ready.notify_one();
    }

    /// Compares the newest sources again (after references changed).
    pub fn again(&self) {
        let mut slot = self.lock();
        if slot.waiting.is_none() {
            slot.waiting = slot.last.clone();
        }
        drop(slot);
        self.ready.notify_one();
    }

    /// Ends the thread once it finishes what it runs.
    pub fn stop(&self) {
        self.lock().stopped = true;
        self.ready.notify_one();
    }

    /// Waits for the next job; `None` once stopped.
    pub fn next(&self) -> Option<Job> {
        let mut slot = self.lock();
        loop {
            if slot.stopped {
                return None;
            }
            if let Some(job) = slot.waiting.take() {
                slot.last = Some(job.clone());
                return Some(job);
            }
            slot = self.ready.wait(slot).unwrap_or_else(|e| e.into_inner());
        }
    }
}
