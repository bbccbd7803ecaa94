//! Whether a binary was built for the CPU it runs on.
//!
//! The workspace builds for the building machine's CPU (`.cargo/config.toml`: `-C
//! target-cpu=native`), which cargo reads from the folder it is run in, not from the manifest's:
//! `cargo build --manifest-path rbc-toolkit/Cargo.toml` from another folder builds for a generic
//! x86-64 without FMA, AVX2 or AVX-512. Such a binary runs, but every `mul_add` becomes a call into
//! a software routine: 1.5 ms of the paper's channel from the issue-11 mid-run fixture cost 3.5x
//! the native binary's core-s on an AMD EPYC (31.1 against 9.0 core-s, the same 9 steps, medians
//! of three pairs side by side; `solver/README.md`, "Session 43"). The other way round, a binary built on a
//! machine with AVX-512 stops with an illegal instruction on one without. [`check`] tells both
//! apart at start, before any work.

/// The instruction-set extensions the hot kernels are written for (Stokeslet and stresslet
/// sums, the dense stage's factor, image filters), in the order a message names them.
pub const FEATURES: [&str; 3] = ["fma", "avx2", "avx512f"];

/// How the build's instruction set compares with the CPU's.
#[derive(Debug, Clone, PartialEq, Eq)]
pub enum Fit {
    /// Built for what the CPU has (or the target is not x86-64).
    Matches,
    /// Built without extensions the CPU has: it runs, slower.
    Missing(Vec<&'static str>),
    /// Built for extensions the CPU lacks: it would stop with an illegal instruction.
    Lacking(Vec<&'static str>),
}

/// Compares the extensions the binary was compiled for with those the CPU has, one flag per
/// entry of [`FEATURES`]; `Lacking` wins over `Missing`.
pub fn fit(compiled: [bool; 3], detected: [bool; 3]) -> Fit {
    let pick = |want: fn(bool, bool) -> bool| -> Vec<&'static str> {
        FEATURES.iter().zip(compiled.iter().zip(detected.iter())).filter(|(_, (&c, &d))| want(c, d)).map(|(f, _)| *f).collect()
    };
    let lacking = pick(|c, d| c && !d);
    if !lacking.is_empty() {
        return Fit::Lacking(lacking);
    }
    let missing = pick(|c, d| !c && d);
    if missing.is_empty() {
        Fit::Matches
    } else {
        Fit::Missing(missing)
    }
}

/// The extensions this binary was compiled for (`cfg!(target_feature)`), as [`FEATURES`].
pub fn compiled() -> [bool; 3] {
    [cfg!(target_feature = "fma"), cfg!(target_feature = "avx2"), cfg!(target_feature = "avx512f")]
}

/// The extensions the running CPU has (`cpuid`), as [`FEATURES`]; none off x86-64.
pub fn detected() -> [bool; 3] {
    #[cfg(target_arch = "x86_64")]
    {
        [
            std::arch::is_x86_feature_detected!("fma"),
            std::arch::is_x86_feature_detected!("avx2"),
            std::arch::is_x86_feature_detected!("avx512f"),
        ]
    }
    #[cfg(not(target_arch = "x86_64"))]
    {
        [false; 3]
    }
}

/// The one-line message of a fit that is not [`Fit::Matches`], for the program `program`.
pub fn message(program: &str, fit: &Fit) -> Option<String> {
    match fit {
        Fit::Matches => None,
        Fit::Missing(f) => Some(format!(
            "{program}: warning: built without {} that this CPU has, so the solver runs ~3.5x slower: build from the \
             checkout's folder (cargo reads .cargo/config.toml, target-cpu=native, from the folder it runs in), e.g. \
             `cd rbc-toolkit && cargo build --release`",
            f.join(", ")
        )),
        Fit::Lacking(f) => Some(format!(
            "{program}: built for {} that this CPU lacks (it would stop with an illegal instruction): build it on a \
             machine of the kind that runs it",
            f.join(", ")
        )),
    }
}

/// Checks this binary against this CPU: prints the warning of a build without the CPU's
/// extensions and goes on (`true`), or prints why it cannot run here (`false`: exit 2).
pub fn check(program: &str) -> bool {
    let fit = fit(compiled(), detected());
    if let Some(m) = message(program, &fit) {
        eprintln!("{m}");
    }
    !matches!(fit, Fit::Lacking(_))
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_build_without_the_cpus_extensions_is_missing_them_and_one_for_more_is_lacking() {
        assert_eq!(fit([true, true, true], [true, true, true]), Fit::Matches);
        assert_eq!(fit([true, true, false], [true, true, false]), Fit::Matches);
        // the generic x86-64 build on an AVX-512 machine
        assert_eq!(fit([false, false, false], [true, true, true]), Fit::Missing(vec!["fma", "avx2", "avx512f"]));
        // built on an AVX-512 login node, run on a node without it
        assert_eq!(fit([true, true, true], [true, true, false]), Fit::Lacking(vec!["avx512f"]));
        // lacking wins: the binary cannot run at all
        assert_eq!(fit([false, true, true], [true, true, false]), Fit::Lacking(vec!["avx512f"]));
        assert_eq!(message("rbc-simulate", &Fit::Matches), None);
        let m = message("rbc-simulate", &Fit::Missing(vec!["fma", "avx2"])).unwrap();
        assert!(m.starts_with("rbc-simulate: warning: built without fma, avx2 that this CPU has"), "{m}");
        assert!(!m.contains('\n'));
        let m = message("rbc-sweep", &Fit::Lacking(vec!["avx512f"])).unwrap();
        assert!(m.starts_with("rbc-sweep: built for avx512f that this CPU lacks"), "{m}");
    }

    /// The test build is the workspace's (`cargo nextest run` from the checkout reads
    /// `.cargo/config.toml`) and runs on the machine that built it: it matches the CPU. A config
    /// that stopped applying (moved, renamed, overridden by `RUSTFLAGS`) fails here.
    #[test]
    fn the_workspace_builds_for_the_cpu_it_runs_on() {
        assert_eq!(fit(compiled(), detected()), Fit::Matches, "compiled {:?}, this CPU {:?} ({FEATURES:?})", compiled(), detected());
    }
}
