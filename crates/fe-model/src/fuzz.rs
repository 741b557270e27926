//! Seeded mutations of input files, for the fuzz tests of every reader (gmsh meshes, reduced
//! bodies, Matrix Market matrices, study files). A fixed seed and a fixed count make the
//! budget the same in every test run; `FLEXMBS_FUZZ_SCALE=N` multiplies the count to search
//! harder. Stable Rust only: no fuzzing engine, a plain loop over mutants.
//!
//! A mutant applies one to four edits: set, flip, delete or insert a byte; replace a number
//! with an extreme one (0, -1, huge counts, 1e308, NaN, a negative zero, an overflowing
//! integer); delete, duplicate or swap lines; cut the file.

/// The extreme numbers a number token may become: counts that overflow or allocate a lot,
/// values outside every range, and text that is not a number.
pub const EXTREMES: &[&str] = &[
    "0",
    "-1",
    "1",
    "2",
    "-0",
    "nan",
    "inf",
    "-inf",
    "1e308",
    "-1e308",
    "1e-320",
    "4294967296",
    "18446744073709551615",
    "18446744073709551616",
    "9223372036854775807",
    "2000000001",
    "1e9",
    "0x10",
    "",
];

/// xorshift64*: the same sequence on every platform.
#[derive(Clone, Debug)]
pub struct Mutator(u64);

impl Mutator {
    pub fn new(seed: u64) -> Self {
        Self(seed.max(1))
    }

    /// The next number of the sequence.
    pub fn next_u64(&mut self) -> u64 {
        self.0 ^= self.0 >> 12;
        self.0 ^= self.0 << 25;
        self.0 ^= self.0 >> 27;
        self.0.wrapping_mul(0x2545_F491_4F6C_DD1D)
    }

    /// A number in `0..n` (`n` > 0).
    pub fn below(&mut self, n: usize) -> usize {
        (self.next_u64() % n.max(1) as u64) as usize
    }

    /// A mutant of `input` (module docs).
    pub fn mutate(&mut self, input: &[u8]) -> Vec<u8> {
        let mut b = input.to_vec();
        for _ in 0..1 + self.below(4) {
            if b.is_empty() {
                b.push(b'0');
            }
            let at = self.below(b.len());
            match self.below(9) {
                0 => b[at] = b"0123456789-+.e $\n\"[]{}=,\xff\0"[self.below(24)],
                1 => b[at] ^= 1 << self.below(8),
                2 => {
                    b.remove(at);
                }
                3 => b.insert(at, self.next_u64() as u8),
                4 | 5 => self.replace_number(&mut b, at),
                6 => self.line_edit(&mut b, at),
                7 => b.truncate(at),
                _ => {
                    // Duplicate a chunk.
                    let len = self.below(64).min(b.len() - at);
                    let chunk = b[at..at + len].to_vec();
                    b.splice(at..at, chunk);
                }
            }
        }
        b
    }

    /// Replaces the number token at or after `at` by one of [`EXTREMES`].
    fn replace_number(&mut self, b: &mut Vec<u8>, at: usize) {
        let is_num = |c: u8| c.is_ascii_digit() || matches!(c, b'.' | b'-' | b'+' | b'e' | b'E');
        let Some(start) = (at..b.len()).find(|&i| b[i].is_ascii_digit()) else {
            return;
        };
        let mut s = start;
        while s > 0 && is_num(b[s - 1]) {
            s -= 1;
        }
        let mut e = start;
        while e < b.len() && is_num(b[e]) {
            e += 1;
        }
        let new = EXTREMES[self.below(EXTREMES.len())].as_bytes().to_vec();
        b.splice(s..e, new);
    }

    /// Deletes, duplicates or swaps whole lines around `at`.
    fn line_edit(&mut self, b: &mut Vec<u8>, at: usize) {
        let start = b[..at].iter().rposition(|&c| c == b'\n').map_or(0, |i| i + 1);
        let end = b[at..].iter().position(|&c| c == b'\n').map_or(b.len(), |i| at + i + 1);
        let line = b[start..end].to_vec();
        match self.below(3) {
            0 => {
                b.drain(start..end);
            }
            1 => {
                b.splice(start..start, line);
            }
            _ => {
                // Move the line to another place.
                b.drain(start..end);
                let to = self.below(b.len() + 1);
                let to = b[..to].iter().rposition(|&c| c == b'\n').map_or(0, |i| i + 1);
                b.splice(to..to, line);
            }
        }
    }
}

/// The number of mutants a fuzz test runs: `base` times `FLEXMBS_FUZZ_SCALE` (default 1).
pub fn budget(base: usize) -> usize {
    let scale = std::env::var("FLEXMBS_FUZZ_SCALE")
        .ok()
        .and_then(|s| s.parse::<usize>().ok())
        .unwrap_or(1);
    base.saturating_mul(scale.max(1))
}

/// The format of an [`Adversarial`] deck.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum DeckFormat {
    Abaqus,
    Nastran,
}

/// A deck made to exhaust a reader: its name, format and text. Read as it is, each must give
/// a model or a located error (file and line) within the readers' bounds; the fuzz tests
/// also mutate each.
#[derive(Clone, Debug)]
pub struct Adversarial {
    pub name: &'static str,
    pub format: DeckFormat,
    pub text: String,
}

/// The adversarial decks: ranges far longer than the deck (GENERATE, THRU), sets of sets
/// that double forty times, boundaries repeated on a set, and a card in every Nastran
/// continuation form (small field with `+` markers and blank markers, large field with `*`,
/// free field, a continuation with no card before it, a card cut in its continuation). Files
/// that include each other (include amplification) need files on disk and are made by the
/// tests.
pub fn adversarial_decks() -> Vec<Adversarial> {
    const NODES: &str = "*NODE\n1, 0, 0, 0\n2, 1, 0, 0\n3, 0, 1, 0\n4, 0, 0, 1\n";
    const GRIDS: &str = "GRID,1,,0.,0.,0.\nGRID,2,,1.,0.,0.\nGRID,3,,0.,1.,0.\nGRID,4,,0.,0.,1.\n";
    let abaqus = |name, rest: String| Adversarial {
        name,
        format: DeckFormat::Abaqus,
        text: format!("{NODES}{rest}"),
    };
    let nastran = |name, text: String| Adversarial {
        name,
        format: DeckFormat::Nastran,
        text,
    };
    let mut sets = "*NSET, NSET=S0\n1, 2, 3, 4\n".to_string();
    for k in 1..=40 {
        sets.push_str(&format!("*NSET, NSET=S{k}\nS{}, S{}\n", k - 1, k - 1));
    }
    vec![
        abaqus(
            "element GENERATE of 10^12",
            "*ELEMENT, TYPE=C3D4\n1, 1, 2, 3, 4\n*ELSET, ELSET=ALL, GENERATE\n1, 1000000000000\n".into(),
        ),
        abaqus("node GENERATE of 10^13", "*NSET, NSET=N, GENERATE\n1, 9999999999999, 1\n".into()),
        abaqus("node GENERATE with step 0", "*NSET, NSET=N, GENERATE\n1, 4, 0\n".into()),
        abaqus("sets of sets doubling forty times", sets),
        abaqus(
            "a boundary on a set 200 times",
            format!("*NSET, NSET=ALL\n1, 2, 3, 4\n*BOUNDARY\n{}", "ALL, ENCASTRE\n".repeat(200)),
        ),
        nastran(
            "THRU of 10^8 grids, eight times",
            format!("{GRIDS}{}", "SPC1,1,123,1,THRU,100000000\n".repeat(8)),
        ),
        nastran("THRU past u64", format!("{GRIDS}SPC1,1,123,1,THRU,18446744073709551616\n")),
        nastran("RBE2 THRU past the grids", format!("{GRIDS}RBE2,9,4,123,1,THRU,5\n")),
        nastran(
            "THRU over every grid 200 times",
            format!("{GRIDS}{}", "SPC1,1,123,1,THRU,4\n".repeat(200)),
        ),
        nastran(
            "small field, '+' continuation markers",
            "CORD2R  5               1.      2.      3.      2.      2.      3.      +C1\n+C1     1.      2.      4.\n".into(),
        ),
        nastran(
            "small field, blank continuation markers",
            "CORD2R  5               1.      2.      3.      2.      2.      3.\n        1.      2.      4.\n".into(),
        ),
        nastran(
            "large field, '*' continuation",
            "GRID*                  7                             1.5             2.5*G1\n*G1                  3.5               0\n".into(),
        ),
        nastran(
            "large field, blank continuation",
            "GRID*                  7                             1.5             2.5\n*                    3.5\n".into(),
        ),
        nastran(
            "free field, continuation by a trailing comma",
            "CORD2R,5,,1.,2.,3.,2.,2.,3.,\n,1.,2.,4.\n".into(),
        ),
        nastran(
            "free field large, '*' continuation",
            "GRID*,7,,1.5,2.5\n*,3.5\n".into(),
        ),
        nastran("a continuation with no card before it", "+C1     1.      2.      4.\n".into()),
        nastran(
            "a card cut in its continuation",
            "CORD2R  5               1.      2.      3.      2.      2.      3.      +C1\n".into(),
        ),
        nastran(
            "ten thousand continuations of one card",
            format!("SET1,1,1,{}\n", ",\n,2".repeat(10_000)),
        ),
    ]
}
