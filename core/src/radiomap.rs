//! What positioning engines read: a building's fingerprints as rows (the UJIIndoorLoc
//! column layout, or JSON lines) and the radio map, the predicted mean and standard
//! deviation of every access point's RSS on a grid over the walkable space.
//!
//! # UJIIndoorLoc layout
//! One row per scan. `WAP001` ... `WAPnnn`, one column per access point (in name order; the
//! names are in a separate two-column `WAP,name` table, because the data set's tools expect
//! `WAP` columns), RSS in dBm and [`UJI_NOT_HEARD`] (100) where the access point was not
//! heard; then the data set's own columns `LONGITUDE`, `LATITUDE`, `FLOOR`, `BUILDINGID`,
//! `SPACEID`, `RELATIVEPOSITION`, `USERID`, `PHONEID`, `TIMESTAMP` (Unix seconds). As in the
//! data set, `LONGITUDE` and `LATITUDE` are metres (its are projected metres): here they are
//! the building's `x` (east) and `y` (north), so that distances between rows are true
//! metres. Columns after `TIMESTAMP`, which tools reading the data set's columns by name
//! skip, say the rest: `LON_DEG`, `LAT_DEG` (WGS84, with `geo`), `SOURCE` (`pilot` or
//! `session`), `SESSION`, `SEQ`, `TIME_MS`, `SURVEYOR`, `DEVICE`, `SIGMA_M` (the position
//! label's standard deviation). `USERID` and `PHONEID` number the surveyors and devices
//! from 1 in order of appearance (0: unknown), `SPACEID`, `RELATIVEPOSITION` and
//! `BUILDINGID` are 0.
//!
//! # Radio map
//! Per access point heard anywhere in the fingerprints, a GP with the building's kernel
//! (SPEC 2 and 5: centred on its mean, a missing reading is -100 dBm) on every fingerprint,
//! pilot rows with noise `sn2`, collected rows with `sn2` plus the label noise of their
//! position's standard deviation (SPEC 4). `sd` is the standard deviation of a new reading
//! there: the latent posterior variance plus `sn2`. The grid covers the walkable outlines
//! of a floor (rooms, corridors, areas) where it has any, else SPEC 5's reference grid
//! (points within 1.5 m of an edge).

use std::collections::{BTreeMap, BTreeSet, HashMap};
use std::fmt::Write as _;

use geo::{Contains, Coord, LineString, Point as GeoPoint, Polygon};
use nalgebra::DMatrix;
use serde::{Deserialize, Serialize};

use crate::building::{Building, GeoOrigin};
use crate::eval::{MISSING_DBM, reference_grid};
use crate::floorplan::LocalFrame;
use crate::gp::predict::GpModel;
use crate::gp::{Extent, Kernel, Point};
use crate::store::{StoredCollected, csv_field};
use crate::{Error, Result};

/// The UJIIndoorLoc value of an access point that was not heard.
pub const UJI_NOT_HEARD: f64 = 100.0;

/// Columns of the UJIIndoorLoc layout after the access points.
pub const UJI_COLUMNS: [&str; 9] = [
    "LONGITUDE",
    "LATITUDE",
    "FLOOR",
    "BUILDINGID",
    "SPACEID",
    "RELATIVEPOSITION",
    "USERID",
    "PHONEID",
    "TIMESTAMP",
];
/// The columns added after them.
pub const UJI_EXTRA_COLUMNS: [&str; 9] = [
    "LON_DEG", "LAT_DEG", "SOURCE", "SESSION", "SEQ", "TIME_MS", "SURVEYOR", "DEVICE", "SIGMA_M",
];

/// One scan: where, when, by whom, and what was heard.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct ScanRow {
    /// `pilot` (the building's pilot data) or `session` (collected in a survey session).
    pub source: String,
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub session: Option<i64>,
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub seq: Option<i64>,
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub time_ms: Option<i64>,
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub surveyor: Option<String>,
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub device: Option<String>,
    pub x: f64,
    pub y: f64,
    pub floor: i64,
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub lon: Option<f64>,
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub lat: Option<f64>,
    /// Standard deviation of the position label, metres (0 for pilot data).
    #[serde(default)]
    pub sigma_m: f64,
    pub rss: BTreeMap<String, f64>,
}

/// Who recorded a session: surveyor name and device, when known.
pub type SessionPeople = HashMap<i64, (Option<String>, Option<String>)>;

/// The rows of a building: its pilot data, then the fingerprints collected in sessions.
pub fn scan_rows(
    building: &Building,
    collected: &[StoredCollected],
    people: &SessionPeople,
) -> Vec<ScanRow> {
    let frame = building.geo.map(LocalFrame::new);
    let lonlat = |x: f64, y: f64| frame.map(|f| f.to_wgs84(x, y));
    let mut out = Vec::with_capacity(building.pilot.len() + collected.len());
    for p in &building.pilot {
        let ll = lonlat(p.x, p.y);
        out.push(ScanRow {
            source: "pilot".into(),
            session: None,
            seq: None,
            time_ms: None,
            surveyor: None,
            device: None,
            x: p.x,
            y: p.y,
            floor: p.floor,
            lon: ll.map(|l| l.0),
            lat: ll.map(|l| l.1),
            sigma_m: 0.0,
            rss: p.rss.clone(),
        });
    }
    for c in collected {
        let fp = &c.fingerprint;
        let ll = lonlat(fp.x, fp.y);
        let (surveyor, device) = people.get(&c.session_id).cloned().unwrap_or_default();
        out.push(ScanRow {
            source: "session".into(),
            session: Some(c.session_id),
            seq: Some(c.seq),
            time_ms: Some(c.at_ms),
            surveyor,
            device,
            x: fp.x,
            y: fp.y,
            floor: fp.floor,
            lon: ll.map(|l| l.0),
            lat: ll.map(|l| l.1),
            sigma_m: fp.sigma_m,
            rss: fp.rss.clone(),
        });
    }
    out
}

fn opt<T: std::fmt::Debug>(v: Option<T>) -> String {
    v.map(|v| format!("{v:?}")).unwrap_or_default()
}

/// The UJIIndoorLoc CSV of the rows and its `WAP,name` table (module docs). Numbers are
/// written in the shortest form that reads back to the same value.
pub fn uji_csv(rows: &[ScanRow]) -> (String, String) {
    let aps: BTreeSet<&str> = rows
        .iter()
        .flat_map(|r| r.rss.keys().map(String::as_str))
        .collect();
    let aps: Vec<&str> = aps.into_iter().collect();
    let wap = |i: usize| format!("WAP{:03}", i + 1);
    let mut ids: HashMap<&str, usize> = HashMap::new();
    let mut devices: HashMap<&str, usize> = HashMap::new();
    for r in rows {
        if let Some(s) = &r.surveyor {
            let n = ids.len() + 1;
            ids.entry(s.as_str()).or_insert(n);
        }
        if let Some(d) = &r.device {
            let n = devices.len() + 1;
            devices.entry(d.as_str()).or_insert(n);
        }
    }
    let mut out = String::new();
    let mut header: Vec<String> = (0..aps.len()).map(wap).collect();
    header.extend(UJI_COLUMNS.iter().map(|s| s.to_string()));
    header.extend(UJI_EXTRA_COLUMNS.iter().map(|s| s.to_string()));
    out.push_str(&header.join(","));
    out.push_str("\r\n");
    for r in rows {
        let mut f: Vec<String> = aps
            .iter()
            .map(|ap| match r.rss.get(*ap) {
                Some(v) => format!("{v:?}"),
                None => format!("{UJI_NOT_HEARD:?}"),
            })
            .collect();
        f.push(format!("{:?}", r.x));
        f.push(format!("{:?}", r.y));
        f.push(r.floor.to_string());
        f.push("0".into());
        f.push("0".into());
        f.push("0".into());
        f.push(
            r.surveyor
                .as_deref()
                .and_then(|s| ids.get(s))
                .copied()
                .unwrap_or(0)
                .to_string(),
        );
        f.push(
            r.device
                .as_deref()
                .and_then(|d| devices.get(d))
                .copied()
                .unwrap_or(0)
                .to_string(),
        );
        f.push(r.time_ms.map_or(0, |t| t.div_euclid(1000)).to_string());
        f.push(opt(r.lon));
        f.push(opt(r.lat));
        f.push(r.source.clone());
        f.push(opt(r.session));
        f.push(opt(r.seq));
        f.push(opt(r.time_ms));
        f.push(r.surveyor.as_deref().map(csv_field).unwrap_or_default());
        f.push(r.device.as_deref().map(csv_field).unwrap_or_default());
        f.push(format!("{:?}", r.sigma_m));
        out.push_str(&f.join(","));
        out.push_str("\r\n");
    }
    let mut map = String::from("WAP,name\r\n");
    for (i, ap) in aps.iter().enumerate() {
        let _ = write!(map, "{},{}\r\n", wap(i), csv_field(ap));
    }
    (out, map)
}

/// Splits one CSV line (RFC 4180 quoting).
fn split_csv(line: &str) -> Vec<String> {
    let mut out = Vec::new();
    let mut cur = String::new();
    let mut quoted = false;
    let mut chars = line.chars().peekable();
    while let Some(c) = chars.next() {
        match (c, quoted) {
            ('"', true) if chars.peek() == Some(&'"') => {
                cur.push('"');
                chars.next();
            }
            ('"', _) => quoted = !quoted,
            (',', false) => out.push(std::mem::take(&mut cur)),
            _ => cur.push(c),
        }
    }
    out.push(cur);
    out
}

/// Reads a UJIIndoorLoc CSV written by [`uji_csv`] (or any file with `WAP` columns and the
/// data set's columns) back into rows; `map` is the `WAP,name` table (`None`: the access
/// points keep their `WAPnnn` names). `LONGITUDE`/`LATITUDE` are read as `x`/`y`.
pub fn read_uji_csv(text: &str, map: Option<&str>, origin: &str) -> Result<Vec<ScanRow>> {
    let bad = |line: usize, msg: String| Error::Parse {
        origin: origin.to_string(),
        path: format!("line {line}"),
        message: msg,
    };
    let mut names: HashMap<String, String> = HashMap::new();
    if let Some(m) = map {
        for (i, line) in m.lines().enumerate().skip(1) {
            if line.trim().is_empty() {
                continue;
            }
            let f = split_csv(line);
            if f.len() != 2 {
                return Err(bad(
                    i + 1,
                    format!("the WAP table needs 2 fields, got {}", f.len()),
                ));
            }
            names.insert(f[0].clone(), f[1].clone());
        }
    }
    let mut lines = text.lines().enumerate();
    let Some((_, header)) = lines.next() else {
        return Ok(Vec::new());
    };
    let header = split_csv(header);
    let col = |name: &str| header.iter().position(|h| h == name);
    let need = |name: &str| col(name).ok_or_else(|| bad(1, format!("no {name} column")));
    let (cx, cy, cf) = (need("LONGITUDE")?, need("LATITUDE")?, need("FLOOR")?);
    let waps: Vec<(usize, String)> = header
        .iter()
        .enumerate()
        .filter(|(_, h)| h.starts_with("WAP"))
        .map(|(i, h)| (i, names.get(h).cloned().unwrap_or_else(|| h.clone())))
        .collect();
    let mut out = Vec::new();
    for (i, line) in lines {
        if line.trim().is_empty() {
            continue;
        }
        let f = split_csv(line);
        if f.len() != header.len() {
            return Err(bad(
                i + 1,
                format!("{} fields, the header has {}", f.len(), header.len()),
            ));
        }
        let num = |c: usize| -> Result<f64> {
            f[c].trim()
                .parse::<f64>()
                .map_err(|_| bad(i + 1, format!("{}: not a number: {:?}", header[c], f[c])))
        };
        let text_of = |name: &str| col(name).map(|c| f[c].clone()).filter(|s| !s.is_empty());
        let int_of = |name: &str| text_of(name).and_then(|s| s.parse::<i64>().ok());
        let mut rss = BTreeMap::new();
        for (c, name) in &waps {
            let v = num(*c)?;
            if v != UJI_NOT_HEARD {
                rss.insert(name.clone(), v);
            }
        }
        let floor = num(cf)?;
        out.push(ScanRow {
            source: text_of("SOURCE").unwrap_or_else(|| "session".into()),
            session: int_of("SESSION"),
            seq: int_of("SEQ"),
            time_ms: int_of("TIME_MS"),
            surveyor: text_of("SURVEYOR"),
            device: text_of("DEVICE"),
            x: num(cx)?,
            y: num(cy)?,
            floor: floor as i64,
            lon: text_of("LON_DEG").and_then(|s| s.parse().ok()),
            lat: text_of("LAT_DEG").and_then(|s| s.parse().ok()),
            sigma_m: text_of("SIGMA_M")
                .and_then(|s| s.parse().ok())
                .unwrap_or(0.0),
            rss,
        });
    }
    Ok(out)
}

/// JSON lines: one [`ScanRow`] object per line.
pub fn jsonl(rows: &[ScanRow]) -> String {
    let mut out = String::new();
    for r in rows {
        // Plain data with string keys and finite numbers serialises.
        out.push_str(&serde_json::to_string(r).unwrap_or_default());
        out.push('\n');
    }
    out
}

/// Reads JSON lines written by [`jsonl`].
pub fn read_jsonl(text: &str, origin: &str) -> Result<Vec<ScanRow>> {
    text.lines()
        .enumerate()
        .filter(|(_, l)| !l.trim().is_empty())
        .map(|(i, l)| {
            serde_json::from_str(l).map_err(|e| Error::Parse {
                origin: origin.to_string(),
                path: format!("line {}", i + 1),
                message: e.to_string(),
            })
        })
        .collect()
}

/// The radio map: per grid point, the mean and standard deviation of every access point.
#[derive(Debug, Clone, PartialEq)]
pub struct RadioMap {
    /// Access points, in column order.
    pub aps: Vec<String>,
    pub kernel: Kernel,
    pub points: Vec<Point>,
    /// `mean[(point, ap)]`, dBm.
    pub mean: DMatrix<f64>,
    /// Standard deviation of a reading at each point, dB (the same for every access point:
    /// one kernel, one set of positions).
    pub sd: Vec<f64>,
}

/// Grid points `step` apart inside the walkable outlines of each floor (SPEC 5's reference
/// grid on floors without walkable outlines).
pub fn walkable_grid(building: &Building, step: f64) -> Result<Vec<Point>> {
    if !(step.is_finite() && step >= 0.1) {
        return Err(Error::InvalidRequest(format!(
            "--grid must be at least 0.1 m, got {step}"
        )));
    }
    let fallback = reference_grid(building, step, 1.5);
    let mut out = Vec::new();
    for floor in &building.floors {
        let polys: Vec<Polygon<f64>> = building
            .outlines
            .iter()
            .filter(|o| o.floor == floor.id && o.kind.is_walkable())
            .map(|o| {
                Polygon::new(
                    LineString::from(
                        o.points
                            .iter()
                            .map(|p| Coord { x: p[0], y: p[1] })
                            .collect::<Vec<_>>(),
                    ),
                    vec![],
                )
            })
            .collect();
        if polys.is_empty() {
            out.extend(fallback.iter().filter(|p| p.floor == floor.id));
            continue;
        }
        let Extent { x0, y0, x1, y1 } = Extent::of(
            polys
                .iter()
                .flat_map(|p| p.exterior().coords())
                .map(|p| (p.x, p.y)),
        );
        let nx = ((x1 - x0) / step).floor() as usize;
        let ny = ((y1 - y0) / step).floor() as usize;
        if (nx + 1).saturating_mul(ny + 1) > 5_000_000 {
            return Err(Error::InvalidRequest(format!(
                "a {step} m grid over floor {} would have over 5 million points; use a coarser --grid",
                floor.id
            )));
        }
        for j in 0..=ny {
            for i in 0..=nx {
                let (x, y) = (x0 + (i as f64 + 0.5) * step, y0 + (j as f64 + 0.5) * step);
                if x > x1 || y > y1 {
                    continue;
                }
                if polys.iter().any(|p| p.contains(&GeoPoint::new(x, y))) {
                    out.push(Point::new(x, y, floor.id));
                }
            }
        }
    }
    Ok(out)
}

/// Fits the per-access-point GPs on the rows and predicts on `grid`.
pub fn radio_map(rows: &[ScanRow], kernel: &Kernel, grid: Vec<Point>) -> Result<RadioMap> {
    kernel.validate("radio map kernel")?;
    if rows.is_empty() {
        return Err(Error::InvalidRequest(
            "no fingerprints to build a radio map from (no pilot data and no survey session)"
                .into(),
        ));
    }
    let aps: Vec<String> = rows
        .iter()
        .flat_map(|r| r.rss.keys().cloned())
        .collect::<BTreeSet<_>>()
        .into_iter()
        .collect();
    let train: Vec<Point> = rows.iter().map(|r| Point::new(r.x, r.y, r.floor)).collect();
    let noise: Vec<f64> = rows
        .iter()
        .map(|r| kernel.sn2 + kernel.label_noise(r.sigma_m))
        .collect();
    let values = DMatrix::from_fn(rows.len(), aps.len(), |i, a| {
        rows[i].rss.get(&aps[a]).copied().unwrap_or(MISSING_DBM)
    });
    let gp = GpModel::fit_with_noise(kernel, &train, &noise, &values)?;
    let p = gp.predict(&grid);
    let sd = p
        .variance
        .iter()
        .map(|v| (v.max(0.0) + kernel.sn2).sqrt())
        .collect();
    Ok(RadioMap {
        aps,
        kernel: *kernel,
        points: grid,
        mean: p.mean,
        sd,
    })
}

/// Long CSV: `floor,x,y,lon,lat,ap,mean_dbm,sd_db`, one row per grid point and access
/// point (`lon`, `lat` empty without `geo`).
pub fn radio_map_csv(map: &RadioMap, geo: Option<GeoOrigin>) -> String {
    let frame = geo.map(LocalFrame::new);
    let mut out = String::from("floor,x,y,lon,lat,ap,mean_dbm,sd_db\r\n");
    for (i, p) in map.points.iter().enumerate() {
        let (lon, lat) = match frame {
            Some(f) => {
                let (lon, lat) = f.to_wgs84(p.x, p.y);
                (format!("{lon:.8}"), format!("{lat:.8}"))
            }
            None => (String::new(), String::new()),
        };
        for (a, ap) in map.aps.iter().enumerate() {
            let _ = write!(
                out,
                "{},{:.3},{:.3},{lon},{lat},{},{:.2},{:.2}\r\n",
                p.floor,
                p.x,
                p.y,
                csv_field(ap),
                map.mean[(i, a)],
                map.sd[i]
            );
        }
    }
    out
}

/// GeoJSON FeatureCollection: one Point per grid point (WGS84), properties `floor`, `x`,
/// `y`, `sd_db` and `mean_dbm` (an object by access point). Needs the building's `geo`.
pub fn radio_map_geojson(map: &RadioMap, geo: Option<GeoOrigin>, building: &str) -> Result<String> {
    let Some(geo) = geo else {
        return Err(Error::InvalidRequest(format!(
            "building {building:?} has no `geo` origin, so its points have no longitude and \
             latitude: write the radio map as .csv, or import the building from a floor plan"
        )));
    };
    let frame = LocalFrame::new(geo);
    let features: Vec<serde_json::Value> = map
        .points
        .iter()
        .enumerate()
        .map(|(i, p)| {
            let (lon, lat) = frame.to_wgs84(p.x, p.y);
            let mean: serde_json::Map<String, serde_json::Value> = map
                .aps
                .iter()
                .enumerate()
                .map(|(a, ap)| {
                    (
                        ap.clone(),
                        serde_json::json!((map.mean[(i, a)] * 100.0).round() / 100.0),
                    )
                })
                .collect();
            serde_json::json!({
                "type": "Feature",
                "geometry": {"type": "Point", "coordinates": [
                    (lon * 1e8).round() / 1e8, (lat * 1e8).round() / 1e8]},
                "properties": {
                    "floor": p.floor,
                    "x": (p.x * 1000.0).round() / 1000.0,
                    "y": (p.y * 1000.0).round() / 1000.0,
                    "sd_db": (map.sd[i] * 100.0).round() / 100.0,
                    "mean_dbm": mean,
                }
            })
        })
        .collect();
    let doc = serde_json::json!({
        "type": "FeatureCollection",
        "name": format!("{building} radio map"),
        "kernel": {"sf2": map.kernel.sf2, "ell": map.kernel.ell, "sn2": map.kernel.sn2},
        "features": features,
    });
    serde_json::to_string(&doc).map_err(|e| Error::InvalidRequest(format!("GeoJSON output: {e}")))
}
