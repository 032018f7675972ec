//! Work resolved off the caller's thread, the newest request first: the viewer's frames ask for what a scene
//! needs that takes long to work out (the objects' light and their translucent tables, the particles' light)
//! and draw without it, or with what they had, until it is ready, so that no frame waits on it.
//!
//! One worker thread per `Latest`, one job at a time. A request for another key cancels the job under way (it
//! stops at its next check, `Cancel::stopped`) and replaces any request queued behind it: a burst of edits
//! works out the last one, not each in turn. Only the result of the newest request is kept. The job and its
//! parallel loops (rayon) run on threads of the worker's own at a lower priority than the caller's, so that the
//! frames drawn meanwhile keep the cores (on a software rasteriser, the GPU's work is threads on them too).

use std::sync::atomic::{AtomicBool, Ordering};
use std::sync::{Arc, Condvar, Mutex};

/// Raised when the job's result is no longer wanted.
#[derive(Clone, Debug, Default)]
pub struct Cancel(Arc<AtomicBool>);

impl Cancel {
    /// Whether the job should stop: a newer request has replaced it. A job checks between its stages and
    /// returns `None` when stopped.
    pub fn stopped(&self) -> bool {
        self.0.load(Ordering::Relaxed)
    }

    fn stop(&self) {
        self.0.store(true, Ordering::Relaxed)
    }
}

type Job<V> = Box<dyn FnOnce(&Cancel) -> Option<V> + Send>;

struct State<K, V> {
    /// The newest request not started yet.
    queued: Option<(K, Job<V>)>,
    /// The key of the job under way, and its flag.
    running: Option<(K, Cancel)>,
    /// The result of the newest request that finished.
    done: Option<(K, Arc<V>)>,
    /// The owner is gone: the worker ends.
    closed: bool,
    worker: bool,
}

/// Values of type `V` worked out for keys `K` on a thread of their own, the newest request first.
pub struct Latest<K, V> {
    name: &'static str,
    shared: Arc<(Mutex<State<K, V>>, Condvar)>,
}

/// What a request found.
#[derive(Debug)]
pub enum Poll<V> {
    /// The value for the key asked for.
    Ready(Arc<V>),
    /// Being worked out (or queued); ask again on a later frame.
    Pending,
}

impl<K, V> Latest<K, V>
where
    K: Clone + PartialEq + Send + 'static,
    V: Send + Sync + 'static,
{
    /// A worker named `name` (its thread's name); the thread starts with the first request.
    pub fn new(name: &'static str) -> Self {
        Self {
            name,
            shared: Arc::new((
                Mutex::new(State {
                    queued: None,
                    running: None,
                    done: None,
                    closed: false,
                    worker: false,
                }),
                Condvar::new(),
            )),
        }
    }

    /// The value for `key` if it is ready; else `Pending`, the job `make` builds queued (unless it is under
    /// way or queued already) and any job for another key cancelled. `make` is called only when the job is
    /// queued, so a frame that finds its request under way clones nothing.
    pub fn request<F>(&self, key: &K, make: impl FnOnce() -> F) -> Poll<V>
    where
        F: FnOnce(&Cancel) -> Option<V> + Send + 'static,
    {
        let (lock, wake) = &*self.shared;
        let Ok(mut state) = lock.lock() else {
            return Poll::Pending;
        };
        if let Some((k, v)) = &state.done
            && k == key
        {
            return Poll::Ready(v.clone());
        }
        let running = state.running.as_ref().is_some_and(|(k, _)| k == key);
        let queued = state.queued.as_ref().is_some_and(|(k, _)| k == key);
        if running {
            // Under way: whatever was queued behind it is no longer wanted.
            state.queued = None;
            return Poll::Pending;
        }
        if !queued {
            if let Some((_, cancel)) = &state.running {
                cancel.stop();
            }
            state.queued = Some((key.clone(), Box::new(make())));
            if !state.worker {
                state.worker = self.spawn();
            }
            wake.notify_all();
        }
        Poll::Pending
    }

    /// `request`, waiting up to `budget` for the value: a job quicker than that (most edits of small scenes)
    /// is drawn in the frame that asked for it, a longer one is not waited for.
    pub fn request_within<F>(
        &self,
        key: &K,
        budget: std::time::Duration,
        make: impl FnOnce() -> F,
    ) -> Poll<V>
    where
        F: FnOnce(&Cancel) -> Option<V> + Send + 'static,
    {
        if let Poll::Ready(v) = self.request(key, make) {
            return Poll::Ready(v);
        }
        let deadline = std::time::Instant::now() + budget;
        let (lock, wake) = &*self.shared;
        let Ok(mut state) = lock.lock() else {
            return Poll::Pending;
        };
        loop {
            if let Some((k, v)) = &state.done
                && k == key
            {
                return Poll::Ready(v.clone());
            }
            let waiting = state.running.as_ref().is_some_and(|(k, _)| k == key)
                || state.queued.as_ref().is_some_and(|(k, _)| k == key);
            let left = deadline.saturating_duration_since(std::time::Instant::now());
            if !waiting || left.is_zero() {
                return Poll::Pending;
            }
            state = match wake.wait_timeout(state, left) {
                Ok((s, _)) => s,
                Err(_) => return Poll::Pending,
            };
        }
    }

    /// Whether a job is under way or queued.
    pub fn busy(&self) -> bool {
        let (lock, _) = &*self.shared;
        lock.lock()
            .is_ok_and(|s| s.running.is_some() || s.queued.is_some())
    }

    /// Waits until no job is under way or queued (tests, and renders that must not show a value pending).
    pub fn wait(&self) {
        let (lock, wake) = &*self.shared;
        let Ok(mut state) = lock.lock() else {
            return;
        };
        while state.running.is_some() || state.queued.is_some() {
            match wake.wait(state) {
                Ok(s) => state = s,
                Err(_) => return,
            }
        }
    }

    /// Starts the worker thread; whether it started (else the next request tries again).
    fn spawn(&self) -> bool {
        let shared = self.shared.clone();
        std::thread::Builder::new()
            .name(self.name.into())
            .spawn(move || work(&shared))
            .is_ok()
    }
}

/// Lowers the calling thread's priority (Linux: its nice value, per thread), so that a job leaves the cores to
/// the frames; elsewhere it runs at the priority it has.
fn lower_priority() {
    #[cfg(target_os = "linux")]
    // SAFETY: gettid and setpriority take no pointers; setpriority on this thread's own id changes its nice
    // value alone, and a failure (not permitted) leaves it as it was.
    unsafe {
        let tid = libc::syscall(libc::SYS_gettid) as libc::id_t;
        libc::setpriority(libc::PRIO_PROCESS, tid, 10);
    }
}

/// The worker: the queued job, one at a time, until the owner is gone; its parallel loops on a pool of its own,
/// every thread at a lower priority.
fn work<K: Clone, V: Send>(shared: &(Mutex<State<K, V>>, Condvar)) {
    lower_priority();
    let pool = rayon::ThreadPoolBuilder::new()
        .thread_name(|k| format!("energywave background {k}"))
        .start_handler(|_| lower_priority())
        .build()
        .ok();
    let (lock, wake) = shared;
    loop {
        let (key, job, cancel) = {
            let Ok(mut state) = lock.lock() else { return };
            loop {
                if state.closed {
                    return;
                }
                if let Some((key, job)) = state.queued.take() {
                    let cancel = Cancel::default();
                    state.running = Some((key.clone(), cancel.clone()));
                    break (key, job, cancel);
                }
                state = match wake.wait(state) {
                    Ok(s) => s,
                    Err(_) => return,
                };
            }
        };
        let value = match &pool {
            Some(pool) => pool.install(|| job(&cancel)),
            None => job(&cancel),
        };
        let Ok(mut state) = lock.lock() else { return };
        state.running = None;
        if let Some(v) = value.filter(|_| !cancel.stopped()) {
            state.done = Some((key, Arc::new(v)));
        }
        wake.notify_all();
    }
}

impl<K, V> Drop for Latest<K, V> {
    fn drop(&mut self) {
        let (lock, wake) = &*self.shared;
        if let Ok(mut state) = lock.lock() {
            state.closed = true;
            if let Some((_, cancel)) = &state.running {
                cancel.stop();
            }
        }
        wake.notify_all();
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use std::sync::mpsc;
    use std::time::Duration;

    fn ready<K, V>(l: &Latest<K, V>, key: &K) -> Option<Arc<V>>
    where
        K: Clone + PartialEq + Send + 'static,
        V: Send + Sync + 'static,
    {
        match l.request(key, || |_: &Cancel| -> Option<V> { None }) {
            Poll::Ready(v) => Some(v),
            Poll::Pending => None,
        }
    }

    #[test]
    fn a_value_is_worked_out_once_and_kept() {
        let l: Latest<u32, u32> = Latest::new("test");
        let (tx, rx) = mpsc::channel();
        assert!(matches!(
            l.request(&3, move || move |_: &Cancel| {
                tx.send(()).unwrap();
                Some(9)
            }),
            Poll::Pending
        ));
        l.wait();
        assert_eq!(rx.try_iter().count(), 1);
        assert_eq!(ready(&l, &3).as_deref(), Some(&9));
        // Asked again: kept, not worked out again (the job `ready` would queue returns nothing).
        assert_eq!(ready(&l, &3).as_deref(), Some(&9));
        assert!(!l.busy());
    }

    #[test]
    fn a_newer_request_cancels_the_job_under_way_and_only_its_result_is_kept() {
        let l: Latest<u32, u32> = Latest::new("test");
        let (started, wait_started) = mpsc::channel();
        let (release, held) = mpsc::channel::<()>();
        let seen_stop = Arc::new(AtomicBool::new(false));
        let seen = seen_stop.clone();
        let _ = l.request(&1, move || {
            move |cancel: &Cancel| {
                started.send(()).unwrap();
                held.recv().unwrap();
                seen.store(cancel.stopped(), Ordering::SeqCst);
                (!cancel.stopped()).then_some(10)
            }
        });
        wait_started.recv_timeout(Duration::from_secs(10)).unwrap();
        // Two newer requests while the first runs: the first is cancelled, the second replaced by the third.
        let ran_2 = Arc::new(AtomicBool::new(false));
        let r2 = ran_2.clone();
        let _ = l.request(&2, move || {
            move |_: &Cancel| {
                r2.store(true, Ordering::SeqCst);
                Some(20)
            }
        });
        let _ = l.request(&3, || |_: &Cancel| Some(30));
        release.send(()).unwrap();
        l.wait();
        assert!(
            seen_stop.load(Ordering::SeqCst),
            "the job under way saw it was stopped"
        );
        assert!(
            !ran_2.load(Ordering::SeqCst),
            "a request replaced while queued never runs"
        );
        assert_eq!(ready(&l, &3).as_deref(), Some(&30));
        assert!(ready(&l, &1).is_none() && ready(&l, &2).is_none());
    }

    #[test]
    fn a_quick_job_is_waited_for_and_a_slow_one_is_not() {
        let l: Latest<u32, u32> = Latest::new("test");
        let quick = l.request_within(&1, Duration::from_secs(30), || |_: &Cancel| Some(1));
        assert!(matches!(quick, Poll::Ready(v) if *v == 1));
        let (release, held) = mpsc::channel::<()>();
        let slow = l.request_within(&2, Duration::from_millis(20), move || {
            move |_: &Cancel| {
                held.recv().unwrap();
                Some(2)
            }
        });
        assert!(matches!(slow, Poll::Pending));
        release.send(()).unwrap();
        l.wait();
        assert_eq!(ready(&l, &2).as_deref(), Some(&2));
    }

    #[test]
    fn asking_again_for_the_job_under_way_does_not_restart_it() {
        let l: Latest<u32, u32> = Latest::new("test");
        let (release, held) = mpsc::channel::<()>();
        let runs = Arc::new(Mutex::new(0));
        let r = runs.clone();
        let _ = l.request(&1, move || {
            move |_: &Cancel| {
                *r.lock().unwrap() += 1;
                held.recv().unwrap();
                Some(1)
            }
        });
        for _ in 0..5 {
            assert!(ready(&l, &1).is_none());
        }
        release.send(()).unwrap();
        l.wait();
        assert_eq!(*runs.lock().unwrap(), 1);
        assert_eq!(ready(&l, &1).as_deref(), Some(&1));
    }
}
