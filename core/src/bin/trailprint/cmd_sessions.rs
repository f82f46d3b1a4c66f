//! `trailprint sessions [--json]`: the survey sessions in the database, with what each
//! walked and collected (replayed from its event log, which writes nothing).

use std::path::Path;
use std::sync::Arc;

use trailprint::Result;
use trailprint::session::{Session, SessionLog, Surveyor};
use trailprint::store::BuildingRef;

use crate::opts::json_line;
use crate::store_cli::open_store;

#[derive(clap::Args)]
pub struct Args {
    /// Print a JSON array instead of a table
    #[arg(long)]
    json: bool,
}

/// One row of the listing.
#[derive(serde::Serialize)]
struct Row {
    id: i64,
    building: String,
    building_id: i64,
    plan_id: Option<i64>,
    created_ms: i64,
    /// `human` or `robot` (null when the session's settings cannot be read).
    surveyor: Option<&'static str>,
    status: &'static str,
    events: i64,
    samples: u64,
    walked_m: Option<f64>,
    budget_m: Option<f64>,
    replans: Option<u32>,
    planned_utility_nats: Option<f64>,
    collected_utility_nats: Option<f64>,
    /// 1 when the collected utility counts every sample; `k > 1` when the session's
    /// memory budget made it count one of every `k` (then a lower bound).
    sample_block: Option<u64>,
    /// Why the figures that need a replay are missing.
    note: Option<String>,
}

pub fn run(args: &Args, db: Option<&Path>) -> Result<()> {
    let store = Arc::new(open_store(db)?);
    let log: Arc<dyn SessionLog> = store.clone();
    let mut rows = Vec::new();
    for b in store.list_buildings()? {
        for s in store.list_sessions(BuildingRef::Id(b.id))? {
            let mut row = Row {
                id: s.id,
                building: b.name.clone(),
                building_id: b.id,
                plan_id: s.plan_id,
                created_ms: s.created_ms,
                surveyor: s
                    .surveyor
                    .as_ref()
                    .and_then(|v| v.get("surveyor"))
                    .and_then(|v| serde_json::from_value::<Surveyor>(v.clone()).ok())
                    .map(|v| if v.is_human() { "human" } else { "robot" }),
                status: match s.status {
                    trailprint::store::SessionStatus::Active => "active",
                    trailprint::store::SessionStatus::Paused => "paused",
                    trailprint::store::SessionStatus::Finished => "finished",
                    trailprint::store::SessionStatus::Aborted => "aborted",
                },
                events: s.last_seq,
                samples: s.collected,
                walked_m: None,
                budget_m: None,
                replans: None,
                planned_utility_nats: None,
                collected_utility_nats: None,
                sample_block: None,
                note: None,
            };
            match Session::replay_to(log.clone(), s.id, i64::MAX).and_then(|x| x.summary()) {
                Ok(sum) => {
                    row.walked_m = Some(sum.walked_m);
                    row.budget_m = Some(sum.budget_m);
                    row.replans = Some(sum.replans);
                    row.planned_utility_nats = Some(sum.planned_utility_nats);
                    row.collected_utility_nats = Some(sum.collected_utility_nats);
                    row.sample_block = Some(sum.sample_block);
                }
                Err(e) => row.note = Some(format!("cannot be replayed: {e}")),
            }
            rows.push(row);
        }
    }
    if args.json {
        println!("{}", json_line(&rows)?);
        return Ok(());
    }
    if rows.is_empty() {
        println!("no sessions (start one with `trailprint simulate` or the app)");
        return Ok(());
    }
    let width = crate::store_cli::column_width(rows.iter().map(|r| &r.building), 8);
    println!(
        "{:>4}  {:<width$}  {:<8} {:<8} {:>9} {:>8} {:>7} {:>7} {:>9}",
        "id",
        "building",
        "surveyor",
        "status",
        "walked_m",
        "budget_m",
        "samples",
        "replans",
        "utility"
    );
    let num = |v: Option<f64>, p: usize| v.map_or("-".to_string(), |x| format!("{x:.p$}"));
    for r in &rows {
        println!(
            "{:>4}  {:<width$}  {:<8} {:<8} {:>9} {:>8} {:>7} {:>7} {:>9}{}",
            r.id,
            r.building,
            r.surveyor.unwrap_or("-"),
            r.status,
            num(r.walked_m, 1),
            num(r.budget_m, 1),
            r.samples,
            r.replans.map_or("-".to_string(), |x| x.to_string()),
            match r.sample_block {
                // A lower bound: one sample of several counted (memory budget).
                Some(k) if k > 1 => format!(">={}", num(r.collected_utility_nats, 2)),
                _ => num(r.collected_utility_nats, 2),
            },
            r.note
                .as_ref()
                .map(|n| format!("  ({n})"))
                .unwrap_or_default()
        );
    }
    Ok(())
}
