//! `trailprint pilot add NAME FILE.json`: pilot fingerprints for a building that has none
//! (one imported from a floor plan), so that `plan` can fit its kernel.

use std::path::{Path, PathBuf};

use trailprint::building::Fingerprint;
use trailprint::store::{BuildingRef, read_import_text};
use trailprint::{Building, Error, Result};

use crate::store_cli::{building_ref, is_file_spec, open_store, write_output};

#[derive(clap::Subcommand)]
pub enum Command {
    /// Add pilot fingerprints (the SPEC 7 `pilot` list) to a building
    Add(AddArgs),
}

#[derive(clap::Args)]
pub struct AddArgs {
    /// Building name (or store id) in the database, or a building file, which is
    /// rewritten with the pilot data added
    name: String,
    /// Pilot fingerprints: a JSON array `[{"x", "y", "floor", "rss": {...}}, ...]`, or an
    /// object with such a `pilot` array (a building file's); `-` reads standard input
    file: PathBuf,
}

#[derive(clap::Args)]
pub struct Args {
    #[command(subcommand)]
    command: Command,
}

/// Reads a pilot list; type errors carry the JSON path (`[3].rss.ap-01`).
fn read_pilot(path: &Path) -> Result<Vec<Fingerprint>> {
    let origin = if path == Path::new("-") {
        "<stdin>".to_string()
    } else {
        path.display().to_string()
    };
    let text = read_import_text(path)?;
    let parse_err = |path: String, message: String| Error::Parse {
        origin: origin.clone(),
        path,
        message,
    };
    let value: serde_json::Value = serde_json::from_str(&text).map_err(|e| {
        let what = trailprint::building::not_json_object(&text)
            .unwrap_or_else(|| format!("its JSON does not parse ({e})"));
        parse_err(
            "$".into(),
            format!(
                "not a JSON pilot list: {what} (a JSON array of {{\"x\", \"y\", \"floor\", \
                 \"rss\": {{AP: dBm}}}}, or a building file's {{\"pilot\": [...]}})"
            ),
        )
    })?;
    let (list, prefix) = match value {
        serde_json::Value::Array(_) => (value, ""),
        serde_json::Value::Object(mut m) => match m.remove("pilot") {
            Some(v) => (v, "pilot"),
            None => {
                return Err(parse_err(
                    "$".into(),
                    "expected a JSON array of fingerprints or an object with a `pilot` array"
                        .into(),
                ));
            }
        },
        _ => {
            return Err(parse_err(
                "$".into(),
                "expected a JSON array of fingerprints or an object with a `pilot` array".into(),
            ));
        }
    };
    let pilot: Vec<Fingerprint> = serde_path_to_error::deserialize(list).map_err(|e| {
        let p = e.path().to_string();
        parse_err(
            if p == "." {
                format!("{prefix}$")
            } else {
                format!("{prefix}{p}")
            },
            e.into_inner().to_string(),
        )
    })?;
    if pilot.is_empty() {
        return Err(parse_err(
            prefix_or(prefix),
            "the pilot list is empty".into(),
        ));
    }
    Ok(pilot)
}

fn prefix_or(prefix: &str) -> String {
    if prefix.is_empty() {
        "$".into()
    } else {
        prefix.into()
    }
}

pub fn run(args: Args, db: Option<&Path>) -> Result<()> {
    let Command::Add(a) = args.command;
    let pilot = read_pilot(&a.file)?;
    if is_file_spec(&a.name) && a.name != "-" {
        let path = Path::new(&a.name);
        let mut file = trailprint::building::BuildingFile::read(path)?;
        let before = file.pilot.len();
        file.pilot.extend(pilot);
        let b = Building::from_file(file, &a.name)?;
        let mut text = b.to_file().to_json();
        text.push('\n');
        write_output(path, &text)?;
        println!(
            "added {} pilot fingerprints to {} ({} in all)",
            b.pilot.len() - before,
            path.display(),
            b.pilot.len()
        );
        return Ok(());
    }
    let store = open_store(db)?;
    let bref = building_ref(&store, &a.name)?;
    let n = pilot.len();
    let total = store.add_pilot(bref, &pilot, &a.file.display().to_string())?;
    let name = match bref {
        BuildingRef::Id(id) => store.building_info(id)?.name,
        BuildingRef::Name(n) => n.to_string(),
    };
    println!("added {n} pilot fingerprints to building {name:?} ({total} in all)");
    Ok(())
}
