//! From a floor plan to a plan, a simulated survey, a picture and the exports positioning
//! engines read, through the command line (issue 17, parts 1 and 2).

#![allow(clippy::expect_used, clippy::unwrap_used)]

use std::path::Path;

use trailprint::Store;
use trailprint::radiomap::{ScanRow, read_jsonl, read_uji_csv};

use crate::store_common::{run, temp_db};

fn fixture(name: &str) -> String {
    format!(
        "{}/tests/fixtures/floorplans/{name}",
        env!("CARGO_MANIFEST_DIR")
    )
}

/// Exports the radio map of `Office` (2 m grid) to the CSV `path`; its rows, header left out.
fn radio_map_rows(db: &Path, path: &Path) -> Vec<String> {
    let p = path.to_str().unwrap();
    ok(
        db,
        &["export", "Office", "--radio-map", "--grid", "2", "-o", p],
    );
    let text = std::fs::read_to_string(path).unwrap();
    text.lines().skip(1).map(str::to_string).collect()
}

fn ok(db: &Path, args: &[&str]) -> String {
    let out = run(db, args);
    assert!(
        out.status.success(),
        "{args:?}: {}\n{}",
        String::from_utf8_lossy(&out.stdout),
        String::from_utf8_lossy(&out.stderr)
    );
    String::from_utf8(out.stdout).unwrap()
}

/// The same scan, field for field (positions and readings exactly).
fn same(a: &ScanRow, b: &ScanRow) {
    assert_eq!(
        (
            a.source.as_str(),
            a.session,
            a.seq,
            a.time_ms,
            a.x,
            a.y,
            a.floor,
            a.sigma_m
        ),
        (
            b.source.as_str(),
            b.session,
            b.seq,
            b.time_ms,
            b.x,
            b.y,
            b.floor,
            b.sigma_m
        )
    );
    assert_eq!(a.rss, b.rss);
    assert_eq!((a.lon, a.lat), (b.lon, b.lat));
}

#[test]
fn floor_plan_to_plan_simulation_picture_and_exports() {
    let (dir, db) = temp_db();
    let db = db.as_path();

    let out = ok(
        db,
        &[
            "import-floorplan",
            &fixture("office-l.geojson"),
            "--name",
            "Office",
        ],
    );
    assert!(
        out.contains("imported building") && out.contains("2 floors"),
        "{out}"
    );
    assert!(out.contains("pilot add"), "{out}");

    let b = Store::open(db).unwrap().get_building("Office").unwrap();
    assert!(
        b.geo.is_some() && !b.outlines.is_empty(),
        "geo and outlines are stored"
    );
    let start = b
        .vertices
        .iter()
        .find(|v| v.label.as_deref() == Some("Corridor 0"))
        .unwrap()
        .id
        .clone();
    let route = ["--start", &start, "--end", &start, "--budget", "60"];

    // Without pilot data, plan says what it needs.
    let mut args = vec!["plan", "--building", "Office", "--time-limit", "0.5"];
    args.extend(route);
    let out = run(db, &args);
    assert!(!out.status.success());
    let err = String::from_utf8_lossy(&out.stderr);
    assert!(
        err.contains("--kernel") && err.contains("pilot add"),
        "{err}"
    );

    // Pilot data at six corridor vertices, three access points with a path-loss falloff.
    let aps = [("ap-a", 2.0, 2.0), ("ap-b", 25.0, 1.0), ("ap-c", 1.0, 18.0)];
    let pilot: Vec<serde_json::Value> = b
        .vertices
        .iter()
        .filter(|v| v.label.as_deref() == Some("Corridor 0"))
        .step_by(3)
        .take(6)
        .map(|v| {
            let rss: serde_json::Map<String, serde_json::Value> = aps
                .iter()
                .map(|(n, x, y)| {
                    let d = ((v.pos.x - x).powi(2) + (v.pos.y - y).powi(2)).sqrt();
                    (
                        n.to_string(),
                        serde_json::json!((-40.0 - 20.0 * (d + 1.0).log10()).round()),
                    )
                })
                .collect();
            serde_json::json!({"x": v.pos.x, "y": v.pos.y, "floor": 0, "rss": rss})
        })
        .collect();
    assert_eq!(pilot.len(), 6);
    let pilot_path = dir.path().join("pilot.json");
    std::fs::write(&pilot_path, serde_json::to_string(&pilot).unwrap()).unwrap();
    let out = ok(
        db,
        &["pilot", "add", "Office", pilot_path.to_str().unwrap()],
    );
    assert!(out.contains("added 6 pilot fingerprints"), "{out}");
    // A pilot point on a floor the building does not have changes nothing.
    let bad = dir.path().join("bad.json");
    std::fs::write(
        &bad,
        r#"[{"x": 1, "y": 1, "floor": 7, "rss": {"ap-a": -50}}]"#,
    )
    .unwrap();
    let out = run(db, &["pilot", "add", "Office", bad.to_str().unwrap()]);
    assert!(!out.status.success());
    let err = String::from_utf8_lossy(&out.stderr);
    assert!(
        err.contains("[0].floor") && err.contains("floor 7"),
        "{err}"
    );
    assert_eq!(
        Store::open(db)
            .unwrap()
            .get_building("Office")
            .unwrap()
            .pilot
            .len(),
        6
    );

    // The radio map of the pilot data: every access point on a grid over the walkable outlines.
    let rows = radio_map_rows(db, &dir.path().join("map.csv"));
    assert!(
        !rows.is_empty() && rows.len().is_multiple_of(3),
        "{} rows",
        rows.len()
    );
    for r in &rows {
        let f: Vec<&str> = r.split(',').collect();
        let (mean, sd): (f64, f64) = (f[6].parse().unwrap(), f[7].parse().unwrap());
        assert!((-130.0..0.0).contains(&mean) && sd > 0.0, "{r}");
        assert!(
            !f[3].is_empty() && !f[4].is_empty(),
            "longitude and latitude: {r}"
        );
    }
    let map_json = dir.path().join("map.geojson");
    ok(
        db,
        &[
            "export",
            "Office",
            "--radio-map",
            "--grid",
            "2",
            "-o",
            map_json.to_str().unwrap(),
        ],
    );
    let doc: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(&map_json).unwrap()).unwrap();
    let feats = doc["features"].as_array().unwrap();
    assert_eq!(feats.len(), rows.len() / 3);
    assert_eq!(
        feats[0]["properties"]["mean_dbm"]
            .as_object()
            .unwrap()
            .len(),
        3
    );
    // Near an access point its mean is higher than far from it.
    let ap_a = |f: &serde_json::Value| f["properties"]["mean_dbm"]["ap-a"].as_f64().unwrap();
    let d = |f: &serde_json::Value| {
        let (x, y) = (
            f["properties"]["x"].as_f64().unwrap(),
            f["properties"]["y"].as_f64().unwrap(),
        );
        ((x - 2.0).powi(2) + (y - 2.0).powi(2)).sqrt()
    };
    let floor0: Vec<&serde_json::Value> = feats
        .iter()
        .filter(|f| f["properties"]["floor"] == 0)
        .collect();
    let near = floor0.iter().min_by(|a, b| d(a).total_cmp(&d(b))).unwrap();
    let far = floor0.iter().max_by(|a, b| d(a).total_cmp(&d(b))).unwrap();
    assert!(
        ap_a(near) > ap_a(far) + 3.0,
        "{} vs {}",
        ap_a(near),
        ap_a(far)
    );

    // Plan, simulate, render.
    let mut args = vec![
        "plan",
        "--building",
        "Office",
        "--time-limit",
        "0.5",
        "--json",
    ];
    args.extend(route);
    let plan: serde_json::Value = serde_json::from_str(ok(db, &args).trim()).unwrap();
    assert!(plan["walk"].as_array().unwrap().len() > 2, "{plan}");
    assert!(plan["length_m"].as_f64().unwrap() <= 60.0 + 1e-9);
    let mut args = vec![
        "simulate",
        "--building",
        "Office",
        "--surveyor",
        "human",
        "--time-limit",
        "0.5",
        "--seed",
        "3",
        "--json",
    ];
    args.extend(route);
    let sim = ok(db, &args);
    assert!(sim.lines().last().unwrap().starts_with('{'), "{sim}");
    let svg = dir.path().join("office.svg");
    ok(
        db,
        &[
            "render",
            "--building",
            "Office",
            "-o",
            svg.to_str().unwrap(),
        ],
    );
    let svg = std::fs::read_to_string(svg).unwrap();
    for class in [
        "outline outline-room",
        "outline outline-corridor",
        "outline outline-wall",
        "class=\"edge\"",
    ] {
        assert!(svg.contains(class), "{class}");
    }
    // The outlines are drawn before (under) the graph.
    assert!(svg.find("outline outline-room").unwrap() < svg.find("class=\"edge\"").unwrap());

    // Fingerprints out: UJIIndoorLoc columns and JSON lines read back to the same scans.
    let store = Store::open(db).unwrap();
    let b = store.get_building("Office").unwrap();
    let collected = store.list_collected("Office", None).unwrap();
    assert!(
        !collected.is_empty(),
        "the simulated session collected fingerprints"
    );
    let expected = trailprint::radiomap::scan_rows(&b, &collected, &Default::default());
    let csv = dir.path().join("scans.csv");
    ok(
        db,
        &[
            "export",
            "Office",
            "--fingerprints",
            "-o",
            csv.to_str().unwrap(),
        ],
    );
    let text = std::fs::read_to_string(&csv).unwrap();
    let header = text.lines().next().unwrap();
    assert!(
        header.starts_with("WAP001,WAP002,WAP003,WAP004,"),
        "{header}"
    );
    assert!(
        header.contains(",LONGITUDE,LATITUDE,FLOOR,BUILDINGID,SPACEID,RELATIVEPOSITION,USERID,PHONEID,TIMESTAMP,"),
        "{header}"
    );
    let waps = std::fs::read_to_string(dir.path().join("scans.waps.csv")).unwrap();
    assert!(
        waps.starts_with("WAP,name\r\nWAP001,ap-a\r\nWAP002,ap-b\r\nWAP003,ap-c\r\n"),
        "{waps}"
    );
    // "Not heard" is UJIIndoorLoc's 100: the pilot rows did not hear the simulated APs.
    assert!(text.lines().nth(1).unwrap().split(',').nth(3) == Some("100.0"));
    let back = read_uji_csv(&text, Some(&waps), "scans.csv").unwrap();
    assert_eq!(back.len(), expected.len());
    assert_eq!(back.len(), 6 + collected.len());
    for (a, e) in back.iter().zip(&expected) {
        same(a, e);
    }
    let jsonl_path = dir.path().join("scans.jsonl");
    ok(
        db,
        &[
            "export",
            "Office",
            "--fingerprints",
            "--format",
            "jsonl",
            "-o",
            jsonl_path.to_str().unwrap(),
        ],
    );
    let back = read_jsonl(
        &std::fs::read_to_string(&jsonl_path).unwrap(),
        "scans.jsonl",
    )
    .unwrap();
    assert_eq!(back.len(), expected.len());
    for (a, e) in back.iter().zip(&expected) {
        same(a, e);
    }

    // After the session, the radio map holds its access points too.
    let n_aps = waps.lines().count() - 1;
    assert!(n_aps > 3);
    assert_eq!(
        radio_map_rows(db, &dir.path().join("map2.csv")).len() % n_aps,
        0
    );
}

#[test]
fn import_to_a_file_and_refusals() {
    let (dir, db) = temp_db();
    let out_path = dir.path().join("mall.json");
    let out = ok(
        &db,
        &[
            "import-floorplan",
            &fixture("mall-imdf"),
            "-o",
            out_path.to_str().unwrap(),
        ],
    );
    assert!(out.contains("Galerie Test"), "{out}");
    assert!(
        !db.exists(),
        "-o writes the file and leaves the database alone"
    );
    let b = trailprint::Building::load(&out_path).unwrap();
    assert_eq!(b.floors.len(), 2);
    // Messy input: warnings on stderr, a building all the same.
    let out = run(
        &db,
        &["import-floorplan", &fixture("messy.geojson"), "-o", "-"],
    );
    assert!(out.status.success());
    let err = String::from_utf8_lossy(&out.stderr);
    assert!(err.contains("warning: unclosed rings (closed): 2"), "{err}");
    assert!(
        err.contains("dropped a part") && err.contains("Island"),
        "{err}"
    );
    trailprint::Building::from_json(&String::from_utf8_lossy(&out.stdout), "stdout").unwrap();
    // Nothing walkable: refused, and the database untouched.
    let out = run(
        &db,
        &["import-floorplan", &fixture("nothing-walkable.geojson")],
    );
    assert_eq!(out.status.code(), Some(1));
    assert!(String::from_utf8_lossy(&out.stderr).contains("nothing walkable"));
    assert!(!db.exists());
}
