//! Picking the analyses of a study: one by its name ([`Study::analysis`], with the close
//! matches of a name the study lacks), the dynamic one a stepper steps
//! ([`Study::dynamic_analysis`]), or all of them ([`Selection`]).

use crate::error::BoxError;
use crate::input::source::unknown_reference;
use crate::input::validate::Study;

impl Study {
    /// The index of the analysis called `name`; a name the study lacks is an error naming the
    /// close matches ("did you mean").
    pub fn analysis(&self, name: &str) -> Result<usize, UnknownName> {
        self.analyses
            .iter()
            .position(|a| a.name == name)
            .ok_or_else(|| UnknownName {
                what: "analysis",
                name: name.to_string(),
                defined: self.analyses.iter().map(|a| a.name.clone()).collect(),
            })
    }

    /// The dynamic analysis a stepper (a `Simulation`, an FMU) steps: `name`, which must be a
    /// dynamic analysis, or the study's only dynamic analysis.
    pub fn dynamic_analysis(&self, name: Option<&str>) -> Result<String, BoxError> {
        if let Some(name) = name {
            let kind = self.analyses[self.analysis(name)?].kind_name();
            if kind != "dynamic" {
                return Err(
                    format!("analysis '{name}' is of type '{kind}'; only a dynamic analysis is stepped").into(),
                );
            }
            return Ok(name.to_string());
        }
        let dynamic: Vec<&str> = self
            .analyses
            .iter()
            .filter(|a| a.kind_name() == "dynamic")
            .map(|a| a.name.as_str())
            .collect();
        let file = self.source.path.display();
        match dynamic.as_slice() {
            [one] => Ok(one.to_string()),
            [] => Err(format!("{file}: the study has no dynamic analysis to step").into()),
            many => Err(format!(
                "{file}: the study has {} dynamic analyses ({}): name the one to step",
                many.len(),
                many.join(", ")
            )
            .into()),
        }
    }
}

/// A name the study lacks: what it was meant to name (`"analysis"`), the name, and every name
/// defined, so a face can offer the close matches in its own way (Python's
/// `UnknownNameError`); its message is [`unknown_reference`]'s "did you mean".
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct UnknownName {
    pub what: &'static str,
    pub name: String,
    pub defined: Vec<String>,
}

impl std::fmt::Display for UnknownName {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.write_str(&unknown_reference(self.what, &self.name, &self.defined))
    }
}

impl std::error::Error for UnknownName {}

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
    pub fn of(study: &Study, name: Option<&str>) -> Result<Self, UnknownName> {
        match name {
            None => Ok(Self::All),
            Some(name) => study.analysis(name).map(Self::One),
        }
    }
}
