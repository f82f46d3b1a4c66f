-- 0001_init: the first schema of the Trailprint store.
--
-- Applied by core/src/store/migrations.rs inside one transaction, which then sets
-- PRAGMA user_version = 1. Never edit this file once released: add 0002_*.sql instead
-- (core/tests/store_migrations.rs replays committed dumps of older databases and fails if
-- an old step changes under them). No BEGIN/COMMIT here: the migrator owns the transaction.
--
-- Conventions (see schema/README.md):
-- * every table has a stable id: an INTEGER PRIMARY KEY (AUTOINCREMENT where an id must never
--   be reused after a delete, because the app may hold it), or a natural key;
-- * vertices are referred to by their stable text id from the building file, never by an
--   in-memory index;
-- * `ord` columns keep the order of the building file so that export reproduces it;
-- * times are milliseconds since the Unix epoch (UTC), columns named *_ms;
-- * every foreign key has an index whose leading columns are the referencing columns, so that
--   cascades and integrity checks do not scan whole tables.

-- A building: one survey-building/1 document.
CREATE TABLE buildings (
    id            INTEGER PRIMARY KEY AUTOINCREMENT,
    name          TEXT    NOT NULL UNIQUE CHECK (length(trim(name)) > 0),
    source        TEXT,                       -- where it was imported from (file name), for people
    imported_ms   INTEGER NOT NULL,
    vertex_count  INTEGER NOT NULL CHECK (vertex_count > 0),  -- written in the import transaction
    edge_count    INTEGER NOT NULL CHECK (edge_count >= 0),
    -- Optional kernel of the file: all three or none.
    kernel_sf2    REAL,
    kernel_ell    REAL,
    kernel_sn2    REAL,
    CHECK ((kernel_sf2 IS NULL AND kernel_ell IS NULL AND kernel_sn2 IS NULL)
        OR (kernel_sf2 > 0 AND kernel_ell > 0 AND kernel_sn2 > 0))
);

CREATE TABLE floors (
    building_id INTEGER NOT NULL REFERENCES buildings(id) ON DELETE CASCADE,
    floor       INTEGER NOT NULL,             -- the file's floor id
    ord         INTEGER NOT NULL,
    name        TEXT,
    PRIMARY KEY (building_id, floor),
    UNIQUE (building_id, ord)
) WITHOUT ROWID;

CREATE TABLE vertices (
    id          INTEGER PRIMARY KEY,          -- rowid table: see `edges`
    building_id INTEGER NOT NULL,
    vid         TEXT    NOT NULL CHECK (length(vid) > 0),  -- stable id from the file
    ord         INTEGER NOT NULL,
    x           REAL    NOT NULL,
    y           REAL    NOT NULL,
    floor       INTEGER NOT NULL,
    label       TEXT,
    UNIQUE (building_id, vid),
    UNIQUE (building_id, ord),
    UNIQUE (building_id, floor, x, y),        -- SPEC 1: no two vertices of a floor share a position
    FOREIGN KEY (building_id, floor) REFERENCES floors(building_id, floor) ON DELETE CASCADE
);

-- Undirected edges; `length` NULL means "the Euclidean distance", as in the file.
-- A rowid table on purpose (so are vertices): as WITHOUT ROWID with PRIMARY KEY
-- (building_id, ord), SQLite's planner (without ANALYZE statistics) looked up the cascade
-- from a deleted vertex by the primary-key prefix `building_id` rather than by
-- (building_id, a), scanning every edge of the building per vertex: deleting a
-- 1,600-vertex building took 0.9 s instead of 0.1 s.
CREATE TABLE edges (
    id          INTEGER PRIMARY KEY,
    building_id INTEGER NOT NULL,
    ord         INTEGER NOT NULL,
    a           TEXT    NOT NULL,
    b           TEXT    NOT NULL,
    length      REAL CHECK (length IS NULL OR length >= 1e-6),
    UNIQUE (building_id, ord),
    UNIQUE (building_id, a, b),
    CHECK (a <> b),
    FOREIGN KEY (building_id, a) REFERENCES vertices(building_id, vid) ON DELETE CASCADE,
    FOREIGN KEY (building_id, b) REFERENCES vertices(building_id, vid) ON DELETE CASCADE
);
CREATE INDEX edges_b ON edges (building_id, b);

-- Every access point ever heard in a building (pilot, test, dense or collected data), so
-- that readings and fits refer to one row per access point.
CREATE TABLE access_points (
    id          INTEGER PRIMARY KEY,
    building_id INTEGER NOT NULL REFERENCES buildings(id) ON DELETE CASCADE,
    name        TEXT    NOT NULL,             -- the key of the `rss` maps (BSSID or label)
    UNIQUE (building_id, name)
);

-- The fingerprints of the building file: `pilot`, `test_points` and `dense_survey`.
CREATE TABLE fingerprint_kinds (
    kind TEXT PRIMARY KEY
) WITHOUT ROWID;
INSERT INTO fingerprint_kinds (kind) VALUES ('pilot'), ('test_points'), ('dense_survey');

CREATE TABLE fingerprints (
    id          INTEGER PRIMARY KEY,
    building_id INTEGER NOT NULL,
    kind        TEXT    NOT NULL REFERENCES fingerprint_kinds(kind),
    ord         INTEGER NOT NULL,
    x           REAL    NOT NULL,
    y           REAL    NOT NULL,
    floor       INTEGER NOT NULL,
    UNIQUE (building_id, kind, ord),
    FOREIGN KEY (building_id, floor) REFERENCES floors(building_id, floor) ON DELETE CASCADE
);
CREATE INDEX fingerprints_floor ON fingerprints (building_id, floor);
CREATE INDEX fingerprints_kind ON fingerprints (kind);

CREATE TABLE fingerprint_readings (
    fingerprint_id INTEGER NOT NULL REFERENCES fingerprints(id) ON DELETE CASCADE,
    ap_id          INTEGER NOT NULL REFERENCES access_points(id) ON DELETE CASCADE,
    rss            REAL    NOT NULL CHECK (rss BETWEEN -150 AND 30),  -- dBm
    PRIMARY KEY (fingerprint_id, ap_id)
) WITHOUT ROWID;
CREATE INDEX fingerprint_readings_ap ON fingerprint_readings (ap_id);

-- Fitted kernels (SPEC 2), newest last; the latest one is the one in use.
CREATE TABLE fits (
    id             INTEGER PRIMARY KEY AUTOINCREMENT,
    building_id    INTEGER NOT NULL REFERENCES buildings(id) ON DELETE CASCADE,
    fitted_ms      INTEGER NOT NULL,
    sf2            REAL    NOT NULL CHECK (sf2 > 0),
    ell            REAL    NOT NULL CHECK (ell > 0),
    sn2            REAL    NOT NULL CHECK (sn2 > 0),
    log_likelihood REAL    NOT NULL
);
CREATE INDEX fits_building ON fits (building_id, fitted_ms);

CREATE TABLE fit_access_points (
    fit_id INTEGER NOT NULL REFERENCES fits(id) ON DELETE CASCADE,
    ord    INTEGER NOT NULL,
    ap_id  INTEGER NOT NULL REFERENCES access_points(id) ON DELETE CASCADE,
    PRIMARY KEY (fit_id, ord),
    UNIQUE (fit_id, ap_id)
) WITHOUT ROWID;
CREATE INDEX fit_access_points_ap ON fit_access_points (ap_id);

-- Planning results: the request, the answer and its figures (SPEC 7, planning result).
CREATE TABLE plans (
    id           INTEGER PRIMARY KEY AUTOINCREMENT,
    building_id  INTEGER NOT NULL REFERENCES buildings(id) ON DELETE CASCADE,
    created_ms   INTEGER NOT NULL,
    start_vid    TEXT    NOT NULL,
    end_vid      TEXT    NOT NULL,
    budget_m     REAL    NOT NULL CHECK (budget_m >= 0),
    surveyor     TEXT    NOT NULL CHECK (json_valid(surveyor)),  -- surveyor model, planner's JSON
    sf2          REAL    NOT NULL CHECK (sf2 > 0),
    ell          REAL    NOT NULL CHECK (ell > 0),
    sn2          REAL    NOT NULL CHECK (sn2 > 0),
    algorithm    TEXT    NOT NULL,
    seed         INTEGER,                     -- u64 stored bit for bit as i64; NULL if none
    length_m     REAL    NOT NULL CHECK (length_m >= 0),
    samples      INTEGER NOT NULL CHECK (samples >= 0),
    utility_nats REAL    NOT NULL,
    elapsed_ms   INTEGER NOT NULL CHECK (elapsed_ms >= 0),
    FOREIGN KEY (building_id, start_vid) REFERENCES vertices(building_id, vid) ON DELETE CASCADE,
    FOREIGN KEY (building_id, end_vid) REFERENCES vertices(building_id, vid) ON DELETE CASCADE
);
CREATE INDEX plans_building ON plans (building_id, created_ms);
CREATE INDEX plans_start ON plans (building_id, start_vid);
CREATE INDEX plans_end ON plans (building_id, end_vid);

-- The walk of a plan, one row per step (vertices may repeat).
CREATE TABLE plan_steps (
    plan_id     INTEGER NOT NULL REFERENCES plans(id) ON DELETE CASCADE,
    step        INTEGER NOT NULL CHECK (step >= 0),
    building_id INTEGER NOT NULL,
    vid         TEXT    NOT NULL,
    PRIMARY KEY (plan_id, step),
    FOREIGN KEY (building_id, vid) REFERENCES vertices(building_id, vid) ON DELETE CASCADE
) WITHOUT ROWID;
CREATE INDEX plan_steps_vertex ON plan_steps (building_id, vid);

-- A survey session: a person (or robot) walking a plan and collecting fingerprints. Its
-- state is the event log below; nothing here is updated in place except by a migration.
CREATE TABLE survey_sessions (
    id          INTEGER PRIMARY KEY AUTOINCREMENT,
    building_id INTEGER NOT NULL REFERENCES buildings(id) ON DELETE CASCADE,
    plan_id     INTEGER REFERENCES plans(id) ON DELETE CASCADE,  -- the plan it started with
    created_ms  INTEGER NOT NULL,
    surveyor    TEXT CHECK (surveyor IS NULL OR json_valid(surveyor))
);
CREATE INDEX survey_sessions_building ON survey_sessions (building_id);
CREATE INDEX survey_sessions_plan ON survey_sessions (plan_id);

-- Event kinds are rows, not a CHECK list, so that a later migration adds a kind with one
-- INSERT instead of rebuilding session_events.
CREATE TABLE session_event_kinds (
    kind TEXT PRIMARY KEY
) WITHOUT ROWID;
INSERT INTO session_event_kinds (kind) VALUES
    ('step'), ('scan'), ('check_in'), ('pose'), ('replan'),
    ('pause'), ('resume'), ('finish'), ('abort');

-- The append-only log of a session. `seq` starts at 1 and increases by one per event of the
-- session; an event is acknowledged to the surveyor only after its transaction committed.
CREATE TABLE session_events (
    session_id INTEGER NOT NULL REFERENCES survey_sessions(id) ON DELETE CASCADE,
    seq        INTEGER NOT NULL CHECK (seq >= 1),
    kind       TEXT    NOT NULL REFERENCES session_event_kinds(kind),
    at_ms      INTEGER NOT NULL,              -- device clock when it happened
    payload    TEXT    NOT NULL CHECK (json_valid(payload)),  -- kind-specific fields
    PRIMARY KEY (session_id, seq)
) WITHOUT ROWID;
CREATE INDEX session_events_kind ON session_events (kind);

CREATE TRIGGER session_events_seq_increases
BEFORE INSERT ON session_events
WHEN NEW.seq <> 1 + coalesce(
    (SELECT max(seq) FROM session_events WHERE session_id = NEW.session_id), 0)
BEGIN
    SELECT RAISE(ABORT, 'session_events: seq must be one more than the session''s last seq');
END;

CREATE TRIGGER session_events_append_only
BEFORE UPDATE ON session_events
BEGIN
    SELECT RAISE(ABORT, 'session_events: events are append-only');
END;

-- Fingerprints collected during a session, one per `scan` event, with the estimated position
-- (step counter since the last check-in) and its uncertainty.
CREATE TABLE collected_fingerprints (
    id          INTEGER PRIMARY KEY AUTOINCREMENT,
    session_id  INTEGER NOT NULL,
    seq         INTEGER NOT NULL,             -- the scan event
    x           REAL    NOT NULL,
    y           REAL    NOT NULL,
    floor       INTEGER NOT NULL,
    sigma_m     REAL    NOT NULL CHECK (sigma_m >= 0),  -- std. deviation of the position label
    since_checkin_m REAL CHECK (since_checkin_m IS NULL OR since_checkin_m >= 0),  -- u of SPEC 4
    UNIQUE (session_id, seq),
    FOREIGN KEY (session_id, seq) REFERENCES session_events(session_id, seq) ON DELETE CASCADE
);

CREATE TABLE collected_readings (
    fingerprint_id INTEGER NOT NULL REFERENCES collected_fingerprints(id) ON DELETE CASCADE,
    ap_id          INTEGER NOT NULL REFERENCES access_points(id) ON DELETE CASCADE,
    rss            REAL    NOT NULL CHECK (rss BETWEEN -150 AND 30),
    PRIMARY KEY (fingerprint_id, ap_id)
) WITHOUT ROWID;
CREATE INDEX collected_readings_ap ON collected_readings (ap_id);
