//! Workspace-level integration tests: one binary, a module per area.

mod docs;
mod scenes;
