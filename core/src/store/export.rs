//! Collected fingerprints out of the store: CSV for spreadsheets and analysis tools, JSON in
//! the shape of the building file's fingerprints.

use std::collections::BTreeSet;
use std::fmt::Write as _;

use serde::Serialize;

use super::StoredCollected;

/// Format tag of the JSON export.
pub const COLLECTED_FORMAT: &str = "survey-collected/1";

/// Wide CSV, one row per fingerprint: `session,seq,at_ms,x,y,floor,sigma_m,since_checkin_m`,
/// then one column per access point heard anywhere in `list` (sorted by name), empty where
/// it was not heard. Fields are quoted per RFC 4180 when needed; positions and distances
/// are written to the millimetre and RSS to 0.01 dB (finer digits are arithmetic noise of
/// the estimated track, `4.199999999999999`, not measurement), in shortest form.
pub fn collected_csv(list: &[StoredCollected]) -> String {
    let aps: BTreeSet<&str> = list
        .iter()
        .flat_map(|c| c.fingerprint.rss.keys().map(String::as_str))
        .collect();
    let mut out = String::new();
    let mut header: Vec<String> = [
        "session",
        "seq",
        "at_ms",
        "x",
        "y",
        "floor",
        "sigma_m",
        "since_checkin_m",
    ]
    .iter()
    .map(|s| s.to_string())
    .collect();
    header.extend(aps.iter().map(|ap| csv_field(ap)));
    out.push_str(&header.join(","));
    out.push_str("\r\n");
    for c in list {
        let fp = &c.fingerprint;
        // Writing to a String cannot fail.
        let _ = write!(
            out,
            "{},{},{},{:?},{:?},{},{:?},{}",
            c.session_id,
            c.seq,
            c.at_ms,
            rounded(fp.x, 3),
            rounded(fp.y, 3),
            fp.floor,
            rounded(fp.sigma_m, 3),
            fp.since_checkin_m
                .map(|u| format!("{:?}", rounded(u, 3)))
                .unwrap_or_default()
        );
        for ap in &aps {
            out.push(',');
            if let Some(rss) = fp.rss.get(*ap) {
                let _ = write!(out, "{:?}", rounded(*rss, 2));
            }
        }
        out.push_str("\r\n");
    }
    out
}

/// `v` rounded to `decimals` places: the double nearest the decimal, so that it prints as
/// that decimal (`4.199999999999999` -> `4.2`); never `-0.0`.
fn rounded(v: f64, decimals: i32) -> f64 {
    let f = 10f64.powi(decimals);
    (v * f).round() / f + 0.0
}

/// Quotes a CSV field if it holds a comma, a quote or a line break (RFC 4180); the one rule
/// of every CSV the crate writes (exports, radio maps, experiment tables).
pub(crate) fn csv_field(s: &str) -> String {
    if s.contains([',', '"', '\n', '\r']) {
        format!("\"{}\"", s.replace('"', "\"\""))
    } else {
        s.to_string()
    }
}

#[derive(Serialize)]
struct CollectedDoc<'a> {
    format: &'static str,
    building: &'a str,
    fingerprints: &'a [StoredCollected],
}

/// JSON document `survey-collected/1`: `{"format", "building", "fingerprints": [{"session_id",
/// "seq", "at_ms", "x", "y", "floor", "sigma_m", "since_checkin_m"?, "rss": {...}}]}`.
pub fn collected_json(building: &str, list: &[StoredCollected]) -> String {
    let doc = CollectedDoc {
        format: COLLECTED_FORMAT,
        building,
        fingerprints: list,
    };
    // Plain data with string keys and finite numbers (checked on the way in) serialises.
    serde_json::to_string_pretty(&doc).unwrap_or_default()
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn csv_fields_are_quoted_when_needed() {
        assert_eq!(csv_field("a b"), "a b");
        assert_eq!(csv_field("a,b"), "\"a,b\"");
        assert_eq!(csv_field("say \"x\""), "\"say \"\"x\"\"\"");
    }
}
