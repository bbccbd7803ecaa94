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
//! its caller's process. Bulk dataset reads are not armed (their time grows with the data).
//!
//! Crashes: libhdf5 also segfaults on some damaged metadata (`rbc-bench fuzz --format results --seed 3
//! --case 535`: in `H5Aiterate`, listing a run's attributes). A crash cannot be undone either, but it
//! need not end the command with a bare `Segmentation fault`: [`enable`] also installs a handler for
//! SIGSEGV, SIGBUS, SIGFPE, SIGILL and SIGABRT (glibc's malloc aborts on a heap libhdf5 has corrupted)
//! that, while a read of a file is in progress (an armed call, or a
//! longer read marked with [`reading`], e.g. listing the runs of a results file or reading a run's
//! datasets), writes `<program>: <file>: <what>: crashed (SIGSEGV) while libhdf5 read it (damaged HDF5
//! metadata ...)` and ends the process with exit code 2 (`_exit`: nothing else runs after a crash).
//! Outside such a read the signal goes to the handler that was there before (Rust's stack-overflow
//! report, or the default: a core dump), so the crashes of other code are not misnamed. The labels of
//! the reads in progress are kept in static memory, not on the heap libhdf5 may have overwritten before
//! it crashed, and the handler allocates nothing. Costs nothing until a signal comes (a label copy per
//! marked read). Best effort: a crash in our own code during a marked read would be named as libhdf5's,
//! and damaged metadata may also corrupt memory without a signal, which nothing here can see;
//! checkpoints, which are only written by us, are checked before libhdf5 parses them
//! (`crate::checkpoint`). The handler is installed only by [`enable`] (the binaries), never by the library.

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
        crash::install(program);
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
            crash::remove(id);
        }
    }
}

/// Watch the libhdf5 work on `path` until the returned guard is dropped (`what` is built only when
/// the watchdog is enabled). Does nothing when it is not.
pub fn arm(path: &Path, what: impl FnOnce() -> String) -> Armed {
    let Some(w) = WATCHDOG.get() else { return Armed(None) };
    let id = NEXT_ID.fetch_add(1, Ordering::Relaxed);
    let label = format!("{}: {}", path.display(), what());
    crash::push(id, &label);
    if let Ok(mut armed) = w.armed.lock() {
        armed.push((id, Instant::now(), label));
    }
    Armed(Some(id))
}

/// A read of a file in progress, for the crash handler; dropping it ends the read.
pub struct Reading(Option<u64>);

impl Drop for Reading {
    fn drop(&mut self) {
        if let Some(id) = self.0 {
            crash::remove(id);
        }
    }
}

/// Mark a read of `path` (`what`: e.g. "listing the runs") until the returned guard is dropped: a crash
/// meanwhile ends the process with one line naming the file (see the module documentation). Not timed
/// (unlike [`arm`]): for reads whose time grows with the data. Does nothing when the watchdog is not enabled.
pub fn reading(path: &Path, what: impl FnOnce() -> String) -> Reading {
    if WATCHDOG.get().is_none() {
        return Reading(None);
    }
    let id = NEXT_ID.fetch_add(1, Ordering::Relaxed);
    crash::push(id, &format!("{}: {}", path.display(), what()));
    Reading(Some(id))
}

/// What the crash handler's line says after the signal's name, for programs that read it.
pub const CRASH_MESSAGE: &str = "while libhdf5 read it";

mod crash {
    use super::CRASH_MESSAGE;
    use std::sync::{Mutex, OnceLock};

    /// SIGABRT too: glibc's malloc aborts when libhdf5 has corrupted the heap (`malloc(): smallbin double
    /// linked list corrupted`, `rbc-bench fuzz --format results --seed 4 --case 7109`).
    const SIGNALS: [(libc::c_int, &str); 5] =
        [(libc::SIGSEGV, "SIGSEGV"), (libc::SIGBUS, "SIGBUS"), (libc::SIGFPE, "SIGFPE"), (libc::SIGILL, "SIGILL"), (libc::SIGABRT, "SIGABRT")];

    /// The actions in place before [`install`], one per entry of [`SIGNALS`].
    static PREVIOUS: OnceLock<[libc::sigaction; 5]> = OnceLock::new();

    const SLOTS: usize = 16;
    const TEXT: usize = 480;

    /// The reads in progress ("<file>: <what>", innermost last) and the program's name, in static memory:
    /// a libhdf5 that crashes on damaged metadata may first have written over heap memory (a label held
    /// in a `String` came out as NUL bytes in one such crash), and the handler must print what was read.
    struct Labels {
        n: usize,
        id: [u64; SLOTS],
        len: [usize; SLOTS],
        text: [[u8; TEXT]; SLOTS],
        program_len: usize,
        program: [u8; 64],
    }

    static LABELS: Mutex<Labels> = Mutex::new(Labels { n: 0, id: [0; SLOTS], len: [0; SLOTS], text: [[0; TEXT]; SLOTS], program_len: 0, program: [0; 64] });

    fn copy(to: &mut [u8], from: &str) -> usize {
        let n = from.len().min(to.len());
        to[..n].copy_from_slice(&from.as_bytes()[..n]);
        n
    }

    /// A read in progress (more than [`SLOTS`] nested ones: the outer ones are named).
    pub(super) fn push(id: u64, label: &str) {
        if let Ok(mut l) = LABELS.lock() {
            let k = l.n;
            if k < SLOTS {
                l.id[k] = id;
                l.len[k] = copy(&mut l.text[k], label);
                l.n += 1;
            }
        }
    }

    /// The read `id` ended.
    pub(super) fn remove(id: u64) {
        if let Ok(mut l) = LABELS.lock() {
            let n = l.n;
            if let Some(k) = l.id[..n].iter().position(|i| *i == id) {
                for j in k..n - 1 {
                    l.id[j] = l.id[j + 1];
                    l.len[j] = l.len[j + 1];
                    l.text[j] = l.text[j + 1];
                }
                l.n -= 1;
            }
        }
    }

    /// Install [`on_signal`] for the crash signals, keeping the actions before it.
    pub(super) fn install(program: &str) {
        if let Ok(mut l) = LABELS.lock() {
            l.program_len = copy(&mut l.program, program);
        }
        PREVIOUS.get_or_init(|| {
            SIGNALS.map(|(sig, _)| {
                // SAFETY: plain sigaction calls with zero-initialised structs; the handler is async-signal-safe
                // as far as it goes (see `on_signal`). SA_ONSTACK: Rust gives every thread an alternate signal
                // stack, so a stack overflow still reaches the previous (Rust's) handler.
                unsafe {
                    let mut new: libc::sigaction = std::mem::zeroed();
                    new.sa_sigaction = on_signal as *const () as usize;
                    new.sa_flags = libc::SA_SIGINFO | libc::SA_ONSTACK;
                    libc::sigemptyset(&mut new.sa_mask);
                    let mut old: libc::sigaction = std::mem::zeroed();
                    libc::sigaction(sig, &new, &mut old);
                    old
                }
            })
        });
    }

    /// `bytes` to stderr, control characters as `?`, through a buffer on the stack.
    fn write_all(bytes: &[u8]) {
        let mut buf = [0u8; TEXT];
        for chunk in bytes.chunks(TEXT) {
            for (b, c) in buf.iter_mut().zip(chunk) {
                *b = if *c < 0x20 && *c != b'\n' || *c == 0x7f { b'?' } else { *c };
            }
            let mut rest = &buf[..chunk.len()];
            while !rest.is_empty() {
                // SAFETY: write(2) is async-signal-safe; the slice is valid for its length.
                let n = unsafe { libc::write(2, rest.as_ptr().cast(), rest.len()) };
                if n <= 0 {
                    return;
                }
                rest = &rest[n as usize..];
            }
        }
    }

    /// During a read marked by `arm` or `reading`: one line naming the innermost read, then `_exit(2)`.
    /// Otherwise the previous action is put back: a fault (raised by the kernel) then happens again at the
    /// same instruction and reaches it with its own address (Rust's stack-overflow check needs that); a
    /// signal sent by a process is raised again. Allocates nothing and takes no lock it could wait for
    /// (`try_lock`); reads only static memory.
    extern "C" fn on_signal(sig: libc::c_int, info: *mut libc::siginfo_t, _ctx: *mut libc::c_void) {
        let index = SIGNALS.iter().position(|(s, _)| *s == sig).unwrap_or(0);
        if let Ok(l) = LABELS.try_lock() {
            if l.n > 0 {
                let k = l.n - 1;
                let (label, program) = (&l.text[k][..l.len[k].min(TEXT)], &l.program[..l.program_len.min(64)]);
                for part in [program, b": ", label, b": crashed (", SIGNALS[index].1.as_bytes(), b") ", CRASH_MESSAGE.as_bytes(), b" (damaged HDF5 metadata; the file cannot be read: restore it from a copy)\n"] {
                    write_all(part);
                }
                // SAFETY: `_exit` ends the process at once; nothing of ours runs after it.
                unsafe { libc::_exit(2) };
            }
        }
        // SAFETY: sigaction, signal and raise are async-signal-safe; `info` is the kernel's siginfo.
        unsafe {
            match PREVIOUS.get() {
                Some(previous) => libc::sigaction(sig, &previous[index], std::ptr::null_mut()),
                None => libc::signal(sig, libc::SIG_DFL) as libc::c_int,
            };
            // si_code <= 0: sent by kill/raise/sigqueue, not by a fault that would happen again
            if info.is_null() || (*info).si_code <= 0 {
                libc::raise(sig);
            }
        }
    }
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

#[cfg(test)]
mod tests {
    use super::*;

    const CHILD: &str = "RBC_HDF5_WATCH_TEST_CHILD";

    fn recurse(n: u64) -> u64 {
        if n == u64::MAX {
            return 0;
        }
        let a = std::hint::black_box([n; 64]);
        recurse(n + 1).wrapping_add(a[3])
    }

    /// The crash handler names the file of a marked read and exits 2; a crash outside any read reaches
    /// the handler that was there before (here Rust's stack-overflow report), not misnamed as libhdf5's.
    /// Each case runs in a child process (this test binary again), which it ends.
    #[test]
    fn a_crash_during_a_read_is_one_line_and_other_crashes_are_left_alone() {
        match std::env::var(CHILD).as_deref() {
            Ok("read") => {
                enable(Duration::from_secs(60), "child");
                let _r = reading(Path::new("damaged.h5"), || "run `x`: attributes".into());
                // SAFETY: not safe at all: the crash this test is about
                unsafe { std::ptr::read_volatile(std::ptr::null::<u8>()) };
                unreachable!();
            }
            Ok("overflow") => {
                enable(Duration::from_secs(60), "child");
                std::hint::black_box(recurse(0));
                unreachable!();
            }
            _ => {}
        }
        let child = |case: &str| {
            std::process::Command::new(std::env::current_exe().unwrap())
                .args(["--exact", "hdf5_watch::tests::a_crash_during_a_read_is_one_line_and_other_crashes_are_left_alone", "--nocapture", "--test-threads", "1"])
                .env(CHILD, case)
                .output()
                .unwrap()
        };
        let out = child("read");
        let err = String::from_utf8_lossy(&out.stderr);
        assert_eq!(out.status.code(), Some(2), "{err}");
        assert!(err.contains("child: damaged.h5: run `x`: attributes: crashed (SIGSEGV) while libhdf5 read it (damaged HDF5 metadata"), "{err}");
        let out = child("overflow");
        let err = String::from_utf8_lossy(&out.stderr);
        assert!(out.status.code().is_none() && err.contains("has overflowed its stack") && !err.contains(CRASH_MESSAGE), "{err}");
    }
}
