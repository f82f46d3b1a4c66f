-- 0003: what a floor-plan import adds to a building (SPEC 7 `geo` and `outlines`).
--
-- Buildings imported from OpenStreetMap indoor data or IMDF keep the WGS84 position of
-- their local origin (exports give longitude and latitude from it) and the polygons of the
-- plan, drawn under the graph. Outlines are only ever drawn, never queried, so they are kept
-- as one JSON array per building (the `outlines` list of the building file) rather than as
-- rows. A building from a plain file has no row here.
--
-- WITHOUT ROWID: the cascade from `buildings` looks the row up by `building_id` itself
-- (core/tests/store_api.rs checks every foreign key's lookup).
--
-- Lesson: a new table instead of new columns on `buildings`, so that the rows of every
-- earlier database stay exactly as they were (core/tests/store_migrations.rs compares them).

CREATE TABLE building_floorplans (
    building_id INTEGER PRIMARY KEY REFERENCES buildings(id) ON DELETE CASCADE,
    geo_lat     REAL CHECK (geo_lat IS NULL OR geo_lat BETWEEN -90 AND 90),
    geo_lon     REAL CHECK (geo_lon IS NULL OR geo_lon BETWEEN -180 AND 180),
    outlines    TEXT NOT NULL DEFAULT '[]' CHECK (json_valid(outlines) AND json_type(outlines) = 'array'),
    CHECK ((geo_lat IS NULL) = (geo_lon IS NULL))
) WITHOUT ROWID;
