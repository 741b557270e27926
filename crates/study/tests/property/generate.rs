//! Broken study files made on purpose (fixed seeds): random text, random soup of TOML
//! fragments of the schema, and mutations of good and broken studies (characters replaced,
//! ranges deleted, fragments inserted, lines duplicated and swapped, numbers replaced by
//! hostile ones: 0, negatives, NaN, infinities, 1e308, huge counts).
//!
//! Used by the study crate's property test (the validator in-process) and by the program's
//! (a sample through the binary, for its exit code): one generator, included by both.

// Each test binary uses the helpers it needs.
#![allow(dead_code)]

use fe_model::fuzz::Mutator;
use std::path::{Path, PathBuf};

/// One of `items`.
fn pick<'a>(rng: &mut Mutator, items: &[&'a str]) -> &'a str {
    items[rng.below(items.len())]
}

/// Fragments of the schema and of TOML syntax, valid and not.
const FRAGMENTS: &[&str] = &[
    "[[parts]]\n",
    "[parts.beam]\n",
    "[parts.box]\n",
    "[parts.mesh]\n",
    "[[parts.interfaces]]\n",
    "[parts.reduction]\n",
    "[[analyses]]\n",
    "[[materials]]\n",
    "[[sections]]\n",
    "[[joints]]\n",
    "[output]\n",
    "[study]\n",
    "name = \"beam\"\n",
    "name = \"\"\n",
    "name = \"a/b\"\n",
    "material = \"steel\"\n",
    "type = \"static\"\n",
    "type = \"modal\"\n",
    "type = \"reduce\"\n",
    "type = \"dynamic\"\n",
    "part = \"beam\"\n",
    "part = \"bar\"\n",
    "modes = 0\n",
    "modes = 3\n",
    "cutoff_hz = -5.0\n",
    "auxiliary_node = true\n",
    "kind = \"arc\"\n",
    "kind = \"frame\"\n",
    "kind = \"straight\"\n",
    "elements = 3\n",
    "elements = 99999\n",
    "section = \"round\"\n",
    "from = [0, 0, 0]\n",
    "to = [0, 0, 0]\n",
    "to = [1e308, 1e308, 1e308]\n",
    "center = [0.0, 0.0, 0.0]\n",
    "start = [0.0, 0.0, 0.0]\n",
    "axis = [0.0, 0.0, 0.0]\n",
    "angle_deg = 720.0\n",
    "points = [[0.0, 0.0, 0.0], [1.0, 0.0, 0.0]]\n",
    "members = [{ from = 0, to = 5, elements = 2 }]\n",
    "members = [{ from = 0, to = 0, elements = 2 }]\n",
    "size = [1.0, 0.1, 0.1]\n",
    "size = [0.0, -1.0, nan]\n",
    "divisions = [2, 1, 1]\n",
    "divisions = [0, 1, 1]\n",
    "divisions = [100000, 100000, 100000]\n",
    "element = \"hex20\"\n",
    "element = \"wedge6\"\n",
    "element = \"tet10\"\n",
    "file = \"meshes/bar_tet10.msh\"\n",
    "file = \"/dev/null\"\n",
    "file = \"meshes\"\n",
    "set = \"x0\"\n",
    "set = \"beam.end\"\n",
    "set = \"tip\"\n",
    "near = [1.0, 0.1, 0.1]\n",
    "radius = 0.05\n",
    "radius = inf\n",
    "spider = \"rbe2\"\n",
    "spider = \"rbe3\"\n",
    "node_at = [2.0, 0.0, 0.0]\n",
    "node_position = [nan, 0.0, 0.0]\n",
    "supports = [{ at = \"root\" }]\n",
    "supports = [{ at = \"x0\", dofs = [] }]\n",
    "loads = [{ at = \"tip\", force = [0.0, 0.0, 1.0] }]\n",
    "loads = [{ at = \"x1\", moment = [1.0, 0.0, 0.0] }]\n",
    "loads = []\n",
    "E = 210e9\n",
    "E = 0\n",
    "nu = 0.3\n",
    "nu = 0.5\n",
    "G = 80e9\n",
    "rho = 7850.0\n",
    "rho = -1.0\n",
    "shape = \"circle\"\n",
    "shape = \"tube\"\n",
    "d = 0.01\n",
    "d_outer = 0.01\n",
    "d_inner = 0.02\n",
    "b = 0.02\n",
    "h = 0.04\n",
    "A = 1e-4\n",
    "ky = 2.0\n",
    "materials = { body = \"steel\" }\n",
    "dofs = \"translations\"\n",
    "solver = \"sparse\"\n",
    "[",
    "]",
    "{",
    "}",
    "\"",
    "=",
    ",",
    "\n",
    "#",
    "'''",
    "\"\"\"",
    "[[",
    "]]",
    "a.b.c = 1\n",
    "x = 1979-05-27T07:32:00Z\n",
    "é",
    "\u{0}",
];

/// Numbers that probe the range checks.
const NUMBERS: &[&str] = &[
    "0",
    "-1",
    "1e308",
    "-0.0",
    "nan",
    "inf",
    "-inf",
    "1e-320",
    "123456789",
    "3",
    "0.5",
    "2",
    "-7e9",
    "1_000",
];

pub fn mutate(rng: &mut Mutator, text: &str) -> String {
    let mut chars: Vec<char> = text.chars().collect();
    for _ in 0..1 + rng.below(4) {
        match rng.below(6) {
            0 if !chars.is_empty() => {
                let i = rng.below(chars.len());
                chars[i] = (b' ' + rng.below(95) as u8) as char;
            }
            1 if !chars.is_empty() => {
                let i = rng.below(chars.len());
                let n = (1 + rng.below(20)).min(chars.len() - i);
                chars.drain(i..i + n);
            }
            2 => {
                let i = rng.below(chars.len() + 1);
                let f: Vec<char> = pick(rng, FRAGMENTS).chars().collect();
                chars.splice(i..i, f);
            }
            3 | 4 => {
                let s: String = chars.iter().collect();
                let mut lines: Vec<&str> = s.lines().collect();
                if lines.len() >= 2 {
                    let (a, b) = (rng.below(lines.len()), rng.below(lines.len()));
                    if rng.below(2) == 0 {
                        lines.swap(a, b);
                    } else {
                        let l = lines[a];
                        lines.insert(b, l);
                    }
                }
                chars = lines.join("\n").chars().collect();
            }
            _ => {
                // Replace a number literal with a hostile one.
                let starts: Vec<usize> = (0..chars.len())
                    .filter(|&i| chars[i].is_ascii_digit() && (i == 0 || !chars[i - 1].is_ascii_alphanumeric()))
                    .collect();
                if !starts.is_empty() {
                    let i = starts[rng.below(starts.len())];
                    let mut j = i;
                    while j < chars.len()
                        && (chars[j].is_ascii_alphanumeric() || matches!(chars[j], '.' | '-' | '+' | '_'))
                    {
                        j += 1;
                    }
                    let n: Vec<char> = pick(rng, NUMBERS).chars().collect();
                    chars.splice(i..j, n);
                }
            }
        }
    }
    chars.into_iter().collect()
}

pub fn random_text(rng: &mut Mutator) -> String {
    let n = rng.below(300);
    if rng.below(2) == 0 {
        (0..n).map(|_| (b' ' + rng.below(95) as u8) as char).collect()
    } else {
        (0..rng.below(20)).map(|_| pick(rng, FRAGMENTS)).collect()
    }
}

/// The `.toml` files of `dir`, sorted.
pub fn toml_files(dir: &Path) -> Vec<PathBuf> {
    let mut files: Vec<PathBuf> = std::fs::read_dir(dir)
        .unwrap()
        .map(|e| e.unwrap().path())
        .filter(|p| p.extension().is_some_and(|e| e == "toml"))
        .collect();
    files.sort();
    files
}

/// The corpus of broken study files, `crates/study/tests/broken`, from the repository root
/// `repo`: each file lists the messages its validation must give (`# expect:` lines).
pub fn corpus(repo: &Path) -> Vec<PathBuf> {
    toml_files(&repo.join("crates/study/tests/broken"))
}

/// The base files of the mutations: the repository's example studies, then the corpus.
pub fn bases(repo: &Path) -> Vec<String> {
    let mut files = toml_files(&repo.join("examples"));
    files.extend(corpus(repo));
    files.into_iter().map(|p| std::fs::read_to_string(p).unwrap()).collect()
}

/// The cases, in order: every fifth random text, the others mutations of a base file.
pub fn cases(repo: &Path, n: usize) -> Vec<String> {
    let bases = bases(repo);
    let mut rng = Mutator::new(0x5eed_f1e8_3b5d_0001);
    (0..n)
        .map(|case| {
            if case % 5 == 0 {
                random_text(&mut rng)
            } else {
                let base = &bases[rng.below(bases.len())];
                mutate(&mut rng, base)
            }
        })
        .collect()
}
