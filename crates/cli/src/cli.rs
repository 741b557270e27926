//! The command line: parsing the arguments and dispatching to the commands.

pub use crate::console::run;
use crate::console::Console;
use std::path::{Path, PathBuf};
use study::error::BoxError;
use study::Options;

pub const USAGE: &str = "\
flexmbs: from a mesh to the motion of a flexible mechanism

usage:
  flexmbs run [STUDY.toml]           run the analyses of a study and write a results folder;
                                     without a file, run the built-in example: the flexible
                                     planar slider-crank (validation problem C2), results in
                                     ./slider_crank-results/
  flexmbs view RESULTS_DIR           write the results page view.html of a results folder again
                                     (every run writes it: the bodies moving, the modes, the
                                     sensors; opens in a browser, no network) and print its path
  flexmbs view STUDY.toml            write STEM-model.html: the study's mechanism before it runs
  flexmbs check STUDY.toml           validate a study file, run nothing
  flexmbs reduce STUDY.toml [--part NAME]
                                     reduce the parts that have a [parts.reduction] (or the one
                                     named) to reduced-body files (.rbody)
  flexmbs inspect FILE.rbody|FILE.fem [--excitation-hz F]
  flexmbs inspect K.mtx --mass M.mtx --nodes NODES (--dofs DOFS | --dofs-per-node 3|6)
                  --interface NAME=NODE ... (--modes N | --cutoff-hz F) [--excitation-hz F]
                                     show a reduced body (or an MBDyn modal element file, or
                                     Matrix Market matrices of another code, reduced as a
                                     study's [bodies.matrices]): interfaces, mass data,
                                     fixed-interface frequencies, modal effective masses (and,
                                     with F, whether the kept modes reach 3 x F), the physical
                                     checks and what they measured
  flexmbs export-fem FILE.rbody OUT.fem [--reference INTERFACE]
                                     write a reduced body as an MBDyn modal element file
                                     (modal node at the reference interface, default the first)
  flexmbs export-fmu STUDY.toml [--analysis NAME] [--fmi-version 2|3] [-o FILE.fmu]
                                     write a dynamic analysis as an FMI 2.0 Co-Simulation FMU
                                     (docs/fmu.md): inputs the actuators and point loads,
                                     outputs the sensors, parameters the study's [fmu] table
  flexmbs example [NAME [DIR]]       list the built-in example studies, or write one into DIR
                                     (default: the current folder)
  flexmbs validate [ARGS]            the validation suite (docs/validation.md): --quick, --no-report,
                                     --report-dir DIR, --only ID ... (in a flexmbs built with
                                     `--features validate`)
  flexmbs --help | --version

options of run and reduce:
  --out DIR      results folder (default: STUDY-results beside the study file)
  --cache DIR    reduced-body cache (default: .flexmbs-cache beside the study file); a part
                 whose mesh and settings did not change is not reduced again
  --foreign-files refuse|keep
                 a results folder holding files flexmbs did not write: refuse to run
                 (default) or write beside them; flexmbs deletes only files it wrote
options of run:
  --t-end T      end every dynamic analysis at T seconds at the latest (a short run; the
                 summary says so)
  --analysis NAME
                 run this analysis alone (first the analyses its `start` names, if any)

`flexmbs COMMAND --help` shows one command.

The study file format is described in docs/study-file.md. Errors go to stderr with the
file, line, column and key they are about; the exit code is 0 on success, 1 when `inspect`
finds a reduced body that fails its physical checks, 2 on any other error.";

/// The help of one command (`flexmbs COMMAND --help`).
pub fn command_help(command: &str) -> Option<&'static str> {
    Some(match command {
        "run" => {
            "\
usage: flexmbs run [STUDY.toml] [--analysis NAME] [--out DIR] [--cache DIR] [--t-end T]
                   [--foreign-files refuse|keep]

Validates the study, then runs its analyses in order and writes the results folder
(default: STUDY-results beside the study file). Without a file, runs the built-in example,
the flexible planar slider-crank (validation problem C2), into ./slider_crank-results/.

  --out DIR      results folder
  --cache DIR    reduced-body cache (default: .flexmbs-cache beside the study file)
  --t-end T      end every dynamic analysis at T seconds at the latest; the summary says so
  --analysis NAME
                 run this analysis alone; when its `start` names another analysis, that one
                 (and the one its `start` names, and so on) runs first and writes its results
                 too. The other analyses' results are left as they are."
        }
        "view" => {
            "\
usage: flexmbs view RESULTS_DIR
       flexmbs view STUDY.toml [--cache DIR]

Writes the results page RESULTS_DIR/view.html again from the data it holds, with this version
of flexmbs, and prints its path. Every `flexmbs run` writes the page: one self-contained HTML
file (no server, no network request) with the bodies moving over time, the mode shapes, the
stresses and the sensors of every analysis. Open it in a browser.

Given a study file, writes the page of its mechanism before it runs, STEM-model.html beside the
study: the bodies at the initial state, their interfaces, the joints, supports, point masses
and loads (the parts reduced through the cache first, as `flexmbs run` does)."
        }
        "check" => {
            "\
usage: flexmbs check STUDY.toml

Validates a study file (every name resolved, every value checked) and runs nothing. Errors
name the file, line, column and key."
        }
        "reduce" => {
            "\
usage: flexmbs reduce STUDY.toml [--part NAME] [--out DIR] [--cache DIR] [--foreign-files refuse|keep]

Reduces the parts that have a [parts.reduction] (or only the one named) to reduced-body
files (.rbody), through the cache."
        }
        "inspect" => {
            "\
usage: flexmbs inspect FILE.rbody|FILE.fem [--excitation-hz F]
       flexmbs inspect K.mtx --mass M.mtx --nodes NODES (--dofs DOFS | --dofs-per-node 3|6)
                       --interface NAME=NODE ... (--modes N | --cutoff-hz F) [--excitation-hz F]

Shows a reduced body (.rbody, or an MBDyn modal element file .fem): interfaces, mass data,
fixed-interface frequencies and modal effective masses; with F, whether the kept modes reach
3 x F; the physical checks every body passes before use, with what they measured. A check
that cannot be made is said so (an MBDyn record 12 without the nodal masses of record 11 to
compare it with).

Matrices from another code (Matrix Market stiffness K.mtx and mass M.mtx, SI units) are
reduced first, as a study's [bodies.matrices] with the same keys is (docs/study-file.md):
  --nodes NODES        node table, `x y z` per line [m]; node k is the k-th data line
  --dofs DOFS          dof table, `node dof` per matrix row (dof: ux uy uz rx ry rz), or
  --dofs-per-node 3|6  every node with 3 or 6 dofs, in node order
  --interface NAME=NODE
                       an interface at node NODE (0-based); once per interface, each on a
                       node with six dofs
  --modes N | --cutoff-hz F
                       the fixed-interface modes kept: a count, or every mode below F Hz
The node table is checked against K (rigid motions) and against M (mass over the volume of
the nodes' box: a table in millimetres is refused) before the body's checks.

Exits with 1 when the body fails its physical checks (the report lists them), with 2 when
the files cannot be read or reduced."
        }
        "export-fmu" => {
            "\
usage: flexmbs export-fmu STUDY.toml [--analysis NAME] [--fmi-version 2|3] [-o FILE.fmu]

Writes the dynamic analysis NAME (default: the study's only one) as an FMI 2.0 (default) or,
with --fmi-version 3, an FMI 3.0 Co-Simulation FMU (default: STUDY.fmu beside the study file), for a co-simulation master (FMPy, Simulink,
OpenModelica, ...). Inputs: the effort of every actuator and the force and moment components
of every point load, held over a communication step; outputs: every sensor column, with its
unit; parameters: the study values the study's [fmu] table names. The mechanism is built and
the analysis started once here, so a study the FMU could not start is refused now; the
archive carries the study, the files it names and its reduced bodies, and runs without
flexmbs (docs/fmu.md).

The FMU's binary is the library libflexmbs_fmu.so, found next to the program or named by the
environment variable FLEXMBS_FMU_LIBRARY; build it with `cargo build --release -p flexmbs-fmu`.

  --analysis NAME   the dynamic analysis the FMU steps
  -o, --out FILE    the FMU file to write"
        }
        "example" => {
            "\
usage: flexmbs example [NAME [DIR]]

Lists the built-in example studies, or writes the one named into DIR (default: the current
folder)."
        }
        _ => return None,
    })
}

fn wants_help(args: &[String]) -> bool {
    args.iter().any(|a| a == "--help" || a == "-h")
}

/// A command line that cannot be understood: the message and a pointer to `--help`.
#[derive(Debug)]
pub struct UsageError(pub String);

impl std::fmt::Display for UsageError {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        write!(f, "{} (see `flexmbs --help`)", self.0)
    }
}

impl std::error::Error for UsageError {}

fn usage(message: impl Into<String>) -> BoxError {
    Box::new(UsageError(message.into()))
}

/// `--name value` pairs, in command-line order.
type Flags = Vec<(String, String)>;

/// Splits `args` into positional arguments and `--name value` options; refuses options not
/// in `known`.
fn parse(args: &[String], known: &[&str]) -> Result<(Vec<String>, Flags), BoxError> {
    let mut positional = Vec::new();
    let mut options = Vec::new();
    let mut it = args.iter();
    while let Some(a) = it.next() {
        if let Some(name) = a.strip_prefix("--") {
            let (name, value) = match name.split_once('=') {
                Some((n, v)) => (n.to_string(), Some(v.to_string())),
                None => (name.to_string(), None),
            };
            if !known.contains(&name.as_str()) {
                let close = study::input::source::close_matches(&name, known.iter().copied());
                let hint = match close.first() {
                    Some(c) => format!("; did you mean --{c}?"),
                    None if known.is_empty() => " (this command takes no options)".to_string(),
                    None => format!(" (options: --{})", known.join(", --")),
                };
                return Err(usage(format!("unknown option --{name}{hint}")));
            }
            let value = match value {
                Some(v) => v,
                None => it
                    .next()
                    .cloned()
                    .ok_or_else(|| usage(format!("option --{name} needs a value")))?,
            };
            options.push((name, value));
        } else {
            positional.push(a.clone());
        }
    }
    Ok((positional, options))
}

fn option<'a>(options: &'a [(String, String)], name: &str) -> Option<&'a str> {
    options.iter().rev().find(|(n, _)| n == name).map(|(_, v)| v.as_str())
}

fn run_options(options: &[(String, String)]) -> Result<Options, BoxError> {
    let foreign = match option(options, "foreign-files") {
        None | Some("refuse") => study::output::folder::ForeignFiles::Refuse,
        Some("keep") => study::output::folder::ForeignFiles::Keep,
        Some(other) => return Err(usage(format!("--foreign-files is 'refuse' or 'keep', not '{other}'"))),
    };
    Ok(Options {
        out: option(options, "out").map(PathBuf::from),
        cache: option(options, "cache").map(PathBuf::from),
        t_end: None,
        foreign,
    })
}

/// The options of `inspect`: `--excitation-hz`, and for a Matrix Market stiffness those of
/// the study's `[bodies.matrices]` (its keys, `_` written `-`; `--interface NAME=NODE` once
/// per interface).
const INSPECT_OPTIONS: [&str; 8] = [
    "excitation-hz",
    "mass",
    "nodes",
    "dofs",
    "dofs-per-node",
    "interface",
    "modes",
    "cutoff-hz",
];

/// `[bodies.matrices]` from the options of `inspect` when `path` is a Matrix Market
/// stiffness (`.mtx`); `None` for a reduced-body or MBDyn file, which take none of them.
fn matrices_spec(path: &Path, options: &Flags) -> Result<Option<study::input::schema::MatricesFile>, BoxError> {
    let given: Vec<&str> = options
        .iter()
        .map(|(n, _)| n.as_str())
        .filter(|n| *n != "excitation-hz")
        .collect();
    if !path.extension().is_some_and(|e| e.eq_ignore_ascii_case("mtx")) {
        return match given.first() {
            Some(name) => Err(usage(format!(
                "--{name} is for a Matrix Market stiffness (K.mtx); {} is not one",
                path.display()
            ))),
            None => Ok(None),
        };
    }
    let required = |name: &str, what: &str| {
        option(options, name)
            .map(str::to_string)
            .ok_or_else(|| usage(format!("a Matrix Market stiffness needs --{name} {what}")))
    };
    let number = |name: &str| -> Result<Option<usize>, BoxError> {
        option(options, name)
            .map(|v| {
                v.parse::<usize>()
                    .map_err(|_| usage(format!("--{name} needs a whole number, got '{v}'")))
            })
            .transpose()
    };
    let mass = required("mass", "M.mtx")?;
    let nodes = required("nodes", "NODES (x y z per line, m)")?;
    let interfaces = interface_options(options)?;
    let cutoff_hz = frequency_option(options, "cutoff-hz")?;
    Ok(Some(study::input::schema::MatricesFile {
        stiffness: path.display().to_string(),
        mass,
        nodes,
        dofs: option(options, "dofs").map(str::to_string),
        dofs_per_node: number("dofs-per-node")?,
        interfaces,
        modes: number("modes")?,
        cutoff_hz,
    }))
}

/// The option `--name`, a positive frequency in Hz, if given.
fn frequency_option(options: &Flags, name: &str) -> Result<Option<f64>, BoxError> {
    option(options, name)
        .map(|v| {
            v.parse::<f64>()
                .ok()
                .filter(|f| *f > 0.0 && f.is_finite())
                .ok_or_else(|| usage(format!("--{name} needs a positive frequency in Hz, got '{v}'")))
        })
        .transpose()
}

/// The `--interface NAME=NODE` options of `inspect`, at least one, each name once.
fn interface_options(options: &Flags) -> Result<std::collections::BTreeMap<String, usize>, BoxError> {
    let mut interfaces = std::collections::BTreeMap::new();
    for (_, v) in options.iter().filter(|(n, _)| n == "interface") {
        let parsed = v
            .split_once('=')
            .and_then(|(name, node)| Some((name.trim(), node.trim().parse::<usize>().ok()?)))
            .filter(|(name, _)| !name.is_empty());
        let Some((name, node)) = parsed else {
            return Err(usage(format!(
                "--interface needs NAME=NODE (NODE: 0-based index into the node table), got '{v}'"
            )));
        };
        if interfaces.insert(name.to_string(), node).is_some() {
            return Err(usage(format!("--interface '{name}' is given twice")));
        }
    }
    if interfaces.is_empty() {
        return Err(usage(
            "a Matrix Market stiffness needs --interface NAME=NODE, once per interface",
        ));
    }
    Ok(interfaces)
}

/// A command that ran to the end but whose checks failed (exit code 1, not 2).
#[derive(Debug)]
pub struct ChecksFailed {
    pub what: String,
}

impl std::fmt::Display for ChecksFailed {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.write_str(&self.what)
    }
}

impl std::error::Error for ChecksFailed {}

fn one_file(positional: &[String], command: &str, what: &str) -> Result<PathBuf, BoxError> {
    match positional {
        [file] => Ok(PathBuf::from(file)),
        [] => Err(usage(format!("`flexmbs {command}` needs {what}"))),
        [_, extra, ..] => Err(usage(format!(
            "`flexmbs {command}` takes one file; unexpected argument '{extra}'"
        ))),
    }
}

/// `flexmbs view STUDY.toml`: the page of the model before it runs, written beside the study
/// as `STEM-model.html` (the parts reduced through the cache first).
fn model_page(path: &Path, options: &Options) -> Result<PathBuf, BoxError> {
    let study = load(path)?;
    let html = study::model_page(&study, options, &mut Console::default())?;
    let stem = path.file_stem().map_or("study".into(), |s| s.to_string_lossy());
    let out = path.with_file_name(format!("{stem}-model.html"));
    // A file of that name that is not a page of ours is the user's: left alone.
    if out.exists() && !std::fs::read_to_string(&out).is_ok_and(|s| s.contains(r#"id="flexmbs-data""#)) {
        return Err(format!(
            "refusing to overwrite {}: it is not a page flexmbs wrote; it is left as it is (move it, or copy the study under another name)",
            out.display()
        )
        .into());
    }
    std::fs::write(&out, html).map_err(|e| format!("{}: cannot write the model's page: {e}", out.display()))?;
    Ok(out)
}

fn load(path: &std::path::Path) -> Result<study::Study, BoxError> {
    let study = study::load(path)?;
    for w in &study.warnings {
        crate::tell!("flexmbs: warning: {w}");
    }
    Ok(study)
}

/// What `flexmbs validate` says when the program was built without the validation suite
/// (the cargo feature `validate`, off by default).
pub const VALIDATE_NOT_BUILT: &str = "\
flexmbs: error: this flexmbs was built without the validation suite (docs/validation.md).
Run the suite's own program, with the same arguments:
  cargo run --release -p validation -- [--quick] [--no-report] [--report-dir DIR] [--only ID ...]
or build flexmbs with it:
  cargo run --release -p flexmbs --features validate -- validate [ARGS]";

/// Runs the command line `args` (without the program name).
pub fn main_with(args: &[String]) -> Result<(), BoxError> {
    let Some((command, rest)) = args.split_first() else {
        return Err(usage("no command given"));
    };
    if let Some(help) = command_help(command).filter(|_| wants_help(rest)) {
        crate::say!("{help}");
        return Ok(());
    }
    match command.as_str() {
        "help" if !rest.is_empty() => match command_help(&rest[0]) {
            Some(help) => {
                crate::say!("{help}");
                Ok(())
            }
            None => Err(usage(format!("no help for '{}'", rest[0]))),
        },
        "--help" | "-h" | "help" => {
            crate::say!("{USAGE}");
            Ok(())
        }
        "--version" | "-V" => {
            crate::say!("flexmbs {}", env!("CARGO_PKG_VERSION"));
            Ok(())
        }
        "run" => {
            let (positional, options) = parse(rest, &["out", "cache", "t-end", "foreign-files", "analysis"])?;
            let mut run_options = run_options(&options)?;
            if let Some(v) = option(&options, "t-end") {
                run_options.t_end = Some(
                    v.parse::<f64>()
                        .ok()
                        .filter(|t| *t > 0.0 && t.is_finite())
                        .ok_or_else(|| usage(format!("--t-end needs a positive time in seconds, got '{v}'")))?,
                );
            }
            match positional.as_slice() {
                [] if option(&options, "analysis").is_none() => crate::builtin::run(&run_options),
                _ => {
                    let path = one_file(&positional, "run", "a study file")?;
                    let study = load(&path)?;
                    run(&study, &run_options, option(&options, "analysis"))?;
                    Ok(())
                }
            }
        }
        "check" => {
            let (positional, _) = parse(rest, &[])?;
            let path = one_file(&positional, "check", "a study file")?;
            let study = load(&path)?;
            if study.analyses.is_empty() {
                return Err(study::nothing_to_run(&study));
            }
            let m = &study.mechanism;
            let mechanism = if m.is_empty() {
                String::new()
            } else {
                format!(
                    ", a mechanism of {} flexible and {} rigid bodies, {}, {} sensors",
                    m.bodies.len(),
                    m.rigid_bodies.len(),
                    study::joint_count(&study),
                    m.sensors.len()
                )
            };
            crate::say!(
                "{}: valid: {} parts, {} analyses{mechanism}",
                path.display(),
                study.parts.len(),
                study.analyses.len()
            );
            Ok(())
        }
        "reduce" => {
            let (positional, options) = parse(rest, &["part", "out", "cache", "foreign-files"])?;
            let path = one_file(&positional, "reduce", "a study file")?;
            let study = load(&path)?;
            let written = study::reduce_command(
                &study,
                option(&options, "part"),
                &run_options(&options)?,
                &mut Console::default(),
            )?;
            for r in written {
                crate::say!(
                    "part '{}': {} coordinates ({} interfaces, {} modes) -> {}",
                    r.part,
                    r.coordinates,
                    r.interfaces,
                    r.modes,
                    r.path.display()
                );
            }
            Ok(())
        }
        "inspect" => {
            let (positional, options) = parse(rest, &INSPECT_OPTIONS)?;
            let path = one_file(
                &positional,
                "inspect",
                "a reduced-body file (.rbody), an MBDyn modal element file (.fem) or a Matrix Market stiffness (.mtx)",
            )?;
            let excitation = frequency_option(&options, "excitation-hz")?;
            let matrices = matrices_spec(&path, &options)?;
            let source = match &matrices {
                Some(m) => study::InspectSource::Matrices(m),
                None => study::InspectSource::File(&path),
            };
            let inspection = study::inspect(&source, excitation, 3.0)?;
            crate::say_raw!("{}", inspection.report);
            if inspection.failed_checks > 0 {
                return Err(Box::new(ChecksFailed {
                    what: format!(
                        "{} fails {} physical check{} (listed above): studies refuse it",
                        path.display(),
                        inspection.failed_checks,
                        if inspection.failed_checks == 1 { "" } else { "s" }
                    ),
                }));
            }
            Ok(())
        }
        "view" => {
            let (positional, options) = parse(rest, &["cache"])?;
            let path = one_file(&positional, "view", "a results folder or a study file")?;
            let page = if !path.exists() {
                return Err(format!("{}: no such results folder or study file", path.display()).into());
            } else if path.is_dir() {
                study::output::folder::rewrite_view(&path)?
            } else {
                model_page(&path, &run_options(&options)?)?
            };
            crate::say!("{}", page.display());
            Ok(())
        }
        "export-fem" => {
            let (positional, options) = parse(rest, &["reference"])?;
            let [input, output] = positional.as_slice() else {
                return Err(usage(
                    "export-fem needs a reduced-body file (.rbody) and the .fem file to write",
                ));
            };
            let body = reduction::file::read(Path::new(input))?;
            let reference = match option(&options, "reference") {
                None => 0,
                Some(name) => body.interfaces.iter().position(|i| i.name == name).ok_or_else(|| {
                    let names: Vec<&str> = body.interfaces.iter().map(|i| i.name.as_str()).collect();
                    usage(format!(
                        "--reference: the body has no interface '{name}' (interfaces: {})",
                        names.join(", ")
                    ))
                })?,
            };
            reduction::mbdyn::write_mbdyn_fem(Path::new(output), &body, reference)?;
            println!(
                "{input}: {} interfaces, {} modes -> {output} (MBDyn modal node at interface '{}')",
                body.interfaces.len(),
                body.n_modes,
                body.interfaces[reference].name
            );
            Ok(())
        }
        "export-fmu" => {
            // `-o FILE` is `--out FILE`.
            let rest: Vec<String> = rest
                .iter()
                .map(|a| if a == "-o" { "--out".to_string() } else { a.clone() })
                .collect();
            let (positional, options) = parse(&rest, &["analysis", "out", "fmi-version"])?;
            let path = one_file(&positional, "export-fmu", "a study file")?;
            let version = match option(&options, "fmi-version") {
                Some(v) => study::fmu::FmiVersion::parse(v).map_err(|e| format!("--fmi-version: {e}"))?,
                None => study::fmu::FmiVersion::V2,
            };
            let out = match option(&options, "out") {
                Some(o) => PathBuf::from(o),
                None => path.with_extension("fmu"),
            };
            let library = study::fmu::library_path()?;
            let exported = study::fmu::export(&path, option(&options, "analysis"), version, &library, &out)?;
            let count = |causality: &str| exported.variables.iter().filter(|v| v.causality() == causality).count();
            crate::say!(
                "{}: analysis '{}' as an FMI {} Co-Simulation FMU (model identifier {}): {} outputs, {} inputs, {} parameters -> {}",
                path.display(),
                exported.analysis,
                exported.version.name(),
                exported.model_identifier,
                count("output"),
                count("input"),
                count("parameter"),
                out.display()
            );
            Ok(())
        }
        "example" => {
            let (positional, _) = parse(rest, &[])?;
            match positional.as_slice() {
                [] => {
                    crate::say_raw!("{}", study::input::examples::list());
                    Ok(())
                }
                [name] | [name, _] => {
                    let dir = PathBuf::from(positional.get(1).map_or(".", String::as_str));
                    let study = study::input::examples::write(name, &dir)?;
                    crate::say!("{}", study.display());
                    crate::tell!("flexmbs: run it with `flexmbs run {}`", study.display());
                    Ok(())
                }
                [_, _, extra, ..] => Err(usage(format!("unexpected argument '{extra}'"))),
            }
        }
        other => {
            let commands = [
                "run",
                "view",
                "check",
                "reduce",
                "inspect",
                "export-fem",
                "export-fmu",
                "example",
                "validate",
                "help",
            ];
            let close = study::input::source::close_matches(other, commands.iter().copied());
            let hint = match close.first() {
                Some(c) => format!("; did you mean `{c}`?"),
                None => String::new(),
            };
            Err(usage(format!("unknown command '{other}'{hint}")))
        }
    }
}
