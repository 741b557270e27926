//! The console observer of `flexmbs`: which analysis runs, progress bars and spinners on
//! stderr (hidden when stderr is not a terminal), and what each analysis found on stdout.

use study::error::BoxError;
use study::output::observer::{AnalysisInfo, Observer, Progress};
use study::output::summary::AnalysisSummary;
use study::Options;

/// Progress on stderr, reports on stdout.
#[derive(Default)]
pub struct Console {
    bar: Option<indicatif::ProgressBar>,
    /// Where progress is drawn; `None`: stderr (hidden when it is not a terminal).
    target: Option<fn() -> indicatif::ProgressDrawTarget>,
}

impl Console {
    /// A console drawing its progress to `target` (tests: `ProgressDrawTarget::hidden`).
    pub fn with_target(target: fn() -> indicatif::ProgressDrawTarget) -> Self {
        Self {
            bar: None,
            target: Some(target),
        }
    }

    fn draw_target(&self) -> indicatif::ProgressDrawTarget {
        self.target.map_or_else(indicatif::ProgressDrawTarget::stderr, |t| t())
    }

    fn finish(&mut self) {
        if let Some(bar) = self.bar.take() {
            bar.finish_and_clear();
        }
    }

    /// The progress shown now: the bar's length (`None` for a stage without one) and its
    /// text.
    pub fn shown(&self) -> Option<(Option<u64>, String)> {
        self.bar.as_ref().map(|b| (b.length(), b.message()))
    }

    /// A spinner with the stage's text: a stage has no length, so no `0/0` bar.
    fn spinner(&mut self, text: &str) {
        let is_spinner = self.bar.as_ref().is_some_and(|b| b.length().is_none());
        if !is_spinner {
            self.finish();
            let bar = indicatif::ProgressBar::with_draw_target(None, self.draw_target());
            if let Ok(style) = indicatif::ProgressStyle::with_template("{spinner} {msg} ({elapsed})") {
                bar.set_style(style);
            }
            bar.enable_steady_tick(std::time::Duration::from_millis(200));
            self.bar = Some(bar);
        }
        if let Some(bar) = &self.bar {
            bar.set_message(text.to_string());
        }
    }

    /// A bar of `total` steps with its text; replaces a stage's spinner or a bar of another
    /// length.
    fn steps(&mut self, what: &str, done: u64, total: u64) {
        if self.bar.as_ref().and_then(|b| b.length()) != Some(total) {
            self.finish();
            let bar = indicatif::ProgressBar::with_draw_target(Some(total), self.draw_target());
            if let Ok(style) =
                indicatif::ProgressStyle::with_template("{msg} [{bar:40}] {pos}/{len} ({elapsed} < {eta})")
            {
                bar.set_style(style.progress_chars("=> "));
            }
            self.bar = Some(bar);
        }
        if let Some(bar) = &self.bar {
            if bar.message() != what {
                bar.set_message(what.to_string());
            }
            bar.set_position(done);
        }
    }
}

impl Observer for Console {
    fn begin(&mut self, a: &AnalysisInfo) -> Result<(), BoxError> {
        crate::tell!(
            "flexmbs: [{}/{}] {} analysis '{}' of {}",
            a.index + 1,
            a.count,
            a.kind,
            a.name,
            a.of
        );
        Ok(())
    }

    fn progress(&mut self, p: &Progress) {
        match p {
            Progress::Info(s) => {
                self.finish();
                crate::tell!("flexmbs: {s}");
            }
            Progress::Warning(s) => {
                self.finish();
                crate::tell!("flexmbs: warning: {s}");
            }
            Progress::Stage(s) => self.spinner(s),
            Progress::Steps { what, done, total } => self.steps(what, *done, *total),
            Progress::Finished => self.finish(),
        }
    }

    fn end(&mut self, a: &AnalysisInfo, s: &AnalysisSummary) -> Result<(), BoxError> {
        self.finish();
        if s.error.is_none() || !s.report.is_empty() {
            crate::say!("{} '{}' ({}):", a.kind, a.name, a.of);
            for line in &s.report {
                crate::say!("  {line}");
            }
        }
        Ok(())
    }
}

/// Runs every analysis of `study` (or only the one named `only`, after the chain of analyses
/// its `start` names) into its results folder, progress on the console.
pub fn run(
    study: &study::Study,
    options: &Options,
    only: Option<&str>,
) -> Result<study::output::summary::Summary, BoxError> {
    let selection =
        study::Selection::of(study, only).map_err(|e| format!("{}: --analysis: {e}", study.source.path.display()))?;
    let summary = study::run_selected(study, options, selection, &mut Console::default())?;
    let done = summary
        .analyses
        .iter()
        .filter(|a| a.status == study::output::summary::Status::Done)
        .count();
    let dir = options.results_dir(study);
    crate::tell!(
        "flexmbs: {} analyses done in {:.2} s; results in {}",
        done,
        summary.total_seconds,
        dir.display()
    );
    let page = dir.join(study::output::folder::VIEW);
    if page.is_file() {
        crate::tell!("flexmbs: open {} in a browser to see them", page.display());
    }
    Ok(summary)
}
