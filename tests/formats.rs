//! The sketch readers against GDAL: every fixture in tests/data/formats/ (written by
//! scripts/make-format-fixtures.sh with GDAL 3.6) read as GDAL reads it. `gdal.json` holds what
//! GDAL reports for each file: size, geotransform, nodata, min, max, mean, valid share and sample
//! values; a refused file is named `refused-*` and must fail with one line naming its compression.

mod common;

use serde_json::Value;
use std::path::PathBuf;
use terrain_engine::sketch::{LoadOptions, RawGrid, read_grid};
use terrain_engine::sketch::{US_SURVEY_FOOT_M, Units};

fn dir() -> PathBuf {
    common::manifest_dir().join("tests/data/formats")
}

fn gdal() -> serde_json::Map<String, Value> {
    let text = std::fs::read_to_string(dir().join("gdal.json")).expect("gdal.json");
    let v: Value = serde_json::from_str(&text).expect("gdal.json parses");
    v["files"].as_object().expect("files").clone()
}

fn read(name: &str) -> RawGrid {
    read_grid(&dir().join(name), &LoadOptions::default()).unwrap_or_else(|e| panic!("{name}: {e}"))
}

/// Our cell for GDAL's (column, row from the north).
fn at(g: &RawGrid, col: usize, row: usize) -> f32 {
    g.data[(g.height - 1 - row) * g.width + col]
}

/// Equal as the f32 our grids hold.
fn same(ours: f64, gdal: f64) -> bool {
    ours as f32 == gdal as f32
}

fn check_against_gdal(want: &Value, g: &RawGrid) -> Result<(), String> {
    let f = |k: &str| want[k].as_f64();
    let size = [g.width as u64, g.height as u64];
    let want_size = [want["size"][0].as_u64(), want["size"][1].as_u64()];
    if want_size != [Some(size[0]), Some(size[1])] {
        return Err(format!("size {size:?}, GDAL {want_size:?}"));
    }
    let nodata = f("nodata");
    for s in want["samples_col_row_from_north"].as_array().unwrap() {
        let (c, r, v) = (
            s[0].as_u64().unwrap() as usize,
            s[1].as_u64().unwrap() as usize,
            s[2].as_f64().unwrap(),
        );
        let ours = at(g, c, r);
        let ok = if nodata.is_some_and(|nd| same(v, nd)) {
            ours.is_nan()
        } else {
            same(ours as f64, v)
        };
        if !ok {
            return Err(format!("cell ({c}, {r}) is {ours}, GDAL {v}"));
        }
    }
    let valid: Vec<f64> = g
        .data
        .iter()
        .filter(|v| v.is_finite())
        .map(|&v| v as f64)
        .collect();
    let min = valid.iter().copied().fold(f64::INFINITY, f64::min);
    let max = valid.iter().copied().fold(f64::NEG_INFINITY, f64::max);
    let mean = valid.iter().sum::<f64>() / valid.len() as f64;
    let (gmin, gmax, gmean) = (f("min").unwrap(), f("max").unwrap(), f("mean").unwrap());
    if !same(min, gmin) || !same(max, gmax) || (mean - gmean).abs() > 1e-6 * gmean.abs().max(1.0) {
        return Err(format!(
            "min/max/mean {min}/{max}/{mean}, GDAL {gmin}/{gmax}/{gmean}"
        ));
    }
    let share = 100.0 * valid.len() as f64 / g.data.len() as f64;
    let gshare = f("valid_percent").unwrap();
    if (share - gshare).abs() > 0.006 {
        return Err(format!("{share:.3} % valid, GDAL {gshare} %"));
    }
    if let Some(gt) = want["geotransform"].as_array() {
        let gt: Vec<f64> = gt.iter().map(|v| v.as_f64().unwrap()).collect();
        let r = g.georef.ok_or("no georeference")?;
        let west = gt[0] + 0.5 * gt[1];
        let south = gt[3] + (g.height as f64 - 0.5) * gt[5];
        let close = |a: f64, b: f64| (a - b).abs() <= 1e-9 * a.abs().max(1.0);
        if !close(r.west, west) || !close(r.south, south) || !close(r.cell_x, gt[1]) {
            return Err(format!(
                "south-west node ({}, {}) cell {}, GDAL ({west}, {south}) cell {}",
                r.west, r.south, r.cell_x, gt[1]
            ));
        }
        let units = match want["crs"].as_str() {
            Some("geographic") => Some(Units::Degrees),
            Some("feet") => Some(Units::Linear(US_SURVEY_FOOT_M)),
            Some("metres") => Some(Units::Linear(1.0)),
            _ => None,
        };
        if units.is_some_and(|u| u != r.units) {
            return Err(format!("units {:?}, GDAL's CRS {:?}", r.units, want["crs"]));
        }
    }
    Ok(())
}

#[test]
fn every_fixture_reads_as_gdal_reads_it_or_is_refused_by_name() {
    let mut failures = Vec::new();
    let mut read_count = 0;
    for (name, want) in gdal() {
        let path = dir().join(&name);
        let got = read_grid(&path, &LoadOptions::default());
        if let Some(kind) = name.strip_prefix("refused-") {
            let method = kind.split('-').next().unwrap().to_ascii_uppercase();
            match got {
                Err(e) if e.to_string().contains(&method) && !e.to_string().contains('\n') => {}
                Err(e) => failures.push(format!("{name}: refused as `{e}`")),
                Ok(_) => failures.push(format!("{name}: read, but should be refused")),
            }
            continue;
        }
        match got {
            Ok(g) => match check_against_gdal(&want, &g) {
                Ok(()) => read_count += 1,
                Err(why) => failures.push(format!("{name}: {why}")),
            },
            Err(e) => failures.push(format!("{name}: {e}")),
        }
    }
    assert!(failures.is_empty(), "{}", failures.join("\n"));
    assert!(read_count >= 110, "only {read_count} fixtures read");
}

/// Every layout, compression and byte order of one sample type decodes to the same cells.
#[test]
fn every_tiff_layout_of_a_type_decodes_to_the_same_cells() {
    for ty in [
        "Byte", "Int8", "UInt16", "Int16", "UInt32", "Int32", "UInt64", "Int64", "Float32",
        "Float64",
    ] {
        let plain = read(&format!("strip-none-{ty}.tif"));
        let mut n = 0;
        for entry in std::fs::read_dir(dir()).unwrap() {
            let name = entry.unwrap().file_name().into_string().unwrap();
            if !name.ends_with(&format!("-{ty}.tif")) || name.starts_with("refused") {
                continue;
            }
            if name.starts_with("utm") || name.starts_with("stateplane") {
                continue; // warped: other cells
            }
            let g = read(&name);
            let same_bits = plain
                .data
                .iter()
                .zip(&g.data)
                .all(|(a, b)| a.to_bits() == b.to_bits() || (a.is_nan() && b.is_nan()));
            assert!(
                same_bits && g.data.len() == plain.data.len(),
                "{name} differs from strip-none-{ty}.tif"
            );
            n += 1;
        }
        assert!(n >= 8, "{ty}: only {n} layouts");
    }
}

/// The mosaics (GDAL's VRT and a glob of the same four tiles) give the whole file's sketch.
#[test]
fn a_mosaic_of_four_tiles_is_the_whole_file() {
    let whole = read("strip-none-Int16.tif");
    for mosaic in ["mosaic.vrt", "tiles/t-*.tif"] {
        let g = read(mosaic);
        assert_eq!((g.width, g.height), (whole.width, whole.height), "{mosaic}");
        assert_eq!((g.dx, g.dy), (whole.dx, whole.dy), "{mosaic}");
        let differ = whole
            .data
            .iter()
            .zip(&g.data)
            .filter(|(a, b)| !(a == b || (a.is_nan() && b.is_nan())))
            .count();
        assert_eq!(
            differ, 0,
            "{mosaic}: {differ} cells differ from the whole file"
        );
        assert_eq!(g.georef, whole.georef, "{mosaic}");
    }
}

/// SRTM tiles share their edge rows; a glob of four synthetic tiles is one grid of 2401² nodes
/// whose shared rows hold both tiles' value, and a missing tile becomes nodata.
#[test]
fn a_glob_of_srtm_tiles_shares_their_edges_and_leaves_gaps_as_nodata() {
    let dir = common::scratch("formats-hgt-glob");
    // Height = 10·(row from the south of the whole mosaic) + column, in 1201² tiles.
    let tile = |lat: i32, lon: i32| {
        let mut bytes = Vec::with_capacity(1201 * 1201 * 2);
        for r in 0..1201 {
            for c in 0..1201 {
                let row_s = (lat - 36) * 1200 + (1200 - r);
                let col = (lon + 84) * 1200 + c;
                let v = ((row_s * 10 + col) % 30000) as i16;
                bytes.extend_from_slice(&v.to_be_bytes());
            }
        }
        let name = format!("N{lat:02}W{:03}.hgt", -lon);
        std::fs::write(dir.join(name), bytes).unwrap();
    };
    tile(36, -84);
    tile(36, -83);
    tile(37, -84); // N37W083 missing
    let g = read_grid(&dir.join("N3*.hgt"), &LoadOptions::default()).unwrap();
    assert_eq!((g.width, g.height), (2401, 2401));
    for (col, row_s) in [
        (0, 0),
        (1200, 0),
        (1200, 1200),
        (2400, 0),
        (0, 2400),
        (700, 1900),
    ] {
        let want = ((row_s * 10 + col) % 30000) as f32;
        assert_eq!(g.data[row_s * 2401 + col], want, "({col}, {row_s})");
    }
    assert!(
        g.data[2400 * 2401 + 2400].is_nan(),
        "the missing tile is nodata"
    );
    let r = g.georef.unwrap();
    assert_eq!((r.west, r.south, r.units), (-84.0, 36.0, Units::Degrees));
}

#[test]
fn a_zipped_srtm_tile_reads_as_gdal_reads_the_bare_one() {
    let want = &gdal()["N36W084.hgt.zip"];
    let g = read("N36W084.hgt.zip");
    check_against_gdal(want, &g).unwrap();
}

/// Malformed mosaics fail in one line naming the file and the cause.
#[test]
fn broken_mosaics_are_refused_in_one_line() {
    let dir = common::scratch("formats-broken-mosaics");
    let tiles = self::dir().join("tiles");
    let src = tiles.join("t-nw.tif");
    let vrt = |name: &str, body: &str| -> PathBuf {
        let p = dir.join(name);
        std::fs::write(&p, body).unwrap();
        p
    };
    let source = |extra: &str| {
        format!(
            "<VRTDataset rasterXSize=\"20\" rasterYSize=\"12\"><VRTRasterBand dataType=\"Int16\" band=\"1\">\
             <SimpleSource><SourceFilename>{}</SourceFilename>{extra}</SimpleSource>\
             </VRTRasterBand></VRTDataset>",
            src.display()
        )
    };
    let self_ref = dir.join("self.vrt");
    let cases: Vec<(PathBuf, &str)> = vec![
        (vrt("notxml.vrt", "<VRTDataset"), "not XML"),
        (vrt("root.vrt", "<Other/>"), "not <VRTDataset>"),
        (
            vrt(
                "huge.vrt",
                "<VRTDataset rasterXSize=\"65536\" rasterYSize=\"32768\"/>",
            ),
            "more than",
        ),
        (
            vrt(
                "resample.vrt",
                &source(
                    "<SrcRect xOff=\"0\" yOff=\"0\" xSize=\"20\" ySize=\"12\"/><DstRect xOff=\"0\" yOff=\"0\" xSize=\"10\" ySize=\"6\"/>",
                ),
            ),
            "resampled",
        ),
        (
            vrt("band2.vrt", &source("<SourceBand>2</SourceBand>")),
            "band 1",
        ),
        (
            vrt(
                "missing.vrt",
                "<VRTDataset rasterXSize=\"4\" rasterYSize=\"4\"><VRTRasterBand band=\"1\"><SimpleSource><SourceFilename relativeToVRT=\"1\">nope.tif</SourceFilename></SimpleSource></VRTRasterBand></VRTDataset>",
            ),
            "nope.tif",
        ),
        (
            vrt(
                "self.vrt",
                &format!(
                    "<VRTDataset rasterXSize=\"4\" rasterYSize=\"4\"><VRTRasterBand band=\"1\"><SimpleSource><SourceFilename>{}</SourceFilename></SimpleSource></VRTRasterBand></VRTDataset>",
                    self_ref.display()
                ),
            ),
            "nests more than",
        ),
        (dir.join("none-*.tif"), "no file matches"),
    ];
    std::fs::copy(
        self::dir().join("utm-metres-Float32.tif"),
        dir.join("mix-a.tif"),
    )
    .unwrap();
    std::fs::copy(&src, dir.join("mix-b.tif")).unwrap();
    let mut cases = cases;
    cases.push((dir.join("mix-*.tif"), "cells of"));
    for (path, want) in cases {
        match read_grid(&path, &LoadOptions::default()) {
            Ok(_) => panic!("{} was read", path.display()),
            Err(e) => {
                let msg = e.to_string();
                assert!(
                    msg.contains(want) && !msg.contains('\n'),
                    "{}: `{msg}` should say `{want}`",
                    path.display()
                );
            }
        }
    }
}

/// A header claiming 2³¹ cells (65536 × 32768) is refused before anything is allocated: the
/// program runs under a 1 GiB address-space limit (8 GiB would be needed for the grid) and must
/// exit 1 with one line naming the cell limit, in every format that states a size.
#[test]
fn a_two_billion_cell_header_is_refused_before_allocating() {
    let dir = common::scratch("formats-huge-headers");
    let (w, h) = (65536u32, 32768u32);
    let tiff = {
        // Little-endian TIFF, one IFD of 9 entries, one strip said to start at byte 8.
        let mut b = b"II*\0".to_vec();
        b.extend_from_slice(&8u32.to_le_bytes());
        let entries: [(u16, u16, u32, u32); 9] = [
            (256, 4, 1, w),
            (257, 4, 1, h),
            (258, 3, 1, 16),
            (259, 3, 1, 1),
            (262, 3, 1, 1),
            (273, 4, 1, 8),
            (277, 3, 1, 1),
            (278, 4, 1, h),
            (279, 4, 1, w * 2),
        ];
        b.extend_from_slice(&(entries.len() as u16).to_le_bytes());
        for (tag, ty, count, value) in entries {
            b.extend_from_slice(&tag.to_le_bytes());
            b.extend_from_slice(&ty.to_le_bytes());
            b.extend_from_slice(&count.to_le_bytes());
            b.extend_from_slice(&value.to_le_bytes());
        }
        b.extend_from_slice(&0u32.to_le_bytes());
        b
    };
    let png = {
        let mut ihdr = b"IHDR".to_vec();
        ihdr.extend_from_slice(&w.to_be_bytes());
        ihdr.extend_from_slice(&h.to_be_bytes());
        ihdr.extend_from_slice(&[16, 0, 0, 0, 0]);
        let mut b = b"\x89PNG\r\n\x1a\n".to_vec();
        b.extend_from_slice(&13u32.to_be_bytes());
        b.extend_from_slice(&ihdr);
        b.extend_from_slice(&crc32fast::hash(&ihdr).to_be_bytes());
        // A short IDAT (an empty zlib stream) and IEND, so the header is all that is wrong.
        for (kind, data) in [
            (&b"IDAT"[..], &b"\x78\x9c\x03\x00\x00\x00\x00\x01"[..]),
            (b"IEND", b""),
        ] {
            let mut chunk = kind.to_vec();
            chunk.extend_from_slice(data);
            b.extend_from_slice(&(data.len() as u32).to_be_bytes());
            b.extend_from_slice(&chunk);
            b.extend_from_slice(&crc32fast::hash(&chunk).to_be_bytes());
        }
        b
    };
    let files: Vec<(&str, Vec<u8>)> = vec![
        ("huge.tif", tiff),
        ("huge.png", png),
        (
            "huge.asc",
            format!("ncols {w}\nnrows {h}\ncellsize 1\n1 2 3\n").into_bytes(),
        ),
        (
            "huge.vrt",
            format!("<VRTDataset rasterXSize=\"{w}\" rasterYSize=\"{h}\"/>").into_bytes(),
        ),
        (
            "huge.xyz",
            format!("0 0 1\n1 0 1\n0 1 1\n{} {} 1\n", w - 1, h - 1).into_bytes(),
        ),
    ];
    let mut paths: Vec<String> = Vec::new();
    for (name, bytes) in &files {
        std::fs::write(dir.join(name), bytes).unwrap();
        paths.push(dir.join(name).display().to_string());
    }
    // Two SRTM tiles 54° and 80° apart: a glob mosaic of 64,801 × 96,001 nodes.
    for name in ["N00E000.hgt", "N80E054.hgt"] {
        std::fs::write(dir.join(name), vec![0u8; 1201 * 1201 * 2]).unwrap();
    }
    paths.push(dir.join("N*.hgt").display().to_string());
    let bin = env!("CARGO_BIN_EXE_terrain");
    for path in paths {
        let out = std::process::Command::new("sh")
            .arg("-c")
            .arg("ulimit -v 1048576 && exec \"$0\" info \"$1\"")
            .arg(bin)
            .arg(&path)
            .output()
            .unwrap();
        let err = String::from_utf8_lossy(&out.stderr);
        assert_eq!(out.status.code(), Some(1), "{path}: {err}");
        assert_eq!(err.lines().count(), 1, "{path}: {err}");
        assert!(err.contains("cells supported"), "{path}: {err}");
    }
}

/// Damaged copies of every fixture (truncated at five points, a byte flipped at five places)
/// given to `terrain info`: each exits 1 with exactly one line on stderr, or, where the damage
/// left a readable file (a flipped height), exits 0 with at most one `warning:` line (a flipped
/// height can make a relief too tall for the sketch, a lost tag a file without a georeference).
/// Never a panic, never a second line, never a warning beside an error.
#[test]
fn every_damaged_fixture_exits_1_with_one_line_or_still_reads() {
    let dir = common::scratch("formats-damaged");
    let bin = env!("CARGO_BIN_EXE_terrain");
    let mut names: Vec<String> = gdal().keys().cloned().collect();
    names.push("grid.pgw".into());
    let (mut refused, mut read, mut tried) = (0, 0, 0);
    // Truncations that still read: formats without a stated size (XYZ, a PNG whose world file
    // lost only its last line's digits) lose their end silently, as they do in GDAL.
    let mut readable_cuts = Vec::new();
    let mut failures = Vec::new();
    for name in &names {
        let bytes = std::fs::read(self::dir().join(name)).unwrap();
        let n = bytes.len();
        let mut damaged: Vec<(String, Vec<u8>)> = Vec::new();
        for k in 0..5 {
            let cut = n * k / 5 + (k % 2) * 3;
            damaged.push((format!("cut{cut}"), bytes[..cut.min(n - 1)].to_vec()));
            let at = (n * (2 * k + 1) / 10 + 7 * k) % n;
            let mut flipped = bytes.clone();
            flipped[at] ^= 0xA5;
            damaged.push((format!("flip{at}"), flipped));
        }
        for (what, data) in damaged {
            let what_name = what.clone();
            let case = dir.join(what);
            std::fs::create_dir_all(&case).unwrap();
            // A world file is damaged beside an intact PNG; a VRT keeps its tiles.
            let target = if name.ends_with(".pgw") {
                std::fs::copy(self::dir().join("grid.png"), case.join("grid.png")).unwrap();
                std::fs::write(case.join("grid.pgw"), &data).unwrap();
                case.join("grid.png")
            } else {
                let p = case.join(name);
                std::fs::write(&p, &data).unwrap();
                if name.ends_with(".vrt") {
                    let _ =
                        std::os::unix::fs::symlink(self::dir().join("tiles"), case.join("tiles"));
                }
                p
            };
            // The wide-integer fixtures span their type's range: scaled to metres, so that only
            // the damage can refuse them.
            let scale = if name.contains("Int64") {
                "1e-9"
            } else if name.contains("Int32") {
                "1e-6"
            } else {
                "1"
            };
            let out = std::process::Command::new(bin)
                .args(["info", "--height-scale", scale])
                .arg(&target)
                .output()
                .unwrap();
            let err = String::from_utf8_lossy(&out.stderr);
            tried += 1;
            match out.status.code() {
                Some(1) if err.lines().count() == 1 => refused += 1,
                Some(0)
                    if err.lines().count() <= 1
                        && err.lines().all(|l| l.starts_with("warning: ")) =>
                {
                    read += 1;
                    if what_name.starts_with("cut") {
                        readable_cuts.push(format!("{name} {what_name}"));
                    }
                }
                code => failures.push(format!(
                    "{name} {}: exit {code:?}, stderr {err:?}",
                    case.display()
                )),
            }
            std::fs::remove_dir_all(&case).unwrap();
        }
    }
    eprintln!(
        "{tried} damaged inputs: {refused} refused in one line, {read} still readable, of which \
         truncations: {readable_cuts:?}"
    );
    assert!(failures.is_empty(), "{}", failures.join("\n"));
    assert!(refused > tried / 2, "only {refused} of {tried} refused");
}

/// XYZ points in any order, with or without the header line, make the same grid.
#[test]
fn xyz_rows_in_any_order_make_the_same_grid() {
    let dir = common::scratch("formats-xyz-order");
    let text = std::fs::read_to_string(self::dir().join("grid.xyz")).unwrap();
    let mut lines: Vec<&str> = text.lines().collect();
    let header = lines.remove(0);
    assert!(header.starts_with('X'), "GDAL's header line: {header}");
    let ordered = read("grid.xyz");
    // A fixed permutation: every 7th line first, then the rest backwards.
    let mut shuffled: Vec<&str> = lines.iter().step_by(7).copied().collect();
    shuffled.extend(
        lines
            .iter()
            .enumerate()
            .rev()
            .filter(|(k, _)| k % 7 != 0)
            .map(|(_, l)| *l),
    );
    for (name, body) in [
        ("shuffled.xyz", shuffled.join("\n")),
        ("headed.xyz", format!("{header}\n{}", shuffled.join("\n"))),
    ] {
        std::fs::write(dir.join(name), body).unwrap();
        let g = read_grid(&dir.join(name), &LoadOptions::default()).unwrap();
        assert_eq!(
            (g.width, g.height),
            (ordered.width, ordered.height),
            "{name}"
        );
        let same = g
            .data
            .iter()
            .zip(&ordered.data)
            .all(|(a, b)| a.to_bits() == b.to_bits());
        assert!(same, "{name}: cells differ from the file in GDAL's order");
    }
}
