//! `terrain tiles` on a single GeoTIFF or a VRT, read window by window: every layout and sample
//! type of docs/formats.md converts to the in-memory atlas bit for bit; a file taller than a band,
//! holes included, converts to the same tiles as a glob mosaic of the same heights; a huge file's
//! header is read without its cells; heights in another unit are refused after level 0's bands;
//! a large text grid is refused with the command that rewrites it.

mod common;

use common::{manifest_dir, scratch};
use std::path::{Path, PathBuf};
use terrain_engine::sketch::convert::{BuildOptions, build};
use terrain_engine::sketch::{Atlas, LoadOptions};
use tiff::encoder::{Compression, TiffEncoder, colortype::Gray32Float};
use tiff::tags::Tag;

fn convert_with(
    src: &Path,
    out: &Path,
    load: LoadOptions,
) -> terrain_engine::sketch::convert::BuildSummary {
    let opts = BuildOptions {
        load,
        threads: 2,
        ..Default::default()
    };
    build(src, out, &opts).unwrap_or_else(|e| panic!("tiles {}: {e}", src.display()))
}

/// Level by level, node for node, the two atlases' bits, and their geometry.
fn assert_same_atlas(name: &str, a: &Atlas, b: &Atlas) {
    assert_eq!(a.levels.len(), b.levels.len(), "{name}: levels");
    for (l, (x, y)) in a.levels.iter().zip(&b.levels).enumerate() {
        assert_eq!(
            (x.width, x.height),
            (y.width, y.height),
            "{name}: level {l}"
        );
        let differ = x
            .data
            .iter()
            .zip(&y.data)
            .filter(|(p, q)| p.to_bits() != q.to_bits())
            .count();
        assert_eq!(differ, 0, "{name}: level {l}: {differ} nodes differ");
    }
    assert_eq!(
        (a.dx, a.dy, a.min_m, a.max_m, a.nodata),
        (b.dx, b.dy, b.min_m, b.max_m, b.nodata),
        "{name}"
    );
    assert_eq!(a.georef, b.georef, "{name}");
}

/// `src` loaded in memory with `load`, and its pyramid (metres already) loaded.
fn in_memory_and_tiled(src: &Path, out: &Path, load: LoadOptions) -> (Atlas, Atlas) {
    convert_with(src, out, load.clone());
    let memory = Atlas::load(src, &load).unwrap();
    let tiled = Atlas::load(out, &LoadOptions::default()).unwrap();
    (memory, tiled)
}

#[test]
fn every_geotiff_layout_and_type_converts_window_by_window_to_the_atlas() {
    let dir = scratch("tiles-single-formats");
    let formats = manifest_dir().join("tests/data/formats");
    let mut names: Vec<PathBuf> = std::fs::read_dir(&formats)
        .unwrap()
        .flatten()
        .map(|e| e.path())
        .filter(|p| {
            let n = p.file_name().unwrap().to_string_lossy();
            (n.ends_with(".tif") && !n.starts_with("refused")) || n.ends_with(".vrt")
        })
        .collect();
    names.sort();
    assert!(names.len() > 90, "{} fixtures", names.len());
    for src in &names {
        let name = src.file_name().unwrap().to_string_lossy().to_string();
        // The 32- and 64-bit integer fixtures span much of their type's range (docs/formats.md):
        // the first scale that reads them in memory.
        let load = [1.0, 1e-6, 1e-9]
            .into_iter()
            .map(|s| LoadOptions {
                height_scale: Some(s),
                ..LoadOptions::default()
            })
            .find(|load| Atlas::load(src, load).is_ok())
            .unwrap_or_else(|| panic!("{name} reads in memory"));
        let (memory, tiled) = in_memory_and_tiled(src, &dir.join(&name), load);
        assert_same_atlas(&name, &memory, &tiled);
    }
}

#[test]
fn a_tiled_geotiff_taller_than_a_band_converts_to_the_atlas() {
    // 403 × 344 nodes in tiles of 64², DEFLATE with predictor 2 (gdal_translate -ot Int16 -co
    // TILED=YES -co BLOCKXSIZE=64 -co BLOCKYSIZE=64 -co COMPRESS=DEFLATE -co PREDICTOR=2 of the
    // Jacksboro DEM): two bands, each starting inside a row of tiles.
    let src = manifest_dir().join("tests/data/tiles/jacksboro-tile64-deflate-Int16.tif");
    let dir = scratch("tiles-single-tiled");
    let (memory, tiled) = in_memory_and_tiled(&src, &dir.join("pyramid"), LoadOptions::default());
    assert_eq!((memory.width(), memory.height()), (403, 344));
    assert_same_atlas("tiled", &memory, &tiled);
    // Scaled heights too: each band scaled as the whole grid is.
    let load = LoadOptions {
        height_scale: Some(0.3048),
        ..LoadOptions::default()
    };
    let (memory, tiled) = in_memory_and_tiled(&src, &dir.join("feet"), load);
    assert_same_atlas("scaled", &memory, &tiled);
}

/// Heights with detail at every scale and no symmetry, so a misplaced node shows.
fn height(i: usize, j: usize) -> f32 {
    let (x, y) = (i as f32, j as f32);
    300.0 + 80.0 * (x * 0.013).sin() * (y * 0.021).cos() + ((i * 7919 + j * 104_729) % 97) as f32
}

/// A Float32 GeoTIFF in strips of 7 rows (LZW) of `w` × `h` nodes whose south-west node is global
/// node (i0, j0) of a 30 m UTM grid; `hole` marks nodata (−9999, declared in `GDAL_NODATA`).
fn write_tiff(
    path: &Path,
    (w, h): (usize, usize),
    (i0, j0): (usize, usize),
    hole: impl Fn(usize, usize) -> bool,
) {
    let mut data = Vec::with_capacity(w * h);
    for r in (0..h).rev() {
        for c in 0..w {
            let (i, j) = (i0 + c, j0 + r);
            data.push(if hole(i, j) { -9999.0 } else { height(i, j) });
        }
    }
    let file = std::fs::File::create(path).unwrap();
    let mut enc = TiffEncoder::new(file)
        .unwrap()
        .with_compression(Compression::Lzw);
    let mut image = enc.new_image::<Gray32Float>(w as u32, h as u32).unwrap();
    image.rows_per_strip(7).unwrap();
    let dir = image.encoder();
    // Pixel-is-area, the north-west corner of node (i0, j0 + h − 1).
    let (west, north) = (
        500_000.0 + 30.0 * i0 as f64 - 15.0,
        4_000_000.0 + 30.0 * (j0 + h - 1) as f64 + 15.0,
    );
    dir.write_tag(Tag::ModelPixelScaleTag, &[30.0f64, 30.0, 0.0][..])
        .unwrap();
    dir.write_tag(
        Tag::ModelTiepointTag,
        &[0.0f64, 0.0, 0.0, west, north, 0.0][..],
    )
    .unwrap();
    // Projected (1024 = 1), pixel-is-area (1025 = 1), metres (3076 = 9001).
    let keys: [u16; 16] = [1, 1, 0, 3, 1024, 0, 1, 1, 1025, 0, 1, 1, 3076, 0, 1, 9001];
    dir.write_tag(Tag::Unknown(34735), &keys[..]).unwrap();
    dir.write_tag(Tag::GdalNodata, "-9999").unwrap();
    image.write_data(&data).unwrap();
}

/// Every tile file under `dir`, by path relative to it.
fn tiles(dir: &Path) -> Vec<(PathBuf, Vec<u8>)> {
    fn walk(root: &Path, dir: &Path, out: &mut Vec<(PathBuf, Vec<u8>)>) {
        for e in std::fs::read_dir(dir).unwrap().flatten() {
            let p = e.path();
            if p.is_dir() {
                walk(root, &p, out);
            } else if p.extension().is_some_and(|x| x == "tile") {
                out.push((
                    p.strip_prefix(root).unwrap().into(),
                    std::fs::read(&p).unwrap(),
                ));
            }
        }
    }
    let mut out = Vec::new();
    walk(dir, dir, &mut out);
    out.sort();
    out
}

#[test]
fn a_single_file_with_holes_converts_as_the_mosaic_of_its_heights_and_a_vrt_over_it() {
    let dir = scratch("tiles-single-mosaic");
    // Holes inside a band and across a band's edge (rows 254..262 from the south).
    let hole = |i: usize, j: usize| {
        ((40..44).contains(&i) && (100..103).contains(&j))
            || ((200..230).contains(&i) && (250..262).contains(&j))
    };
    let (w, h) = (333, 610);
    write_tiff(&dir.join("whole.tif"), (w, h), (0, 0), hole);
    std::fs::create_dir_all(dir.join("parts")).unwrap();
    for (name, size, at) in [
        ("a", (200, 300), (0, 0)),
        ("b", (133, 300), (200, 0)),
        ("c", (200, 310), (0, 300)),
        ("d", (133, 310), (200, 300)),
    ] {
        write_tiff(&dir.join(format!("parts/{name}.tif")), size, at, hole);
    }
    let single = dir.join("single");
    let s = convert_with(&dir.join("whole.tif"), &single, LoadOptions::default());
    assert_eq!((s.width, s.height, s.sources), (w, h, 1));
    let mosaic = dir.join("mosaic");
    convert_with(&dir.join("parts/*.tif"), &mosaic, LoadOptions::default());
    let (a, b) = (tiles(&single), tiles(&mosaic));
    let (p, q) = (
        terrain_engine::sketch::tiles::Pyramid::open(&single)
            .unwrap()
            .meta,
        terrain_engine::sketch::tiles::Pyramid::open(&mosaic)
            .unwrap()
            .meta,
    );
    assert_eq!(a.len(), p.tile_count());
    assert!(a == b, "the single file's tiles equal the mosaic's");
    assert_eq!(p.nodata, 12 + 30 * 12);
    assert_eq!((p.georef, p.nodata, p.min_m), (q.georef, q.nodata, q.min_m));
    // A VRT over the parts, as gdalbuildvrt writes one, reads its GeoTIFFs window by window.
    let mut vrt = format!(
        "<VRTDataset rasterXSize=\"{w}\" rasterYSize=\"{h}\">\n\
         <GeoTransform>499985, 30, 0, {}, 0, -30</GeoTransform>\n\
         <VRTRasterBand dataType=\"Float32\" band=\"1\">\n",
        4_000_000.0 + 30.0 * (h - 1) as f64 + 15.0
    );
    for (name, (pw, ph), (x0, y0)) in [
        ("a", (200, 300), (0, 0)),
        ("b", (133, 300), (200, 0)),
        ("c", (200, 310), (0, 300)),
        ("d", (133, 310), (200, 300)),
    ] {
        vrt += &format!(
            "<ComplexSource><SourceFilename relativeToVRT=\"1\">parts/{name}.tif</SourceFilename>\
             <SourceBand>1</SourceBand><SrcRect xOff=\"0\" yOff=\"0\" xSize=\"{pw}\" ySize=\"{ph}\"/>\
             <DstRect xOff=\"{x0}\" yOff=\"{}\" xSize=\"{pw}\" ySize=\"{ph}\"/>\
             <NODATA>-9999</NODATA></ComplexSource>\n",
            h - y0 - ph
        );
    }
    vrt += "</VRTRasterBand>\n</VRTDataset>\n";
    std::fs::write(dir.join("parts.vrt"), vrt).unwrap();
    let from_vrt = dir.join("vrt");
    convert_with(&dir.join("parts.vrt"), &from_vrt, LoadOptions::default());
    assert!(
        tiles(&from_vrt) == a,
        "the VRT's tiles equal the single file's"
    );
    // Without holes the single file's pyramid is the in-memory atlas.
    write_tiff(&dir.join("full.tif"), (w, h), (0, 0), |_, _| false);
    let (memory, tiled) = in_memory_and_tiled(
        &dir.join("full.tif"),
        &dir.join("full"),
        LoadOptions::default(),
    );
    assert_same_atlas("full", &memory, &tiled);
}

#[test]
fn a_huge_geotiffs_header_is_read_without_its_cells() {
    let dir = scratch("tiles-single-header");
    let src = manifest_dir().join("tests/data/tiles/jacksboro-tile64-deflate-Int16.tif");
    let bytes = std::fs::read(&src).unwrap();
    // GDAL writes the header and its tags first: cut the cells off.
    let cut = dir.join("cut.tif");
    std::fs::write(&cut, &bytes[..4096]).unwrap();
    let header = terrain_engine::sketch::read_header(&cut, &LoadOptions::default())
        .unwrap()
        .expect("a GeoTIFF's header");
    let atlas = Atlas::load(&src, &LoadOptions::default()).unwrap();
    assert_eq!((header.width, header.height), (403, 344));
    assert_eq!((header.dx, header.dy), (atlas.dx, atlas.dy));
    assert_eq!(header.georef, atlas.georef);
    assert!(Atlas::load(&cut, &LoadOptions::default()).is_err());
}

#[test]
fn a_text_grid_above_the_stated_size_is_refused_with_the_command_that_rewrites_it() {
    let dir = scratch("tiles-single-text");
    let src = dir.join("big.asc");
    let file = std::fs::File::create(&src).unwrap();
    // Sparse: the size is what is refused, before a byte is read.
    file.set_len((256 << 20) + 1).unwrap();
    let err = build(&src, &dir.join("pyramid"), &BuildOptions::default())
        .unwrap_err()
        .to_string();
    assert!(!err.contains('\n'), "{err}");
    assert!(
        err.contains("gdal_translate -of GTiff -co TILED=YES"),
        "{err}"
    );
}

#[test]
fn heights_in_another_unit_are_refused_after_level_0_and_again_on_a_second_run() {
    let dir = scratch("tiles-single-unit");
    let src = dir.join("cm.tif");
    write_tiff(&src, (300, 300), (0, 0), |_, _| false);
    let out = dir.join("pyramid");
    // 300 m read as 300 × 10⁴ km: every height lies beyond ±1000 km.
    let load = LoadOptions {
        height_scale: Some(1e5),
        ..LoadOptions::default()
    };
    let opts = BuildOptions {
        load,
        threads: 2,
        ..Default::default()
    };
    for run in 0..2 {
        let err = build(&src, &out, &opts).unwrap_err().to_string();
        assert!(err.contains("beyond ±1000 km"), "run {run}: {err}");
        assert!(!err.contains('\n'), "{err}");
        assert!(!terrain_engine::sketch::tiles::is_pyramid(&out));
    }
}
