//! Regular-grid XYZ text (as SwissTopo ships it): one `x y z` point per line, separated by spaces,
//! tabs, commas or semicolons, an optional header line. The points must lie on one regular grid;
//! points the grid lacks are nodata.

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
        .map_err(|_| Error::sketch(path, "not an XYZ text file (binary content)"))?;
    parse(path, text)
}

fn parse(path: &Path, text: &str) -> Result<RawGrid> {
    let bad = |reason: String| Error::sketch(path, reason);
    let mut points: Vec<[f64; 3]> = Vec::new();
    for (n, line) in text.lines().enumerate() {
        let line = line.trim();
        if line.is_empty() || line.starts_with('#') {
            continue;
        }
        let fields: Vec<&str> = line
            .split(|c: char| c.is_whitespace() || c == ',' || c == ';')
            .filter(|f| !f.is_empty())
            .collect();
        let parsed: Option<Vec<f64>> = fields.iter().map(|f| f.parse().ok()).collect();
        match parsed {
            Some(v) if v.len() == 3 && v[0].is_finite() && v[1].is_finite() => {
                points.push([v[0], v[1], v[2]])
            }
            None if points.is_empty() && n == 0 => continue, // header line
            _ => {
                return Err(bad(format!(
                    "line {}: expected `x y z`, got `{line}`",
                    n + 1
                )));
            }
        }
    }
    if points.len() < 4 {
        return Err(bad(format!(
            "{} points; a grid needs at least 2×2",
            points.len()
        )));
    }
    let (x0, dx, nx) =
        axis(points.iter().map(|p| p[0])).map_err(|why| bad(format!("x coordinates: {why}")))?;
    let (y0, dy, ny) =
        axis(points.iter().map(|p| p[1])).map_err(|why| bad(format!("y coordinates: {why}")))?;
    let (w, h) = RawGrid::check_size(path, nx, ny)?;
    let mut data = vec![f32::NAN; w * h];
    let mut seen = vec![false; w * h];
    for p in &points {
        let i = ((p[0] - x0) / dx).round() as usize;
        let j = ((p[1] - y0) / dy).round() as usize;
        let k = j * w + i;
        if std::mem::replace(&mut seen[k], true) {
            return Err(bad(format!("point ({}, {}) appears twice", p[0], p[1])));
        }
        data[k] = p[2] as f32;
    }
    let georef = Georef {
        west: x0,
        south: y0,
        cell_x: dx,
        cell_y: dy,
        units: Units::Unknown,
        epsg: None,
    };
    Ok(RawGrid::georeferenced(w, h, data, georef))
}

/// The grid along one axis: first value, spacing and count, or why the values are not a grid.
fn axis(values: impl Iterator<Item = f64>) -> std::result::Result<(f64, f64, i64), String> {
    let mut v: Vec<f64> = values.collect();
    v.sort_by(f64::total_cmp);
    v.dedup();
    if v.len() < 2 {
        return Err("all points share one value".into());
    }
    let step = v
        .windows(2)
        .map(|p| p[1] - p[0])
        .fold(f64::INFINITY, f64::min);
    let (first, last) = (v[0], v[v.len() - 1]);
    let tol = 1e-6 * step.max(1e-9) + 1e-9 * first.abs().max(last.abs());
    for &x in &v {
        let k = (x - first) / step;
        if (k - k.round()).abs() * step > tol.max(1e-3 * step) {
            return Err(format!("{x} is off the regular spacing {step}"));
        }
    }
    let count = ((last - first) / step).round() as i64 + 1;
    Ok((first, step, count))
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn swisstopo_style_rows_with_header_and_a_gap() {
        let text = "X Y Z\n2600000 1200002 500\n2600002 1200002 501\n\
                    2600000 1200000 502\n2600002 1200000 503\n2600004 1200000 504\n";
        let g = parse(Path::new("t.xyz"), text).unwrap();
        assert_eq!((g.width, g.height, g.dx, g.dy), (3, 2, 2.0, 2.0));
        assert_eq!(&g.data[..3], &[502.0, 503.0, 504.0]);
        assert!(g.data[5].is_nan());
    }

    #[test]
    fn irregular_and_malformed_files_are_refused() {
        for (text, want) in [
            ("0 0 1\n1 0 1\n0 1 1\n1.7 1 1\n", "off the regular spacing"),
            ("0 0 1\n1 0 1\n0 1 1\n1 1\n", "expected `x y z`"),
            ("0 0 1\n0 0 2\n1 1 1\n1 0 1\n", "twice"),
            ("0 0 1\n", "at least 2×2"),
        ] {
            let err = parse(Path::new("t.xyz"), text).err().unwrap().to_string();
            assert!(err.contains(want), "{text:?}: {err}");
        }
    }
}
