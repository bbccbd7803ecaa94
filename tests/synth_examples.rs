//! `rbc-synth --examples DIR` replaces the example recordings as one set: every example folder is
//! written anew (a file left in an old one is gone), files that are not examples stay, and no
//! staging folder is left behind.

mod output_common;

use output_common::{files_in, hidden_entries};
use rbc_analysis::simulated::synth::examples::examples;
use std::process::Command;

#[test]
fn examples_are_replaced_as_a_set() {
    let dir = tempfile::tempdir().unwrap();
    let root = dir.path().join("frames");
    let first = examples().into_iter().next().unwrap().name;
    std::fs::create_dir_all(root.join(&first)).unwrap();
    std::fs::write(root.join(&first).join("frame_00099.png"), "from an older synthesiser").unwrap();
    std::fs::write(root.join("README.md"), "mine").unwrap();
    let o = Command::new(env!("CARGO_BIN_EXE_rbc-synth")).arg("--examples").arg(&root).output().unwrap();
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    let files = files_in(&root);
    assert_eq!(files[std::path::Path::new("README.md")], b"mine");
    assert!(!root.join(&first).join("frame_00099.png").exists(), "an example folder is replaced as a whole");
    for ex in examples() {
        let n = files.keys().filter(|p| p.starts_with(&ex.name) && p.extension().is_some_and(|e| e == "png")).count();
        assert_eq!(n, ex.spec.n_frames, "{}", ex.name);
        assert!(files.contains_key(&std::path::Path::new(&ex.name).join("truth.csv")), "{}", ex.name);
    }
    assert_eq!(hidden_entries(dir.path()), Vec::<String>::new());
}
