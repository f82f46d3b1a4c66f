-- 0002: survey bundles (several surveyors, offline merge).
--
-- Phones survey offline and exchange what they collected as bundle files. A session gets a
-- globally unique id (`uid`) the first time it leaves or enters a database; importing
-- matches sessions by `uid`, so the same bundle imported twice, or bundles in any order,
-- add each session (and each of its events) once.
--
-- Lesson: `ALTER TABLE ... ADD COLUMN` keeps existing rows; a partial UNIQUE index lets the
-- sessions recorded before this migration keep a NULL uid until they are exported.

ALTER TABLE survey_sessions ADD COLUMN uid TEXT;            -- global id, set on first export/import
ALTER TABLE survey_sessions ADD COLUMN device TEXT;         -- device that recorded the session
ALTER TABLE survey_sessions ADD COLUMN surveyor_name TEXT;  -- who walked it
ALTER TABLE survey_sessions ADD COLUMN imported_ms INTEGER; -- when it arrived here; NULL if recorded here
CREATE UNIQUE INDEX survey_sessions_uid ON survey_sessions (uid) WHERE uid IS NOT NULL;

-- One row per bundle imported (provenance; a re-import updates nothing).
CREATE TABLE bundle_imports (
    bundle_id      TEXT PRIMARY KEY,          -- SHA-256 of the bundle body, hex
    device         TEXT,                      -- exporting device
    surveyor_name  TEXT,                      -- exporting surveyor
    created_ms     INTEGER NOT NULL,          -- when the bundle was written
    imported_ms    INTEGER NOT NULL,          -- when it was first imported here
    sessions_added INTEGER NOT NULL CHECK (sessions_added >= 0),
    events_added   INTEGER NOT NULL CHECK (events_added >= 0)
) WITHOUT ROWID;
