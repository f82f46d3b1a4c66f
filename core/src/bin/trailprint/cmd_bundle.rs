//! `trailprint bundle export|import`: move collected surveys between devices as files.

use std::path::{Path, PathBuf};

use clap::{Args as ClapArgs, Subcommand};
use trailprint::store::{ExportOptions, read_bundle_text};
use trailprint::{Error, Result};

use crate::opts::json_line;

#[derive(ClapArgs, Debug)]
pub struct Args {
    #[command(subcommand)]
    action: Action,
}

#[derive(Subcommand, Debug)]
enum Action {
    /// Write a building's survey sessions (or some of them) to one bundle file.
    Export {
        /// The building (name or id in the database).
        #[arg(long)]
        building: String,
        /// Only this session id (repeatable); default: every session of the building.
        #[arg(long = "session")]
        sessions: Vec<i64>,
        /// This device's name, recorded as provenance.
        #[arg(long)]
        device: Option<String>,
        /// The surveyor's name, recorded as provenance.
        #[arg(long)]
        surveyor: Option<String>,
        /// Output file.
        #[arg(short, long)]
        out: PathBuf,
    },
    /// Merge bundle files into the database (idempotent, in any order).
    Import {
        /// Bundle files.
        #[arg(required = true)]
        files: Vec<PathBuf>,
        /// Print one JSON object per bundle.
        #[arg(long)]
        json: bool,
    },
}

pub fn run(a: Args, db: Option<&Path>) -> Result<()> {
    let store = crate::store_cli::open_store(db)?;
    match a.action {
        Action::Export {
            building,
            sessions,
            device,
            surveyor,
            out,
        } => {
            let bref = crate::store_cli::building_ref(&store, &building)?;
            let text = store.export_bundle(
                bref,
                &ExportOptions {
                    device,
                    surveyor_name: surveyor,
                    sessions,
                },
            )?;
            crate::store_cli::write_output(&out, &text)?;
            println!("wrote bundle {} ({} bytes)", out.display(), text.len());
        }
        Action::Import { files, json } => {
            for f in files {
                let text = read_bundle_text(&f)?;
                let r = store
                    .import_bundle(&text, &f.display().to_string())
                    .map_err(|e| match e {
                        Error::Parse { .. }
                        | Error::InvalidRequest(_)
                        | Error::InvalidBuilding { .. } => e,
                        other => Error::InvalidRequest(format!("{}: {other}", f.display())),
                    })?;
                if json {
                    println!("{}", json_line(&r)?);
                } else {
                    println!(
                        "{}: building {:?}{}, {} sessions added, {} extended, {} unchanged, {} events added",
                        f.display(),
                        r.building,
                        if r.building_created { " (created)" } else { "" },
                        r.sessions_added,
                        r.sessions_extended,
                        r.sessions_unchanged,
                        r.events_added
                    );
                }
            }
        }
    }
    Ok(())
}
