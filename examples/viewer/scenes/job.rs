//! Work a scene hands to a thread of its own so that no frame waits for it: its result taken
//! on the first frame it is ready, the thread joined then — and when the job is dropped, so
//! that no worker is still inside the driver when the scene (or the process) goes.

use std::sync::mpsc::{Receiver, TryRecvError};
use std::thread::JoinHandle;

use fieldkit::Error;

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

/// A value made on a worker thread for a key (a renderer for some settings): the last one
/// made keeps serving while the next is made, so a change of settings never waits for it. A
/// key whose making failed gives that error whenever it is asked for, without trying again.
pub struct Latest<K, T> {
    current: Option<(K, T)>,
    next: Option<(K, Job<Result<T, Error>>)>,
    failed: Option<(K, Error)>,
}

impl<K, T> Default for Latest<K, T> {
    fn default() -> Self {
        Self {
            current: None,
            next: None,
            failed: None,
        }
    }
}

impl<K: PartialEq + Clone, T: Send + 'static> Latest<K, T> {
    /// The value for `key`; while it is being made (`make` runs on a worker thread when
    /// `key` is neither the current key nor being made), the one made for an earlier key, or
    /// `None` before the first arrives. A worker still making a value for another key is
    /// left to end (the frame never joins a running thread); `key`'s starts after it.
    pub fn get(
        &mut self,
        key: &K,
        make: impl FnOnce() -> Result<T, Error> + Send + 'static,
    ) -> Result<Option<&mut T>, Error> {
        self.poll();
        if let Some((k, e)) = &self.failed
            && k == key
        {
            return Err(e.clone());
        }
        if !self.has(key) && self.next.is_none() {
            self.next = Some((key.clone(), Job::spawn(make)));
        }
        Ok(self.current.as_mut().map(|c| &mut c.1))
    }

    /// Take the value being made if it is ready (a scene that no longer asks for it calls
    /// this every frame, so that it does not stay busy).
    pub fn poll(&mut self) {
        if let Some((_, job)) = &mut self.next
            && let Some(result) = job.try_take()
        {
            let (k, _) = self.next.take().expect("checked");
            match result {
                Some(Ok(value)) => self.current = Some((k, value)),
                Some(Err(e)) => self.failed = Some((k, e)),
                None => self.failed = Some((k, Error::invalid("viewer", "its worker panicked"))),
            }
        }
    }

    /// Take `value`, made elsewhere for `key` (a worker that made it with other work).
    pub fn put(&mut self, key: K, value: T) {
        self.current = Some((key, value));
    }

    /// The value in use (made for the key last asked for, or an earlier one).
    pub fn current(&self) -> Option<&T> {
        self.current.as_ref().map(|c| &c.1)
    }

    /// The value in use if it was made for `key`.
    pub fn ready(&self, key: &K) -> Option<&T> {
        self.current.as_ref().filter(|c| &c.0 == key).map(|c| &c.1)
    }

    /// The value in use and the key it was made for.
    pub fn current_with_key(&self) -> Option<(&K, &T)> {
        self.current.as_ref().map(|(k, v)| (k, v))
    }

    /// Whether the current value is `key`'s.
    pub fn has(&self, key: &K) -> bool {
        self.current.as_ref().is_some_and(|c| &c.0 == key)
    }

    /// Whether a value is being made, or is made and not yet taken. A scene that asks for a
    /// key every frame starts its making the frame the previous one is taken, so between its
    /// frames it is busy until the value it asks for is there; one that stopped asking is not.
    pub fn busy(&self) -> bool {
        self.next.is_some()
    }

    /// Wait for the value being made (headless runs that need a settled scene); the next
    /// [`Self::get`] takes it.
    pub fn wait(&mut self) {
        if let Some((k, job)) = self.next.take() {
            self.next = Some((k, job.wait()));
        }
    }
}
