//! What the benchmarks measure time with: the least wall time of repeated calls, the CPU time of
//! this process and the machine's load, the last two from Linux's `/proc` (the one module of the
//! benchmarks that reads it).
//!
//! On a shared machine the wall clock also counts the time other processes hold the cores; the
//! CPU time of a single-threaded measurement does not (std has no CPU clock, and no crate of the
//! workspace offers one).

/// The least wall time (s) of `repeats` (at least one) calls of `f`: the least disturbed run on a
/// shared machine.
pub fn min_wall_s(repeats: usize, mut f: impl FnMut()) -> f64 {
    (0..repeats.max(1))
        .map(|_| {
            let t = std::time::Instant::now();
            f();
            t.elapsed().as_secs_f64()
        })
        .fold(f64::INFINITY, f64::min)
}

/// A rayon pool of `threads` (at least one) threads for a measurement.
pub fn pool(threads: usize) -> rayon::ThreadPool {
    rayon::ThreadPoolBuilder::new().num_threads(threads.max(1)).build().expect("rayon thread pool")
}

/// CPU time (s) of this process so far: the sum over its threads of the first field of
/// `/proc/self/task/*/schedstat` (nanoseconds on a CPU); `None` off Linux.
pub fn process_cpu_s() -> Option<f64> {
    let mut ns = 0u64;
    for e in std::fs::read_dir("/proc/self/task").ok()? {
        let text = std::fs::read_to_string(e.ok()?.path().join("schedstat")).ok()?;
        ns += text.split_whitespace().next()?.parse::<u64>().ok()?;
    }
    Some(ns as f64 * 1e-9)
}

/// CPU time (user + system, s) of this process so far, from `/proc/self/stat` (fields 14 and 15,
/// in clock ticks of 1/100 s: USER_HZ is 100 on Linux; reading it via sysconf would need libc);
/// `None` off Linux. Coarser than [`process_cpu_s`]; the runs of whole scenes report it.
pub fn process_cpu_ticks_s() -> Option<f64> {
    let stat = std::fs::read_to_string("/proc/self/stat").ok()?;
    // the command name (field 2) is in parentheses and may contain spaces
    let rest = &stat[stat.rfind(')')? + 2..];
    let f: Vec<&str> = rest.split_whitespace().collect();
    let utime: f64 = f.get(11)?.parse().ok()?;
    let stime: f64 = f.get(12)?.parse().ok()?;
    Some((utime + stime) / 100.0)
}

/// The least CPU time (s, [`process_cpu_s`]; NaN off Linux) of `repeats` (at least one) calls of
/// `f`, and the result of the last call.
pub fn best_cpu<T>(repeats: usize, mut f: impl FnMut() -> T) -> (f64, T) {
    let mut best = f64::INFINITY;
    let mut out = None;
    for _ in 0..repeats.max(1) {
        let t = process_cpu_s().unwrap_or(f64::NAN);
        out = Some(f());
        best = best.min(process_cpu_s().unwrap_or(f64::NAN) - t);
    }
    (best, out.expect("at least one repeat"))
}

/// The machine's 1, 5 and 15 minute load averages (`/proc/loadavg`), space-separated, or
/// `unknown` off Linux.
pub fn load_average() -> String {
    std::fs::read_to_string("/proc/loadavg")
        .map(|s| s.split_whitespace().take(3).collect::<Vec<_>>().join(" "))
        .unwrap_or_else(|_| "unknown".into())
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Spinning on this thread until the schedstat clock has counted 0.1 s of CPU time: the
    /// tick clock (10 ms coarse, sampled) counts it too, within five ticks, and neither counts more than
    /// the wall time plus a tick (one busy thread). On a loaded machine the spin takes longer in
    /// wall time, not in CPU time.
    #[test]
    fn busy_loop_costs_cpu_time() {
        let (c0, t0) = (process_cpu_s().unwrap(), process_cpu_ticks_s().unwrap());
        let start = std::time::Instant::now();
        let mut x = 0u64;
        while process_cpu_s().unwrap() - c0 < 0.1 && start.elapsed().as_secs_f64() < 30.0 {
            for _ in 0..10_000 {
                x = std::hint::black_box(x.wrapping_add(1));
            }
        }
        let wall = start.elapsed().as_secs_f64();
        let (dc, dt) = (process_cpu_s().unwrap() - c0, process_cpu_ticks_s().unwrap() - t0);
        assert!(dc >= 0.1 && dc <= wall + 0.02, "schedstat {dc} s for {wall} s of wall time");
        assert!((dt - dc).abs() <= 0.05 && dt <= wall + 0.02, "stat {dt} s against schedstat {dc} s for {wall} s of wall time");
        assert_eq!(load_average().split(' ').count(), 3);
    }
}
