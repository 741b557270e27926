//! The input wing: a study file read, checked and resolved into a [`validate::Study`] before
//! anything is built or run.
//!
//! | module | what it holds |
//! |---|---|
//! | [`schema`] | the serde schema of a study file, raw: every key |
//! | [`keys`] | the registry of the keys: each declared once, with type, unit, default, range and meaning |
//! | [`source`] | spans, key paths, error rendering, close matches |
//! | [`validate`] | validation `StudyFile` → `Study` (parts, analyses; `validate::mechanism`: the mechanism) |
//! | [`part`] | a validated part and the FE model an analysis runs on |
//! | [`matrices`] | a body reduced from another FE code's Matrix Market K and M, node and dof tables |
//! | `toml_path` | key paths into a study's TOML text: resolve by index or name, read a value |
//! | [`document`] | a study as an editable document: load from a file or text, get and set values by key path |
//! | [`examples`] | the built-in example studies of `examples/` |

pub mod document;
pub mod examples;
pub mod keys;
pub mod matrices;
pub mod part;
pub mod schema;
pub mod source;
pub(crate) mod toml_path;
pub mod validate;
