//! `trailprint fit`: the kernel hyperparameters of SPEC section 2.

use clap::Args as ClapArgs;
use trailprint::gp::fit_kernel;
use trailprint::store::{FitRecord, now_ms};
use trailprint::{Error, Result};

use crate::opts::{BuildingOpts, json_line};

#[derive(ClapArgs, Debug)]
pub struct Args {
    #[command(flatten)]
    building: BuildingOpts,
    /// Print one JSON object.
    #[arg(long)]
    json: bool,
}

pub fn run(a: Args, db: Option<&std::path::Path>) -> Result<()> {
    let b = a.building.load(db)?;
    if b.pilot.is_empty() {
        // An imported floor plan has none: say how to add them, or how to do without.
        return Err(Error::InvalidRequest(format!(
            "{:?} has no pilot fingerprints to fit the kernel on: add them with \
             `trailprint pilot add {:?} FILE.json` (a JSON list of {{\"x\", \"y\", \"floor\", \
             \"rss\"}}), or plan with `--kernel SF2,ELL,SN2`",
            b.name, b.name
        )));
    }
    let fit = fit_kernel(&b.pilot).map_err(|e| crate::opts::hint(e, &b))?;
    // A building of the database keeps its fit there (`trailprint buildings` counts it;
    // `demo` reuses the latest); a file has nowhere to keep it.
    let fit_id = if crate::store_cli::is_file_spec(&a.building.building) {
        None
    } else {
        let store = crate::store_cli::open_store(db)?;
        let bref = crate::store_cli::building_ref(&store, &a.building.building)?;
        Some(store.record_fit(bref, &FitRecord::from_fit(&fit, now_ms()))?)
    };
    if a.json {
        let out = serde_json::json!({
            "building": b.name,
            "sf2": fit.kernel.sf2,
            "ell": fit.kernel.ell,
            "sn2": fit.kernel.sn2,
            "log_likelihood": fit.log_likelihood,
            "aps_used": fit.aps_used,
            "ap_rule": fit.ap_rule,
            "locations": fit.locations,
            "fit_id": fit_id,
        });
        println!("{}", json_line(&out)?);
    } else {
        println!("building        {}", crate::store_cli::printable(&b.name));
        println!("sf2             {:.4} dB²", fit.kernel.sf2);
        println!("ell             {:.4} m", fit.kernel.ell);
        println!("sn2             {:.4} dB²", fit.kernel.sn2);
        println!("log_likelihood  {:.4}", fit.log_likelihood);
        println!(
            "aps_used        {} ({})",
            fit.aps_used.len(),
            fit.aps_used.join(", ")
        );
        println!("ap_rule         {}", fit.ap_rule.describe());
        println!("locations       {}", fit.locations);
        match fit_id {
            Some(id) => println!("stored          as fit {id} of this building in the database"),
            None => println!("stored          no (a file; import it to keep fits and plans)"),
        }
    }
    Ok(())
}
