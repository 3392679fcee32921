//! `compare`'s figures: error against frame time (with the Pareto fronts), the warped mode's
//! density-ratio histogram, the error along the camera path, and the image strip.

use super::report::{PSNR_CAP_DB, Row, TARGET_PSNR_DB, TARGET_SSE_PX};
use crate::output::write_image;
use crate::plot::chart::{Axis, Figure, Panel, Scale, Series, Style};
use crate::plot::{Rgb, draw_on_rgba, font};
use plotters::style::text_anchor::{HPos, Pos, VPos};
use std::path::Path;
use terrain_engine::Result;
use terrain_engine::scene::Mode;
use terrain_engine::stage::quality::Bin;

/// A mode's colour in every figure, its row's (rows name their mode as `Mode::name` writes it).
pub fn colour(mode: &str) -> Rgb {
    let [r, g, b] = Mode::parse(mode).map_or([120, 120, 120], |m| m.row().colour);
    Rgb(r, g, b)
}

/// A line per mode through each of its rows' `point` (rows without one left out), in order of x.
fn lines_per_mode(rows: &[Row], point: &dyn Fn(&Row) -> Option<(f64, f64)>) -> Vec<Series> {
    modes(rows)
        .into_iter()
        .map(|m| {
            let mut points: Vec<(f64, f64)> = rows
                .iter()
                .filter(|r| r.mode == m)
                .filter_map(point)
                .collect();
            points.sort_by(|a, b| a.0.total_cmp(&b.0));
            Series {
                name: display(m).to_string(),
                colour: colour(m),
                style: Style::LineMarkers,
                points,
            }
        })
        .collect()
}

/// A mode's name in figure legends, as the papers write it ([`Mode::display`]).
pub fn display(mode: &str) -> &str {
    match Mode::parse(mode) {
        Some(m) => m.display(),
        None => mode,
    }
}

fn modes(rows: &[Row]) -> Vec<&str> {
    let mut out: Vec<&str> = Vec::new();
    for r in rows {
        if !out.contains(&r.mode.as_str()) {
            out.push(&r.mode);
        }
    }
    out
}

/// `error_vs_time`: PSNR and mean screen-space error against frame time, a line per mode
/// through its settings in order of frame time, each front as rings on a dashed line.
pub fn error_vs_time(rows: &[Row], title: &str) -> Figure {
    error_against(
        rows,
        title,
        Axis::new("frame time (ms, CPU stage + GPU passes)", Scale::Log10),
        &|r| r.frame_ms,
        true,
    )
}

/// `error_vs_triangles`: the same errors against triangles drawn, without fronts (they are
/// fronts of frame time).
pub fn error_vs_triangles(rows: &[Row], title: &str) -> Figure {
    error_against(
        rows,
        title,
        Axis::new("triangles drawn", Scale::Log10),
        &|r| r.triangles as f64,
        false,
    )
}

/// PSNR and mean screen-space error against `cost`, a line per mode in order of cost, and with
/// `fronts` the Pareto front of all modes.
fn error_against(
    rows: &[Row],
    title: &str,
    x: Axis,
    cost: &dyn Fn(&Row) -> f64,
    fronts: bool,
) -> Figure {
    let panel = |name: &str,
                 y: Axis,
                 value: &dyn Fn(&Row) -> f64,
                 on_front: &dyn Fn(&Row) -> bool,
                 guide: (f64, String)| {
        let mut series = lines_per_mode(rows, &|r| Some((cost(r), value(r))));
        if fronts {
            let mut front: Vec<(f64, f64)> = rows
                .iter()
                .filter(|r| on_front(r))
                .map(|r| (cost(r), value(r)))
                .collect();
            front.sort_by(|a, b| a.0.total_cmp(&b.0));
            series.push(Series {
                name: "Pareto front".into(),
                colour: Rgb::BLACK,
                style: Style::Front,
                points: front,
            });
        }
        Panel {
            title: name.to_string(),
            x: x.clone(),
            y,
            series,
            guides: vec![guide],
        }
    };
    Figure {
        title: title.to_string(),
        width: 1100,
        height: 520,
        panels: vec![
            panel(
                "Image error against the reference",
                Axis::new("PSNR (dB, higher is better)", Scale::Linear),
                &|r| r.psnr_db.min(PSNR_CAP_DB),
                &|r| r.pareto_psnr,
                (TARGET_PSNR_DB, format!("{TARGET_PSNR_DB} dB")),
            ),
            panel(
                "Screen-space geometric error",
                Axis::new(
                    "mean screen-space error (px, lower is better)",
                    Scale::Log10,
                ),
                &|r| r.sse_mean_px.max(1e-3),
                &|r| r.pareto_sse,
                (TARGET_SSE_PX, format!("{TARGET_SSE_PX} px")),
            ),
        ],
    }
}

/// `lod_change_vs_psnr`: each setting's LOD change per frame (along the camera path) against its
/// PSNR, a line per mode in order of PSNR: what each mode's quality costs in
/// swimming or popping. Brute force, which has no level of detail, scores 0 and is left off the
/// log axis.
pub fn lod_change_vs_psnr(rows: &[Row], title: &str) -> Figure {
    let series = lines_per_mode(rows, &|r| {
        Some((r.psnr_db.min(PSNR_CAP_DB), r.lod_change_levels?))
    });
    Figure {
        title: title.to_string(),
        width: 700,
        height: 520,
        panels: vec![Panel {
            title: "Change per frame from the LOD update against image error".into(),
            x: Axis::new("PSNR (dB, higher is better)", Scale::Linear),
            y: Axis::new(
                "LOD change per frame (8-bit levels, lower is better)",
                Scale::Log10,
            ),
            series,
            guides: Vec::new(),
        }],
    }
}

/// The density-ratio histogram of the warped mode's geometry image (the paper's Fig. 6 as bars):
/// share of visible cells per half-octave bin of obtained / demanded density.
pub fn ratio_histogram(bins: &[Bin], visible: usize, title: &str) -> Figure {
    let total = visible.max(1) as f64;
    let points: Vec<(f64, f64)> = bins
        .iter()
        .map(|b| {
            let centre = match (b.lo > 0.0, b.hi.is_finite()) {
                (true, true) => 0.5 * (b.lo.log2() + b.hi.log2()),
                (false, _) => b.hi.log2() - 0.25,
                (_, false) => b.lo.log2() + 0.25,
            };
            (centre, 100.0 * b.cells as f64 / total)
        })
        .collect();
    Figure {
        title: title.to_string(),
        width: 700,
        height: 440,
        panels: vec![Panel {
            title: "obtained / demanded density (end bars: beyond 1/8 and 8)".into(),
            x: Axis::new("log2 of the density ratio", Scale::Linear),
            y: Axis::new("visible cells (%)", Scale::Linear),
            series: vec![Series {
                name: "warped geometry image".into(),
                colour: colour(Mode::Warped.name()),
                style: Style::Bars(0.5),
                points,
            }],
            guides: vec![],
        }],
    }
}

/// One frame of a mode along the path.
#[derive(Clone, Copy, Debug)]
pub struct PathPoint {
    pub t_s: f64,
    pub psnr_db: f64,
    /// The LOD update's change (none at the first frame).
    pub change: Option<f64>,
}

/// A mode's name and its frames along the path.
pub type ModeSeries = (String, Vec<PathPoint>);

/// Per-frame PSNR and the change from the level-of-detail update along the path, a line per mode.
pub fn path_error(series: &[ModeSeries], title: &str) -> Figure {
    let line = |f: &dyn Fn(&PathPoint) -> Option<f64>| -> Vec<Series> {
        series
            .iter()
            .map(|(m, pts)| Series {
                name: display(m).to_string(),
                colour: colour(m),
                style: Style::LineMarkers,
                points: pts.iter().filter_map(|p| Some((p.t_s, f(p)?))).collect(),
            })
            .collect()
    };
    Figure {
        title: title.to_string(),
        width: 1100,
        height: 460,
        panels: vec![
            Panel {
                title: "Image error per frame".into(),
                x: Axis::new("time along the path (s)", Scale::Linear),
                y: Axis::new("PSNR (dB)", Scale::Linear),
                series: line(&|p| Some(p.psnr_db)),
                guides: vec![],
            },
            Panel {
                title: "Change from the LOD update alone (popping, swimming)".into(),
                x: Axis::new("time along the path (s)", Scale::Linear),
                y: Axis::new("mean change per pixel (8-bit levels)", Scale::Linear),
                series: line(&|p| p.change),
                guides: vec![],
            },
        ],
    }
}

/// The image strip: the reference and each mode (name, setting, pixels) on top, each mode's
/// difference from the reference (×4; white is equal) below, labelled.
pub fn strip(
    path: &Path,
    width: u32,
    height: u32,
    reference: &[u8],
    modes: &[(String, String, Vec<u8>)],
) -> Result<()> {
    let label_h = 36;
    let columns = 1 + modes.len() as u32;
    let (w, h) = (columns * width, 2 * (height + label_h));
    let mut px = vec![255u8; 4 * w as usize * h as usize];
    let mut blit = |x0: u32, y0: u32, rgba: &[u8]| {
        let row = (width * 4) as usize;
        for y in 0..height {
            let src = (y * width * 4) as usize;
            let dst = (((y0 + y) * w + x0) * 4) as usize;
            px[dst..dst + row].copy_from_slice(&rgba[src..src + row]);
        }
    };
    // Each label: its column, its top, its two lines (name, then setting).
    let mut labels: Vec<(u32, u32, [&str; 2])> = vec![
        (0, 0, ["reference", "ray march"]),
        (
            0,
            height + label_h,
            ["below: difference", "|mode − ref| × 4"],
        ),
    ];
    blit(0, label_h, reference);
    for (k, (name, setting, rgba)) in modes.iter().enumerate() {
        let column = k as u32 + 1;
        blit(column * width, label_h, rgba);
        let diff: Vec<u8> = rgba
            .chunks_exact(4)
            .zip(reference.chunks_exact(4))
            .flat_map(|(a, b)| {
                let d = |i: usize| (4 * (a[i] as i32 - b[i] as i32).abs()).min(255) as u8;
                [255 - d(0), 255 - d(1), 255 - d(2), 255]
            })
            .collect();
        blit(column * width, height + 2 * label_h, &diff);
        labels.push((column, 0, [name, setting]));
    }
    let centred = Pos::new(HPos::Center, VPos::Top);
    draw_on_rgba(&mut px, w, h, |area| {
        for (column, y, lines) in labels {
            let x = (column * width + width / 2) as i32;
            let y = y as i32;
            area.draw_text(lines[0], &font(13.0, Rgb::BLACK).pos(centred), (x, y + 6))?;
            area.draw_text(lines[1], &font(11.0, Rgb::GREY).pos(centred), (x, y + 23))?;
        }
        Ok(())
    })?;
    write_image(path, w, h, &px)
}
