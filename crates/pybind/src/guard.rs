//! The boundary between Python and the core: no panic crosses it, and long calls stay
//! cancellable.
//!
//! [`run`] does the core's work on a worker thread with the GIL released, while the calling
//! thread (Python's main thread in a script or the CLI) polls every 20 ms for Ctrl-C and
//! forwards progress to the Python callback. Ctrl-C or a callback returning `False` sets an
//! atomic flag that the core's loops ask between small work items ([`Progress::cancelled`]),
//! so every method stops within a fraction of a second. Signals can only be checked on the
//! main thread, which is why the callback is never called from the core's threads.
//! [`catch`] turns a panic of a short call into `gi.InternalError`.

use crate::errors::{internal, to_py};
use gi_core::Progress;
use pyo3::prelude::*;
use std::panic::{catch_unwind, AssertUnwindSafe};
use std::sync::atomic::{AtomicBool, Ordering};
use std::sync::{mpsc, Mutex};
use std::time::{Duration, Instant};

/// How often the calling thread checks for Ctrl-C and forwards progress.
const POLL: Duration = Duration::from_millis(20);
/// Least time between two progress calls of the same unfinished stage.
const CALLBACK_INTERVAL: Duration = Duration::from_millis(100);
/// The callback is called at least this often while a render runs (with the last progress
/// reported), so that it can cancel during stages that report rarely.
const HEARTBEAT: Duration = Duration::from_millis(250);
/// Stack of the worker thread (the core's recursive builders run on it).
const WORKER_STACK: usize = 16 << 20;

/// Progress shared between the core's threads and the polling thread.
#[derive(Default)]
struct Poller {
    cancelled: AtomicBool,
    state: Mutex<PollState>,
}

#[derive(Default)]
struct PollState {
    /// Stages that reported completion (fraction 1) since the last poll, in order.
    finished: Vec<String>,
    /// The last progress reported, and whether it is new since the last callback.
    latest: Option<(String, f64)>,
    fresh: bool,
}

impl Progress for Poller {
    fn update(&self, stage: &str, fraction: f64) -> bool {
        let mut s = self.state.lock().unwrap_or_else(|p| p.into_inner());
        if fraction >= 1.0 && s.finished.last().map(String::as_str) != Some(stage) {
            s.finished.push(stage.to_string());
        }
        match &mut s.latest {
            Some((name, f)) if name.as_str() == stage => *f = fraction,
            latest => *latest = Some((stage.to_string(), fraction)),
        }
        s.fresh = true;
        !self.cancelled()
    }

    fn cancelled(&self) -> bool {
        self.cancelled.load(Ordering::Relaxed)
    }
}

/// Calls the Python progress callback on the calling thread.
struct Forwarder<'a> {
    callback: Option<&'a Py<PyAny>>,
    last_call: Option<Instant>,
}

impl Forwarder<'_> {
    /// Forwards what is due; `Ok(false)` when the callback returned `False`. `end`: the
    /// render is over, deliver every finished stage and nothing else.
    fn forward(&mut self, py: Python<'_>, poller: &Poller, end: bool) -> PyResult<bool> {
        let Some(cb) = self.callback else {
            return Ok(true);
        };
        let (finished, latest) = {
            let mut s = poller.state.lock().unwrap_or_else(|p| p.into_inner());
            let since = self.last_call.map(|t| t.elapsed());
            let due = since.is_none_or(|d| d >= CALLBACK_INTERVAL) && s.fresh
                || since.is_some_and(|d| d >= HEARTBEAT);
            let latest = match &s.latest {
                Some((stage, f)) if due && !end && *f < 1.0 => Some((stage.clone(), *f)),
                _ => None,
            };
            if latest.is_some() {
                s.fresh = false;
            }
            (std::mem::take(&mut s.finished), latest)
        };
        let calls = finished.into_iter().map(|s| (s, 1.0)).chain(latest);
        for (stage, fraction) in calls {
            self.last_call = Some(Instant::now());
            let r = cb.call1(py, (stage, fraction))?;
            if r.bind(py).is(&*pyo3::types::PyBool::new(py, false)) {
                return Ok(false);
            }
        }
        Ok(true)
    }
}

/// Runs `work` on a worker thread with the GIL released, polling Ctrl-C and forwarding
/// progress to `callback` `(stage, fraction) -> bool | None` on the calling thread. Ctrl-C
/// raises `KeyboardInterrupt`, an exception of the callback propagates, a `False` from it
/// raises `gi.RenderCancelled`, a panic raises `gi.InternalError` naming `what`.
pub fn run<T: Send>(
    py: Python<'_>,
    what: &str,
    callback: Option<&Py<PyAny>>,
    work: impl FnOnce(&dyn Progress) -> gi_core::Result<T> + Send,
) -> PyResult<T> {
    let poller = Poller::default();
    let mut forwarder = Forwarder {
        callback,
        last_call: None,
    };
    let mut py_error: Option<PyErr> = None;
    let outcome = py.detach(|| {
        std::thread::scope(|scope| {
            let (tx, rx) = mpsc::channel::<()>();
            let poller = &poller;
            let worker = std::thread::Builder::new()
                .name("gi-worker".into())
                .stack_size(WORKER_STACK)
                .spawn_scoped(scope, move || {
                    let r = catch_unwind(AssertUnwindSafe(|| work(poller)));
                    let _ = tx.send(());
                    // The GPU counters are per thread: hand the worker's to the caller.
                    (r, gi_core::gpu::alloc::counters())
                });
            let worker = match worker {
                Ok(w) => w,
                Err(e) => return Err(format!("cannot start a worker thread: {e}")),
            };
            loop {
                match rx.recv_timeout(POLL) {
                    Ok(()) | Err(mpsc::RecvTimeoutError::Disconnected) => break,
                    Err(mpsc::RecvTimeoutError::Timeout) => {}
                }
                if poller.cancelled() {
                    continue; // wait for the worker to notice
                }
                let go_on = Python::attach(|py| {
                    py.check_signals()?;
                    forwarder.forward(py, poller, false)
                });
                match go_on {
                    Ok(true) => {}
                    Ok(false) => poller.cancelled.store(true, Ordering::Relaxed),
                    Err(e) => {
                        py_error = Some(e);
                        poller.cancelled.store(true, Ordering::Relaxed);
                    }
                }
            }
            let (result, counters) = worker
                .join()
                .map_err(|_| "the worker thread died".to_string())?;
            gi_core::gpu::alloc::merge(counters);
            Ok(result)
        })
    });
    if let Some(e) = py_error {
        return Err(e);
    }
    match outcome {
        Ok(Ok(Ok(value))) => {
            // Deliver the stages that finished since the last poll (e.g. the final 100%).
            if !forwarder.forward(py, &poller, true)? {
                return Err(to_py(py, gi_core::Error::Cancelled));
            }
            Ok(value)
        }
        Ok(Ok(Err(e))) => Err(to_py(py, e)),
        Ok(Err(payload)) => Err(internal(what, payload)),
        Err(msg) => Err(internal(what, Box::new(msg))),
    }
}

/// Runs a short call `f`, turning a panic into `gi.InternalError` naming `what`.
pub fn catch<T>(what: &str, f: impl FnOnce() -> PyResult<T>) -> PyResult<T> {
    catch_unwind(AssertUnwindSafe(f)).unwrap_or_else(|payload| Err(internal(what, payload)))
}

/// Waits until the GPU work of every device gi opened has finished; `gi` calls it at
/// interpreter exit, since lavapipe crashes a process that exits while it still works.
#[pyfunction]
#[pyo3(name = "_wait_gpu_idle")]
pub fn wait_gpu_idle(py: Python<'_>) {
    py.detach(gi_core::gpu::wait_idle_all);
}

/// Panics inside the core's worker thread, to show that a panic becomes `gi.InternalError`.
#[pyfunction]
#[pyo3(name = "_panic_for_tests")]
pub fn panic_for_tests(py: Python<'_>) -> PyResult<()> {
    run(py, "_panic_for_tests", None, |_| -> gi_core::Result<()> {
        panic!("a deliberate panic")
    })
}

/// Returns a core [`gi_core::Error::Internal`] (a broken invariant), to show that it becomes
/// `gi.InternalError`, not `gi.RenderCancelled`.
#[pyfunction]
#[pyo3(name = "_internal_error_for_tests")]
pub fn internal_error_for_tests(py: Python<'_>) -> PyResult<()> {
    run(
        py,
        "_internal_error_for_tests",
        None,
        |_| -> gi_core::Result<()> {
            Err(gi_core::Error::Internal(
                "a deliberate broken invariant".into(),
            ))
        },
    )
}
