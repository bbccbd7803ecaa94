//! A watchdog for the libhdf5 calls that can hang on a damaged file: a call that does not return in
//! time ends the process with a one-line error naming the file and what was being read.
//!
//! libhdf5 1.10.8 (Debian 12's) loops forever on some damaged metadata: `rbc-bench fuzz --format
//! results --seed 1 --case 239` enlarges a global heap collection's size field by one bit (4096 ->
//! 4352 bytes), and `H5Aread` of a variable-length string attribute then never returns (its
//! collection decoder, `H5HG__cache_heap_deserialize` under `H5HG_read`, walks objects whose decoded
//! size makes it stand still). Such a call cannot be cancelled in-process: it holds libhdf5's (and
//! hdf5-metno's) global lock, so every later HDF5 call would block too. What a command can do is not
//! hang: [`enable`] starts a thread that watches the calls armed with [`arm`] (opening a file, reading
//! an attribute, reading a checkpoint: metadata work of milliseconds, never proportional to the data)
//! and, when one has run longer than the limit, prints
//! `<program>: <file>: <what>: libhdf5 did not return within N s (...)` and ends the process with exit
//! code 2 through `_exit`, which skips the `atexit` hook libhdf5 registers (it would touch the
//! structures the stuck call is still looping in).
//!
//! Off unless a program enables it (the binaries do, with [`enable_from_env`]): a library must not end
//! its caller's process. Bulk dataset reads are not armed (their time grows with the data). Crashes
//! inside libhdf5 (a segfault on other damaged metadata) are not caught.

use std::path::Path;
use std::sync::atomic::{AtomicU64, Ordering};
use std::sync::{Mutex, OnceLock};
use std::time::{Duration, Instant};

/// Seconds a watched call may take unless `RBC_HDF5_TIMEOUT_S` says otherwise: generous for metadata
/// reads of milliseconds on a loaded machine or a slow network file system.
pub const DEFAULT_LIMIT_S: f64 = 60.0;

/// The environment variable of the limit (seconds; `0` or `off`: no watchdog).
pub const LIMIT_ENV: &str = "RBC_HDF5_TIMEOUT_S";

/// What the watchdog's line says (after `<program>: <file>: <what>: `), for programs that read it.
pub const MESSAGE: &str = "libhdf5 did not return within";

struct Watchdog {
    limit: Duration,
    program: String,
    /// Calls in progress: (id, start, "<file>: <what>").
    armed: Mutex<Vec<(u64, Instant, String)>>,
}

static WATCHDOG: OnceLock<Watchdog> = OnceLock::new();
static NEXT_ID: AtomicU64 = AtomicU64::new(0);

/// Start watching armed calls: one that runs longer than `limit` ends the process (see the module
/// documentation); `program` starts the message. Only the first call has an effect.
pub fn enable(limit: Duration, program: &str) {
    let mut started = false;
    WATCHDOG.get_or_init(|| {
        started = true;
        Watchdog { limit, program: program.to_string(), armed: Mutex::new(Vec::new()) }
    });
    if started {
        std::thread::Builder::new().name("hdf5-watchdog".into()).spawn(watch_loop).expect("spawning the HDF5 watchdog thread");
    }
}

/// [`enable`] with the limit of `RBC_HDF5_TIMEOUT_S` (seconds, > 0; `0` or `off`: not enabled),
/// [`DEFAULT_LIMIT_S`] when unset. Returns the limit in force.
pub fn enable_from_env(program: &str) -> Option<Duration> {
    let limit_s = match std::env::var(LIMIT_ENV) {
        Ok(v) if v.trim() == "off" => return None,
        Ok(v) => v.trim().parse::<f64>().ok().filter(|s| s.is_finite() && *s >= 0.0).unwrap_or(DEFAULT_LIMIT_S),
        Err(_) => DEFAULT_LIMIT_S,
    };
    if limit_s == 0.0 {
        return None;
    }
    let limit = Duration::from_secs_f64(limit_s);
    enable(limit, program);
    Some(limit)
}

/// A watched call in progress; dropping it ends the watch.
pub struct Armed(Option<u64>);

impl Drop for Armed {
    fn drop(&mut self) {
        if let (Some(id), Some(w)) = (self.0, WATCHDOG.get()) {
            if let Ok(mut armed) = w.armed.lock() {
                armed.retain(|(i, _, _)| *i != id);
            }
        }
    }
}

/// Watch the libhdf5 work on `path` until the returned guard is dropped (`what` is built only when
/// the watchdog is enabled). Does nothing when it is not.
pub fn arm(path: &Path, what: impl FnOnce() -> String) -> Armed {
    let Some(w) = WATCHDOG.get() else { return Armed(None) };
    let id = NEXT_ID.fetch_add(1, Ordering::Relaxed);
    let label = format!("{}: {}", path.display(), what());
    if let Ok(mut armed) = w.armed.lock() {
        armed.push((id, Instant::now(), label));
    }
    Armed(Some(id))
}

fn watch_loop() {
    let Some(w) = WATCHDOG.get() else { return };
    let tick = (w.limit / 20).clamp(Duration::from_millis(10), Duration::from_secs(1));
    loop {
        std::thread::sleep(tick);
        let stuck = w.armed.lock().ok().and_then(|armed| armed.iter().find(|(_, t0, _)| t0.elapsed() > w.limit).map(|(_, _, what)| what.clone()));
        if let Some(what) = stuck {
            let line = format!(
                "{}: {what}: {MESSAGE} {} s (damaged HDF5 metadata that libhdf5 loops on; the file cannot be read: restore it from a copy)\n",
                w.program,
                w.limit.as_secs_f64()
            );
            use std::io::Write;
            let mut err = std::io::stderr().lock();
            let _ = err.write_all(line.as_bytes());
            let _ = err.flush();
            // SAFETY: `_exit` ends the process at once; nothing of ours runs after it.
            unsafe { libc::_exit(2) };
        }
    }
}
