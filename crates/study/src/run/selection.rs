//! Picking the analyses of a study: one by its name ([`Study::analysis`], with the close
//! matches of a name the study lacks), or all of them ([`Selection`]).

use crate::input::source::unknown_reference;
use crate::input::validate::Study;

impl Study {
    /// The index of the analysis called `name`; a name the study lacks is an error naming the
    /// close matches ("did you mean").
    pub fn analysis(&self, name: &str) -> Result<usize, String> {
        self.analyses.iter().position(|a| a.name == name).ok_or_else(|| {
            let names: Vec<String> = self.analyses.iter().map(|a| a.name.clone()).collect();
            unknown_reference("analysis", name, &names)
        })
    }
}

/// The analyses a run runs: every one, or one (after the chain of analyses its `start`
/// names).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Selection {
    All,
    One(usize),
}

impl Selection {
    /// Every analysis of `study` (`name` is `None`), or the one called `name`
    /// ([`Study::analysis`]).
    pub fn of(study: &Study, name: Option<&str>) -> Result<Self, String> {
        match name {
            None => Ok(Self::All),
            Some(name) => study.analysis(name).map(Self::One),
        }
    }
}
