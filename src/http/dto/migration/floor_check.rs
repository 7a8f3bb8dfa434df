//! The checks of a migration request's floor: its memory estimate, each kind and form (plane,
//! ESRI grid, heights grid, contours and their points, elevations and crossings) turned into
//! the physics floor.

use super::*;

/// Refuses a floor whose estimated memory exceeds the configured limit, naming `field`.
fn check_floor_memory(
    ck: &mut Checker,
    field: String,
    value: Value,
    what: &str,
    bytes: f64,
    limit: u64,
) {
    if bytes > limit as f64 {
        ck.push(
            field,
            value,
            format!(
                "{what} would need about {:.0} MB, more than the limit of {:.0} MB \
                 (--max-floor-bytes, GANGUE_MAX_FLOOR_BYTES; see /v1/presets limits)",
                bytes / 1e6,
                limit as f64 / 1e6
            ),
        );
    }
}

/// JSON Pointer of the floor's field `name`.
fn floor_pointer(name: &str) -> String {
    format!("/face/floor/{name}")
}

/// The values a floor request sent, as an error echoes them (a grid's heights as
/// [rows, columns], contours as their count, long texts as their length).
struct SentFloor {
    origin: Option<Value>,
    spacing: Option<Value>,
    heights: Option<Value>,
    contours: Option<Value>,
    resolution: Option<Value>,
    esri: Option<Value>,
    geojson: Option<Value>,
    property: Option<Value>,
    map: Option<Value>,
}

impl SentFloor {
    /// The echoes of the fields `f` sent.
    fn of(f: &FloorDto) -> Self {
        Self {
            origin: f.origin_m.map(|o| json!(o)),
            spacing: f.spacing_m.map(num),
            heights: f
                .heights_m
                .as_ref()
                .map(|h| json!([h.len(), h.first().map_or(0, Vec::len)])),
            contours: f.contours.as_ref().map(|c| json!(c.len())),
            resolution: f.resolution_m.map(num),
            esri: f
                .esri_ascii
                .as_ref()
                .map(|t| json!(format!("{} characters", t.len()))),
            geojson: f.geojson.as_ref().map(|_| json!("a GeoJSON object")),
            property: f.elevation_property.as_ref().map(|s| json!(s)),
            map: f.map.map(|m| json!(m)),
        }
    }
}

/// The checks of one floor request: its checker, what it sent, its map frame (map
/// coordinates) and the memory limit, bytes.
struct FloorCheck<'a> {
    ck: &'a mut Checker,
    sent: SentFloor,
    map: Option<MapFrame>,
    max_floor_bytes: u64,
}

/// Contour lines with the pointers to each one's points and elevation.
type PointedLines = (Vec<ContourDto>, Vec<(String, String)>);

impl FloorCheck<'_> {
    /// Refuses a field `name` that the floor's kind does not take.
    fn stray(&mut self, name: &str, sent: Option<Value>, kind: &str) {
        if let Some(v) = sent {
            self.ck
                .push(floor_pointer(name), v, format!("not a field of {kind}"));
        }
    }

    /// Offset (m) of the map frame's origin from the floor's coordinates' origin.
    fn shift(&self) -> [f64; 2] {
        self.map.map_or([0.0, 0.0], |m| m.origin)
    }

    /// The floor in map coordinates, when a map frame was given.
    fn wrap(&self, spec: FloorSpec) -> FloorSpec {
        match self.map {
            Some(map) => FloorSpec::Mapped {
                floor: Box::new(spec),
                map,
            },
            None => spec,
        }
    }

    /// The plane: no other field allowed.
    fn plane(&mut self) -> FloorSpec {
        let s = &mut self.sent;
        let sent = [
            ("origin_m", s.origin.take()),
            ("spacing_m", s.spacing.take()),
            ("heights_m", s.heights.take()),
            ("esri_ascii", s.esri.take()),
            ("contours", s.contours.take()),
            ("geojson", s.geojson.take()),
            ("elevation_property", s.property.take()),
            ("resolution_m", s.resolution.take()),
            ("map", s.map.take()),
        ];
        for (name, v) in sent {
            self.stray(name, v, "a plane floor");
        }
        FloorSpec::Plane
    }

    /// A grid floor, from an ESRI ASCII text or from its heights.
    fn grid(&mut self, f: &mut FloorDto) -> FloorSpec {
        let s = &mut self.sent;
        let sent = [
            ("contours", s.contours.take()),
            ("geojson", s.geojson.take()),
            ("elevation_property", s.property.take()),
            ("resolution_m", s.resolution.take()),
        ];
        for (name, v) in sent {
            self.stray(name, v, "a grid floor");
        }
        if f.esri_ascii.is_some() {
            self.esri_grid(f)
        } else {
            self.heights_grid(f)
        }
    }

    /// Estimated memory of a grid of `rows` × `cols` nodes, bytes: a rotated grid becomes a
    /// mesh, with its nodes, triangles and buckets besides the grid.
    fn grid_bytes(&self, rows: usize, cols: usize) -> f64 {
        let rotated = self.map.is_some_and(|m| m.dip_direction_deg != 90.0);
        migration::grid_bytes(rows, cols)
            + if rotated {
                rows as f64 * cols as f64 * migration::CONTOUR_BYTES_PER_POINT
            } else {
                0.0
            }
    }

    /// A grid given as an ESRI ASCII text: its header gives origin and spacing; the work and
    /// memory are estimated from the header before the data are read.
    fn esri_grid(&mut self, f: &mut FloorDto) -> FloorSpec {
        let s = &mut self.sent;
        let sent = [
            ("origin_m", s.origin.take()),
            ("spacing_m", s.spacing.take()),
            ("heights_m", s.heights.take()),
        ];
        for (name, v) in sent {
            self.stray(name, v, "an ESRI ASCII grid (its header gives them)");
        }
        f.sha256 = Some(f.digest());
        let Some(text) = &f.esri_ascii else {
            return FloorSpec::Plane;
        };
        let field = floor_pointer("esri_ascii");
        let line_v = |line: usize| {
            let l = text.lines().nth(line.saturating_sub(1)).unwrap_or("");
            json!(l.chars().take(80).collect::<String>())
        };
        let header = match formats::esri_header(text) {
            Ok(h) => h,
            Err(e) => {
                self.ck.push(field, line_v(e.line), e.message);
                return FloorSpec::Plane;
            }
        };
        let origin = [header.x_center, header.y_center];
        let shift = self.shift();
        for (i, o) in origin.iter().enumerate() {
            let rel = o - shift[i];
            if !(-1e6..=1e6).contains(&rel) {
                self.ck.push(
                    field,
                    num(*o),
                    format!(
                        "the grid's first cell centre {} = {o} m{} must lie in [−1e6, 1e6] m",
                        ["x", "y"][i],
                        if self.map.is_some() {
                            " minus map.origin_m"
                        } else {
                            " (give map.origin_m for map coordinates)"
                        }
                    ),
                );
                return FloorSpec::Plane;
            }
        }
        let (rows, cols) = (header.nrows, header.ncols);
        let need = self.grid_bytes(rows, cols);
        if need > self.max_floor_bytes as f64 {
            check_floor_memory(
                self.ck,
                field,
                json!([rows, cols]),
                &format!("an ESRI ASCII grid of {rows} × {cols} cells"),
                need,
                self.max_floor_bytes,
            );
            return FloorSpec::Plane;
        }
        let heights = match formats::esri_heights(text, &header, 1e6) {
            Ok((z, nodata)) => {
                if nodata == rows * cols {
                    self.ck.push(field, json!(nodata), "every cell is NODATA");
                    return FloorSpec::Plane;
                }
                z
            }
            Err(e) => {
                self.ck.push(field, line_v(e.line), e.message);
                return FloorSpec::Plane;
            }
        };
        self.wrap(FloorSpec::Grid {
            origin,
            spacing: header.cellsize,
            heights,
        })
    }

    /// A grid given by its origin, spacing and rows of heights.
    fn heights_grid(&mut self, f: &mut FloorDto) -> FloorSpec {
        let origin = *f.origin_m.get_or_insert([0.0, 0.0]);
        let shift = self.shift();
        for (i, o) in origin.iter().enumerate() {
            if self.map.is_some() {
                let rel = o - shift[i];
                if !(-1e6..=1e6).contains(&rel) {
                    self.ck.push(
                        floor_pointer(&format!("origin_m/{i}")),
                        num(*o),
                        "must lie within 1e6 m of map.origin_m",
                    );
                }
            } else if !(-1e6..=1e6).contains(o) {
                self.ck.push(
                    floor_pointer(&format!("origin_m/{i}")),
                    num(*o),
                    "must be in [−1e6, 1e6] m (give map.origin_m for map coordinates such \
                     as UTM)",
                );
            }
        }
        let spacing = match f.spacing_m {
            Some(d) => {
                FLOOR_SPACING.check(self.ck, &floor_pointer("spacing_m"), d);
                d
            }
            None => {
                self.ck.push(
                    floor_pointer("spacing_m"),
                    Value::Null,
                    "a grid floor needs spacing_m in [0.01, 100] m",
                );
                1.0
            }
        };
        // The echo needs only the hash: hash the floor as received, then move its heights
        // into the case rather than copying up to 16 M values.
        f.sha256 = Some(f.digest());
        let heights = f.heights_m.take().unwrap_or_default();
        self.check_heights(&heights);
        self.wrap(FloorSpec::Grid {
            origin,
            spacing,
            heights,
        })
    }

    /// A grid's rows of heights: 2 to 4096 rows of as many heights each, within 1e6 m, and
    /// within the memory limit.
    fn check_heights(&mut self, heights: &[Vec<f64>]) {
        let rows = heights.len();
        let cols = heights.first().map_or(0, Vec::len);
        if !(2..=4096).contains(&rows) || !(2..=4096).contains(&cols) {
            self.ck.push(
                floor_pointer("heights_m"),
                json!([rows, cols]),
                "needs 2 to 4096 rows of 2 to 4096 heights each",
            );
        } else if let Some(i) = heights.iter().position(|r| r.len() != cols) {
            self.ck.push(
                floor_pointer(&format!("heights_m/{i}")),
                json!(heights[i].len()),
                format!("every row needs {cols} heights, like row 0"),
            );
        } else if let Some((i, j)) = heights
            .iter()
            .enumerate()
            .find_map(|(i, r)| r.iter().position(|z| z.abs() > 1e6).map(|j| (i, j)))
        {
            self.ck.push(
                floor_pointer(&format!("heights_m/{i}/{j}")),
                num(heights[i][j]),
                "heights must lie in [−1e6, 1e6] m",
            );
        } else {
            check_floor_memory(
                self.ck,
                floor_pointer("heights_m"),
                json!([rows, cols]),
                &format!("a grid of {rows} × {cols} heights"),
                self.grid_bytes(rows, cols),
                self.max_floor_bytes,
            );
        }
    }

    /// A contour floor, from GeoJSON or from contour lines: the lines' points and elevations,
    /// one elevation per plan point, no crossing, and the resampled floor's memory.
    fn contours(&mut self, f: &mut FloorDto) -> FloorSpec {
        let s = &mut self.sent;
        let sent = [
            ("origin_m", s.origin.take()),
            ("spacing_m", s.spacing.take()),
            ("heights_m", s.heights.take()),
            ("esri_ascii", s.esri.take()),
        ];
        for (name, v) in sent {
            self.stray(name, v, "a contour floor");
        }
        let resolution = *f.resolution_m.get_or_insert(FLOOR_RESOLUTION.value());
        let resolution_ok =
            FLOOR_RESOLUTION.check(self.ck, &floor_pointer("resolution_m"), resolution);
        let Some((lines, paths)) = self.contour_lines(f) else {
            return FloorSpec::Plane;
        };
        if f.geojson.is_some() {
            // the lines hold their own copy: the GeoJSON is not needed any more
            f.geojson = Some(Value::Null);
        }
        if lines.is_empty() {
            self.ck.push(
                if f.geojson.is_some() {
                    floor_pointer("geojson/features")
                } else {
                    floor_pointer("contours")
                },
                Value::Null,
                "a contour floor needs at least one contour line",
            );
        }
        let total = self.check_contour_points(&lines, &paths);
        if total > 4_000_000 {
            self.ck.push(
                floor_pointer("contours"),
                json!(total),
                "at most 4 000 000 points in all",
            );
        }
        let dup = self.check_one_elevation_per_point(&lines, &paths);
        if !dup && total <= 4_000_000 {
            self.check_crossing(&lines, &paths);
        }
        let contours: Vec<ContourLine> = lines
            .into_iter()
            .map(|c| ContourLine {
                elevation: c.elevation_m,
                points: c.points_m,
            })
            .collect();
        if total <= 4_000_000 && resolution_ok {
            // estimated before resampling: the work and memory grow with length / resolution
            let points = migration::contour_points(&contours, resolution);
            check_floor_memory(
                self.ck,
                floor_pointer("resolution_m"),
                num(resolution),
                &format!(
                    "the contours resampled every {resolution} m have about {points:.3e} \
                     points and"
                ),
                points * migration::CONTOUR_BYTES_PER_POINT,
                self.max_floor_bytes,
            );
        }
        self.wrap(FloorSpec::Contours {
            contours,
            resolution,
        })
    }

    /// The contour lines with the pointers to each one's points and elevation: read from the
    /// GeoJSON (None when it is malformed) or moved out of `contours`.
    fn contour_lines(&mut self, f: &mut FloorDto) -> Option<PointedLines> {
        let Some(g) = &f.geojson else {
            let sent = self.sent.property.take();
            self.stray(
                "elevation_property",
                sent,
                "contours given as contours (it names a GeoJSON property)",
            );
            f.sha256 = Some(f.digest());
            let lines = f.contours.take().unwrap_or_default();
            let paths = (0..lines.len())
                .map(|i| {
                    (
                        floor_pointer(&format!("contours/{i}/points_m")),
                        floor_pointer(&format!("contours/{i}/elevation_m")),
                    )
                })
                .collect();
            return Some((lines, paths));
        };
        let sent = self.sent.contours.take();
        self.stray("contours", sent, "GeoJSON contours (give one or the other)");
        let prop = f
            .elevation_property
            .get_or_insert_with(|| ELEVATION_PROPERTY.into())
            .clone();
        f.sha256 = Some(f.digest());
        let gp = floor_pointer("geojson");
        match formats::geojson_lines(g, &prop) {
            Ok(ls) => {
                f.geographic = self.map.is_none()
                    && looks_geographic(ls.iter().map(|l| (l.elevation, l.points.as_slice())));
                Some(
                    ls.into_iter()
                        .map(|l| {
                            (
                                ContourDto {
                                    elevation_m: l.elevation,
                                    points_m: l.points,
                                },
                                (
                                    format!("{gp}{}", l.points_pointer),
                                    format!("{gp}{}", l.elevation_pointer),
                                ),
                            )
                        })
                        .unzip(),
                )
            }
            Err(e) => {
                self.ck
                    .push(format!("{gp}{}", e.pointer), e.value, e.message);
                None
            }
        }
    }

    /// Each line's elevation within 1e6 m and its points (one at least) within 1e6 m of the
    /// origin (the map's, in map coordinates); returns the number of points in all.
    fn check_contour_points(&mut self, lines: &[ContourDto], paths: &[(String, String)]) -> usize {
        let shift = self.shift();
        let mut total = 0usize;
        for (c, (pts, elev)) in lines.iter().zip(paths) {
            self.ck.closed(elev, c.elevation_m, -1e6, 1e6, "m");
            if c.points_m.is_empty() {
                self.ck
                    .push(pts.clone(), json!(0), "needs at least one point");
            }
            if let Some(j) = c
                .points_m
                .iter()
                .position(|q| !((q[0] - shift[0]).abs() <= 1e6 && (q[1] - shift[1]).abs() <= 1e6))
            {
                self.ck.push(
                    format!("{pts}/{j}"),
                    json!(c.points_m[j]),
                    if self.map.is_some() {
                        "coordinates must lie within 1e6 m of map.origin_m"
                    } else {
                        "coordinates must lie in [−1e6, 1e6] m (give map.origin_m for map \
                         coordinates)"
                    },
                );
            }
            total += c.points_m.len();
        }
        total
    }

    /// One plan point on two elevations would make the floor a vertical wall there: refuses
    /// the first such point; true if there was one.
    fn check_one_elevation_per_point(
        &mut self,
        lines: &[ContourDto],
        paths: &[(String, String)],
    ) -> bool {
        let mut seen: std::collections::HashMap<(u64, u64), (usize, f64)> =
            std::collections::HashMap::new();
        for (i, c) in lines.iter().enumerate() {
            for (j, q) in c.points_m.iter().enumerate() {
                let key = ((q[0] + 0.0).to_bits(), (q[1] + 0.0).to_bits());
                match seen.get(&key) {
                    Some(&(k, z)) if z != c.elevation_m => {
                        self.ck.push(
                            format!("{}/{j}", paths[i].0),
                            json!(q),
                            format!(
                                "this point also lies on the line at {} (elevation {z} m): \
                                 one point cannot have two elevations",
                                paths[k].0
                            ),
                        );
                        return true;
                    }
                    Some(_) => {}
                    None => {
                        seen.insert(key, (i, c.elevation_m));
                    }
                }
            }
        }
        false
    }

    /// Crossing contours have no single height where they cross: refuses the first crossing.
    fn check_crossing(&mut self, lines: &[ContourDto], paths: &[(String, String)]) {
        let Some(x) = find_crossing(lines) else {
            return;
        };
        let (i, k) = x.later;
        let (i2, k2) = x.earlier;
        let what = if lines[i].elevation_m == lines[i2].elevation_m {
            "crosses"
        } else {
            "meets"
        };
        self.ck.push(
            format!("{}/{k}", paths[i].0),
            json!(lines[i].points_m[k]),
            format!(
                "the segment from this point to point {} {what} the segment {}/{k2}–{} \
                 (elevation {} m) near [{}, {}]: contours must not cross (touching at a \
                 point at the same elevation is allowed)",
                k + 1,
                paths[i2].0,
                k2 + 1,
                lines[i2].elevation_m,
                x.at[0],
                x.at[1]
            ),
        );
    }
}

/// The floor case of a request's `face.floor`, its fields checked into `ck` (the floor's
/// hash set for the echo; large inputs moved, not copied); the map frame first, as the
/// floor's own ranges are relative to it.
pub(super) fn resolve_floor(f: &mut FloorDto, ck: &mut Checker, max_floor_bytes: u64) -> FloorSpec {
    let sent = SentFloor::of(f);
    // map coordinates: checked first, the floor's own ranges are checked relative to them
    let map = f.map.map(|m| {
        for (i, o) in m.origin_m.iter().enumerate() {
            ck.closed(
                &floor_pointer(&format!("map/origin_m/{i}")),
                *o,
                -1e8,
                1e8,
                "m",
            );
        }
        MAP_DIP_DIRECTION.check(
            ck,
            &floor_pointer("map/dip_direction_deg"),
            m.dip_direction_deg,
        );
        MapFrame {
            origin: m.origin_m,
            dip_direction_deg: m.dip_direction_deg,
        }
    });
    let mut check = FloorCheck {
        ck,
        sent,
        map,
        max_floor_bytes,
    };
    match f.kind {
        FloorKind::Plane => check.plane(),
        FloorKind::Grid => check.grid(f),
        FloorKind::Contours => check.contours(f),
    }
}

/// A place where contour polylines cross: the later segment (contour, first point index), the
/// earlier one, and a plan point of the contact, m.
#[derive(Debug, Clone, Copy, PartialEq)]
struct Crossing {
    later: (usize, usize),
    earlier: (usize, usize),
    at: [f64; 2],
}

/// Sign of the orientation of (a, b, c): +1 left turn, −1 right turn, 0 collinear within the
/// rounding error of the determinant.
fn orient(a: [f64; 2], b: [f64; 2], c: [f64; 2]) -> i8 {
    let l = (b[0] - a[0]) * (c[1] - a[1]);
    let r = (b[1] - a[1]) * (c[0] - a[0]);
    let det = l - r;
    let bound = 8.0 * f64::EPSILON * (l.abs() + r.abs());
    if det > bound {
        1
    } else if det < -bound {
        -1
    } else {
        0
    }
}

/// Whether c (collinear with a–b) lies within the bounding box of a–b.
fn on_segment(a: [f64; 2], b: [f64; 2], c: [f64; 2]) -> bool {
    c[0] >= a[0].min(b[0])
        && c[0] <= a[0].max(b[0])
        && c[1] >= a[1].min(b[1])
        && c[1] <= a[1].max(b[1])
}

/// How two plan segments meet: `None` apart, `Some(true)` crossing through each other's
/// interiors, `Some(false)` touching (an end on the other segment, or collinear overlap);
/// with a point of the contact.
fn contact(a: [f64; 2], b: [f64; 2], c: [f64; 2], d: [f64; 2]) -> Option<(bool, [f64; 2])> {
    let (o1, o2) = (orient(a, b, c), orient(a, b, d));
    let (o3, o4) = (orient(c, d, a), orient(c, d, b));
    if o1 * o2 < 0 && o3 * o4 < 0 {
        // the crossing point, for the message only
        let r = [b[0] - a[0], b[1] - a[1]];
        let s = [d[0] - c[0], d[1] - c[1]];
        let den = r[0] * s[1] - r[1] * s[0];
        let t = ((c[0] - a[0]) * s[1] - (c[1] - a[1]) * s[0]) / den;
        return Some((true, [a[0] + t * r[0], a[1] + t * r[1]]));
    }
    if o1 == 0 && on_segment(a, b, c) {
        return Some((false, c));
    }
    if o2 == 0 && on_segment(a, b, d) {
        return Some((false, d));
    }
    if o3 == 0 && on_segment(c, d, a) {
        return Some((false, a));
    }
    if o4 == 0 && on_segment(c, d, b) {
        return Some((false, b));
    }
    None
}

/// Finds contour segments that give the floor no single height: two contours of different
/// elevations that meet anywhere, or segments (of one polyline or of two at the same elevation)
/// that cross through each other. Touching at a point at the same elevation is allowed. Uses a
/// uniform grid of at most n + 16 cells (n segments), each segment entered in the cells it
/// passes, so the work is about linear for contours spread over their extent. Reports the
/// crossing whose later segment comes first in the request.
fn find_crossing(lines: &[ContourDto]) -> Option<Crossing> {
    // segments as (contour, first point index)
    let mut segs: Vec<(u32, u32)> = Vec::new();
    let (mut lo, mut hi) = ([f64::INFINITY; 2], [f64::NEG_INFINITY; 2]);
    let mut total_len = 0.0;
    for (i, c) in lines.iter().enumerate() {
        for q in &c.points_m {
            for a in 0..2 {
                lo[a] = lo[a].min(q[a]);
                hi[a] = hi[a].max(q[a]);
            }
        }
        for k in 0..c.points_m.len().saturating_sub(1) {
            let (p, q) = (c.points_m[k], c.points_m[k + 1]);
            total_len += (q[0] - p[0]).abs().max((q[1] - p[1]).abs());
            segs.push((i as u32, k as u32));
        }
    }
    let n = segs.len();
    if n < 2 {
        return None;
    }
    let (w, h) = ((hi[0] - lo[0]).max(0.0), (hi[1] - lo[1]).max(0.0));
    let mut cell = (total_len / n as f64)
        .max((w * h / n as f64).sqrt())
        .max(w.max(h) * 1e-9)
        .max(f64::MIN_POSITIVE);
    let max_cells = n as f64 + 16.0;
    let dims = |cell: f64| ((w / cell).floor() + 1.0, (h / cell).floor() + 1.0);
    while {
        let (a, b) = dims(cell);
        a * b > max_cells
    } {
        cell *= 2.0;
    }
    let (ncx, ncy) = dims(cell);
    let (ncx, ncy) = (ncx as usize, ncy as usize);
    let col = |x: f64| (((x - lo[0]) / cell).floor().max(0.0) as usize).min(ncx - 1);
    let row = |y: f64| (((y - lo[1]) / cell).floor().max(0.0) as usize).min(ncy - 1);
    let ends = |s: (u32, u32)| {
        let pts = &lines[s.0 as usize].points_m;
        (pts[s.1 as usize], pts[s.1 as usize + 1])
    };
    // the cells a segment passes: per column strip, the rows its y spans there (widened by one
    // rounding step so that no cell it touches is missed)
    let cells_of = |s: (u32, u32), f: &mut dyn FnMut(usize)| {
        let (a, b) = ends(s);
        let (i0, i1) = (col(a[0].min(b[0])), col(a[0].max(b[0])));
        for i in i0..=i1 {
            let (y0, y1) = if i0 == i1 || a[0] == b[0] {
                (a[1].min(b[1]), a[1].max(b[1]))
            } else {
                let xl = (lo[0] + i as f64 * cell).max(a[0].min(b[0]));
                let xr = (lo[0] + (i + 1) as f64 * cell).min(a[0].max(b[0]));
                let y = |x: f64| a[1] + (x - a[0]) / (b[0] - a[0]) * (b[1] - a[1]);
                let (ya, yb) = (y(xl), y(xr));
                let slack = 1e-9 * cell;
                (
                    (ya.min(yb) - slack).max(a[1].min(b[1])),
                    (ya.max(yb) + slack).min(a[1].max(b[1])),
                )
            };
            for j in row(y0)..=row(y1) {
                f(j * ncx + i);
            }
        }
    };
    let mut start = vec![0u32; ncx * ncy + 1];
    for &s in &segs {
        cells_of(s, &mut |c| start[c + 1] += 1);
    }
    for c in 1..start.len() {
        start[c] += start[c - 1];
    }
    let mut fill = start.clone();
    let mut items = vec![0u32; start[ncx * ncy] as usize];
    for (id, &s) in segs.iter().enumerate() {
        cells_of(s, &mut |c| {
            items[fill[c] as usize] = id as u32;
            fill[c] += 1;
        });
    }
    drop(fill);
    let mut best: Option<Crossing> = None;
    for c in 0..ncx * ncy {
        let bucket = &items[start[c] as usize..start[c + 1] as usize];
        for (u, &s1) in bucket.iter().enumerate() {
            for &s2 in &bucket[u + 1..] {
                let (e, l) = (segs[s1.min(s2) as usize], segs[s1.max(s2) as usize]);
                if best.is_some_and(|b| (l.0 as usize, l.1 as usize) >= b.later) {
                    continue;
                }
                // neighbours on one polyline share a point by construction
                if e.0 == l.0 && l.1 == e.1 + 1 {
                    continue;
                }
                let ((a, b), (p, q)) = (ends(e), ends(l));
                let Some((cross, at)) = contact(a, b, p, q) else {
                    continue;
                };
                let same = lines[e.0 as usize].elevation_m == lines[l.0 as usize].elevation_m;
                if cross || !same {
                    best = Some(Crossing {
                        later: (l.0 as usize, l.1 as usize),
                        earlier: (e.0 as usize, e.1 as usize),
                        at,
                    });
                }
            }
        }
    }
    best
}

/// Ratio of the contours' elevation range to their horizontal extent above which coordinates
/// within ±180 × ±90 are taken for longitude/latitude: a face 100 times higher than wide
/// (steeper than 89.4°) does not exist, while a face of a few hundred metres spans thousandths
/// of a degree.
const GEOGRAPHIC_RELIEF_RATIO: f64 = 100.0;

/// Whether contour lines (elevation in metres, points) look like longitude/latitude: every
/// point within ±180 × ±90, and the horizontal extent less than the elevation range divided by
/// [`GEOGRAPHIC_RELIEF_RATIO`] — in metres such a floor would be a wall. Contours in a local
/// metric frame near the origin (within ±180 × ±90 too) are not flagged.
fn looks_geographic<'a>(lines: impl Iterator<Item = (f64, &'a [[f64; 2]])>) -> bool {
    let (mut lo, mut hi) = ([f64::INFINITY; 2], [f64::NEG_INFINITY; 2]);
    let (mut z_lo, mut z_hi) = (f64::INFINITY, f64::NEG_INFINITY);
    for (z, points) in lines {
        z_lo = z_lo.min(z);
        z_hi = z_hi.max(z);
        for q in points {
            if q[0].abs() > 180.0 || q[1].abs() > 90.0 {
                return false;
            }
            for k in 0..2 {
                lo[k] = lo[k].min(q[k]);
                hi[k] = hi[k].max(q[k]);
            }
        }
    }
    let extent = (hi[0] - lo[0]).max(hi[1] - lo[1]);
    let relief = z_hi - z_lo;
    extent.is_finite() && relief > 0.0 && extent * GEOGRAPHIC_RELIEF_RATIO < relief
}

#[cfg(test)]
mod geographic_tests {
    use super::looks_geographic;

    fn lines(scale: f64, offset: [f64; 2]) -> Vec<(f64, Vec<[f64; 2]>)> {
        // a 45° face 120 m along the dip: contours every 10 m of elevation, 20 m across
        (0..9)
            .map(|i| {
                let x = 10.0 * i as f64;
                let pts = vec![
                    [offset[0] + scale * x, offset[1] - scale * 10.0],
                    [offset[0] + scale * x, offset[1] + scale * 10.0],
                ];
                (-x, pts)
            })
            .collect()
    }

    fn check(ls: &[(f64, Vec<[f64; 2]>)]) -> bool {
        looks_geographic(ls.iter().map(|(z, p)| (*z, p.as_slice())))
    }

    #[test]
    fn metres_near_the_origin_are_not_geographic() {
        assert!(!check(&lines(1.0, [0.0, 0.0])));
        assert!(!check(&lines(1.0, [-60.0, 40.0])));
        // a small face: 1 m of relief over 1.4 m
        assert!(!check(
            &lines(0.01, [0.0, 0.0])
                .iter()
                .map(|(z, p)| (z / 100.0, p.clone()))
                .collect::<Vec<_>>()
        ));
    }

    #[test]
    fn degrees_are_geographic_and_map_metres_are_not() {
        // the same face in degrees near 8.7° E 46.6° N: 1 m ≈ 9e-6 °
        assert!(check(&lines(9e-6, [8.7, 46.6])));
        assert!(check(&lines(9e-6, [-179.9, -89.9])));
        // in map metres (easting, northing): outside ±180 × ±90
        assert!(!check(&lines(1.0, [500_000.0, 5_160_000.0])));
        // one elevation only: no relief, nothing to judge by
        assert!(!check(&[(0.0, vec![[8.7, 46.6], [8.7001, 46.6]])]));
    }
}
