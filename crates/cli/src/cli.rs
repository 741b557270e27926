//! The command line: parsing the arguments and dispatching to the commands.

use crate::console::Console;
use std::path::PathBuf;
use study::error::BoxError;
use study::run::Options;

pub const USAGE: &str = "\
flexmbs: from a mesh to the motion of a flexible mechanism

usage:
  flexmbs run [STUDY.toml]           run the analyses of a study and write a results folder;
                                     without a file, run the built-in example: the flexible
                                     planar slider-crank (benchmarks.md C2), results in
                                     ./slider_crank-results/
  flexmbs check STUDY.toml           validate a study file, run nothing
  flexmbs reduce STUDY.toml [--part NAME]
                                     reduce the parts that have a [parts.reduction] (or the one
                                     named) to reduced-body files (.rbody)
  flexmbs inspect FILE.rbody [--excitation-hz F]
                                     show a reduced body: interfaces, mass data, fixed-interface
                                     frequencies, modal effective masses (and, with F, whether
                                     the kept modes reach 3 x F)
  flexmbs example [NAME [DIR]]       list the built-in example studies, or write one into DIR
                                     (default: the current folder)
  flexmbs validate [ARGS]            the validation suite (benchmarks.md): --quick, --no-report,
                                     --report-dir DIR, --only ID ...
  flexmbs --help | --version

options of run and reduce:
  --out DIR      results folder (default: STUDY-results beside the study file)
  --cache DIR    reduced-body cache (default: .flexmbs-cache beside the study file); a part
                 whose mesh and settings did not change is not reduced again
  --t-end T      end every dynamic analysis at T seconds at the latest (a short run)
  --foreign-files refuse|keep
                 a results folder holding files flexmbs did not write: refuse to run
                 (default) or write beside them; flexmbs deletes only files it wrote

The study file format is described in docs/study-file.md. Errors go to stderr with the
file, line, column and key they are about; the exit code is 0 on success, 2 on any error.";

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
                let close = study::source::close_matches(&name, known.iter().copied());
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
        None | Some("refuse") => study::folder::ForeignFiles::Refuse,
        Some("keep") => study::folder::ForeignFiles::Keep,
        Some(other) => return Err(usage(format!("--foreign-files is 'refuse' or 'keep', not '{other}'"))),
    };
    Ok(Options {
        out: option(options, "out").map(PathBuf::from),
        cache: option(options, "cache").map(PathBuf::from),
        t_end: None,
        foreign,
    })
}

fn one_file(positional: &[String], command: &str, what: &str) -> Result<PathBuf, BoxError> {
    match positional {
        [file] => Ok(PathBuf::from(file)),
        [] => Err(usage(format!("`flexmbs {command}` needs {what}"))),
        [_, extra, ..] => Err(usage(format!(
            "`flexmbs {command}` takes one file; unexpected argument '{extra}'"
        ))),
    }
}

fn load(path: &std::path::Path) -> Result<study::Study, BoxError> {
    let study = study::load(path)?;
    for w in &study.warnings {
        eprintln!("flexmbs: warning: {w}");
    }
    Ok(study)
}

/// Runs every analysis of `study` into its results folder, progress on the console.
pub fn run(study: &study::Study, options: &Options) -> Result<study::output::Summary, BoxError> {
    let summary = study::run(study, options, &mut Console::default())?;
    eprintln!(
        "flexmbs: {} analyses done in {:.2} s; results in {}",
        summary.analyses.len(),
        summary.total_seconds,
        options.results_dir(study).display()
    );
    Ok(summary)
}

/// Runs the command line `args` (without the program name).
pub fn main_with(args: &[String]) -> Result<(), BoxError> {
    let Some((command, rest)) = args.split_first() else {
        return Err(usage("no command given"));
    };
    match command.as_str() {
        "--help" | "-h" | "help" => {
            println!("{USAGE}");
            Ok(())
        }
        "--version" | "-V" => {
            println!("flexmbs {}", env!("CARGO_PKG_VERSION"));
            Ok(())
        }
        "run" => {
            let (positional, options) = parse(rest, &["out", "cache", "t-end", "foreign-files"])?;
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
                [] => crate::builtin::run(&run_options),
                _ => {
                    let path = one_file(&positional, "run", "a study file")?;
                    let study = load(&path)?;
                    run(&study, &run_options)?;
                    Ok(())
                }
            }
        }
        "check" => {
            let (positional, _) = parse(rest, &[])?;
            let path = one_file(&positional, "check", "a study file")?;
            let study = load(&path)?;
            let m = &study.mechanism;
            let mechanism = if m.is_empty() {
                String::new()
            } else {
                format!(
                    ", a mechanism of {} flexible and {} rigid bodies, {} joints, {} sensors",
                    m.bodies.len(),
                    m.rigid_bodies.len(),
                    m.joints.len(),
                    m.sensors.len()
                )
            };
            println!(
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
            let written = study::run::reduce_command(
                &study,
                option(&options, "part"),
                &run_options(&options)?,
                &mut Console::default(),
            )?;
            for r in written {
                println!(
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
            let (positional, options) = parse(rest, &["excitation-hz"])?;
            let path = one_file(&positional, "inspect", "a reduced-body file (.rbody)")?;
            let excitation = match option(&options, "excitation-hz") {
                Some(v) => Some(
                    v.parse::<f64>()
                        .ok()
                        .filter(|f| *f > 0.0 && f.is_finite())
                        .ok_or_else(|| usage(format!("--excitation-hz needs a positive frequency in Hz, got '{v}'")))?,
                ),
                None => None,
            };
            print!("{}", crate::inspect::inspect(&path, excitation, 3.0)?);
            Ok(())
        }
        "example" => {
            let (positional, _) = parse(rest, &[])?;
            match positional.as_slice() {
                [] => {
                    print!("{}", study::examples::list());
                    Ok(())
                }
                [name] | [name, _] => {
                    let dir = PathBuf::from(positional.get(1).map_or(".", String::as_str));
                    let study = study::examples::write(name, &dir)?;
                    println!("{}", study.display());
                    eprintln!("flexmbs: run it with `flexmbs run {}`", study.display());
                    Ok(())
                }
                [_, _, extra, ..] => Err(usage(format!("unexpected argument '{extra}'"))),
            }
        }
        other => {
            let commands = ["run", "check", "reduce", "inspect", "example", "validate", "help"];
            let close = study::source::close_matches(other, commands.iter().copied());
            let hint = match close.first() {
                Some(c) => format!("; did you mean `{c}`?"),
                None => String::new(),
            };
            Err(usage(format!("unknown command '{other}'{hint}")))
        }
    }
}
