//! Study texts the study tests share, built from parameters: one function per recurring
//! shape (a material, a rectangular section, a straight beam part with interfaces at its
//! ends, a chain of such bodies welded end to end, a rigid body, the rigid pendulum, joints,
//! loads, sensors and analyses). Each returns TOML entries ending in a newline, to be joined
//! in the order the test wants them; numbers are written with `{:?}` (`7850.0`,
//! `210000000000.0`), which TOML reads back to the same `f64`.

// Each test binary uses the helpers it needs.
#![allow(dead_code, non_snake_case)]

use std::fmt::Write;
use std::path::PathBuf;

/// A study text built when it is used, which `format!` can name inline as it names a `&str`
/// constant: `const PENDULUM: Text = Text(pendulum_text);` then `format!("{PENDULUM}...")`.
pub struct Text(pub fn() -> String);

impl std::fmt::Display for Text {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.write_str(&(self.0)())
    }
}

/// A fresh scratch folder `study-<kind>-<process>-<name>` for one test.
pub fn scratch_dir(kind: &str, name: &str) -> PathBuf {
    let dir = std::env::temp_dir().join(format!("study-{kind}-{}-{name}", std::process::id()));
    let _ = std::fs::remove_dir_all(&dir);
    std::fs::create_dir_all(&dir).unwrap();
    dir
}

/// `[x, y, z]`.
pub fn vec3(v: [f64; 3]) -> String {
    format!("[{:?}, {:?}, {:?}]", v[0], v[1], v[2])
}

/// `[[materials]]`: Young's modulus `E` \[Pa\], Poisson's ratio `nu`, density `rho` \[kg/m^3\].
pub fn material(name: &str, E: f64, nu: f64, rho: f64) -> String {
    format!("[[materials]]\nname = \"{name}\"\nE = {E:?}\nnu = {nu:?}\nrho = {rho:?}\n")
}

/// `[[sections]]`: a `b` x `h` rectangle \[m\].
pub fn rectangle(name: &str, b: f64, h: f64) -> String {
    format!("[[sections]]\nname = \"{name}\"\nshape = \"rectangle\"\nb = {b:?}\nh = {h:?}\n")
}

/// A straight beam part along x from the origin.
pub struct BeamPart<'a> {
    pub name: &'a str,
    pub material: &'a str,
    pub section: &'a str,
    /// Length \[m\].
    pub length: f64,
    pub elements: usize,
    /// `theory` (`None`: the default).
    pub theory: Option<&'a str>,
    /// `orientation` (`None`: the default).
    pub orientation: Option<[f64; 3]>,
    /// The interfaces: name and node set (`"<part>.start"`, `"<part>.end"`).
    pub interfaces: &'a [(&'a str, &'a str)],
    /// `[parts.reduction] modes` (`None`: no reduction table).
    pub modes: Option<usize>,
}

impl BeamPart<'_> {
    /// `[[parts]]` with its `[parts.beam]`, interfaces and reduction.
    pub fn toml(&self) -> String {
        let mut t = format!(
            "[[parts]]\nname = \"{}\"\nmaterial = \"{}\"\n[parts.beam]\nkind = \"straight\"\nfrom = [0.0, 0.0, 0.0]\n\
             to = {}\nelements = {}\nsection = \"{}\"\n",
            self.name,
            self.material,
            vec3([self.length, 0.0, 0.0]),
            self.elements,
            self.section
        );
        if let Some(v) = self.orientation {
            writeln!(t, "orientation = {}", vec3(v)).unwrap();
        }
        if let Some(theory) = self.theory {
            writeln!(t, "theory = \"{theory}\"").unwrap();
        }
        for (name, set) in self.interfaces {
            write!(t, "[[parts.interfaces]]\nname = \"{name}\"\nset = \"{set}\"\n").unwrap();
        }
        if let Some(modes) = self.modes {
            write!(t, "[parts.reduction]\nmodes = {modes}\n").unwrap();
        }
        t
    }
}

/// A beam part `name` with the interfaces `a` at its start and `b` at its end, reduced with
/// `modes` modes.
pub fn two_ended_beam(
    name: &str,
    material: &str,
    section: &str,
    length: f64,
    elements: usize,
    theory: Option<&str>,
    modes: usize,
) -> String {
    let (a, b) = (format!("{name}.start"), format!("{name}.end"));
    BeamPart {
        name,
        material,
        section,
        length,
        elements,
        theory,
        orientation: None,
        interfaces: &[("a", &a), ("b", &b)],
        modes: Some(modes),
    }
    .toml()
}

/// `n` bodies `s0`, `s1`, ... of the two-ended beam part `part`, each `length` further along x
/// (the first at the origin, where a body is by default), and fixed joints `w1`, `w2`, ...
/// welding `b` of each to `a` of the next.
pub fn welded_chain(part: &str, n: usize, length: f64) -> String {
    let mut t = String::new();
    for i in 0..n {
        write!(t, "[[bodies]]\nname = \"s{i}\"\npart = \"{part}\"\n").unwrap();
        if i > 0 {
            writeln!(t, "position = {}", vec3([length * i as f64, 0.0, 0.0])).unwrap();
        }
    }
    for i in 1..n {
        write!(
            t,
            "[[joints]]\nname = \"w{i}\"\ntype = \"fixed\"\nbetween = [\"s{}.b\", \"s{i}.a\"]\n",
            i - 1
        )
        .unwrap();
    }
    t
}

/// `[[rigid_bodies]]`: `mass` \[kg\], centre of mass \[m\], a diagonal inertia about it
/// \[kg m^2\] and named points \[m\].
pub fn rigid_body(
    name: &str,
    mass: f64,
    center_of_mass: [f64; 3],
    inertia: [f64; 3],
    points: &[(&str, [f64; 3])],
) -> String {
    let [a, b, c] = inertia;
    let points: Vec<String> = points.iter().map(|(p, x)| format!("{p} = {}", vec3(*x))).collect();
    format!(
        "[[rigid_bodies]]\nname = \"{name}\"\nmass = {mass:?}\ncenter_of_mass = {}\n\
         inertia = [{}, {}, {}]\npoints = {{ {} }}\n",
        vec3(center_of_mass),
        vec3([a, 0.0, 0.0]),
        vec3([0.0, b, 0.0]),
        vec3([0.0, 0.0, c]),
        points.join(", ")
    )
}

/// A revolute joint about `axis`.
pub fn revolute(name: &str, between: [&str; 2], axis: [f64; 3]) -> String {
    format!(
        "[[joints]]\nname = \"{name}\"\ntype = \"revolute\"\nbetween = [\"{}\", \"{}\"]\naxis = {}\n",
        between[0],
        between[1],
        vec3(axis)
    )
}

/// The rigid pendulum: `bob` (1 kg, centre of mass 1 m below its point `O`, 0.01 kg m^2 about
/// each axis through it: 1.01 kg m^2 about the pivot) on the revolute joint `pivot` about z
/// from the ground at `O` (the origin); `points` besides `O`.
pub fn pendulum(points: &[(&str, [f64; 3])]) -> String {
    let mut all = vec![("O", [0.0; 3])];
    all.extend_from_slice(points);
    rigid_body("bob", 1.0, [0.0, -1.0, 0.0], [0.01; 3], &all) + &revolute("pivot", ["ground", "bob.O"], [0.0, 0.0, 1.0])
}

/// A `gravity` load `g` \[m/s^2\].
pub fn gravity(name: &str, g: [f64; 3]) -> String {
    format!("[[loads]]\nname = \"{name}\"\ntype = \"gravity\"\ng = {}\n", vec3(g))
}

/// A `clamp` support at `at`.
pub fn clamp(at: &str) -> String {
    format!("[[supports]]\nat = \"{at}\"\ntype = \"clamp\"\n")
}

/// A sensor of `kind` on `of`.
pub fn sensor(name: &str, kind: &str, of: &str) -> String {
    format!("[[sensors]]\nname = \"{name}\"\ntype = \"{kind}\"\nof = \"{of}\"\n")
}

/// A `dynamic` analysis to `t_end` in steps `dt` \[s\] (numbers as the test writes them).
pub fn dynamic(t_end: &str, dt: &str) -> String {
    format!("[[analyses]]\ntype = \"dynamic\"\nt_end = {t_end}\ndt = {dt}\n")
}

/// A `dynamic` analysis `name` that starts from the final state of the analysis `start`
/// (`None`: from the initial state).
pub fn named_dynamic(name: &str, start: Option<&str>, t_end: &str, dt: &str) -> String {
    let start = start.map(|s| format!("start = \"{s}\"\n")).unwrap_or_default();
    format!("[[analyses]]\ntype = \"dynamic\"\nname = \"{name}\"\n{start}t_end = {t_end}\ndt = {dt}\n")
}

/// An `equilibrium` analysis `name` with the relative residual `tolerance`.
pub fn equilibrium(name: &str, tolerance: &str) -> String {
    format!("[[analyses]]\ntype = \"equilibrium\"\nname = \"{name}\"\ntolerance = {tolerance}\n")
}

/// A `linearized` analysis of `modes` modes.
pub fn linearized(modes: usize) -> String {
    format!("[[analyses]]\ntype = \"linearized\"\nmodes = {modes}\n")
}
