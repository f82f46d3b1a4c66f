//! Live planning progress on stderr and Ctrl-C as "stop and give me the best so far".
//!
//! `plan` and `team-plan` show the best utility, the length it uses and the time elapsed
//! while they search, on stderr only (stdout stays the result, so `--json` output is
//! untouched): redrawn in place on a terminal, one line every half second with
//! `--progress` when stderr is a file or a pipe. The first Ctrl-C cancels the plan, which
//! then returns its best walk so far (`termination: cancelled`) and is printed and saved
//! like any other; a second Ctrl-C ends the process.

use std::io::{IsTerminal, Write};
use std::sync::Arc;
use std::sync::Mutex;
use std::sync::atomic::{AtomicBool, AtomicUsize, Ordering};
use std::time::{Duration, Instant};

use trailprint::plan::{Control, Observer, Progress};

/// Ctrl-C presses seen (the handler only counts; a watcher thread acts).
static INTERRUPTS: AtomicUsize = AtomicUsize::new(0);

#[cfg(unix)]
extern "C" fn on_sigint(_: libc::c_int) {
    if INTERRUPTS.fetch_add(1, Ordering::SeqCst) >= 1 {
        // Second press: the default action (only async-signal-safe calls here).
        // SAFETY: restoring the default disposition and re-raising is async-signal-safe.
        unsafe {
            libc::signal(libc::SIGINT, libc::SIG_DFL);
            libc::raise(libc::SIGINT);
        }
    }
}

/// Prints progress reports on stderr, at most every `every`.
struct StderrObserver {
    started: Instant,
    tty: bool,
    every: Duration,
    last: Mutex<Option<Instant>>,
    drawn: AtomicBool,
}

impl Observer for StderrObserver {
    fn progress(&self, p: &Progress) {
        let now = Instant::now();
        {
            let Ok(mut last) = self.last.lock() else {
                return;
            };
            if last.is_some_and(|t| now.duration_since(t) < self.every) && p.fraction < 1.0 {
                return;
            }
            *last = Some(now);
        }
        let best = p
            .best_utility
            .map_or("-".to_string(), |u| format!("{u:.2} nats"));
        let len = p
            .best_length
            .map_or(String::new(), |l| format!(", {l:.0} m"));
        let line = format!(
            "planning {:>5.1} s  best {best}{len}  ({}: {})",
            self.started.elapsed().as_secs_f64(),
            p.algorithm,
            p.message
        );
        let mut err = std::io::stderr().lock();
        if self.tty {
            // Redraw in place; cut to 100 columns so that the line never wraps.
            let cut: String = line.chars().take(100).collect();
            let _ = write!(err, "\r\x1b[2K{cut}");
            self.drawn.store(true, Ordering::Relaxed);
        } else {
            let _ = writeln!(err, "{line}");
        }
        let _ = err.flush();
    }
}

/// What a planning command holds while it plans: the control to pass to the planner.
pub struct Live {
    pub control: Control,
    observer: Option<Arc<StderrObserver>>,
    done: Arc<AtomicBool>,
}

impl Live {
    /// A control that Ctrl-C cancels, with a stderr progress observer when stderr is a
    /// terminal or `force` is set.
    pub fn start(force: bool) -> Self {
        let tty = std::io::stderr().is_terminal();
        let observer = (tty || force).then(|| {
            Arc::new(StderrObserver {
                started: Instant::now(),
                tty,
                every: if tty {
                    Duration::from_millis(100)
                } else {
                    Duration::from_millis(500)
                },
                last: Mutex::new(None),
                drawn: AtomicBool::new(false),
            })
        });
        let mut control = Control::new();
        if let Some(o) = &observer {
            control = control.with_observer(o.clone());
        }
        let done = Arc::new(AtomicBool::new(false));
        #[cfg(unix)]
        {
            INTERRUPTS.store(0, Ordering::SeqCst);
            // SAFETY: installing a handler that only touches an atomic counter.
            unsafe {
                libc::signal(
                    libc::SIGINT,
                    on_sigint as extern "C" fn(libc::c_int) as libc::sighandler_t,
                );
            }
            let token = control.cancel_token();
            let done2 = done.clone();
            std::thread::spawn(move || {
                while !done2.load(Ordering::Relaxed) {
                    if INTERRUPTS.load(Ordering::SeqCst) > 0 {
                        token.store(true, Ordering::Relaxed);
                        eprintln!(
                            "\ninterrupted: stopping with the best walk so far (Ctrl-C again to quit)"
                        );
                        return;
                    }
                    std::thread::sleep(Duration::from_millis(20));
                }
            });
        }
        Live {
            control,
            observer,
            done,
        }
    }

    /// Ends the progress line (a newline after an in-place line) and the Ctrl-C watcher.
    pub fn finish(&self) {
        self.done.store(true, Ordering::Relaxed);
        if let Some(o) = &self.observer
            && o.drawn.load(Ordering::Relaxed)
        {
            eprintln!();
        }
        #[cfg(unix)]
        // SAFETY: restoring the default disposition.
        unsafe {
            libc::signal(libc::SIGINT, libc::SIG_DFL);
        }
    }
}
