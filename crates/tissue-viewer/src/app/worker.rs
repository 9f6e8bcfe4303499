//! One background-worker type for every thread the viewer starts (the physics thread, a
//! calibration, the chart, the FEM answer of a load case): a named thread, a typed channel of
//! messages to the UI, a wake-up of the UI after each message, a cancel flag, "finished" or
//! "stopped unexpectedly" once the thread is gone, and a join on drop. A [`Slot`] holds at most
//! one worker of a kind and refuses a second job while one runs.

use std::sync::Arc;
use std::sync::atomic::{AtomicBool, Ordering};
use std::sync::mpsc::{Receiver, Sender, TryRecvError, channel};
use std::thread::JoinHandle;

/// What a worker's body sees: the channel to the UI and the cancel flag.
pub struct Context<M> {
    tx: Sender<M>,
    cancel: Arc<AtomicBool>,
    wake: Arc<dyn Fn() + Send + Sync>,
}

impl<M> Context<M> {
    /// Sends a message to the UI and wakes it; `false` once the UI side is gone.
    pub fn send(&self, message: M) -> bool {
        let sent = self.tx.send(message).is_ok();
        (self.wake)();
        sent
    }

    /// Whether the UI asked the worker to stop.
    pub fn cancelled(&self) -> bool {
        self.cancel.load(Ordering::Relaxed)
    }

    /// The cancel flag itself (for core functions that take an `&AtomicBool`).
    pub fn cancel_flag(&self) -> &AtomicBool {
        &self.cancel
    }

    /// A shared handle to the cancel flag (for core options that carry one).
    pub fn cancel_handle(&self) -> Arc<AtomicBool> {
        Arc::clone(&self.cancel)
    }
}

/// Where a worker stands after a [`Worker::poll`].
#[derive(Debug, Clone, PartialEq, Eq)]
pub enum State {
    /// Still running.
    Running,
    /// Its body returned; every message it sent has been delivered.
    Finished,
    /// It ended without returning (a panic): what it said, if anything.
    Stopped(String),
}

/// A running (or ended) background thread sending messages of type `M`.
pub struct Worker<M> {
    name: String,
    rx: Receiver<M>,
    cancel: Arc<AtomicBool>,
    completed: Arc<AtomicBool>,
    handle: Option<JoinHandle<()>>,
    state: State,
}

impl<M> std::fmt::Debug for Worker<M> {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.debug_struct("Worker").field("name", &self.name).field("state", &self.state).finish()
    }
}

impl<M: Send + 'static> Worker<M> {
    /// Starts `body` on a thread called `name`; `wake` is called after every message (to
    /// repaint the UI) and when the thread ends.
    pub fn spawn(
        name: &str,
        wake: impl Fn() + Send + Sync + 'static,
        body: impl FnOnce(&Context<M>) + Send + 'static,
    ) -> std::io::Result<Self> {
        let (tx, rx) = channel();
        let cancel = Arc::new(AtomicBool::new(false));
        let completed = Arc::new(AtomicBool::new(false));
        let wake: Arc<dyn Fn() + Send + Sync> = Arc::new(wake);
        let ctx = Context { tx, cancel: Arc::clone(&cancel), wake: Arc::clone(&wake) };
        let done = Arc::clone(&completed);
        let handle = std::thread::Builder::new().name(name.to_owned()).spawn(move || {
            // Wakes the UI when the thread ends, however it ends.
            struct WakeOnExit(Arc<dyn Fn() + Send + Sync>);
            impl Drop for WakeOnExit {
                fn drop(&mut self) {
                    (self.0)();
                }
            }
            let _exit = WakeOnExit(Arc::clone(&ctx.wake));
            body(&ctx);
            done.store(true, Ordering::Release);
        })?;
        Ok(Self { name: name.to_owned(), rx, cancel, completed, handle: Some(handle), state: State::Running })
    }
}

impl<M> Worker<M> {
    /// Hands every message received since the last call to `on_message` (no allocation), then
    /// says whether the worker still runs.
    pub fn poll(&mut self, mut on_message: impl FnMut(M)) -> &State {
        if self.state != State::Running {
            return &self.state;
        }
        loop {
            match self.rx.try_recv() {
                Ok(m) => on_message(m),
                Err(TryRecvError::Empty) => return &self.state,
                Err(TryRecvError::Disconnected) => break,
            }
        }
        // Disconnected: the thread is gone and every message it sent has been delivered.
        let joined = self.handle.take().map(JoinHandle::join);
        self.state = match joined {
            Some(Ok(())) if self.completed.load(Ordering::Acquire) => State::Finished,
            Some(Err(panic)) => State::Stopped(panic_text(&*panic)),
            _ => State::Stopped(String::new()),
        };
        &self.state
    }

    /// Asks the worker to stop (it checks [`Context::cancelled`]).
    pub fn cancel(&self) {
        self.cancel.store(true, Ordering::Relaxed);
    }

    /// Whether the worker still runs (as of the last [`Worker::poll`]).
    pub fn running(&self) -> bool {
        self.state == State::Running
    }

    /// The thread's name.
    pub fn name(&self) -> &str {
        &self.name
    }
}

impl<M> Drop for Worker<M> {
    fn drop(&mut self) {
        self.cancel();
        if let Some(h) = self.handle.take() {
            let _ = h.join();
        }
    }
}

fn panic_text(panic: &(dyn std::any::Any + Send)) -> String {
    if let Some(s) = panic.downcast_ref::<&str>() {
        (*s).to_owned()
    } else if let Some(s) = panic.downcast_ref::<String>() {
        s.clone()
    } else {
        String::new()
    }
}

/// At most one worker of a kind.
pub struct Slot<M> {
    worker: Option<Worker<M>>,
}

impl<M> Default for Slot<M> {
    fn default() -> Self {
        Self { worker: None }
    }
}

impl<M> std::fmt::Debug for Slot<M> {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.debug_struct("Slot").field("worker", &self.worker).finish()
    }
}

/// A second job of a kind while one runs.
#[derive(Debug, Clone, PartialEq, Eq, thiserror::Error)]
#[error("the {0} is already running: cancel it or wait for it to finish")]
pub struct Busy(pub String);

impl<M: Send + 'static> Slot<M> {
    /// Starts a job, unless one is running (then [`Busy`], naming the running job).
    pub fn start(
        &mut self,
        what: &str,
        wake: impl Fn() + Send + Sync + 'static,
        body: impl FnOnce(&Context<M>) + Send + 'static,
    ) -> Result<(), StartError> {
        if self.busy() {
            return Err(StartError::Busy(Busy(what.to_owned())));
        }
        self.worker = Some(Worker::spawn(what, wake, body).map_err(StartError::Spawn)?);
        Ok(())
    }
}

/// Why a job did not start.
#[derive(Debug, thiserror::Error)]
pub enum StartError {
    /// One of the same kind runs.
    #[error(transparent)]
    Busy(Busy),
    /// The thread could not be created.
    #[error("cannot start a thread: {0}")]
    Spawn(std::io::Error),
}

impl<M> Slot<M> {
    /// Whether a job runs.
    pub fn busy(&self) -> bool {
        self.worker.as_ref().is_some_and(Worker::running)
    }

    /// Delivers the running job's messages; returns how it ended, once, when it has (and frees
    /// the slot).
    pub fn poll(&mut self, on_message: impl FnMut(M)) -> Option<State> {
        let w = self.worker.as_mut()?;
        let state = w.poll(on_message).clone();
        if state == State::Running {
            None
        } else {
            self.worker = None;
            Some(state)
        }
    }

    /// Asks the running job to stop.
    pub fn cancel(&self) {
        if let Some(w) = &self.worker {
            w.cancel();
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn wait_for<M>(slot: &mut Slot<M>, mut on: impl FnMut(M)) -> State {
        for _ in 0..2000 {
            if let Some(s) = slot.poll(&mut on) {
                return s;
            }
            std::thread::sleep(std::time::Duration::from_millis(1));
        }
        State::Running
    }

    #[test]
    fn messages_arrive_then_finished() {
        let mut slot: Slot<u32> = Slot::default();
        slot.start(
            "counter",
            || {},
            |ctx| {
                for i in 0..5 {
                    ctx.send(i);
                }
            },
        )
        .expect("starts");
        let mut got = Vec::new();
        assert_eq!(wait_for(&mut slot, |m| got.push(m)), State::Finished);
        assert_eq!(got, [0, 1, 2, 3, 4]);
        assert!(!slot.busy());
    }

    #[test]
    fn a_worker_that_dies_is_reported_as_stopped() {
        let mut slot: Slot<u32> = Slot::default();
        slot.start(
            "doomed",
            || {},
            |ctx| {
                ctx.send(1);
                panic!("out of luck");
            },
        )
        .expect("starts");
        let mut got = Vec::new();
        let state = wait_for(&mut slot, |m| got.push(m));
        assert_eq!(state, State::Stopped("out of luck".into()));
        assert_eq!(got, [1], "messages sent before the panic are delivered");
    }

    #[test]
    fn a_second_job_is_refused_and_cancel_stops_the_first() {
        let mut slot: Slot<()> = Slot::default();
        let woken = Arc::new(std::sync::atomic::AtomicUsize::new(0));
        let w = Arc::clone(&woken);
        slot.start(
            "calibration",
            move || _ = w.fetch_add(1, Ordering::Relaxed),
            |ctx| {
                while !ctx.cancelled() {
                    std::thread::sleep(std::time::Duration::from_millis(1));
                }
            },
        )
        .expect("starts");
        let second = slot.start("calibration", || {}, |_| {});
        assert!(matches!(second, Err(StartError::Busy(_))), "{second:?}");
        assert!(second.err().is_some_and(|e| e.to_string().contains("calibration is already running")));
        slot.cancel();
        assert_eq!(wait_for(&mut slot, |()| {}), State::Finished);
        assert!(woken.load(Ordering::Relaxed) >= 1, "the UI is woken when the thread ends");
        slot.start("calibration", || {}, |_| {}).expect("free again");
    }
}
