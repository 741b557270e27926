//! Built-in example studies, `flexmbs example NAME [DIR]`: the files of `examples/` at the
//! root of the repository, compiled into the program so that it can write them anywhere.
//! The study tests run each of them (`every_example_runs_through_the_library`).

use crate::error::{BoxError, ResultExt};
use crate::input::source::unknown_reference;
use std::path::{Path, PathBuf};

/// One example: its name, what it shows, and its files (path relative to the folder it is
/// written to, contents).
pub struct Example {
    pub name: &'static str,
    pub description: &'static str,
    pub files: &'static [(&'static str, &'static [u8])],
}

/// The study file of the slider-crank example, which `flexmbs run` without a file runs.
pub const SLIDER_CRANK: &str = include_str!("../../../../examples/slider_crank.toml");

pub const EXAMPLES: &[Example] = &[
    Example {
        name: "cantilever",
        description: "a steel beam: statics and modes against beam theory, reduced with an interface at each end",
        files: &[(
            "cantilever.toml",
            include_bytes!("../../../../examples/cantilever.toml"),
        )],
    },
    Example {
        name: "solid_bar",
        description: "solid bars (a gmsh tet10 mesh and a generated hex20 box) reduced with RBE2 and RBE3 interfaces",
        files: &[
            ("solid_bar.toml", include_bytes!("../../../../examples/solid_bar.toml")),
            (
                "meshes/bar_tet10.msh",
                include_bytes!("../../../../examples/meshes/bar_tet10.msh"),
            ),
        ],
    },
    Example {
        name: "elastica",
        description:
            "B1: Mattiasson's elastica, a cantilever of four superelements under a large tip force (equilibrium)",
        files: &[("elastica.toml", include_bytes!("../../../../examples/elastica.toml"))],
    },
    Example {
        name: "bend45",
        description: "B3: the Bathe-Bolourchi 45-degree bend under an out-of-plane tip force (equilibrium)",
        files: &[("bend45.toml", include_bytes!("../../../../examples/bend45.toml"))],
    },
    Example {
        name: "spin_up",
        description: "C1: spin-up of a flexible beam by a driven hub, tip seen from the hub (dynamic)",
        files: &[("spin_up.toml", include_bytes!("../../../../examples/spin_up.toml"))],
    },
    Example {
        name: "slider_crank",
        description:
            "C2: planar flexible slider-crank at 150 rad/s, rod midpoint deflection (dynamic); `flexmbs run` runs it",
        files: &[("slider_crank.toml", SLIDER_CRANK.as_bytes())],
    },
    Example {
        name: "slider_crank_spatial",
        description: "C3: spatial slider-crank, crank axis offset 0.1 m from the guide (dynamic)",
        files: &[(
            "slider_crank_spatial.toml",
            include_bytes!("../../../../examples/slider_crank_spatial.toml"),
        )],
    },
    Example {
        name: "double_pendulum",
        description:
            "a double pendulum of two flexible links released from 30 degrees by one [[initial]] line (dynamic)",
        files: &[(
            "double_pendulum.toml",
            include_bytes!("../../../../examples/double_pendulum.toml"),
        )],
    },
    Example {
        name: "four_bar",
        description:
            "a four-bar whose coupler is a solid from a gmsh mesh (equilibrium, linearized and dynamic from it)",
        files: &[
            ("four_bar.toml", include_bytes!("../../../../examples/four_bar.toml")),
            (
                "meshes/link_hex8.msh",
                include_bytes!("../../../../examples/meshes/link_hex8.msh"),
            ),
        ],
    },
    Example {
        name: "controlled_arm",
        description:
            "a flexible arm on a motor hub whose torque a controller sets between steps (dynamic; docs/python.md)",
        files: &[(
            "controlled_arm.toml",
            include_bytes!("../../../../examples/controlled_arm.toml"),
        )],
    },
];

/// The list for `flexmbs example` without a name.
pub fn list() -> String {
    let mut s = String::from("built-in examples (write one with `flexmbs example NAME [DIR]`):\n");
    for e in EXAMPLES {
        s.push_str(&format!("  {:<21} {}\n", e.name, e.description));
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
