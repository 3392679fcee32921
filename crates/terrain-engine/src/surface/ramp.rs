//! Colour ramps in gdaldem `color-relief`'s text format, and the built-in ones.
//!
//! Rules (as GDAL's `gdaldem color-relief` reads and applies them, without `-exact_color_entry`
//! or `-nearest_color_entry`):
//! - A line is a height and a colour: `height R G B [A]` (0–255), or `height name` for one of
//!   GRASS's colour names; fields are separated by spaces, tabs, commas or colons; blank lines
//!   and lines starting with `#` are skipped.
//! - A height is metres, or a percentage of the sketch's range (`0%` its lowest, `100%` its
//!   highest); `nv` is the nodata entry, which a sketch (its nodata filled on reading) never
//!   shows.
//! - Entries are ordered by height; between two the colour is interpolated linearly in the
//!   file's (encoded) values; below the first and above the last the end colours hold.
//!
//! Rejected: baking the ramp into a lookup table over the sketch's range. A ramp's steps (two
//! entries at one height, as at a coastline) would blur by a table cell; the stops themselves,
//! a handful, are what the shader reads.

use crate::error::{Error, Result, Role};
use std::path::Path;

/// One entry's height: metres, or a percentage of the sketch's range.
#[derive(Clone, Copy, Debug, PartialEq)]
enum Height {
    Metres(f64),
    Percent(f64),
}

/// A colour ramp as its file gives it (percentages not yet resolved).
#[derive(Clone, Debug, PartialEq)]
pub struct ColorRamp {
    entries: Vec<(Height, [u8; 4])>,
}

/// A ramp's entry resolved for one sketch: the height in metres and the colour (0–255, encoded
/// as the file gives it).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Stop {
    /// Metres.
    pub height_m: f64,
    /// Red, green, blue, alpha, as the file gives them.
    pub rgba: [u8; 4],
}

/// The names built-in ramps go by (`surface.color_ramp = "hypsometric"`).
pub const BUILT_IN: [&str; 2] = ["hypsometric", "viridis"];

/// Atlas tints: sea blues below 0 m, then greens through browns to white on the highest ground,
/// by percentage of the sketch's range above sea level.
const HYPSOMETRIC: &str = "\
# Hypsometric tints: the sea below 0 m, then lowland green to summit white.
-11000 8 48 107
-200 33 113 181
-0.01 107 174 214
0 84 140 68
5% 118 163 83
20% 172 190 112
40% 222 205 140
60% 196 159 103
80% 152 116 86
95% 214 206 198
100% 250 250 250
";

/// Viridis (matplotlib's perceptually uniform map), by percentage of the sketch's range.
const VIRIDIS: &str = "\
0% 68 1 84
12.5% 71 44 122
25% 59 81 139
37.5% 44 113 142
50% 33 144 141
62.5% 39 173 129
75% 92 200 99
87.5% 170 220 50
100% 253 231 37
";

/// GRASS's colour names with the colours gdaldem gives them (read back from `gdaldem
/// color-relief` of GDAL 3.6: its table, not CSS's, e.g. brown is 191 127 63).
const NAMED: [(&str, [u8; 3]); 16] = [
    ("white", [255, 255, 255]),
    ("black", [0, 0, 0]),
    ("red", [255, 0, 0]),
    ("green", [0, 255, 0]),
    ("blue", [0, 0, 255]),
    ("yellow", [255, 255, 0]),
    ("magenta", [255, 0, 255]),
    ("cyan", [0, 255, 255]),
    ("aqua", [0, 191, 191]),
    ("grey", [191, 191, 191]),
    ("gray", [191, 191, 191]),
    ("orange", [255, 127, 0]),
    ("brown", [191, 127, 63]),
    ("purple", [127, 0, 255]),
    ("violet", [127, 0, 255]),
    ("indigo", [0, 127, 255]),
];

impl ColorRamp {
    /// Parses a ramp's text; the error names the line.
    pub fn parse(text: &str) -> std::result::Result<ColorRamp, String> {
        let mut entries = Vec::new();
        for (n, line) in text.lines().enumerate() {
            let line = line.trim();
            if line.is_empty() || line.starts_with('#') {
                continue;
            }
            let fields: Vec<&str> = line
                .split([' ', '\t', ',', ':'])
                .filter(|f| !f.is_empty())
                .collect();
            let entry = entry(&fields).map_err(|why| format!("line {}: {why}", n + 1))?;
            if let Some(e) = entry {
                entries.push(e);
            }
        }
        if entries.is_empty() {
            return Err("no colour entries (each line: height R G B [A], or height name)".into());
        }
        Ok(ColorRamp { entries })
    }

    /// Reads the ramp file at `path`.
    pub fn load(path: &Path) -> Result<ColorRamp> {
        let text = std::fs::read(path).map_err(|e| Error::io(Role::ColorRamp, path, e))?;
        let text = String::from_utf8(text).map_err(|_| {
            Error::file(
                Role::ColorRamp,
                path,
                "not text: give gdaldem color-relief's text format",
            )
        })?;
        ColorRamp::parse(&text).map_err(|why| Error::file(Role::ColorRamp, path, why))
    }

    /// The built-in ramp called `name`.
    pub fn built_in(name: &str) -> Option<ColorRamp> {
        let text = match name {
            "hypsometric" => HYPSOMETRIC,
            "viridis" => VIRIDIS,
            _ => return None,
        };
        Some(ColorRamp::parse(text).expect("the built-in ramps parse"))
    }

    /// The entries resolved for a sketch whose heights span `min_m`…`max_m`, ordered by height
    /// (percentages placed within the range, as gdaldem places them within the raster's).
    pub fn stops(&self, min_m: f64, max_m: f64) -> Vec<Stop> {
        let mut stops: Vec<Stop> = self
            .entries
            .iter()
            .map(|&(h, rgba)| Stop {
                height_m: match h {
                    Height::Metres(m) => m,
                    Height::Percent(p) => min_m + p / 100.0 * (max_m - min_m),
                },
                rgba,
            })
            .collect();
        // A stable sort: two entries at one height keep the file's order, a step between them.
        stops.sort_by(|a, b| a.height_m.total_cmp(&b.height_m));
        stops
    }
}

/// The colour `stops` give height `h` (0–255 per channel, unrounded): linear between the two
/// around it, the end colours beyond them.
pub fn colour_at(stops: &[Stop], h: f64) -> [f64; 4] {
    let as_f64 = |s: &Stop| s.rgba.map(|c| c as f64);
    let Some(first) = stops.first() else {
        return [0.0; 4];
    };
    if h <= first.height_m {
        return as_f64(first);
    }
    for pair in stops.windows(2) {
        let (a, b) = (&pair[0], &pair[1]);
        if h < b.height_m {
            let t = (h - a.height_m) / (b.height_m - a.height_m);
            let (ca, cb) = (as_f64(a), as_f64(b));
            return [0, 1, 2, 3].map(|c| ca[c] + t * (cb[c] - ca[c]));
        }
    }
    as_f64(stops.last().unwrap_or(first))
}

/// One line's fields as an entry; `None` for the nodata entry.
fn entry(fields: &[&str]) -> std::result::Result<Option<(Height, [u8; 4])>, String> {
    let (first, colour) = fields.split_first().ok_or("empty")?;
    let height = if first.eq_ignore_ascii_case("nv") {
        None
    } else if let Some(p) = first.strip_suffix('%') {
        let p: f64 = number(p)?;
        Some(Height::Percent(p))
    } else {
        Some(Height::Metres(number(first)?))
    };
    let rgba = match colour {
        [name] => {
            let name = name.to_ascii_lowercase();
            let (_, [r, g, b]) = NAMED
                .iter()
                .find(|(n, _)| *n == name)
                .ok_or_else(|| format!("{name:?} is not a colour name gdaldem knows"))?;
            [*r, *g, *b, 255]
        }
        [r, g, b] => [channel(r)?, channel(g)?, channel(b)?, 255],
        [r, g, b, a] => [channel(r)?, channel(g)?, channel(b)?, channel(a)?],
        _ => {
            return Err(format!(
                "{} fields: give height R G B [A], or height name",
                fields.len()
            ));
        }
    };
    Ok(height.map(|h| (h, rgba)))
}

fn number(s: &str) -> std::result::Result<f64, String> {
    match s.parse::<f64>() {
        Ok(v) if v.is_finite() => Ok(v),
        _ => Err(format!("{s:?} is not a finite height")),
    }
}

fn channel(s: &str) -> std::result::Result<u8, String> {
    // gdaldem reads the channels with atoi and keeps them as they are; a value outside 0–255
    // is a mistake in the file, said here.
    s.parse::<u8>()
        .map_err(|_| format!("{s:?} is not a colour channel 0–255"))
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn reads_gdaldems_format() {
        let text = "# a ramp\n100% white\n0,0,0,255\n50%:255:0:0\nnv 0 0 0 0\n\n20\tbrown\n";
        let ramp = ColorRamp::parse(text).unwrap();
        let stops = ramp.stops(-100.0, 300.0);
        let heights: Vec<f64> = stops.iter().map(|s| s.height_m).collect();
        assert_eq!(heights, [0.0, 20.0, 100.0, 300.0]);
        assert_eq!(stops[1].rgba, [191, 127, 63, 255]);
        assert_eq!(stops[2].rgba, [255, 0, 0, 255]);
        // Between two entries, linear; beyond the ends, the end colours.
        assert_eq!(colour_at(&stops, 10.0), [95.5, 63.5, 159.0, 255.0]);
        assert_eq!(colour_at(&stops, -50.0), [0.0, 0.0, 255.0, 255.0]);
        assert_eq!(colour_at(&stops, 1e6), [255.0; 4]);
    }

    #[test]
    fn a_step_keeps_its_order() {
        let ramp = ColorRamp::parse("0 0 0 255\n0 255 0 0\n10 0 0 0\n").unwrap();
        let stops = ramp.stops(0.0, 10.0);
        assert_eq!(colour_at(&stops, 0.0), [0.0, 0.0, 255.0, 255.0]);
        assert!(colour_at(&stops, 1e-9)[0] > 254.0);
    }

    #[test]
    fn refuses_with_the_line() {
        for (text, line) in [
            ("0 0 0 0\n10 mauve\n", "line 2"),
            ("0 300 0 0\n", "line 1"),
            ("x 1 2 3\n", "line 1"),
            ("0 1 2\n1 1 2 3 4 5\n", "line 1"),
        ] {
            let why = ColorRamp::parse(text).unwrap_err();
            assert!(why.starts_with(line), "{text:?}: {why}");
        }
        assert!(ColorRamp::parse("# nothing\n").is_err());
        assert!(ColorRamp::parse("nan 0 0 0\n").is_err());
    }

    #[test]
    fn built_in_ramps_span_the_range() {
        for name in BUILT_IN {
            let stops = ColorRamp::built_in(name).unwrap().stops(10.0, 910.0);
            assert!(stops.iter().any(|s| s.height_m == 910.0), "{name}");
            assert!(stops.windows(2).all(|w| w[0].height_m <= w[1].height_m));
        }
    }
}
