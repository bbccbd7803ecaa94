//! Reader for real-time deformability cytometry (`.rtdc`, HDF5) files: images, masks and features of events.
