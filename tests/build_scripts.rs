//! The scripts build the binaries from the checkout's folder.
//!
//! cargo reads `.cargo/config.toml` (`-C target-cpu=native`) from the folder it runs in, not from
//! the manifest's: `cargo build --manifest-path ...` from the user's folder (as `scripts/example.sh`,
//! the README's main job, did until session 43) builds for a generic x86-64, whose solver runs
//! ~3.5x slower (`src/build_cpu.rs`).

use std::path::Path;

/// Whether a shell line runs `cargo build` (not in a comment).
fn builds(line: &str) -> bool {
    let code = line.split('#').next().unwrap_or("");
    code.contains("cargo build")
}

/// The `cargo build` lines of a script that may not run in the checkout's folder: a build that
/// names the manifest, or one that neither changes folder on its own line nor follows the
/// script's `cd "$(dirname "$0")/.."` (or `cd "$(dirname "$0")/.." && ...`).
fn builds_elsewhere(text: &str) -> Vec<String> {
    let mut in_checkout = false;
    let mut found = Vec::new();
    for line in text.lines() {
        let t = line.trim_start();
        if t.starts_with("cd \"$(dirname \"$0\")/..\"") {
            in_checkout = true;
        }
        if !builds(line) {
            continue;
        }
        let cd_first = t.find("cd ").is_some_and(|c| t.find("cargo build").is_some_and(|b| c < b));
        if line.contains("--manifest-path") || !(in_checkout || cd_first) {
            found.push(line.trim().to_string());
        }
    }
    found
}

#[test]
fn a_build_that_names_the_manifest_or_runs_from_elsewhere_is_found() {
    let bad = "set -e\nhere=x\ncargo build --manifest-path \"$here/Cargo.toml\" --release --bins\n";
    assert_eq!(builds_elsewhere(bad).len(), 1);
    let bad = "set -e\ncargo build --release\n";
    assert_eq!(builds_elsewhere(bad).len(), 1);
    let good = "set -e\n(cd \"$here\" && cargo build --release --bins)\n";
    assert!(builds_elsewhere(good).is_empty());
    let good = "cd \"$(dirname \"$0\")/..\"\nROOT=$PWD\n# cargo build --manifest-path in a comment\ncargo build --release --quiet --bin rbc-sweep\n";
    assert!(builds_elsewhere(good).is_empty());
}

#[test]
fn every_script_builds_from_the_checkouts_folder() {
    let dir = Path::new(env!("CARGO_MANIFEST_DIR")).join("scripts");
    let mut checked = 0;
    let mut bad = Vec::new();
    for entry in std::fs::read_dir(&dir).expect("scripts/") {
        let path = entry.expect("an entry of scripts/").path();
        if path.extension().and_then(|e| e.to_str()) != Some("sh") {
            continue;
        }
        let text = std::fs::read_to_string(&path).expect("a script");
        if text.lines().any(builds) {
            checked += 1;
        }
        bad.extend(builds_elsewhere(&text).into_iter().map(|l| format!("{}: {l}", path.display())));
    }
    // example.sh, examples.sh, study.sh, bench_speed.sh, extreme_cases.sh, slurm_check.sh at least
    assert!(checked >= 6, "only {checked} scripts build");
    assert!(bad.is_empty(), "builds outside the checkout's folder (cargo would not read .cargo/config.toml):\n{}", bad.join("\n"));
}
