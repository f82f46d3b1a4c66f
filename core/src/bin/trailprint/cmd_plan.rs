//! `trailprint plan`: plan a survey walk (SPEC section 7 result JSON with `--json`).

use std::sync::Arc;

use clap::Args as ClapArgs;
use trailprint::plan::{Algorithm, Params, PlanRequest, PlanSettings, plan};
use trailprint::store::StorePlanRequest;
use trailprint::team::SurveyorTask;
use trailprint::{Error, Result};

use crate::opts::{BuildingOpts, EvalOpts, RouteOpts, json_line};

#[derive(ClapArgs, Debug)]
pub struct Args {
    #[command(flatten)]
    building: BuildingOpts,
    #[command(flatten)]
    route: RouteOpts,
    /// auto, greedy, genetic, recursive-greedy, ero, exact or coverage (the systematic
    /// walk: nearest unwalked edge first).
    #[arg(long, default_value = "auto", value_parser = crate::opts::parse_algorithm)]
    algorithm: Algorithm,
    /// Genetic: population size.
    #[arg(long, default_value_t = 200)]
    population: usize,
    /// Genetic: generations.
    #[arg(long, default_value_t = 5)]
    generations: usize,
    /// Genetic: tournament size.
    #[arg(long, default_value_t = 10)]
    tournament: usize,
    /// Genetic: probability that an offspring is mutated.
    #[arg(long, default_value_t = 0.9)]
    mutation: f64,
    /// Recursive greedy: recursion depth.
    #[arg(long, default_value_t = 2)]
    depth: usize,
    /// Recursive greedy: budget step, metres (0 = automatic).
    #[arg(long, default_value_t = 0.0)]
    budget_step: f64,
    /// ERO: iterations (0 = until the time limit, else 2000).
    #[arg(long, default_value_t = 0)]
    iterations: usize,
    /// Seed of every random choice.
    #[arg(long, default_value_t = 1)]
    seed: u64,
    /// Stop after this many seconds with the best walk so far (auto: 2 s by default; a
    /// baseline returns the systematic walk it started from when that is worth more).
    #[arg(long, value_name = "SECONDS", allow_negative_numbers = true)]
    time_limit: Option<f64>,
    #[command(flatten)]
    eval: EvalOpts,
    /// Show progress on stderr even when it is not a terminal (one line every 0.5 s).
    #[arg(long)]
    progress: bool,
    /// Print a turn-by-turn sheet to walk with (the sentences of a session's live
    /// guidance) instead of the table of steps.
    #[arg(long)]
    instructions: bool,
    /// Robot: its speed, m/s, for the time of its walk (a human's is `--speed`).
    #[arg(long, value_name = "M_PER_S", default_value_t = crate::walk_text::ROBOT_SPEED_M_S)]
    robot_speed: f64,
    /// Print the result as one JSON object.
    #[arg(long)]
    json: bool,
}

pub fn run(a: Args, db: Option<&std::path::Path>) -> Result<()> {
    // The time limit counts from here: loading the building and fitting its kernel are
    // set-up too (a fit on 60 pilot locations and 40 access points is 0.2 s).
    let started = std::time::Instant::now();
    let b = Arc::new(a.building.load(db)?);
    let settings = PlanSettings {
        params: Params {
            population: a.population,
            generations: a.generations,
            tournament: a.tournament,
            mutation: a.mutation,
            depth: a.depth,
            budget_step: a.budget_step,
            iterations: a.iterations,
        },
        ..crate::opts::plan_settings(
            &a.eval.model,
            a.eval.memory,
            a.algorithm,
            a.seed,
            a.time_limit,
        )?
    };
    let model = settings.model;
    let route = a.route;
    let live = crate::progress::Live::start(a.progress);
    let control = live.control.clone().with_clock_from(started);
    // A building from the database is planned by the store, as on the phone (its kernel
    // policy, conditioned on everything collected, saved); a file has nowhere to keep a
    // fit or a plan, and nothing collected.
    let planned = if crate::store_cli::is_file_spec(&a.building.building) {
        a.eval.kernel.resolve(&b).and_then(|(kernel, source)| {
            let req = PlanRequest::with_settings(
                &route.start,
                route.end(),
                route.budget,
                kernel,
                &settings,
            );
            let r = plan(b.clone(), &req, &control)?;
            Ok((r, None, kernel, source, 0))
        })
    } else {
        crate::store_cli::open_store(db).and_then(|store| {
            let bref = crate::store_cli::building_ref(&store, &a.building.building)?;
            let request = StorePlanRequest {
                route: SurveyorTask {
                    start: route.start.clone(),
                    end: route.end().to_string(),
                    budget: route.budget,
                },
                settings,
                kernel: a.eval.kernel.kernel,
            };
            let saved = store
                .plan_and_save(bref, &request, &control)
                .map_err(|e| crate::opts::hint(e, &b))?;
            Ok((
                saved.result,
                Some(saved.stored.id),
                saved.kernel.kernel,
                saved.kernel.source.to_string(),
                saved.conditioned_on,
            ))
        })
    };
    live.finish();
    let (r, plan_id, kernel, source, conditioned_on) = planned?;
    if a.json {
        let mut v = serde_json::to_value(&r)
            .map_err(|e| Error::InvalidRequest(format!("JSON output: {e}")))?;
        if let (Some(id), Some(obj)) = (plan_id, v.as_object_mut()) {
            obj.insert("plan_id".into(), id.into());
        }
        println!("{}", json_line(&v)?);
    } else {
        if let Some(id) = plan_id {
            println!("plan id       {id}");
        }
        if conditioned_on > 0 {
            println!("conditioned   on {conditioned_on} fingerprints already collected");
        }
        println!("building      {}", crate::store_cli::printable(&b.name));
        println!("algorithm     {}", r.algorithm);
        println!(
            "route         {} -> {}",
            crate::store_cli::printable(&route.start),
            crate::store_cli::printable(route.end())
        );
        println!(
            "kernel        sf2={:.4} ell={:.4} sn2={:.4} ({source})",
            kernel.sf2, kernel.ell, kernel.sn2
        );
        crate::walk_text::print_walk_summary(
            &r.walk,
            r.length_m,
            r.budget_m,
            r.samples as u64,
            &model,
        );
        println!(
            "utility       {:.3} nats (mutual information of the samples and the radio map)",
            r.utility_nats
        );
        let optimal = match r.optimal {
            Some(true) => ", proven optimal",
            Some(false) => ", not proven optimal",
            None => "",
        };
        println!(
            "planning      {} ms, {}{optimal}{}",
            r.elapsed_ms,
            r.termination.name(),
            r.nodes
                .map(|n| format!(", {n} search nodes"))
                .unwrap_or_default()
        );
        crate::walk_text::print_walk(
            &b,
            &r.walk_indices,
            r.length_m,
            &model,
            a.robot_speed,
            a.instructions,
        );
        if let Some(id) = plan_id {
            println!();
            println!(
                "next          trailprint render --plan {id} -o plan-{id}.svg   (draw it)\n              \
                 trailprint plans show {id} --instructions   (the sheet to walk with)"
            );
        }
    }
    Ok(())
}
