//! Mipmaps for base-colour textures, made on the GPU: a chain of render passes, each drawing
//! one level from the level above through a bilinear sampler (wgpu has no mipmap generation of
//! its own, and WebGL2's `generateMipmap` is not reachable through it). Render passes, not a
//! compute shader, because WebGL2 has none; both back ends run the same code. The levels are
//! made once, at the first frame after the image is copied in (`Renderer::texture_target`).

/// The blit pipeline and its sampler, made the first time a texture needs levels.
pub(crate) struct MipBlit {
    pipeline: wgpu::RenderPipeline,
    sampler: wgpu::Sampler,
}

/// Levels of a full chain for a `width` × `height` image (down to 1 × 1).
pub(crate) fn full_chain(width: u32, height: u32) -> u32 {
    32 - width.max(height).max(1).leading_zeros()
}

/// Whether a glTF minification filter code samples mipmaps: the four `*_MIPMAP_*` codes, and
/// none given (the client's choice; glTF viewers mipmap).
pub(crate) fn wants_mipmaps(min_filter: Option<u32>) -> bool {
    !matches!(min_filter, Some(9728) | Some(9729))
}

impl MipBlit {
    pub(crate) fn new(device: &wgpu::Device, format: wgpu::TextureFormat) -> MipBlit {
        let sm = device.create_shader_module(wgpu::ShaderModuleDescriptor {
            label: Some("mip"),
            source: wgpu::ShaderSource::Wgsl(include_str!("shaders/mip.wgsl").into()),
        });
        let pipeline = device.create_render_pipeline(&wgpu::RenderPipelineDescriptor {
            label: Some("mip"),
            layout: None,
            vertex: wgpu::VertexState { module: &sm, entry_point: Some("vs_main"), compilation_options: Default::default(), buffers: &[] },
            primitive: Default::default(),
            depth_stencil: None,
            multisample: Default::default(),
            fragment: Some(wgpu::FragmentState {
                module: &sm,
                entry_point: Some("fs_main"),
                compilation_options: Default::default(),
                targets: &[Some(format.into())],
            }),
            multiview_mask: None,
            cache: None,
        });
        let sampler = device.create_sampler(&wgpu::SamplerDescriptor {
            label: Some("mip"),
            mag_filter: wgpu::FilterMode::Linear,
            min_filter: wgpu::FilterMode::Linear,
            ..Default::default()
        });
        MipBlit { pipeline, sampler }
    }

    /// Records the passes that fill levels 1.. of `tex` from level 0.
    pub(crate) fn encode(&self, device: &wgpu::Device, encoder: &mut wgpu::CommandEncoder, tex: &wgpu::Texture) {
        let layout = self.pipeline.get_bind_group_layout(0);
        let level = |i: u32| tex.create_view(&wgpu::TextureViewDescriptor { base_mip_level: i, mip_level_count: Some(1), ..Default::default() });
        for i in 1..tex.mip_level_count() {
            let src = level(i - 1);
            let dst = level(i);
            let bg = device.create_bind_group(&wgpu::BindGroupDescriptor {
                label: Some("mip"),
                layout: &layout,
                entries: &[
                    wgpu::BindGroupEntry { binding: 0, resource: wgpu::BindingResource::TextureView(&src) },
                    wgpu::BindGroupEntry { binding: 1, resource: wgpu::BindingResource::Sampler(&self.sampler) },
                ],
            });
            let mut pass = encoder.begin_render_pass(&wgpu::RenderPassDescriptor {
                label: Some("mip"),
                color_attachments: &[Some(wgpu::RenderPassColorAttachment {
                    view: &dst,
                    depth_slice: None,
                    resolve_target: None,
                    ops: wgpu::Operations { load: wgpu::LoadOp::Clear(wgpu::Color::TRANSPARENT), store: wgpu::StoreOp::Store },
                })],
                depth_stencil_attachment: None,
                timestamp_writes: None,
                occlusion_query_set: None,
                multiview_mask: None,
            });
            pass.set_pipeline(&self.pipeline);
            pass.set_bind_group(0, &bg, &[]);
            pass.draw(0..3, 0..1);
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn chains_and_filters() {
        assert_eq!(full_chain(1024, 1024), 11);
        assert_eq!(full_chain(1, 1), 1);
        assert_eq!(full_chain(300, 17), 9);
        assert!(wants_mipmaps(Some(9987)) && wants_mipmaps(Some(9984)) && wants_mipmaps(None));
        assert!(!wants_mipmaps(Some(9729)) && !wants_mipmaps(Some(9728)));
    }
}
