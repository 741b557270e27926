//! Where results and cached bodies go, and the run's overrides of the study.

use crate::input::validate::Study;
use crate::output::summary::default_results_dir;
use std::path::PathBuf;

/// Where results and cached bodies go.
#[derive(Clone, Debug, Default)]
pub struct Options {
    /// Results folder (default: `<study dir>/<study stem>-results`).
    pub out: Option<PathBuf>,
    /// Reduced-body cache (default: `<study dir>/.flexmbs-cache`).
    pub cache: Option<PathBuf>,
    /// Ends every dynamic analysis at this time if it is earlier (`--t-end`, for short runs).
    pub t_end: Option<f64>,
    /// Files in the results folder that flexmbs did not write: refuse (default) or keep
    /// (`--foreign-files keep`; `crate::output::folder`).
    pub foreign: crate::output::folder::ForeignFiles,
}

impl Options {
    pub fn results_dir(&self, study: &Study) -> PathBuf {
        self.out
            .clone()
            .unwrap_or_else(|| default_results_dir(&study.source.path))
    }
    pub fn cache_dir(&self, study: &Study) -> PathBuf {
        self.cache
            .clone()
            .unwrap_or_else(|| study.source.dir().join(".flexmbs-cache"))
    }
}
