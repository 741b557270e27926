//! The validator against wrong study files: the corpus `tests/broken/*.toml`, each file with
//! the messages its validation must give (`# expect:` lines: file:line:col, key, close
//! matches), one wrong value reported once, and random and mutated files (fixed seeds) that
//! must give a located message, never a panic. The program's side (exit code 2, the report on
//! stderr) is tested in crates/cli.

use std::path::{Path, PathBuf};
use study::input::source::Source;

/// Broken study files made on purpose: random text and mutations of good and broken studies.
#[path = "../property/generate.rs"]
mod generate;

/// The repository's root.
fn repo() -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).join("../..")
}

/// The report `flexmbs check` prints for the study file at `path` (`study::load`'s error),
/// `None` when the file is valid.
fn report(path: &Path) -> Option<String> {
    study::load(path).err().map(|e| study::error::report(&*e))
}

/// Checks one broken file's `# expect:` lines against its report. Every error must name the
/// file with a line and a column.
fn check_broken(path: &Path) {
    let text = std::fs::read_to_string(path).unwrap();
    let expected: Vec<&str> = text.lines().filter_map(|l| l.strip_prefix("# expect: ")).collect();
    let name = path.file_name().unwrap().to_string_lossy().to_string();
    assert!(!expected.is_empty(), "{name} has no `# expect:` line");
    let message = report(path).unwrap_or_else(|| panic!("{name} is valid"));
    assert!(message.starts_with("flexmbs: error: "), "{name}:\n{message}");
    for e in expected {
        assert!(message.contains(e), "{name}: expected\n  {e}\nin\n{message}");
    }
    // Every error line starts with file:line:col.
    let file = path.display().to_string();
    let errors: Vec<&str> = message.lines().filter(|l| l.starts_with(&file)).collect();
    assert!(!errors.is_empty(), "{name}: no located error in\n{message}");
    for l in errors {
        let rest = &l[file.len()..];
        let mut parts = rest.splitn(4, ':');
        assert_eq!(parts.next(), Some(""), "{l}");
        let line: Option<usize> = parts.next().and_then(|s| s.parse().ok());
        let col: Option<usize> = parts.next().and_then(|s| s.parse().ok());
        assert!(line.is_some() && col.is_some(), "{name}: no line:col in '{l}'");
    }
}

#[test]
fn broken_study_files_are_reported_with_location_key_and_close_matches() {
    let files = generate::corpus(&repo());
    assert!(files.len() >= 20, "the corpus has {} files", files.len());
    for f in files {
        check_broken(&f);
    }
}

/// A material with a wrong value is one error, where it is defined: the parts made of it,
/// the bodies placed from those parts and the joints and sensors on those bodies are not
/// reported again as "unknown material" or "unknown body".
#[test]
fn a_bad_material_is_one_error_not_a_cascade() {
    let text = std::fs::read_to_string(repo().join("examples/slider_crank.toml")).unwrap();
    assert!(text.contains("\nnu = 0.3\n"));
    let source = Source::from_text(Path::new("nu.toml"), text.replace("\nnu = 0.3\n", "\nnu = 0.6\n"));
    let message = study::parse_and_validate(source).unwrap_err().to_string();
    assert!(message.contains("is not valid (1 error)"), "{message}");
    assert!(
        message.contains("materials[0].nu: nu must lie in (-1, 0.5), got 0.6"),
        "{message}"
    );
    assert!(!message.contains("unknown"), "{message}");
}

/// Validates `text` in-process; panics (failing the test) only if the validator does.
fn check_in_process(study: &Path, text: &str, case: usize) {
    let result = std::panic::catch_unwind(std::panic::AssertUnwindSafe(|| {
        match study::parse_and_validate(Source::from_text(study, text.to_string())) {
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

/// Random and mutated study files (fixed seeds): no panic; every invalid one a message that
/// names the file. The study's relative paths (meshes) are taken from the examples.
#[test]
fn random_and_mutated_study_files_fail_cleanly() {
    let study = repo().join("examples/case.toml");
    for (case, text) in generate::cases(&repo(), 1500).iter().enumerate() {
        check_in_process(&study, text, case);
    }
}

/// The text of the example `name`, with `from` (which must occur once) replaced by `to`.
fn example_with(name: &str, from: &str, to: &str) -> String {
    let text = std::fs::read_to_string(repo().join("examples").join(name)).unwrap();
    assert_eq!(text.matches(from).count(), 1, "{name}: '{from}'");
    text.replace(from, to)
}

/// The message of validating `text` as the file `file`, which must be invalid.
fn errors_of(file: &str, text: String) -> String {
    study::parse_and_validate(Source::from_text(Path::new(file), text))
        .err()
        .unwrap_or_else(|| panic!("{file} is valid"))
        .to_string()
}

/// Checks that `message` has exactly one error, that it contains every fragment of
/// `expected`, and none of the words of a follow-on error.
fn one_error(message: &str, expected: &[&str]) {
    assert!(message.contains("is not valid (1 error)"), "{message}");
    for e in expected {
        assert!(message.contains(e), "expected '{e}' in\n{message}");
    }
    for follow_on in ["unknown", "is defined)", "defines none", "no actuator", "no driver"] {
        assert!(
            !message.contains(follow_on),
            "follow-on error '{follow_on}' in\n{message}"
        );
    }
}

/// A section with a wrong value is one error: the part built from it, the bodies placed from
/// that part, the joints and driver on those bodies, the sensor of that driver and the
/// analysis of the mechanism (whose every body is now invalid) are not reported again as
/// "unknown section", "unknown driver" or "the study defines none".
#[test]
fn a_bad_section_is_one_error_not_a_cascade() {
    let message = errors_of(
        "section.toml",
        example_with("spin_up.toml", "\nA = 4e-4\n", "\nA = -4e-4\n"),
    );
    one_error(&message, &["section.toml:", "sections[0].A"]);
    let message = errors_of("d.toml", example_with("slider_crank.toml", "d = 0.006", "d = -0.006"));
    one_error(&message, &["d.toml:", "sections[0].d"]);
}

/// An actuator with a wrong value is one error: the `actuator-effort` sensor that names it
/// is not reported as naming an unknown actuator.
#[test]
fn a_bad_actuator_is_one_error_not_a_cascade() {
    let text = std::fs::read_to_string(repo().join("examples/controlled_arm.toml")).unwrap();
    let text = format!(
        "{text}\n[[actuators]]\nname = \"drive\"\njoint = \"motor-axis\"\n\
         pid = {{ kp = 5.0, max_effort = -1.0, setpoint = {{ type = \"ramp\", t_end = 1.0, to = 0.5 }} }}\n\
         [[sensors]]\nname = \"torque\"\ntype = \"actuator-effort\"\nof = \"drive\"\n"
    );
    let message = errors_of("actuator.toml", text);
    one_error(&message, &["actuator.toml:", "actuators[0].pid.max_effort"]);
}

/// A reduction asking for more modes than the part's interior has dofs is refused by
/// `check`, at the key, not by `run` after the analyses before it.
#[test]
fn more_modes_than_interior_dofs_are_refused_at_check() {
    // The segment: four beam elements, interfaces at both ends: 3 interior nodes, 18 dofs.
    let message = errors_of(
        "modes.toml",
        example_with(
            "slider_crank.toml",
            "[parts.reduction]\nmodes = 2",
            "[parts.reduction]\nmodes = 18",
        ),
    );
    one_error(
        &message,
        &[
            "modes.toml:",
            "parts[0].reduction.modes",
            "18 fixed-interface modes",
            "has 18 dofs, so at most 17 modes",
        ],
    );
    // The largest count the interior gives is valid.
    let text = example_with(
        "slider_crank.toml",
        "[parts.reduction]\nmodes = 2",
        "[parts.reduction]\nmodes = 17",
    );
    study::parse_and_validate(Source::from_text(Path::new("modes.toml"), text)).unwrap();
}

/// Two entries of one name contradict each other: the second is refused, naming where the
/// first is, for materials, sections, parts, bodies (flexible and rigid share names), joints,
/// drivers, sensors and the joint forces.
#[test]
fn duplicated_names_are_refused_naming_both_places() {
    let base = std::fs::read_to_string(repo().join("examples/slider_crank.toml")).unwrap();
    let line_of = |needle: &str| base.lines().position(|l| l == needle).unwrap() + 1;
    let cases = [
        (
            "[[materials]]\nname = \"steel\"\nE = 70e9\nnu = 0.33\nrho = 2700.0\n",
            "materials[1].name: a material named 'steel' is already defined at materials[0].name",
            line_of("name = \"steel\""),
        ),
        (
            "[[sections]]\nname = \"rod\"\nshape = \"circle\"\nd = 0.008\n",
            "sections[1].name: a section named 'rod' is already defined at sections[0].name",
            line_of("name = \"rod\""),
        ),
        (
            "[[rigid_bodies]]\nname = \"r1\"\nmass = 1.0\ncenter_of_mass = [0.0, 0.0, 0.0]\ninertia = [[1.0, 0.0, 0.0], [0.0, 1.0, 0.0], [0.0, 0.0, 1.0]]\n",
            "rigid_bodies[2].name: a body named 'r1' is already defined at bodies[1].name",
            line_of("name = \"r1\""),
        ),
        (
            "[[joints]]\nname = \"weld1\"\ntype = \"fixed\"\nbetween = [\"r2.b\", \"r3.a\"]\n",
            "joints[6].name: a joint named 'weld1' is already defined at joints[0].name",
            line_of("name = \"weld1\""),
        ),
        (
            "[[drivers]]\nname = \"crank-angle\"\njoint = \"crank-pivot\"\nfunction = { type = \"constant-speed\", speed = 100.0 }\n",
            "drivers[1].joint: coordinate 0 of joint 'crank-pivot' is already driven by driver 'crank-speed' at drivers[0].joint",
            line_of("joint = \"crank-pivot\""),
        ),
    ];
    for (extra, expected, line) in cases {
        let message = errors_of("twice.toml", format!("{base}\n{extra}"));
        one_error(&message, &[expected, &format!("(line {line})")]);
    }
    // A key of a table that arrays of tables let a file give twice.
    let text = format!("{base}\n[[initial]]\nstart = \"consistent\"\n[[initial]]\nstart = \"at-rest\"\n");
    let line = text.lines().position(|l| l == "start = \"consistent\"").unwrap() + 1;
    let message = errors_of("twice.toml", text);
    one_error(
        &message,
        &[
            "initial[1].start: `start` is given twice in `[[initial]]`: first at initial[0].start",
            &format!("(line {line})"),
        ],
    );
}

/// Serde's Rust type names are the study file's words: a number, a whole number, an array.
#[test]
fn type_errors_speak_of_numbers_not_rust_types() {
    let message = errors_of(
        "type.toml",
        example_with("slider_crank.toml", "E = 200e9", "E = \"200e9\""),
    );
    assert!(message.contains("expected a number"), "{message}");
    assert!(!message.contains("f64"), "{message}");
    let message = errors_of(
        "type.toml",
        example_with("slider_crank.toml", "elements = 4", "elements = 4.5"),
    );
    assert!(message.contains("expected a whole number"), "{message}");
    assert!(!message.contains("usize"), "{message}");
}

/// The tet4 fixture deck `tet4.<ext>` (Abaqus `inp` or Nastran `bdf`) with its element cards
/// changed by `edit`, as the part 'bad' of a study in a folder of its own; the deck's file
/// name and the study's validation message.
fn deck_study(name: &str, ext: &str, edit: &dyn Fn(&str) -> String) -> (String, String) {
    let fixture = repo()
        .join("crates/fe-model/tests/data/import")
        .join(format!("tet4.{ext}"));
    let deck = std::fs::read_to_string(fixture).unwrap();
    let dir = Path::new(env!("CARGO_TARGET_TMPDIR")).join("broken_decks").join(name);
    std::fs::create_dir_all(&dir).unwrap();
    let file = format!("{name}.{ext}");
    std::fs::write(dir.join(&file), edit(&deck)).unwrap();
    let study = dir.join("study.toml");
    std::fs::write(
        &study,
        format!("[[parts]]\nname = \"bad\"\n[parts.mesh]\nfile = \"{file}\"\n"),
    )
    .unwrap();
    let message = study::load(&study).err().map(|e| e.to_string());
    (file, message.unwrap_or_else(|| panic!("{name}: valid")))
}

/// The deck with `card` (which must occur once) replaced by `by`.
fn replace_card(deck: &str, card: &str, by: &str) -> String {
    assert_eq!(deck.matches(card).count(), 1, "{card}");
    deck.replace(card, by)
}

/// An inverted element (its nodes in mirrored order) and a degenerate one (four coplanar
/// corners) are refused by `check`, by their element number in the deck, with the deck's
/// file and the part, not at `run` by their position in the model. (The Nastran reader
/// renumbers a mirrored solid, as Nastran accepts both handednesses; a flat one it refuses.)
#[test]
fn inverted_and_degenerate_elements_are_refused_by_their_deck_number() {
    let swap = |deck: &str| replace_card(deck, "\n7,11,9,13,10\n", "\n7,9,11,13,10\n");
    let (file, message) = deck_study("inverted", "inp", &swap);
    one_error(
        &message,
        &[
            &file,
            "parts[0].mesh.file",
            "part 'bad'",
            "element 7 (tet4) is inverted",
        ],
    );
    let flat = |deck: &str| replace_card(deck, "\n18,8,5,7,16\n", "\n18,1,2,3,4\n");
    let (file, message) = deck_study("degenerate", "inp", &flat);
    one_error(
        &message,
        &[
            &file,
            "parts[0].mesh.file",
            "part 'bad'",
            "element 18 (tet4) is degenerate",
        ],
    );
    let flat = |deck: &str| {
        let card = "CTETRA  18      1       8       5       7       16";
        replace_card(deck, card, "CTETRA  18      1       1       2       3       4")
    };
    let (file, message) = deck_study("degenerate_nastran", "bdf", &flat);
    one_error(
        &message,
        &[
            &file,
            "parts[0].mesh.file",
            "part 'bad'",
            "element 18 (tet4) is degenerate",
        ],
    );
}
