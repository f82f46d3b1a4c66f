//! `trailprint demo`: the main job on a fresh machine. Creates (or opens) the database,
//! loads the bundled demo building if it is not there yet, fits the kernel (or reuses the
//! stored fit), plans a survey walk, saves the plan and prints it.

use std::path::Path;
use std::sync::Arc;

use clap::Args as ClapArgs;
use trailprint::building::Building;
use trailprint::gp::fit_kernel;
use trailprint::plan::{Algorithm, PlanRequest, plan};
use trailprint::store::{BuildingRef, FitRecord, ImportOptions, PlanRecord, now_ms};
use trailprint::synth::DEMO_BUILDING_JSON;
use trailprint::{Error, Result};

use crate::opts::{ModelOpts, json_line};

#[derive(ClapArgs, Debug)]
pub struct Args {
    /// Budget of the planned walk, metres.
    #[arg(long, default_value_t = 120.0, allow_negative_numbers = true)]
    budget: f64,
    /// Planner (auto, greedy, genetic, recursive-greedy, ero, exact).
    #[arg(long, default_value = "auto", value_parser = crate::opts::parse_algorithm)]
    algorithm: Algorithm,
    /// Seed of every random choice.
    #[arg(long, default_value_t = 1)]
    seed: u64,
    #[command(flatten)]
    model: ModelOpts,
    /// Print the plan as one JSON object.
    #[arg(long)]
    json: bool,
}

pub fn run(a: Args, db: Option<&Path>) -> Result<()> {
    let store = crate::store_cli::open_store(db)?;
    let db_path = store
        .path()
        .map(|p| p.display().to_string())
        .unwrap_or_else(|| "<memory>".into());
    let demo = Building::from_json(DEMO_BUILDING_JSON, "bundled demo building")?;
    let info = match store.building_info(BuildingRef::Name(&demo.name)) {
        Ok(info) => info,
        Err(Error::NotFound(_)) => {
            let report = store.import_building(
                &demo,
                Some("bundled demo building"),
                &ImportOptions::default(),
            )?;
            if !a.json {
                println!(
                    "imported the demo building {:?} into {db_path}",
                    report.name
                );
            }
            store.building_info(BuildingRef::Id(report.id))?
        }
        Err(e) => return Err(e),
    };
    let building = Arc::new(store.get_building(BuildingRef::Id(info.id))?);
    let kernel = match store.latest_fit(BuildingRef::Id(info.id))? {
        Some(f) => f.record.kernel,
        None => {
            let fit = fit_kernel(&building.pilot)?;
            store.record_fit(
                BuildingRef::Id(info.id),
                &FitRecord::from_fit(&fit, now_ms()),
            )?;
            fit.kernel
        }
    };
    // From one end of the main corridor to the other: the first and last vertex of the
    // generator's corridor (`f0-c..`), whatever its length.
    let corridor: Vec<&str> = building
        .vertices
        .iter()
        .map(|v| v.id.as_str())
        .filter(|id| id.starts_with("f0-c"))
        .collect();
    let (start, end) = match (corridor.first(), corridor.last()) {
        (Some(s), Some(e)) => (s.to_string(), e.to_string()),
        _ => (
            building.vertices[0].id.clone(),
            building.vertices[0].id.clone(),
        ),
    };
    let mut req = PlanRequest::new(&start, &end, a.budget, kernel);
    req.settings.model = a.model.model()?;
    req.settings.algorithm = a.algorithm;
    req.settings.seed = a.seed;
    let result = plan(building.clone(), &req, &trailprint::plan::Control::new())?;
    let plan_id = store.save_plan(
        BuildingRef::Id(info.id),
        &PlanRecord::from_plan(&req, &result, now_ms()),
    )?;
    if a.json {
        let mut v = serde_json::to_value(&result)
            .map_err(|e| Error::InvalidRequest(format!("JSON output: {e}")))?;
        if let Some(obj) = v.as_object_mut() {
            obj.insert("plan_id".into(), plan_id.into());
            obj.insert("building".into(), building.name.clone().into());
            obj.insert("database".into(), db_path.into());
        }
        println!("{}", json_line(&v)?);
        return Ok(());
    }
    println!("database      {db_path}");
    println!(
        "building      {} ({} vertices, {} pilot locations)",
        building.name,
        building.len(),
        building.pilot.len()
    );
    println!(
        "kernel        sf2={:.3} dB², ell={:.3} m, sn2={:.3} dB²",
        kernel.sf2, kernel.ell, kernel.sn2
    );
    println!(
        "request       {start} -> {end}, budget {} m, {}, planner {}",
        a.budget,
        crate::walk_text::model_text(&req.settings.model),
        req.settings.algorithm.name()
    );
    println!("plan id       {plan_id}");
    println!(
        "length        {:.1} m ({} samples)",
        result.length_m, result.samples
    );
    println!(
        "utility       {:.3} nats ({} ms)",
        result.utility_nats, result.elapsed_ms
    );
    crate::walk_text::print_walk(
        &building,
        &result.walk_indices,
        result.length_m,
        &req.settings.model,
        a.model.speed,
        false,
    );
    let name = format!("{:?}", building.name);
    let db_opt = match db {
        Some(p) => format!(" --db {:?}", p.display().to_string()),
        None => String::new(),
    };
    println!();
    println!("next steps:");
    println!(
        "  trailprint{db_opt} render --plan {plan_id} -o demo-plan.svg     draw the walk on the map"
    );
    println!(
        "  trailprint{db_opt} plans show {plan_id} --instructions          the turn-by-turn sheet"
    );
    println!(
        "  trailprint{db_opt} simulate --building {name} --start {start} --end {end} --budget {} --surveyor human",
        a.budget
    );
    println!(
        "                                                   walk it with a simulated surveyor"
    );
    println!("  trailprint{db_opt} vertices {name}       pick another start and end");
    Ok(())
}
