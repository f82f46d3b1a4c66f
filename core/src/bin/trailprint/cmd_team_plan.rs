//! `trailprint team-plan`: split one survey among several surveyors so that their walks
//! complement each other (or, with `--independent`, plan each alone for comparison).

use std::sync::Arc;

use clap::Args as ClapArgs;
use trailprint::Result;
use trailprint::plan::{Algorithm, PlanRequest};
use trailprint::store::PlanRecord;
use trailprint::team::{SurveyorTask, TeamRequest, plan_team};

use crate::opts::{BuildingOpts, KernelOpts, ModelOpts, json_line};

#[derive(ClapArgs, Debug)]
pub struct Args {
    #[command(flatten)]
    building: BuildingOpts,
    /// One surveyor as START:END:BUDGET (repeat for each surveyor).
    #[arg(long = "surveyor", required = true, value_parser = |s: &str| SurveyorTask::parse(s).map_err(|e| e.to_string()))]
    surveyors: Vec<SurveyorTask>,
    /// Plan each surveyor alone, ignoring the others.
    #[arg(long)]
    independent: bool,
    /// Refinement rounds (each surveyor replanned given all the others).
    #[arg(long, default_value_t = 1)]
    rounds: usize,
    /// Planner for each surveyor.
    #[arg(long, default_value = "genetic", value_parser = crate::opts::parse_algorithm)]
    algorithm: Algorithm,
    /// Time limit of each planner run, seconds.
    #[arg(long)]
    time_limit: Option<f64>,
    /// Seed (surveyor i uses SEED + i).
    #[arg(long, default_value_t = 1)]
    seed: u64,
    /// Do not condition on fingerprints already collected in this building.
    #[arg(long)]
    ignore_collected: bool,
    #[command(flatten)]
    model: ModelOpts,
    #[command(flatten)]
    kernel: KernelOpts,
    /// Print one JSON object.
    #[arg(long)]
    json: bool,
}

pub fn run(a: Args, db: Option<&std::path::Path>) -> Result<()> {
    let b = Arc::new(a.building.load(db)?);
    let (kernel, source) = a.kernel.resolve(&b)?;
    let mut base = PlanRequest::new("", "", 0.0, kernel);
    base.model = a.model.model()?;
    base.algorithm = a.algorithm;
    base.seed = a.seed;
    base.time_limit = crate::opts::time_limit(a.time_limit)?;
    let prior = if a.ignore_collected {
        Vec::new()
    } else {
        crate::store_cli::collected_prior(&a.building.building, db, &kernel)?
    };
    let req = TeamRequest {
        surveyors: a.surveyors,
        base,
        independent: a.independent,
        rounds: a.rounds,
    };
    let team = plan_team(b.clone(), &req, &prior, &trailprint::plan::Control::new())?;
    // A building of the database keeps each surveyor's walk as a plan, so that
    // `plans show ID` and `render --team ID --team ID` find them; a file has nowhere.
    let plan_ids: Vec<i64> = if crate::store_cli::is_file_spec(&a.building.building) {
        Vec::new()
    } else {
        let store = crate::store_cli::open_store(db)?;
        let bref = crate::store_cli::building_ref(&store, &a.building.building)?;
        let now = trailprint::store::now_ms();
        let mut ids = Vec::new();
        for (task, p) in req.surveyors.iter().zip(&team.plans) {
            let mut one = req.base.clone();
            one.start = task.start.clone();
            one.end = task.end.clone();
            one.budget = task.budget;
            ids.push(store.save_plan(bref, &PlanRecord::from_plan(&one, p, now))?);
        }
        ids
    };
    if a.json {
        let out = serde_json::json!({
            "walks": team.plans.iter().map(|p| p.walk.clone()).collect::<Vec<_>>(),
            "team_utility_nats": team.team_utility_nats,
            "utility_nats": team.plans.iter().map(|p| p.utility_nats).collect::<Vec<_>>(),
            "length_m": team.plans.iter().map(|p| p.length_m).collect::<Vec<_>>(),
            "samples": team.plans.iter().map(|p| p.samples).collect::<Vec<_>>(),
            "independent": team.independent,
            "rounds_used": team.rounds_used,
            "conditioned_on_collected": prior.len(),
            "kernel": kernel,
            "plan_ids": plan_ids,
        });
        println!("{}", json_line(&out)?);
    } else {
        println!("building        {}", crate::store_cli::printable(&b.name));
        println!(
            "kernel          sf2={:.4} ell={:.4} sn2={:.4} ({source})",
            kernel.sf2, kernel.ell, kernel.sn2
        );
        if !prior.is_empty() {
            println!(
                "conditioned on  {} fingerprints already collected",
                prior.len()
            );
        }
        for (i, p) in team.plans.iter().enumerate() {
            println!(
                "surveyor {}      {}{:.1} m, {} samples, {:.3} nats alone: {}",
                i + 1,
                plan_ids
                    .get(i)
                    .map(|id| format!("plan {id}, "))
                    .unwrap_or_default(),
                p.length_m + 0.0, // never "-0.0"
                p.samples,
                p.utility_nats,
                p.walk.join(",")
            );
        }
        println!(
            "team utility    {:.3} nats ({})",
            team.team_utility_nats,
            if team.independent {
                "planned independently".to_string()
            } else {
                format!(
                    "planned as a team, {} refinement rounds used",
                    team.rounds_used
                )
            }
        );
        if !plan_ids.is_empty() {
            let team_args: Vec<String> = plan_ids.iter().map(|id| format!("--team {id}")).collect();
            println!(
                "next            trailprint render {} -o team.svg   (one colour per surveyor)",
                team_args.join(" ")
            );
        }
    }
    Ok(())
}
