//! Helpers shared by every command that touches the database: where it lives, opening it,
//! loading a building from a file or from the database, and writing output files safely.

use std::io::Write;
use std::path::{Path, PathBuf};

use trailprint::store::{BuildingRef, Store, read_import_text};
use trailprint::{Building, Error, Result};

/// The default database: `$XDG_DATA_HOME/trailprint/trailprint.db`, or
/// `$HOME/.local/share/trailprint/trailprint.db` (the XDG default) when XDG_DATA_HOME is
/// unset or not absolute, as the XDG Base Directory specification says.
pub fn default_db_path() -> Result<PathBuf> {
    let base = match std::env::var_os("XDG_DATA_HOME").map(PathBuf::from) {
        Some(p) if p.is_absolute() => p,
        _ => match std::env::var_os("HOME") {
            Some(home) if !home.is_empty() => PathBuf::from(home).join(".local").join("share"),
            _ => {
                return Err(Error::InvalidRequest(
                    "no data directory: neither XDG_DATA_HOME nor HOME is set; pass --db PATH"
                        .into(),
                ));
            }
        },
    };
    Ok(base.join("trailprint").join("trailprint.db"))
}

/// Opens the database given by `--db`, or the default one (creating its directory on first
/// use; an explicit `--db` directory must exist).
pub fn open_store(db: Option<&Path>) -> Result<Store> {
    match db {
        Some(path) => {
            check_db_path(path)?;
            Store::open(path)
        }
        None => {
            let path = default_db_path()?;
            if let Some(dir) = path.parent() {
                std::fs::create_dir_all(dir).map_err(|e| Error::io(dir, e))?;
            }
            Store::open(&path)
        }
    }
}

/// Refuses a `--db` that is a directory (SQLite would say "unable to open database file"),
/// naming a file inside it that would do.
pub fn check_db_path(path: &Path) -> Result<()> {
    if path.is_dir() {
        return Err(Error::InvalidRequest(format!(
            "--db {}: is a directory; --db takes the database file, for example --db {}",
            path.display(),
            path.join("trailprint.db").display()
        )));
    }
    Ok(())
}

/// Whether `spec` names a building file rather than a building in the database: an existing
/// file, or anything ending in `.json`, or `-` (standard input).
pub fn is_file_spec(spec: &str) -> bool {
    spec == "-" || spec.ends_with(".json") || Path::new(spec).is_file()
}

/// A building given on the command line, either as a file (path, `-`) or as the name of a
/// building in the database (then by store id if no name matches and `spec` is a number).
/// Commands such as fit, utility and plan take their building through this.
pub fn load_building(spec: &str, db: Option<&Path>) -> Result<Building> {
    if is_file_spec(spec) {
        let path = Path::new(spec);
        let origin = if spec == "-" {
            "<stdin>".to_string()
        } else {
            spec.to_string()
        };
        let text = read_import_text(path)?;
        return Building::from_json(&text, &origin);
    }
    let store = open_store(db)?;
    building_in_store(&store, spec)
}

/// A building of the store by name, or by id if `spec` is a number that no name matches.
/// The error lists the names that are there.
pub fn building_in_store(store: &Store, spec: &str) -> Result<Building> {
    match store.get_building(BuildingRef::Name(spec)) {
        Err(Error::NotFound(_)) => {
            if let Ok(id) = spec.parse::<i64>()
                && let Ok(b) = store.get_building(BuildingRef::Id(id))
            {
                return Ok(b);
            }
            let names: Vec<String> = store
                .list_buildings()?
                .into_iter()
                .map(|b| format!("{:?}", b.name))
                .collect();
            let db = store
                .path()
                .map_or_else(|| ":memory:".into(), |p| p.display().to_string());
            Err(Error::NotFound(if names.is_empty() {
                format!(
                    "no file and no building named {spec:?} (the database {db} holds no buildings)"
                )
            } else {
                format!(
                    "no file and no building named {spec:?}; buildings in {db}: {}",
                    names.join(", ")
                )
            }))
        }
        other => other,
    }
}

/// Resolves a building name (or number) of the store to a reference, with the same rules
/// and errors as [`building_in_store`].
pub fn building_ref<'a>(store: &Store, spec: &'a str) -> Result<BuildingRef<'a>> {
    match store.building_info(BuildingRef::Name(spec)) {
        Ok(info) => Ok(BuildingRef::Id(info.id)),
        Err(Error::NotFound(_)) => building_in_store(store, spec)
            .and_then(|b| store.building_info(BuildingRef::Name(&b.name)))
            .map(|info| BuildingRef::Id(info.id)),
        Err(e) => Err(e),
    }
}

/// Writes `text` to `path` (`-`: standard output), the one writer of every `-o` option.
///
/// A regular file (or a new one) is replaced whole, so a kill never leaves half a file: the
/// text goes to a temporary file beside it, created with `create_new` under a random name
/// (a file or symlink planted under a predictable name cannot be written through),
/// flushed to disk and renamed over the target, which keeps its permissions. A target that
/// exists and is not a regular file (a FIFO, `/dev/null`, a terminal) is written straight
/// into: replacing it with a regular file would break whatever reads it.
pub fn write_output(path: &Path, text: &str) -> Result<()> {
    use std::fs::OpenOptions;
    if path == Path::new("-") {
        let mut out = std::io::stdout().lock();
        return out
            .write_all(text.as_bytes())
            .and_then(|()| out.flush())
            .map_err(|e| Error::io("<stdout>", e));
    }
    // Follows a symlink: a link to a FIFO is written into like the FIFO.
    let existing = std::fs::metadata(path).ok();
    if let Some(meta) = &existing
        && !meta.is_file()
    {
        if meta.is_dir() {
            return Err(Error::io(
                path,
                std::io::Error::new(
                    std::io::ErrorKind::IsADirectory,
                    "is a directory, not a file to write",
                ),
            ));
        }
        let mut f = OpenOptions::new()
            .write(true)
            .open(path)
            .map_err(|e| Error::io(path, e))?;
        return f
            .write_all(text.as_bytes())
            .and_then(|()| f.flush())
            .map_err(|e| Error::io(path, e));
    }
    let dir = match path.parent() {
        Some(d) if !d.as_os_str().is_empty() => d.to_path_buf(),
        _ => PathBuf::from("."),
    };
    let file_name = path
        .file_name()
        .map(|n| n.to_string_lossy().into_owned())
        .unwrap_or_else(|| "output".into());
    let (tmp, mut f) = create_temporary(&dir, &file_name).map_err(|e| Error::io(path, e))?;
    let result = (|| {
        f.write_all(text.as_bytes())?;
        if let Some(meta) = &existing {
            f.set_permissions(meta.permissions())?;
        }
        f.sync_all()?;
        drop(f);
        std::fs::rename(&tmp, path)?;
        // The rename itself reaches the disk with the directory (best effort: some file
        // systems cannot sync a directory).
        if let Ok(d) = std::fs::File::open(&dir) {
            let _ = d.sync_all();
        }
        Ok::<(), std::io::Error>(())
    })();
    result.map_err(|e| {
        let _ = std::fs::remove_file(&tmp);
        Error::io(path, e)
    })
}

/// A new file `.<name>.<random>.tmp` in `dir`, created with `create_new` (never an existing
/// file, never through a symlink). The random part is an identifier, not a modelling choice,
/// so it comes from the operating system's entropy rather than a seed.
fn create_temporary(dir: &Path, name: &str) -> std::io::Result<(PathBuf, std::fs::File)> {
    use rand::RngExt;
    let mut rng = rand::rng();
    let mut last = None;
    for _ in 0..16 {
        let tag: u64 = rng.random();
        let tmp = dir.join(format!(".{name}.{tag:016x}.tmp"));
        match std::fs::OpenOptions::new()
            .write(true)
            .create_new(true)
            .open(&tmp)
        {
            Ok(f) => return Ok((tmp, f)),
            Err(e) if e.kind() == std::io::ErrorKind::AlreadyExists => last = Some(e),
            Err(e) => return Err(e),
        }
    }
    Err(last.unwrap_or_else(|| std::io::Error::other("no free temporary file name")))
}

/// A name from the database (or a file) made safe to print on a terminal: control
/// characters, escape sequences and invisible format characters (bidirectional overrides,
/// zero-width characters) are written as Rust escapes (`\u{1b}`), as `{:?}` does, so a
/// building named with terminal escape sequences cannot clear the screen or hide text.
/// Quotes are kept as they are (the table of `trailprint buildings` prints names bare).
pub fn printable(name: &str) -> String {
    name.escape_debug()
        .to_string()
        .replace("\\\"", "\"")
        .replace("\\'", "'")
}

/// A vertex label as a table cell: [`printable`], `-` for none, cut to `width` characters.
pub fn label_cell(label: Option<&str>, width: usize) -> String {
    label
        .map_or_else(|| "-".into(), printable)
        .chars()
        .take(width)
        .collect()
}

/// The width of a table column: its widest cell in characters, at least `min` (the
/// header's width).
pub fn column_width<S: AsRef<str>>(cells: impl IntoIterator<Item = S>, min: usize) -> usize {
    cells
        .into_iter()
        .map(|c| c.as_ref().chars().count())
        .max()
        .unwrap_or(min)
        .max(min)
}
