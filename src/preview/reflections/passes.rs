//! The reflection passes on the device: per frame the Fermat solves of every search, their cull
//! and one indirect draw of the reflected triangles that show, over the main pass's mirror
//! pixels ([`Reflections`], `wgsl/preview/reflect.wgsl`), and the reflected triangles made anew
//! where the camera cuts the curved shapes anew.

use super::kernel::{FermatCull, FermatPass, FermatSolve};
use super::{MirrorSurface, Reflector, ReflectorPass};
use crate::error::Result;
use crate::gpu::GpuContext;
use crate::gpu::kernels::Access::{StorageRead, UintTexture};
use crate::gpu::kernels::Binding;
use crate::layout::{GpuDrawArgs, GpuReflector};
use crate::preview::renderer::mesh::{indexed, shared_positions};
use crate::preview::renderer::pipeline::{
    COLOR_FORMAT, DEPTH_FORMAT, RasterPipeline, buffer_entry, color_attachment, depth_attachment,
    render_pipeline, texture_entry,
};
use crate::preview::renderer::shading::{SHADING_GROUP, Shading, ShadingVariant};
use crate::preview::{CurvedShapes, Detail, PreviewOptions, PreviewVertex, shader_source};

const VERTEX: wgpu::ShaderStages = wgpu::ShaderStages::VERTEX;

/// The distinct reflected vertices (`PreviewVertex`).
pub const REFLECTED_VERTICES: Binding = Binding::new(0, "reflected_vertices", StorageRead, VERTEX);
/// Every search's reflection points, search after search (a Fermat solve's output).
pub const REFLECTED_POINTS: Binding = Binding::new(1, "reflected_points", StorageRead, VERTEX);
/// Per search of a batch, its `ReflectorPass`.
pub const REFLECTOR_PASSES: Binding = Binding::new(2, "reflector_passes", StorageRead, VERTEX);
/// The main pass's id target: which mirror each pixel sees, and how far.
pub const REFLECTOR_IDS: Binding = Binding::new(
    3,
    "reflector_ids",
    UintTexture,
    wgpu::ShaderStages::FRAGMENT,
);
/// Per distinct reflected vertex, the index of its Fermat solve.
pub const SOLVE_OF: Binding = Binding::new(4, "solve_of", StorageRead, VERTEX);

/// What a batch of searches draws: group 1 of the reflection pass.
pub const REFLECTION_GROUP: &[Binding] = &[
    REFLECTED_VERTICES,
    REFLECTED_POINTS,
    REFLECTOR_PASSES,
    REFLECTOR_IDS,
    SOLVE_OF,
];

/// The reflection pass: each search's shown reflected triangles over its mirror's pixels
/// (`wgsl/preview/reflect.wgsl`), shaded as the main pass shades (its group 0).
pub const REFLECTION_PASS: RasterPipeline = RasterPipeline {
    name: "preview reflections",
    source: shader_source,
    vertex: "reflected_vertex",
    fragment: Some("reflected_fragment"),
    groups: &[SHADING_GROUP, REFLECTION_GROUP],
};

/// What the reflection passes share with the main pass.
pub(crate) struct ReflectionSetup<'a> {
    pub(crate) module: &'a wgpu::ShaderModule,
    pub(crate) variant: ShadingVariant,
    pub(crate) shading: Shading<'a>,
    pub(crate) color_view: &'a wgpu::TextureView,
    pub(crate) id_view: &'a wgpu::TextureView,
    pub(crate) eye: glam::Vec3,
    pub(crate) far: f64,
    pub(crate) size: wgpu::Extent3d,
}

/// The reflection passes of the curved mirrors: the Fermat solves (a search per surface of
/// each mirror, all in one dispatch per kind of surface), the cull of the reflected triangles
/// for every search in one dispatch, the reflected triangles' pipeline and its own depth buffer
/// (|P − V|); it draws over the main pass's colour target, the shown triangles of all the
/// searches by one indirect draw. (Searches come in batches where their buffers would outgrow a
/// binding: a solve, a cull and a draw per batch.) The reflected triangles can be replaced
/// ([`Reflections::load`]) where the main pass cuts its curved shapes anew.
pub(crate) struct Reflections {
    fermat: FermatPass,
    /// Per search: 1 + its mirror's index (the id the main pass wrote), and its surface.
    searches: Vec<(u32, MirrorSurface)>,
    /// Per mirror: its material.
    materials: Vec<u32>,
    searches_per_dispatch: Option<usize>,
    /// Whether mirrors that can see themselves draw their own triangles reflected.
    self_reflections: bool,
    pipeline: wgpu::RenderPipeline,
    shared_group: wgpu::BindGroup,
    far: f64,
    color_view: wgpu::TextureView,
    depth_view: wgpu::TextureView,
    id_view: wgpu::TextureView,
    geometry: ReflectedGeometry,
}

/// The reflected triangles' buffers and the searches' batches over them.
#[derive(Default)]
struct ReflectedGeometry {
    batches: Vec<SearchBatch>,
    /// Per batch, what its draw reads.
    batch_groups: Vec<wgpu::BindGroup>,
    vertex_count: u32,
    /// Distinct reflected vertices: one Fermat solve each.
    solve_count: u32,
}

impl Reflections {
    /// `None` where the scene has no curved mirror or nothing to reflect.
    pub(crate) fn new(
        context: &GpuContext,
        setup: &ReflectionSetup,
        reflectors: Vec<Reflector>,
        triangles: &[PreviewVertex],
        options: PreviewOptions,
    ) -> Result<Option<Reflections>> {
        if reflectors.is_empty() || triangles.is_empty() {
            return Ok(None);
        }
        let device = &context.device;
        let kinds: Vec<u32> = reflectors
            .iter()
            .flat_map(|r| r.searches.iter().map(MirrorSurface::kind))
            .collect();
        let searches: Vec<(u32, MirrorSurface)> = reflectors
            .iter()
            .enumerate()
            .flat_map(|(k, r)| r.searches.iter().map(move |&s| (k as u32 + 1, s)))
            .collect();
        let pipeline = render_pipeline(
            device,
            setup.module,
            &REFLECTION_PASS,
            &[],
            &[Some(COLOR_FORMAT.into())],
            &setup.variant.constants(),
        );
        let shared_group = device.create_bind_group(&wgpu::BindGroupDescriptor {
            label: Some("preview reflections"),
            layout: &pipeline.get_bind_group_layout(0),
            entries: &setup.shading.entries(),
        });
        let depth = device.create_texture(&wgpu::TextureDescriptor {
            label: Some("preview reflections"),
            size: setup.size,
            mip_level_count: 1,
            sample_count: 1,
            dimension: wgpu::TextureDimension::D2,
            format: DEPTH_FORMAT,
            usage: wgpu::TextureUsages::RENDER_ATTACHMENT,
            view_formats: &[],
        });
        let mut reflections = Reflections {
            fermat: FermatPass::new(
                context,
                options.steps,
                &kinds,
                options.self_reflections.is_some(),
            ),
            searches,
            materials: reflectors.iter().map(|r| r.material).collect(),
            searches_per_dispatch: options.searches_per_dispatch,
            self_reflections: options.self_reflections.is_some(),
            pipeline,
            shared_group,
            far: setup.far,
            color_view: setup.color_view.clone(),
            depth_view: depth.create_view(&Default::default()),
            id_view: setup.id_view.clone(),
            geometry: ReflectedGeometry::default(),
        };
        reflections.load(context, triangles, setup.eye)?;
        Ok(Some(reflections))
    }

    /// Reflects `triangles` (not empty) from now on, the eye at `eye`: their buffers, and the
    /// searches' batches over them.
    pub(crate) fn load(
        &mut self,
        context: &GpuContext,
        triangles: &[PreviewVertex],
        eye: glam::Vec3,
    ) -> Result<()> {
        // The draw is indexed: each distinct reflected vertex (position, normal, material) runs
        // the vertex stage once for each search, however many shown triangles share it; and
        // the distinct vertices at one position share one solve.
        let (distinct, vertex_of) = indexed(triangles);
        let (positions, vertex_solves) = shared_positions(&distinct);
        // The mirror each solved vertex lies on: a teapot's own points search on.
        let mut mirrors = vec![0; positions.len()];
        for (&solve, v) in vertex_solves.iter().zip(&distinct) {
            mirrors[solve as usize] = mirrors[solve as usize].max(v.reflector);
        }
        let fermat_vertices = super::kernel::vertex_buffer(context, &positions, &mirrors)?;
        let solve_buffer =
            context.storage_buffer("vertex solves", bytemuck::cast_slice(&vertex_solves))?;
        let vertices =
            context.storage_buffer("reflected vertices", bytemuck::cast_slice(&distinct))?;
        let table: Vec<[u32; 4]> = vertex_of
            .chunks(3)
            .zip(triangles.chunks(3))
            .map(|(v, t)| [v[0], v[1], v[2], t[0].reflector])
            .collect();
        let table = context.storage_buffer(
            &format!("the {} reflected triangles", table.len()),
            bytemuck::cast_slice(&table),
        )?;
        let triangle_count = triangles.len() as u32 / 3;
        let fitting =
            super::kernel::searches_per_solve(context, positions.len() as u32, triangle_count);
        let per_batch = self
            .searches_per_dispatch
            .map_or(fitting, |n| n.clamp(1, fitting));
        let batches = (0..self.searches.len())
            .step_by(per_batch)
            .map(|first| {
                let range = first..(first + per_batch).min(self.searches.len());
                let uniforms = search_uniforms(
                    &self.searches[range.clone()],
                    eye,
                    positions.len(),
                    self.self_reflections,
                );
                let solve = self.fermat.solve(context, &uniforms, &fermat_vertices)?;
                let cull =
                    self.fermat
                        .cull(context, &solve, (&table, &solve_buffer), triangle_count)?;
                Ok(SearchBatch {
                    solve,
                    cull,
                    searches: range,
                })
            })
            .collect::<Result<Vec<_>>>()?;
        let batch_groups = batches
            .iter()
            .map(|batch| {
                let passes: Vec<ReflectorPass> = self.searches[batch.searches.clone()]
                    .iter()
                    .map(|&(id, _)| ReflectorPass {
                        far: self.far as f32,
                        id,
                        material: self.materials[id as usize - 1],
                        solves: positions.len() as u32,
                    })
                    .collect();
                let passes =
                    context.storage_buffer("reflector passes", bytemuck::cast_slice(&passes))?;
                Ok(context
                    .device
                    .create_bind_group(&wgpu::BindGroupDescriptor {
                        label: Some("reflector batch"),
                        layout: &self.pipeline.get_bind_group_layout(1),
                        entries: &[
                            buffer_entry(REFLECTED_VERTICES, &vertices),
                            buffer_entry(REFLECTED_POINTS, &batch.solve.output),
                            buffer_entry(REFLECTOR_PASSES, &passes),
                            buffer_entry(SOLVE_OF, &solve_buffer),
                            texture_entry(REFLECTOR_IDS, &self.id_view),
                        ],
                    }))
            })
            .collect::<Result<Vec<_>>>()?;
        self.geometry = ReflectedGeometry {
            batches,
            batch_groups,
            vertex_count: triangles.len() as u32,
            solve_count: positions.len() as u32,
        };
        Ok(())
    }

    /// The reflected triangles the last frame drew, summed over the searches (the cull's
    /// counts, read back).
    pub(crate) fn drawn(&self, context: &GpuContext) -> Result<usize> {
        let mut drawn = 0;
        for batch in &self.geometry.batches {
            let args = context.read_buffer::<GpuDrawArgs>(&batch.cull.args)?[0];
            drawn += args.index_count as usize / 3;
        }
        Ok(drawn)
    }

    /// Reflected triangles a frame, summed over the searches: each search's cull considers
    /// them all.
    pub(crate) fn triangles(&self) -> usize {
        self.geometry.vertex_count as usize / 3 * self.searches.len()
    }

    /// Every reflector's solves see the eye at `eye` from the next frame on.
    pub(crate) fn set_eye(&self, context: &GpuContext, eye: glam::Vec3) {
        for batch in &self.geometry.batches {
            let searches = &self.searches[batch.searches.clone()];
            let count = self.geometry.solve_count as usize;
            let reflectors = search_uniforms(searches, eye, count, self.self_reflections);
            context.queue.write_buffer(
                &batch.solve.reflectors,
                0,
                bytemuck::cast_slice(&reflectors),
            );
        }
    }

    /// Records the Fermat solves of every search.
    pub(crate) fn solve(&self, encoder: &mut wgpu::CommandEncoder) {
        for batch in &self.geometry.batches {
            self.fermat.encode(encoder, &batch.solve);
        }
    }

    /// Records the cull of every search's triangles, after their solves.
    pub(crate) fn cull(&self, encoder: &mut wgpu::CommandEncoder) {
        for batch in &self.geometry.batches {
            self.fermat.encode_cull(encoder, &batch.cull);
        }
    }

    /// Records the reflection passes, after the main pass: reflected fragments replace the
    /// colour of the sphere's pixels they land on (the nearest |P − V| last).
    pub(crate) fn draw(&self, encoder: &mut wgpu::CommandEncoder) {
        let mut pass = encoder.begin_render_pass(&wgpu::RenderPassDescriptor {
            label: Some("preview reflections"),
            color_attachments: &[color_attachment(&self.color_view, wgpu::LoadOp::Load)],
            // One depth buffer serves every reflector: a pixel shows one reflector only.
            depth_stencil_attachment: depth_attachment(&self.depth_view, wgpu::StoreOp::Discard),
            timestamp_writes: None,
            occlusion_query_set: None,
            multiview_mask: None,
        });
        pass.set_pipeline(&self.pipeline);
        pass.set_bind_group(0, &self.shared_group, &[]);
        for (group, batch) in self
            .geometry
            .batch_groups
            .iter()
            .zip(&self.geometry.batches)
        {
            pass.set_bind_group(1, group, &[]);
            pass.set_index_buffer(batch.cull.shown.slice(..), wgpu::IndexFormat::Uint32);
            pass.draw_indexed_indirect(&batch.cull.args, 0);
        }
    }
}

/// Searches solved and culled together: their rows of the solve's and the cull's buffers.
struct SearchBatch {
    solve: FermatSolve,
    cull: FermatCull,
    /// The searches (indices into `Reflections::searches`), row after row.
    searches: std::ops::Range<usize>,
}

/// The Fermat kernel's searches: each surface of `searches` as a part of its mirror (1 + the
/// mirror's index, with it), seen from `eye`, solving `count` vertices.
fn search_uniforms(
    searches: &[(u32, MirrorSurface)],
    eye: glam::Vec3,
    count: usize,
    self_reflections: bool,
) -> Vec<GpuReflector> {
    searches
        .iter()
        .map(|&(id, search)| GpuReflector {
            mirror: id,
            sees_itself: (self_reflections && search.sees_itself()) as u32,
            ..search.gpu(eye, count as u32)
        })
        .collect()
}

/// The triangles the mirrors reflect, before `ReflectedSet::of` cuts them: the flat ones and
/// the curved shapes as the main pass cuts them (`curved_triangles`), but where mirrors
/// reflect themselves (`own_detail`), the mirrors' own triangles cut for that detail: a
/// convex mirror shows what it reflects smaller than the eye sees it, so a coarser cut than the
/// main pass's serves, at a fraction of the solves.
pub(crate) fn reflected_triangles(
    flat_triangles: &[PreviewVertex],
    curved_triangles: &[PreviewVertex],
    curved: &CurvedShapes,
    own_detail: Option<Detail>,
) -> Vec<PreviewVertex> {
    let Some(detail) = own_detail else {
        return [flat_triangles, curved_triangles].concat();
    };
    let on_mirror = |t: &&[PreviewVertex]| t[0].reflector != 0;
    let others = curved_triangles.chunks_exact(3).filter(|t| !on_mirror(t));
    let mirrors = curved.triangles(&curved.cuts(&detail));
    let mirrors = mirrors.chunks_exact(3).filter(on_mirror);
    let mut out = flat_triangles.to_vec();
    out.extend(others.chain(mirrors).flatten());
    out
}
