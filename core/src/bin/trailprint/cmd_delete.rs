//! `trailprint delete NAME`: a building and everything recorded for it.

use std::path::Path;

use crate::store_cli::{building_ref, open_store};

#[derive(clap::Args)]
pub struct Args {
    /// Building name (or store id)
    name: String,
}

pub fn run(args: &Args, db: Option<&Path>) -> trailprint::Result<()> {
    let store = open_store(db)?;
    let building = building_ref(&store, &args.name)?;
    let info = store.delete_building(building)?;
    println!(
        "deleted building {} {:?} with its {} fits, {} plans, {} sessions and {} collected fingerprints",
        info.id, info.name, info.fits, info.plans, info.sessions, info.collected
    );
    Ok(())
}
