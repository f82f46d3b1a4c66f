//! `trailprint team-plan`: split one survey among several surveyors so that their walks
//! complement each other (or, with `--independent`, plan each alone for comparison).

use std::sync::Arc;

use clap::Args as ClapArgs;
use trailprint::Result;
use trailprint::plan::Algorithm;
use trailprint::store::StoreTeamRequest;
use trailprint::team::{SurveyorTask, TeamRequest, plan_team};

use crate::opts::{BuildingOpts, EvalOpts, json_line};

#[derive(ClapArgs, Debug)]
pub struct Args {
    #[command(flatten)]
    building: BuildingOpts,
    /// One surveyor as START:END:BUDGET, or START:BUDGET for a walk back to its start
    /// (repeat for each surveyor).
    #[arg(long = "surveyor", required = true, value_parser = |s: &str| SurveyorTask::parse(s).map_err(|e| e.to_string()))]
    surveyors: Vec<SurveyorTask>,
    /// Plan each surveyor alone, ignoring the others.
    #[arg(long)]
    independent: bool,
    /// Refinement rounds (each surveyor replanned given all the others).
    #[arg(long, default_value_t = 1)]
    rounds: usize,
    /// Planner for each surveyor (auto, as for `plan`: on the generated 565-vertex mall,
    /// two robots of 250 m, 189.79 team nats in 12 s where genetic took 89 s for 142.84).
    #[arg(long, default_value = "auto", value_parser = crate::opts::parse_algorithm)]
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
    eval: EvalOpts,
    /// Show progress on stderr even when it is not a terminal (one line every 0.5 s).
    /// Ctrl-C stops the team plan with the walks it has (see `plan_team`).
    #[arg(long)]
    progress: bool,
    /// Print one JSON object.
    #[arg(long)]
    json: bool,
}

pub fn run(a: Args, db: Option<&std::path::Path>) -> Result<()> {
    let b = Arc::new(a.building.load(db)?);
    let settings = crate::opts::plan_settings(
        &a.eval.model,
        a.eval.memory,
        a.algorithm,
        a.seed,
        a.time_limit,
    )?;
    let live = crate::progress::Live::start(a.progress);
    let control = live.control.clone();
    // A building from the database is planned and saved by the store, as on the phone; a
    // file has nowhere to keep the plans, nothing collected and no stored fit.
    let planned = (|| -> Result<_> {
        Ok(if crate::store_cli::is_file_spec(&a.building.building) {
            let (kernel, source) = a.eval.kernel.resolve(&b)?;
            let req = TeamRequest {
                surveyors: a.surveyors,
                kernel,
                settings,
                independent: a.independent,
                rounds: a.rounds,
            };
            (
                plan_team(b.clone(), &req, &[], &control)?,
                Vec::new(),
                kernel,
                source,
                0,
            )
        } else {
            let store = crate::store_cli::open_store(db)?;
            let bref = crate::store_cli::building_ref(&store, &a.building.building)?;
            let req = StoreTeamRequest {
                members: a.surveyors,
                settings,
                kernel: a.eval.kernel.kernel,
                independent: a.independent,
                rounds: a.rounds,
                condition_on_collected: !a.ignore_collected,
            };
            let saved = store
                .plan_team_and_save(bref, &req, &control)
                .map_err(|e| crate::opts::hint(e, &b))?;
            let source = saved.kernel.source.to_string();
            (
                saved.team,
                saved.plan_ids,
                saved.kernel.kernel,
                source,
                saved.conditioned_on,
            )
        })
    })();
    live.finish();
    let (team, plan_ids, kernel, source, conditioned_on) = planned?;
    if a.json {
        let out = serde_json::json!({
            "walks": team.plans.iter().map(|p| p.walk.clone()).collect::<Vec<_>>(),
            "team_utility_nats": team.team_utility_nats,
            "utility_nats": team.plans.iter().map(|p| p.utility_nats).collect::<Vec<_>>(),
            "length_m": team.plans.iter().map(|p| p.length_m).collect::<Vec<_>>(),
            "samples": team.plans.iter().map(|p| p.samples).collect::<Vec<_>>(),
            "independent": team.independent,
            "rounds_used": team.rounds_used,
            "cancelled": team.cancelled,
            "terminations": team.plans.iter().map(|p| p.termination.name()).collect::<Vec<_>>(),
            "conditioned_on_collected": conditioned_on,
            "plan_ids": plan_ids,
            "kernel": kernel,
        });
        println!("{}", json_line(&out)?);
    } else {
        println!("building        {}", crate::store_cli::printable(&b.name));
        println!(
            "kernel          sf2={:.4} ell={:.4} sn2={:.4} ({source})",
            kernel.sf2, kernel.ell, kernel.sn2
        );
        if conditioned_on > 0 {
            println!("conditioned on  {conditioned_on} fingerprints already collected");
        }
        for (i, p) in team.plans.iter().enumerate() {
            if let Some(id) = plan_ids.get(i) {
                println!("surveyor {}      plan id {id}", i + 1);
            }
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
        if team.cancelled {
            println!(
                "cancelled       the walks planned so far ({}); a surveyor not yet planned has the systematic walk",
                team.plans
                    .iter()
                    .enumerate()
                    .map(|(i, p)| format!(
                        "surveyor {}: {} {}",
                        i + 1,
                        p.algorithm,
                        p.termination.name()
                    ))
                    .collect::<Vec<_>>()
                    .join(", ")
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
