//! The C allocator's thresholds for the long runs of the command-line front ends.
//!
//! A velocity evaluation of the paper's channel allocates and frees many 0.1-30 MB temporaries
//! (Ewald grids, block rows, spreading maps). With glibc's defaults the threshold above which a
//! block is mapped afresh adapts (up to 32 MB) and the heap top is returned to the kernel once more
//! than twice that is free, so the same memory is unmapped and faulted in again at every
//! evaluation: measured 2 ms of the study's late r_init = 1.2 um state, 869k minor page faults and
//! 2.8 s of system time in ~40 core-s. Fixing the mmap threshold at its maximum (32 MB) and never
//! trimming the heap top keeps the freed pages for the next evaluation: 72k faults, 0.4 s of system
//! time, the same results bit for bit (`solver/README.md`, session 11).

/// Fix glibc's mmap threshold at 32 MB and stop trimming the heap (see the module docs). Does
/// nothing where the C library is not glibc, or when `GLIBC_TUNABLES` already sets a
/// `glibc.malloc` tunable (the user's choice wins). Call it first thing in `main`, after
/// [`crate::build_cpu::check`].
pub fn keep_freed_memory() {
    #[cfg(all(target_os = "linux", target_env = "gnu"))]
    {
        if std::env::var("GLIBC_TUNABLES").is_ok_and(|t| t.contains("glibc.malloc")) {
            return;
        }
        extern "C" {
            fn mallopt(param: std::ffi::c_int, value: std::ffi::c_int) -> std::ffi::c_int;
        }
        // <malloc.h>: M_TRIM_THRESHOLD -1, M_TOP_PAD -2, M_MMAP_THRESHOLD -3
        const M_TRIM_THRESHOLD: std::ffi::c_int = -1;
        const M_TOP_PAD: std::ffi::c_int = -2;
        const M_MMAP_THRESHOLD: std::ffi::c_int = -3;
        // SAFETY: mallopt only sets allocator parameters; called before any thread is started.
        unsafe {
            mallopt(M_MMAP_THRESHOLD, 32 << 20);
            mallopt(M_TRIM_THRESHOLD, std::ffi::c_int::MAX);
            mallopt(M_TOP_PAD, 64 << 20);
        }
    }
}
