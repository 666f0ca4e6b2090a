//! The progress bar of the long sampling commands (`motion`, `check --motion`), driven by the
//! library's [`Progress`] reports.

use indicatif::{ProgressBar, ProgressDrawTarget, ProgressStyle};
use quad_host::ops::motion::Progress;
use std::io::{self, IsTerminal};

/// A progress bar on stderr when it is a terminal, hidden otherwise, driven by the library's
/// [`Progress`] reports.
pub struct Bar {
    bar: ProgressBar,
    what: String,
}

impl Bar {
    /// A bar labelled `what`, not yet shown.
    pub fn new(what: &str) -> Bar {
        Bar {
            bar: ProgressBar::hidden(),
            what: what.to_owned(),
        }
    }

    /// Follows one report.
    pub fn update(&mut self, p: Progress) {
        match p {
            Progress::Start(len) => self.bar = progress(len, &self.what),
            Progress::Done(n) => self.bar.set_position(n),
            Progress::Finished => self.bar.finish_and_clear(),
        }
    }
}

fn progress(len: u64, what: &str) -> ProgressBar {
    if !io::stderr().is_terminal() {
        return ProgressBar::hidden();
    }
    let bar = ProgressBar::with_draw_target(Some(len), ProgressDrawTarget::stderr());
    if let Ok(style) =
        ProgressStyle::with_template("{msg} [{bar:40}] {pos}/{len} samples ({per_sec}, {eta})")
    {
        bar.set_style(style.progress_chars("=> "));
    }
    bar.set_message(what.to_owned());
    bar
}
