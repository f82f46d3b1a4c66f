//! The one public error type. Kotlin sees it as `TrailprintException` with one subclass per
//! variant; each variant is something the app can act on, and its message is the core's
//! message, which names the file, JSON path, vertex id or value that is wrong.

/// Everything a Trailprint call can fail with, grouped by what the app should do about it.
#[derive(Debug, thiserror::Error, uniffi::Error)]
#[uniffi(flat_error)]
pub enum TrailprintError {
    /// A file could not be read or written (show the path; ask for another file).
    #[error("{0}")]
    Io(String),
    /// A building file that does not parse or breaks a rule (show the message; the file
    /// must be fixed).
    #[error("{0}")]
    InvalidBuilding(String),
    /// A request with a bad argument: unknown vertex, bad budget, bad surveyor model, a
    /// walk that does not follow the edges (fix the form).
    #[error("{0}")]
    InvalidRequest(String),
    /// The end cannot be reached from the start within the budget (raise the budget; the
    /// message gives the shortest length).
    #[error("{0}")]
    Unreachable(String),
    /// The time limit cannot hold one exact evaluation of a walk that uses the budget (a
    /// robot's long walk on a large floor): nothing was planned. The message names the
    /// time needed and ends "raise the time limit (...) to N s or more, or plan a budget
    /// of about M m"; offer to plan again with N seconds, or with the smaller budget.
    #[error("{0}")]
    TimeLimitTooShort(String),
    /// The kernel cannot be fitted on the building's pilot data (give a kernel or more
    /// pilot data).
    #[error("{0}")]
    Fit(String),
    /// The operation was cancelled through its cancel handle (nothing to show).
    #[error("{0}")]
    Cancelled(String),
    /// A building of that name is already stored (offer to replace it).
    #[error("{0}")]
    AlreadyExists(String),
    /// Something looked up by id is not in the store (refresh the list).
    #[error("{0}")]
    NotFound(String),
    /// The database file is unusable: not SQLite, newer schema, read-only, corrupt
    /// (offer to choose another file).
    #[error("{0}")]
    Database(String),
    /// A survey event that the session cannot accept in its state (for example a scan
    /// after finish).
    #[error("{0}")]
    Session(String),
    /// A numerical or internal failure (report a bug).
    #[error("{0}")]
    Internal(String),
}

impl From<trailprint::Error> for TrailprintError {
    fn from(e: trailprint::Error) -> Self {
        use trailprint::Error as E;
        let msg = e.to_string();
        match e {
            E::Io { .. } => TrailprintError::Io(msg),
            E::Parse { .. } | E::InvalidBuilding { .. } => TrailprintError::InvalidBuilding(msg),
            E::InvalidWalk { .. } | E::InvalidRequest(_) => TrailprintError::InvalidRequest(msg),
            E::TimeLimitTooShort { .. } => TrailprintError::TimeLimitTooShort(msg),
            E::Unreachable { .. } => TrailprintError::Unreachable(msg),
            E::Fit(_) => TrailprintError::Fit(msg),
            E::Cancelled => TrailprintError::Cancelled(msg),
            E::NotFound(_) => TrailprintError::NotFound(msg),
            E::AlreadyExists(_) => TrailprintError::AlreadyExists(msg),
            E::Database { .. } => TrailprintError::Database(msg),
            E::Session { .. } => TrailprintError::Session(msg),
            E::Numerical(_) | E::Sqlite(_) => TrailprintError::Internal(msg),
        }
    }
}

/// Result alias of the exported functions.
pub type Result<T, E = TrailprintError> = std::result::Result<T, E>;

#[cfg(test)]
mod tests {
    use super::TrailprintError as T;
    use trailprint::Error as E;

    #[test]
    fn every_core_error_maps_to_the_variant_the_app_acts_on_and_keeps_its_message() {
        let io = std::io::Error::new(std::io::ErrorKind::NotFound, "gone");
        type IsVariant = fn(&T) -> bool;
        let cases: Vec<(E, IsVariant)> = vec![
            (E::io("/x/b.json", io), |t| matches!(t, T::Io(_))),
            (
                E::Parse {
                    origin: "b.json".into(),
                    path: "vertices[0].x".into(),
                    message: "bad".into(),
                },
                |t| matches!(t, T::InvalidBuilding(_)),
            ),
            (
                E::invalid("b.json", "edges[1].a", "unknown vertex \"q\""),
                |t| matches!(t, T::InvalidBuilding(_)),
            ),
            (
                E::InvalidWalk {
                    step: 2,
                    message: "no edge".into(),
                },
                |t| matches!(t, T::InvalidRequest(_)),
            ),
            (E::InvalidRequest("budget".into()), |t| {
                matches!(t, T::InvalidRequest(_))
            }),
            (
                E::Unreachable {
                    start: "a".into(),
                    end: "b".into(),
                    budget: 1.0,
                    shortest: 2.0,
                },
                |t| matches!(t, T::Unreachable(_)),
            ),
            (
                E::TimeLimitTooShort {
                    needed: std::time::Duration::from_secs(4),
                    message: "raise the time limit (--time-limit) to 6 s or more".into(),
                },
                |t| matches!(t, T::TimeLimitTooShort(_)),
            ),
            (E::Fit("few".into()), |t| matches!(t, T::Fit(_))),
            (E::Cancelled, |t| matches!(t, T::Cancelled(_))),
            (E::NotFound("plan 3".into()), |t| {
                matches!(t, T::NotFound(_))
            }),
            (E::AlreadyExists("building \"A\"".into()), |t| {
                matches!(t, T::AlreadyExists(_))
            }),
            (
                E::Database {
                    path: "/d.db".into(),
                    message: "newer".into(),
                },
                |t| matches!(t, T::Database(_)),
            ),
            (
                E::Session {
                    session: 4,
                    message: "finished".into(),
                },
                |t| matches!(t, T::Session(_)),
            ),
            (E::Numerical("not PD".into()), |t| {
                matches!(t, T::Internal(_))
            }),
        ];
        for (e, is) in cases {
            let msg = e.to_string();
            let t = T::from(e);
            assert!(is(&t), "{msg} mapped to {t:?}");
            assert_eq!(t.to_string(), msg);
        }
    }
}
