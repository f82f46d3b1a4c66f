//! Where things go: the plan area, the scale, the rows a long thin floor is cut into, and
//! label placement that keeps labels from running into each other.

use crate::building::Building;
use crate::{Error, Result};

pub(super) const MARGIN_PX: f64 = 30.0;
/// Height of a panel's title line.
pub(super) const TITLE_PX: f64 = 24.0;
/// Height of the building's heading.
pub(super) const HEADING_PX: f64 = 34.0;
/// The widest drawing of one row, pixels.
const MAX_ROW_PX: f64 = 1400.0;
/// The tallest drawing of one floor, pixels.
const MAX_FLOOR_PX: f64 = 1000.0;
/// The narrowest picture (the legend needs the room).
pub(super) const MIN_WIDTH_PX: f64 = 720.0;
/// Most pixels per metre chosen automatically.
const MAX_SCALE: f64 = 40.0;

/// The plan area (metres) shared by all floors, its scale and its rows.
#[derive(Debug, Clone, Copy)]
pub(super) struct Layout {
    pub x0: f64,
    pub y0: f64,
    pub y1: f64,
    /// Pixels per metre.
    pub scale: f64,
    /// A floor much wider than tall is cut into this many rows, left to right, each
    /// `slice_m` wide plus `overlap_m` on both sides, stacked like lines of text.
    pub rows: usize,
    pub slice_m: f64,
    pub overlap_m: f64,
}

impl Layout {
    /// The area of the vertices (plus `pad`) and of the outlines, and a scale: `scale`
    /// if given, else one that keeps a row within 1400 px and a floor within 1000 px.
    /// A floor more than five times as wide as tall is cut into rows (two for a 12:1
    /// strip), so the picture keeps a readable shape.
    pub fn new(building: &Building, pad: f64, scale: Option<f64>) -> Result<Layout> {
        let (mut x0, mut y0) = (f64::INFINITY, f64::INFINITY);
        let (mut x1, mut y1) = (f64::NEG_INFINITY, f64::NEG_INFINITY);
        for v in &building.vertices {
            x0 = x0.min(v.pos.x - pad);
            y0 = y0.min(v.pos.y - pad);
            x1 = x1.max(v.pos.x + pad);
            y1 = y1.max(v.pos.y + pad);
        }
        for o in &building.outlines {
            for p in &o.points {
                x0 = x0.min(p[0] - 0.5);
                y0 = y0.min(p[1] - 0.5);
                x1 = x1.max(p[0] + 0.5);
                y1 = y1.max(p[1] + 0.5);
            }
        }
        let (w, h) = (x1 - x0, y1 - y0);
        let aspect = w / h;
        let rows = if aspect > 5.0 {
            ((aspect / 3.0).sqrt().round() as usize).clamp(2, 4)
        } else {
            1
        };
        let overlap_m = if rows > 1 { pad.max(1.0) } else { 0.0 };
        let slice_m = w / rows as f64;
        let row_w = slice_m + 2.0 * overlap_m;
        let scale = match scale {
            Some(s) if s.is_finite() && s > 0.0 => s,
            Some(s) => {
                return Err(Error::InvalidRequest(format!(
                    "render scale must be a positive number of pixels per metre, got {s}"
                )));
            }
            None => (MAX_ROW_PX / row_w)
                .min(MAX_FLOOR_PX / (h * rows as f64))
                .min(MAX_SCALE),
        };
        Ok(Layout {
            x0,
            y0,
            y1,
            scale,
            rows,
            slice_m,
            overlap_m,
        })
    }

    /// Plan x (metres) to the floor drawing's own pixels.
    pub fn px(&self, x: f64) -> f64 {
        (x - self.x0) * self.scale
    }

    /// Plan y (metres, north up) to the floor drawing's own pixels.
    pub fn py(&self, y: f64) -> f64 {
        (self.y1 - y) * self.scale
    }

    /// Width of one row's drawing, pixels.
    pub fn row_w_px(&self) -> f64 {
        (self.slice_m + 2.0 * self.overlap_m) * self.scale
    }

    /// Height of the drawing of one row, pixels.
    pub fn row_h_px(&self) -> f64 {
        (self.y1 - self.y0) * self.scale
    }

    /// Left edge of row `r` in the floor drawing's pixels: its slice less the overlap,
    /// kept inside the plan area (the first row starts at its left edge, the last ends at
    /// its right edge).
    pub fn row_left_px(&self, r: usize) -> f64 {
        let total = self.slice_m * self.rows as f64;
        let row_w = self.slice_m + 2.0 * self.overlap_m;
        let left = (r as f64 * self.slice_m - self.overlap_m).clamp(0.0, (total - row_w).max(0.0));
        left * self.scale
    }

    /// Plan x (metres) of the left edge of row `r`.
    pub fn row_left_m(&self, r: usize) -> f64 {
        self.x0 + self.row_left_px(r) / self.scale
    }

    /// Width of the whole picture.
    pub fn width_px(&self) -> f64 {
        (self.row_w_px() + 2.0 * MARGIN_PX).max(MIN_WIDTH_PX)
    }

    /// Height of one floor's panel (its title and all its rows).
    pub fn panel_h_px(&self) -> f64 {
        TITLE_PX + self.rows as f64 * (self.row_h_px() + 10.0) + 10.0
    }
}

/// Boxes already taken by labels and markers, so that a new label goes where it does not
/// cover another (or is left out when there is no room).
#[derive(Debug)]
pub(super) struct Placer {
    taken: Vec<[f64; 4]>,
    /// The drawing's size: a label never sticks out of it.
    width: f64,
    height: f64,
}

impl Placer {
    /// An empty drawing of `width` x `height` pixels.
    pub fn new(width: f64, height: f64) -> Placer {
        Placer {
            taken: Vec::new(),
            width,
            height,
        }
    }

    /// Marks a box (`x`, `y` top-left, width, height) as taken.
    pub fn block(&mut self, x: f64, y: f64, w: f64, h: f64) {
        self.taken.push([x, y, x + w, y + h]);
    }

    fn free(&self, b: [f64; 4]) -> bool {
        self.taken
            .iter()
            .all(|t| b[2] <= t[0] || b[0] >= t[2] || b[3] <= t[1] || b[1] >= t[3])
    }

    /// Places a text of `chars` characters of `font` px near `(x, y)`: tries the four
    /// corners around the point, then further out; returns the text's baseline origin,
    /// or `None` when every spot is taken.
    pub fn place(&mut self, x: f64, y: f64, chars: usize, font: f64) -> Option<(f64, f64)> {
        let w = chars as f64 * font * 0.62 + 2.0;
        let h = font + 2.0;
        for d in [4.0, 9.0, 15.0] {
            for (dx, dy) in [(d, -d - h), (d, d), (-d - w, -d - h), (-d - w, d)] {
                let b = [x + dx, y + dy, x + dx + w, y + dy + h];
                let inside =
                    b[0] >= 0.0 && b[1] >= 0.0 && b[2] <= self.width && b[3] <= self.height;
                if inside && self.free(b) {
                    self.taken.push(b);
                    return Some((b[0] + 1.0, b[3] - 2.5));
                }
            }
        }
        None
    }
}
