//! Shared helpers of the fuzz targets: a byte reader that turns fuzz input into values
//! (with the edge cases a parser must refuse coming up often), the small building the
//! session and bundle targets work on, and a row-for-row snapshot of a store.

use trailprint::Building;
use trailprint::building::{BuildingFile, FloorSpec};
use trailprint::store::Store;

/// The building the session and bundle targets use: a corridor `a-b-c-d` with a branch
/// `b-e` (so a surveyor can take a wrong turn) and a stair `d-f` to floor 1, with pilot
/// data and a kernel.
pub const SMALL_BUILDING_JSON: &str = r#"{"format":"survey-building/1","name":"Fuzz",
"floors":[{"id":0,"name":"ground"},{"id":1}],
"vertices":[{"id":"a","x":0,"y":0},{"id":"b","x":4,"y":0,"label":"junction"},
{"id":"c","x":8,"y":0},{"id":"d","x":8,"y":4},{"id":"e","x":4,"y":-4},
{"id":"f","x":8,"y":4,"floor":1}],
"edges":[{"a":"a","b":"b"},{"a":"b","b":"c"},{"a":"c","b":"d"},{"a":"b","b":"e"},
{"a":"d","b":"f","length":8}],
"pilot":[{"x":0,"y":0,"rss":{"ap1":-40,"ap2":-70}},{"x":8,"y":4,"floor":1,"rss":{"ap1":-75}}],
"kernel":{"sf2":20,"ell":5,"sn2":2}}"#;

/// The parsed and validated [`SMALL_BUILDING_JSON`].
pub fn small_building() -> Building {
    match Building::from_json(SMALL_BUILDING_JSON, "fuzz building") {
        Ok(b) => b,
        Err(e) => panic!("the fuzz building is invalid: {e}"),
    }
}

/// Reads values off the fuzz input; past the end every read gives zero.
pub struct Bytes<'a> {
    data: &'a [u8],
    pos: usize,
}

impl<'a> Bytes<'a> {
    pub fn new(data: &'a [u8]) -> Self {
        Bytes { data, pos: 0 }
    }

    pub fn is_empty(&self) -> bool {
        self.pos >= self.data.len()
    }

    pub fn u8(&mut self) -> u8 {
        let b = self.data.get(self.pos).copied().unwrap_or(0);
        self.pos += 1;
        b
    }

    pub fn u32(&mut self) -> u32 {
        u32::from_le_bytes([self.u8(), self.u8(), self.u8(), self.u8()])
    }

    pub fn u64(&mut self) -> u64 {
        u64::from(self.u32()) | (u64::from(self.u32()) << 32)
    }

    /// A float: mostly ordinary values, often a value on or past a limit (NaN, the
    /// infinities, -0, subnormals, 1e308, the RSS and coordinate bounds).
    pub fn f64(&mut self) -> f64 {
        const EDGE: [f64; 16] = [
            f64::NAN,
            f64::INFINITY,
            f64::NEG_INFINITY,
            -0.0,
            0.0,
            5e-324,
            1e308,
            -1e308,
            1e6,
            1e6 + 1.0,
            -120.0,
            -120.000_000_1,
            0.0,
            1e-7,
            f64::MAX,
            f64::MIN_POSITIVE,
        ];
        match self.u8() % 4 {
            0 => EDGE[usize::from(self.u8() % 16)],
            1 => f64::from_bits(self.u64()),
            _ => f64::from(self.u8() as i8) / 4.0,
        }
    }

    /// A short string: one of `known` most of the time, else raw bytes (lossy UTF-8).
    pub fn string(&mut self, known: &[&str]) -> String {
        let k = usize::from(self.u8());
        if k < 200 && !known.is_empty() {
            return known[k % known.len()].to_string();
        }
        let n = usize::from(self.u8() % 16);
        let start = self.pos.min(self.data.len());
        let end = (start + n).min(self.data.len());
        self.pos += n;
        String::from_utf8_lossy(&self.data[start..end]).into_owned()
    }
}

/// The floor list a file gives, with the implicit default (`floors` absent) spelled out,
/// so that two files that mean the same floors compare equal.
pub fn normalised(mut file: BuildingFile) -> BuildingFile {
    if file.floors.as_deref() == Some(&[FloorSpec { id: 0, name: None }][..]) {
        file.floors = None;
    }
    file
}

/// Checks that an accepted building re-exports to an equal building: its export parses and
/// validates again, says the same as `given` (the file it was accepted from, when known),
/// and exports to the same text.
pub fn check_reexport(b: &Building, given: Option<&BuildingFile>, what: &str) {
    let first = b.to_file();
    if let Some(g) = given {
        assert_eq!(
            &normalised(g.clone()),
            &first,
            "{what}: validation changed the building"
        );
    }
    let text = first.to_json();
    let again = Building::from_json(&text, "re-export")
        .unwrap_or_else(|e| panic!("{what}: the export of an accepted building is refused: {e}"));
    let second = again.to_file();
    assert_eq!(first, second, "{what}: re-export differs");
    assert_eq!(text, second.to_json(), "{what}: re-export text differs");
    assert_eq!(b.graph.node_count(), b.len());
    assert_eq!(b.graph.edge_count(), b.edges.len());
    for e in &b.edges {
        assert!(
            e.length.is_finite() && e.length >= trailprint::building::MIN_EDGE_LENGTH,
            "{what}: edge length {}",
            e.length
        );
    }
    assert!(
        b.total_edge_length().is_finite(),
        "{what}: total edge length"
    );
}

/// Every row of every table of the store, in rowid order, as text: equal snapshots mean an
/// unchanged database.
pub fn snapshot(store: &Store) -> Vec<String> {
    let out = store.with_connection(|c| {
        let tables: Vec<String> = c
            .prepare("SELECT name FROM sqlite_master WHERE type = 'table' ORDER BY name")?
            .query_map([], |r| r.get(0))?
            .collect::<Result<_, _>>()?;
        let mut out = Vec::new();
        for t in tables {
            let mut st = c.prepare(&format!("SELECT * FROM \"{t}\""))?;
            let n = st.column_count();
            let rows: Vec<String> = st
                .query_map([], |r| {
                    let mut row = format!("{t}:");
                    for i in 0..n {
                        let v: rusqlite::types::Value = r.get(i)?;
                        row.push_str(&format!(" {v:?}"));
                    }
                    Ok(row)
                })?
                .collect::<Result<_, _>>()?;
            out.push(format!("{t}: {} rows", rows.len()));
            out.extend(rows);
        }
        Ok(out)
    });
    match out {
        Ok(v) => v,
        Err(e) => panic!("cannot read the store back: {e}"),
    }
}

// ---- bundles ----

use std::collections::BTreeMap;

use trailprint::gp::Kernel;
use trailprint::store::{
    BuildingRef, CollectedFingerprint, ExportOptions, ImportOptions, PlanRecord, SessionEvent,
};

fn plan_record(walk: &[&str]) -> PlanRecord {
    PlanRecord {
        start: walk[0].into(),
        end: walk[walk.len() - 1].into(),
        budget_m: 40.0,
        surveyor: Some(trailprint::surveyor::Surveyor::robot()),
        kernel: Kernel::new(20.0, 5.0, 2.0),
        algorithm: trailprint::plan::Algorithm::Greedy.into(),
        seed: Some(1),
        walk: walk.iter().map(|s| s.to_string()).collect(),
        length_m: 12.0,
        samples: 25,
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
        rss: BTreeMap::from([("ap1".to_string(), rss), ("ap2".to_string(), rss - 10.0)]),
    })
}

fn ok<T>(r: trailprint::Result<T>, what: &str) -> T {
    match r {
        Ok(v) => v,
        Err(e) => panic!("{what}: {e}"),
    }
}

/// A store holding [`SMALL_BUILDING_JSON`] and one session (global id `uid`) of a check-in,
/// `scans` scans and a replan, at times from `t0`.
pub fn device_store(uid: &str, t0: i64, scans: usize) -> Store {
    let s = ok(Store::open_in_memory(), "store");
    let b = small_building();
    let id = ok(
        s.import_building(&b, Some("fuzz"), &ImportOptions::default()),
        "import",
    )
    .id;
    let p1 = ok(
        s.save_plan(BuildingRef::Id(id), &plan_record(&["a", "b", "c", "d"])),
        "plan",
    );
    let p2 = ok(
        s.save_plan(BuildingRef::Id(id), &plan_record(&["b", "c", "d"])),
        "plan",
    );
    let sid = ok(
        s.create_session(BuildingRef::Id(id), Some(p1), None, t0),
        "session",
    );
    ok(
        s.append_event(sid, t0 + 1, &SessionEvent::CheckIn { vertex: "a".into() }),
        "check-in",
    );
    ok(
        s.append_event(
            sid,
            t0 + 2,
            &SessionEvent::Step {
                steps: 3,
                distance_m: 2.1,
            },
        ),
        "step",
    );
    for i in 0..scans {
        ok(
            s.append_event(sid, t0 + 10 + i as i64, &scan(i as f64, -50.0 - i as f64)),
            "scan",
        );
    }
    ok(
        s.append_event(sid, t0 + 100, &SessionEvent::Replan { plan_id: p2 }),
        "replan",
    );
    ok(
        s.with_connection(|c| {
            c.execute(
                "UPDATE survey_sessions SET uid = ?1 WHERE id = ?2",
                rusqlite::params![uid, sid],
            )?;
            Ok(())
        }),
        "uid",
    );
    s
}

/// The store the bundle target imports into: session `base` with two scans.
pub fn bundle_base() -> Store {
    device_store("base", 1_700_000_000_000, 2)
}

/// Seed bundles: the base session again (nothing new), the base session walked on (an
/// extension, then finished), another device's session, and a building of another name.
pub fn bundle_seeds() -> Vec<(&'static str, String)> {
    let export = |s: &Store| {
        ok(
            s.export_bundle(
                "Fuzz",
                &ExportOptions {
                    device: Some("phone".into()),
                    surveyor_name: Some("Ann".into()),
                    sessions: Vec::new(),
                },
            ),
            "export",
        )
    };
    let mut out = vec![("same", export(&bundle_base()))];
    let longer = device_store("base", 1_700_000_000_000, 2);
    ok(
        longer.append_event(1, 1_700_000_000_200, &scan(3.0, -60.0)),
        "scan",
    );
    ok(
        longer.append_event(
            1,
            1_700_000_000_300,
            &SessionEvent::Pose {
                x: 8.0,
                y: 4.0,
                floor: 1,
                sigma_m: 0.5,
            },
        ),
        "pose",
    );
    ok(
        longer.append_event(1, 1_700_000_000_400, &SessionEvent::Pause),
        "pause",
    );
    ok(
        longer.append_event(1, 1_700_000_000_500, &SessionEvent::Resume),
        "resume",
    );
    ok(
        longer.append_event(1, 1_700_000_000_600, &SessionEvent::Finish),
        "finish",
    );
    out.push(("extended", export(&longer)));
    let other = device_store("other", 1_700_000_100_000, 3);
    ok(
        other.append_event(
            1,
            1_700_000_100_900,
            &SessionEvent::Abort {
                reason: Some("battery".into()),
            },
        ),
        "abort",
    );
    out.push(("other", export(&other)));
    let renamed = bundle_base();
    ok(
        renamed.with_connection(|c| {
            c.execute("UPDATE buildings SET name = 'Fuzz annexe'", [])?;
            Ok(())
        }),
        "rename",
    );
    out.push((
        "renamed",
        ok(
            renamed.export_bundle("Fuzz annexe", &ExportOptions::default()),
            "export",
        ),
    ));
    out
}

/// The bundle checksum of a body (SHA-256 of its compact JSON, keys sorted).
pub fn bundle_checksum(body: &serde_json::Value) -> String {
    use sha2::Digest;
    sha2::Sha256::digest(body.to_string().as_bytes())
        .iter()
        .map(|b| format!("{b:02x}"))
        .collect()
}

// ---- floor plans ----

use std::cell::RefCell;

use trailprint::floorplan::FloorplanImport;

thread_local! {
    /// The in-memory store the floor-plan targets import into, as `trailprint
    /// import-floorplan` does; kept from input to input (every accepted building is deleted
    /// again, so it stays empty between inputs).
    static FLOORPLAN_STORE: RefCell<Option<Store>> = const { RefCell::new(None) };
}

/// The rows of a snapshot without SQLite's autoincrement counters (an import and a delete
/// move them on and leave every other row as it was).
pub fn without_counters(snap: Vec<String>) -> Vec<String> {
    snap.into_iter()
        .filter(|r| !r.starts_with("sqlite_sequence"))
        .collect()
}

/// Grid cells the floor-plan targets let an import lay (`ImportOptions::max_grid_cells`),
/// against 100,000 in the product: about the 5,000 vertices the planner takes under its
/// default memory budget. At the product's limit a 10 KB plan legitimately grows 28,000
/// vertices, which the instrumented binary imports, round-trips through the store and
/// checks for leaks in 25 s (0.3 s in release): every such input was a timeout, and the
/// runs spent their time there instead of on mutations. A plan over the limit still takes
/// the refusal path, and the large imports are replayed in release by the ordinary tests
/// (`core/tests/fuzz_regressions.rs`).
pub const FLOORPLAN_MAX_GRID_CELLS: usize = 5_000;

/// The import options of the floor-plan targets: the defaults with
/// [`FLOORPLAN_MAX_GRID_CELLS`].
pub fn floorplan_options() -> trailprint::floorplan::ImportOptions {
    trailprint::floorplan::ImportOptions {
        max_grid_cells: FLOORPLAN_MAX_GRID_CELLS,
        ..Default::default()
    }
}

/// Checks a floor-plan import's outcome and takes it on to a store in memory, as
/// `trailprint import-floorplan` does (`Building::from_file`, then `Store::import_building`).
///
/// A refusal is an `Err` naming something, and the store is row for row unchanged. An
/// accepted plan is a valid building (it passes the same validation as a file), re-exports
/// to an equal building, and its counts match it; the store takes it (a store refusing a
/// building the validator accepts is a bug, and must leave the store unchanged), reads it
/// back equal (`export_building` validates it again; floor outlines and geo-reference
/// included), and deleting it leaves no row
/// behind.
pub fn check_floorplan(result: trailprint::Result<FloorplanImport>, what: &str) {
    FLOORPLAN_STORE.with(|cell| {
        let mut cell = cell.borrow_mut();
        let store = cell.get_or_insert_with(|| ok(Store::open_in_memory(), "in-memory store"));
        let before = snapshot(store);
        let imp = match result {
            Err(e) => {
                assert!(!e.to_string().is_empty(), "{what}: an error saying nothing");
                assert_eq!(
                    before,
                    snapshot(store),
                    "{what}: a refused floor plan changed the store"
                );
                return;
            }
            Ok(imp) => imp,
        };
        let b = Building::from_file(imp.file.clone(), what).unwrap_or_else(|e| {
            panic!("{what}: the importer wrote a building the validator refuses: {e}")
        });
        check_reexport(&b, Some(&imp.file), what);
        assert_eq!(imp.stats.vertices, b.len(), "{what}: vertex count");
        assert_eq!(imp.stats.edges, b.edges.len(), "{what}: edge count");
        let report = match store.import_building(&b, Some(what), &ImportOptions::default()) {
            Ok(r) => r,
            Err(e) => {
                assert_eq!(
                    before,
                    snapshot(store),
                    "{what}: a refused import changed the store ({e})"
                );
                panic!("{what}: the store refuses a building the validator accepts: {e}");
            }
        };
        let back = ok(store.export_building(report.id), "export from the store");
        assert_eq!(back, b.to_file(), "{what}: the store changed the building");
        ok(store.delete_building(report.id), "delete");
        assert_eq!(
            without_counters(before),
            without_counters(snapshot(store)),
            "{what}: deleting the imported building left rows behind"
        );
    });
}
