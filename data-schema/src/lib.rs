//! rbc-schema: every on-disk format of rbc-toolkit, with its reader, writer and validation.
//!
//! Formats are documented where they are defined and summarised in
//! `../shared/spec/interfaces.md`:
//! - [`recording`]: `recording.toml` beside a folder of frames.
//! - [`tables`]: the CSV tables of `rbc-analyze` and `rbc-predict`, one row type per table.
//! - [`scene`]: the solver's scene TOML files; [`sweep`]: the sweep files of `rbc-sweep`.
//! - [`results`]: `results.h5`, many simulation runs in one HDF5 file.
//! - [`start_shape`]: an ended run's last shape copied into a file of start shapes for other runs.
//! - [`xdmf`]: `.xmf` descriptions of the snapshots in `results.h5` for ParaView.
//! - [`rtdc`]: reader for real-time deformability cytometry files (real test frames).
//! - [`hdf5_watch`]: the watchdog that ends a command whose libhdf5 call hangs or crashes on a damaged file with one line naming it.
//!
//! Tables are read and written with the `csv` crate rather than polars: our
//! tables hold at most a few thousand rows, and polars would add 5 to 14 minutes
//! of build time on the 2-core CI machine (`../shared/spec/dependencies.md`)
//! for no capability we use.
//!
//! Every error names the file and the field, row or column that is wrong
//! ([`SchemaError`]); every writer writes to a temporary file in the target
//! folder and renames it into place ([`atomic`]), so a failed run never leaves
//! a half-written output, and a command writing several outputs replaces them as a set
//! ([`output_set`]); an error of the temporary file or folder names the target ([`unstage`]).

pub mod atomic;
pub mod checkpoint;
pub mod paper_scene;
pub mod error;
pub mod hdf5_watch;
pub mod output_set;
pub mod recording;
pub mod results;
pub mod rtdc;
pub mod scene;
pub mod start_shape;
pub mod sweep;
pub mod tables;
pub mod unstage;
pub mod xdmf;

pub use error::SchemaError;
