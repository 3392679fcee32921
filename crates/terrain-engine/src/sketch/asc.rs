//! ESRI ASCII grid: a header of `key value` lines (`ncols`, `nrows`, `xllcorner`|`xllcenter`,
//! `yllcorner`|`yllcenter`, `cellsize` or `dx` and `dy`, optional `NODATA_value`), then rows north first.
//!
//! `xllcorner` names the south-west cell's corner, `xllcenter` its centre (GDAL writes the first,
//! some national surveys the second). The file says nothing of its coordinate system: see
//! [`Units::Unknown`](super::georef::Units::Unknown) for how it is told.

use super::RawGrid;
use super::georef::{Georef, Units};
use crate::error::{Error, Result, Role};
use std::path::Path;

pub fn read(path: &Path) -> Result<RawGrid> {
    let bytes = std::fs::read(path).map_err(|e| Error::io(Role::Sketch, path, e))?;
    parse_bytes(path, &bytes)
}

pub fn parse_bytes(path: &Path, bytes: &[u8]) -> Result<RawGrid> {
    let text = std::str::from_utf8(bytes)
        .map_err(|_| Error::sketch(path, "not an ASCII grid (binary content)"))?;
    parse(path, text)
}

#[derive(Default)]
struct Header {
    ncols: Option<f64>,
    nrows: Option<f64>,
    xll: Option<f64>,
    yll: Option<f64>,
    /// `xllcenter` / `yllcenter` rather than `…corner`.
    x_centre: bool,
    y_centre: bool,
    cellsize: Option<f64>,
    dx: Option<f64>,
    dy: Option<f64>,
    nodata: Option<f64>,
}

fn parse(path: &Path, text: &str) -> Result<RawGrid> {
    let bad = |reason: String| Error::sketch(path, reason);
    let mut header = Header::default();
    let mut rest = text;
    // Header lines start with a key; the first line starting with a number (`nan` included)
    // begins the data.
    loop {
        let line_end = rest.find('\n').map_or(rest.len(), |k| k + 1);
        let line = rest[..line_end].trim();
        let mut parts = line.split_whitespace();
        let key = match parts.next() {
            Some(k) if k.parse::<f64>().is_err() => k.to_ascii_lowercase(),
            _ => break,
        };
        let value = parts
            .next()
            .ok_or_else(|| bad(format!("header `{key}` has no value")))?;
        let v: f64 = value
            .parse()
            .map_err(|_| bad(format!("header `{key}` = `{value}` is not a number")))?;
        let slot = match key.as_str() {
            "ncols" => &mut header.ncols,
            "nrows" => &mut header.nrows,
            "xllcorner" => &mut header.xll,
            "yllcorner" => &mut header.yll,
            "xllcenter" => {
                header.x_centre = true;
                &mut header.xll
            }
            "yllcenter" => {
                header.y_centre = true;
                &mut header.yll
            }
            "cellsize" => &mut header.cellsize,
            "dx" | "xdim" => &mut header.dx,
            "dy" | "ydim" => &mut header.dy,
            "nodata_value" => &mut header.nodata,
            _ => return Err(bad(format!("unknown header key `{key}`"))),
        };
        *slot = Some(v);
        rest = &rest[line_end..];
    }
    let need = |v: Option<f64>, key: &str| v.ok_or_else(|| bad(format!("header lacks `{key}`")));
    let ncols = need(header.ncols, "ncols")?;
    let nrows = need(header.nrows, "nrows")?;
    if ncols.fract() != 0.0 || nrows.fract() != 0.0 {
        return Err(bad(format!(
            "ncols {ncols} / nrows {nrows} are not whole numbers"
        )));
    }
    let (w, h) = RawGrid::check_size(path, ncols as i64, nrows as i64)?;
    let (cx, cy) = match (header.cellsize, header.dx, header.dy) {
        (Some(c), None, None) => (c, c),
        (None, Some(x), Some(y)) => (x, y),
        (None, Some(_), None) | (None, None, Some(_)) => {
            return Err(bad("header gives only one of `dx` and `dy`".into()));
        }
        (None, None, None) => return Err(bad("header lacks `cellsize` (or `dx` and `dy`)".into())),
        _ => return Err(bad("header gives both `cellsize` and `dx`/`dy`".into())),
    };
    if !(cx > 0.0 && cy > 0.0 && cx.is_finite() && cy.is_finite()) {
        return Err(bad(format!("cell size {cx} × {cy} is not positive")));
    }
    let half = |centre: bool| if centre { 0.0 } else { 0.5 };
    let georef = Georef {
        west: header.xll.unwrap_or(0.0) + half(header.x_centre) * cx,
        south: header.yll.unwrap_or(0.0) + half(header.y_centre) * cy,
        cell_x: cx,
        cell_y: cy,
        units: Units::Unknown,
        epsg: None,
    };

    let mut data = vec![f32::NAN; w * h];
    let mut count = 0usize;
    for token in rest.split_ascii_whitespace() {
        if count == w * h {
            return Err(bad(format!(
                "more values than ncols × nrows = {} (extra `{token}`)",
                w * h
            )));
        }
        let v: f64 = token.parse().map_err(|_| {
            bad(format!(
                "value {} (row {}, column {}) `{token}` is not a number",
                count + 1,
                count / w + 1,
                count % w + 1
            ))
        })?;
        let (col, row_from_north) = (count % w, count / w);
        let is_nodata = header.nodata.is_some_and(|nd| v == nd) || !v.is_finite();
        data[(h - 1 - row_from_north) * w + col] = if is_nodata { f32::NAN } else { v as f32 };
        count += 1;
    }
    if count < w * h {
        return Err(bad(format!(
            "truncated: {count} of ncols × nrows = {} values",
            w * h
        )));
    }
    Ok(RawGrid::georeferenced(w, h, data, georef))
}

#[cfg(test)]
mod tests {
    use super::*;

    fn p(text: &str) -> Result<RawGrid> {
        parse(Path::new("t.asc"), text)
    }

    #[test]
    fn reads_rows_north_first_and_marks_nodata() {
        let g = p(
            "ncols 2\nnrows 2\nxllcorner 0\nyllcorner 0\ncellsize 10\nNODATA_value -9\n1 2\n-9 4\n",
        )
        .unwrap();
        assert_eq!((g.dx, g.dy), (10.0, 10.0));
        assert!(g.data[0].is_nan()); // south-west came last in the file
        assert_eq!(&g.data[1..], &[4.0, 1.0, 2.0]);
        assert_eq!(g.georef.map(|r| (r.west, r.south)), Some((5.0, 5.0)));
    }

    #[test]
    fn centre_registration_names_the_node_itself() {
        let g =
            p("ncols 2\nnrows 2\nxllcenter 100\nyllcenter 200\ncellsize 10\n1 2\n3 4\n").unwrap();
        assert_eq!(g.georef.map(|r| (r.west, r.south)), Some((100.0, 200.0)));
    }

    #[test]
    fn dx_dy_variant_and_geographic_cells() {
        let g = p("ncols 2\nnrows 2\nxllcorner -84\nyllcorner 36\ndx 0.001\ndy 0.002\n1 2 3 4")
            .unwrap();
        assert!(
            g.dx > 80.0 && g.dx < 100.0 && (g.dy - 222.4).abs() < 0.5,
            "{} {}",
            g.dx,
            g.dy
        );
    }

    #[test]
    fn malformed_headers_and_bodies_name_their_cause() {
        let cases = [
            ("ncols 2\nnrows 2\ncellsize 1\n1 2 3", "truncated"),
            ("ncols 2\nnrows 2\ncellsize 1\n1 2 3 4 5", "more values"),
            ("ncols 2\nnrows 2\ncellsize 1\n1 2 x 4", "not a number"),
            ("ncols 0\nnrows 0\ncellsize 1\n", "at least 2×2"),
            ("ncols -5\nnrows 2\ncellsize 1\n", "at least 2×2"),
            ("ncols 2\nnrows 2\n1 2 3 4", "cellsize"),
            ("ncols 2\nnrows 2\ncellsize -1\n1 2 3 4", "not positive"),
            ("ncols 2\nnrows 2\ncellsize 1\ndx 1\n1 2 3 4", "both"),
            ("ncols 2\ncellsize 1\n1 2 3 4", "nrows"),
            ("nclos 2\n", "unknown header key"),
            (
                "ncols 2\nnrows 2\ncellsize 1\nNODATA_value -9\nnan -9\n3 4",
                "",
            ),
            ("ncols 1e12\nnrows 1e12\ncellsize 1\n", "more than"),
        ];
        for (text, want) in cases {
            match p(text) {
                Err(e) => assert!(
                    !want.is_empty() && e.to_string().contains(want),
                    "{text:?}: {e}"
                ),
                Ok(_) => assert!(want.is_empty(), "{text:?} was accepted"),
            }
        }
    }
}
