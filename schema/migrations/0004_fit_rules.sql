-- 0004: which rule chose a fit's access points (core/src/gp/fit.rs, `ApRule`).
--
-- SPEC 2 keeps the access points heard at half the pilot locations or more; on a large
-- floor it keeps none, and the fit then takes each access point on the locations that
-- hear it (decision record 0007). A fit recorded under that rule has a row here; a fit
-- without one used SPEC 2's rule, as every fit recorded before this step did.
--
-- Lesson (0003): a new table instead of a new column on `fits`, so that the rows of every
-- earlier database stay exactly as they were. WITHOUT ROWID keyed by `fit_id`: the
-- cascade from `fits` looks the row up by its key.

CREATE TABLE fit_rules (
    fit_id  INTEGER PRIMARY KEY REFERENCES fits(id) ON DELETE CASCADE,
    ap_rule TEXT    NOT NULL CHECK (ap_rule IN ('heard_only'))
) WITHOUT ROWID;
