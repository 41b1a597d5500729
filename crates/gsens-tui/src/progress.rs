//! Progress on standard error for the command line's long steps: a bar for
//! work counted in thousandths or in runs, a spinner for work that is not
//! counted, and the calibration pipeline's stages
//! ([`gsens_calib::Progress`]) as a spinner, or a bar for a stage with
//! counted steps. Each is drawn only when standard error is a terminal
//! (indicatif's default), so redirected output carries none of it.

use indicatif::{ProgressBar, ProgressStyle};
use std::sync::Arc;
use std::time::Duration;

/// A bar for work counted in thousandths (`set_position(1000·fraction)`),
/// `verb` before it.
pub fn progress_bar(verb: &str) -> ProgressBar {
    let template = format!("{verb} {{bar:40}} {{percent:>3}}% {{elapsed_precise}} (eta {{eta}})");
    styled(ProgressBar::new(1000), &template)
}

/// A bar for `len` counted `units` (`inc(1)` each), `verb` before it.
pub fn count_bar(verb: &str, len: u64, units: &str) -> ProgressBar {
    let template = format!("{verb} {{bar:40}} {{pos}}/{{len}} {units} {{elapsed_precise}} (eta {{eta}})");
    styled(ProgressBar::new(len), &template)
}

/// A spinner with the elapsed time and a message.
pub fn spinner() -> ProgressBar {
    let bar = styled(ProgressBar::new_spinner(), "{spinner} {elapsed} {msg}");
    bar.enable_steady_tick(Duration::from_millis(120));
    bar
}

fn styled(bar: ProgressBar, template: &str) -> ProgressBar {
    bar.set_style(ProgressStyle::with_template(template).expect("valid template"));
    bar
}

/// The pipeline's progress on a bar: the stage's name as its message, and
/// for a stage with counted steps (the receiver-loop search's candidates)
/// its position among them.
pub struct BarProgress(pub ProgressBar);

impl gsens_calib::Progress for BarProgress {
    fn stage(&self, name: &str, steps: Option<u64>) {
        let template = match steps {
            Some(_) => "{spinner} {elapsed} {msg} {bar:30} {pos}/{len}",
            None => "{spinner} {elapsed} {msg}",
        };
        self.0.set_style(ProgressStyle::with_template(template).expect("valid template"));
        self.0.set_position(0);
        self.0.set_length(steps.unwrap_or(0));
        self.0.set_message(name.to_string());
    }

    fn step(&self) {
        self.0.inc(1);
    }
}

/// Runs `f`, a call of the calibration pipeline, with its stages shown on a
/// spinner ([`BarProgress`]), cleared when `f` returns.
pub fn observed<R>(f: impl FnOnce() -> R) -> R {
    let bar = spinner();
    let result = gsens_calib::observe(Arc::new(BarProgress(bar.clone())), f);
    bar.finish_and_clear();
    result
}

/// Runs `f` with a spinner saying `what`, cleared when `f` returns.
pub fn with_spinner<R>(what: &str, f: impl FnOnce() -> R) -> R {
    let bar = spinner();
    bar.set_message(what.to_string());
    let result = f();
    bar.finish_and_clear();
    result
}

/// Runs `f` with a [`progress_bar`] saying `verb` that `f`'s callback sets
/// to the fraction done, cleared when `f` returns.
pub fn with_fraction_bar<R>(verb: &str, f: impl FnOnce(&mut dyn FnMut(f64)) -> R) -> R {
    let bar = progress_bar(verb);
    let result = f(&mut |fraction| bar.set_position((fraction * 1000.0) as u64));
    bar.finish_and_clear();
    result
}

/// Runs `f` with a [`count_bar`] of `len` `units` that `f`'s callback (called
/// from any thread) advances by one, cleared when `f` returns.
pub fn with_count_bar<R>(verb: &str, len: u64, units: &str, f: impl FnOnce(&(dyn Fn() + Sync)) -> R) -> R {
    let bar = count_bar(verb, len, units);
    let result = f(&|| bar.inc(1));
    bar.finish_and_clear();
    result
}

/// Runs `f`, which draws figures and tells each one's id as it starts it,
/// with a spinner saying `drawing` and the id, cleared when `f` returns.
pub fn drawing<R>(f: impl FnOnce(&mut dyn FnMut(&str)) -> R) -> R {
    let bar = spinner();
    let result = f(&mut |id| bar.set_message(format!("drawing {id}")));
    bar.finish_and_clear();
    result
}

#[cfg(test)]
mod tests {
    use super::*;
    use gsens_calib::Progress;

    /// A stage with steps sets the bar's length and counts from 0; a stage
    /// without steps starts again from 0 with no length.
    #[test]
    fn stages_reset_the_bar_and_steps_count_on_it() {
        let p = BarProgress(ProgressBar::hidden());
        p.stage("searching the loop", Some(12));
        p.step();
        p.step();
        assert_eq!((p.0.position(), p.0.length()), (2, Some(12)));
        assert_eq!(p.0.message(), "searching the loop");
        p.stage("estimating", None);
        assert_eq!((p.0.position(), p.0.length()), (0, Some(0)));
        assert_eq!(p.0.message(), "estimating");
    }

    /// What the wrapped closures return comes back unchanged, and a bar
    /// counts to its length.
    #[test]
    fn wrappers_return_the_closures_value() {
        assert_eq!(observed(|| 6 * 7), 42);
        assert_eq!(with_spinner("waiting", || "done"), "done");
        assert_eq!(with_fraction_bar("simulating", |progress| (0..=4).map(|k| progress(k as f64 / 4.0)).count()), 5);
        assert_eq!(with_count_bar("runs", 3, "runs", |tick| (0..3).map(|_| tick()).count()), 3);
        let mut drawn = Vec::new();
        let ids = drawing(|on_figure| {
            ["fig3", "fig4"].map(|id| {
                on_figure(id);
                drawn.push(id);
                id
            })
        });
        assert_eq!((ids, drawn), (["fig3", "fig4"], vec!["fig3", "fig4"]));
        let bar = count_bar("monte carlo", 3, "runs");
        (0..3).for_each(|_| bar.inc(1));
        assert_eq!((bar.position(), bar.length()), (3, Some(3)));
        assert_eq!(progress_bar("simulating").length(), Some(1000));
    }
}
