//! Scene and sweep TOML files of the solver: raw serde structs and validation into typed configs.
