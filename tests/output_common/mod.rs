//! Shared checks of the tests of commands' outputs: that they are replaced as a set, and what a
//! figure shows.
#![allow(dead_code)]

use std::collections::BTreeMap;
use std::path::{Path, PathBuf};

/// Every file under `dir` with its bytes, by path relative to `dir`.
pub fn files_in(dir: &Path) -> BTreeMap<PathBuf, Vec<u8>> {
    let mut out = BTreeMap::new();
    let mut todo = vec![dir.to_path_buf()];
    while let Some(d) = todo.pop() {
        for e in std::fs::read_dir(&d).unwrap() {
            let p = e.unwrap().path();
            if p.is_dir() {
                todo.push(p);
            } else {
                out.insert(p.strip_prefix(dir).unwrap().to_path_buf(), std::fs::read(&p).unwrap());
            }
        }
    }
    out
}

/// Names of the hidden entries of `dir` (a staging or replaced folder left behind would be one).
pub fn hidden_entries(dir: &Path) -> Vec<String> {
    let mut left: Vec<String> = std::fs::read_dir(dir).unwrap().map(|e| e.unwrap().file_name().to_string_lossy().into_owned()).collect();
    left.retain(|n| n.starts_with('.'));
    left
}

/// Pixels close to `c` (max channel difference <= 40) in a PNG.
pub fn pixels_like(path: &Path, c: [u8; 3]) -> usize {
    pixels_like_in(path, c, 0..u32::MAX)
}

/// [`pixels_like`] in the PNG's pixel columns `columns` (e.g. one panel of a figure of several).
pub fn pixels_like_in(path: &Path, c: [u8; 3], columns: std::ops::Range<u32>) -> usize {
    let img = image::open(path).unwrap().to_rgb8();
    img.enumerate_pixels().filter(|(x, _, p)| columns.contains(x) && (0..3).all(|k| (p.0[k] as i32 - c[k] as i32).abs() <= 40)).count()
}
