//! Survey bundles (issue 9): merging is idempotent and order-independent, provenance is
//! kept, and a corrupt or truncated bundle is rejected with nothing imported.

use std::collections::BTreeMap;

use trailprint::building::Building;
use trailprint::gp::Kernel;
use trailprint::store::{
    BuildingRef, CollectedFingerprint, ExportOptions, ImportOptions, PlanRecord, SessionEvent,
    Store,
};
use trailprint::synth::DEMO_BUILDING_JSON;

fn demo() -> Building {
    Building::from_json(DEMO_BUILDING_JSON, "demo").expect("demo")
}

fn plan_record(walk: &[&str]) -> PlanRecord {
    PlanRecord {
        start: walk[0].into(),
        end: walk[walk.len() - 1].into(),
        budget_m: 50.0,
        surveyor: Some(trailprint::surveyor::Surveyor::robot()),
        kernel: Kernel::new(40.0, 6.0, 4.0),
        algorithm: trailprint::plan::Algorithm::Greedy.into(),
        seed: Some(1),
        walk: walk.iter().map(|s| s.to_string()).collect(),
        length_m: 10.0,
        samples: 21,
        utility_nats: 3.5,
        elapsed_ms: 12,
        created_ms: 1_700_000_000_000,
    }
}

fn scan(x: f64, rss: f64) -> SessionEvent {
    SessionEvent::Scan(CollectedFingerprint {
        x,
        y: 0.0,
        floor: 0,
        sigma_m: 0.1 * x,
        since_checkin_m: Some(x),
        rss: BTreeMap::from([
            ("ap-01".to_string(), rss),
            ("ap-02".to_string(), rss - 10.0),
        ]),
    })
}

/// A store with the demo building and one session of `n` scans (plus a check-in and a
/// replan) recorded at times starting from `t0`.
fn device(t0: i64, n: usize) -> (Store, i64) {
    let s = Store::open_in_memory().expect("store");
    let b = demo();
    let id = s
        .import_building(&b, Some("demo"), &ImportOptions::default())
        .expect("import")
        .id;
    let first = b.vertices[0].id.clone();
    let second = b.vertices[1].id.clone();
    let p1 = s
        .save_plan(BuildingRef::Id(id), &plan_record(&[&first, &second]))
        .expect("plan");
    let p2 = s
        .save_plan(BuildingRef::Id(id), &plan_record(&[&first]))
        .expect("plan");
    let sid = s
        .create_session(BuildingRef::Id(id), Some(p1), None, t0)
        .expect("session");
    s.append_event(
        sid,
        t0 + 1,
        &SessionEvent::CheckIn {
            vertex: first.clone(),
        },
    )
    .expect("check-in");
    for i in 0..n {
        s.append_event(sid, t0 + 10 + i as i64, &scan(i as f64, -50.0 - i as f64))
            .expect("scan");
    }
    s.append_event(sid, t0 + 100, &SessionEvent::Replan { plan_id: p2 })
        .expect("replan");
    (s, sid)
}

/// Everything a merge must agree on, independent of local ids: per session uid, its
/// provenance and its event log (kinds, times, scans).
fn content(s: &Store) -> Vec<String> {
    let mut out = Vec::new();
    for b in s.list_buildings().expect("list") {
        for sess in s.list_sessions(BuildingRef::Id(b.id)).expect("sessions") {
            let (uid, device, who): (Option<String>, Option<String>, Option<String>) = s
                .with_connection(|c| {
                    Ok(c.query_row(
                        "SELECT uid, device, surveyor_name FROM survey_sessions WHERE id = ?1",
                        [sess.id],
                        |r| Ok((r.get(0)?, r.get(1)?, r.get(2)?)),
                    )?)
                })
                .expect("row");
            let events: Vec<String> = s
                .list_events(sess.id, 0)
                .expect("events")
                .iter()
                .map(|e| match &e.event {
                    SessionEvent::Replan { .. } => format!("{} {} replan", e.seq, e.at_ms),
                    other => format!(
                        "{} {} {}",
                        e.seq,
                        e.at_ms,
                        serde_json::to_string(other).expect("json")
                    ),
                })
                .collect();
            out.push(format!(
                "{uid:?} {device:?} {who:?} {} {}",
                sess.created_ms,
                events.join("|")
            ));
        }
    }
    out.sort();
    out
}

fn counts(s: &Store) -> (i64, i64, i64, i64) {
    s.with_connection(|c| {
        let q = |sql: &str| c.query_row(sql, [], |r| r.get::<_, i64>(0));
        Ok((
            q("SELECT count(*) FROM survey_sessions")?,
            q("SELECT count(*) FROM session_events")?,
            q("SELECT count(*) FROM collected_fingerprints")?,
            q("SELECT count(*) FROM plans")?,
        ))
    })
    .expect("counts")
}

fn export(s: &Store, device: &str, who: &str) -> String {
    s.export_bundle(
        BuildingRef::Name(&demo().name),
        &ExportOptions {
            device: Some(device.into()),
            surveyor_name: Some(who.into()),
            sessions: vec![],
        },
    )
    .expect("export")
}

#[test]
fn importing_twice_changes_nothing_and_order_does_not_matter() {
    let (a, _) = device(1_000, 5);
    let (c, _) = device(5_000, 3);
    let ba = export(&a, "phone-a", "Ann");
    let bc = export(&c, "phone-c", "Cid");
    // Into an empty database (the building comes with the bundle) in both orders.
    let x = Store::open_in_memory().expect("x");
    let r = x.import_bundle(&ba, "a.json").expect("a");
    assert!(r.building_created);
    assert_eq!((r.sessions_added, r.events_added), (1, 7));
    x.import_bundle(&bc, "c.json").expect("c");
    let before = (content(&x), counts(&x));
    let again = x.import_bundle(&ba, "a.json").expect("a again");
    assert_eq!(
        (
            again.sessions_added,
            again.sessions_extended,
            again.events_added
        ),
        (0, 0, 0)
    );
    x.import_bundle(&bc, "c.json").expect("c again");
    assert_eq!(
        (content(&x), counts(&x)),
        before,
        "a second import must change nothing"
    );
    let y = Store::open_in_memory().expect("y");
    y.import_bundle(&bc, "c.json").expect("c");
    y.import_bundle(&ba, "a.json").expect("a");
    assert_eq!(content(&y), content(&x), "order must not matter");
    // Provenance is kept.
    assert!(
        content(&x)
            .iter()
            .any(|c| c.contains("\"phone-a\"") && c.contains("\"Ann\""))
    );
    assert_eq!(counts(&x), (2, 7 + 5, 5 + 3, 4));
}

#[test]
fn a_session_exported_again_after_walking_on_gets_only_its_new_events() {
    let (a, sid) = device(1_000, 2);
    let early = export(&a, "phone-a", "Ann");
    a.append_event(sid, 2_000, &scan(9.0, -70.0)).expect("scan");
    a.append_event(sid, 2_001, &SessionEvent::Finish)
        .expect("finish");
    let late = export(&a, "phone-a", "Ann");
    let x = Store::open_in_memory().expect("x");
    x.import_bundle(&early, "early").expect("early");
    let r = x.import_bundle(&late, "late").expect("late");
    assert_eq!(
        (r.sessions_added, r.sessions_extended, r.events_added),
        (0, 1, 2)
    );
    let y = Store::open_in_memory().expect("y");
    y.import_bundle(&late, "late").expect("late");
    let r = y.import_bundle(&early, "early").expect("early");
    assert_eq!((r.sessions_extended, r.events_added), (0, 0));
    assert_eq!(content(&x), content(&y));
    // The exporting device keeps the uid: exporting again names the session the same.
    assert_eq!(
        trailprint::store::parse_bundle(&early, "e")
            .expect("e")
            .1
            .sessions[0]
            .uid,
        trailprint::store::parse_bundle(&late, "l")
            .expect("l")
            .1
            .sessions[0]
            .uid
    );
}

#[test]
fn corrupt_or_truncated_bundles_are_rejected_and_nothing_is_imported() {
    let (a, _) = device(1_000, 4);
    let good = export(&a, "phone-a", "Ann");
    let x = Store::open_in_memory().expect("x");
    let before = counts(&x);
    let truncated = &good[..good.len() / 2];
    let e = refused(&x, truncated, "half.json");
    assert!(
        e.starts_with("half.json: not a complete bundle (truncated or not JSON)"),
        "{e}"
    );
    // Flip one RSS value inside the body: still valid JSON, but the checksum fails.
    let corrupt = good.replacen("-51.0", "-15.0", 1);
    assert_ne!(corrupt, good);
    let e = refused(&x, &corrupt, "flip.json");
    assert!(
        e.contains("flip.json: sha256: checksum mismatch: the bundle is corrupt"),
        "{e}"
    );
    let e = refused(&x, "{\"format\":\"trailprint-bundle/9\"}", "v9.json");
    assert!(
        e.contains("unknown bundle format \"trailprint-bundle/9\""),
        "{e}"
    );
    assert_eq!(counts(&x), before);
    assert!(
        x.list_buildings().expect("list").is_empty(),
        "no building may be created either"
    );
}

/// Imports `text` as `origin` into `x`, which must refuse it; the error message.
fn refused(x: &Store, text: &str, origin: &str) -> String {
    match x.import_bundle(text, origin) {
        Ok(r) => panic!("{origin} must be refused, it imported: {r:?}"),
        Err(e) => e.to_string(),
    }
}

/// Device A's bundle (one session of 3 scans), a database that imported it, and that
/// database's content and counts: what a refused import must leave as it was.
#[allow(clippy::type_complexity)]
fn imported_once() -> (String, Store, (Vec<String>, (i64, i64, i64, i64))) {
    let (a, _) = device(1_000, 3);
    let good = export(&a, "phone-a", "Ann");
    let x = Store::open_in_memory().expect("x");
    x.import_bundle(&good, "a").expect("a");
    let before = (content(&x), counts(&x));
    (good, x, before)
}

#[test]
fn conflicting_histories_are_refused_whole() {
    let (good, x, before) = imported_once();
    // Same session uid, different history: rewrite a time and recompute the checksum.
    let mut doc: serde_json::Value = serde_json::from_str(&good).expect("json");
    doc["body"]["sessions"][0]["events"][1]["at_ms"] = 999_999.into();
    let events = doc["body"]["sessions"][0]["events"]
        .as_array_mut()
        .expect("events");
    events.push(serde_json::json!({"seq": events.len() + 1, "at_ms": 1_000_000, "event": {"kind": "finish"}}));
    let forged = resign(&mut doc);
    let e = refused(&x, &forged, "forged");
    assert!(e.contains("conflicting histories at event 2"), "{e}");
    assert_eq!((content(&x), counts(&x)), before);
}

/// Re-signs a bundle document after editing its body (what a forger, or a buggy exporter,
/// produces: the checksum is right, the content is not).
fn resign(doc: &mut serde_json::Value) -> String {
    use sha2::Digest;
    let body = doc["body"].to_string();
    doc["sha256"] = sha2::Sha256::digest(body.as_bytes())
        .iter()
        .map(|b| format!("{b:02x}"))
        .collect::<String>()
        .into();
    doc.to_string()
}

#[test]
fn a_shared_event_that_differs_in_a_reading_is_a_conflict() {
    let (good, x, before) = imported_once();
    // Same kinds, same times: only one RSS reading of the second scan (event 3) changes.
    let mut doc: serde_json::Value = serde_json::from_str(&good).expect("json");
    let uid = doc["body"]["sessions"][0]["uid"]
        .as_str()
        .expect("uid")
        .to_string();
    let ev = &mut doc["body"]["sessions"][0]["events"][2];
    assert_eq!(ev["event"]["kind"], "scan");
    ev["event"]["rss"]["ap-01"] = (-99.0).into();
    let forged = resign(&mut doc);
    let e = refused(&x, &forged, "forged");
    assert!(
        e.contains(&format!(
            "(session {uid}): conflicting histories at event 3"
        )),
        "{e}"
    );
    assert!(e.contains("-99") && e.contains("-51"), "{e}");
    assert_eq!((content(&x), counts(&x)), before, "nothing may change");

    // A replan to another plan (same kind, same time) conflicts as well.
    let mut doc: serde_json::Value = serde_json::from_str(&good).expect("json");
    let n = doc["body"]["sessions"][0]["events"]
        .as_array()
        .expect("events")
        .len();
    let replan = &doc["body"]["sessions"][0]["events"][n - 1]["event"];
    assert_eq!(replan["kind"], "replan");
    let target = replan["plan_id"].as_i64().expect("plan id");
    for p in doc["body"]["sessions"][0]["plans"]
        .as_array_mut()
        .expect("plans")
    {
        if p["source_id"] == target {
            p["plan"]["budget_m"] = 77.0.into();
        }
    }
    let forged = resign(&mut doc);
    let e = refused(&x, &forged, "forged");
    assert!(
        e.contains(&format!("conflicting histories at event {n}")) && e.contains("different plans"),
        "{e}"
    );
    assert_eq!((content(&x), counts(&x)), before);
}

#[test]
fn events_after_finish_are_refused_in_bundles_and_in_the_store() {
    let (a, sid) = device(1_000, 2);
    a.append_event(sid, 5_000, &SessionEvent::Finish)
        .expect("finish");
    // The store itself accepts nothing after the end of a log.
    let before = counts(&a);
    let e = a
        .append_event(sid, 5_001, &scan(1.0, -60.0))
        .expect_err("after finish")
        .to_string();
    assert!(
        e.contains("the session ended with finish at event") && e.contains("(got scan)"),
        "{e}"
    );
    assert_eq!(counts(&a), before);

    let good = export(&a, "phone-a", "Ann");
    let mut doc: serde_json::Value = serde_json::from_str(&good).expect("json");
    let events = doc["body"]["sessions"][0]["events"]
        .as_array_mut()
        .expect("events");
    let n = events.len();
    events.push(serde_json::json!({"seq": n + 1, "at_ms": 6_000, "event": {"kind": "step", "steps": 2, "distance_m": 1.4}}));
    let forged = resign(&mut doc);
    let x = Store::open_in_memory().expect("x");
    let e = refused(&x, &forged, "late.json");
    assert!(
        e.contains(&format!(
            "late.json: body.sessions[0].events[{n}]: session "
        )) && e.contains(&format!(
            "event {} (step) comes after the session ended with finish at event {n}",
            n + 1
        )),
        "{e}"
    );
    assert!(x.list_buildings().expect("list").is_empty());
}

#[test]
fn a_same_name_building_with_other_geometry_is_refused() {
    let (a, _) = device(1_000, 2);
    let good = export(&a, "phone-a", "Ann");
    // The receiving database has a building of the same name, one vertex moved.
    let mut file = demo().to_file();
    let moved = file.vertices[3].id.clone();
    file.vertices[3].x += 0.5;
    let other = Building::from_file(file, "moved").expect("still valid");
    let x = Store::open_in_memory().expect("x");
    x.import_building(&other, Some("moved"), &ImportOptions::default())
        .expect("import");
    let before = (content(&x), counts(&x));
    let e = refused(&x, &good, "a.json");
    assert!(
        e.contains(&format!(
            "a.json: body.building: building {:?} (id 1) is already in the database with other geometry (vertex {moved:?} is at",
            demo().name
        )),
        "{e}"
    );
    assert_eq!((content(&x), counts(&x)), before);
    // The same geometry (labels and survey data aside) is the same building.
    let mut file = demo().to_file();
    file.vertices[3].label = Some("relabelled".into());
    file.test_points.clear();
    let same = Building::from_file(file, "same").expect("valid");
    let y = Store::open_in_memory().expect("y");
    y.import_building(&same, Some("same"), &ImportOptions::default())
        .expect("import");
    let r = y.import_bundle(&good, "a.json").expect("same geometry");
    assert!(!r.building_created && r.sessions_added == 1);
}
