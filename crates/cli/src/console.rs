//! The console observer of `flexmbs`: which analysis runs, progress bars and spinners on
//! stderr (hidden when stderr is not a terminal), and what each analysis found on stdout.

use study::error::BoxError;
use study::observer::{AnalysisInfo, Observer, Progress};
use study::output::AnalysisSummary;

/// Progress on stderr, reports on stdout.
#[derive(Default)]
pub struct Console {
    bar: Option<indicatif::ProgressBar>,
}

impl Console {
    fn finish(&mut self) {
        if let Some(bar) = self.bar.take() {
            bar.finish_and_clear();
        }
    }
}

impl Observer for Console {
    fn begin(&mut self, a: &AnalysisInfo) -> Result<(), BoxError> {
        eprintln!(
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
                eprintln!("flexmbs: {s}");
            }
            Progress::Warning(s) => {
                self.finish();
                eprintln!("flexmbs: warning: {s}");
            }
            Progress::Stage(s) => {
                let bar = self.bar.get_or_insert_with(|| {
                    let bar = indicatif::ProgressBar::with_draw_target(None, indicatif::ProgressDrawTarget::stderr());
                    bar.enable_steady_tick(std::time::Duration::from_millis(200));
                    bar
                });
                bar.set_message(s.clone());
            }
            Progress::Steps { what, done, total } => {
                let bar = self.bar.get_or_insert_with(|| {
                    let bar =
                        indicatif::ProgressBar::with_draw_target(Some(*total), indicatif::ProgressDrawTarget::stderr());
                    if let Ok(style) =
                        indicatif::ProgressStyle::with_template("{msg} [{bar:40}] {pos}/{len} ({elapsed} < {eta})")
                    {
                        bar.set_style(style.progress_chars("=> "));
                    }
                    bar.set_message(what.clone());
                    bar
                });
                bar.set_position(*done);
            }
            Progress::Finished => self.finish(),
        }
    }

    fn end(&mut self, a: &AnalysisInfo, s: &AnalysisSummary) -> Result<(), BoxError> {
        self.finish();
        if s.error.is_none() || !s.report.is_empty() {
            println!("{} '{}' ({}):", a.kind, a.name, a.of);
            for line in &s.report {
                println!("  {line}");
            }
        }
        Ok(())
    }
}
