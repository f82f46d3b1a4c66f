//! `trailprint plans [NAME] [--json]` lists the saved plans; `trailprint plans show ID`
//! prints one with its walk (or, with `--instructions`, the sheet to walk it with).

use std::path::Path;

use trailprint::store::{BuildingRef, Store, StoredPlan};
use trailprint::surveyor::Surveyor;
use trailprint::{Error, Result};

use crate::opts::json_line;
use crate::store_cli::{building_ref, open_store, printable};

#[derive(clap::Args)]
#[command(args_conflicts_with_subcommands = true)]
pub struct Args {
    #[command(subcommand)]
    action: Option<Action>,
    /// Only the plans of this building (name or id); default: every building.
    name: Option<String>,
    /// Print a JSON array instead of a table.
    #[arg(long)]
    json: bool,
}

#[derive(clap::Subcommand)]
enum Action {
    /// One plan: its request, figures and walk.
    Show(ShowArgs),
}

#[derive(clap::Args)]
struct ShowArgs {
    /// Plan id (the `id` column of `trailprint plans`).
    id: i64,
    /// Print the turn-by-turn sheet instead of the table of steps.
    #[arg(long)]
    instructions: bool,
    /// Robot: its speed, m/s, for the time of a robot's plan (a human plan uses its own).
    #[arg(long = "robot-speed", alias = "speed", value_name = "M_PER_S", default_value_t = crate::walk_text::ROBOT_SPEED_M_S)]
    speed: f64,
    /// Print the stored plan as one JSON object.
    #[arg(long)]
    json: bool,
}

/// One row of the listing.
#[derive(serde::Serialize)]
struct Row<'a> {
    id: i64,
    building: &'a str,
    building_id: i64,
    start: &'a str,
    end: &'a str,
    budget_m: f64,
    length_m: f64,
    samples: u64,
    utility_nats: f64,
    algorithm: &'a str,
    surveyor: &'a str,
    created_ms: i64,
    created: String,
}

pub fn run(a: Args, db: Option<&Path>) -> Result<()> {
    match a.action {
        Some(Action::Show(s)) => show(&s, db),
        None => list(a.name.as_deref(), a.json, db),
    }
}

fn surveyor_kind(p: &StoredPlan) -> &'static str {
    match p.record.surveyor {
        Some(s) if s.is_human() => "human",
        Some(_) => "robot",
        None => "-",
    }
}

/// Milliseconds since the Unix epoch as `YYYY-MM-DD HH:MM` UTC (civil-from-days, Howard
/// Hinnant's algorithm; no time-zone database needed).
pub fn utc_text(ms: i64) -> String {
    let secs = ms.div_euclid(1000);
    let days = secs.div_euclid(86_400);
    let rem = secs.rem_euclid(86_400);
    let z = days + 719_468;
    let era = z.div_euclid(146_097);
    let doe = z.rem_euclid(146_097);
    let yoe = (doe - doe / 1460 + doe / 36_524 - doe / 146_096) / 365;
    let doy = doe - (365 * yoe + yoe / 4 - yoe / 100);
    let mp = (5 * doy + 2) / 153;
    let d = doy - (153 * mp + 2) / 5 + 1;
    let m = if mp < 10 { mp + 3 } else { mp - 9 };
    let y = yoe + era * 400 + i64::from(m <= 2);
    format!(
        "{y:04}-{m:02}-{d:02} {:02}:{:02}",
        rem / 3600,
        (rem % 3600) / 60
    )
}

fn list(name: Option<&str>, json: bool, db: Option<&Path>) -> Result<()> {
    let store = open_store(db)?;
    let buildings = match name {
        Some(n) => {
            let id = match building_ref(&store, n)? {
                BuildingRef::Id(id) => id,
                BuildingRef::Name(n) => store.building_info(BuildingRef::Name(n))?.id,
            };
            vec![store.building_info(BuildingRef::Id(id))?]
        }
        None => store.list_buildings()?,
    };
    let mut plans = Vec::new();
    for b in &buildings {
        for p in store.list_plans(BuildingRef::Id(b.id))? {
            plans.push((b.name.clone(), p));
        }
    }
    let rows: Vec<Row> = plans
        .iter()
        .map(|(b, p)| Row {
            id: p.id,
            building: b,
            building_id: p.building_id,
            start: &p.record.start,
            end: &p.record.end,
            budget_m: p.record.budget_m,
            length_m: p.record.length_m,
            samples: p.record.samples,
            utility_nats: p.record.utility_nats,
            algorithm: p.record.algorithm.name(),
            surveyor: surveyor_kind(p),
            created_ms: p.record.created_ms,
            created: utc_text(p.record.created_ms),
        })
        .collect();
    if json {
        println!("{}", json_line(&rows)?);
        return Ok(());
    }
    if rows.is_empty() {
        match name {
            Some(n) => println!(
                "no plans of {} (make one with `trailprint plan --building {n:?} --start V --end V --budget M`)",
                printable(n)
            ),
            None => println!("no plans (make one with `trailprint plan` or `trailprint demo`)"),
        }
        return Ok(());
    }
    let names: Vec<String> = rows.iter().map(|r| printable(r.building)).collect();
    let ends: Vec<String> = rows
        .iter()
        .map(|r| format!("{} -> {}", printable(r.start), printable(r.end)))
        .collect();
    let nw = crate::store_cli::column_width(&names, 8);
    let ew = crate::store_cli::column_width(&ends, 5);
    println!(
        "{:>4}  {:<nw$}  {:<ew$}  {:>8} {:>8} {:>7} {:>9}  {:<16} {:<8} created (UTC)",
        "id",
        "building",
        "route",
        "budget_m",
        "length_m",
        "samples",
        "utility",
        "algorithm",
        "surveyor",
    );
    for ((r, n), e) in rows.iter().zip(&names).zip(&ends) {
        println!(
            "{:>4}  {:<nw$}  {:<ew$}  {:>8.1} {:>8.1} {:>7} {:>9.3}  {:<16} {:<8} {}",
            r.id,
            n,
            e,
            r.budget_m,
            r.length_m,
            r.samples,
            r.utility_nats,
            r.algorithm,
            r.surveyor,
            r.created
        );
    }
    println!("\n(utility in nats; `trailprint plans show ID` prints a plan's walk)");
    Ok(())
}

/// A plan by id, with an error that says which ids exist.
pub fn load_plan(store: &Store, id: i64) -> Result<StoredPlan> {
    match store.load_plan(id) {
        Err(Error::NotFound(_)) => {
            let mut ids = Vec::new();
            for b in store.list_buildings()? {
                ids.extend(
                    store
                        .list_plans(BuildingRef::Id(b.id))?
                        .iter()
                        .map(|p| p.id),
                );
            }
            ids.sort_unstable();
            let db = store
                .path()
                .map_or_else(|| ":memory:".into(), |p| p.display().to_string());
            Err(Error::NotFound(if ids.is_empty() {
                format!("no plan {id}: the database {db} holds no plans")
            } else {
                let shown: Vec<String> = ids
                    .iter()
                    .rev()
                    .take(10)
                    .rev()
                    .map(i64::to_string)
                    .collect();
                format!(
                    "no plan {id} in {db}; plan ids there: {}{} (`trailprint plans` lists them)",
                    if ids.len() > 10 { "..., " } else { "" },
                    shown.join(", ")
                )
            }))
        }
        other => other,
    }
}

/// The surveyor a plan was made for (the paper's robot for a walk handed to a session,
/// which records none).
pub fn plan_model(p: &StoredPlan) -> Surveyor {
    p.record.surveyor.unwrap_or_default()
}

fn show(a: &ShowArgs, db: Option<&Path>) -> Result<()> {
    let store = open_store(db)?;
    let p = load_plan(&store, a.id)?;
    let b = store.get_building(BuildingRef::Id(p.building_id))?;
    if a.json {
        let mut v = serde_json::to_value(&p)
            .map_err(|e| Error::InvalidRequest(format!("JSON output: {e}")))?;
        if let Some(o) = v.as_object_mut() {
            o.insert("building".into(), b.name.clone().into());
        }
        println!("{}", json_line(&v)?);
        return Ok(());
    }
    if !(a.speed.is_finite() && a.speed > 0.0) {
        return Err(Error::InvalidRequest(format!(
            "--robot-speed must be a positive number of m/s, got {}",
            a.speed
        )));
    }
    let walk = b.resolve_walk(&p.record.walk)?;
    let model = plan_model(&p);
    let r = &p.record;
    println!("plan id       {}", p.id);
    println!("building      {}", printable(&b.name));
    println!(
        "route         {} -> {}",
        printable(&r.start),
        printable(&r.end)
    );
    println!(
        "algorithm     {}{}",
        r.algorithm,
        r.seed.map(|s| format!(", seed {s}")).unwrap_or_default()
    );
    println!(
        "kernel        sf2={:.4} ell={:.4} sn2={:.4}",
        r.kernel.sf2, r.kernel.ell, r.kernel.sn2
    );
    println!("created       {} UTC", utc_text(r.created_ms));
    crate::walk_text::print_walk_summary(&r.walk, r.length_m, r.budget_m, r.samples, &model);
    println!("utility       {:.3} nats", r.utility_nats);
    crate::walk_text::print_walk(&b, &walk, r.length_m, &model, a.speed, a.instructions);
    Ok(())
}
