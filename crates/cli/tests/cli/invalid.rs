//! Property test (fixed seeds): no study file, however broken, makes `flexmbs`
//! panic; every invalid one gives exit code 2 and a located message.
//!
//! Inputs: random text, random soup of TOML fragments of the schema, and mutations of the
//! example studies and of the broken corpus (characters replaced, ranges deleted, fragments
//! inserted, lines duplicated and swapped, numbers replaced by hostile ones: 0, negatives,
//! NaN, infinities, 1e308, huge counts). Most cases run in-process through the validator
//! (fast); a sample runs through the binary to check the exit code.

use crate::support::*;
use std::path::Path;
use study::input::source::Source;

/// xorshift64*: small, fast, and the same sequence on every platform.
struct Rng(u64);

impl Rng {
    fn next(&mut self) -> u64 {
        self.0 ^= self.0 >> 12;
        self.0 ^= self.0 << 25;
        self.0 ^= self.0 >> 27;
        self.0.wrapping_mul(0x2545_f491_4f6c_dd1d)
    }
    fn below(&mut self, n: usize) -> usize {
        (self.next() % n.max(1) as u64) as usize
    }
    fn pick<'a>(&mut self, items: &[&'a str]) -> &'a str {
        items[self.below(items.len())]
    }
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

fn mutate(rng: &mut Rng, text: &str) -> String {
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
                let f: Vec<char> = rng.pick(FRAGMENTS).chars().collect();
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
                    let n: Vec<char> = rng.pick(NUMBERS).chars().collect();
                    chars.splice(i..j, n);
                }
            }
        }
    }
    chars.into_iter().collect()
}

fn random_text(rng: &mut Rng) -> String {
    let n = rng.below(300);
    if rng.below(2) == 0 {
        (0..n).map(|_| (b' ' + rng.below(95) as u8) as char).collect()
    } else {
        (0..rng.below(20)).map(|_| rng.pick(FRAGMENTS)).collect()
    }
}

/// The base files: the examples and the broken corpus.
fn bases() -> Vec<String> {
    let mut files = Vec::new();
    for dir in [
        examples_dir(),
        Path::new(env!("CARGO_MANIFEST_DIR")).join("tests/broken"),
    ] {
        for e in std::fs::read_dir(dir).unwrap() {
            let p = e.unwrap().path();
            if p.extension().is_some_and(|e| e == "toml") {
                files.push(p);
            }
        }
    }
    files.sort();
    files.into_iter().map(|p| std::fs::read_to_string(p).unwrap()).collect()
}

/// Validates `text` in-process; panics (failing the test) only if the program would.
fn check_in_process(study: &Path, text: String, case: usize) {
    let result = std::panic::catch_unwind(std::panic::AssertUnwindSafe(|| {
        match study::parse_and_validate(Source::from_text(study, text.clone())) {
            Ok(_) => None,
            Err(errors) => Some(errors.to_string()),
        }
    }));
    match result {
        Ok(Some(message)) => {
            assert!(
                message.contains("case.toml"),
                "case {case}: message without the file:\n{message}"
            );
        }
        Ok(None) => {}
        Err(_) => panic!("case {case} panicked on:\n{text}"),
    }
}

#[test]
fn random_and_mutated_study_files_fail_cleanly() {
    let dir = examples_copy("property");
    let study = dir.join("case.toml");
    let bases = bases();
    let mut rng = Rng(0x5eed_f1e8_3b5d_0001);
    let mut cases = Vec::new();
    for case in 0..1500 {
        let text = if case % 5 == 0 {
            random_text(&mut rng)
        } else {
            let base = &bases[rng.below(bases.len())];
            mutate(&mut rng, base)
        };
        check_in_process(&study, text.clone(), case);
        if case % 30 == 0 {
            cases.push(text);
        }
    }
    // A sample through the binary: exit code 0 (still valid) or 2 with a message, never a
    // panic (101) or a signal.
    let mut invalid = 0;
    for (k, text) in cases.iter().enumerate() {
        std::fs::write(&study, text).unwrap();
        let out = flexmbs(&dir, &["check", "case.toml"]);
        match out.code {
            0 => {}
            2 => {
                invalid += 1;
                assert!(
                    out.stderr.starts_with("flexmbs: error: "),
                    "sample {k}:\n{}",
                    out.stderr
                );
                assert!(out.stderr.contains("case.toml"), "sample {k}:\n{}", out.stderr);
            }
            code => panic!("sample {k}: exit code {code}\n{}\non:\n{text}", out.stderr),
        }
    }
    assert!(
        invalid > cases.len() / 2,
        "the mutations should mostly break the files ({invalid} of {})",
        cases.len()
    );
}

/// Inputs that are not text, and nesting deep enough to overflow a recursive parser.
#[test]
fn binary_and_deeply_nested_files_fail_cleanly() {
    let dir = scratch("property-special");
    std::fs::write(dir.join("binary.toml"), [0xff, 0xfe, 0x00, 0x41, 0x80]).unwrap();
    let out = flexmbs(&dir, &["check", "binary.toml"]);
    assert_eq!(out.code, 2);
    assert!(out.stderr.contains("not UTF-8"), "{}", out.stderr);
    for text in [
        format!("a = {}", "[".repeat(100_000)),
        format!("a = {}", "{ b = ".repeat(50_000)),
    ] {
        std::fs::write(dir.join("deep.toml"), text).unwrap();
        let out = flexmbs(&dir, &["check", "deep.toml"]);
        assert_eq!(out.code, 2, "{}", out.stderr);
        assert!(out.stderr.contains("deep.toml"), "{}", out.stderr);
    }
    std::fs::write(dir.join("empty.toml"), "").unwrap();
    // An empty study parses, and is refused for having nothing to run.
    let out = flexmbs(&dir, &["check", "empty.toml"]);
    assert_eq!(out.code, 2, "{}", out.stderr);
    assert!(out.stderr.contains("no [[analyses]]"), "{}", out.stderr);
}
