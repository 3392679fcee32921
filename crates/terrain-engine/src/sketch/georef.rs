//! Where a grid's nodes lie in its file's coordinate system, and what its cells measure on the
//! ground.
//!
//! Rules:
//! - A [`Georef`] names the south-west *node* (a cell's centre for pixel-is-area files, the sample
//!   itself for pixel-is-point ones such as SRTM), so tiles of one mosaic line up by subtracting
//!   positions, whatever registration each file used.
//! - Geographic grids are converted to metres at the grid's mid latitude (the sketch is flat);
//!   projected ones in feet by the foot they name (international 0.3048 m, US survey 1200/3937 m).
//! - A file that does not say its coordinate system (ESRI ASCII, XYZ, a PNG's world file) is taken
//!   as geographic when its cells are under 0.1 and it lies within longitude and latitude range, as
//!   GDAL's users expect of an SRTM-style grid; otherwise its units are metres.

use super::EARTH_RADIUS_M;

/// International foot, metres.
pub const FOOT_M: f64 = 0.3048;
/// US survey foot, metres.
pub const US_SURVEY_FOOT_M: f64 = 1200.0 / 3937.0;

/// The unit of a file's horizontal coordinates.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum Units {
    /// Geographic: longitude and latitude, degrees.
    Degrees,
    /// Projected, metres per unit (1 for metres).
    Linear(f64),
    /// Not stated by the file: see [`Georef::resolved`].
    Unknown,
}

/// The position of a grid's nodes in its file's coordinate system.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Georef {
    /// The south-west node's x (easting or longitude), in `units`.
    pub west: f64,
    /// The south-west node's y (northing or latitude), in `units`.
    pub south: f64,
    /// Node spacing along x (east), positive, in `units`.
    pub cell_x: f64,
    /// Node spacing along y (north), positive, in `units`.
    pub cell_y: f64,
    /// What the coordinates measure.
    pub units: Units,
    /// The coordinate system's EPSG code, where the file names one.
    pub epsg: Option<u16>,
}

impl Georef {
    /// From a GDAL geotransform of a pixel-is-area grid (`[x0, dx, 0, y0, 0, −dy]`, corner of the
    /// north-west cell) `height` rows tall; `None` when rotated or not finite.
    pub fn from_geotransform(gt: [f64; 6], height: usize, units: Units) -> Option<Georef> {
        let [x0, dx, rx, y0, ry, dy] = gt;
        if rx != 0.0 || ry != 0.0 || !(dx > 0.0 && dy < 0.0) || !(x0.is_finite() && y0.is_finite())
        {
            return None;
        }
        let west = x0 + 0.5 * dx;
        let north = y0 + 0.5 * dy;
        Some(Georef {
            west,
            south: north + (height as f64 - 1.0) * dy,
            cell_x: dx,
            cell_y: -dy,
            units,
            epsg: None,
        })
    }

    /// The units made definite: `Unknown` is degrees when the grid fits in longitude and latitude
    /// with cells under 0.1, else metres.
    pub fn resolved(self, width: usize, height: usize) -> Georef {
        if self.units != Units::Unknown {
            return self;
        }
        let east = self.west + (width as f64 - 1.0) * self.cell_x;
        let north = self.south + (height as f64 - 1.0) * self.cell_y;
        let geographic = self.cell_x < 0.1
            && self.cell_y < 0.1
            && self.west >= -180.5
            && east <= 360.5
            && self.south >= -90.5
            && north <= 90.5;
        Georef {
            units: if geographic {
                Units::Degrees
            } else {
                Units::Linear(1.0)
            },
            ..self
        }
    }

    /// Ground spacing in metres (east–west, north–south) of a grid `height` rows tall.
    pub fn spacing_m(&self, width: usize, height: usize) -> (f64, f64) {
        match self.resolved(width, height).units {
            Units::Degrees => {
                let mid_lat = self.south + 0.5 * (height as f64 - 1.0) * self.cell_y;
                degrees_to_metres(self.cell_x, self.cell_y, mid_lat)
            }
            Units::Linear(m) => (self.cell_x * m, self.cell_y * m),
            // `resolved` never leaves the units unknown; metres, were it to.
            Units::Unknown => (self.cell_x, self.cell_y),
        }
    }
}

impl Georef {
    /// The file's coordinates of a point given by latitude and longitude (degrees): a geographic
    /// file's own, directly (in whatever datum the file uses); a projected file's through the
    /// projection its EPSG code names, from WGS 84. `Err` says why the system cannot be converted.
    pub fn from_lat_lon(&self, lat_deg: f64, lon_deg: f64) -> Result<[f64; 2], String> {
        if self.units == Units::Degrees {
            return Ok([lon_deg, lat_deg]);
        }
        let mut p = (lon_deg.to_radians(), lat_deg.to_radians(), 0.0);
        let (wgs84, proj) = (wgs84()?, self.projection()?);
        proj4rs::transform::transform(&wgs84, &proj, &mut p).map_err(|e| self.cannot(e))?;
        finite_pair([p.0, p.1], || {
            self.cannot("the point lies outside the projection")
        })
    }

    /// The latitude and longitude (degrees) of a point in the file's coordinates: the inverse of
    /// [`Georef::from_lat_lon`].
    pub fn to_lat_lon(&self, x: f64, y: f64) -> Result<[f64; 2], String> {
        if self.units == Units::Degrees {
            return Ok([y, x]);
        }
        let mut p = (x, y, 0.0);
        let (wgs84, proj) = (wgs84()?, self.projection()?);
        proj4rs::transform::transform(&proj, &wgs84, &mut p).map_err(|e| self.cannot(e))?;
        finite_pair([p.1.to_degrees(), p.0.to_degrees()], || {
            self.cannot("the point lies outside the projection")
        })
    }

    fn projection(&self) -> Result<proj4rs::Proj, String> {
        match self.epsg {
            Some(code) => proj4rs::Proj::from_epsg_code(code).map_err(|e| self.cannot(e)),
            None if self.units == Units::Unknown => {
                Err("the file does not say its coordinate system".into())
            }
            None => Err("the file's projected coordinate system has no EPSG code".into()),
        }
    }

    fn cannot(&self, why: impl std::fmt::Display) -> String {
        let code = self
            .epsg
            .map_or("the file's coordinate system".into(), |c| {
                format!("EPSG:{c}")
            });
        format!("{code} cannot be converted from latitude and longitude: {why}")
    }
}

fn wgs84() -> Result<proj4rs::Proj, String> {
    proj4rs::Proj::from_proj_string("+proj=longlat +datum=WGS84 +no_defs")
        .map_err(|e| format!("WGS 84: {e}"))
}

fn finite_pair(p: [f64; 2], why: impl FnOnce() -> String) -> Result<[f64; 2], String> {
    if p.iter().all(|v| v.is_finite()) {
        Ok(p)
    } else {
        Err(why())
    }
}

/// The EPSG code a WKT coordinate system names for itself: its last `AUTHORITY["EPSG","…"]`
/// (WKT 1) or `ID["EPSG",…]` (WKT 2), the outermost node's, which both write last.
pub fn wkt_epsg(wkt: &str) -> Option<u16> {
    let t = wkt.to_ascii_uppercase();
    let at = ["AUTHORITY[\"EPSG\",", "ID[\"EPSG\","]
        .iter()
        .filter_map(|tag| t.rfind(tag).map(|k| k + tag.len()))
        .max()?;
    let digits: String = t[at..]
        .trim_start_matches([' ', '"'])
        .chars()
        .take_while(char::is_ascii_digit)
        .collect();
    digits.parse().ok()
}

/// Converts a geographic cell size (degrees) to metres at `lat_deg`: (east–west, north–south).
pub fn degrees_to_metres(cell_x_deg: f64, cell_y_deg: f64, lat_deg: f64) -> (f64, f64) {
    let m_per_deg = EARTH_RADIUS_M * std::f64::consts::PI / 180.0;
    let east = cell_x_deg * m_per_deg * lat_deg.clamp(-90.0, 90.0).to_radians().cos();
    (east, cell_y_deg * m_per_deg)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_wkt_names_its_own_epsg_code_last() {
        let wkt1 = r#"PROJCS["WGS 84 / UTM zone 16N",GEOGCS["WGS 84",AUTHORITY["EPSG","4326"]],UNIT["metre",1,AUTHORITY["EPSG","9001"]],AUTHORITY["EPSG","32616"]]"#;
        assert_eq!(wkt_epsg(wkt1), Some(32616));
        let wkt2 = r#"PROJCRS["NAD83 / UTM zone 16N",BASEGEOGCRS["NAD83",ID["EPSG",4269]],ID["EPSG",26916]]"#;
        assert_eq!(wkt_epsg(wkt2), Some(26916));
        assert_eq!(wkt_epsg("LOCAL_CS[\"arbitrary\"]"), None);
    }

    #[test]
    fn a_system_without_a_known_epsg_code_is_refused_naming_it() {
        let g = Georef {
            west: 500000.0,
            south: 4000000.0,
            cell_x: 30.0,
            cell_y: 30.0,
            units: Units::Linear(1.0),
            epsg: None,
        };
        let e = g.from_lat_lon(36.0, -84.0).unwrap_err();
        assert!(e.contains("no EPSG code"), "{e}");
        let unknown = Georef { epsg: Some(1), ..g };
        let e = unknown.from_lat_lon(36.0, -84.0).unwrap_err();
        assert!(e.starts_with("EPSG:1 cannot be converted"), "{e}");
        // UTM 16N (EPSG:32616) both ways: the inverse returns the point.
        let utm = Georef {
            epsg: Some(32616),
            ..g
        };
        let [x, y] = utm.from_lat_lon(36.639, -84.2306).unwrap();
        assert!(
            (x - 747598.308).abs() < 0.01 && (y - 4058399.281).abs() < 0.01,
            "{x} {y}"
        );
        let [lat, lon] = utm.to_lat_lon(x, y).unwrap();
        assert!((lat - 36.639).abs() < 1e-9 && (lon + 84.2306).abs() < 1e-9);
    }

    #[test]
    fn degrees_to_metres_matches_jacksboro() {
        let (e, n) = degrees_to_metres(0.000833333333, 0.000833333333, 36.59);
        assert!((e - 74.4).abs() < 0.5 && (n - 92.66).abs() < 0.1, "{e} {n}");
    }

    #[test]
    fn a_geotransform_names_the_south_west_cell_centre() {
        let g = Georef::from_geotransform([100.0, 10.0, 0.0, 500.0, 0.0, -20.0], 3, Units::Unknown)
            .unwrap();
        assert_eq!(
            (g.west, g.south, g.cell_x, g.cell_y),
            (105.0, 450.0, 10.0, 20.0)
        );
        assert_eq!(g.resolved(2, 3).units, Units::Linear(1.0));
        assert!(
            Georef::from_geotransform([0.0, 1.0, 0.1, 0.0, 0.0, -1.0], 3, Units::Unknown).is_none()
        );
    }

    #[test]
    fn small_cells_within_longitude_and_latitude_are_degrees() {
        let g = Georef {
            west: -84.0,
            south: 36.0,
            cell_x: 1.0 / 1200.0,
            cell_y: 1.0 / 1200.0,
            units: Units::Unknown,
            epsg: None,
        };
        assert_eq!(g.resolved(1201, 1201).units, Units::Degrees);
        let (e, n) = g.spacing_m(1201, 1201);
        assert!((n - 92.66).abs() < 0.1 && (e - 74.5).abs() < 0.5, "{e} {n}");
        let feet = Georef {
            units: Units::Linear(US_SURVEY_FOOT_M),
            cell_x: 250.0,
            cell_y: 250.0,
            ..g
        };
        assert!((feet.spacing_m(3, 3).0 - 76.2).abs() < 0.01);
    }
}
