//! `trailprint simulate`: plan a walk, then walk it as a survey session with a simulated
//! surveyor (synthetic steps with stride noise, or robot poses; scans from a world model;
//! wrong turns with probability `--deviate`), and print the session's summary.
//!
//! The session is stored like any other: in `--db` (or the default database) when given or
//! when the building is named from the database, in memory for a building file without
//! `--db`. `trailprint export NAME --collected csv -o FILE` exports what it collected.

use std::io::{IsTerminal, Write};
use std::path::{Path, PathBuf};
use std::sync::Arc;
use std::time::{Duration, Instant};

use clap::Args as ClapArgs;
use trailprint::building::Building;
use trailprint::plan::{Algorithm, Control, PlanRequest, PlanSettings, plan};
use trailprint::session::sim::{SimOptions, World, simulate};
use trailprint::session::{
    Ack, Event, GreedyReplanner, PlannerReplanner, Replanner, Session, SessionLog, SessionOptions,
};
use trailprint::store::{BuildingRef, ImportOptions, PlanRecord, Store, now_ms};
use trailprint::{Error, Result};

use crate::opts::{BuildingOpts, EvalOpts, RouteOpts, json_line};
use crate::store_cli::{building_ref, is_file_spec, open_store};

#[derive(ClapArgs, Debug)]
#[command(mut_arg("model", |a| a
    .long("surveyor")
    .visible_alias("model")
    .default_value(None)
    .required(true)
    .help("Who walks: a human with a step counter or a robot reporting its poses")))]
pub struct Args {
    #[command(flatten)]
    building: BuildingOpts,
    #[command(flatten)]
    route: RouteOpts,
    #[command(flatten)]
    eval: EvalOpts,
    /// Probability of taking a wrong turn at each vertex.
    #[arg(long, value_name = "P", default_value_t = 0.0)]
    deviate: f64,
    /// Seed of the plan, the simulated surveyor and the world model.
    #[arg(long, default_value_t = 1)]
    seed: u64,
    /// Planner of the initial walk (auto, greedy, genetic, recursive-greedy, ero, exact).
    #[arg(long, default_value = "auto", value_parser = crate::opts::parse_algorithm)]
    algorithm: Algorithm,
    /// Time limit of the initial plan, seconds (auto: 2 s by default).
    #[arg(long, value_name = "SECONDS", allow_negative_numbers = true)]
    time_limit: Option<f64>,
    /// Planner of replans: `default` (`session-greedy` on buildings of up to 200
    /// vertices, `auto` with a 1 s limit on larger ones), `session-greedy` (deterministic)
    /// or a planner name.
    #[arg(long, default_value = "default")]
    replan_algorithm: String,
    /// Never replan automatically when off-route (the surveyor walks back instead).
    #[arg(long)]
    no_auto_replan: bool,
    /// Replan with the whole budget left, keeping nothing in reserve for further wrong
    /// turns (the walk may then end over budget).
    #[arg(long)]
    no_reserve: bool,
    /// Off-route slack past a due check-in, metres (plus 25% of the leg).
    #[arg(long, default_value_t = 3.0)]
    slack: f64,
    /// Human: the step length the session starts from (calibration), metres.
    #[arg(long, default_value_t = trailprint::surveyor::DEFAULT_STEP_LENGTH_M)]
    step_length: f64,
    /// Human: the simulated surveyor's real mean step, metres.
    #[arg(long, default_value_t = 0.75)]
    true_step: f64,
    /// Human: relative standard deviation of one stride.
    #[arg(long, default_value_t = 0.05)]
    stride_noise: f64,
    /// Robot: speed, m/s.
    #[arg(long, default_value_t = crate::walk_text::ROBOT_SPEED_M_S)]
    robot_speed: f64,
    /// Seconds the surveyor stands at each check-in (the phone keeps scanning).
    #[arg(long, value_name = "SECONDS", default_value_t = 2.0)]
    check_in_pause: f64,
    /// Write the collected fingerprints to FILE (CSV, or JSON when FILE ends in .json).
    #[arg(long, value_name = "FILE")]
    export: Option<PathBuf>,
    /// Print `session ID` first and `ack SEQ LAST_SEQ` for every acknowledged event,
    /// flushed at once (for crash tests).
    #[arg(long, hide = true)]
    print_acks: bool,
    /// Print the summary as one JSON object (the last line of output).
    #[arg(long)]
    json: bool,
}

/// Progress on a terminal (a redrawn bar), or plain lines at check-ins, off-route events
/// and replans otherwise.
struct Display {
    bar: bool,
    plain: bool,
    to_stderr: bool,
    last_draw: Option<Instant>,
    budget: f64,
}

impl Display {
    fn new(json: bool, budget: f64) -> Self {
        let (bar, plain, to_stderr) = if json {
            (std::io::stderr().is_terminal(), false, true)
        } else if std::io::stdout().is_terminal() {
            (true, false, false)
        } else {
            (false, true, false)
        };
        Display {
            bar,
            plain,
            to_stderr,
            last_draw: None,
            budget,
        }
    }

    fn write(&self, text: &str) {
        // Progress output is best effort: a closed pipe must not stop the session.
        if self.to_stderr {
            let mut e = std::io::stderr().lock();
            let _ = e.write_all(text.as_bytes()).and_then(|()| e.flush());
        } else {
            let mut o = std::io::stdout().lock();
            let _ = o.write_all(text.as_bytes()).and_then(|()| o.flush());
        }
    }

    fn update(&mut self, s: &Session, ev: &Event, ack: &Ack) {
        let t = s.tracker();
        if self.plain {
            let walked = t.walked_m();
            let line = match ev {
                Event::CheckIn { vertex, .. } if ack.went_off_route => Some(format!(
                    "event {:>5}  {walked:>6.1} m  check-in at {vertex}: OFF ROUTE{}",
                    ack.seq,
                    match (ack.replan_seq, &ack.replan_error) {
                        (Some(q), _) => format!(", replanned (event {q})"),
                        (None, Some(e)) => format!(", replan failed: {e}"),
                        _ => String::new(),
                    }
                )),
                Event::CheckIn { vertex, .. } => Some(format!(
                    "event {:>5}  {walked:>6.1} m  check-in at {vertex}; step {:.3} m",
                    ack.seq,
                    t.step_length_m()
                )),
                _ if ack.went_off_route => Some(format!(
                    "event {:>5}  {walked:>6.1} m  OFF ROUTE{}",
                    ack.seq,
                    ack.replan_seq
                        .map(|q| format!(", replanned (event {q})"))
                        .unwrap_or_default()
                )),
                Event::Finish { .. } | Event::Abort { .. } => Some(format!(
                    "event {:>5}  {walked:>6.1} m  {}",
                    ack.seq,
                    ev.kind()
                )),
                _ => None,
            };
            if let Some(l) = line {
                let g = s.guidance();
                let tail = if g.next_vertex.is_some() && !matches!(ev, Event::Finish { .. }) {
                    format!("\n             next: {}", g.message)
                } else {
                    String::new()
                };
                self.write(&format!("{l}{tail}\n"));
            }
        }
        if self.bar {
            let done = matches!(ev, Event::Finish { .. } | Event::Abort { .. });
            if !done
                && self
                    .last_draw
                    .is_some_and(|d| d.elapsed() < Duration::from_millis(80))
            {
                return;
            }
            self.last_draw = Some(Instant::now());
            let walked = t.walked_m();
            let remaining = t.remaining_m(s.building());
            let frac = if walked + remaining > 0.0 {
                walked / (walked + remaining)
            } else {
                1.0
            };
            let width = 30;
            let fill = ((frac * width as f64).round() as usize).min(width);
            self.write(&format!(
                "\r[{}{}] {:>3.0}%  {walked:>6.1}/{:.0} m  samples {:>4}  replans {}  off-route {}{}",
                "#".repeat(fill),
                "-".repeat(width - fill),
                frac * 100.0,
                self.budget,
                t.samples().len(),
                t.replans(),
                t.off_route_events(),
                if done { "\n" } else { "  " }
            ));
        }
    }
}

/// The store to use, the building and its id there.
fn open(a: &Args, db: Option<&Path>) -> Result<(Arc<Store>, Building, i64, String)> {
    let spec = &a.building.building;
    if is_file_spec(spec) {
        let b = a.building.load(db)?;
        let (store, where_) = match db {
            Some(p) => (open_store(Some(p))?, p.display().to_string()),
            None => (Store::open_in_memory()?, "memory".to_string()),
        };
        let id = match store.building_info(BuildingRef::Name(&b.name)) {
            Ok(info) => info.id,
            Err(Error::NotFound(_)) => {
                store
                    .import_building(&b, Some(spec), &ImportOptions::default())?
                    .id
            }
            Err(e) => return Err(e),
        };
        // The stored copy is what the session walks.
        let b = store.get_building(BuildingRef::Id(id))?;
        return Ok((Arc::new(store), b, id, where_));
    }
    let store = open_store(db)?;
    let where_ = store
        .path()
        .map_or_else(|| "memory".into(), |p| p.display().to_string());
    let id = match building_ref(&store, spec)? {
        BuildingRef::Id(id) => id,
        BuildingRef::Name(n) => store.building_info(BuildingRef::Name(n))?.id,
    };
    let b = store.get_building(BuildingRef::Id(id))?;
    Ok((Arc::new(store), b, id, where_))
}

pub fn run(a: Args, db: Option<&Path>) -> Result<()> {
    let wall = Instant::now();
    let (store, b, bid, where_) = open(&a, db)?;
    let b = Arc::new(b);
    let (kernel, kernel_source) = a.eval.kernel.resolve(&b)?;
    let surveyor = a.eval.model.surveyor(a.step_length, a.robot_speed)?;
    let sim = SimOptions {
        deviate: a.deviate,
        seed: a.seed,
        true_step_m: a.true_step,
        stride_noise: a.stride_noise,
        check_in_ms: (a.check_in_pause * 1000.0).round() as i64,
        ..SimOptions::default()
    };
    sim.validate()?;
    let replanner: Option<Arc<dyn Replanner>> = match a.replan_algorithm.as_str() {
        "default" => None,
        "session-greedy" => Some(Arc::new(GreedyReplanner)),
        name => Some(Arc::new(PlannerReplanner::new(Algorithm::from_name(name)?))),
    };
    let time_limit = crate::opts::time_limit(a.time_limit)?;
    let req = PlanRequest {
        start: a.route.start.clone(),
        end: a.route.end().to_string(),
        budget: a.route.budget,
        kernel,
        settings: PlanSettings {
            model: surveyor,
            algorithm: a.algorithm,
            seed: a.seed,
            time_limit,
            memory_budget: a.eval.memory.bytes(),
            ..PlanSettings::default()
        },
    };
    // The simulated world first: a building too large for it is refused before a plan is
    // made and saved.
    let world = World::for_building(&b, &kernel, a.seed)?;
    let planned = plan(b.clone(), &req, &Control::new())?;
    let plan_id = store.save_plan(
        BuildingRef::Id(bid),
        &PlanRecord::from_plan(&req, &planned, now_ms()),
    )?;
    let options = SessionOptions {
        auto_replan: !a.no_auto_replan,
        off_route_slack_m: a.slack,
        seed: a.seed,
        deviation_reserve: !a.no_reserve,
        memory_budget_mb: a.eval.memory.memory_budget,
        ..SessionOptions::default()
    };
    let log: Arc<dyn SessionLog> = store.clone();
    let mut session = Session::start(log, plan_id, surveyor, options)?;
    if let Some(r) = replanner {
        session.set_replanner(r);
    }
    if a.print_acks {
        println!("session {} plan {plan_id}", session.id());
    }
    if !a.json {
        println!(
            "session {} on {:?} ({where_}): plan {plan_id} by {}, {} vertices, {:.1} m of {} m, \
             {:.2} nats",
            session.id(),
            b.name,
            planned.algorithm,
            planned.walk.len(),
            planned.length_m,
            a.route.budget,
            planned.utility_nats
        );
    }
    let mut display = Display::new(a.json, a.route.budget);
    let print_acks = a.print_acks;
    let (summary, report) = simulate(&mut session, &world, &sim, |s, ev, ack| {
        if print_acks {
            let mut o = std::io::stdout().lock();
            writeln!(o, "ack {} {}", ack.seq, ack.last_seq())
                .and_then(|()| o.flush())
                .map_err(|e| Error::io("<stdout>", e))?;
        }
        display.update(s, ev, ack);
        Ok(())
    })?;
    if let Some(path) = &a.export {
        let list = store.list_collected(BuildingRef::Id(bid), Some(session.id()))?;
        let text = if path.extension().is_some_and(|e| e == "json") {
            trailprint::store::collected_json(&b.name, &list) + "\n"
        } else {
            trailprint::store::collected_csv(&list)
        };
        crate::store_cli::write_output(path, &text)?;
    }
    let wall_ms = wall.elapsed().as_millis() as u64;
    if a.json {
        let out = serde_json::json!({
            "session_id": session.id(),
            "plan_id": plan_id,
            "database": where_,
            "building": b.name,
            "surveyor": surveyor,
            "status": summary.status,
            "algorithm": planned.algorithm,
            "plan_length_m": planned.length_m,
            "budget_m": a.route.budget,
            "walked_m": summary.walked_m,
            "true_walked_m": report.true_walked_m,
            "samples": summary.samples,
            "check_ins": summary.check_ins,
            "steps": summary.steps,
            "step_length_m": summary.step_length_m,
            "planned_utility_nats": summary.planned_utility_nats,
            "collected_utility_nats": summary.collected_utility_nats,
            "replans": summary.replans,
            "reserve_m": session.reserve_m(),
            "off_route_events": summary.off_route_events,
            "wrong_turns": report.wrong_turns,
            "mean_std_db": summary.mean_std_db,
            "max_std_db": summary.max_std_db,
            "events": report.events,
            "sim_time_s": report.sim_time_s,
            "kernel": kernel,
            "kernel_source": kernel_source,
            "seed": a.seed,
            "wall_ms": wall_ms,
        });
        println!("{}", json_line(&out)?);
    } else {
        let s = &summary;
        println!(
            "{:?}: walked {:.1} m of the {} m budget ({:.1} m really) in {:.0} s simulated",
            s.status, s.walked_m, a.route.budget, report.true_walked_m, report.sim_time_s
        );
        if surveyor.is_human() {
            println!(
                "samples {}; check-ins {}; steps {}; step length {:.3} m",
                s.samples, s.check_ins, s.steps, s.step_length_m
            );
        } else {
            println!("samples {}; check-ins {}", s.samples, s.check_ins);
        }
        if s.sample_block > 1 {
            println!(
                "utility: planned {:.2} nats, collected at least {:.2} nats (past half the \
                 memory budget, one sample of every {} counted)",
                s.planned_utility_nats, s.collected_utility_nats, s.sample_block
            );
        } else {
            println!(
                "utility: planned {:.2} nats, collected {:.2} nats",
                s.planned_utility_nats, s.collected_utility_nats
            );
        }
        println!(
            "wrong turns {}; off-route events {}; replans {}",
            report.wrong_turns, s.off_route_events, s.replans
        );
        println!(
            "coverage: posterior std mean {:.2} dB, max {:.2} dB; {} events in {wall_ms} ms",
            s.mean_std_db, s.max_std_db, report.events
        );
    }
    Ok(())
}
