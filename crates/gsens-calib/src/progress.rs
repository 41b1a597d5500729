//! Progress of a long calibration, for a caller that shows it (the CLI draws
//! a bar on a terminal): the pipeline names each stage as it begins and
//! counts the steps of the stages that have them (the candidate loops of
//! [`crate::choose_loop`]). The library draws nothing itself.
//!
//! The observer is set for the duration of a closure on the calling thread
//! ([`observe`]); every entry point of the pipeline called inside it reports
//! to it, and nothing is reported outside one.

use std::cell::RefCell;
use std::sync::Arc;

/// Receives the pipeline's progress. Steps may be reported from any of the
/// pipeline's worker threads.
pub trait Progress: Send + Sync {
    /// A stage begins: `name` says what it does, `steps` how many steps it
    /// counts with [`step`](Self::step) (`None`: not counted).
    fn stage(&self, name: &str, steps: Option<u64>);
    /// One step of the current stage is done.
    fn step(&self);
}

thread_local! {
    static OBSERVER: RefCell<Option<Arc<dyn Progress>>> = const { RefCell::new(None) };
}

/// Restores the observer in place before [`observe`] when dropped (a panic included).
struct Restore(Option<Arc<dyn Progress>>);

impl Drop for Restore {
    fn drop(&mut self) {
        let previous = self.0.take();
        OBSERVER.with(|o| *o.borrow_mut() = previous);
    }
}

/// Runs `f` with `progress` receiving the progress of the pipeline's calls
/// made in it on this thread.
pub fn observe<R>(progress: Arc<dyn Progress>, f: impl FnOnce() -> R) -> R {
    let previous = OBSERVER.with(|o| o.borrow_mut().replace(progress));
    let _restore = Restore(previous);
    f()
}

/// The observer of the calling thread, if any.
pub(crate) fn current() -> Option<Arc<dyn Progress>> {
    OBSERVER.with(|o| o.borrow().clone())
}

/// Reports the start of stage `name` to the calling thread's observer.
pub(crate) fn stage(name: &str, steps: Option<u64>) {
    if let Some(p) = current() {
        p.stage(name, steps);
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use std::sync::Mutex;

    #[derive(Default)]
    struct Record(Mutex<Vec<String>>);

    impl Progress for Record {
        fn stage(&self, name: &str, steps: Option<u64>) {
            self.0.lock().unwrap().push(format!("{name} {steps:?}"));
        }
        fn step(&self) {
            self.0.lock().unwrap().push("step".into());
        }
    }

    #[test]
    fn an_observer_sees_its_closure_only_and_nests() {
        let outer = Arc::new(Record::default());
        let inner = Arc::new(Record::default());
        stage("before", None);
        observe(outer.clone(), || {
            stage("a", Some(2));
            observe(inner.clone(), || stage("b", None));
            stage("c", None);
        });
        stage("after", None);
        assert_eq!(*outer.0.lock().unwrap(), ["a Some(2)", "c None"]);
        assert_eq!(*inner.0.lock().unwrap(), ["b None"]);
        assert!(current().is_none());
    }
}
