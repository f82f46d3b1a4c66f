//! `trailprint render`: draw a building, a walk (typed, a saved plan, a session as walked,
//! or a team's walks) and the posterior uncertainty as SVG.

use std::path::{Path, PathBuf};
use std::sync::Arc;

use clap::Args as ClapArgs;
use trailprint::building::Building;
use trailprint::gp::{Kernel, Point};
use trailprint::render::{RenderOptions, Scene, WalkLayer, render_svg};
use trailprint::samples::{Sample, Surveyor, sample_walk};
use trailprint::session::{Session, SessionLog};
use trailprint::store::{BuildingRef, SessionEvent, Store, StoredPlan};
use trailprint::{Error, Result};

use crate::opts::{KernelOpts, ModelOpts, split_walk};
use crate::store_cli::{building_in_store, is_file_spec, load_building, open_store};

/// Draw a building as one SVG, one panel per floor, with a heat map of the posterior
/// standard deviation given the pilot points and the walk's samples, and a legend.
#[derive(ClapArgs, Debug)]
#[command(group = clap::ArgGroup::new("what").args(["walk", "plan", "session", "team"]))]
pub struct Args {
    /// A `survey-building/1` JSON file, or the name (or id) of a building in the database
    /// (not needed with --plan, --session or plan ids in --team).
    #[arg(long, value_name = "FILE|NAME")]
    building: Option<String>,
    /// A walk to draw, as comma-separated vertex ids.
    #[arg(long)]
    walk: Option<String>,
    /// A saved plan to draw (`trailprint plans` lists them), with its samples.
    #[arg(long, value_name = "ID")]
    plan: Option<i64>,
    /// A survey session to draw as walked: its planned walk, the estimated track and the
    /// scans it collected (`trailprint sessions` lists them).
    #[arg(long, value_name = "ID")]
    session: Option<i64>,
    /// One surveyor's walk of a team, one colour each: a plan id or comma-separated vertex
    /// ids (repeat for each surveyor, for example the walks `team-plan` prints).
    #[arg(long, value_name = "PLAN_ID|WALK")]
    team: Vec<String>,
    #[command(flatten)]
    model: ModelOpts,
    #[command(flatten)]
    kernel: KernelOpts,
    /// Pixels per metre (default: a row about 1400 px wide at most).
    #[arg(long)]
    scale: Option<f64>,
    /// Write vertex ids (where there is room for them).
    #[arg(long)]
    labels: bool,
    /// Leave out the heat map.
    #[arg(long)]
    no_heatmap: bool,
    /// Output SVG file (`-` for standard output).
    #[arg(short = 'o', long = "out")]
    out: PathBuf,
}

/// The building of a stored plan or session, checked against `--building` if given.
fn stored_building(
    store: &Store,
    building_id: i64,
    given: Option<&str>,
    what: &str,
) -> Result<Building> {
    let b = store.get_building(BuildingRef::Id(building_id))?;
    if let Some(spec) = given
        && !is_file_spec(spec)
    {
        let named = building_in_store(store, spec)?;
        if named.name != b.name {
            return Err(Error::InvalidRequest(format!(
                "{what} belongs to building {:?}, not {:?}",
                b.name, named.name
            )));
        }
    }
    Ok(b)
}

fn plan_caption(p: &StoredPlan) -> String {
    format!(
        "plan {}: {} -> {}, {}, {:.1} m of {} m, {} samples, {:.2} nats",
        p.id,
        p.record.start,
        p.record.end,
        p.record.algorithm,
        p.record.length_m,
        p.record.budget_m,
        p.record.samples,
        p.record.utility_nats
    )
}

/// What to draw: the building, the scene without kernel, the model and a kernel the
/// source brings (a plan's).
struct Source {
    building: Building,
    scene: Scene,
    model: Surveyor,
    kernel: Option<Kernel>,
    /// Samples are computed from the walks (not given, as a session's are).
    sample_walks: bool,
}

fn from_plan(id: i64, a: &Args, db: Option<&Path>) -> Result<Source> {
    let store = open_store(db)?;
    let p = crate::cmd_plans::load_plan(&store, id)?;
    let b = stored_building(
        &store,
        p.building_id,
        a.building.as_deref(),
        &format!("plan {id}"),
    )?;
    let walk = b.resolve_walk(&p.record.walk)?;
    let mut scene = Scene::one_walk(walk, &format!("plan {id}, {:.1} m", p.record.length_m));
    scene.caption = Some(plan_caption(&p));
    Ok(Source {
        building: b,
        scene,
        model: crate::cmd_plans::plan_model(&p),
        kernel: Some(p.record.kernel),
        sample_walks: true,
    })
}

fn from_session(id: i64, a: &Args, db: Option<&Path>) -> Result<Source> {
    let store = Arc::new(open_store(db)?);
    let log: Arc<dyn SessionLog> = store.clone();
    let session = Session::replay_to(log, id, i64::MAX)?;
    let b = stored_building(
        &store,
        session.building_id(),
        a.building.as_deref(),
        &format!("session {id}"),
    )?;
    let plan = store.load_plan(session.plan_id())?;
    let walk = b.resolve_walk(&plan.record.walk)?;
    // The track: every position the session knew, in order (check-ins at their vertex,
    // scans and pose estimates where they were labelled).
    let mut track = Vec::new();
    for e in store.list_events(id, 0)? {
        match e.event {
            SessionEvent::CheckIn { vertex } => {
                if let Some(v) = b.vertex_index(&vertex) {
                    track.push(b.vertices[v].pos);
                }
            }
            SessionEvent::Scan(f) => track.push(Point::new(f.x, f.y, f.floor)),
            SessionEvent::Pose { x, y, floor, .. } => track.push(Point::new(x, y, floor)),
            _ => {}
        }
    }
    let samples: Vec<Sample> = session
        .samples()
        .iter()
        .map(|c| Sample {
            pos: Point::new(c.position.x, c.position.y, c.position.floor),
            arc: 0.0,
            since_checkin: c.since_checkin_m.unwrap_or(0.0),
            extra_noise: c.extra_noise,
        })
        .collect();
    let summary = session.summary()?;
    let mut scene = Scene::one_walk(walk, &format!("planned walk (plan {})", plan.id));
    // The status word as `trailprint sessions` prints it (`finished`, `active`, ...).
    let status = serde_json::to_value(summary.status)
        .ok()
        .and_then(|v| v.as_str().map(str::to_string))
        .unwrap_or_default();
    scene.caption = Some(format!(
        "session {id} ({status}): walked {:.1} m of {} m, {} scans, {} replans, {:.2} nats \
         collected",
        summary.walked_m,
        summary.budget_m,
        summary.samples,
        summary.replans,
        summary.collected_utility_nats
    ));
    scene.track = track;
    scene.samples = samples;
    Ok(Source {
        building: b,
        scene,
        model: crate::cmd_plans::plan_model(&plan),
        kernel: Some(plan.record.kernel),
        sample_walks: false,
    })
}

fn from_team(a: &Args, db: Option<&Path>) -> Result<Source> {
    let mut building: Option<Building> = None;
    let mut store: Option<Store> = None;
    let mut layers = Vec::new();
    let mut kernel = None;
    for (i, t) in a.team.iter().enumerate() {
        if let Ok(id) = t.trim().parse::<i64>() {
            if store.is_none() {
                store = Some(open_store(db)?);
            }
            let Some(st) = store.as_ref() else { continue };
            let p = crate::cmd_plans::load_plan(st, id)?;
            let b = stored_building(
                st,
                p.building_id,
                a.building.as_deref(),
                &format!("plan {id}"),
            )?;
            if let Some(prev) = &building
                && prev.name != b.name
            {
                return Err(Error::InvalidRequest(format!(
                    "--team: plan {id} is of building {:?}, the other walks of {:?}",
                    b.name, prev.name
                )));
            }
            let walk = b.resolve_walk(&p.record.walk)?;
            kernel = kernel.or(Some(p.record.kernel));
            layers.push(WalkLayer {
                walk,
                name: format!("surveyor {}: plan {id}, {:.1} m", i + 1, p.record.length_m),
            });
            building = Some(b);
        } else {
            if building.is_none() {
                let Some(spec) = &a.building else {
                    return Err(Error::InvalidRequest(
                        "--team with vertex ids needs --building FILE|NAME".into(),
                    ));
                };
                building = Some(load_building(spec, db)?);
            }
            let Some(b) = building.as_ref() else { continue };
            let walk = b
                .resolve_walk(&split_walk(t))
                .map_err(|e| Error::InvalidRequest(format!("--team walk {}: {e}", i + 1)))?;
            let len = b.walk_length(&walk);
            layers.push(WalkLayer {
                walk,
                name: format!("surveyor {}: {len:.1} m", i + 1),
            });
        }
    }
    let Some(b) = building else {
        return Err(Error::InvalidRequest("--team: no walk given".into()));
    };
    Ok(Source {
        building: b,
        scene: Scene {
            walks: layers,
            caption: Some(format!("{} surveyors", a.team.len())),
            ..Scene::default()
        },
        model: a.model.model()?,
        kernel,
        sample_walks: true,
    })
}

fn from_walk(a: &Args, db: Option<&Path>) -> Result<Source> {
    let Some(spec) = &a.building else {
        return Err(Error::InvalidRequest(
            "render needs --building FILE|NAME (or --plan ID, --session ID)".into(),
        ));
    };
    let b = load_building(spec, db)?;
    let scene = match &a.walk {
        Some(w) => {
            let walk = b.resolve_walk(&split_walk(w))?;
            let len = b.walk_length(&walk);
            Scene::one_walk(walk, &format!("walk, {len:.1} m"))
        }
        None => Scene::default(),
    };
    Ok(Source {
        building: b,
        scene,
        model: a.model.model()?,
        kernel: None,
        sample_walks: true,
    })
}

pub fn run(a: Args, db: Option<&Path>) -> Result<()> {
    let src = if let Some(id) = a.plan {
        from_plan(id, &a, db)?
    } else if let Some(id) = a.session {
        from_session(id, &a, db)?
    } else if !a.team.is_empty() {
        from_team(&a, db)?
    } else {
        from_walk(&a, db)?
    };
    let Source {
        building: b,
        mut scene,
        model,
        kernel: source_kernel,
        sample_walks,
    } = src;
    // The kernel is needed for the heat map and for the samples (a human's label noise).
    let has_walks = !scene.walks.is_empty();
    let kernel = if a.no_heatmap && (!has_walks || !sample_walks) {
        None
    } else if a.kernel.kernel.is_some() || source_kernel.is_none() {
        Some(a.kernel.resolve(&b)?.0)
    } else {
        source_kernel
    };
    if sample_walks && let Some(k) = &kernel {
        for w in &scene.walks {
            scene.samples.extend(sample_walk(&b, &w.walk, &model, k)?);
        }
    }
    scene.kernel = if a.no_heatmap { None } else { kernel };
    let options = RenderOptions {
        scale_px_per_m: a.scale,
        labels: a.labels,
        heatmap: !a.no_heatmap,
        ..RenderOptions::default()
    };
    let svg = render_svg(&b, &scene, &options)?;
    crate::store_cli::write_output(&a.out, &svg)?;
    if a.out.as_os_str() != "-" {
        eprintln!("wrote {}", a.out.display());
    }
    Ok(())
}
