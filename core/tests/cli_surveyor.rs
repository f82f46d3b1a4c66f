//! The surveyor's side of the command line (issue 18), run as a user runs it: saved plans
//! listed and shown, vertices listed, fits stored, `demo` ending with next steps, `plan`
//! printed for a person, errors that say what would do, and maps of plans, sessions and
//! teams.

#![cfg(unix)]
#![allow(clippy::expect_used)] // tests and their helpers may expect

use crate::store_common;

use std::path::Path;

use store_common::{demo_db, demo_name, run, run_ok, shared_instance, shell_words, temp_db};

const DEMO: &str = store_common::DEMO_BUILDING;

fn stderr(out: &std::process::Output) -> String {
    String::from_utf8_lossy(&out.stderr).into_owned()
}

/// Runs and expects exit code 1 with one `error:` line; returns it.
fn run_err(db: &Path, args: &[&str]) -> String {
    let out = run(db, args);
    let e = stderr(&out);
    assert_eq!(out.status.code(), Some(1), "{args:?}: {e}");
    assert!(e.starts_with("error: "), "{e}");
    e
}

/// `plan --building B --start S --end E --budget M`, expected to fail: its error line.
fn plan_err(db: &Path, building: &str, start: &str, end: &str, budget: &str) -> String {
    let args = [
        "--building",
        building,
        "--start",
        start,
        "--end",
        end,
        "--budget",
        budget,
    ];
    run_err(db, &[&["plan"][..], &args].concat())
}

/// The demo's corridor walk, from `f0-c00` to `f0-c15` within `budget` metres.
fn corridor(budget: &str) -> [&str; 6] {
    ["--start", "f0-c00", "--end", "f0-c15", "--budget", budget]
}

/// `COMMAND --building BUILDING` on the demo's [`corridor`] walk within `budget` metres,
/// with `extra` arguments, expected to succeed: its output.
fn on_corridor(db: &Path, command: &str, building: &str, budget: &str, extra: &[&str]) -> String {
    run_ok(
        db,
        &[
            &[command, "--building", building][..],
            &corridor(budget),
            extra,
        ]
        .concat(),
    )
}

/// A human's simulated survey of the demo's corridor walk (40 m, 20% wrong turns, 0.3 s to
/// plan), as `simulate --json` reports it: the session id, the samples collected.
fn simulate_walk(db: &Path, building: &str) -> serde_json::Value {
    let out = on_corridor(
        db,
        "simulate",
        building,
        "40",
        &[
            "--surveyor",
            "human",
            "--deviate",
            "0.2",
            "--time-limit",
            "0.3",
            "--json",
        ],
    );
    serde_json::from_str(out.lines().last().expect("json")).expect("simulate json")
}

/// A database holding the demo building and one plan of it (a human's walk).
fn with_plan(db: &Path) -> (String, i64) {
    run_ok(db, &["import", DEMO]);
    let name = demo_name();
    let out = on_corridor(
        db,
        "plan",
        &name,
        "60",
        &["--model", "human", "--time-limit", "0.3", "--json"],
    );
    let v: serde_json::Value = serde_json::from_str(out.trim()).expect("json");
    (name, v["plan_id"].as_i64().expect("plan_id"))
}

#[test]
fn plans_are_listed_and_shown_with_their_walk() {
    let (_dir, db) = temp_db();
    let empty = run_ok(&db, &["plans"]);
    assert!(empty.starts_with("no plans"), "{empty}");
    let (name, id) = with_plan(&db);

    let list = run_ok(&db, &["plans"]);
    let header = list.lines().next().expect("header");
    for col in [
        "id",
        "building",
        "route",
        "budget_m",
        "length_m",
        "utility",
        "algorithm",
        "created",
    ] {
        assert!(header.contains(col), "{header}");
    }
    let row = list.lines().nth(1).expect("row");
    assert!(row.trim_start().starts_with(&id.to_string()), "{row}");
    assert!(
        row.contains("f0-c00 -> f0-c15") && row.contains("60.0") && row.contains("human"),
        "{row}"
    );

    let json: serde_json::Value =
        serde_json::from_str(run_ok(&db, &["plans", &name, "--json"]).trim()).expect("json");
    let rows = json.as_array().expect("array");
    assert_eq!(rows.len(), 1);
    assert_eq!(rows[0]["id"], id);
    assert_eq!(rows[0]["building"], name.as_str());
    assert_eq!(rows[0]["budget_m"], 60.0);
    assert!(rows[0]["length_m"].as_f64().expect("length") <= 60.0 + 1e-9);
    assert!(
        rows[0]["created"]
            .as_str()
            .expect("created")
            .starts_with("20")
    );

    let e = run_err(&db, &["plans", "No such building"]);
    assert!(e.contains("No such building") && e.contains(&name), "{e}");

    // `plans show`: the figures and the numbered walk, the same walk as stored.
    let show = run_ok(&db, &["plans", "show", &id.to_string()]);
    let stored = &rows[0];
    let walk: Vec<String> = serde_json::from_str::<serde_json::Value>(
        run_ok(&db, &["plans", "show", &id.to_string(), "--json"]).trim(),
    )
    .expect("json")["walk"]
        .as_array()
        .expect("walk")
        .iter()
        .map(|v| v.as_str().expect("id").to_string())
        .collect();
    assert!(
        show.contains(&format!("walk          {}", walk.join(","))),
        "{show}"
    );
    assert!(
        show.contains(&format!("steps         {} vertices", walk.len())),
        "{show}"
    );
    let last_row = format!("{:>4}  {}", walk.len(), walk[walk.len() - 1]);
    assert!(show.contains(&last_row), "{show}");
    assert!(show.contains("at 1.2 m/s"), "{show}");
    assert!(show.contains(&format!(
        "{:.1} m of the 60 m budget",
        stored["length_m"].as_f64().expect("len")
    )));

    let sheet = run_ok(&db, &["plans", "show", &id.to_string(), "--instructions"]);
    assert!(
        sheet.contains("Start at f0-c00 on Ground; check in there"),
        "{sheet}"
    );
    let last = sheet.lines().last().expect("line");
    assert!(
        last.contains(&format!("step {:>3}  In ", walk.len()))
            && last.ends_with("at f0-c15: that is the end of the walk; check in there."),
        "{sheet}"
    );

    let e = run_err(&db, &["plans", "show", "999"]);
    assert!(
        e.contains("no plan 999") && e.contains(&format!("plan ids there: {id}")),
        "{e}"
    );
}

#[test]
fn vertices_lists_ids_labels_floors_and_positions() {
    let (_dir, db, _) = demo_db();
    let b = trailprint::Building::from_json(trailprint::synth::DEMO_BUILDING_JSON, "demo")
        .expect("demo");
    let text = run_ok(&db, &["vertices", &b.name]);
    assert!(
        text.starts_with(&format!("{}: {} vertices", b.name, b.len())),
        "{text}"
    );
    assert_eq!(text.lines().count(), b.len() + 2);
    let door = b
        .vertices
        .iter()
        .find(|v| v.label.is_some())
        .expect("a labelled vertex");
    let line = text
        .lines()
        .find(|l| l.starts_with(&format!("{} ", door.id)))
        .expect("door line");
    assert!(
        line.contains(door.label.as_deref().expect("label")) && line.contains("Ground"),
        "{line}"
    );
    assert!(line.contains(&format!("{:.2}", door.pos.x)), "{line}");

    // From a file too, as JSON, filtered.
    let file = shared_instance("area-two.json");
    let json: serde_json::Value = serde_json::from_str(
        run_ok(
            &db,
            &[
                "vertices",
                file.to_str().expect("utf-8"),
                "--grep",
                "t2",
                "--json",
            ],
        )
        .trim(),
    )
    .expect("json");
    let ids: Vec<&str> = json
        .as_array()
        .expect("array")
        .iter()
        .map(|v| v["id"].as_str().expect("id"))
        .collect();
    assert_eq!(ids, (20..30).map(|i| format!("t{i}")).collect::<Vec<_>>());
    assert!(json[0]["neighbours"].as_array().expect("neighbours").len() >= 2);
}

#[test]
fn fit_of_a_building_in_the_database_is_stored() {
    let (_dir, db, name) = demo_db();
    let fits = |db: &Path| -> i64 {
        let v: serde_json::Value =
            serde_json::from_str(&run_ok(db, &["buildings", "--json"])).expect("json");
        v[0]["fits"].as_i64().expect("fits")
    };
    assert_eq!(fits(&db), 0);
    let out = run_ok(&db, &["fit", "--building", &name]);
    assert!(out.contains("stored          as fit"), "{out}");
    assert_eq!(fits(&db), 1);
    let v: serde_json::Value =
        serde_json::from_str(run_ok(&db, &["fit", "--building", &name, "--json"]).trim())
            .expect("json");
    assert!(v["fit_id"].as_i64().is_some(), "{v}");
    assert_eq!(fits(&db), 2);
    // The stored fit is the one printed.
    let store = trailprint::Store::open(&db).expect("open");
    let latest = store.latest_fit(name.as_str()).expect("fit").expect("some");
    assert!((latest.record.kernel.ell - v["ell"].as_f64().expect("ell")).abs() < 1e-12);
    // A file has nowhere to keep it.
    let out = run_ok(&db, &["fit", "--building", DEMO]);
    assert!(out.contains("stored          no"), "{out}");
    assert_eq!(fits(&db), 2);
}

#[test]
fn demo_prints_words_not_debug_text_and_its_next_steps_work() {
    let (dir, db) = temp_db();
    let out = run_ok(&db, &["demo", "--budget", "40"]);
    assert!(
        !out.contains("Robot {") && !out.contains("Human {") && !out.contains("interval:"),
        "{out}"
    );
    assert!(out.contains("robot, a scan every 0.5 m"), "{out}");
    let next: Vec<&str> = out
        .lines()
        .skip_while(|l| *l != "next steps:")
        .skip(1)
        .filter_map(|l| l.trim().strip_prefix("trailprint "))
        .collect();
    assert_eq!(next.len(), 4, "{out}");
    // Each next step runs as printed (the db option included), bar the arguments that
    // are words of the explanation after it.
    let render = next[0].split("     ").next().expect("command");
    assert!(
        render.contains("render --plan 1 -o demo-plan.svg"),
        "{render}"
    );
    let words: Vec<String> = shell_words(render);
    let status = std::process::Command::new(store_common::BIN)
        .args(&words)
        .current_dir(dir.path())
        .output()
        .expect("run");
    assert!(status.status.success(), "{}", stderr(&status));
    let svg = std::fs::read_to_string(dir.path().join("demo-plan.svg")).expect("svg");
    assert!(svg.contains("class=\"walk walk-0"));
    let vertices = shell_words(next[3].split("     ").next().expect("command"));
    let status = std::process::Command::new(store_common::BIN)
        .args(&vertices)
        .output()
        .expect("run");
    assert!(status.status.success(), "{}", stderr(&status));
}

#[test]
fn a_plan_without_an_end_returns_to_its_start() {
    // Most surveys end where they began: `--end` defaults to `--start`, for `plan` and
    // `simulate` alike, and the route says so.
    let (_dir, db) = temp_db();
    let route = [
        "--building",
        DEMO,
        "--start",
        "f0-c03",
        "--budget",
        "40",
        "--time-limit",
        "0.3",
    ];
    let with =
        |command: &str, extra: &[&str]| run_ok(&db, &[&[command][..], &route, extra].concat());
    let v: serde_json::Value =
        serde_json::from_str(with("plan", &["--json"]).trim()).expect("json");
    let walk = v["walk"].as_array().expect("walk");
    assert_eq!(walk.first().and_then(|x| x.as_str()), Some("f0-c03"), "{v}");
    assert_eq!(walk.last().and_then(|x| x.as_str()), Some("f0-c03"), "{v}");
    assert!(v["length_m"].as_f64().expect("length") > 30.0, "{v}");
    let text = with("plan", &[]);
    assert!(text.contains("route         f0-c03 -> f0-c03"), "{text}");
    let sim = with("simulate", &["--surveyor", "human", "--json"]);
    let s: serde_json::Value =
        serde_json::from_str(sim.lines().last().expect("json")).expect("simulate json");
    assert_eq!(s["status"], "finished", "{s}");
    let id = s["plan_id"].as_i64().expect("plan_id").to_string();
    let shown = run_ok(&db, &["plans", "show", &id, "--json"]);
    let p: serde_json::Value = serde_json::from_str(shown.trim()).expect("plan json");
    assert_eq!(
        (p["start"].as_str(), p["end"].as_str()),
        (Some("f0-c03"), Some("f0-c03")),
        "{p}"
    );
}

#[test]
fn plan_is_printed_for_a_person() {
    let (_dir, db) = temp_db();
    let person = ["--model", "human", "--time-limit", "0.3"];
    let out = on_corridor(&db, "plan", DEMO, "70", &person);
    let walk: Vec<&str> = out
        .lines()
        .find_map(|l| l.strip_prefix("walk          "))
        .expect("walk line")
        .split(',')
        .collect();
    let b = trailprint::Building::from_json(trailprint::synth::DEMO_BUILDING_JSON, "demo")
        .expect("demo");
    let length: f64 = {
        let idx = b.resolve_walk(&walk).expect("walk");
        b.walk_length(&idx)
    };
    // The time at the surveyor's 1.2 m/s.
    let secs = (length / 1.2).round() as u64;
    let expect = if secs < 60 {
        format!("about {secs} s at 1.2 m/s")
    } else {
        format!("about {} min {:02} s at 1.2 m/s", secs / 60, secs % 60)
    };
    assert!(out.contains(&expect), "{expect}\n{out}");
    // Every vertex numbered, with its label where it has one.
    for (i, id) in walk.iter().enumerate() {
        let line = out
            .lines()
            .find(|l| l.starts_with(&format!("  {:>4}  {id} ", i + 1)))
            .unwrap_or_else(|| panic!("no step {} {id} in\n{out}", i + 1));
        if let Some(label) = b.vertex_index(id).and_then(|v| b.vertices[v].label.clone()) {
            assert!(line.contains(&label), "{line}");
        }
    }
    // The sheet: the guidance sentences of a live session.
    let sheet = on_corridor(
        &db,
        "plan",
        DEMO,
        "70",
        &[&person[..], &["--instructions"]].concat(),
    );
    let lines: Vec<&str> = sheet.lines().filter(|l| l.contains(". step ")).collect();
    assert!(!lines.is_empty(), "{sheet}");
    for l in &lines {
        let sentence = l.split_once("  In ").map(|x| x.1).expect("sentence");
        assert!(sentence.contains(" m at "), "{l}");
        assert!(
            [
                "turn left",
                "turn right",
                "turn back",
                "go straight on",
                "change floor",
                "end of the walk"
            ]
            .iter()
            .any(|w| sentence.contains(w)),
            "{l}"
        );
    }
    // The distances on the sheet add up to the walk's length (each rounded to 1 m).
    let total: f64 = lines
        .iter()
        .map(|l| {
            l.split_once("  In ")
                .and_then(|x| x.1.split(' ').next())
                .and_then(|d| d.parse::<f64>().ok())
                .expect("distance")
        })
        .sum();
    assert!(
        (total - length).abs() <= 0.5 * lines.len() as f64 + 1e-9,
        "{total} vs {length}"
    );
}

#[test]
fn errors_say_what_would_do() {
    let (dir, db) = temp_db();
    // A near-miss vertex id gets the nearest ids.
    let e = plan_err(&db, DEMO, "f0-c0", "f0-c15", "30");
    assert!(
        e.contains("start: unknown vertex \"f0-c0\"") && e.contains("did you mean \"f0-c00\""),
        "{e}"
    );
    let e = run_err(
        &db,
        &["utility", "--building", DEMO, "--walk", "f0-c00,f0-c1"],
    );
    assert!(e.contains("did you mean"), "{e}");
    // CSV, Markdown and text given as a building.
    for (name, text, begins) in [
        ("pilot.csv", "x,y,ap-01\n0,0,-60\n", "x,y,ap-01"),
        ("notes.md", "# Survey\n\nsome notes\n", "# Survey"),
        ("empty.json", "", "the file is empty"),
    ] {
        let path = dir.path().join(name);
        std::fs::write(&path, text).expect("write");
        let building = plan_err(&db, path.to_str().expect("utf-8"), "a", "a", "5");
        let e = &building;
        assert!(
            e.contains(&format!("{name}: not a JSON survey-building/1 file")) && e.contains(begins),
            "{e}"
        );
        assert!(
            !e.contains("expected ident") && !e.contains("expected value"),
            "{e}"
        );
        // The same files given as a floor plan or a pilot list say what they are not.
        let file = path.to_str().expect("utf-8");
        let plan = run_err(&db, &["import-floorplan", file]);
        assert!(
            plan.contains(&format!("{name}: not a GeoJSON floor plan")) && plan.contains(begins),
            "{plan}"
        );
        let pilot = run_err(&db, &["pilot", "add", DEMO, file]);
        assert!(
            pilot.contains(&format!("{name}: not a JSON pilot list")) && pilot.contains(begins),
            "{pilot}"
        );
        // JSON paths are named, the document itself (`$`) is not.
        for e in [&building, &plan, &pilot] {
            assert!(!e.contains("$:"), "{e}");
        }
    }
    // Broken JSON as a floor plan: where it breaks, without the `$` of the document.
    let broken = dir.path().join("cut.geojson");
    std::fs::write(&broken, "{\"type\": \"FeatureCollection\", \"features\": [").expect("write");
    let e = run_err(&db, &["import-floorplan", broken.to_str().expect("utf-8")]);
    assert!(
        e.contains("cut.geojson: not a GeoJSON floor plan")
            && e.contains("line 1")
            && !e.contains("$:"),
        "{e}"
    );
    // A negative budget is a number the planner refuses, not an unknown option.
    for cmd in ["plan", "simulate"] {
        let mut args = vec![
            cmd,
            "--building",
            DEMO,
            "--start",
            "f0-c00",
            "--end",
            "f0-c00",
            "--budget",
            "-5",
        ];
        if cmd == "simulate" {
            args.extend(["--surveyor", "human"]);
        }
        let e = run_err(&db, &args);
        assert!(
            e.contains("budget must be a positive") && e.contains("-5"),
            "{cmd}: {e}"
        );
    }
    // An absurd budget is named as typed, not as 309 digits.
    let e = run_err(
        &db,
        &[
            "plan",
            "--building",
            DEMO,
            "--start",
            "f0-c00",
            "--budget=1e308",
        ],
    );
    assert!(
        e.contains("budget 1e308 m is more than 4 times") && e.len() < 600,
        "{e}"
    );
    // A directory as --db.
    let e = run_err(dir.path(), &["buildings"]);
    assert!(
        e.contains("is a directory")
            && e.contains(&format!("{}", dir.path().join("trailprint.db").display())),
        "{e}"
    );
}

#[test]
fn render_draws_plans_sessions_and_teams() {
    let (dir, db) = temp_db();
    let (name, id) = with_plan(&db);
    let svg_of = |args: &[&str]| -> String {
        let path = dir.path().join("out.svg");
        let mut all = args.to_vec();
        all.extend(["-o", path.to_str().expect("utf-8")]);
        run_ok(&db, &all);
        std::fs::read_to_string(&path).expect("svg")
    };
    let stored = trailprint::Store::open(&db)
        .expect("open")
        .load_plan(id)
        .expect("plan");
    let svg = svg_of(&["render", "--plan", &id.to_string()]);
    assert_eq!(
        svg.matches("class=\"walk walk-0").count(),
        stored.record.walk.len() - 1,
        "one segment per step of the stored walk"
    );
    assert!(
        svg.contains(&format!("plan {id}: f0-c00 -&gt; f0-c15")),
        "caption"
    );
    assert!(
        svg.contains("class=\"heat\""),
        "heat map with the plan's kernel"
    );
    assert!(svg.contains("class=\"step\""), "step numbers");
    assert!(svg.contains(&format!(
        "class=\"legend-text\" x=\"18\" y=\"4\">plan {id},"
    )));

    // A session: the walk as walked, with its scans.
    let sim = simulate_walk(&db, &name);
    let sid = sim["session_id"].as_i64().expect("session id");
    let svg = svg_of(&["render", "--session", &sid.to_string()]);
    assert_eq!(
        svg.matches("class=\"sample\"").count(),
        sim["samples"].as_u64().expect("samples") as usize + 1,
        "one dot per collected scan, plus the legend's"
    );
    assert!(svg.contains("class=\"track\""), "the track as walked");
    assert!(
        svg.contains(&format!("session {sid} (finished)")),
        "caption"
    );

    // A team: plan ids and typed walks, one colour each.
    let svg = svg_of(&[
        "render",
        "--team",
        &id.to_string(),
        "--team",
        "f0-c15,f0-c14,f0-c13",
    ]);
    assert!(svg.contains("class=\"walk walk-0") && svg.contains("class=\"walk walk-1"));
    assert!(
        svg.contains("surveyor 2: 4.0 m"),
        "legend names each surveyor"
    );
    let e = run_err(&db, &["render", "--team", "f0-c00,f0-c01", "-o", "x.svg"]);
    assert!(e.contains("--building"), "{e}");
    let e = run_err(&db, &["render", "--plan", "999", "-o", "x.svg"]);
    assert!(e.contains("no plan 999"), "{e}");
    // A plan of one building drawn on another is refused.
    run_ok(
        &db,
        &[
            "import",
            shared_instance("area-two.json").to_str().expect("utf-8"),
        ],
    );
    let e = run_err(
        &db,
        &[
            "render",
            "--plan",
            &id.to_string(),
            "--building",
            "Area Two (synthetic)",
            "-o",
            "x.svg",
        ],
    );
    assert!(e.contains("belongs to building"), "{e}");
}

#[test]
fn team_plan_keeps_its_walks_as_plans() {
    let (_dir, db, name) = demo_db();
    let out = run_ok(
        &db,
        &[
            "team-plan",
            "--building",
            &name,
            "--surveyor",
            "f0-c00:f0-c00:20",
            "--surveyor",
            "f0-c15:f0-c15:20",
            "--algorithm",
            "greedy",
            "--json",
        ],
    );
    let v: serde_json::Value = serde_json::from_str(out.trim()).expect("json");
    let ids: Vec<i64> = v["plan_ids"]
        .as_array()
        .expect("plan ids")
        .iter()
        .map(|x| x.as_i64().expect("id"))
        .collect();
    assert_eq!(ids.len(), 2);
    let store = trailprint::Store::open(&db).expect("open");
    for (i, id) in ids.iter().enumerate() {
        let p = store.load_plan(*id).expect("plan");
        assert_eq!(serde_json::json!(p.record.walk), v["walks"][i]);
    }
}

/// Runs `trailprint --db db COMMAND --building BUILDING ARGS` (`args` split at spaces,
/// with `--progress --json`), reads its stderr until
/// `until` holds for a progress line, interrupts it (SIGINT, as Ctrl-C) and waits. Checks
/// what every interrupted planning command does: each stderr line before is a progress
/// line, the process says it stops with the best so far, exits 0 within `within`, and
/// prints one JSON line on stdout, which is returned.
fn interrupted(
    db: &Path,
    command: &str,
    building: &str,
    args: &str,
    until: impl Fn(&str) -> bool,
    within: std::time::Duration,
) -> serde_json::Value {
    use std::io::{BufRead, Read};
    let mut child = std::process::Command::new(env!("CARGO_BIN_EXE_trailprint"))
        .arg("--db")
        .arg(db)
        .args([command, "--building", building])
        .args(args.split_whitespace())
        .args(["--progress", "--json"])
        .stdout(std::process::Stdio::piped())
        .stderr(std::process::Stdio::piped())
        .spawn()
        .expect("spawn");
    let started = std::time::Instant::now();
    let mut err = std::io::BufReader::new(child.stderr.take().expect("stderr"));
    let mut line = String::new();
    loop {
        line.clear();
        assert!(
            err.read_line(&mut line).expect("stderr") > 0,
            "no such progress line"
        );
        assert!(line.starts_with("planning "), "{line}");
        if until(&line) {
            break;
        }
    }
    let killed = std::process::Command::new("kill")
        .args(["-INT", &child.id().to_string()])
        .status()
        .expect("kill");
    assert!(killed.success());
    let mut rest = String::new();
    err.read_to_string(&mut rest).expect("stderr");
    let mut out = String::new();
    let mut stdout = child.stdout.take().expect("stdout");
    stdout.read_to_string(&mut out).expect("stdout");
    assert!(child.wait().expect("wait").success(), "{line}{rest}");
    assert!(started.elapsed() < within, "took {:?}", started.elapsed());
    assert!(
        rest.contains("interrupted: stopping with the best walk so far"),
        "{rest}"
    );
    assert_eq!(out.lines().count(), 1, "{out}");
    serde_json::from_str(out.trim()).expect("json")
}

/// `plan --progress` writes its progress to stderr only, and Ctrl-C during a long plan
/// prints the best walk so far as the result (`termination: cancelled`), saved.
#[test]
fn plan_shows_progress_and_ctrl_c_returns_the_best_walk_so_far_saved() {
    let (_dir, db, name) = demo_db();
    // Branch and bound on 120 m of the demo building: far longer than the test without
    // the interrupt. Interrupted once a report carries a best walk.
    let v = interrupted(
        &db,
        "plan",
        &name,
        "--start f0-c00 --end f0-c00 --budget 120 --algorithm exact --time-limit 600",
        |line| line.contains(" nats"),
        std::time::Duration::from_secs(60),
    );
    assert_eq!(v["termination"], "cancelled", "{v}");
    let walk = v["walk"].as_array().expect("walk");
    assert!(walk.len() > 2 && walk[0] == "f0-c00" && walk[walk.len() - 1] == "f0-c00");
    assert!(v["length_m"].as_f64().expect("length") <= 120.0 + 1e-9);
    let stored = trailprint::Store::open(&db)
        .expect("open")
        .load_plan(v["plan_id"].as_i64().expect("plan id"))
        .expect("plan");
    assert_eq!(serde_json::json!(stored.record.walk), v["walk"]);
}

/// `team-plan --progress` shows each run's progress on stderr (stdout stays one JSON
/// object), and Ctrl-C stops the team plan with a walk for every surveyor, saved.
#[test]
fn team_plan_shows_progress_and_ctrl_c_keeps_the_walks_so_far() {
    let (_dir, db, name) = demo_db();
    // Long enough runs (20 s each) that the interrupt comes during the first.
    let v = interrupted(
        &db,
        "team-plan",
        &name,
        "--surveyor f0-c00:f0-c00:60 --surveyor f0-c15:f0-c15:60 --time-limit 20",
        |line| {
            assert!(line.contains("surveyor 1/2, in turn: "), "{line}");
            true
        },
        std::time::Duration::from_secs(15),
    );
    assert_eq!(v["cancelled"], true, "{v}");
    assert_eq!(
        v["terminations"],
        serde_json::json!(["cancelled", "cancelled"]),
        "{v}"
    );
    let store = trailprint::Store::open(&db).expect("open");
    let ids = v["plan_ids"].as_array().expect("plan ids");
    assert_eq!(ids.len(), 2);
    for (i, (id, start)) in ids.iter().zip(["f0-c00", "f0-c15"]).enumerate() {
        let p = store.load_plan(id.as_i64().expect("id")).expect("plan");
        assert_eq!(serde_json::json!(p.record.walk), v["walks"][i]);
        assert_eq!(p.record.walk.first().map(String::as_str), Some(start));
        assert_eq!(p.record.walk.last().map(String::as_str), Some(start));
        assert!(p.record.length_m <= 60.0 + 1e-9);
    }
}

/// `plan --start ID` with an id as a user types it, on the bundled buildings: the floor
/// prefix of the generated ids left out (`c0` for `f0-c00`), leading zeros left out
/// (`b5` for `b05`), a number past the end, a label instead of an id.
#[test]
fn unknown_vertex_suggests_the_ids_of_the_bundled_buildings() {
    let (_dir, db) = temp_db();
    let area_two = shared_instance("area-two.json");
    let area_two = area_two.to_str().expect("utf-8");
    for (building, typed, end, expect) in [
        (DEMO, "c0", "f0-c15", "; did you mean \"f0-c00\"?"),
        (DEMO, "C3", "f0-c15", "; did you mean \"f0-c03\"?"),
        (DEMO, "f0-c0", "f0-c15", "; did you mean \"f0-c00\"?"),
        (DEMO, "c16", "f0-c15", "; did you mean \"f0-c15\""),
        (DEMO, "r2", "f0-c15", "; did you mean \"f0-r2-door\", "),
        (DEMO, "Room 1", "f0-c15", "\"f0-r0-door\""),
        (
            DEMO,
            "c99",
            "f0-c15",
            "; did you mean \"f0-c09\"? (the 16 ids like it run from \"f0-c00\" to \"f0-c15\"",
        ),
        (area_two, "b5", "t29", "; did you mean \"b05\"?"),
        (area_two, "t3", "t29", "; did you mean \"t03\"?"),
    ] {
        let e = plan_err(&db, building, typed, end, "30");
        assert!(
            e.contains(&format!("start: unknown vertex {typed:?}")) && e.contains(expect),
            "{typed}: {e}"
        );
    }
    // The end and a walk are answered the same way.
    let e = plan_err(&db, DEMO, "f0-c00", "c15", "30");
    assert!(
        e.contains("end: unknown vertex \"c15\"") && e.contains("did you mean \"f0-c15\"?"),
        "{e}"
    );
    let e = run_err(&db, &["utility", "--building", DEMO, "--walk", "c0,c1"]);
    assert!(e.contains("did you mean \"f0-c00\"?"), "{e}");
}

/// The class tokens of an SVG's elements, split at the legend: (drawn on the floors,
/// in the legend's swatches). Containers (`<g>`), the floor frames (`panel`), the
/// outlines' lines redrawn over the heat map (`outline-line`), a walk's colour index
/// (`walk-N`) and text in words (titles, "stairs to Level 1 (4 m)", "start = end": they
/// say what they are) are left out.
fn mark_classes(
    svg: &str,
) -> (
    std::collections::BTreeSet<String>,
    std::collections::BTreeSet<String>,
) {
    let legend_at = svg.find("<g class=\"legend\">").expect("a legend");
    let classes = |part: &str| {
        let mut out = std::collections::BTreeSet::new();
        for tag in part.split('<').skip(1) {
            let name = tag.split([' ', '>', '/']).next().unwrap_or("");
            if name == "g" || name.is_empty() {
                continue;
            }
            let Some(class) = tag
                .split("class=\"")
                .nth(1)
                .and_then(|c| c.split('"').next())
            else {
                continue;
            };
            let text = tag.split_once('>').map_or("", |(_, t)| t);
            if name == "text" && text.contains(' ') {
                continue;
            }
            for c in class.split_whitespace() {
                let walk_index = c
                    .strip_prefix("walk-")
                    .is_some_and(|n| n.parse::<u32>().is_ok());
                let words = ["heading", "title", "subtitle", "legend-text", "heat-scale"];
                if !(walk_index || words.contains(&c) || c == "panel" || c == "outline-line") {
                    out.insert(c.to_string());
                }
            }
        }
        out
    };
    (classes(&svg[..legend_at]), classes(&svg[legend_at..]))
}

/// Every kind of mark a map draws has its legend entry, and the legend has no entry for a
/// mark the map does not draw ("edge walked twice" only when an edge is walked twice):
/// an imported floor plan (building footprint, rooms, walls, stairs, an elevator) with a
/// walk that ends where it starts and vertex ids, a walk there and back and one that is
/// not, two surveyors who share an edge and two who do not, and a session as walked.
#[test]
fn every_mark_on_a_map_has_its_legend_entry() {
    let (dir, db) = temp_db();
    let office = concat!(
        env!("CARGO_MANIFEST_DIR"),
        "/tests/fixtures/floorplans/office-l.geojson"
    );
    run_ok(&db, &["import-floorplan", office, "--name", "Office"]);
    run_ok(&db, &["import", DEMO]);
    let demo = demo_name();
    let out = run_ok(
        &db,
        &[
            "plan",
            "--building",
            "Office",
            "--start",
            "f0-s0-1",
            "--end",
            "f0-s0-1",
            "--budget",
            "60",
            "--kernel",
            "40,6,9",
            "--model",
            "human",
            "--time-limit",
            "0.3",
            "--json",
        ],
    );
    let plan: serde_json::Value =
        serde_json::from_str(out.lines().last().expect("json")).expect("plan json");
    let plan_id = plan["plan_id"].as_i64().expect("plan id").to_string();
    let sim = simulate_walk(&db, &demo);
    let session = sim["session_id"].as_i64().expect("session id").to_string();
    // Two surveyors, the first walking f0-c00 to f0-c01, the second the walk given.
    let team_with = |second| {
        vec![
            "--building",
            &demo,
            "--team",
            "f0-c00,f0-c01",
            "--team",
            second,
        ]
    };
    let cases: Vec<(&str, Vec<&str>, Option<bool>)> = vec![
        (
            "office, start = end, ids",
            vec!["--plan", &plan_id, "--labels"],
            None,
        ),
        (
            "there and back",
            vec!["--building", &demo, "--walk", "f0-c00,f0-c01,f0-c00"],
            Some(true),
        ),
        (
            "one way",
            vec!["--building", &demo, "--walk", "f0-c00,f0-c01,f0-c02"],
            Some(false),
        ),
        (
            "team sharing an edge",
            team_with("f0-c02,f0-c01,f0-c00"),
            Some(true),
        ),
        ("team apart", team_with("f0-c03,f0-c04"), Some(false)),
        ("session", vec!["--session", &session], None),
    ];
    for (what, args, repeat) in cases {
        let path = dir.path().join("map.svg");
        let mut all = vec!["render"];
        all.extend(args);
        all.extend(["-o", path.to_str().expect("utf-8")]);
        run_ok(&db, &all);
        let svg = std::fs::read_to_string(&path).expect("svg");
        let (drawn, legend) = mark_classes(&svg);
        let missing: Vec<_> = drawn.difference(&legend).collect();
        assert!(
            missing.is_empty(),
            "{what}: drawn without a legend entry: {missing:?}"
        );
        let extra: Vec<_> = legend.difference(&drawn).collect();
        assert!(
            extra.is_empty(),
            "{what}: in the legend, not drawn: {extra:?}"
        );
        if let Some(r) = repeat {
            assert_eq!(svg.contains("edge walked twice"), r, "{what}");
        }
        if what.starts_with("office") {
            // Footprint, rooms, walls, the elevator and the stairs, the marker and the ids.
            for c in [
                "outline-building",
                "outline-room",
                "outline-wall",
                "lift",
                "stairs",
                "start-end",
                "label",
            ] {
                assert!(drawn.contains(c), "{what}: no {c} drawn");
            }
            assert!(
                svg.contains(">elevator to "),
                "{what}: the elevator is called one"
            );
            assert!(
                svg.contains(">stairs to "),
                "{what}: the stairs are called stairs"
            );
        }
    }
}

/// Small things a user reads: a robot's plan is timed at the robot's speed (not a
/// person's 1.2 m/s); `fit` of a building without pilot data says how to add it; the
/// collected CSV holds numbers to the millimetre and 0.01 dB, not `4.199999999999999`.
#[test]
fn robot_time_fit_without_pilot_and_collected_csv_digits() {
    let (dir, db, demo) = demo_db();
    let out = on_corridor(
        &db,
        "plan",
        demo.as_str(),
        "40",
        &["--model", "robot", "--time-limit", "0.3"],
    );
    let length: f64 = out
        .lines()
        .find_map(|l| l.strip_prefix("length"))
        .and_then(|l| l.split_whitespace().next())
        .and_then(|l| l.parse().ok())
        .expect("length line");
    let secs = (length / 0.5).round() as u64;
    assert!(
        out.contains(&format!(
            "about {} min {:02} s at the robot's 0.5 m/s",
            secs / 60,
            secs % 60
        )) || out.contains(&format!("about {secs} s at the robot's 0.5 m/s")),
        "{out}"
    );
    assert!(!out.contains("1.2 m/s"), "{out}");
    let fast = on_corridor(
        &db,
        "plan",
        demo.as_str(),
        "40",
        &[
            "--model",
            "robot",
            "--time-limit",
            "0.3",
            "--robot-speed",
            "2",
        ],
    );
    assert!(fast.contains("at the robot's 2 m/s"), "{fast}");

    // A floor plan has no pilot data: fit says how to add it.
    let office = concat!(
        env!("CARGO_MANIFEST_DIR"),
        "/tests/fixtures/floorplans/office-l.geojson"
    );
    run_ok(&db, &["import-floorplan", office, "--name", "Office"]);
    let e = run_err(&db, &["fit", "--building", "Office"]);
    assert!(
        e.contains("no pilot fingerprints")
            && e.contains("trailprint pilot add \"Office\" FILE.json")
            && e.contains("--kernel"),
        "{e}"
    );

    // The collected fingerprints of a walk with wrong turns (estimated positions).
    on_corridor(
        &db,
        "simulate",
        demo.as_str(),
        "40",
        &[
            "--surveyor",
            "human",
            "--deviate",
            "0.3",
            "--seed",
            "3",
            "--time-limit",
            "0.3",
        ],
    );
    let csv = dir.path().join("c.csv");
    run_ok(
        &db,
        &[
            "export",
            demo.as_str(),
            "--collected",
            "csv",
            "-o",
            csv.to_str().expect("utf-8"),
        ],
    );
    let text = std::fs::read_to_string(&csv).expect("csv");
    let mut rows = 0;
    for line in text.lines().skip(1) {
        rows += 1;
        for (i, field) in line.split(',').enumerate().skip(3).filter(|(i, _)| *i != 5) {
            let decimals = field.split_once('.').map_or(0, |(_, d)| d.len());
            let most = if i <= 7 { 3 } else { 2 };
            assert!(decimals <= most, "column {i}: {field} in {line}");
        }
    }
    assert!(rows > 5, "{text}");
}
