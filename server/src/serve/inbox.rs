//! What clients can make the daemon hold, bounded.
//!
//! Client requests reach the render thread through the channel the
//! watcher's and compile workers' events take (so the daemon waits on one
//! receiver), but nothing a client does can grow it without bound:
//! - commands (rebuild, scene overrides and saves, history resets,
//!   lose-device, previews) count against [`COMMAND_QUEUE`] while they
//!   wait; one more is refused with [`Refused::Busy`];
//! - subscriptions are "latest wins" per client: a client's newest set
//!   waits in a map, and the channel holds one marker per client whose set
//!   waits; the [`Inbox`] hands the daemon the newest set when it reads the
//!   marker;
//! - a WebSocket client holds one of [`MAX_CONNECTIONS`] slots. A client
//!   that leaves while the daemon may hold outputs for it keeps its slot
//!   until the daemon has read that it left, so no more than
//!   [`MAX_CONNECTIONS`] sets ever wait.

use std::collections::{BTreeMap, BTreeSet};
use std::sync::atomic::{AtomicU64, AtomicUsize, Ordering};
use std::sync::mpsc::{self, Receiver, RecvTimeoutError, Sender};
use std::sync::{Arc, Mutex};
use std::time::Duration;

use tokio::sync::{OwnedSemaphorePermit, Semaphore};

use super::event::{Event, SceneCommand};

/// How many WebSocket clients may be connected at once.
pub const MAX_CONNECTIONS: usize = 32;
/// How many client commands may wait for the daemon at once.
pub const COMMAND_QUEUE: usize = 64;

/// What a client may ask of the daemon (besides subscriptions).
pub enum Command {
    Rebuild,
    Scene(SceneCommand),
    ResetHistory,
    LoseDevice,
    Trace,
    Preview(super::preview::Request),
    DebugPixel(Option<[u32; 2]>),
}

impl Command {
    fn into_event(self) -> Event {
        match self {
            Command::Rebuild => Event::Rebuild,
            Command::Scene(c) => Event::Scene(c),
            Command::ResetHistory => Event::ResetHistory,
            Command::LoseDevice => Event::LoseDevice,
            Command::Trace => Event::Trace,
            Command::Preview(r) => Event::Preview(r),
            Command::DebugPixel(p) => Event::DebugPixel(p),
        }
    }
}

/// The events [`Command::into_event`] makes: counted while they wait.
fn is_command(event: &Event) -> bool {
    matches!(
        event,
        Event::Rebuild
            | Event::Scene(_)
            | Event::ResetHistory
            | Event::LoseDevice
            | Event::Trace
            | Event::Preview(_)
            | Event::DebugPixel(_)
    )
}

#[derive(Debug, thiserror::Error)]
pub enum Refused {
    #[error("the daemon is busy: {COMMAND_QUEUE} client requests are already waiting for it; try again later")]
    Busy,
    #[error("the daemon is not running")]
    Gone,
}

/// A client's newest set of outputs, not yet read by the daemon.
struct Waiting {
    outputs: BTreeSet<String>,
    /// A leaving client's connection slot: freed when the daemon reads this.
    slot: Option<OwnedSemaphorePermit>,
}

struct Queue {
    tx: Sender<Event>,
    /// Commands sent and not yet read by the daemon.
    commands: AtomicUsize,
    waiting: Mutex<BTreeMap<u64, Waiting>>,
    slots: Arc<Semaphore>,
    next_client: AtomicU64,
}

impl Queue {
    fn waiting(&self) -> std::sync::MutexGuard<'_, BTreeMap<u64, Waiting>> {
        self.waiting.lock().unwrap_or_else(|e| e.into_inner())
    }

    /// Makes `outputs` what the daemon reads next for `client`: it replaces
    /// a set still waiting, else a marker is queued. Nothing is queued when
    /// nothing waits, the set is empty and the daemon holds none for this
    /// client (`told_empty`). `slot` is kept until the daemon reads the set.
    fn set(&self, client: u64, outputs: BTreeSet<String>, told_empty: bool, slot: Option<OwnedSemaphorePermit>) {
        let mut waiting = self.waiting();
        if let Some(w) = waiting.get_mut(&client) {
            w.outputs = outputs;
            w.slot = slot.or(w.slot.take());
        } else if !(outputs.is_empty() && told_empty) {
            // The marker's own set is replaced by the newest when read. If
            // the daemon is gone nothing waits (and the slot is freed).
            if self.tx.send(Event::Subscriptions { client, outputs: BTreeSet::new() }).is_ok() {
                waiting.insert(client, Waiting { outputs, slot });
            }
        }
    }

    /// What the daemon gets for `event` read from the channel.
    fn received(&self, event: Event) -> Event {
        match event {
            Event::Subscriptions { client, outputs } => {
                let newest = self.waiting().remove(&client);
                Event::Subscriptions { client, outputs: newest.map_or(outputs, |w| w.outputs) }
            }
            event => {
                if is_command(&event) {
                    // Never below zero, even for a command sent around the count.
                    let _ = self.commands.fetch_update(Ordering::SeqCst, Ordering::SeqCst, |n| n.checked_sub(1));
                }
                event
            }
        }
    }
}

/// The channel into the daemon: the sender for its own threads (watcher,
/// compile workers, device-lost callback), the bounded way in for clients,
/// and the daemon's receiving end.
pub fn open() -> (Sender<Event>, Clients, Inbox) {
    let (tx, rx) = mpsc::channel();
    let queue = Arc::new(Queue {
        tx: tx.clone(),
        commands: AtomicUsize::new(0),
        waiting: Mutex::new(BTreeMap::new()),
        slots: Arc::new(Semaphore::new(MAX_CONNECTIONS)),
        next_client: AtomicU64::new(1),
    });
    (tx, Clients(queue.clone()), Inbox { rx, queue })
}

/// The HTTP side's way into the daemon.
pub struct Clients(Arc<Queue>);

impl Clients {
    /// Queues `command` for the daemon, or refuses it when
    /// [`COMMAND_QUEUE`] commands already wait or the daemon is gone.
    pub fn command(&self, command: Command) -> Result<(), Refused> {
        let q = &self.0;
        if q.commands.fetch_update(Ordering::SeqCst, Ordering::SeqCst, |n| (n < COMMAND_QUEUE).then_some(n + 1)).is_err() {
            return Err(Refused::Busy);
        }
        q.tx.send(command.into_event()).map_err(|_| {
            q.commands.fetch_sub(1, Ordering::SeqCst);
            Refused::Gone
        })
    }

    /// How many WebSocket clients hold a slot (connected, or left but not
    /// yet read as gone by the daemon).
    pub fn connected(&self) -> usize {
        MAX_CONNECTIONS - self.0.slots.available_permits()
    }

    /// A slot for a new WebSocket client, or `None` when
    /// [`MAX_CONNECTIONS`] are taken.
    pub fn join(&self) -> Option<Client> {
        let slot = self.0.slots.clone().try_acquire_owned().ok()?;
        let id = self.0.next_client.fetch_add(1, Ordering::Relaxed);
        Some(Client { id, queue: self.0.clone(), slot: Some(slot), told_empty: true })
    }
}

/// A connected WebSocket client. Dropping it tells the daemon, when it
/// may hold outputs for this client, that it wants nothing any more.
pub struct Client {
    id: u64,
    queue: Arc<Queue>,
    slot: Option<OwnedSemaphorePermit>,
    /// Whether the last set this client sent was empty.
    told_empty: bool,
}

impl Client {
    /// This client's whole set of outputs, replacing the previous one.
    pub fn subscribe(&mut self, outputs: BTreeSet<String>) {
        let empty = outputs.is_empty();
        self.queue.set(self.id, outputs, self.told_empty, None);
        self.told_empty = empty;
    }
}

impl Drop for Client {
    fn drop(&mut self) {
        self.queue.set(self.id, BTreeSet::new(), self.told_empty, self.slot.take());
    }
}

/// The daemon's receiving end.
pub struct Inbox {
    rx: Receiver<Event>,
    queue: Arc<Queue>,
}

impl Inbox {
    /// As [`Receiver::recv_timeout`]; a `Subscriptions` event carries the
    /// client's newest set.
    pub fn recv_timeout(&self, wait: Duration) -> Result<Event, RecvTimeoutError> {
        let event = self.rx.recv_timeout(wait)?;
        Ok(self.queue.received(event))
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn outputs(event: Result<Event, RecvTimeoutError>) -> BTreeSet<String> {
        match event {
            Ok(Event::Subscriptions { outputs, .. }) => outputs,
            _ => panic!("expected a subscriptions event"),
        }
    }

    #[test]
    fn a_leaving_client_keeps_its_slot_until_the_daemon_reads_that_it_left() {
        let (_tx, clients, inbox) = open();
        let mut joined: Vec<Client> = (0..MAX_CONNECTIONS).map(|_| clients.join().unwrap()).collect();
        assert!(clients.join().is_none());

        // Nothing to tell: the slot is free at once and nothing is queued.
        drop(joined.pop());
        assert!(inbox.recv_timeout(Duration::ZERO).is_err());
        joined.push(clients.join().unwrap());

        // The daemon holds outputs for this one: its slot waits for the read.
        let mut leaving = joined.pop().unwrap();
        leaving.subscribe(BTreeSet::from(["a/b".to_owned()]));
        assert_eq!(outputs(inbox.recv_timeout(Duration::ZERO)), BTreeSet::from(["a/b".to_owned()]));
        drop(leaving);
        assert!(clients.join().is_none());
        assert!(outputs(inbox.recv_timeout(Duration::ZERO)).is_empty());
        assert!(clients.join().is_some());
    }

    #[test]
    fn a_command_for_a_daemon_that_is_gone_is_refused_and_not_counted() {
        let (tx, clients, inbox) = open();
        drop((tx, inbox));
        for _ in 0..=COMMAND_QUEUE {
            assert!(matches!(clients.command(Command::Rebuild), Err(Refused::Gone)));
        }
    }
}
