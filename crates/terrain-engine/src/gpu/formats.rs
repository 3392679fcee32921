//! The formats of a frame's own targets, which the device check (`context`) and the passes that
//! draw into them share. Rule: a pass names its targets' formats from here, never inline.

/// The picture, sRGB.
pub const COLOUR: wgpu::TextureFormat = wgpu::TextureFormat::Rgba8UnormSrgb;
/// Each pixel's depth as four bytes, kept for recovering ground positions (depth textures cannot
/// be copied, nor float targets rendered, on every adapter).
pub const DEPTH_COPY: wgpu::TextureFormat = wgpu::TextureFormat::Rgba8Unorm;
/// The depth buffer, reversed-Z.
pub const DEPTH: wgpu::TextureFormat = wgpu::TextureFormat::Depth32Float;
/// The G-buffer's targets: the f32s of the shader's `Surface` as bits, four to a target. Integer
/// targets keep the bits exactly, so deferred shading sees what forward interpolates; float ones
/// are not renderable on every adapter either (llvmpipe's GL path).
pub const GBUFFER: [wgpu::TextureFormat; 4] = [wgpu::TextureFormat::Rgba32Uint; 4];
