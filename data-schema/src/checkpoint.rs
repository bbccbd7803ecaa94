//! Checkpoint files of running simulations: a small HDF5 file beside `results.h5`, replaced atomically, that lets a killed run continue.
//!
//! # Why beside the results file and not inside it
//!
//! HDF5 (1.10, without SWMR) is not crash-safe: a process killed while it writes
//! can leave half-updated datasets. A checkpoint must survive a `SIGKILL` at any
//! instant, so it is written as a whole new file next to the results file
//! (temporary name, flushed and `fsync`ed, then renamed over the previous
//! checkpoint, as [`crate::atomic`]): a kill leaves either the old or the new
//! checkpoint, never a mixture. Before a checkpoint is written, the run's
//! samples and snapshots up to it are flushed into `results.h5`; the checkpoint
//! records how many there were (`n_samples`, `n_snapshots`), and a resumed run
//! first cuts the results back to those counts
//! ([`crate::results::RunWriter::truncate_to`]), dropping the rows written after
//! the checkpoint, so no row is duplicated or missing. The checkpoint is
//! deleted when the run finishes or fails.
//!
//! # Layout (`<results file name>.<run_id>.ckpt`, in the results file's folder)
//!
//! ```text
//! bytes 0-511  the user block: the checksum lines (see "Integrity" below); the HDF5 file from byte 512:
//! /            attrs: schema_version (u32 = 1), kind = "rbc-checkpoint",
//!                     run_id (string), scene (string: the scene TOML of the run),
//!                     t_s (f64, s: the output time of the checkpoint),
//!                     n_samples, n_snapshots (u64: rows of timeseries/ and snapshots/ up to t_s)
//! /fields/<name>      f64[len]: the state, named by its owner, e.g.
//!                     runner.t_s, runner.h_s (next trial step), runner.next_output,
//!                     runner.err_prev (optional: the PI step-size controller's previous error norm),
//!                     runner.vertices_um (nv*3, x y z per vertex), runner.accepted, ...,
//!                     integrator.k1_um_s (Bogacki-Shampine's first-same-as-last stage),
//!                     dynamics.last_velocity_um_s, observer.snapshot_every, ...
//! ```
//!
//! All state is `f64` (integer counters are exact below 2^53), so a resumed run
//! continues bit-for-bit (see `rbc_solver::run::checkpoint`).
//!
//! # Integrity: a checksum verified before libhdf5 sees the file
//!
//! libhdf5 1.10.8 trusts the metadata it parses: on some damaged bytes (a flipped bit in a global
//! heap collection, a B-tree node address) it segfaults or loops forever (`rbc-bench fuzz --format
//! checkpoint` found both, in about 0.4 % of files with 1 to 4 damaged bytes). A segfault cannot be
//! turned into an error inside the process, so a checkpoint is checked before libhdf5 parses a byte of it.
//! The file starts with a 512-byte HDF5 *user block* (which libhdf5 skips: the HDF5 file proper begins
//! at byte 512, and `h5dump`/h5py read the file as usual) holding two text lines:
//!
//! ```text
//! rbc-checkpoint crc32 1a2b3c4d\n      (30 bytes: the CRC-32 (IEEE) of every byte after this line)
//! length 757848\n                      (the file's length in bytes), then zeros up to byte 512
//! ```
//!
//! [`write()`] computes the checksum after libhdf5 has closed the temporary file and before the file is
//! renamed into place, so a checkpoint at its final name always carries a checksum of its whole
//! content. [`read`] reads the file into memory once, verifies the checksum, and only then hands those
//! very bytes (not the file again: no window for a change between check and parse) to libhdf5 as a file
//! image (core driver). What the check covers: every byte of the file (those after the checksum line
//! through the CRC, the line itself by its exact form and the value it holds); a file changed by
//! accident (bit rot, a partial copy, a truncation, an edit) is refused with `<file>: checkpoint
//! damaged (...)`, and a random change passes with probability 2^-32. Its cost is one read of the file
//! and a CRC at GB/s (`rbc-sweep status` of a study run with a 0.76 MB checkpoint: the same CPU time
//! with and without the check), plus a read-back of the file when it is written. What it does not cover: a deliberately forged file
//! (CRC-32 is no signature), and checkpoints of builds before the check (they start with the HDF5
//! signature at byte 0 and are read unchecked, as then, so a run checkpointed by an older build still
//! resumes; its next checkpoint carries the check).

use crate::error::{Result, SchemaError};
use hdf5::types::VarLenUnicode;
use hdf5::File;
use std::collections::BTreeMap;
use std::path::{Path, PathBuf};

/// Version of the checkpoint layout.
pub const CHECKPOINT_VERSION: u32 = 1;

/// Bytes of the HDF5 user block at the start of a checkpoint: the checksum lines (see the module documentation).
pub const USER_BLOCK: usize = 512;

/// Start of a checkpoint's first line: `rbc-checkpoint crc32 ` then 8 lower-case hex digits and `\n`.
pub const CHECKSUM_TAG: &[u8] = b"rbc-checkpoint crc32 ";

/// Length of the checksum line (tag, 8 hex digits, newline); the checksum covers every byte after it.
pub const CHECKSUM_LINE: usize = CHECKSUM_TAG.len() + 9;

/// The signature libhdf5 looks for at byte 0, 512, 1024, ... (the superblock).
const HDF5_SIGNATURE: &[u8; 8] = b"\x89HDF\r\n\x1a\n";

/// How far a checkpoint's bytes were checked before libhdf5 parsed them.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Integrity {
    /// The checksum line matches every byte after it.
    Verified,
    /// A checkpoint of a build before the check (HDF5 signature at byte 0): read unchecked.
    Unchecked,
}

/// One checkpoint of one run.
#[derive(Debug, Clone, PartialEq)]
pub struct Checkpoint {
    pub run_id: String,
    /// The scene TOML the run was started from.
    pub scene: String,
    /// Output time of the checkpoint (s).
    pub t_s: f64,
    /// Timeseries rows of the run in `results.h5` up to and including `t_s`.
    pub n_samples: usize,
    /// Snapshots of the run in `results.h5` up to `t_s`.
    pub n_snapshots: usize,
    /// The state, as named arrays.
    pub fields: BTreeMap<String, Vec<f64>>,
}

/// Path of the checkpoint of run `run_id` of the results file `results`.
pub fn checkpoint_path(results: &Path, run_id: &str) -> PathBuf {
    let name = results.file_name().map(|n| n.to_string_lossy().into_owned()).unwrap_or_default();
    results.with_file_name(format!("{name}.{run_id}.ckpt"))
}

fn h5err(path: &Path, context: &str, e: hdf5::Error) -> SchemaError {
    SchemaError::Hdf5 { path: path.into(), message: format!("{context}: {}", e.to_string().replace('\n', " ")) }
}

fn field(path: &Path, name: &str, message: impl Into<String>) -> SchemaError {
    SchemaError::field(path, name, message)
}

fn put_str(path: &Path, f: &File, name: &str, value: &str) -> Result<()> {
    let v: VarLenUnicode = value.parse().map_err(|e| field(path, name, format!("{e}")))?;
    f.new_attr::<VarLenUnicode>().shape(()).create(name).and_then(|a| a.write_scalar(&v)).map_err(|e| h5err(path, name, e))
}

fn put<T: hdf5::H5Type>(path: &Path, f: &File, name: &str, value: &T) -> Result<()> {
    f.new_attr::<T>().shape(()).create(name).and_then(|a| a.write_scalar(value)).map_err(|e| h5err(path, name, e))
}

/// Write `ck` to `path` atomically: a kill at any moment leaves the previous file or the new one.
pub fn write(path: &Path, ck: &Checkpoint) -> Result<()> {
    crate::atomic::write_via(path, |tmp| {
        let f = File::with_options().with_fcpl(|p| p.userblock(USER_BLOCK as u64)).create(tmp).map_err(|e| h5err(tmp, "create", e))?;
        put(tmp, &f, "schema_version", &CHECKPOINT_VERSION)?;
        put_str(tmp, &f, "kind", "rbc-checkpoint")?;
        put_str(tmp, &f, "run_id", &ck.run_id)?;
        put_str(tmp, &f, "scene", &ck.scene)?;
        put(tmp, &f, "t_s", &ck.t_s)?;
        put(tmp, &f, "n_samples", &(ck.n_samples as u64))?;
        put(tmp, &f, "n_snapshots", &(ck.n_snapshots as u64))?;
        let g = f.create_group("fields").map_err(|e| h5err(tmp, "fields", e))?;
        for (name, v) in &ck.fields {
            if name.is_empty() || name.contains('/') {
                return Err(field(path, name, "checkpoint field names must be non-empty and without `/`"));
            }
            g.new_dataset_builder().with_data(&v[..]).create(name.as_str()).map_err(|e| h5err(tmp, name, e))?;
        }
        f.flush().map_err(|e| h5err(tmp, "flush", e))?;
        drop(g);
        f.close().map_err(|e| h5err(tmp, "close", e))?;
        seal(tmp)
    })
}

/// Write the checksum lines into the user block of the closed HDF5 file `tmp` and sync it to disk.
fn seal(tmp: &Path) -> Result<()> {
    use std::io::{Seek, Write};
    let mut bytes = std::fs::read(tmp).map_err(|e| SchemaError::io(tmp, e))?;
    if bytes.len() < USER_BLOCK + HDF5_SIGNATURE.len() || &bytes[USER_BLOCK..USER_BLOCK + 8] != HDF5_SIGNATURE || bytes[..USER_BLOCK].iter().any(|&b| b != 0) {
        return Err(SchemaError::Invalid { path: tmp.into(), message: format!("libhdf5 did not leave the {USER_BLOCK}-byte user block for the checksum") });
    }
    let length = format!("length {}\n", bytes.len());
    bytes[CHECKSUM_LINE..CHECKSUM_LINE + length.len()].copy_from_slice(length.as_bytes());
    let line = format!("{}{:08x}\n", std::str::from_utf8(CHECKSUM_TAG).expect("ASCII"), crc32fast::hash(&bytes[CHECKSUM_LINE..]));
    bytes[..CHECKSUM_LINE].copy_from_slice(line.as_bytes());
    let mut h = std::fs::OpenOptions::new().write(true).open(tmp).map_err(|e| SchemaError::io(tmp, e))?;
    h.seek(std::io::SeekFrom::Start(0)).and_then(|_| h.write_all(&bytes[..USER_BLOCK])).and_then(|()| h.sync_all()).map_err(|e| SchemaError::io(tmp, e))
}

fn damaged(path: &Path, message: impl Into<String>) -> SchemaError {
    SchemaError::Damaged { path: path.into(), what: "checkpoint", message: message.into() }
}

/// Check the bytes of the checkpoint `path` before any of them reaches libhdf5 (see the module
/// documentation): [`Integrity::Verified`] when the checksum line matches, [`Integrity::Unchecked`]
/// for a checkpoint of an older build (HDF5 signature at byte 0), and an error
/// `<file>: checkpoint damaged (...)` otherwise (a checksum mismatch, a damaged or missing checksum line).
pub fn verify(path: &Path, bytes: &[u8]) -> Result<Integrity> {
    if bytes.starts_with(HDF5_SIGNATURE) {
        return Ok(Integrity::Unchecked);
    }
    if !bytes.starts_with(CHECKSUM_TAG) {
        return Err(damaged(path, format!("its first bytes are neither `{}...` nor an HDF5 signature", String::from_utf8_lossy(CHECKSUM_TAG).trim_end())));
    }
    let stored = bytes
        .get(CHECKSUM_TAG.len()..CHECKSUM_LINE)
        .and_then(|d| d.strip_suffix(b"\n"))
        .filter(|d| d.iter().all(|c| c.is_ascii_digit() || (b'a'..=b'f').contains(c)))
        .and_then(|d| u32::from_str_radix(std::str::from_utf8(d).ok()?, 16).ok());
    let Some(stored) = stored else {
        return Err(damaged(path, "the checksum line is not `rbc-checkpoint crc32 <8 hex digits>`"));
    };
    let computed = crc32fast::hash(&bytes[CHECKSUM_LINE..]);
    if computed != stored {
        // the length line, when still legible, tells a cut file from a changed one
        let written = bytes[CHECKSUM_LINE..bytes.len().min(USER_BLOCK)]
            .strip_prefix(b"length ")
            .and_then(|r| r.split(|&c| c == b'\n').next())
            .and_then(|d| std::str::from_utf8(d).ok()?.parse::<u64>().ok());
        let size = match written {
            Some(n) if n != bytes.len() as u64 => format!("; {} bytes, written with {n}", bytes.len()),
            _ => String::new(),
        };
        return Err(damaged(path, format!("checksum mismatch: its bytes changed after it was written{size}; restore it from a copy, or delete it to start the run again")));
    }
    Ok(Integrity::Verified)
}

/// Open the checkpoint image `bytes` (already verified) with libhdf5's core driver: the file is not read again.
fn open_image(path: &Path, bytes: &[u8]) -> Result<File> {
    use std::os::unix::ffi::OsStrExt;
    let fapl = hdf5::plist::FileAccess::build().core_filebacked(false).finish().map_err(|e| h5err(path, "open checkpoint", e))?;
    // libhdf5 refuses an image under the name of a file that exists (and would take two opens of one
    // name for the same file): a name of its own, never created on disk
    static OPENED: std::sync::atomic::AtomicU64 = std::sync::atomic::AtomicU64::new(0);
    let n = OPENED.fetch_add(1, std::sync::atomic::Ordering::Relaxed);
    let mut image_name = path.as_os_str().to_owned();
    image_name.push(format!(".in-memory-image-{}-{n}", std::process::id()));
    let name = std::ffi::CString::new(image_name.as_bytes()).map_err(|_| SchemaError::Invalid { path: path.into(), message: "a file name with a NUL byte".into() })?;
    let id = hdf5::sync::sync(|| {
        // SAFETY: without image callbacks libhdf5 copies the buffer during the call; `bytes`, `fapl` and
        // `name` outlive it. The id H5Fopen returns is handed to `from_id`, which owns it from then on.
        hdf5::h5check(unsafe { hdf5_sys::h5p::H5Pset_file_image(fapl.id(), bytes.as_ptr() as *mut std::ffi::c_void, bytes.len()) })
            .and_then(|_| hdf5::h5check(unsafe { hdf5_sys::h5f::H5Fopen(name.as_ptr(), hdf5_sys::h5f::H5F_ACC_RDONLY, fapl.id()) }))
    })
    .map_err(|e| h5err(path, "open checkpoint", e))?;
    // SAFETY: `id` is a file id just returned by H5Fopen, owned by nobody else.
    unsafe { hdf5::from_id::<File>(id) }.map_err(|e| h5err(path, "open checkpoint", e))
}

fn get_str(path: &Path, f: &File, name: &str) -> Result<String> {
    f.attr(name)
        .and_then(|a| a.read_scalar::<VarLenUnicode>())
        .map_err(|_| field(path, name, "missing or not a string"))
        .and_then(|v| crate::results::utf8_text(path, name, v.as_bytes()))
}

/// Read a checkpoint written by [`write()`], after [`verify`]ing its checksum (an older build's
/// checkpoint without one is read unchecked).
pub fn read(path: &Path) -> Result<Checkpoint> {
    let bytes = std::fs::read(path).map_err(|e| SchemaError::io(path, e))?;
    // a checkpoint is small (the state and the observer's ring): all of its reading is watched
    let _watch = crate::hdf5_watch::arm(path, || "reading the checkpoint".into());
    let f = match verify(path, &bytes)? {
        Integrity::Verified => open_image(path, &bytes)?,
        Integrity::Unchecked => File::open(path).map_err(|e| h5err(path, "open checkpoint", e))?,
    };
    drop(bytes);
    let version = f.attr("schema_version").and_then(|a| a.read_scalar::<u32>()).map_err(|_| field(path, "schema_version", "missing"))?;
    let kind = get_str(path, &f, "kind")?;
    if kind != "rbc-checkpoint" {
        return Err(field(path, "kind", format!("is `{kind}`, not `rbc-checkpoint`")));
    }
    if version != CHECKPOINT_VERSION {
        return Err(SchemaError::SchemaVersion { path: path.into(), found: version.to_string(), supported: CHECKPOINT_VERSION.to_string() });
    }
    let num = |name: &str| f.attr(name).and_then(|a| a.read_scalar::<u64>()).map_err(|_| field(path, name, "missing or not an integer"));
    let t_s = f.attr("t_s").and_then(|a| a.read_scalar::<f64>()).map_err(|_| field(path, "t_s", "missing or not a number"))?;
    let g = f.group("fields").map_err(|e| h5err(path, "fields", e))?;
    let mut fields = BTreeMap::new();
    for name in g.member_names().map_err(|e| h5err(path, "fields", e))? {
        let ctx = format!("fields/{name}");
        let v = crate::results::read_all::<f64>(path, &g.dataset(&name).map_err(|e| h5err(path, &ctx, e))?, &ctx)?;
        fields.insert(name, v);
    }
    Ok(Checkpoint {
        run_id: get_str(path, &f, "run_id")?,
        scene: get_str(path, &f, "scene")?,
        t_s,
        n_samples: num("n_samples")? as usize,
        n_snapshots: num("n_snapshots")? as usize,
        fields,
    })
}

/// Delete the checkpoint at `path` and temporary files a killed writer left beside it.
pub fn remove(path: &Path) -> Result<()> {
    if let (Some(dir), Some(name)) = (path.parent(), path.file_name()) {
        let dir = if dir.as_os_str().is_empty() { Path::new(".") } else { dir };
        let prefix = format!(".{}.", name.to_string_lossy());
        if let Ok(entries) = std::fs::read_dir(dir) {
            for e in entries.flatten() {
                let n = e.file_name().to_string_lossy().into_owned();
                if n.starts_with(&prefix) && n.ends_with(".tmp") {
                    let _ = std::fs::remove_file(e.path());
                }
            }
        }
    }
    match std::fs::remove_file(path) {
        Err(e) if e.kind() != std::io::ErrorKind::NotFound => Err(SchemaError::io(path, e)),
        _ => Ok(()),
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn round_trip_is_exact_and_replacement_keeps_one_file() {
        let dir = tempfile::tempdir().unwrap();
        let p = checkpoint_path(&dir.path().join("results.h5"), "r-1");
        assert_eq!(p.file_name().unwrap(), "results.h5.r-1.ckpt");
        let mut fields = BTreeMap::new();
        fields.insert("runner.t_s".to_string(), vec![0.1 + 0.2]);
        fields.insert("runner.vertices_um".to_string(), vec![1.0 / 3.0, -0.0, 1e-310, f64::MAX]);
        fields.insert("runner.h_min_s".to_string(), vec![f64::INFINITY]);
        let mut ck = Checkpoint { run_id: "r-1".into(), scene: "name = \"x\"\n".into(), t_s: 0.3, n_samples: 4, n_snapshots: 1, fields };
        write(&p, &ck).unwrap();
        let back = read(&p).unwrap();
        assert_eq!(back, ck);
        assert!(back.fields["runner.vertices_um"][1].is_sign_negative(), "-0.0 kept bit-for-bit");
        ck.n_samples = 9;
        write(&p, &ck).unwrap();
        assert_eq!(read(&p).unwrap().n_samples, 9);
        // a temporary file of a writer killed mid-write is removed with the checkpoint
        std::fs::write(dir.path().join(".results.h5.r-1.ckpt.999.tmp"), b"partial").unwrap();
        remove(&p).unwrap();
        assert_eq!(std::fs::read_dir(dir.path()).unwrap().count(), 0);
        remove(&p).unwrap();
        assert!(read(&p).is_err());
    }

    /// `bytes` (a checkpoint) with its checksum line recomputed: what a damage before sealing would give.
    fn reseal(bytes: &mut [u8]) {
        let line = format!("rbc-checkpoint crc32 {:08x}\n", crc32fast::hash(&bytes[CHECKSUM_LINE..]));
        bytes[..CHECKSUM_LINE].copy_from_slice(line.as_bytes());
    }

    fn small() -> Checkpoint {
        let mut fields = BTreeMap::new();
        fields.insert("runner.t_s".to_string(), vec![0.5]);
        fields.insert("runner.vertices_um".to_string(), (0..54).map(|i| i as f64 / 7.0).collect());
        Checkpoint { run_id: "cap".into(), scene: "name = \"cap\"\n".into(), t_s: 0.5, n_samples: 3, n_snapshots: 1, fields }
    }

    /// [`small`] written to `r.h5.cap.ckpt` in a new folder: (folder, path, the file's bytes).
    fn written() -> (tempfile::TempDir, PathBuf, Vec<u8>) {
        let dir = tempfile::tempdir().unwrap();
        let p = dir.path().join("r.h5.cap.ckpt");
        write(&p, &small()).unwrap();
        let bytes = std::fs::read(&p).unwrap();
        (dir, p, bytes)
    }

    /// A checkpoint starts with its checksum line in the user block; libhdf5 (and h5py, h5dump) read the
    /// HDF5 file after it as usual.
    #[test]
    fn a_checkpoint_carries_a_checksum_of_its_bytes_and_round_trips() {
        let (_dir, p, bytes) = written();
        assert_eq!(verify(&p, &bytes).unwrap(), Integrity::Verified);
        let head = String::from_utf8_lossy(&bytes[..64]);
        assert!(head.starts_with("rbc-checkpoint crc32 ") && head.contains(&format!("\nlength {}\n", bytes.len())), "{head:?}");
        assert_eq!(&bytes[USER_BLOCK..USER_BLOCK + 8], HDF5_SIGNATURE);
        assert_eq!(read(&p).unwrap(), small());
        let plain = File::open(&p).unwrap();
        assert_eq!(plain.userblock(), USER_BLOCK as u64);
        assert_eq!(plain.attr("run_id").unwrap().read_scalar::<VarLenUnicode>().unwrap().as_str(), "cap");
    }

    /// One changed byte anywhere (the HDF5 superblock, an object header, the global heap holding the
    /// strings, a B-tree, the data, the checksum or length line), a truncation or an appended byte: the
    /// checkpoint is refused with one line naming the file, before libhdf5 parses any of it (the
    /// segfaults and hangs `rbc-bench fuzz --format checkpoint` found were in such damaged metadata).
    #[test]
    fn a_checkpoint_with_one_changed_byte_is_refused_naming_the_file() {
        let (_dir, p, good) = written();
        let at = |sig: &[u8]| good.windows(sig.len()).position(|w| w == sig).unwrap_or_else(|| panic!("{}", String::from_utf8_lossy(sig)));
        let mut places = vec![0, CHECKSUM_TAG.len() + 3, CHECKSUM_LINE + 8, USER_BLOCK - 1, USER_BLOCK, USER_BLOCK + 12, good.len() - 1];
        places.extend([&b"OHDR"[..], b"GCOL", b"TREE", b"HEAP", b"SNOD"].iter().filter(|s| good.windows(4).any(|w| w == **s)).map(|s| at(s) + 9));
        assert!(places.len() >= 9, "the signatures of an HDF5 1.10 file are there: {places:?}");
        let mut cases: Vec<(String, Vec<u8>)> = places
            .iter()
            .flat_map(|&i| {
                [0x01u8, 0x80].map(|bit| {
                    let mut b = good.clone();
                    b[i] ^= bit;
                    (format!("byte {i} ^ {bit:#x}"), b)
                })
            })
            .collect();
        cases.push(("cut at 2/3".into(), good[..good.len() * 2 / 3].to_vec()));
        cases.push(("a byte appended".into(), [&good[..], &[0]].concat()));
        cases.push(("empty".into(), Vec::new()));
        for (what, bytes) in cases {
            std::fs::write(&p, &bytes).unwrap();
            let e = read(&p).unwrap_err();
            assert!(matches!(e, SchemaError::Damaged { .. }), "{what}: {e}");
            let e = e.to_string();
            assert!(e.starts_with(&format!("{}: checkpoint damaged (", p.display())) && !e.contains('\n'), "{what}: {e}");
        }
        std::fs::write(&p, [&good[..], &[0]].concat()).unwrap();
        let e = read(&p).unwrap_err().to_string();
        assert!(e.contains("checksum mismatch") && e.contains(&format!("{} bytes, written with {}", good.len() + 1, good.len())), "{e}");
        std::fs::write(&p, &good).unwrap();
        assert_eq!(read(&p).unwrap(), small(), "the good bytes still read");
    }

    /// Checkpoints of builds before the checksum (the HDF5 file from byte 0) still load, unchecked: a
    /// checkpoint of the science-6p5 study written before the checksum (`examples/fixtures/pre-checksum/`,
    /// read from a copy), and a new checkpoint with its user block cut off (which is exactly the
    /// older layout: HDF5 addresses count from the superblock).
    #[test]
    fn a_checkpoint_without_the_checksum_still_loads() {
        let dir = tempfile::tempdir().unwrap();
        let study = Path::new(env!("CARGO_MANIFEST_DIR")).join("../examples/fixtures/pre-checksum");
        let name = "discocyte_u3.8_r0.8.h5.discocyte_u3.8_r0.8.ckpt";
        let p = dir.path().join(name);
        std::fs::copy(study.join(name), &p).unwrap();
        let bytes = std::fs::read(&p).unwrap();
        let integrity = verify(&p, &bytes).unwrap();
        let ck = read(&p).unwrap();
        assert_eq!(ck.run_id, "discocyte_u3.8_r0.8");
        assert!(ck.t_s > 0.0 && !ck.fields["runner.vertices_um"].is_empty() && ck.n_samples > 0, "{} s", ck.t_s);
        assert_eq!(integrity, Integrity::Unchecked, "the fixture is of the layout without a checksum");

        let (_new, q, new) = written();
        let old = new[USER_BLOCK..].to_vec();
        std::fs::write(&q, &old).unwrap();
        assert_eq!(verify(&q, &old).unwrap(), Integrity::Unchecked);
        assert_eq!(read(&q).unwrap(), small());
    }

    /// A file whose `kind` attribute is not a checkpoint's is refused naming that attribute (the
    /// message blamed `schema_version` before, the right version included).
    #[test]
    fn a_file_of_another_kind_is_refused_naming_the_attribute() {
        let dir = tempfile::tempdir().unwrap();
        let p = dir.path().join("r.h5.cap.ckpt");
        let mut fields = BTreeMap::new();
        fields.insert("runner.t_s".to_string(), vec![0.5]);
        let ck = Checkpoint { run_id: "cap".into(), scene: "[time]\noutput_interval_s = 0.0005 # kind-test\n".into(), t_s: 0.5, n_samples: 1, n_snapshots: 1, fields };
        write(&p, &ck).unwrap();
        let mut bytes = std::fs::read(&p).unwrap();
        // the attribute's value (after the user block, whose checksum line names the format too),
        // same length
        let at = USER_BLOCK + bytes[USER_BLOCK..].windows(14).position(|w| w == b"rbc-checkpoint").expect("the kind is stored as bytes");
        bytes[at..at + 14].copy_from_slice(b"rbc-elsewhere!");
        reseal(&mut bytes);
        std::fs::write(&p, &bytes).unwrap();
        let e = read(&p).unwrap_err().to_string();
        assert!(e.contains("r.h5.cap.ckpt") && e.contains("`kind`") && e.contains("rbc-elsewhere!") && !e.contains("schema_version"), "{e}");
    }

    /// A checkpoint whose scene text holds a byte that is not UTF-8 (a damaged file: `rbc-bench fuzz
    /// --format checkpoint --seed 2 --case 56` flipped a space to 0xA0) was handed on as a `String`
    /// unchecked and panicked in the TOML parser; it is refused naming the file and the attribute.
    #[test]
    fn scene_text_that_is_not_utf8_is_refused_naming_the_attribute() {
        let dir = tempfile::tempdir().unwrap();
        let p = dir.path().join("r.h5.cap.ckpt");
        let mut fields = BTreeMap::new();
        fields.insert("runner.t_s".to_string(), vec![0.5]);
        let ck = Checkpoint { run_id: "cap".into(), scene: "[time]\noutput_interval_s = 0.0005 # QQQQ\n".into(), t_s: 0.5, n_samples: 1, n_snapshots: 1, fields };
        write(&p, &ck).unwrap();
        let mut bytes = std::fs::read(&p).unwrap();
        let at = bytes.windows(4).position(|w| w == b"QQQQ").expect("the scene text is stored as bytes");
        bytes[at] = 0xa0;
        std::fs::write(&p, &bytes).unwrap();
        let e = read(&p).unwrap_err().to_string();
        assert!(e.contains("r.h5.cap.ckpt: checkpoint damaged (checksum mismatch"), "the checksum sees the change first: {e}");
        // the same bytes with a checksum that matches (a file damaged before it was sealed, or an older build's)
        reseal(&mut bytes);
        std::fs::write(&p, &bytes).unwrap();
        let e = read(&p).unwrap_err().to_string();
        assert!(e.contains("r.h5.cap.ckpt") && e.contains("`scene`") && e.contains("UTF-8"), "{e}");
    }
}
