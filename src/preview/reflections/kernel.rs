//! The Fermat search's GPU side: reflection points on curved mirrors (sphere, torus, ellipsoid,
//! cylinder, Bézier patch) found by the `fermat` kernel of the registry (`gpu::kernels`), one
//! scene vertex of one search (a surface of a mirror) per invocation; `fermat::Solver` is its
//! CPU twin (f64), and `tests/fermat.rs` checks that they agree. The reflection passes
//! (`passes`) encode it before their draws: every search in one dispatch per kind of surface,
//! then the `fermat_cull` kernel, which lists the reflected triangles whose reflection shows on
//! each search's surface, for one indirect draw of them all (one dispatch per search costs
//! more in fixed costs on lavapipe than its work: docs/fermat.md).

use glam::Vec3;
use wgpu::util::DeviceExt;

use super::MirrorSurface;
use crate::error::{Error, Result};
use crate::gpu::GpuContext;
use crate::gpu::kernels::{self, FERMAT, FERMAT_CULL, FERMAT_START, slot};
use crate::layout::{GpuDrawArgs, GpuReflection, GpuReflector, REFLECTOR_PATCH};

/// Roger and Holzschuch's step count ("4–5 steps"), the kernel's default.
pub const PAPER_STEPS: u32 = 5;

/// Vertices an invocation group of the kernel takes (its `@workgroup_size`).
const WORKGROUP: u32 = 64;

/// Bytes of an entry of the cull's list: a triangle's three indices.
const SHOWN_BYTES: u64 = 12;

/// The Fermat search's steps at most that the command lines take (`--fermat-steps`,
/// `bench fermat --steps`): the preview's default is 12 and the f64 truth of `bench fermat`
/// runs 60; more only lets searches that do not converge run on, and far more would meet
/// lavapipe's silent cut of an invocation's loops at 65,535 iterations.
pub const MAX_FERMAT_STEPS: u32 = 1000;

/// The fermat kernel's pipelines, one per kind of reflector (`layout::REFLECTOR_*`, the
/// kernel's `REFLECTOR_KIND`): specialised, a sphere's search carries none of a patch's code
/// (on lavapipe the general kernel took a sphere's preview frame from 4 to 12 ms).
pub struct FermatPass {
    pipelines: Vec<(u32, kernels::Pipeline)>,
    /// The patches' eye-free corners B (`fermat_start`), where a patch is among the kinds.
    start: Option<kernels::Pipeline>,
    cull: kernels::Pipeline,
}

/// The searches' inputs and output on the device: every surface of every curved mirror solves
/// the same vertices, all in one dispatch per kind of surface (a dispatch row per search).
pub struct FermatSolve {
    /// One `GpuReflector` per search (its surface, the eye, the vertex count, its mirror); the
    /// eye is rewritten as the camera moves.
    pub reflectors: wgpu::Buffer,
    /// One `GpuReflection` per vertex and search, search after search.
    pub output: wgpu::Buffer,
    /// Per kind of surface present, its pipeline's index in `FermatPass::pipelines` and the
    /// bind group it runs with.
    bind_groups: Vec<(usize, wgpu::BindGroup)>,
    count: u32,
    searches: u32,
}

/// The searches' cull of the reflected triangles (`fermat_cull`): the triangles whose
/// reflection shows on a search's surface, and the arguments of the one indirect draw of them.
pub struct FermatCull {
    /// The index buffer of the draw, with room for every triangle of every search: three
    /// indices, (the search's row) x (distinct vertices) + the vertex, per triangle shown on a
    /// search's surface, the first `index_count` written, triangle by triangle in no fixed
    /// order.
    pub shown: wgpu::Buffer,
    /// One `GpuDrawArgs`: three indices per triangle shown.
    pub args: wgpu::Buffer,
    bind_group: wgpu::BindGroup,
    triangles: u32,
    searches: u32,
}

impl FermatPass {
    /// Builds the kernel for each of `kinds` of reflector, to take at most `steps` steps, a
    /// patch's own points searched again where Roger and Holzschuch's corners find nothing when
    /// `own_points` (mirrors reflecting themselves; without, the kernel carries none of that
    /// code: on lavapipe it cost the teapot's frame 5% unused). Validation errors surface
    /// through the caller's error scope.
    pub fn new(context: &GpuContext, steps: u32, kinds: &[u32], own_points: bool) -> FermatPass {
        assert!(
            (1..=MAX_FERMAT_STEPS).contains(&steps),
            "{steps} Fermat steps: the command lines take 1..={MAX_FERMAT_STEPS}"
        );
        let mut kinds = kinds.to_vec();
        kinds.sort_unstable();
        kinds.dedup();
        let start = kinds
            .contains(&REFLECTOR_PATCH)
            .then(|| kernels::build_pipeline(&context.device, &FERMAT_START, 0));
        let pipelines = kinds
            .into_iter()
            .map(|kind| {
                let overrides = [
                    ("FERMAT_STEPS", steps as f64),
                    ("REFLECTOR_KIND", kind as f64),
                    ("OWN_POINTS_SEARCHED_AGAIN", own_points as u32 as f64),
                ];
                let pipeline = kernels::build_pipeline_with(
                    &context.device,
                    &FERMAT,
                    0,
                    &overrides,
                    kernels::ShaderChecks::default(),
                );
                (kind, pipeline)
            })
            .collect();
        let cull = kernels::build_pipeline(&context.device, &FERMAT_CULL, 0);
        FermatPass {
            pipelines,
            start,
            cull,
        }
    }

    /// The buffers that solve `vertices` (positions, w the mirror each lies on:
    /// `vertex_buffer`) for each of `reflectors` (one search each, all with the vertices'
    /// count); the patches' starts are submitted to the queue here, ahead of any frame.
    pub fn solve(
        &self,
        context: &GpuContext,
        reflectors: &[GpuReflector],
        vertices: &wgpu::Buffer,
    ) -> Result<FermatSolve> {
        let count = reflectors.first().map_or(0, |r| r.count);
        within_one_dispatch(context, "vertices to solve", count)?;
        let searches = context
            .device
            .create_buffer_init(&wgpu::util::BufferInitDescriptor {
                label: Some("reflectors"),
                contents: bytemuck::cast_slice(reflectors),
                usage: wgpu::BufferUsages::STORAGE | wgpu::BufferUsages::COPY_DST,
            });
        let solves = count.max(1) as u64 * reflectors.len() as u64;
        let output = self.storage(
            context,
            "reflection points",
            solves * size_of::<GpuReflection>() as u64,
            wgpu::BufferUsages::empty(),
        )?;
        // A patch's corner B per vertex and search, as `output`: found once, here, as it does
        // not depend on the eye (`fermat_start`); the bind groups keep it. Smaller than
        // `output`, so within a binding wherever `output` is.
        let starts = self.storage(
            context,
            "patch starts",
            solves * size_of::<[f32; 2]>() as u64,
            wgpu::BufferUsages::empty(),
        )?;
        let mut kinds: Vec<u32> = reflectors.iter().map(|r| r.kind).collect();
        kinds.sort_unstable();
        kinds.dedup();
        let bind_groups = kinds
            .into_iter()
            .map(|kind| {
                let pipeline = self
                    .pipelines
                    .iter()
                    .position(|(k, _)| *k == kind)
                    .ok_or_else(|| {
                        Error::Gpu(format!("no fermat pipeline for reflector kind {kind}"))
                    })?;
                let bind_group = self.pipelines[pipeline].1.bind_group(
                    &context.device,
                    &[
                        (slot::REFLECTORS, &searches),
                        (slot::FERMAT_VERTICES, vertices),
                        (slot::REFLECTIONS, &output),
                        (slot::FERMAT_STARTS, &starts),
                    ],
                )?;
                Ok((pipeline, bind_group))
            })
            .collect::<Result<Vec<_>>>()?;
        let has_patch = reflectors.iter().any(|r| r.kind == REFLECTOR_PATCH);
        if let (Some(start), true) = (&self.start, has_patch) {
            let bind_group = start.bind_group(
                &context.device,
                &[
                    (slot::REFLECTORS, &searches),
                    (slot::FERMAT_VERTICES, vertices),
                    (slot::FERMAT_STARTS, &starts),
                ],
            )?;
            let mut encoder = context.device.create_command_encoder(&Default::default());
            {
                let mut pass = encoder.begin_compute_pass(&Default::default());
                pass.set_pipeline(&start.pipeline);
                pass.set_bind_group(kernels::KERNEL_GROUP, &bind_group, &[]);
                pass.dispatch_workgroups(count.div_ceil(WORKGROUP), reflectors.len() as u32, 1);
            }
            context.queue.submit([encoder.finish()]);
        }
        Ok(FermatSolve {
            reflectors: searches,
            output,
            bind_groups,
            count,
            searches: reflectors.len() as u32,
        })
    }

    /// A storage buffer of `bytes` the kernels write (and tests read back), also used as
    /// `usage` says, or the refusal of one larger than a binding may be on this adapter.
    fn storage(
        &self,
        context: &GpuContext,
        what: &str,
        bytes: u64,
        usage: wgpu::BufferUsages,
    ) -> Result<wgpu::Buffer> {
        let limit = context.device.limits().max_storage_buffer_binding_size;
        if bytes > limit {
            return Err(crate::gpu::over_binding_limit(what, bytes, limit));
        }
        Ok(context.device.create_buffer(&wgpu::BufferDescriptor {
            label: Some(what),
            size: bytes,
            usage: wgpu::BufferUsages::STORAGE | wgpu::BufferUsages::COPY_SRC | usage,
            mapped_at_creation: false,
        }))
    }

    /// Records the solve of every search of `solve` into `encoder`: one dispatch per kind of
    /// surface, a row of it per search (a pipeline skips the rows of other kinds).
    pub fn encode(&self, encoder: &mut wgpu::CommandEncoder, solve: &FermatSolve) {
        let mut pass = encoder.begin_compute_pass(&Default::default());
        for (pipeline, bind_group) in &solve.bind_groups {
            pass.set_pipeline(&self.pipelines[*pipeline].1.pipeline);
            pass.set_bind_group(kernels::KERNEL_GROUP, bind_group, &[]);
            pass.dispatch_workgroups(solve.count.div_ceil(WORKGROUP), solve.searches, 1);
        }
    }

    /// The buffers that cull `triangles` (`count` of them: per triangle its vertices, indices
    /// into the distinct reflected vertices whose solves `vertex_solves` gives, and 1 + the
    /// index of the mirror it lies on, as `reflected_triangles` in wgsl/bindings.wgsl) against
    /// each search of `solve`; a search's reflector names the mirror (`GpuReflector::mirror`)
    /// whose own triangles it leaves out.
    pub fn cull(
        &self,
        context: &GpuContext,
        solve: &FermatSolve,
        (triangles, vertex_solves): (&wgpu::Buffer, &wgpu::Buffer),
        count: u32,
    ) -> Result<FermatCull> {
        within_one_dispatch(context, "reflected triangles to cull", count)?;
        let what = format!("the lists of {count} reflected triangles");
        let shown = self.storage(
            context,
            &what,
            count.max(1) as u64 * SHOWN_BYTES * solve.searches as u64,
            wgpu::BufferUsages::INDEX,
        )?;
        let args = context.device.create_buffer(&wgpu::BufferDescriptor {
            label: Some("reflected draw"),
            size: size_of::<GpuDrawArgs>() as u64,
            usage: wgpu::BufferUsages::STORAGE
                | wgpu::BufferUsages::INDIRECT
                | wgpu::BufferUsages::COPY_DST
                | wgpu::BufferUsages::COPY_SRC,
            mapped_at_creation: false,
        });
        let bind_group = self.cull.bind_group(
            &context.device,
            &[
                (slot::REFLECTORS, &solve.reflectors),
                (slot::REFLECTIONS, &solve.output),
                (slot::REFLECTED_TRIANGLES, triangles),
                (slot::SHOWN_INDICES, &shown),
                (slot::DRAW_ARGS, &args),
                (slot::VERTEX_SOLVES, vertex_solves),
            ],
        )?;
        Ok(FermatCull {
            shown,
            args,
            bind_group,
            triangles: count,
            searches: solve.searches,
        })
    }

    /// Records `cull` into `encoder`, after its searches' solve: the draw's arguments are
    /// cleared (the kernel sets its instance count back to 1), then every search's triangles
    /// are listed anew, in one dispatch (a row per search).
    pub fn encode_cull(&self, encoder: &mut wgpu::CommandEncoder, cull: &FermatCull) {
        encoder.clear_buffer(&cull.args, 0, None);
        let mut pass = encoder.begin_compute_pass(&Default::default());
        pass.set_pipeline(&self.cull.pipeline);
        pass.set_bind_group(kernels::KERNEL_GROUP, &cull.bind_group, &[]);
        pass.dispatch_workgroups(cull.triangles.div_ceil(WORKGROUP), cull.searches, 1);
    }
}

/// Refuses `count` items of one dispatch row (`WORKGROUP` an invocation group) beyond the
/// adapter's workgroups per dimension, which would fail the dispatch's validation.
fn within_one_dispatch(context: &GpuContext, what: &str, count: u32) -> Result<()> {
    let groups = context.device.limits().max_compute_workgroups_per_dimension;
    if count.div_ceil(WORKGROUP) > groups {
        return Err(Error::Gpu(format!(
            "{count} {what}: one dispatch takes at most {} on this adapter \
             (max_compute_workgroups_per_dimension = {groups}); use a lower --subdivision",
            groups as u64 * WORKGROUP as u64
        )));
    }
    Ok(())
}

/// How many searches one solve and its cull take: as many as keep their reflection points
/// (`vertices` per search) and their lists of shown triangles (`triangles` per search) within
/// one binding each, and the dispatch's rows within the adapter's limit; at least one (a search
/// too large for a binding alone is refused by `FermatPass::solve` or `FermatPass::cull`).
pub fn searches_per_solve(context: &GpuContext, vertices: u32, triangles: u32) -> usize {
    let limits = context.device.limits();
    let binding = limits.max_storage_buffer_binding_size;
    let points = binding / (vertices.max(1) as u64 * size_of::<GpuReflection>() as u64);
    let lists = binding / (triangles.max(1) as u64 * SHOWN_BYTES);
    let rows = limits.max_compute_workgroups_per_dimension as u64;
    points.min(lists).min(rows).max(1) as usize
}

/// The vertices' positions as the kernel reads them, w the mirror each lies on (`mirrors`: 1 +
/// its index, 0 for none; empty: none lies on one), in a storage buffer.
pub fn vertex_buffer(
    context: &GpuContext,
    vertices: &[Vec3],
    mirrors: &[u32],
) -> Result<wgpu::Buffer> {
    let mirror = |k: usize| mirrors.get(k).copied().unwrap_or(0) as f32;
    let points: Vec<[f32; 4]> = (vertices.iter().enumerate())
        .map(|(k, v)| v.extend(mirror(k)).to_array())
        .collect();
    context.storage_buffer("fermat vertices", bytemuck::cast_slice(&points))
}

/// The reflections of `vertices` seen from `eye` on `surface` (at most `steps` steps) and the
/// triangles of `triangles` (three indices into `vertices` and 1 + the index of the mirror each
/// lies on) that the preview draws on it as a part of mirror `mirror`, sorted: `fermat_cull`'s
/// list, read back (none is culled where `triangles` is empty). With `sees_itself`, the
/// mirror's own triangles are drawn where they stand clear of their points.
pub fn shown_triangles(
    context: &GpuContext,
    surface: MirrorSurface,
    (eye, mirror, sees_itself): (Vec3, u32, bool),
    vertices: &[Vec3],
    triangles: &[[u32; 4]],
    steps: u32,
) -> Result<(Vec<GpuReflection>, Vec<u32>)> {
    solve_and_cull(
        context,
        surface,
        (eye, mirror, sees_itself),
        (vertices, &[]),
        triangles,
        steps,
    )
}

/// The reflection point of each of `vertices`, points of the mirror `surface` is part of,
/// seen from `eye` on `surface`, found in at most `steps` steps (a teapot's own points
/// search again where Roger and Holzschuch's corners find none: `fermat::solve_on_patch`).
pub fn own_reflections(
    context: &GpuContext,
    surface: MirrorSurface,
    eye: Vec3,
    vertices: &[Vec3],
    steps: u32,
) -> Result<Vec<GpuReflection>> {
    points_of(context, surface, eye, vertices, true, steps)
}

/// The reflection points of `vertices` (the searched mirror's own where `own`), none culled.
fn points_of(
    context: &GpuContext,
    surface: MirrorSurface,
    eye: Vec3,
    vertices: &[Vec3],
    own: bool,
    steps: u32,
) -> Result<Vec<GpuReflection>> {
    // The reflector is mirror 1 where its own points are solved, none otherwise.
    let mirror = own as u32;
    let mirrors = vec![mirror; if own { vertices.len() } else { 0 }];
    let (reflections, _) = solve_and_cull(
        context,
        surface,
        (eye, mirror, own),
        (vertices, &mirrors),
        &[],
        steps,
    )?;
    Ok(reflections)
}

/// [`shown_triangles`], the vertices each tagged with the mirror it lies on (`vertex_buffer`).
fn solve_and_cull(
    context: &GpuContext,
    surface: MirrorSurface,
    (eye, mirror, sees_itself): (Vec3, u32, bool),
    (vertices, mirrors): (&[Vec3], &[u32]),
    triangles: &[[u32; 4]],
    steps: u32,
) -> Result<(Vec<GpuReflection>, Vec<u32>)> {
    if vertices.is_empty() {
        return Ok((Vec::new(), Vec::new()));
    }
    let device = &context.device;
    let scope = device.push_error_scope(wgpu::ErrorFilter::Validation);
    let reflector = GpuReflector {
        mirror,
        sees_itself: sees_itself as u32,
        ..surface.gpu(eye, vertices.len() as u32)
    };
    let pass = FermatPass::new(context, steps, &[reflector.kind], !mirrors.is_empty());
    let input = vertex_buffer(context, vertices, mirrors)?;
    let solve = pass.solve(context, &[reflector], &input)?;
    let mut encoder = device.create_command_encoder(&Default::default());
    pass.encode(&mut encoder, &solve);
    let cull = if triangles.is_empty() {
        None
    } else {
        let table =
            context.storage_buffer("reflected triangles", bytemuck::cast_slice(triangles))?;
        // Each vertex its own solve.
        let solves: Vec<u32> = (0..vertices.len() as u32).collect();
        let solves = context.storage_buffer("vertex solves", bytemuck::cast_slice(&solves))?;
        let cull = pass.cull(context, &solve, (&table, &solves), triangles.len() as u32)?;
        pass.encode_cull(&mut encoder, &cull);
        Some(cull)
    };
    if let Some(e) = pollster::block_on(scope.pop()) {
        return Err(Error::Gpu(format!(
            "the fermat kernels: {}",
            crate::gpu::wgpu_error_text(&e)
        )));
    }
    context.wait(context.queue.submit([encoder.finish()]))?;
    let reflections = context.read_buffer(&solve.output)?;
    let Some(cull) = cull else {
        return Ok((reflections, Vec::new()));
    };
    let args = context.read_buffer::<GpuDrawArgs>(&cull.args)?[0];
    let listed: Vec<[u32; 3]> = context.read_buffer(&cull.shown)?;
    // One search, row 0: each entry is a triangle's three vertices, which name it.
    let named: std::collections::HashMap<[u32; 3], u32> = (triangles.iter().zip(0..))
        .map(|(t, k)| ([t[0], t[1], t[2]], k))
        .collect();
    let mut shown = (listed[..(args.index_count / 3) as usize].iter())
        .map(|corners| {
            named.get(corners).copied().ok_or_else(|| {
                Error::Gpu(format!(
                    "the cull listed {corners:?}, no triangle's vertices"
                ))
            })
        })
        .collect::<Result<Vec<u32>>>()?;
    shown.sort_unstable();
    Ok((reflections, shown))
}

/// The reflection point of each of `vertices` seen from `eye` on `surface`, found in at most
/// `steps` steps.
pub fn reflections(
    context: &GpuContext,
    surface: MirrorSurface,
    eye: Vec3,
    vertices: &[Vec3],
    steps: u32,
) -> Result<Vec<GpuReflection>> {
    points_of(context, surface, eye, vertices, false, steps)
}
