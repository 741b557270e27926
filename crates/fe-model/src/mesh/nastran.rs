//! Reader for Nastran bulk data (`.bdf`, `.nas`, `.dat`): small field, large field and free
//! field cards with continuations.
//!
//! [`read`] reads a file and the files it `INCLUDE`s; [`parse`] takes the text (for tests).
//! When the file has a `BEGIN BULK` line, everything before it (executive and case control)
//! is skipped; `ENDDATA` ends the bulk data.
//!
//! # Card formats
//!
//! * **Small field**: ten fields of 8 columns; field 1 is the card name (or blank, `+`, `*`
//!   on a continuation line), fields 2-9 data, field 10 (columns 73-80) a continuation marker.
//! * **Large field**: the name ends in `*` (`GRID*`); 16-column data fields, four per line; a
//!   continuation line starts with `*` (alone or as a marker `*G1`), `+` or a blank.
//! * **Free field**: fields separated by commas; a continuation line starts with `,`, `+` or
//!   `*`. Each line carries up to eight data fields (four for a large-field name).
//!
//! A continuation line has the field width of the card it continues, whatever its marker.
//!
//! # Units
//!
//! [`read`] and [`parse`] take the [`UnitSystem`] the deck is written in; in another than SI,
//! `GRID` and `CORD2R` coordinates, `E`, `G` and `RHO` (times `WTMASS`) are converted to SI.
//! A material whose constants no solid has in SI is a note in [`ImportedModel::notes`] that
//! names it (`MAT1_<mid>`), its line and the unit system its numbers fit.
//!
//! # Bounds
//!
//! A `G1 THRU G2` range may name at most as many grids as the deck has `GRID` cards, and all
//! ranges together at most 32 times that; a deck with its included files (each counted every
//! time it is included) holds at most [`MAX_INCLUDED_FILES`](super::import::MAX_INCLUDED_FILES)
//! files and [`MAX_EXPANDED_BYTES`](super::import::MAX_EXPANDED_BYTES) bytes. Past a bound
//! the error is [`ImportError::Limit`].
//!
//! Real numbers may use Nastran's exponent shorthand (`1.5-3` is $1.5\times10^{-3}$, `2.+5`)
//! and `D` exponents. Tabs expand to 8-column stops. `$` starts a comment line.
//!
//! # Cards read
//!
//! | card | read as |
//! |---|---|
//! | `GRID` | node; `CP` a `CORD2R` system (or 0); `CD` other than 0 only where no support or spider needs the node's axes |
//! | `CORD2R` | rectangular coordinate system (`RID` 0 or another `CORD2R`) |
//! | `CTETRA` (4, 10 nodes), `CHEXA` (8, 20), `CPENTA` (6) | solid cells in the cell set `PSOLID_<pid>`; either handedness (renumbered to a positive volume) |
//! | `PSOLID` | the material of its cells |
//! | `MAT1` | isotropic material `MAT1_<mid>` from two of `E`, `G`, `NU` (with all three, `G` must agree), `RHO` times `PARAM,WTMASS` |
//! | `RBE2` | a rigid spider `RBE2_<eid>`: an interface node at `GN` tied to the `GMi` (which must have `CM` ⊇ 123) |
//! | `RBE3` | an interpolation spider `RBE3_<eid>` at `REFGRID` on all the independent grids (components ⊇ 123); flexmbs' own area weights replace `WTi` (noted) |
//! | `SPC1`, `SPC` (zero values) | supports `SPC1_<sid>` / `SPC_<sid>`, one node set per SID |
//! | `PARAM,WTMASS` | scales every density |
//! | `INCLUDE 'file'` | the included file, in place |
//! | other elements, masses and constraints (`CBAR`, `CQUAD4`, `CONM2`, `CELAS1`, `MPC`, `RBAR`, ...) | refused: the model would lose stiffness or mass |
//! | anything else (`EIGRL`, `FORCE`, `SPCADD`, other `PARAM`s, ...) | skipped, listed once in [`ImportedModel::ignored`] |
//!
//! # Node orderings
//!
//! Corners are ordered as gmsh's; `CTETRA`'s mid-edge nodes 9 and 10 swap, and `CHEXA`'s
//! ring the bottom face, then the vertical edges, then the top face ([`ours_from_nastran`]).

use super::import::{
    excerpt, malformed, material, node_order, read_text, unsupported, Entity, IgnoredList, ImportError, ImportedModel,
    ImportedSpider, ImportedSupport, Includes, MeshBuilder, SolidSection,
};
use crate::interface::SpiderKind;
use crate::mesh::{CellId, CellKind, NodeId};
use crate::model::DofMask;
use crate::units::{deck_material_warning, Quantity, UnitSystem};
use nalgebra::{Matrix3, Point3, Vector3};
use std::cell::Cell;
use std::collections::BTreeMap;
use std::path::{Path, PathBuf};

/// Reads the Nastran bulk data file at `path`, written in `units` (`UnitSystem::Si` for SI),
/// and the files it includes; every quantity converted to SI.
pub fn read(path: &Path, units: UnitSystem) -> Result<ImportedModel, ImportError> {
    let text = read_text(path)?;
    parse(text, path, units)
}

/// Parses the text of a Nastran input file written in `units`, every quantity converted to
/// SI; `origin` names it in errors and is where `INCLUDE`d paths start from.
pub fn parse(text: impl AsRef<[u8]>, origin: &Path, units: UnitSystem) -> Result<ImportedModel, ImportError> {
    let mut files = Vec::new();
    let mut cards = Vec::new();
    let mut in_bulk = None;
    let mut includes = Includes::default();
    includes.start(origin, text.as_ref())?;
    let mut deck = Deck {
        files: &mut files,
        cards: &mut cards,
        in_bulk: &mut in_bulk,
        includes: &mut includes,
    };
    read_cards(text.as_ref(), origin, &mut deck)?;
    Reader::new(&files, &cards, units).run(&cards)
}

/// Our node `i` of a Nastran element is the Nastran grid `ours_from_nastran(kind)[i]`.
pub fn ours_from_nastran(kind: CellKind) -> &'static [usize] {
    const TET10: [usize; 10] = [0, 1, 2, 3, 4, 5, 6, 7, 9, 8];
    // CHEXA: 9-12 bottom ring (1-2, 2-3, 3-4, 4-1), 13-16 vertical edges, 17-20 top ring.
    const HEX20: [usize; 20] = [0, 1, 2, 3, 4, 5, 6, 7, 8, 11, 12, 9, 13, 10, 14, 15, 16, 19, 17, 18];
    node_order(kind, &TET10, &HEX20)
}

/// Our node `i` of the mirrored element is node `mirrored(kind)[i]` of the element: the same
/// cell with the opposite handedness (Nastran accepts both, our elements need a positive
/// volume).
fn mirrored(kind: CellKind) -> &'static [usize] {
    const TET4: [usize; 4] = [0, 2, 1, 3];
    const TET10: [usize; 10] = [0, 2, 1, 3, 6, 5, 4, 7, 9, 8];
    const HEX8: [usize; 8] = [0, 3, 2, 1, 4, 7, 6, 5];
    const HEX20: [usize; 20] = [0, 3, 2, 1, 4, 7, 6, 5, 9, 8, 10, 13, 15, 11, 14, 12, 17, 16, 19, 18];
    const WEDGE6: [usize; 6] = [0, 2, 1, 3, 5, 4];
    match kind {
        CellKind::Tet4 => &TET4,
        CellKind::Tet10 => &TET10,
        CellKind::Hex8 => &HEX8,
        CellKind::Hex20 => &HEX20,
        _ => &WEDGE6,
    }
}

/// The signed volume measure of a cell's corners (ours ordering): positive for our handedness.
fn handedness(kind: CellKind, x: &[Point3<f64>]) -> f64 {
    let (a, b, c) = match kind {
        CellKind::Hex8 | CellKind::Hex20 => (1, 3, 4),
        _ => (1, 2, 3),
    };
    Matrix3::from_columns(&[x[a] - x[0], x[b] - x[0], x[c] - x[0]]).determinant()
}

/// Cards that carry stiffness, mass or constraints we do not read: refused, not skipped.
const REFUSED: &[&str] = &[
    "CBAR", "CBEAM", "CBEND", "CROD", "CONROD", "CTUBE", "CQUAD4", "CQUAD8", "CQUADR", "CTRIA3", "CTRIA6", "CTRIAR",
    "CSHEAR", "CQUAD", "CPYRAM", "CHEXA8", "CONM1", "CONM2", "CMASS1", "CMASS2", "CMASS3", "CMASS4", "CELAS1",
    "CELAS2", "CELAS3", "CELAS4", "CBUSH", "CBUSH1D", "CDAMP1", "CDAMP2", "CGAP", "CWELD", "CFAST", "MPC", "RBAR",
    "RBAR1", "RBE1", "RROD", "RSPLINE", "RTRPLT", "GENEL", "DMIG", "SPOINT", "EPOINT", "MAT2", "MAT8", "MAT9", "PCOMP",
    "PCOMPG",
];

/// The width of a card's data fields: 8 columns, or 16 for a name ending in `*`.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
enum FieldWidth {
    Small,
    Large,
}

/// One card: its name (upper case, without `*`), its data fields (field 2 on), their width,
/// where it starts.
struct Card {
    name: String,
    fields: Vec<String>,
    width: FieldWidth,
    file: usize,
    line: usize,
}

/// Expands tabs to 8-column stops.
fn expand_tabs(line: &str) -> String {
    let mut out = String::with_capacity(line.len());
    for ch in line.chars() {
        if ch == '\t' {
            let pad = 8 - out.chars().count() % 8;
            out.extend(std::iter::repeat_n(' ', pad));
        } else {
            out.push(ch);
        }
    }
    out
}

/// Columns `from..to` of a line (by characters), blank past its end.
fn columns(line: &str, from: usize, to: usize) -> String {
    line.chars().skip(from).take(to - from).collect()
}

/// What [`read_cards`] fills, through every included file.
struct Deck<'a> {
    files: &'a mut Vec<PathBuf>,
    cards: &'a mut Vec<Card>,
    /// `None` until it is known whether the main file has `BEGIN BULK`.
    in_bulk: &'a mut Option<bool>,
    includes: &'a mut Includes,
}

/// Splits the bulk data of `data` (from `path`) into cards, reading `INCLUDE`d files in
/// place.
fn read_cards(data: &[u8], path: &Path, deck: &mut Deck) -> Result<(), ImportError> {
    let file = deck.files.len();
    deck.files.push(path.to_path_buf());
    let text = String::from_utf8_lossy(data);
    if deck.in_bulk.is_none() {
        // Without BEGIN BULK the whole file is bulk data.
        let has_begin = text
            .lines()
            .any(|l| l.trim().to_uppercase().starts_with("BEGIN") && l.to_uppercase().contains("BULK"));
        *deck.in_bulk = Some(!has_begin);
    }
    for (k, raw) in text.lines().enumerate() {
        let line = k + 1;
        let raw = expand_tabs(raw);
        let trimmed = raw.trim();
        let upper = trimmed.to_uppercase();
        if *deck.in_bulk != Some(true) {
            if upper.starts_with("BEGIN") && upper.contains("BULK") {
                *deck.in_bulk = Some(true);
            }
            continue;
        }
        if trimmed.is_empty() || trimmed.starts_with('$') {
            continue;
        }
        if upper.starts_with("ENDDATA") {
            break;
        }
        if upper.starts_with("INCLUDE") {
            let name = trimmed[7..].trim().trim_matches(|c| c == '\'' || c == '"').trim();
            if name.is_empty() {
                return Err(malformed(path, line, "INCLUDE", "a quoted file name", trimmed));
            }
            let (target, data) = deck.includes.open(path, line, "INCLUDE", name)?;
            read_cards(&data, &target, deck)?;
            deck.includes.close();
            continue;
        }
        let free = raw.contains(',');
        let head = if free {
            raw.split(',').next().unwrap_or_default().trim().to_string()
        } else {
            columns(&raw, 0, 8).trim().to_string()
        };
        let continuation = head.is_empty() || head.starts_with('+') || head.starts_with('*');
        if continuation {
            // A continuation line has the field width of its card, whatever its marker
            // (`*`, `+`, blank): pre-processors continue `GRID*` with `*G1` or `+G1` lines.
            let Some(card) = deck.cards.last_mut() else {
                return Err(ImportError::Malformed {
                    path: path.to_path_buf(),
                    line,
                    entity: "continuation line".into(),
                    expected: "a card before its continuation".into(),
                    found: excerpt(trimmed),
                });
            };
            let fields = data_fields(&raw, free, card.width, path, line, &card.name)?;
            card.fields.extend(fields);
            continue;
        }
        let width = if head.ends_with('*') {
            FieldWidth::Large
        } else {
            FieldWidth::Small
        };
        let name = head.trim_end_matches('*').to_uppercase();
        let fields = data_fields(&raw, free, width, path, line, &name)?;
        deck.cards.push(Card {
            name,
            fields,
            width,
            file,
            line,
        });
    }
    Ok(())
}

/// The data fields of one line (`line` of `path`) of card `name`: comma separated if
/// `free`, else in columns; four per line in large field, eight in small field.
fn data_fields(
    raw: &str,
    free: bool,
    width: FieldWidth,
    path: &Path,
    line: usize,
    name: &str,
) -> Result<Vec<String>, ImportError> {
    let per_line = match width {
        FieldWidth::Large => 4,
        FieldWidth::Small => 8,
    };
    if !free {
        let w = 64 / per_line;
        return Ok((0..per_line)
            .map(|i| columns(raw, 8 + w * i, 8 + w * (i + 1)).trim().to_string())
            .collect());
    }
    let mut data: Vec<String> = raw.split(',').skip(1).map(|f| f.trim().to_string()).collect();
    if data.len() > per_line + 1 {
        return Err(ImportError::Malformed {
            path: path.to_path_buf(),
            line,
            entity: format!("free-field line of {name}"),
            expected: format!("at most {per_line} data fields and a continuation marker"),
            found: format!("{} fields", data.len()),
        });
    }
    data.truncate(per_line);
    data.resize(per_line, String::new());
    Ok(data)
}

/// A Nastran real: `1.5`, `1.5E-3`, `1.5D-3`, `1.5-3`, `-2.+5`.
fn parse_real(field: &str) -> Option<f64> {
    let s = field.trim().to_uppercase().replace('D', "E");
    if let Ok(v) = s.parse::<f64>() {
        return v.is_finite().then_some(v);
    }
    // Exponent shorthand: a sign after the first character, without an E.
    if s.contains('E') {
        return None;
    }
    let at = s.char_indices().skip(1).find(|&(_, c)| c == '+' || c == '-')?.0;
    let v = format!("{}E{}", &s[..at], &s[at..]).parse::<f64>().ok()?;
    v.is_finite().then_some(v)
}

/// A raw GRID before coordinate systems are resolved.
struct Grid {
    id: u64,
    cp: u64,
    x: [f64; 3],
    cd: u64,
    file: usize,
    line: usize,
}

/// A CORD2R: reference system, points A (origin), B (on z), C (in the x-z plane).
struct Cord2r {
    rid: u64,
    abc: [[f64; 3]; 3],
    file: usize,
    line: usize,
}

/// A resolved rectangular system: basic = origin + axes * local.
#[derive(Clone, Copy)]
struct Frame {
    origin: Vector3<f64>,
    axes: Matrix3<f64>,
}

/// A MAT1 as given: E, G, NU (any may be blank), RHO, file, line.
type Mat1 = (Option<f64>, Option<f64>, Option<f64>, f64, usize, usize);

/// An SPC1 or SPC: card name, SID, grids, components, file, line.
type Spc = (&'static str, u64, Vec<u64>, DofMask, usize, usize);

struct Reader<'a> {
    files: &'a [PathBuf],
    /// The deck's units: lengths, moduli and densities are converted to SI in
    /// [`Reader::finish`] and [`Reader::frame`].
    units: UnitSystem,
    grids: Vec<Grid>,
    cord2r: BTreeMap<u64, Cord2r>,
    /// Other coordinate systems: id -> card name.
    other_systems: BTreeMap<u64, (String, usize, usize)>,
    /// (eid, pid, kind, grids, file, line).
    elements: Vec<(u64, u64, CellKind, Vec<u64>, usize, usize)>,
    /// pid -> (mid, file, line).
    psolid: BTreeMap<u64, (u64, usize, usize)>,
    /// mid -> (E, G, NU, RHO as given, file, line).
    mat1: BTreeMap<u64, Mat1>,
    wtmass: f64,
    /// (eid, kind, reference grid, surface grids, file, line).
    spiders: Vec<(u64, SpiderKind, u64, Vec<u64>, usize, usize)>,
    supports: Vec<Spc>,
    notes: Vec<String>,
    ignored: IgnoredList,
    /// The number of GRID cards of the deck, which bounds the `THRU` ranges.
    grid_count: usize,
    /// The grids that `THRU` ranges have named so far.
    thru_used: Cell<usize>,
}

/// All `THRU` ranges of a deck together may name at most this many times its grids (a
/// support and a spider or two over every grid; a set of billions is a mistake).
const THRU_PER_GRID: usize = 32;

impl<'a> Reader<'a> {
    fn new(files: &'a [PathBuf], cards: &[Card], units: UnitSystem) -> Self {
        Reader {
            units,
            grid_count: cards.iter().filter(|c| c.name == "GRID").count(),
            thru_used: Cell::new(0),
            files,
            grids: Vec::new(),
            cord2r: BTreeMap::new(),
            other_systems: BTreeMap::new(),
            elements: Vec::new(),
            psolid: BTreeMap::new(),
            mat1: BTreeMap::new(),
            wtmass: 1.0,
            spiders: Vec::new(),
            supports: Vec::new(),
            notes: Vec::new(),
            ignored: IgnoredList::default(),
        }
    }

    fn path(&self, card: &Card) -> PathBuf {
        self.files[card.file].clone()
    }

    fn malformed(&self, card: &Card, entity: &str, expected: &str, found: &str) -> ImportError {
        malformed(&self.files[card.file], card.line, entity, expected, found)
    }

    fn unsupported(&self, card: &Card, entity: &str, what: String) -> ImportError {
        unsupported(&self.files[card.file], card.line, entity, what)
    }

    fn limit(&self, card: &Card, entity: &str, what: String) -> ImportError {
        ImportError::Limit {
            path: self.files[card.file].clone(),
            line: card.line,
            entity: entity.to_string(),
            what,
            chain: String::new(),
        }
    }

    /// Field `k` (0 = field 2 of the card), blank past the end.
    fn field(card: &Card, k: usize) -> &str {
        card.fields.get(k).map(String::as_str).unwrap_or("")
    }

    /// A positive integer id in field `k`.
    fn id(&self, card: &Card, k: usize, entity: &str, what: &str) -> Result<u64, ImportError> {
        let f = Self::field(card, k);
        match f.parse::<u64>() {
            Ok(v) if v > 0 => Ok(v),
            _ => Err(self.malformed(
                card,
                entity,
                &format!("{what} (a positive integer) in field {}", k + 2),
                f,
            )),
        }
    }

    /// A non-negative integer in field `k`, `default` if blank.
    fn int_or(&self, card: &Card, k: usize, default: u64, entity: &str, what: &str) -> Result<u64, ImportError> {
        let f = Self::field(card, k);
        if f.is_empty() {
            return Ok(default);
        }
        f.parse::<u64>()
            .map_err(|_| self.malformed(card, entity, &format!("{what} (an integer) in field {}", k + 2), f))
    }

    /// A real in field `k`, `None` if blank.
    fn real_opt(&self, card: &Card, k: usize, entity: &str, what: &str) -> Result<Option<f64>, ImportError> {
        let f = Self::field(card, k);
        if f.is_empty() {
            return Ok(None);
        }
        parse_real(f)
            .map(Some)
            .ok_or_else(|| self.malformed(card, entity, &format!("{what} (a real number) in field {}", k + 2), f))
    }

    fn real_or(&self, card: &Card, k: usize, default: f64, entity: &str, what: &str) -> Result<f64, ImportError> {
        Ok(self.real_opt(card, k, entity, what)?.unwrap_or(default))
    }

    /// Component digits such as `123456` as a mask.
    fn components(&self, card: &Card, k: usize, entity: &str) -> Result<DofMask, ImportError> {
        let f = Self::field(card, k);
        let mut m = [false; 6];
        if f.is_empty() || f == "0" {
            return Err(self.malformed(card, entity, &format!("component digits 1-6 in field {}", k + 2), f));
        }
        for c in f.chars() {
            match c.to_digit(10) {
                Some(d @ 1..=6) => m[d as usize - 1] = true,
                _ => return Err(self.malformed(card, entity, &format!("component digits 1-6 in field {}", k + 2), f)),
            }
        }
        Ok(DofMask(m))
    }

    /// Grid ids from field `from` on, with `G1 THRU G2` ranges. A range may name at most as
    /// many grids as the deck defines (every grid it names must exist), and all ranges of
    /// the deck together at most [`THRU_PER_GRID`] times that: the list is as long as the
    /// deck, never as long as a range claims.
    fn grid_list(&self, card: &Card, from: usize, entity: &str) -> Result<Vec<u64>, ImportError> {
        let mut out = Vec::new();
        let mut k = from;
        while k < card.fields.len() {
            let f = Self::field(card, k);
            if f.is_empty() {
                k += 1;
                continue;
            }
            if f.eq_ignore_ascii_case("THRU") {
                let (Some(&first), Ok(last)) = (out.last(), Self::field(card, k + 1).parse::<u64>()) else {
                    return Err(self.malformed(card, entity, "'G1 THRU G2' with grid ids", f));
                };
                if last < first {
                    return Err(self.malformed(card, entity, "'G1 THRU G2' with G1 <= G2", Self::field(card, k + 1)));
                }
                let count = last - first + 1;
                if count > self.grid_count as u64 {
                    return Err(self.limit(
                        card,
                        entity,
                        format!(
                            "'{first} THRU {last}' names {count} grids, more than the {} GRIDs the deck defines",
                            self.grid_count
                        ),
                    ));
                }
                let used = self.thru_used.get() + count as usize;
                if used > THRU_PER_GRID * self.grid_count {
                    return Err(self.limit(
                        card,
                        entity,
                        format!(
                            "'{first} THRU {last}': the THRU ranges of the deck name more than {THRU_PER_GRID} times its {} GRIDs",
                            self.grid_count
                        ),
                    ));
                }
                self.thru_used.set(used);
                out.extend(first + 1..=last);
                k += 2;
                continue;
            }
            match f.parse::<u64>() {
                Ok(id) if id > 0 => out.push(id),
                _ => {
                    return Err(self.malformed(card, entity, &format!("a grid id in field {}", k % 8 + 2), f));
                }
            }
            k += 1;
        }
        Ok(out)
    }

    fn run(mut self, cards: &[Card]) -> Result<ImportedModel, ImportError> {
        for card in cards {
            let name = card.name.as_str();
            match name {
                "GRID" => {
                    let id = self.id(card, 0, "GRID", "grid id")?;
                    let entity = format!("GRID {id}");
                    let cp = self.int_or(card, 1, 0, &entity, "CP")?;
                    let mut x = [0.0; 3];
                    for (c, xc) in x.iter_mut().enumerate() {
                        *xc = self.real_or(card, 2 + c, 0.0, &entity, ["X1", "X2", "X3"][c])?;
                    }
                    let cd = self.int_or(card, 5, 0, &entity, "CD")?;
                    self.grids.push(Grid {
                        id,
                        cp,
                        x,
                        cd,
                        file: card.file,
                        line: card.line,
                    });
                }
                "CORD2R" => {
                    let id = self.id(card, 0, "CORD2R", "CID")?;
                    let entity = format!("CORD2R {id}");
                    let rid = self.int_or(card, 1, 0, &entity, "RID")?;
                    let mut abc = [[0.0; 3]; 3];
                    for (p, point) in abc.iter_mut().enumerate() {
                        for (c, v) in point.iter_mut().enumerate() {
                            *v = self.real_or(card, 2 + 3 * p + c, 0.0, &entity, "a coordinate")?;
                        }
                    }
                    if let Some(first) = self.cord2r.get(&id) {
                        return Err(ImportError::Duplicate {
                            path: self.path(card),
                            line: card.line,
                            kind: Entity::CoordinateSystem,
                            id: id.to_string(),
                            first_line: first.line,
                        });
                    }
                    self.cord2r.insert(
                        id,
                        Cord2r {
                            rid,
                            abc,
                            file: card.file,
                            line: card.line,
                        },
                    );
                }
                "CORD1R" | "CORD1C" | "CORD1S" | "CORD2C" | "CORD2S" | "CORD3G" => {
                    if let Ok(id) = self.id(card, 0, name, "CID") {
                        self.other_systems.insert(id, (name.to_string(), card.file, card.line));
                    }
                    self.ignored.add(name, &self.files[card.file], card.line);
                }
                "CTETRA" | "CHEXA" | "CPENTA" => self.solid(card)?,
                "PSOLID" => {
                    let pid = self.id(card, 0, "PSOLID", "PID")?;
                    let mid = self.id(card, 1, &format!("PSOLID {pid}"), "MID")?;
                    if let Some(&(_, _, first_line)) = self.psolid.get(&pid) {
                        return Err(ImportError::Duplicate {
                            path: self.path(card),
                            line: card.line,
                            kind: Entity::Property,
                            id: pid.to_string(),
                            first_line,
                        });
                    }
                    self.psolid.insert(pid, (mid, card.file, card.line));
                }
                "MAT1" => {
                    let mid = self.id(card, 0, "MAT1", "MID")?;
                    let entity = format!("MAT1 {mid}");
                    let E = self.real_opt(card, 1, &entity, "E")?;
                    let G = self.real_opt(card, 2, &entity, "G")?;
                    let nu = self.real_opt(card, 3, &entity, "NU")?;
                    let rho = self.real_or(card, 4, 0.0, &entity, "RHO")?;
                    if let Some(&(.., first_line)) = self.mat1.get(&mid) {
                        return Err(ImportError::Duplicate {
                            path: self.path(card),
                            line: card.line,
                            kind: Entity::Material,
                            id: mid.to_string(),
                            first_line,
                        });
                    }
                    self.mat1.insert(mid, (E, G, nu, rho, card.file, card.line));
                }
                "PARAM" => {
                    let param = Self::field(card, 0).to_uppercase();
                    if param == "WTMASS" {
                        self.wtmass = self
                            .real_opt(card, 1, "PARAM,WTMASS", "the mass factor")?
                            .filter(|w| *w > 0.0)
                            .ok_or_else(|| self.malformed(card, "PARAM,WTMASS", "a positive factor", Self::field(card, 1)))?;
                    } else {
                        self.ignored.add(&format!("PARAM,{param}"), &self.files[card.file], card.line);
                    }
                }
                "RBE2" => {
                    let eid = self.id(card, 0, "RBE2", "EID")?;
                    let entity = format!("RBE2 {eid}");
                    let gn = self.id(card, 1, &entity, "GN")?;
                    let cm = self.components(card, 2, &entity)?;
                    if !(cm.0[0] && cm.0[1] && cm.0[2]) {
                        return Err(self.unsupported(
                            card,
                            &entity,
                            "CM must hold the translations 123: a spider on solid nodes ties all three".into(),
                        ));
                    }
                    // A trailing real is ALPHA (thermal expansion), not a grid.
                    let mut fields = card.fields.clone();
                    while fields.last().is_some_and(|f| f.is_empty() || f.contains('.')) {
                        fields.pop();
                    }
                    let trimmed = Card {
                        name: card.name.clone(),
                        fields,
                        width: card.width,
                        file: card.file,
                        line: card.line,
                    };
                    let grids = self.grid_list(&trimmed, 3, &entity)?;
                    self.spiders.push((eid, SpiderKind::Rbe2, gn, grids, card.file, card.line));
                }
                "RBE3" => self.rbe3(card)?,
                "SPC1" => {
                    let sid = self.id(card, 0, "SPC1", "SID")?;
                    let entity = format!("SPC1 {sid}");
                    let dofs = self.components(card, 1, &entity)?;
                    let grids = self.grid_list(card, 2, &entity)?;
                    self.supports.push(("SPC1", sid, grids, dofs, card.file, card.line));
                }
                "SPC" => {
                    let sid = self.id(card, 0, "SPC", "SID")?;
                    let entity = format!("SPC {sid}");
                    for pair in 0..2 {
                        let at = 1 + 3 * pair;
                        if Self::field(card, at).is_empty() {
                            continue;
                        }
                        let grid = self.id(card, at, &entity, "grid id")?;
                        let dofs = self.components(card, at + 1, &entity)?;
                        if self.real_or(card, at + 2, 0.0, &entity, "D")? != 0.0 {
                            return Err(self.unsupported(card, &entity, "a non-zero enforced displacement is not a support".into()));
                        }
                        self.supports.push(("SPC", sid, vec![grid], dofs, card.file, card.line));
                    }
                }
                other if REFUSED.contains(&other) => {
                    return Err(self.unsupported(
                        card,
                        other,
                        format!("{other} is not read, and skipping it would change the model's stiffness, mass or constraints (read: GRID, CORD2R, CTETRA, CHEXA, CPENTA, PSOLID, MAT1, RBE2, RBE3, SPC1, SPC)"),
                    ))
                }
                other => self.ignored.add(other, &self.files[card.file], card.line),
            }
        }
        self.finish()
    }

    fn solid(&mut self, card: &Card) -> Result<(), ImportError> {
        let name = card.name.as_str();
        let eid = self.id(card, 0, name, "EID")?;
        let entity = format!("{name} {eid}");
        let pid = self.id(card, 1, &entity, "PID")?;
        let mut grids = Vec::new();
        let mut last_nonblank = 0;
        for k in 2..card.fields.len() {
            let f = Self::field(card, k);
            if f.is_empty() {
                grids.push(None);
            } else {
                grids.push(Some(self.id(card, k, &entity, "a grid id")?));
                last_nonblank = grids.len();
            }
        }
        grids.truncate(last_nonblank);
        let count = grids.len();
        let kind = match (name, count) {
            ("CTETRA", 4) => CellKind::Tet4,
            ("CTETRA", 10) => CellKind::Tet10,
            ("CHEXA", 8) => CellKind::Hex8,
            ("CHEXA", 20) => CellKind::Hex20,
            ("CPENTA", 6) => CellKind::Wedge6,
            ("CPENTA", 15) => {
                return Err(self.unsupported(card, &entity, "the 15-node CPENTA is not read (6 nodes are)".into()))
            }
            _ => {
                return Err(self.malformed(
                    card,
                    &entity,
                    match name {
                        "CTETRA" => "4 or 10 grids",
                        "CHEXA" => "8 or 20 grids",
                        _ => "6 grids",
                    },
                    &format!("{count} grid fields"),
                ))
            }
        };
        let Some(grids) = grids.into_iter().collect::<Option<Vec<u64>>>() else {
            return Err(self.malformed(
                card,
                &entity,
                "no blank grid field among the used ones",
                "a blank field",
            ));
        };
        self.elements.push((eid, pid, kind, grids, card.file, card.line));
        Ok(())
    }

    fn rbe3(&mut self, card: &Card) -> Result<(), ImportError> {
        let eid = self.id(card, 0, "RBE3", "EID")?;
        let entity = format!("RBE3 {eid}");
        let refgrid = self.id(card, 2, &entity, "REFGRID")?;
        let refc = self.components(card, 3, &entity)?;
        if !(refc.0[0] && refc.0[1] && refc.0[2]) {
            return Err(self.unsupported(card, &entity, "REFC must hold the translations 123".into()));
        }
        let mut grids = Vec::new();
        let mut weights = Vec::new();
        let mut k = 4;
        while k < card.fields.len() {
            let f = Self::field(card, k).to_uppercase();
            if f.is_empty() {
                k += 1;
                continue;
            }
            if f == "UM" || f == "ALPHA" || f == "STRESS" {
                self.notes.push(format!(
                    "RBE3 {eid}: {f} is not used (flexmbs chooses the dependent dofs itself; the constraint is the same)"
                ));
                break;
            }
            let w = parse_real(&f).filter(|_| f.contains('.') || f.contains('E'));
            let Some(w) = w else {
                return Err(self.malformed(
                    card,
                    &entity,
                    &format!("a weight WTi (a real) in field {}", k % 8 + 2),
                    &f,
                ));
            };
            weights.push(w);
            let c = self.components(card, k + 1, &entity)?;
            if !(c.0[0] && c.0[1] && c.0[2]) {
                return Err(self.unsupported(card, &entity, "each component Ci must hold the translations 123".into()));
            }
            k += 2;
            while k < card.fields.len() {
                let g = Self::field(card, k);
                if g.is_empty() {
                    k += 1;
                    continue;
                }
                match g.parse::<u64>() {
                    Ok(id) if id > 0 => grids.push(id),
                    _ => break,
                }
                k += 1;
            }
        }
        if grids.is_empty() {
            return Err(self.malformed(card, &entity, "independent grids after WT1 C1", "none"));
        }
        self.notes.push(format!(
            "RBE3 {eid}: the weights {weights:?} are not used; flexmbs weights the surface nodes by tributary area"
        ));
        self.spiders
            .push((eid, SpiderKind::Rbe3, refgrid, grids, card.file, card.line));
        Ok(())
    }

    /// The frame of coordinate system `cid` (0: basic), resolving reference systems.
    fn frame(&self, cid: u64, path: &Path, line: usize, entity: &str) -> Result<Frame, ImportError> {
        let mut chain = Vec::new();
        let mut id = cid;
        while id != 0 {
            let Some(c) = self.cord2r.get(&id) else {
                let hint = match self.other_systems.get(&id) {
                    Some((card, ..)) => format!(" as a CORD2R (it is a {card}; only CORD2R is read)"),
                    None => String::new(),
                };
                return Err(ImportError::Undefined {
                    path: path.to_path_buf(),
                    line,
                    entity: entity.to_string(),
                    kind: Entity::CoordinateSystem,
                    id: id.to_string(),
                    hint,
                });
            };
            if chain.contains(&id) || chain.len() > 64 {
                return Err(ImportError::Unsupported {
                    path: self.files[c.file].clone(),
                    line: c.line,
                    entity: format!("CORD2R {id}"),
                    what: "its reference systems (RID) form a cycle".into(),
                });
            }
            chain.push(id);
            id = c.rid;
        }
        // From the innermost reference outwards: points given in system RID.
        let mut frame = Frame {
            origin: Vector3::zeros(),
            axes: Matrix3::identity(),
        };
        for &id in chain.iter().rev() {
            let c = &self.cord2r[&id];
            let to_basic =
                |p: [f64; 3]| frame.origin + frame.axes * Vector3::from(p) * self.units.to_si(Quantity::Length);
            let (a, b, cc) = (to_basic(c.abc[0]), to_basic(c.abc[1]), to_basic(c.abc[2]));
            let z = b - a;
            let y = z.cross(&(cc - a));
            let bad = || ImportError::Malformed {
                path: self.files[c.file].clone(),
                line: c.line,
                entity: format!("CORD2R {id}"),
                expected: "points A, B, C not on one line".into(),
                found: format!("A {:?}, B {:?}, C {:?}", c.abc[0], c.abc[1], c.abc[2]),
            };
            let scale = z.norm().max((cc - a).norm());
            if !(z.norm() > 0.0) || !(y.norm() > 1e-12 * scale * scale) {
                return Err(bad());
            }
            let z = z.normalize();
            let y = y.normalize();
            let x = y.cross(&z);
            frame = Frame {
                origin: a,
                axes: Matrix3::from_columns(&[x, y, z]),
            };
        }
        Ok(frame)
    }

    fn finish(self) -> Result<ImportedModel, ImportError> {
        let mut builder = MeshBuilder::default();
        let mut cd_of = BTreeMap::new();
        for g in &self.grids {
            let path = &self.files[g.file];
            let entity = format!("GRID {}", g.id);
            let x = Vector3::from(g.x) * self.units.to_si(Quantity::Length);
            let x = if g.cp == 0 {
                Point3::from(x)
            } else {
                let f = self.frame(g.cp, path, g.line, &entity)?;
                Point3::from(f.origin + f.axes * x)
            };
            builder.add_node(g.id, x, path, g.line)?;
            if g.cd != 0 {
                cd_of.insert(g.id, g.cd);
            }
        }
        let mut imported = ImportedModel::default();
        // Materials.
        let mut material_names = BTreeMap::new();
        let stress = self.units.to_si(Quantity::Stress);
        for (&mid, &(E, G, nu, rho, file, line)) in &self.mat1 {
            // E and G stay in the deck's units until the checks below have passed, so that
            // their messages quote the numbers the user wrote.
            let rho = rho * self.wtmass * self.units.to_si(Quantity::Density);
            let path = &self.files[file];
            let entity = format!("MAT1 {mid}");
            let name = format!("MAT1_{mid}");
            let bad = |expected: &str, found: String| ImportError::Malformed {
                path: path.clone(),
                line,
                entity: entity.clone(),
                expected: expected.to_string(),
                found,
            };
            let (E, nu) = match (E, G, nu) {
                (Some(E), _, Some(nu)) => {
                    if let Some(G) = G {
                        let G_iso = E / (2.0 * (1.0 + nu));
                        // Three constants given: they must describe one isotropic material
                        // (to the 4-5 digits a small field holds).
                        if ((G - G_iso) / G_iso).abs() > 1e-3 {
                            return Err(bad(
                                &format!("G = E / (2 (1 + NU)) = {G_iso:e} (an isotropic material)"),
                                format!("G = {G:e}"),
                            ));
                        }
                    }
                    (E, nu)
                }
                (Some(E), Some(G), None) => (E, E / (2.0 * G) - 1.0),
                (None, Some(G), Some(nu)) => (2.0 * G * (1.0 + nu), nu),
                _ => return Err(bad("two of E, G, NU", "fewer".into())),
            };
            let E = E * stress;
            imported
                .materials
                .push(material(&name, E, nu, rho, path, line, &entity)?);
            let place = format!("{}:{line}", path.display());
            imported
                .notes
                .extend(deck_material_warning(&name, &place, E, rho, self.units));
            material_names.insert(mid, name);
        }
        // Cells, grouped per property.
        let mut mirrored_count = 0usize;
        let mut sets: BTreeMap<u64, Vec<CellId>> = BTreeMap::new();
        for (eid, pid, kind, grids, file, line) in &self.elements {
            let path = &self.files[*file];
            let entity = format!("element {eid}");
            let Some(&(mid, pfile, pline)) = self.psolid.get(pid) else {
                return Err(ImportError::Undefined {
                    path: path.clone(),
                    line: *line,
                    entity,
                    kind: Entity::Psolid,
                    id: pid.to_string(),
                    hint: String::new(),
                });
            };
            if !material_names.contains_key(&mid) {
                return Err(ImportError::Undefined {
                    path: self.files[pfile].clone(),
                    line: pline,
                    entity: format!("PSOLID {pid}"),
                    kind: Entity::Mat1,
                    id: mid.to_string(),
                    hint: String::new(),
                });
            }
            let nodes = grids
                .iter()
                .map(|&g| builder.node(g, path, *line, &entity))
                .collect::<Result<Vec<_>, _>>()?;
            let index = builder.add_cell(*eid, *kind, &nodes, ours_from_nastran(*kind), path, *line)?;
            let cell = &mut builder.mesh.cells[index];
            let x: Vec<Point3<f64>> = cell.nodes.iter().map(|n| builder.mesh.nodes[n.index()]).collect();
            if handedness(*kind, &x) < 0.0 {
                cell.nodes = mirrored(*kind).iter().map(|&i| cell.nodes[i]).collect();
                mirrored_count += 1;
            }
            sets.entry(*pid).or_default().push(CellId(index as u32));
        }
        if mirrored_count > 0 {
            imported.notes.push(format!(
                "{mirrored_count} solid element(s) had the other handedness and were renumbered (same cells)"
            ));
        }
        for (pid, cells) in sets {
            let name = format!("PSOLID_{pid}");
            let mut nodes: Vec<NodeId> = cells
                .iter()
                .flat_map(|c| builder.mesh.cells[c.index()].nodes.clone())
                .collect();
            nodes.sort_unstable();
            nodes.dedup();
            builder.mesh.add_to_node_set(&name, nodes);
            builder.mesh.cell_sets.insert(name.clone(), cells);
            imported.solid_sections.push(SolidSection {
                cell_set: name,
                material: material_names[&self.psolid[&pid].0].clone(),
            });
        }
        // Spiders and supports, with node sets of the same names.
        let cd_check = |g: u64, path: &Path, line: usize, entity: &str| {
            match cd_of.get(&g) {
            Some(cd) => Err(ImportError::Unsupported {
                path: path.to_path_buf(),
                line,
                entity: entity.to_string(),
                what: format!("GRID {g} has its dofs in coordinate system CD = {cd}; supports and spiders on such grids are not read (use CD = 0)"),
            }),
            None => Ok(()),
        }
        };
        for (eid, kind, reference, grids, file, line) in &self.spiders {
            let path = &self.files[*file];
            let prefix = if *kind == SpiderKind::Rbe2 { "RBE2" } else { "RBE3" };
            let entity = format!("{prefix} {eid}");
            let name = format!("{prefix}_{eid}");
            let reference_id = builder.node(*reference, path, *line, &entity)?;
            let mut surface = Vec::with_capacity(grids.len());
            for &g in grids {
                cd_check(g, path, *line, &entity)?;
                surface.push(builder.node(g, path, *line, &entity)?);
            }
            builder.mesh.add_to_node_set(&name, surface.clone());
            imported.spiders.push(ImportedSpider {
                name,
                kind: *kind,
                reference: reference_id,
                position: builder.mesh.nodes[reference_id.index()],
                surface,
            });
        }
        for (card, sid, grids, dofs, file, line) in &self.supports {
            let path = &self.files[*file];
            let entity = format!("{card} {sid}");
            let name = format!("{card}_{sid}");
            let mut nodes = Vec::with_capacity(grids.len());
            for &g in grids {
                if !(dofs.0[0] && dofs.0[1] && dofs.0[2]) {
                    cd_check(g, path, *line, &entity)?;
                }
                nodes.push(builder.node(g, path, *line, &entity)?);
            }
            builder.mesh.add_to_node_set(&name, nodes.clone());
            imported.supports.push(ImportedSupport {
                name,
                nodes,
                dofs: *dofs,
            });
        }
        imported.mesh = builder.mesh;
        imported.notes.extend(self.notes);
        imported.ignored = self.ignored.into_vec();
        Ok(imported)
    }
}
