//! The render targets and their read-back pass: RGBA8 colour, Depth32Float depth, and the
//! metadata buffer of paper 001 §3.1 — per pixel the face id (R32Uint, face index + 1, 0 the
//! background) and the surface's (u, v) (Rg32Float). Later passes of issue 21 (GPU trimming,
//! crack filling) read and write these same targets, so they are one struct that any pass can
//! attach to.
//!
//! Read-back copies every target into a mappable buffer whose rows are padded to wgpu's
//! 256-byte `bytes_per_row` alignment, then strips the padding on the CPU.

use crate::RenderError;
use std::sync::mpsc;
use tessd_gpu::ErrorScopes;

/// Colour format: 8-bit RGBA, values as shaded (no sRGB conversion).
pub const COLOR_FORMAT: wgpu::TextureFormat = wgpu::TextureFormat::Rgba8Unorm;
/// Depth format.
pub const DEPTH_FORMAT: wgpu::TextureFormat = wgpu::TextureFormat::Depth32Float;
/// Face-id format.
pub const FACE_ID_FORMAT: wgpu::TextureFormat = wgpu::TextureFormat::R32Uint;
/// (u, v) format.
pub const UV_FORMAT: wgpu::TextureFormat = wgpu::TextureFormat::Rg32Float;

/// The targets of one image size.
pub struct Targets {
    /// Width in pixels.
    pub width: u32,
    /// Height in pixels.
    pub height: u32,
    /// RGBA8 colour.
    pub color: wgpu::Texture,
    /// Depth, 0 at the near plane, 1 at the far one.
    pub depth: wgpu::Texture,
    /// Face id + 1 per pixel, 0 for the background.
    pub face_id: wgpu::Texture,
    /// (u, v) per pixel.
    pub uv: wgpu::Texture,
}

/// The targets' contents on the CPU, rows top to bottom, padding removed.
pub struct RawImages {
    /// RGBA8, 4 bytes per pixel.
    pub color: Vec<u8>,
    /// Depth-buffer values.
    pub depth: Vec<f32>,
    /// Face id + 1.
    pub face_id: Vec<u32>,
    /// (u, v).
    pub uv: Vec<[f32; 2]>,
}

impl Targets {
    /// Creates the four targets (render attachments that can be copied out).
    pub fn new(device: &wgpu::Device, width: u32, height: u32) -> Targets {
        let make = |label, format| {
            device.create_texture(&wgpu::TextureDescriptor {
                label: Some(label),
                size: wgpu::Extent3d {
                    width,
                    height,
                    depth_or_array_layers: 1,
                },
                mip_level_count: 1,
                sample_count: 1,
                dimension: wgpu::TextureDimension::D2,
                format,
                usage: wgpu::TextureUsages::RENDER_ATTACHMENT
                    | wgpu::TextureUsages::COPY_SRC
                    | wgpu::TextureUsages::TEXTURE_BINDING,
                view_formats: &[],
            })
        };
        Targets {
            width,
            height,
            color: make("color", COLOR_FORMAT),
            depth: make("depth", DEPTH_FORMAT),
            face_id: make("face_id", FACE_ID_FORMAT),
            uv: make("uv", UV_FORMAT),
        }
    }

    /// Copies every target back to the CPU (one submission, then one wait).
    ///
    /// # Errors
    /// [`RenderError::Gpu`] when wgpu reports an error or mapping fails.
    pub fn read(
        &self,
        device: &wgpu::Device,
        queue: &wgpu::Queue,
    ) -> Result<RawImages, RenderError> {
        let scopes = ErrorScopes::push(device);
        let mut encoder = device.create_command_encoder(&wgpu::CommandEncoderDescriptor {
            label: Some("read back targets"),
        });
        let parts = [
            (&self.color, 4u32, wgpu::TextureAspect::All),
            (&self.depth, 4, wgpu::TextureAspect::DepthOnly),
            (&self.face_id, 4, wgpu::TextureAspect::All),
            (&self.uv, 8, wgpu::TextureAspect::All),
        ];
        let mut buffers = Vec::with_capacity(parts.len());
        for (texture, texel, aspect) in parts {
            let row = padded_row(self.width, texel);
            let buffer = device.create_buffer(&wgpu::BufferDescriptor {
                label: Some("readback"),
                size: row as u64 * self.height as u64,
                usage: wgpu::BufferUsages::MAP_READ | wgpu::BufferUsages::COPY_DST,
                mapped_at_creation: false,
            });
            encoder.copy_texture_to_buffer(
                wgpu::TexelCopyTextureInfo {
                    texture,
                    mip_level: 0,
                    origin: wgpu::Origin3d::ZERO,
                    aspect,
                },
                wgpu::TexelCopyBufferInfo {
                    buffer: &buffer,
                    layout: wgpu::TexelCopyBufferLayout {
                        offset: 0,
                        bytes_per_row: Some(row),
                        rows_per_image: Some(self.height),
                    },
                },
                wgpu::Extent3d {
                    width: self.width,
                    height: self.height,
                    depth_or_array_layers: 1,
                },
            );
            buffers.push((buffer, row, texel));
        }
        queue.submit([encoder.finish()]);
        let (tx, rx) = mpsc::channel();
        for (i, (buffer, _, _)) in buffers.iter().enumerate() {
            let tx = tx.clone();
            buffer.map_async(wgpu::MapMode::Read, .., move |r| {
                let _ = tx.send((i, r));
            });
        }
        drop(tx);
        device
            .poll(wgpu::PollType::wait_indefinitely())
            .map_err(|e| RenderError::Gpu(tessd_gpu::GpuError::Wgpu(e.to_string())))?;
        scopes.pop_blocking()?;
        for (i, r) in rx.iter() {
            r.map_err(|e| {
                RenderError::Gpu(tessd_gpu::GpuError::Wgpu(format!(
                    "mapping target {i}: {e}"
                )))
            })?;
        }
        let mut tight: Vec<Vec<u8>> = Vec::with_capacity(buffers.len());
        for (buffer, row, texel) in &buffers {
            let view = buffer.get_mapped_range(..).map_err(|e| {
                RenderError::Gpu(tessd_gpu::GpuError::Wgpu(format!("reading back: {e}")))
            })?;
            let width_bytes = (self.width * texel) as usize;
            let mut out = Vec::with_capacity(width_bytes * self.height as usize);
            for y in 0..self.height as usize {
                let at = y * *row as usize;
                out.extend_from_slice(&view[at..at + width_bytes]);
            }
            drop(view);
            buffer.unmap();
            tight.push(out);
        }
        let uv = tight.pop().unwrap_or_default();
        let face_id = tight.pop().unwrap_or_default();
        let depth = tight.pop().unwrap_or_default();
        let color = tight.pop().unwrap_or_default();
        Ok(RawImages {
            color,
            depth: words(&depth).map(f32::from_ne_bytes).collect(),
            face_id: words(&face_id).map(u32::from_ne_bytes).collect(),
            uv: words(&uv)
                .map(f32::from_ne_bytes)
                .collect::<Vec<_>>()
                .chunks_exact(2)
                .map(|p| [p[0], p[1]])
                .collect(),
        })
    }
}

/// The 4-byte words of `bytes` (which need not be aligned).
fn words(bytes: &[u8]) -> impl Iterator<Item = [u8; 4]> + '_ {
    bytes.chunks_exact(4).map(|c| [c[0], c[1], c[2], c[3]])
}

/// Bytes per row of a `width`-texel row of `texel` bytes, rounded up to wgpu's copy alignment.
pub fn padded_row(width: u32, texel: u32) -> u32 {
    let align = wgpu::COPY_BYTES_PER_ROW_ALIGNMENT;
    (width * texel).div_ceil(align) * align
}

#[cfg(test)]
mod tests {
    #[test]
    fn rows_pad_to_256_bytes() {
        assert_eq!(super::padded_row(1, 4), 256);
        assert_eq!(super::padded_row(64, 4), 256);
        assert_eq!(super::padded_row(65, 4), 512);
        assert_eq!(super::padded_row(160, 8), 1280);
        assert_eq!(super::padded_row(161, 8), 1536);
    }
}
