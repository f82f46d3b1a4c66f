//! Colours, the style sheet and XML escaping of the drawings.

/// Escapes text for XML content and attribute values (the drawings and the experiment's
/// charts).
pub(crate) fn esc(s: &str) -> String {
    let mut out = String::with_capacity(s.len());
    for c in s.chars() {
        match c {
            '&' => out.push_str("&amp;"),
            '<' => out.push_str("&lt;"),
            '>' => out.push_str("&gt;"),
            '"' => out.push_str("&quot;"),
            '\'' => out.push_str("&apos;"),
            _ => out.push(c),
        }
    }
    out
}

/// Viridis colour map, `t` in `[0, 1]`, as `#rrggbb` (linear between 9 stops).
pub(super) fn viridis(t: f64) -> String {
    const STOPS: [(f64, f64, f64); 9] = [
        (68.0, 1.0, 84.0),
        (71.0, 44.0, 122.0),
        (59.0, 81.0, 139.0),
        (44.0, 113.0, 142.0),
        (33.0, 144.0, 141.0),
        (39.0, 173.0, 129.0),
        (92.0, 200.0, 99.0),
        (170.0, 220.0, 50.0),
        (253.0, 231.0, 37.0),
    ];
    let t = if t.is_finite() {
        t.clamp(0.0, 1.0)
    } else {
        0.0
    };
    let pos = t * (STOPS.len() - 1) as f64;
    let i = (pos.floor() as usize).min(STOPS.len() - 2);
    let f = pos - i as f64;
    let (a, b) = (STOPS[i], STOPS[i + 1]);
    let ch = |x: f64, y: f64| (x + f * (y - x)).round().clamp(0.0, 255.0) as u8;
    format!(
        "#{:02x}{:02x}{:02x}",
        ch(a.0, b.0),
        ch(a.1, b.1),
        ch(a.2, b.2)
    )
}

/// One colour per walk (a team draws each surveyor's walk in its own colour); chosen to
/// stand out on the viridis heat map (none is a viridis colour).
pub(super) const WALK_COLOURS: [&str; 6] = [
    "#e6194b", "#111111", "#f032e6", "#f58231", "#ffffff", "#9a6324",
];

/// The colour of walk `i`.
pub(super) fn walk_colour(i: usize) -> &'static str {
    WALK_COLOURS[i % WALK_COLOURS.len()]
}

/// The style sheet: one class per kind of mark (tests and users style by class).
pub(super) const CSS: &str = "\
.edge{stroke:#555;stroke-width:2;stroke-linecap:round}\
.vertex{fill:#fff;stroke:#333;stroke-width:1}\
.stairs{fill:#fff;fill-opacity:0.6;stroke:#c0392b;stroke-width:2.5}\
.stairs-text{font-size:10px;fill:#c0392b;font-weight:bold;stroke:#fff;stroke-width:3;paint-order:stroke;stroke-linejoin:round}\
.pilot{fill:#e67e22;stroke:#fff;stroke-width:1}\
.sample{fill:#fff;stroke:#111;stroke-width:0.8}\
.walk{fill:none;stroke-width:2.5;stroke-opacity:0.9;stroke-linecap:round}\
.track{fill:none;stroke:#111;stroke-width:1.5;stroke-dasharray:5 3}\
.start{fill:#2ca02c;stroke:#fff;stroke-width:1.5}\
.end{fill:#111;stroke:#fff;stroke-width:1.5}\
.marker-text{font-size:9px;font-weight:bold;fill:#fff;text-anchor:middle;dominant-baseline:central}\
.step{font-size:10px;font-weight:bold;fill:#111;stroke:#fff;stroke-width:3;paint-order:stroke;stroke-linejoin:round}\
.label{font-size:9px;fill:#222;stroke:#fff;stroke-width:2.5;paint-order:stroke}\
.legend-text{font-size:12px;fill:#222}\
.heading{font-size:17px;font-weight:bold;fill:#111}\
.title{font-size:14px;font-weight:bold;fill:#111}\
.subtitle{font-size:12px;fill:#444}\
.panel{fill:#fff;stroke:#ccc;stroke-width:1}\
.unmapped{fill:#d9d9d9}\
.outline{stroke:#8a8f98;stroke-width:1}\
.outline-building{fill:#f0f0f0}\
.outline-room{fill:#e8eef7}\
.outline-corridor,.outline-area{fill:#fbf6e6}\
.outline-wall{fill:none;stroke:#3c3f44;stroke-width:2.5}\
.outline-line{fill:none;stroke:#f4f4f4;stroke-width:1.2;stroke-opacity:0.8}\
";
