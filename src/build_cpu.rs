//! Whether a binary was built for the CPU it runs on.
//!
//! The workspace builds for the building machine's CPU (`.cargo/config.toml`: `-C
//! target-cpu=native`), which cargo reads from the folder it is run in, not from the manifest's:
//! `cargo build --manifest-path rbc-toolkit/Cargo.toml` from another folder builds for a generic
//! x86-64 without FMA, AVX2 or AVX-512. Such a binary runs, but every `mul_add` becomes a call into
//! a software routine: 1.5 ms of the paper's channel from the issue-11 mid-run fixture cost 3.5x
//! the native binary's core-s on an AMD EPYC (31.1 against 9.0 core-s, the same 9 steps, medians
//! of three pairs side by side; `solver/README.md`, "Session 43"). The other way round, a binary
//! built on a machine with more extensions than this one (AVX-512 and its relatives, GFNI, VAES, ...)
//! stops with an illegal instruction wherever the compiler used one. [`check`] tells these apart
//! at start, before the program's work.

/// One instruction-set extension: whether the binary was compiled for it and whether the CPU has it.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct Feature {
    pub name: &'static str,
    pub compiled: bool,
    pub detected: bool,
}

/// The extensions a build for a generic x86-64 lacks whose absence costs the 3.5x
/// (`mul_add` as a software call, no 256-bit integer and float vectors).
pub const GENERIC_MISSES: [&str; 2] = ["fma", "avx2"];

/// Every extension `target-cpu=native` may turn on that [`check`] compares (x86 and x86-64):
/// compiled ([`cfg!`]) against the CPU's ([`std::arch::is_x86_feature_detected!`]).
#[cfg(any(target_arch = "x86", target_arch = "x86_64"))]
pub fn features() -> Vec<Feature> {
    macro_rules! compare {
        ($($name:tt),* $(,)?) => {
            vec![$(Feature { name: $name, compiled: cfg!(target_feature = $name), detected: std::arch::is_x86_feature_detected!($name) }),*]
        };
    }
    compare!(
        "sse4.2", "popcnt", "avx", "avx2", "fma", "f16c", "bmi1", "bmi2", "lzcnt", "movbe", "avx512f", "avx512cd", "avx512bw",
        "avx512dq", "avx512vl", "avx512ifma", "avx512vbmi", "avx512vbmi2", "avx512vnni", "avx512bitalg", "avx512vpopcntdq",
        "gfni", "vaes", "vpclmulqdq",
    )
}

/// No extension is compared off x86.
#[cfg(not(any(target_arch = "x86", target_arch = "x86_64")))]
pub fn features() -> Vec<Feature> {
    Vec::new()
}

/// How the build's instruction set compares with the CPU's.
#[derive(Debug, Clone, PartialEq, Eq)]
pub enum Fit {
    /// Built for what the CPU has, or for less but not for the extensions below.
    Matches,
    /// Built without FMA or AVX2 that the CPU has ([`GENERIC_MISSES`]: a build for a generic
    /// x86-64): it runs ~3.5x slower.
    Generic(Vec<&'static str>),
    /// Built with FMA and AVX2 but without AVX-512 that the CPU has (built on another kind of
    /// machine): it runs; the AVX-512 Stokeslet and stresslet sums are chosen at run time anyway.
    WithoutAvx512,
    /// Built for extensions the CPU lacks: it would stop with an illegal instruction.
    Lacking(Vec<&'static str>),
}

/// Compares the extensions the binary was compiled for with those the CPU has: `Lacking` wins
/// over `Generic`, `Generic` over `WithoutAvx512`.
pub fn fit(features: &[Feature]) -> Fit {
    let lacking: Vec<_> = features.iter().filter(|f| f.compiled && !f.detected).map(|f| f.name).collect();
    if !lacking.is_empty() {
        return Fit::Lacking(lacking);
    }
    let missing = |name: &str| features.iter().any(|f| f.name == name && !f.compiled && f.detected);
    let generic: Vec<_> = GENERIC_MISSES.iter().copied().filter(|n| missing(n)).collect();
    if !generic.is_empty() {
        Fit::Generic(generic)
    } else if missing("avx512f") {
        Fit::WithoutAvx512
    } else {
        Fit::Matches
    }
}

/// The one-line message of a fit that is not [`Fit::Matches`], for the program `program`.
pub fn message(program: &str, fit: &Fit) -> Option<String> {
    match fit {
        Fit::Matches => None,
        Fit::Generic(f) => Some(format!(
            "{program}: warning: built without {} that this CPU has (a build for a generic x86-64), so the channel's \
             solver runs ~3.5x slower: build from the checkout's folder (cargo reads .cargo/config.toml, \
             target-cpu=native, from the folder it runs in), e.g. `cd rbc-toolkit && cargo build --release`",
            f.join(", ")
        )),
        Fit::WithoutAvx512 => Some(format!(
            "{program}: warning: built on a CPU without the AVX-512 this one has: it runs (the AVX-512 Stokeslet sums \
             are chosen at run time), a build on this kind of machine may run faster"
        )),
        Fit::Lacking(f) => Some(format!(
            "{program}: built for {} that this CPU lacks (it would stop with an illegal instruction): build it on the \
             kind of machine with the fewest extensions among those that run it",
            f.join(", ")
        )),
    }
}

/// Checks this binary against this CPU: prints the warning of a build without the CPU's
/// extensions and goes on (`true`), or prints why it cannot run here (`false`: exit 2). Call it
/// first in `main`. Its own code is compiled for the build's CPU too, so it stops a binary built
/// for more before the program's work, not before every instruction of that CPU: in practice the
/// comparison and the message use none beyond the base set.
#[inline(never)]
pub fn check(program: &str) -> bool {
    let fit = fit(&features());
    if let Some(m) = message(program, &fit) {
        eprintln!("{m}");
    }
    !matches!(fit, Fit::Lacking(_))
}

#[cfg(test)]
mod tests {
    use super::*;

    fn cpu(list: &[(&'static str, bool, bool)]) -> Vec<Feature> {
        list.iter().map(|&(name, compiled, detected)| Feature { name, compiled, detected }).collect()
    }

    #[test]
    fn a_generic_build_is_told_from_one_for_another_cpu_and_one_for_more_lacks() {
        let all = |c: bool, d: bool| cpu(&[("fma", c, d), ("avx2", c, d), ("avx512f", c, d), ("gfni", c, d)]);
        assert_eq!(fit(&all(true, true)), Fit::Matches);
        assert_eq!(fit(&all(false, false)), Fit::Matches);
        // the generic x86-64 build on an AVX-512 machine
        assert_eq!(fit(&all(false, true)), Fit::Generic(vec!["fma", "avx2"]));
        // built from the checkout on a machine without AVX-512, run on one with it
        let other = cpu(&[("fma", true, true), ("avx2", true, true), ("avx512f", false, true), ("gfni", false, true)]);
        assert_eq!(fit(&other), Fit::WithoutAvx512);
        // built on an AVX-512 login node, run on a node without it
        let login = cpu(&[("fma", true, true), ("avx2", true, true), ("avx512f", true, false), ("gfni", true, false)]);
        assert_eq!(fit(&login), Fit::Lacking(vec!["avx512f", "gfni"]));
        // an extension beyond AVX-512F alone (a Zen 4/5 build on a Skylake-SP node) is lacking too
        let skylake = cpu(&[("fma", true, true), ("avx2", true, true), ("avx512f", true, true), ("gfni", true, false)]);
        assert_eq!(fit(&skylake), Fit::Lacking(vec!["gfni"]));
        // lacking wins: the binary cannot run at all
        let both = cpu(&[("fma", false, true), ("avx2", true, true), ("avx512f", true, false)]);
        assert_eq!(fit(&both), Fit::Lacking(vec!["avx512f"]));
        assert_eq!(message("rbc-simulate", &Fit::Matches), None);
        let m = message("rbc-simulate", &Fit::Generic(vec!["fma", "avx2"])).unwrap();
        assert!(m.starts_with("rbc-simulate: warning: built without fma, avx2 that this CPU has") && m.contains("3.5x"), "{m}");
        let m = message("rbc-sweep", &Fit::WithoutAvx512).unwrap();
        assert!(m.starts_with("rbc-sweep: warning: built on a CPU without the AVX-512") && !m.contains("3.5x"), "{m}");
        let m = message("rbc-sweep", &Fit::Lacking(vec!["avx512f"])).unwrap();
        assert!(m.starts_with("rbc-sweep: built for avx512f that this CPU lacks"), "{m}");
        for m in [Fit::Generic(vec!["fma"]), Fit::WithoutAvx512, Fit::Lacking(vec!["gfni"])].iter().filter_map(|f| message("x", f)) {
            assert!(!m.contains('\n'), "{m}");
        }
    }

    /// The test build is the workspace's (`cargo nextest run` from the checkout reads
    /// `.cargo/config.toml`) and runs on the machine that built it: it matches the CPU. A config
    /// that stopped applying (moved, renamed, overridden by `RUSTFLAGS`) fails here.
    #[test]
    fn the_workspace_builds_for_the_cpu_it_runs_on() {
        let f = features();
        #[cfg(target_arch = "x86_64")]
        assert!(f.iter().any(|x| x.name == "fma") && f.iter().any(|x| x.name == "avx512f"), "{f:?}");
        assert_eq!(fit(&f), Fit::Matches, "{f:?}");
    }
}
