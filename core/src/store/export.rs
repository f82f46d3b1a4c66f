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
/// it was not heard. Fields are quoted per RFC 4180 when needed; numbers are written in
/// Rust's shortest round-trip form, so nothing is lost.
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
            fp.x,
            fp.y,
            fp.floor,
            fp.sigma_m,
            fp.since_checkin_m
                .map(|u| format!("{u:?}"))
                .unwrap_or_default()
        );
        for ap in &aps {
            out.push(',');
            if let Some(rss) = fp.rss.get(*ap) {
                let _ = write!(out, "{rss:?}");
            }
        }
        out.push_str("\r\n");
    }
    out
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
