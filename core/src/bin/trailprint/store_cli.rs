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
        Some(path) => Store::open(path),
        None => {
            let path = default_db_path()?;
            if let Some(dir) = path.parent() {
                std::fs::create_dir_all(dir).map_err(|e| Error::io(dir, e))?;
            }
            Store::open(&path)
        }
    }
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

/// Writes `text` to `path` (`-`: standard output) so that a kill never leaves half a file:
/// a temporary file beside it, flushed to disk, then renamed over it.
pub fn write_output(path: &Path, text: &str) -> Result<()> {
    if path == Path::new("-") {
        let mut out = std::io::stdout().lock();
        return out
            .write_all(text.as_bytes())
            .and_then(|()| out.flush())
            .map_err(|e| Error::io("<stdout>", e));
    }
    let dir = match path.parent() {
        Some(d) if !d.as_os_str().is_empty() => d.to_path_buf(),
        _ => PathBuf::from("."),
    };
    let file_name = path
        .file_name()
        .map(|n| n.to_string_lossy().into_owned())
        .unwrap_or_else(|| "output".into());
    let tmp = dir.join(format!(".{file_name}.{}.tmp", std::process::id()));
    let result = (|| {
        let mut f = std::fs::File::create(&tmp)?;
        f.write_all(text.as_bytes())?;
        f.sync_all()?;
        std::fs::rename(&tmp, path)
    })();
    result.map_err(|e| {
        let _ = std::fs::remove_file(&tmp);
        Error::io(path, e)
    })
}

/// Everything collected so far in `spec`'s building (nothing for a building read from a
/// file); see [`trailprint::Store::collected_observations`].
pub fn collected_prior(
    spec: &str,
    db: Option<&Path>,
    kernel: &trailprint::gp::Kernel,
) -> Result<Vec<trailprint::utility::Observation>> {
    if is_file_spec(spec) {
        return Ok(Vec::new());
    }
    let store = open_store(db)?;
    let bref = building_ref(&store, spec)?;
    store.collected_observations(bref, kernel)
}
