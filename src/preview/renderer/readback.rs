//! The preview's image read back from the device, as the ray tracer's [`Image`].

use crate::error::Result;
use crate::gpu::GpuContext;
use crate::render::Image;

/// The colour target's pixels, rows padded to wgpu's 256-byte copy alignment on the way.
pub(crate) fn read_back(
    context: &GpuContext,
    color: &wgpu::Texture,
    width: u32,
    height: u32,
) -> Result<Image> {
    let row = (width * 16).div_ceil(wgpu::COPY_BYTES_PER_ROW_ALIGNMENT)
        * wgpu::COPY_BYTES_PER_ROW_ALIGNMENT;
    let buffer = context.device.create_buffer(&wgpu::BufferDescriptor {
        label: Some("preview pixels"),
        size: row as u64 * height as u64,
        usage: wgpu::BufferUsages::COPY_DST | wgpu::BufferUsages::COPY_SRC,
        mapped_at_creation: false,
    });
    let mut encoder = context.device.create_command_encoder(&Default::default());
    encoder.copy_texture_to_buffer(
        color.as_image_copy(),
        wgpu::TexelCopyBufferInfo {
            buffer: &buffer,
            layout: wgpu::TexelCopyBufferLayout {
                offset: 0,
                bytes_per_row: Some(row),
                rows_per_image: Some(height),
            },
        },
        color.size(),
    );
    context.wait(context.queue.submit([encoder.finish()]))?;
    let bytes: Vec<u8> = context.read_buffer(&buffer)?;
    let pixels = bytes
        .chunks(row as usize)
        .flat_map(|r| {
            let floats: Vec<f32> = bytemuck::pod_collect_to_vec(&r[..width as usize * 16]);
            floats
                .chunks(4)
                .map(|p| glam::Vec3::new(p[0], p[1], p[2]))
                .collect::<Vec<_>>()
        })
        .collect();
    Ok(Image {
        width,
        height,
        pixels,
    })
}
