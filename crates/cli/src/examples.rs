//! Built-in example studies, `flexmbs example NAME [DIR]`: the files of `examples/` at the
//! root of the repository, compiled into the program so that it can write them anywhere.
//! `tests/cli.rs` runs each of them.

use crate::error::{BoxError, ResultExt};
use crate::source::unknown_reference;
use std::path::{Path, PathBuf};

/// One example: its name, what it shows, and its files (path relative to the folder it is
/// written to, contents).
pub struct Example {
    pub name: &'static str,
    pub description: &'static str,
    pub files: &'static [(&'static str, &'static [u8])],
}

pub const EXAMPLES: &[Example] = &[
    Example {
        name: "cantilever",
        description: "a steel beam: statics and modes against beam theory, reduced with an interface at each end",
        files: &[("cantilever.toml", include_bytes!("../../../examples/cantilever.toml"))],
    },
    Example {
        name: "solid_bar",
        description: "solid bars (a gmsh tet10 mesh and a generated hex20 box) reduced with RBE2 and RBE3 interfaces",
        files: &[
            ("solid_bar.toml", include_bytes!("../../../examples/solid_bar.toml")),
            (
                "meshes/bar_tet10.msh",
                include_bytes!("../../../examples/meshes/bar_tet10.msh"),
            ),
        ],
    },
];

/// The list for `flexmbs example` without a name.
pub fn list() -> String {
    let mut s = String::from("built-in examples (write one with `flexmbs example NAME [DIR]`):\n");
    for e in EXAMPLES {
        s.push_str(&format!("  {:<12} {}\n", e.name, e.description));
    }
    s
}

/// Writes example `name` into `dir` and returns the study file. An existing file with other
/// contents is not overwritten (it may be the user's edited copy).
pub fn write(name: &str, dir: &Path) -> Result<PathBuf, BoxError> {
    let Some(example) = EXAMPLES.iter().find(|e| e.name == name) else {
        let names: Vec<String> = EXAMPLES.iter().map(|e| e.name.to_string()).collect();
        return Err(unknown_reference("example", name, &names).into());
    };
    for (file, contents) in example.files {
        let path = dir.join(file);
        if let Ok(existing) = std::fs::read(&path) {
            if existing != *contents {
                return Err(format!(
                    "{} exists with other contents: not overwriting it (remove it, or give another folder)",
                    path.display()
                )
                .into());
            }
        }
    }
    for (file, contents) in example.files {
        let path = dir.join(file);
        if let Some(parent) = path.parent() {
            std::fs::create_dir_all(parent).context(|| format!("cannot create the folder {}", parent.display()))?;
        }
        std::fs::write(&path, contents).context(|| format!("cannot write {}", path.display()))?;
        eprintln!("flexmbs: wrote {}", path.display());
    }
    Ok(dir.join(example.files[0].0))
}
