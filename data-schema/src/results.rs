//! `results.h5`: many simulation runs in one HDF5 file (layout, writer, reader, schema_version).
