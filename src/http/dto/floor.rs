//! Floors in the formats engineers already have: ESRI ASCII grids (`.asc`) and GeoJSON contour
//! lines, parsed into the plain grid and contour forms (api.md `POST /v1/migration`, Floors).
//!
//! ESRI ASCII is read by the strict parser below rather than the `esri_ascii_grid` crate (0.4.6):
//! that crate reads a file through `Read + Seek`, but it takes the sixth line for `NODATA_value`
//! whether or not it is one, so a file without `NODATA_value` silently loses its first data row
//! (its row 0 is the file's second row); a short row panics (index out of bounds); extra values
//! are ignored; header keywords must come in one fixed order; and its errors name no line. A file
//! is small, its format a few lines of text, and an engineer needs the line that is wrong.
//! GeoJSON goes through the `geojson` crate, one feature at a time so that errors name it.

use serde::Deserialize;
use serde_json::Value;

/// Largest number of rows or columns of an ESRI ASCII grid (as for `heights_m`).
pub const MAX_GRID_SIDE: usize = 4096;

/// The header of an ESRI ASCII grid, with where its data starts.
#[derive(Debug, Clone, PartialEq)]
pub struct EsriHeader {
    /// Number of columns (west to east).
    pub ncols: usize,
    /// Number of rows (the first data row is the northernmost).
    pub nrows: usize,
    /// x of the centre of column 0, m.
    pub x_center: f64,
    /// y of the centre of the southernmost row, m.
    pub y_center: f64,
    /// Square cell size, m.
    pub cellsize: f64,
    /// The value that marks a cell without data.
    pub nodata: Option<f64>,
    /// Byte offset of the first data line.
    data_offset: usize,
    /// 1-based number of the first data line.
    data_line: usize,
}

/// A parse error: the 1-based line number, and a message that starts with it.
#[derive(Debug, Clone, PartialEq)]
pub struct TextError {
    /// 1-based line number (0: the text as a whole).
    pub line: usize,
    /// "line 7: expected 12 values, got 11".
    pub message: String,
}

fn err(line: usize, msg: impl std::fmt::Display) -> TextError {
    TextError {
        line,
        message: if line > 0 {
            format!("line {line}: {msg}")
        } else {
            msg.to_string()
        },
    }
}

/// Lines of `text` with their byte offsets and 1-based numbers (`\n` or `\r\n` endings).
fn lines_at(text: &str, from: usize, first: usize) -> impl Iterator<Item = (usize, usize, &str)> {
    let mut off = from;
    let mut no = first;
    std::iter::from_fn(move || {
        if off >= text.len() {
            return None;
        }
        let rest = &text[off..];
        let end = rest.find('\n').map_or(rest.len(), |k| k + 1);
        let line = rest[..end].trim_end_matches(['\n', '\r']);
        let item = (off, no, line);
        off += end;
        no += 1;
        Some(item)
    })
}

/// Reads the header of an ESRI ASCII grid: `ncols`, `nrows`, `xllcorner`|`xllcenter`,
/// `yllcorner`|`yllcenter`, `cellsize` and an optional `NODATA_value`, one per line, in any order,
/// keywords in any case. Cell values are heights at the cells' centres.
pub fn esri_header(text: &str) -> Result<EsriHeader, TextError> {
    let mut ncols = None;
    let mut nrows = None;
    let mut xll: Option<(bool, f64)> = None;
    let mut yll: Option<(bool, f64)> = None;
    let mut cellsize = None;
    let mut nodata = None;
    let mut data = None;
    let mut last_line = 0;
    for (off, no, line) in lines_at(text, 0, 1) {
        last_line = no;
        let mut tok = line.split_whitespace();
        let Some(key) = tok.next() else {
            continue;
        };
        if key.parse::<f64>().is_ok() {
            data = Some((off, no));
            break;
        }
        let k = key.to_ascii_lowercase();
        let value = tok
            .next()
            .ok_or_else(|| err(no, format!("{key} has no value")))?;
        if let Some(extra) = tok.next() {
            return Err(err(
                no,
                format!("{key} takes one value, found also '{extra}'"),
            ));
        }
        let num = || -> Result<f64, TextError> {
            value
                .parse::<f64>()
                .ok()
                .filter(|v| v.is_finite())
                .ok_or_else(|| err(no, format!("{key}: '{value}' is not a finite number")))
        };
        let count = || -> Result<usize, TextError> {
            value
                .parse::<usize>()
                .ok()
                .filter(|n| (2..=MAX_GRID_SIDE).contains(n))
                .ok_or_else(|| {
                    err(
                        no,
                        format!("{key}: '{value}' must be a whole number in [2, {MAX_GRID_SIDE}]"),
                    )
                })
        };
        let dup = |seen: bool| {
            if seen {
                Err(err(no, format!("{key} is given twice")))
            } else {
                Ok(())
            }
        };
        match k.as_str() {
            "ncols" => {
                dup(ncols.is_some())?;
                ncols = Some(count()?);
            }
            "nrows" => {
                dup(nrows.is_some())?;
                nrows = Some(count()?);
            }
            "xllcorner" | "xllcenter" => {
                dup(xll.is_some())?;
                xll = Some((k == "xllcenter", num()?));
            }
            "yllcorner" | "yllcenter" => {
                dup(yll.is_some())?;
                yll = Some((k == "yllcenter", num()?));
            }
            "cellsize" => {
                dup(cellsize.is_some())?;
                cellsize = Some(num()?);
            }
            "nodata_value" => {
                dup(nodata.is_some())?;
                // a NODATA marker may be any number, NaN excepted
                nodata = Some(
                    value
                        .parse::<f64>()
                        .ok()
                        .filter(|v| !v.is_nan())
                        .ok_or_else(|| err(no, format!("{key}: '{value}' is not a number")))?,
                );
            }
            "dx" | "dy" => {
                return Err(err(
                    no,
                    format!("{key}: only square cells (one cellsize) are supported"),
                ));
            }
            _ => {
                return Err(err(
                    no,
                    format!(
                        "unknown header keyword '{key}' (expected ncols, nrows, xllcorner or \
                         xllcenter, yllcorner or yllcenter, cellsize, NODATA_value)"
                    ),
                ));
            }
        }
    }
    let (data_offset, data_line) =
        data.ok_or_else(|| err(last_line.max(1), "the header is not followed by any data"))?;
    let missing = |name: &str| {
        err(
            data_line,
            format!("the header lacks {name} before the data"),
        )
    };
    let ncols = ncols.ok_or_else(|| missing("ncols"))?;
    let nrows = nrows.ok_or_else(|| missing("nrows"))?;
    let (xc, x) = xll.ok_or_else(|| missing("xllcorner or xllcenter"))?;
    let (yc, y) = yll.ok_or_else(|| missing("yllcorner or yllcenter"))?;
    let cellsize = cellsize.ok_or_else(|| missing("cellsize"))?;
    if !(0.01..=100.0).contains(&cellsize) {
        return Err(err(
            0,
            format!("cellsize {cellsize} m is outside [0.01, 100] m"),
        ));
    }
    Ok(EsriHeader {
        ncols,
        nrows,
        x_center: if xc { x } else { x + 0.5 * cellsize },
        y_center: if yc { y } else { y + 0.5 * cellsize },
        cellsize,
        nodata,
        data_offset,
        data_line,
    })
}

/// Reads the data rows of an ESRI ASCII grid, one row of `ncols` values per line (blank lines
/// are skipped): rows returned south to north (row i at y = y_center + i·cellsize), NODATA cells
/// as NaN. Heights must be finite and within ±`max_abs` m.
pub fn esri_heights(
    text: &str,
    h: &EsriHeader,
    max_abs: f64,
) -> Result<(Vec<Vec<f64>>, usize), TextError> {
    let mut nodata = 0usize;
    let rows = esri_rows(text, h, |n, tok| {
        let v: f64 = tok
            .parse()
            .map_err(|_| format!("value {n}: '{tok}' is not a number"))?;
        if h.nodata == Some(v) {
            nodata += 1;
            return Ok(f64::NAN);
        }
        if !v.is_finite() {
            return Err(format!("value {n}: '{tok}' is not a finite height"));
        }
        if v.abs() > max_abs {
            return Err(format!(
                "value {n}: height {v} m is outside [−{max_abs:e}, {max_abs:e}] m"
            ));
        }
        Ok(v)
    })?;
    Ok((rows, nodata))
}

/// Reads the data rows of an ESRI ASCII grid of integer codes (a zone map), south to north as
/// [`esri_heights`]; NODATA cells as None. A value that is not an integer in ±2^53 is an error
/// naming its line and place.
pub fn esri_codes(text: &str, h: &EsriHeader) -> Result<Vec<Vec<Option<i64>>>, TextError> {
    esri_rows(text, h, |n, tok| {
        let v: f64 = tok
            .parse()
            .map_err(|_| format!("value {n}: '{tok}' is not a number"))?;
        if h.nodata == Some(v) {
            return Ok(None);
        }
        if !(v.is_finite() && v.fract() == 0.0 && v.abs() <= 9_007_199_254_740_992.0) {
            return Err(format!(
                "value {n}: '{tok}' is not an integer code (in ±2^53)"
            ));
        }
        Ok(Some(v as i64))
    })
}

/// The data rows of an ESRI ASCII grid, each value read by `cell` (its 1-based place in the
/// row and its text; an error is its message), south to north.
fn esri_rows<T>(
    text: &str,
    h: &EsriHeader,
    mut cell: impl FnMut(usize, &str) -> Result<T, String>,
) -> Result<Vec<Vec<T>>, TextError> {
    let mut rows: Vec<Vec<T>> = Vec::with_capacity(h.nrows);
    let mut last = h.data_line;
    for (_, no, line) in lines_at(text, h.data_offset, h.data_line) {
        last = no;
        if line.trim().is_empty() {
            continue;
        }
        if rows.len() == h.nrows {
            return Err(err(no, format!("more data than nrows = {} rows", h.nrows)));
        }
        let mut row = Vec::with_capacity(h.ncols);
        let mut n = 0usize;
        for tok in line.split_whitespace() {
            n += 1;
            if n > h.ncols {
                continue;
            }
            row.push(cell(n, tok).map_err(|m| err(no, m))?);
        }
        if n != h.ncols {
            return Err(err(no, format!("expected {} values, got {n}", h.ncols)));
        }
        rows.push(row);
    }
    if rows.len() != h.nrows {
        return Err(err(
            last,
            format!(
                "expected nrows = {} rows of data, got {} (end of the text)",
                h.nrows,
                rows.len()
            ),
        ));
    }
    rows.reverse();
    Ok(rows)
}

/// One contour line read from a GeoJSON feature, with JSON Pointers (relative to the
/// `geojson` object) to its coordinate array and to what gave its elevation.
#[derive(Debug, Clone, PartialEq)]
pub struct GeoLine {
    /// Elevation of the line, m.
    pub elevation: f64,
    /// Plan points [x, y], m.
    pub points: Vec<[f64; 2]>,
    /// Pointer to the line's coordinate array, e.g. `/features/3/geometry/coordinates/1`.
    pub points_pointer: String,
    /// Pointer to the elevation's source (the property or the feature).
    pub elevation_pointer: String,
}

/// An error in a GeoJSON floor: pointer relative to the `geojson` object, value, message.
#[derive(Debug, Clone, PartialEq)]
pub struct GeoError {
    /// JSON Pointer relative to the `geojson` object.
    pub pointer: String,
    /// The offending value (shortened).
    pub value: Value,
    /// What is wrong.
    pub message: String,
}

fn geo_err(pointer: String, value: Value, message: impl Into<String>) -> GeoError {
    GeoError {
        pointer,
        value,
        message: message.into(),
    }
}

/// Escapes a JSON Pointer token (RFC 6901).
fn pointer_token(s: &str) -> String {
    s.replace('~', "~0").replace('/', "~1")
}

/// Contour lines of a GeoJSON FeatureCollection of LineString and MultiLineString features: the
/// elevation comes from the number in property `elevation_property`, else from the third
/// coordinate (equal along the line), else it is an error naming the feature.
pub fn geojson_lines(v: &Value, elevation_property: &str) -> Result<Vec<GeoLine>, GeoError> {
    let ty = v.get("type").and_then(Value::as_str);
    if ty != Some("FeatureCollection") {
        return Err(geo_err(
            String::new(),
            v.get("type").cloned().unwrap_or(Value::Null),
            "must be a GeoJSON FeatureCollection (\"type\": \"FeatureCollection\") of LineString or \
             MultiLineString features",
        ));
    }
    let Some(features) = v.get("features").and_then(Value::as_array) else {
        return Err(geo_err(
            "/features".into(),
            v.get("features").cloned().unwrap_or(Value::Null),
            "a FeatureCollection needs a features array",
        ));
    };
    let mut out = Vec::new();
    for (i, fv) in features.iter().enumerate() {
        let fp = format!("/features/{i}");
        let f = geojson::Feature::deserialize(fv).map_err(|e| {
            geo_err(
                fp.clone(),
                Value::Null,
                format!("not a GeoJSON Feature: {e}"),
            )
        })?;
        let Some(geom) = &f.geometry else {
            return Err(geo_err(
                format!("{fp}/geometry"),
                Value::Null,
                "a contour feature needs a LineString or MultiLineString geometry",
            ));
        };
        let parts: Vec<(String, &Vec<geojson::Position>)> = match &geom.value {
            geojson::GeometryValue::LineString { coordinates } => {
                vec![(format!("{fp}/geometry/coordinates"), coordinates)]
            }
            geojson::GeometryValue::MultiLineString { coordinates } => coordinates
                .iter()
                .enumerate()
                .map(|(k, c)| (format!("{fp}/geometry/coordinates/{k}"), c))
                .collect(),
            other => {
                return Err(geo_err(
                    format!("{fp}/geometry/type"),
                    Value::String(geometry_name(other).into()),
                    "contours are LineString or MultiLineString geometries",
                ));
            }
        };
        let prop = f.property(elevation_property);
        let from_prop = match prop {
            Some(Value::Number(n)) => n.as_f64(),
            Some(Value::Null) | None => None,
            Some(other) => {
                return Err(geo_err(
                    format!("{fp}/properties/{}", pointer_token(elevation_property)),
                    other.clone(),
                    "the elevation must be a number (m)",
                ));
            }
        };
        for (pp, coords) in parts {
            let mut points = Vec::with_capacity(coords.len());
            let mut third: Option<f64> = None;
            let mut all_third = !coords.is_empty();
            for (j, c) in coords.iter().enumerate() {
                let s = c.as_slice();
                points.push([s[0], s[1]]);
                match s.get(2) {
                    Some(&z) => match third {
                        None => third = Some(z),
                        Some(z0) if z0 != z && from_prop.is_none() => {
                            return Err(geo_err(
                                format!("{pp}/{j}"),
                                serde_json::json!(s),
                                format!(
                                    "a contour line has one elevation: this point's third \
                                     coordinate {z} differs from the line's first, {z0}"
                                ),
                            ));
                        }
                        _ => {}
                    },
                    None => all_third = false,
                }
            }
            let (elevation, elevation_pointer) = match (from_prop, third) {
                (Some(z), _) => (
                    z,
                    format!("{fp}/properties/{}", pointer_token(elevation_property)),
                ),
                (None, Some(z)) if all_third => (z, format!("{pp}/0/2")),
                _ => {
                    return Err(geo_err(
                        fp.clone(),
                        Value::Null,
                        format!(
                            "no elevation: the feature has no numeric property \
                             '{elevation_property}' (elevation_property) and its coordinates \
                             have no third value"
                        ),
                    ));
                }
            };
            out.push(GeoLine {
                elevation,
                points,
                points_pointer: pp,
                elevation_pointer,
            });
        }
    }
    Ok(out)
}

fn geometry_name(g: &geojson::GeometryValue) -> &'static str {
    use geojson::GeometryValue as G;
    match g {
        G::Point { .. } => "Point",
        G::MultiPoint { .. } => "MultiPoint",
        G::LineString { .. } => "LineString",
        G::MultiLineString { .. } => "MultiLineString",
        G::Polygon { .. } => "Polygon",
        G::MultiPolygon { .. } => "MultiPolygon",
        G::GeometryCollection { .. } => "GeometryCollection",
    }
}

/// Serializes a JSON value with every object's keys sorted (for a canonical hash).
pub struct Sorted<'a>(pub &'a Value);

impl serde::Serialize for Sorted<'_> {
    fn serialize<S: serde::Serializer>(&self, s: S) -> Result<S::Ok, S::Error> {
        use serde::ser::{SerializeMap, SerializeSeq};
        match self.0 {
            Value::Object(m) => {
                let mut keys: Vec<&String> = m.keys().collect();
                keys.sort();
                let mut out = s.serialize_map(Some(keys.len()))?;
                for k in keys {
                    out.serialize_entry(k, &Sorted(&m[k]))?;
                }
                out.end()
            }
            Value::Array(a) => {
                let mut out = s.serialize_seq(Some(a.len()))?;
                for x in a {
                    out.serialize_element(&Sorted(x))?;
                }
                out.end()
            }
            other => other.serialize(s),
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    const ASC: &str = "ncols 3\nNROWS 2\nxllcorner 10\nyllcorner 20\ncellsize 2\n\
                       NODATA_value -9999\n1 2 3\n4 -9999 6\n";

    #[test]
    fn esri_rows_run_south_to_north_at_cell_centres() {
        let h = esri_header(ASC).unwrap();
        assert_eq!((h.ncols, h.nrows), (3, 2));
        assert_eq!((h.x_center, h.y_center, h.cellsize), (11.0, 21.0, 2.0));
        let (z, nodata) = esri_heights(ASC, &h, 1e6).unwrap();
        assert_eq!(nodata, 1);
        assert_eq!(z[1], vec![1.0, 2.0, 3.0]);
        assert_eq!(z[0][0], 4.0);
        assert!(z[0][1].is_nan());
    }

    #[test]
    fn esri_without_nodata_keeps_its_first_row() {
        let t = "ncols 2\nnrows 2\nxllcenter 0\nyllcenter 0\ncellsize 1\n1 2\n3 4\n";
        let h = esri_header(t).unwrap();
        let (z, _) = esri_heights(t, &h, 1e6).unwrap();
        assert_eq!(z, vec![vec![3.0, 4.0], vec![1.0, 2.0]]);
        assert_eq!((h.x_center, h.y_center), (0.0, 0.0));
    }

    #[test]
    fn esri_errors_name_the_line() {
        let t = "ncols 3\nnrows 2\nxllcorner 0\nyllcorner 0\ncellsize 1\n1 2 3\n4 5\n";
        let h = esri_header(t).unwrap();
        let e = esri_heights(t, &h, 1e6).unwrap_err();
        assert_eq!(e.message, "line 7: expected 3 values, got 2");
        let t = "ncols 3\nnrows 2\nxllcorner 0\nyllcorner 0\ncellsize 1\n1 2 3\n4 x 6\n";
        let h = esri_header(t).unwrap();
        assert_eq!(
            esri_heights(t, &h, 1e6).unwrap_err().message,
            "line 7: value 2: 'x' is not a number"
        );
        let t = "ncols 3\nnrows 3\nxllcorner 0\nyllcorner 0\ncellsize 1\n1 2 3\n4 5 6\n";
        let h = esri_header(t).unwrap();
        assert!(
            esri_heights(t, &h, 1e6)
                .unwrap_err()
                .message
                .starts_with("line 7: expected nrows = 3")
        );
        let e = esri_header("ncols 3\nnrows 2\nxllcorner 0\nyllcorner 0\ncelsize 1\n1 2 3\n")
            .unwrap_err();
        assert_eq!(e.line, 5);
    }
}
