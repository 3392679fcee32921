//! How a frame reaches the canvas: through the canvas's WebGPU context (the default), or drawn
//! into a texture of the viewer's own and copied into the canvas's 2D context (`?present=copy`,
//! and every still).
//!
//! Rules: both draw the same passes into targets of the same formats' family (sRGB views, four
//! bytes a texel); a copy in flight is never overtaken (a frame drawn meanwhile is not shown),
//! so the canvas shows whole frames in order. The copy is for browsers whose compositor cannot
//! show a WebGPU canvas — headless Chromium on SwiftShader cannot make the canvas's swap-chain
//! image, and then drops the page's WebGPU connection — and for a still, a picture drawn once.
//! Rejected: the copy for every page, a read-back a frame where the canvas needs none.

use std::cell::Cell;
use std::rc::Rc;
use terrain::readback::Readback;
use terrain::wgpu;
use wasm_bindgen::{Clamped, JsCast, JsError, JsValue};

/// The canvas a frame is shown on.
pub enum Present {
    /// The canvas's WebGPU context.
    Canvas {
        surface: wgpu::Surface<'static>,
        config: wgpu::SurfaceConfiguration,
    },
    /// A texture of the viewer's own, copied into the canvas's 2D context.
    Copy {
        colour: wgpu::Texture,
        context: web_sys::CanvasRenderingContext2d,
        /// A copy is being mapped; the frames drawn meanwhile are not shown.
        in_flight: Rc<Cell<bool>>,
        /// Frames whose pixels reached the canvas.
        shown: Rc<Cell<u64>>,
    },
}

/// The colour texture a frame is drawn into, and what to do once it is recorded.
pub enum Target {
    Surface(wgpu::SurfaceTexture),
    Own(wgpu::Texture),
}

impl Target {
    pub fn texture(&self) -> &wgpu::Texture {
        match self {
            Target::Surface(t) => &t.texture,
            Target::Own(t) => t,
        }
    }
}

/// The 2D context of `canvas`, for [`Present::Copy`].
pub fn context_2d(
    canvas: &web_sys::HtmlCanvasElement,
) -> Result<web_sys::CanvasRenderingContext2d, JsError> {
    canvas
        .get_context("2d")
        .ok()
        .flatten()
        .and_then(|c| c.dyn_into().ok())
        .ok_or_else(|| JsError::new("the canvas: no 2D context for the copied frames"))
}

/// A single-sampled 2D texture of `size`: the viewer's own colour target (copied from) and its
/// depth.
pub fn texture(
    device: &wgpu::Device,
    format: wgpu::TextureFormat,
    (w, h): (u32, u32),
    usage: wgpu::TextureUsages,
) -> wgpu::Texture {
    device.create_texture(&wgpu::TextureDescriptor {
        label: Some("page target"),
        size: wgpu::Extent3d {
            width: w,
            height: h,
            depth_or_array_layers: 1,
        },
        mip_level_count: 1,
        sample_count: 1,
        dimension: wgpu::TextureDimension::D2,
        format,
        usage,
        view_formats: &[],
    })
}

/// The viewer's own colour target for [`Present::Copy`], of `size`.
pub fn own_colour(
    device: &wgpu::Device,
    format: wgpu::TextureFormat,
    size: (u32, u32),
) -> wgpu::Texture {
    let usage = wgpu::TextureUsages::RENDER_ATTACHMENT | wgpu::TextureUsages::COPY_SRC;
    texture(device, format, size, usage)
}

impl Present {
    /// The texture this frame draws into, or None where the canvas has none to give now (a
    /// page in the background, a canvas being resized): the next frame draws.
    pub fn target(&self, device: &wgpu::Device) -> Result<Option<Target>, JsError> {
        match self {
            Present::Canvas { surface, config } => match surface.get_current_texture() {
                wgpu::CurrentSurfaceTexture::Success(t)
                | wgpu::CurrentSurfaceTexture::Suboptimal(t) => Ok(Some(Target::Surface(t))),
                wgpu::CurrentSurfaceTexture::Timeout
                | wgpu::CurrentSurfaceTexture::Occluded
                | wgpu::CurrentSurfaceTexture::Outdated => {
                    surface.configure(device, config);
                    Ok(None)
                }
                other => Err(JsError::new(&format!("the canvas: {other:?}"))),
            },
            Present::Copy { colour, .. } => Ok(Some(Target::Own(colour.clone()))),
        }
    }

    /// After the frame's commands were submitted: the surface's texture presented, or the own
    /// texture's copy (recorded by [`Present::record_copy`]) put on the canvas once mapped.
    pub fn show(&self, queue: &wgpu::Queue, target: Target, copy: Option<Readback>) {
        match (self, target) {
            (Present::Canvas { .. }, Target::Surface(t)) => queue.present(t),
            (
                Present::Copy {
                    context,
                    in_flight,
                    shown,
                    colour,
                },
                Target::Own(_),
            ) => {
                let Some(copy) = copy else { return };
                let (context, in_flight, shown) =
                    (context.clone(), in_flight.clone(), shown.clone());
                let (w, h) = (colour.width(), colour.height());
                in_flight.set(true);
                copy.read_rgba_later(move |texels| {
                    in_flight.set(false);
                    if let Ok(t) = texels
                        && put(&context, &t, w, h).is_ok()
                    {
                        shown.set(shown.get() + 1);
                    }
                });
            }
            _ => {}
        }
    }

    /// The copy of this frame for the canvas, where it is shown by copy and no copy is in
    /// flight.
    pub fn record_copy(
        &self,
        device: &wgpu::Device,
        encoder: &mut wgpu::CommandEncoder,
    ) -> Result<Option<Readback>, JsError> {
        let Present::Copy {
            colour, in_flight, ..
        } = self
        else {
            return Ok(None);
        };
        if in_flight.get() {
            return Ok(None);
        }
        let r = Readback::new(device, colour).map_err(|e| JsError::new(&e.to_string()))?;
        r.record(encoder, colour)
            .map_err(|e| JsError::new(&e.to_string()))?;
        Ok(Some(r))
    }

    /// Frames whose pixels reached the canvas by copy (None when shown through WebGPU).
    pub fn shown(&self) -> Option<u64> {
        match self {
            Present::Canvas { .. } => None,
            Present::Copy { shown, .. } => Some(shown.get()),
        }
    }

    /// The canvas is now `size`.
    pub fn resize(&mut self, device: &wgpu::Device, (w, h): (u32, u32)) {
        match self {
            Present::Canvas { surface, config } => {
                (config.width, config.height) = (w, h);
                surface.configure(device, config);
            }
            Present::Copy { colour, .. } => *colour = own_colour(device, colour.format(), (w, h)),
        }
    }

    /// Whether a copy is being mapped.
    pub fn in_flight(&self) -> bool {
        matches!(self, Present::Copy { in_flight, .. } if in_flight.get())
    }

    /// `"canvas"` or `"copy"`, for the page's figures.
    pub fn name(&self) -> &'static str {
        match self {
            Present::Canvas { .. } => "canvas",
            Present::Copy { .. } => "copy",
        }
    }
}

/// `rgba` (`w` × `h`, rows top first) onto the canvas.
fn put(
    context: &web_sys::CanvasRenderingContext2d,
    rgba: &[u8],
    w: u32,
    h: u32,
) -> Result<(), JsValue> {
    let image = web_sys::ImageData::new_with_u8_clamped_array_and_sh(Clamped(rgba), w, h)?;
    context.put_image_data(&image, 0.0, 0.0)
}
