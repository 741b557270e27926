//! No code. This crate's manifest asks for the union of the features that the workspace's
//! builds ask of some shared third-party crates, so that every build compiles them once
//! (the manifest says why).
