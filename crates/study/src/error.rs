//! Errors of a study run: any error of the libraries, wrapped in the context that says which
//! part, analysis or file it is about. `main` prints the chain, one cause per line.

use crate::input::source::KeyPath;
use std::fmt;
use std::path::PathBuf;

/// Any error, sendable across threads.
pub type BoxError = Box<dyn std::error::Error + Send + Sync + 'static>;

/// An error with a sentence of context in front of it.
#[derive(Debug)]
pub struct Context {
    pub message: String,
    pub source: BoxError,
}

impl fmt::Display for Context {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.write_str(&self.message)
    }
}

impl std::error::Error for Context {
    fn source(&self) -> Option<&(dyn std::error::Error + 'static)> {
        Some(&*self.source)
    }
}

/// Where an entity is described in the study file: `file:line:column` of its value, and its
/// key path (`bodies[1]`).
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct Location {
    pub file: PathBuf,
    /// 1-based line and column; `None` when the key path is not in the file.
    pub line_column: Option<(usize, usize)>,
    pub key: KeyPath,
}

/// `file:line:col`, or the file alone when the line is not known.
impl fmt::Display for Location {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match self.line_column {
            Some((l, c)) => write!(f, "{}:{l}:{c}", self.file.display()),
            None => write!(f, "{}", self.file.display()),
        }
    }
}

/// A solver that stopped within an analysis after the results before it were written: what
/// stopped and what was kept (`message`), the number of the step that failed when the
/// analysis steps, where the entity the solver failed at (`mbs::SolveError::entity`: a body
/// whose frame failed) is described in the study, and the solver's error (time, step,
/// residual).
#[derive(Debug, thiserror::Error)]
#[error("{}", match .location {
    Some(at) => format!("{at}: {}: {}", at.key, .message),
    None => .message.clone(),
})]
pub struct SolverStopped {
    pub message: String,
    /// The number of the time or load step that failed (1 = the first).
    pub step: Option<usize>,
    /// Where the entity the solver failed at is described, when it is one of the study's.
    pub location: Option<Location>,
    #[source]
    pub source: mbs::SolveError,
}

/// An analysis of a run that failed: which one, where its results are, and the cause.
#[derive(Debug, thiserror::Error)]
#[error("{message}")]
pub struct AnalysisFailed {
    /// The analysis' name.
    pub analysis: String,
    pub message: String,
    #[source]
    pub source: BoxError,
}

/// `.context(|| "what was being done")` on any result.
pub trait ResultExt<T> {
    fn context(self, message: impl FnOnce() -> String) -> Result<T, BoxError>;
}

impl<T, E: Into<BoxError>> ResultExt<T> for Result<T, E> {
    fn context(self, message: impl FnOnce() -> String) -> Result<T, BoxError> {
        self.map_err(|e| {
            Box::new(Context {
                message: message(),
                source: e.into(),
            }) as BoxError
        })
    }
}

/// The error and its causes, one per line: the report `main` prints.
pub fn report(e: &(dyn std::error::Error + 'static)) -> String {
    format!("flexmbs: error: {}", chain(e))
}

/// The error and its causes on one line, `error: cause: cause`: for a message that goes into a
/// table or a summary rather than a report (each cause once, as the chain holds it).
pub fn sentence(e: &(dyn std::error::Error + 'static)) -> String {
    let mut out = e.to_string();
    let mut source = e.source();
    while let Some(s) = source {
        out.push_str(": ");
        out.push_str(&s.to_string());
        source = s.source();
    }
    out
}

/// The error and its causes, one per line, each cause as `caused by: ...`.
pub fn chain(e: &(dyn std::error::Error + 'static)) -> String {
    let mut out = e.to_string();
    let mut source = e.source();
    while let Some(s) = source {
        out.push_str(&format!("\n  caused by: {s}"));
        source = s.source();
    }
    out
}
