//! Work a scene hands to a thread of its own so that no frame waits for it: its result taken
//! on the first frame it is ready, the thread joined then — and when the job is dropped, so
//! that no worker is still inside the driver when the scene (or the process) goes.

use std::sync::mpsc::{Receiver, TryRecvError};
use std::thread::JoinHandle;

/// A result being made on a worker thread.
pub struct Job<T> {
    result: Receiver<T>,
    thread: Option<JoinHandle<()>>,
}

impl<T: Send + 'static> Job<T> {
    /// Run `work` on a new thread.
    pub fn spawn(work: impl FnOnce() -> T + Send + 'static) -> Self {
        let (tx, result) = std::sync::mpsc::channel();
        let thread = std::thread::spawn(move || {
            let _ = tx.send(work());
        });
        Self {
            result,
            thread: Some(thread),
        }
    }

    /// A job whose result is already known.
    pub fn done(value: T) -> Self {
        let (tx, result) = std::sync::mpsc::channel();
        let _ = tx.send(value);
        Self {
            result,
            thread: None,
        }
    }

    /// The result if it is ready (the thread joined), `None` while it is being made; `Some(None)`
    /// if the thread ended without one (it panicked).
    pub fn try_take(&mut self) -> Option<Option<T>> {
        let out = match self.result.try_recv() {
            Ok(value) => Some(value),
            Err(TryRecvError::Empty) => return None,
            Err(TryRecvError::Disconnected) => None,
        };
        self.join();
        Some(out)
    }

    /// Wait for the result (headless runs that need a settled scene); `None` if the thread
    /// ended without one. The job then holds it, ready for [`Self::try_take`].
    pub fn wait(self) -> Self {
        match self.result.recv() {
            Ok(value) => Self::done(value),
            Err(_) => {
                let (_, result) = std::sync::mpsc::channel();
                Self {
                    result,
                    thread: None,
                }
            }
        }
    }

    fn join(&mut self) {
        if let Some(thread) = self.thread.take() {
            // Its panic, if any, already showed as a missing result.
            let _ = thread.join();
        }
    }
}

impl<T> Drop for Job<T> {
    fn drop(&mut self) {
        if let Some(thread) = self.thread.take() {
            let _ = thread.join();
        }
    }
}
