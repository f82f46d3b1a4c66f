//! `trailprint delete NAME [--force]`: a building and everything recorded for it.

use std::path::Path;

use trailprint::Error;

use crate::store_cli::{building_ref, open_store};

#[derive(clap::Args)]
pub struct Args {
    /// Building name (or store id)
    name: String,
    /// Also delete its plans, survey sessions and collected fingerprints (without it, a
    /// building with any of them is refused and nothing is deleted)
    #[arg(long)]
    force: bool,
}

/// `n thing` or `n things`.
fn count(n: u64, thing: &str) -> String {
    format!("{n} {thing}{}", if n == 1 { "" } else { "s" })
}

pub fn run(args: &Args, db: Option<&Path>) -> trailprint::Result<()> {
    let store = open_store(db)?;
    let building = building_ref(&store, &args.name)?;
    let force = args.force;
    // The check runs inside the delete's transaction: a session another process adds
    // meanwhile cannot slip past it.
    let info = store.delete_building_checked(building, |info| {
        if force || (info.plans == 0 && info.sessions == 0 && info.collected == 0) {
            return Ok(());
        }
        Err(Error::InvalidRequest(format!(
            "building {} {:?} has {}, {} and {}: deleting it deletes them too; nothing was \
             deleted (export the survey data with `trailprint bundle export` first, then \
             pass --force)",
            info.id,
            info.name,
            count(info.plans, "plan"),
            count(info.sessions, "survey session"),
            count(info.collected, "collected fingerprint")
        )))
    })?;
    println!(
        "deleted building {} {:?} with its {}, {}, {} and {}",
        info.id,
        info.name,
        count(info.fits, "fit"),
        count(info.plans, "plan"),
        count(info.sessions, "session"),
        count(info.collected, "collected fingerprint")
    );
    Ok(())
}
