//! PSNR, SSIM and FLIP mean of a test image against a reference image, as `terrain compare`
//! computes them (docs/metrics.md): for setting its figures beside another tool's.
//!
//! cargo run --release --example image_metrics -- REFERENCE.png TEST.png

use anyhow::{Context, Result, bail};
use terrain_cli::eval::metrics;

/// An 8-bit RGB or RGBA PNG as RGBA.
fn rgba(path: &str) -> Result<(u32, u32, Vec<u8>)> {
    let file = std::fs::File::open(path).with_context(|| path.to_string())?;
    let mut decoder = png::Decoder::new(std::io::BufReader::new(file));
    decoder.set_transformations(png::Transformations::EXPAND | png::Transformations::STRIP_16);
    let mut reader = decoder
        .read_info()
        .with_context(|| format!("{path}: not a PNG"))?;
    let mut buf = vec![0; reader.output_buffer_size().context("PNG too large")?];
    let info = reader.next_frame(&mut buf)?;
    let pixels = &buf[..info.buffer_size()];
    let rgba = match info.color_type {
        png::ColorType::Rgba => pixels.to_vec(),
        png::ColorType::Rgb => pixels
            .chunks_exact(3)
            .flat_map(|p| [p[0], p[1], p[2], 255])
            .collect(),
        other => bail!("{path}: {other:?}; RGB or RGBA expected"),
    };
    Ok((info.width, info.height, rgba))
}

fn main() -> Result<()> {
    let args: Vec<String> = std::env::args().skip(1).collect();
    let [reference, test] = args.as_slice() else {
        bail!("usage: image_metrics REFERENCE.png TEST.png");
    };
    let (w, h, a) = rgba(reference)?;
    let (tw, th, b) = rgba(test)?;
    if (w, h) != (tw, th) {
        bail!("{test}: {tw}×{th}, the reference is {w}×{h}");
    }
    let ssim = metrics::ssim(&a, &b, w).context("SSIM needs images of at least 11×11 pixels")?;
    let flip = metrics::flip_mean(&a, &b, w).context("FLIP could not be computed")?;
    println!(
        "psnr_db {:.4}  ssim {ssim:.5}  flip_mean {flip:.5}",
        metrics::psnr(&a, &b)
    );
    Ok(())
}
