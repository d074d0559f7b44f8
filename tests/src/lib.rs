//! Workspace-level tests live in this crate.
