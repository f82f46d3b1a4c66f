//! The one error type of the core.
//!
//! Every message names the thing that is wrong (file, JSON path, vertex id, value) and,
//! where it helps, what would be right. The bindings map this enum onto their smaller
//! public error in exactly one `From` impl.

use std::path::PathBuf;

/// Result alias used throughout the core.
pub type Result<T, E = Error> = std::result::Result<T, E>;

/// Everything that can go wrong in the core.
#[derive(Debug, thiserror::Error)]
pub enum Error {
    /// A file could not be read or written.
    #[error("{path}: {source}")]
    Io {
        path: PathBuf,
        #[source]
        source: std::io::Error,
    },

    /// JSON that does not parse, or does not have the expected shape.
    #[error("{origin}: {}{message}", at(.path))]
    Parse {
        /// File name or other origin of the text (for example `<stdin>`).
        origin: String,
        /// JSON path of the offending value (`$` for the document itself).
        path: String,
        message: String,
    },

    /// A building that parses but breaks a rule of SPEC section 1 or 7.
    #[error("{origin}: {}{message}", at(.path))]
    InvalidBuilding {
        origin: String,
        path: String,
        message: String,
    },

    /// A walk that is not a walk of the building (unknown vertex, missing edge).
    #[error("invalid walk at step {step}: {message}")]
    InvalidWalk { step: usize, message: String },

    /// Pilot data that cannot support a hyperparameter fit, or a fit that failed.
    #[error("cannot fit the kernel: {0}")]
    Fit(String),

    /// A request that does not make sense (bad budget, unknown vertex, bad option).
    #[error("{0}")]
    InvalidRequest(String),

    /// The end vertex cannot be reached from the start within the budget.
    #[error(
        "no walk from {start} to {end} fits the budget of {budget} m (shortest is {shortest:.3} m)"
    )]
    Unreachable {
        start: String,
        end: String,
        budget: f64,
        shortest: f64,
    },

    /// A numerical failure (a matrix that is not positive definite, a non-finite value).
    #[error("numerical failure: {0}")]
    Numerical(String),

    /// A time limit too short for the answer: on a large building one exact evaluation
    /// of a walk that uses the budget (SPEC 3, the only utility a plan reports) takes
    /// longer than the limit leaves. `needed` is about what the plan would take; a caller
    /// that prefers a late answer to none (a survey session's replan) may retry with it.
    #[error("{message}")]
    TimeLimitTooShort {
        needed: std::time::Duration,
        message: String,
    },

    /// A long computation was cancelled by its caller.
    #[error("cancelled")]
    Cancelled,

    /// Something was looked up in the store and is not there.
    #[error("not found: {0}")]
    NotFound(String),

    /// Something is already in the store under this name (for example a building, on an
    /// import without `replace`); the app can offer to replace it.
    #[error("already exists: {0}")]
    AlreadyExists(String),

    /// The database file is not usable (not SQLite, newer schema, read-only, corrupt).
    #[error("database {path}: {message}")]
    Database { path: String, message: String },

    /// An SQLite error from inside a store operation.
    #[error("sqlite: {0}")]
    Sqlite(#[from] rusqlite::Error),

    /// A survey-session event that cannot be accepted in the session's state.
    #[error("session {session}: {message}")]
    Session { session: i64, message: String },
}

/// `path: ` before a message, or nothing for the document itself (`$`): the file's name
/// already says which document.
fn at(path: &str) -> String {
    if path == "$" || path.is_empty() {
        String::new()
    } else {
        format!("{path}: ")
    }
}

impl Error {
    /// Convenience constructor for a building rule violation.
    pub fn invalid(origin: &str, path: impl Into<String>, message: impl Into<String>) -> Self {
        Error::InvalidBuilding {
            origin: origin.to_string(),
            path: path.into(),
            message: message.into(),
        }
    }

    /// Convenience constructor for an I/O error on a path.
    pub fn io(path: impl Into<PathBuf>, source: std::io::Error) -> Self {
        Error::Io {
            path: path.into(),
            source,
        }
    }
}

/// The first of `fields` (a name and its value) that is not a finite number `>= 0`: the one
/// rule of the option checks (session, evaluation, propagation), each of which words its
/// own message.
pub(crate) fn first_negative<'a>(
    fields: impl IntoIterator<Item = (&'a str, f64)>,
) -> Option<(&'a str, f64)> {
    fields.into_iter().find(|&(_, v)| !v.is_finite() || v < 0.0)
}
