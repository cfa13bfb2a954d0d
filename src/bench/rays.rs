//! The ray benchmark: the same rays traced by each backend, closest hit and any hit.
//!
//! Two ray sets over one mesh, both deterministic so another ray tracer can trace the very same
//! rays and compare the checksum (hit count, sum of hit distances):
//! - coherent: a pinhole camera (position, look_at, up, vertical field of view, resolution),
//!   one ray per pixel per frame through a jittered point of the pixel;
//! - incoherent: origins uniform in the mesh's bounding box scaled by 0.9 about its centre,
//!   directions uniform on the sphere, as many rays as the coherent set.

use std::path::{Path, PathBuf};
use std::time::{Duration, Instant};

use glam::Vec3;
use rayon::prelude::*;
use serde::Serialize;

use super::Spread;
use crate::accel::cwbvh::{self, CwGeometry};
use crate::accel::intersect::RayQuery;
pub use crate::accel::ray::{Query, RaySet};
use crate::accel::traverse::{closest_hit, occluded};
use crate::accel::wide::{PACKET, WideBvh};
use crate::error::{Error, Result};
use crate::gpu::GpuContext;
use crate::gpu::kernels::ShaderChecks;
use crate::gpu::trace::GpuTracer;
use crate::layout::{FEATURES_ALL, GpuCwNode, GpuPrimitive, GpuRay, NONE, PRIM_TRIANGLE, T_FAR};
use crate::math::rng::Rng;
use crate::named::named_enum;
use crate::pack::{FlatScene, flatten};
use crate::scene::Scene;

/// A pinhole camera as other ray tracers take it.
#[derive(Clone, Copy, Debug, PartialEq, Serialize)]
pub struct Pinhole {
    /// Eye position (scene units).
    pub position: [f32; 3],
    /// The point at the image centre.
    pub look_at: [f32; 3],
    /// World up direction for the view.
    pub up: [f32; 3],
    /// Vertical field of view (degrees).
    pub vertical_fov_deg: f32,
    /// Image width in pixels.
    pub width: u32,
    /// Image height in pixels.
    pub height: u32,
}

impl Pinhole {
    /// The camera of the benchmark figures: the Stanford dragon's head, 1024x1024.
    pub const DRAGON: Pinhole = Pinhole {
        position: [0.035_549_864, 0.152_570_43, 0.133_492_49],
        look_at: [-0.005_878_899, 0.124_951_25, -0.004_603_401],
        up: [0.0, 1.0, 0.0],
        vertical_fov_deg: 40.0,
        width: 1024,
        height: 1024,
    };
}

/// What to trace.
#[derive(Clone, Debug, Serialize)]
pub struct RaysConfig {
    /// Mesh file (OBJ or PLY, optionally .gz).
    pub mesh: PathBuf,
    /// The camera of the coherent rays.
    pub camera: Pinhole,
    /// Coherent frames: `width * height * frames` rays per set.
    pub frames: u32,
    /// Timed runs after one warm-up.
    pub runs: u32,
    /// Seed of the pixel jitter and of the incoherent rays.
    pub seed: u32,
    /// The ray sets traced, in this order.
    pub sets: Vec<RaySetName>,
    /// The queries asked of each set, in this order.
    pub queries: Vec<Query>,
    /// The acceleration structures traversed, side by side.
    pub bvhs: Vec<Bvh>,
    /// wgpu's run-time checks the GPU kernels are built with, side by side.
    pub shader_checks: Vec<ShaderChecks>,
}

impl RaysConfig {
    /// The checks each GPU measurement is made with.
    fn gpu_checks(&self) -> Vec<Option<ShaderChecks>> {
        match self.shader_checks.is_empty() {
            true => vec![Some(ShaderChecks::default())],
            false => self.shader_checks.iter().copied().map(Some).collect(),
        }
    }
}

named_enum! {
    /// One of the two ray sets (module docs).
    #[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize)]
    #[serde(rename_all = "lowercase")]
    pub enum RaySetName {
        /// A pinhole camera's rays, one jittered ray per pixel and frame.
        Coherent = "coherent",
        /// Origins in the mesh's bounding box, directions uniform on the sphere.
        Incoherent = "incoherent",
    }
}

named_enum! {
    /// The acceleration structure rays traverse: the renderer's BVH2, the compressed wide BVH
    /// made from it (`accel::cwbvh`), or the CPU's uncompressed 8-wide BVH made from that
    /// (`accel::wide`, CPU only).
    #[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize)]
    #[serde(rename_all = "lowercase")]
    pub enum Bvh {
        /// The renderer's binary BVH.
        Bvh2 = "bvh2",
        /// The compressed wide BVH: eight children per node.
        Cwbvh = "cwbvh",
        /// The CWBVH's tree with f32 child boxes, tested eight at a time (the CPU only).
        Wide = "wide",
        /// The wide BVH traced in packets of sixteen rays (`accel::wide::packet`; the CPU
        /// only): 4x4 pixels of a frame for the camera's rays, sixteen consecutive rays
        /// otherwise.
        Packets = "packets",
        /// The wide BVH traced by streams of rays, eight of them at once a node each in turn
        /// (`accel::wide::stream`; the CPU only).
        Stream = "stream",
    }
}

impl Bvh {
    /// Its name in the reports' tables.
    pub fn label(self) -> &'static str {
        match self {
            Bvh::Bvh2 => "BVH2",
            Bvh::Cwbvh => "CWBVH",
            Bvh::Wide => "wide (CPU)",
            Bvh::Packets => "wide, packets of 16 (CPU)",
            Bvh::Stream => "wide, streams of 8 in flight (CPU)",
        }
    }
}

/// One ray per pixel per frame through the pixel at a jittered point (random dimensions 0-1 of
/// `Rng::new(seed, pixel, frame)`).
pub fn coherent_rays(camera: &Pinhole, frames: u32, seed: u32) -> RaySet {
    let position = Vec3::from(camera.position);
    let forward = (Vec3::from(camera.look_at) - position).normalize();
    let right = forward.cross(Vec3::from(camera.up)).normalize();
    let up = right.cross(forward);
    let half_height = (0.5 * camera.vertical_fov_deg).to_radians().tan();
    let half_width = half_height * camera.width as f32 / camera.height as f32;
    let (w, h) = (camera.width, camera.height);
    let mut set = RaySet {
        image_width: w,
        ..RaySet::default()
    };
    for frame in 0..frames {
        for y in 0..h {
            for x in 0..w {
                let [jx, jy] = Rng::new(seed, y * w + x, frame).next_2d();
                let sx = (2.0 * (x as f32 + jx) / w as f32 - 1.0) * half_width;
                let sy = (1.0 - 2.0 * (y as f32 + jy) / h as f32) * half_height;
                set.origins.push(position);
                set.directions
                    .push((forward + sx * right + sy * up).normalize());
            }
        }
    }
    set
}

/// `count` rays with origins uniform in `[lo, hi]` scaled by 0.9 about its centre and
/// directions uniform on the sphere.
pub fn incoherent_rays(lo: Vec3, hi: Vec3, count: usize, seed: u32) -> RaySet {
    let centre = 0.5 * (lo + hi);
    let half = 0.45 * (hi - lo);
    let mut set = RaySet::default();
    for i in 0..count {
        let mut rng = Rng::new(seed ^ 0x1c0_4e27, i as u32, 0);
        let [a, b] = rng.next_2d();
        let [c, _] = rng.next_2d();
        let [u, v] = rng.next_2d();
        set.origins
            .push(centre + half * Vec3::new(2.0 * a - 1.0, 2.0 * b - 1.0, 2.0 * c - 1.0));
        let z = 1.0 - 2.0 * u;
        let r = (1.0 - z * z).max(0.0).sqrt();
        let phi = std::f32::consts::TAU * v;
        set.directions
            .push(Vec3::new(r * phi.cos(), r * phi.sin(), z));
    }
    set
}

/// Columns of a packet's block of camera rays.
const BLOCK_COLUMNS: usize = 4;

/// Rows of a packet's block of camera rays: as many as fill a packet.
const BLOCK_ROWS: usize = PACKET / BLOCK_COLUMNS;

/// The rays of `rays` in the order packets take them, [`PACKET`] at a time: blocks of
/// [`BLOCK_COLUMNS`] x [`BLOCK_ROWS`] pixels (the frames' rows one after another; the last
/// blocks of a row or column cut short where the width or the rows are not a multiple), or
/// the set's order when its rays are no image's.
pub fn packet_order(rays: &RaySet) -> Vec<u32> {
    let width = rays.image_width as usize;
    if width == 0 {
        return (0..rays.len() as u32).collect();
    }
    let rows = rays.len() / width;
    let mut order = Vec::with_capacity(rays.len());
    for block_y in (0..rows).step_by(BLOCK_ROWS) {
        for block_x in (0..width).step_by(BLOCK_COLUMNS) {
            for y in block_y..(block_y + BLOCK_ROWS).min(rows) {
                for x in block_x..(block_x + BLOCK_COLUMNS).min(width) {
                    order.push((y * width + x) as u32);
                }
            }
        }
    }
    order
}

/// What the rays found: the checksum another tracer can compare.
#[derive(Clone, Copy, Debug, Default, PartialEq, Serialize)]
pub struct Checksum {
    /// Rays that hit something.
    pub hits: u64,
    /// Sum of the closest-hit distances (0 for any-hit queries).
    pub sum_t: f64,
}

impl Checksum {
    /// The checksum of per-ray results: a distance below `T_FAR` is a hit.
    pub fn of(distances: &[f32]) -> Checksum {
        let hits = distances.iter().filter(|&&t| t < T_FAR);
        Checksum {
            hits: hits.clone().count() as u64,
            sum_t: hits.map(|&t| t as f64).sum(),
        }
    }
}

/// Per ray: the closest-hit distance (`T_FAR` on a miss), or 0 / `T_FAR` for occluded / free;
/// through `bvh`.
pub fn trace_cpu(scene: &FlatScene, bvh: Bvh, rays: &RaySet, query: Query) -> Result<Vec<f32>> {
    match bvh {
        Bvh::Packets => return trace_packets(scene.wide().map_err(Error::Gpu)?, rays, query),
        Bvh::Stream => return trace_stream(scene.wide().map_err(Error::Gpu)?, rays, query),
        _ => {}
    }
    let cw = match bvh {
        Bvh::Cwbvh => Some(scene.cwbvh().map_err(Error::Gpu)?),
        _ => None,
    };
    let wide = match bvh {
        Bvh::Wide => Some(scene.wide().map_err(Error::Gpu)?),
        _ => None,
    };
    let distance = |ray: &RayQuery| -> f32 {
        let closest = match (cw, wide) {
            (Some(cw), _) => cwbvh::closest_hit(cw, ray, T_FAR),
            (_, Some(wide)) => wide.closest_hit::<FEATURES_ALL>(ray, NONE, T_FAR),
            _ => closest_hit::<FEATURES_ALL>(scene.primitives(), ray, NONE, T_FAR),
        };
        closest.map_or(T_FAR, |(_, hit)| hit.t)
    };
    let blocked = |ray: &RayQuery| -> bool {
        match (cw, wide) {
            (Some(cw), _) => cwbvh::occluded(cw, ray, T_FAR),
            (_, Some(wide)) => wide.occluded::<FEATURES_ALL>(ray, NONE, NONE, T_FAR),
            _ => occluded::<FEATURES_ALL>(scene.primitives(), ray, NONE, NONE, T_FAR),
        }
    };
    Ok((0..rays.len())
        .into_par_iter()
        .with_min_len(1024)
        .map(|i| {
            let ray = RayQuery::new(rays.origins[i], rays.directions[i]);
            match query {
                Query::ClosestHit => distance(&ray),
                Query::AnyHit if blocked(&ray) => 0.0,
                Query::AnyHit => T_FAR,
            }
        })
        .collect())
}

/// [`trace_cpu`] through the wide BVH in packets of [`PACKET`] rays, taken in
/// [`packet_order`].
fn trace_packets(wide: &WideBvh, rays: &RaySet, query: Query) -> Result<Vec<f32>> {
    let order = packet_order(rays);
    let traced: Vec<[f32; PACKET]> = order
        .par_chunks(PACKET)
        .with_min_len(128)
        .map(|packet| {
            // On the stack, as Embree's benchmark keeps its packets: no allocation per packet.
            let mut queries = [RayQuery::default(); PACKET];
            for (query, &i) in queries.iter_mut().zip(packet) {
                *query = RayQuery::new(rays.origins[i as usize], rays.directions[i as usize]);
            }
            let queries = &queries[..packet.len()];
            let mut distances = [T_FAR; PACKET];
            match query {
                Query::ClosestHit => {
                    let mut hits = [None; PACKET];
                    let hits = &mut hits[..packet.len()];
                    wide.closest_hits::<FEATURES_ALL>(queries, T_FAR, hits);
                    for (d, hit) in distances.iter_mut().zip(hits.iter()) {
                        *d = hit.map_or(T_FAR, |(_, hit)| hit.t);
                    }
                }
                Query::AnyHit => {
                    let mut blocked = [false; PACKET];
                    let blocked = &mut blocked[..packet.len()];
                    wide.occluded_packet::<FEATURES_ALL>(queries, T_FAR, blocked);
                    for (d, &b) in distances.iter_mut().zip(blocked.iter()) {
                        *d = if b { 0.0 } else { T_FAR };
                    }
                }
            }
            distances
        })
        .collect();
    let mut distances = vec![T_FAR; rays.len()];
    for (packet, traced) in order.chunks(PACKET).zip(traced) {
        for (&i, d) in packet.iter().zip(traced) {
            distances[i as usize] = d;
        }
    }
    Ok(distances)
}

/// [`trace_cpu`] through the wide BVH in streams of the rays' order, 1024 rays a stream (the
/// one-ray queries' share of work a thread takes at once).
fn trace_stream(wide: &WideBvh, rays: &RaySet, query: Query) -> Result<Vec<f32>> {
    let mut distances = vec![T_FAR; rays.len()];
    distances
        .par_chunks_mut(1024)
        .enumerate()
        .for_each(|(chunk, distances)| {
            let first = chunk * 1024;
            let queries: Vec<RayQuery> = (first..first + distances.len())
                .map(|i| RayQuery::new(rays.origins[i], rays.directions[i]))
                .collect();
            match query {
                Query::ClosestHit => {
                    let mut hits = vec![None; queries.len()];
                    wide.closest_hit_stream::<FEATURES_ALL>(&queries, T_FAR, &mut hits);
                    for (d, hit) in distances.iter_mut().zip(&hits) {
                        *d = hit.map_or(T_FAR, |(_, hit)| hit.t);
                    }
                }
                Query::AnyHit => {
                    let mut blocked = vec![false; queries.len()];
                    wide.occluded_stream::<FEATURES_ALL>(&queries, T_FAR, &mut blocked);
                    for (d, &b) in distances.iter_mut().zip(&blocked) {
                        *d = if b { 0.0 } else { T_FAR };
                    }
                }
            }
        });
    Ok(distances)
}

/// What every CPU query pays before traversing, as Embree's benchmark measures it: each ray
/// read, its `RayQuery` built (the slab test's reciprocals, the watertight test's shear), and a
/// result written, over the same threads as `trace_cpu`, with no traversal.
pub fn set_up_cpu(rays: &RaySet) -> Vec<f32> {
    (0..rays.len())
        .into_par_iter()
        .with_min_len(1024)
        .map(|i| {
            let ray = RayQuery::new(rays.origins[i], rays.directions[i]);
            std::hint::black_box(&ray);
            T_FAR
        })
        .collect()
}

/// The ray set-up alone on the CPU, for one ray set ([`set_up_cpu`]).
#[derive(Clone, Debug, Serialize)]
pub struct SetUpResult {
    /// "coherent" or "incoherent".
    pub set: &'static str,
    /// Millions of rays set up per second over the timed runs.
    pub mrays_per_s: Spread,
}

/// The figures of one ray set, query and backend.
#[derive(Clone, Debug, Serialize)]
pub struct RaysResult {
    /// "coherent" or "incoherent".
    pub set: &'static str,
    /// Closest hit or any hit.
    pub query: Query,
    /// The backend and its threads or adapter.
    pub backend: String,
    /// The acceleration structure traversed.
    pub bvh: Bvh,
    /// Rays in the set.
    pub rays: usize,
    /// Millions of rays per second over the timed runs.
    pub mrays_per_s: Spread,
    /// What the rays found.
    pub checksum: Checksum,
}

/// The whole benchmark's report.
#[derive(Clone, Debug, Serialize)]
pub struct RaysReport {
    /// What was traced.
    pub config: RaysConfig,
    /// Triangles of the mesh.
    pub triangles: usize,
    /// The BVH2 build (ms).
    pub bvh_build_ms: f64,
    /// The CWBVH's conversion from the BVH2, after it.
    pub cwbvh_build_ms: f64,
    /// Nodes of the BVH2.
    pub bvh2_nodes: usize,
    /// Nodes of the CWBVH.
    pub cwbvh_nodes: usize,
    /// What a CWBVH closest-hit query reads, per ray set.
    pub cwbvh_reads: Vec<Reads>,
    /// One entry per ray set, backend, BVH and query.
    pub results: Vec<RaysResult>,
    /// The CPU's ray set-up alone, per ray set (when the CPU is measured).
    pub set_up: Vec<SetUpResult>,
}

/// Mean bytes one closest-hit ray reads through the CWBVH: its nodes (80 bytes each) and
/// primitives (48) as the CPU twin counts them (the GPU kernel visits the same), the ray (32)
/// and its result (4). Times rays/s, the memory traffic a kernel asks of the caches and DRAM.
#[derive(Clone, Debug, Serialize)]
pub struct Reads {
    /// "coherent" or "incoherent".
    pub set: &'static str,
    /// Mean CWBVH nodes visited per ray.
    pub nodes_per_ray: f64,
    /// Mean primitives tested per ray, planes included.
    pub prims_per_ray: f64,
    /// Mean bytes read per ray: nodes, primitives, the ray and its result.
    pub bytes_per_ray: f64,
}

impl Reads {
    fn of(set: &'static str, cw: &CwGeometry, rays: &RaySet) -> Reads {
        let (nodes, prims) = (0..rays.len())
            .into_par_iter()
            .map(|i| {
                let ray = RayQuery::new(rays.origins[i], rays.directions[i]);
                let (_, counts) = cwbvh::closest_hit_counted(cw, &ray, T_FAR);
                (counts.nodes as u64, counts.prims as u64)
            })
            .reduce(|| (0, 0), |a, b| (a.0 + b.0, a.1 + b.1));
        let n = rays.len().max(1) as f64;
        let (nodes_per_ray, prims_per_ray) = (nodes as f64 / n, prims as f64 / n);
        Reads {
            set,
            nodes_per_ray,
            prims_per_ray,
            bytes_per_ray: size_of::<GpuCwNode>() as f64 * nodes_per_ray
                + size_of::<GpuPrimitive>() as f64 * prims_per_ray
                + (size_of::<GpuRay>() + 4) as f64,
        }
    }
}

/// A scene holding just the mesh, so the renderer's own loading and BVH build are measured.
pub fn mesh_scene(mesh: &Path) -> Result<FlatScene> {
    let absolute = std::path::absolute(mesh).map_err(|e| Error::io(mesh, e))?;
    let text = format!(
        "[render]\nwidth = 1\nheight = 1\n[camera]\nposition = [0.0, 0.0, 1.0]\n\
         look_at = [0.0, 0.0, 0.0]\nfilm = [24.0, 24.0]\n[[materials]]\nname = \"m\"\n\
         model = \"lambert\"\n[[shapes]]\ntype = \"mesh\"\nfile = {}\nmaterial = \"m\"\n",
        toml::Value::String(absolute.to_string_lossy().into_owned())
    );
    let scene = Scene::from_str(Path::new("bench.toml"), &text, &[])?;
    Ok(flatten(&scene))
}

/// Bounds of the scene's primitives (its BVH root).
pub fn bounds(scene: &FlatScene) -> (Vec3, Vec3) {
    scene
        .nodes
        .first()
        .map_or((Vec3::ZERO, Vec3::ZERO), |root| {
            (Vec3::from(root.min), Vec3::from(root.max))
        })
}

/// The files [`write_rays`] writes: what `run` traces, for another ray tracer to trace
/// (`tools/embree/`), little-endian throughout.
pub const WRITTEN_FILES: [&str; 5] = [
    "rays.txt",
    "vertices.f32",
    "indices.u32",
    "coherent.f32",
    "incoherent.f32",
];

/// Writes the mesh and both ray sets of `config` into `dir`, each file atomically: the mesh's
/// distinct vertices (x, y, z as f32, exactly as chambre loaded them) and its triangles (three
/// u32 vertex indices each, in the scene's order), each ray set as origin and direction (six
/// f32 a ray, in the set's order: the camera's rays frame by frame, row by row), and
/// `rays.txt`, `key value` lines of the counts, the camera's image size and frames, and the
/// distance rays reach (`t_far`). Returns a one-line summary.
pub fn write_rays(config: &RaysConfig, dir: &Path) -> Result<String> {
    let scene = mesh_scene(&config.mesh)?;
    let (vertices, indices) = indexed_triangles(&scene.prims).map_err(|message| Error::Output {
        path: dir.to_path_buf(),
        message,
    })?;
    let coherent = coherent_rays(&config.camera, config.frames, config.seed);
    let (lo, hi) = bounds(&scene);
    let incoherent = incoherent_rays(lo, hi, coherent.len(), config.seed);
    let cam = &config.camera;
    let header = format!(
        "triangles {}\nvertices {}\ncoherent_rays {}\nwidth {}\nheight {}\nframes {}\n\
         incoherent_rays {}\nt_far {:e}\n",
        indices.len() / 3,
        vertices.len() / 3,
        coherent.len(),
        cam.width,
        cam.height,
        config.frames,
        incoherent.len(),
        T_FAR
    );
    std::fs::create_dir_all(dir).map_err(|e| Error::io(dir, e))?;
    let files: [(&str, Vec<u8>); 5] = [
        (WRITTEN_FILES[0], header.into_bytes()),
        (WRITTEN_FILES[1], le_bytes(&vertices)),
        (WRITTEN_FILES[2], le_bytes(&indices)),
        (WRITTEN_FILES[3], ray_bytes(&coherent)),
        (WRITTEN_FILES[4], ray_bytes(&incoherent)),
    ];
    for (name, bytes) in &files {
        let path = dir.join(name);
        crate::output::replace_atomically(&path, bytes)
            .map_err(|message| Error::Output { path, message })?;
    }
    Ok(format!(
        "wrote {} ({} triangles, {} vertices; {} coherent and {} incoherent rays) to {}\n",
        WRITTEN_FILES.join(", "),
        indices.len() / 3,
        vertices.len() / 3,
        coherent.len(),
        incoherent.len(),
        dir.display()
    ))
}

/// The triangles of `prims` as an indexed mesh: each distinct vertex (by its bits) once, in
/// the order first met, and three indices a triangle. Fails on any other primitive.
fn indexed_triangles(prims: &[GpuPrimitive]) -> std::result::Result<(Vec<f32>, Vec<u32>), String> {
    let mut index_of = std::collections::HashMap::new();
    let (mut vertices, mut indices) = (Vec::new(), Vec::with_capacity(3 * prims.len()));
    for (i, prim) in prims.iter().enumerate() {
        if prim.kind != PRIM_TRIANGLE {
            return Err(format!(
                "primitive {i} is of kind {}, not a triangle: only a mesh's triangles can be \
                 written for another ray tracer",
                prim.kind
            ));
        }
        for p in [prim.p0, prim.p1, prim.p2] {
            let next = (vertices.len() / 3) as u32;
            let index = *index_of.entry(p.map(f32::to_bits)).or_insert_with(|| {
                vertices.extend_from_slice(&p);
                next
            });
            indices.push(index);
        }
    }
    Ok((vertices, indices))
}

/// Little-endian bytes of 32-bit values.
fn le_bytes<T: Copy + bytemuck::NoUninit>(values: &[T]) -> Vec<u8> {
    let mut bytes = Vec::with_capacity(4 * values.len());
    for v in values {
        let word: u32 = bytemuck::cast(*v);
        bytes.extend_from_slice(&word.to_le_bytes());
    }
    bytes
}

/// Origin then direction of each ray, as little-endian f32s.
fn ray_bytes(rays: &RaySet) -> Vec<u8> {
    let floats: Vec<f32> = rays
        .origins
        .iter()
        .zip(&rays.directions)
        .flat_map(|(o, d)| o.to_array().into_iter().chain(d.to_array()))
        .collect();
    le_bytes(&floats)
}

named_enum! {
    /// Which path traces the rays.
    #[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize)]
    #[serde(rename_all = "lowercase")]
    pub enum Backend {
        /// The CPU reference path (rayon threads).
        Cpu = "cpu",
        /// The GPU kernels (wgpu).
        Gpu = "gpu",
    }
}

/// Mrays/s of `runs` timed runs after a warm-up of at least `WARM_UP`, each run's time given
/// by `trace`.
fn measure(runs: u32, rays: usize, mut trace: impl FnMut() -> Result<Duration>) -> Result<Spread> {
    let warm_up = Instant::now();
    trace()?;
    while warm_up.elapsed() < WARM_UP {
        trace()?;
    }
    let mut mrays = Vec::new();
    for _ in 0..runs.max(1) {
        mrays.push(rays as f64 / trace()?.as_secs_f64() / 1e6);
    }
    Ok(Spread::of(&mrays))
}

/// An idle GPU runs at a fraction of its clock: an H100 timed after one 7 ms warm-up run gave
/// 226 Mrays/s in its first timed run and 1226 in its last.
const WARM_UP: Duration = Duration::from_millis(300);

/// Traces `rays` with `query` on the CPU path, `runs` times after a warm-up.
fn measure_cpu(
    scene: &FlatScene,
    bvh: Bvh,
    rays: &RaySet,
    query: Query,
    runs: u32,
) -> Result<(Spread, Checksum)> {
    let checksum = Checksum::of(&trace_cpu(scene, bvh, rays, query)?);
    let spread = measure(runs, rays.len(), || {
        let start = Instant::now();
        trace_cpu(scene, bvh, rays, query)?;
        Ok(start.elapsed())
    })?;
    Ok((spread, checksum))
}

/// The same on the GPU: the time of each run is the device's, from submission to completion.
fn measure_gpu(
    tracer: &GpuTracer,
    rays: &RaySet,
    query: Query,
    runs: u32,
) -> Result<(Spread, Checksum)> {
    let spread = measure(runs, rays.len(), || tracer.trace(query))?;
    Ok((spread, Checksum::of(&tracer.distances()?)))
}

/// Traces both ray sets with both queries on each of `backends` (`gpu` is the context of
/// [`Backend::Gpu`]).
pub fn run(
    config: &RaysConfig,
    backends: &[Backend],
    gpu: Option<&GpuContext>,
) -> Result<RaysReport> {
    let scene = mesh_scene(&config.mesh)?;
    let start = Instant::now();
    let cw = scene.cwbvh().map_err(Error::Gpu)?;
    let cwbvh_build_ms = start.elapsed().as_secs_f64() * 1e3;
    let coherent = coherent_rays(&config.camera, config.frames, config.seed);
    let (lo, hi) = bounds(&scene);
    let incoherent = incoherent_rays(lo, hi, coherent.len(), config.seed);
    let gpu_checks = config.gpu_checks();
    let mut results = Vec::new();
    let mut cwbvh_reads = Vec::new();
    let mut set_up = Vec::new();
    for &name in &config.sets {
        let (set, rays) = match name {
            RaySetName::Coherent => (name.name(), &coherent),
            RaySetName::Incoherent => (name.name(), &incoherent),
        };
        if config.bvhs.contains(&Bvh::Cwbvh) {
            cwbvh_reads.push(Reads::of(set, cw, rays));
        }
        if backends.contains(&Backend::Cpu) {
            let mrays_per_s = measure(config.runs, rays.len(), || {
                let start = Instant::now();
                set_up_cpu(rays);
                Ok(start.elapsed())
            })?;
            set_up.push(SetUpResult { set, mrays_per_s });
        }
        for &backend in backends {
            for &bvh in &config.bvhs {
                if matches!(bvh, Bvh::Wide | Bvh::Packets | Bvh::Stream) && backend == Backend::Gpu
                {
                    continue;
                }
                let cwbvh = (bvh == Bvh::Cwbvh).then_some(cw);
                let checks: &[Option<ShaderChecks>] = match backend {
                    Backend::Cpu => &[None],
                    Backend::Gpu => &gpu_checks,
                };
                for &checks in checks {
                    let (name, tracer) = match (backend, checks) {
                        (Backend::Gpu, Some(checks)) => {
                            let context =
                                gpu.expect("the GPU backend is only asked for with a context");
                            let tracer = GpuTracer::with_checks(
                                context.clone(),
                                &scene,
                                cwbvh,
                                rays,
                                checks,
                            )?;
                            let label = match checks == ShaderChecks::default() {
                                true => String::new(),
                                false => format!(", checks: {}", checks.name()),
                            };
                            (
                                format!("gpu ({}{label})", tracer.adapter_name()),
                                Some(tracer),
                            )
                        }
                        _ => (
                            format!("cpu ({} threads)", rayon::current_num_threads()),
                            None,
                        ),
                    };
                    for &query in &config.queries {
                        let (mrays_per_s, checksum) = match &tracer {
                            None => measure_cpu(&scene, bvh, rays, query, config.runs)?,
                            Some(tracer) => measure_gpu(tracer, rays, query, config.runs)?,
                        };
                        results.push(RaysResult {
                            set,
                            query,
                            backend: name.clone(),
                            bvh,
                            rays: rays.len(),
                            mrays_per_s,
                            checksum,
                        });
                    }
                }
            }
        }
    }
    Ok(RaysReport {
        config: config.clone(),
        triangles: scene.triangle_count,
        bvh_build_ms: scene.build_time.as_secs_f64() * 1e3,
        cwbvh_build_ms,
        cwbvh_nodes: cw.nodes.len(),
        bvh2_nodes: scene.nodes.len(),
        cwbvh_reads,
        results,
        set_up,
    })
}

impl RaysReport {
    /// The report as a Markdown table.
    pub fn to_markdown(&self) -> String {
        let c = &self.config;
        let cam = &c.camera;
        let mut out = format!(
            "rays: {} ({} triangles, BVH2 of {} nodes built in {:.0} ms, CWBVH of {} nodes \
             converted from it in {:.0} ms); camera {:?} -> {:?}, up {:?}, \
             vertical fov {} deg, {}x{}, {} frames ({} rays per set), seed {}; median of {} \
             runs after a warm-up\n\n",
            c.mesh.display(),
            self.triangles,
            self.bvh2_nodes,
            self.bvh_build_ms,
            self.cwbvh_nodes,
            self.cwbvh_build_ms,
            cam.position,
            cam.look_at,
            cam.up,
            cam.vertical_fov_deg,
            cam.width,
            cam.height,
            c.frames,
            cam.width as u64 * cam.height as u64 * c.frames as u64,
            c.seed,
            c.runs
        );
        for r in &self.cwbvh_reads {
            out += &format!(
                "CWBVH closest hit, {} rays: {:.1} nodes and {:.1} primitives per ray, {:.0} bytes \
                 read per ray (GB/s below: bytes per ray times rays per second)\n",
                r.set, r.nodes_per_ray, r.prims_per_ray, r.bytes_per_ray
            );
        }
        out += "\n| rays | query | backend | BVH | Mrays/s median | min | max | GB/s read | hits | sum of t |\n";
        out += "|---|---|---|---|---|---|---|---|---|---|\n";
        for r in &self.results {
            let query = r.query.name();
            let bvh = r.bvh.label();
            let reads = self
                .cwbvh_reads
                .iter()
                .find(|x| x.set == r.set)
                .filter(|_| r.bvh == Bvh::Cwbvh && r.query == Query::ClosestHit);
            let gb_per_s = reads.map_or("-".into(), |x| {
                format!("{:.0}", x.bytes_per_ray * r.mrays_per_s.median / 1e3)
            });
            out += &format!(
                "| {} | {query} | {} | {bvh} | {:.2} | {:.2} | {:.2} | {gb_per_s} | {} | {:.6e} |\n",
                r.set,
                r.backend,
                r.mrays_per_s.median,
                r.mrays_per_s.min,
                r.mrays_per_s.max,
                r.checksum.hits,
                r.checksum.sum_t
            );
        }
        for s in &self.set_up {
            // The share of the fastest CPU closest-hit query's time that is set-up.
            let fastest = self
                .results
                .iter()
                .filter(|r| r.set == s.set && r.query == Query::ClosestHit)
                .filter(|r| r.backend.starts_with("cpu"))
                .map(|r| r.mrays_per_s.median)
                .fold(0.0, f64::max);
            out += &format!(
                "\nRay set-up alone on the CPU, {} rays (each read, its `RayQuery` built, a \
                 result written; no traversal): {:.0} Mrays/s (min {:.0}, max {:.0}), {:.1}% of \
                 the time of the fastest CPU closest-hit query above\n",
                s.set,
                s.mrays_per_s.median,
                s.mrays_per_s.min,
                s.mrays_per_s.max,
                100.0 * fastest / s.mrays_per_s.median
            );
        }
        out
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn reports_and_flags_spell_bvhs_and_backends_alike() {
        use crate::named::Named;
        for v in Bvh::VALUES {
            assert_eq!(
                serde_json::to_string(&v.value).unwrap(),
                format!("\"{}\"", v.name)
            );
        }
        for v in Backend::VALUES {
            assert_eq!(
                serde_json::to_string(&v.value).unwrap(),
                format!("\"{}\"", v.name)
            );
        }
    }

    #[test]
    fn coherent_rays_pass_through_their_pixels() {
        let camera = Pinhole {
            position: [0.0, 0.0, 0.0],
            look_at: [0.0, 0.0, -1.0],
            up: [0.0, 1.0, 0.0],
            vertical_fov_deg: 90.0,
            width: 4,
            height: 2,
        };
        let set = coherent_rays(&camera, 2, 1);
        assert_eq!(set.len(), 16);
        for (i, d) in set.directions.iter().enumerate() {
            let (x, y) = ((i % 4) as f32, ((i / 4) % 2) as f32);
            // On the plane z = -1 the image spans [-2, 2] x [-1, 1] (aspect 2, tan 45 = 1).
            let p = *d / -d.z;
            assert!((d.length() - 1.0).abs() < 1e-6);
            assert!(p.x >= -2.0 + x && p.x <= -2.0 + x + 1.0, "{i}: {p}");
            assert!(p.y <= 1.0 - y && p.y >= -y, "{i}: {p}");
        }
        assert_ne!(
            set.directions[0], set.directions[8],
            "frames jitter differently"
        );
    }

    #[test]
    fn incoherent_rays_start_inside_the_shrunk_box_and_cover_the_sphere() {
        let set = incoherent_rays(Vec3::splat(-1.0), Vec3::new(1.0, 3.0, 1.0), 20_000, 3);
        let mut octants = [0usize; 8];
        for (o, d) in set.origins.iter().zip(&set.directions) {
            assert!(o.x.abs() <= 0.9 && o.z.abs() <= 0.9 && (o.y - 1.0).abs() <= 1.8);
            assert!((d.length() - 1.0).abs() < 1e-5);
            octants[(d.x > 0.0) as usize + 2 * (d.y > 0.0) as usize + 4 * (d.z > 0.0) as usize] +=
                1;
        }
        // Uniform directions: each octant holds 1/8 of them (2,500 +- 5 sigma = 220).
        assert!(
            octants.iter().all(|&n| n.abs_diff(2500) < 220),
            "{octants:?}"
        );
    }

    /// Little-endian words of a written file.
    fn words(path: &Path) -> Vec<u32> {
        std::fs::read(path)
            .unwrap()
            .chunks_exact(4)
            .map(|w| u32::from_le_bytes(w.try_into().unwrap()))
            .collect()
    }

    #[test]
    fn written_rays_and_triangles_are_the_ones_traced() {
        let dir = std::env::temp_dir().join(format!("chambre-write-rays-{}", std::process::id()));
        let camera = Pinhole {
            width: 6,
            height: 5,
            ..Pinhole::DRAGON
        };
        let config = RaysConfig {
            mesh: PathBuf::from("scenes/meshes/bunny-npm-lowres.obj"),
            camera,
            frames: 2,
            runs: 1,
            seed: 4,
            sets: vec![RaySetName::Coherent, RaySetName::Incoherent],
            queries: vec![Query::ClosestHit, Query::AnyHit],
            bvhs: vec![Bvh::Packets],
            shader_checks: Vec::new(),
        };
        write_rays(&config, &dir).unwrap();
        let scene = mesh_scene(&config.mesh).unwrap();
        let vertices: Vec<f32> = words(&dir.join("vertices.f32"))
            .into_iter()
            .map(f32::from_bits)
            .collect();
        let indices = words(&dir.join("indices.u32"));
        assert_eq!(indices.len(), 3 * scene.prims.len());
        // Shared vertices are written once, and every triangle's corners come back bit for bit.
        assert!(vertices.len() < 3 * indices.len());
        for (prim, corners) in scene.prims.iter().zip(indices.chunks(3)) {
            for (p, &i) in [prim.p0, prim.p1, prim.p2].iter().zip(corners) {
                assert_eq!(&vertices[3 * i as usize..3 * i as usize + 3], p);
            }
        }
        let coherent = coherent_rays(&camera, 2, 4);
        let (lo, hi) = bounds(&scene);
        let incoherent = incoherent_rays(lo, hi, coherent.len(), 4);
        for (name, set) in [("coherent.f32", &coherent), ("incoherent.f32", &incoherent)] {
            let floats: Vec<f32> = words(&dir.join(name))
                .into_iter()
                .map(f32::from_bits)
                .collect();
            assert_eq!(floats.len(), 6 * set.len(), "{name}");
            for (i, ray) in floats.chunks(6).enumerate() {
                assert_eq!(ray[..3], set.origins[i].to_array(), "{name}: ray {i}");
                assert_eq!(ray[3..], set.directions[i].to_array(), "{name}: ray {i}");
            }
        }
        let header = std::fs::read_to_string(dir.join("rays.txt")).unwrap();
        for line in [
            format!("triangles {}", scene.prims.len()),
            format!("vertices {}", vertices.len() / 3),
            "coherent_rays 60".to_string(),
            "width 6".to_string(),
            "height 5".to_string(),
            "frames 2".to_string(),
            "incoherent_rays 60".to_string(),
            "t_far 1e30".to_string(),
        ] {
            assert!(header.lines().any(|l| l == line), "{line} in\n{header}");
        }
        std::fs::remove_dir_all(&dir).unwrap();
    }

    #[test]
    fn only_triangles_are_written() {
        let sphere = GpuPrimitive {
            kind: crate::layout::PRIM_SPHERE,
            ..Default::default()
        };
        let triangle = GpuPrimitive::default();
        let err = indexed_triangles(&[triangle, sphere]).unwrap_err();
        assert!(err.contains("primitive 1"), "{err}");
    }

    /// The labels give the traversals' own sizes, and `tools/bench_tables.py` (and
    /// `tools/bench_embree.sh`, which takes its labels) name each BVH in their tables as the
    /// reports here do.
    #[test]
    fn the_table_script_labels_the_bvhs_as_the_reports_do() {
        use crate::accel::wide::IN_FLIGHT;
        use crate::named::Named;
        let packets = format!("packets of {PACKET} ");
        assert!(Bvh::Packets.label().contains(&packets));
        let streams = format!("streams of {IN_FLIGHT} ");
        assert!(Bvh::Stream.label().contains(&streams));
        let script = include_str!("../../tools/bench_tables.py");
        for value in Bvh::VALUES {
            let entry = format!("\"{}\": \"{}\"", value.name, value.value.label());
            assert!(
                script.contains(&entry),
                "tools/bench_tables.py lacks {entry}"
            );
        }
    }

    #[test]
    fn the_checksum_counts_hits_and_sums_their_distances() {
        let c = Checksum::of(&[1.0, T_FAR, 2.5, T_FAR]);
        assert_eq!((c.hits, c.sum_t), (2, 3.5));
    }

    #[test]
    fn packets_take_every_ray_once_in_blocks_of_four_by_four_pixels() {
        assert_eq!(BLOCK_COLUMNS * BLOCK_ROWS, PACKET);
        // A frame of 10x6: blocks cut short at the right edge and, the rows not a multiple
        // of four, at the last rows.
        let set = RaySet {
            origins: vec![Vec3::ZERO; 60],
            directions: vec![Vec3::Z; 60],
            image_width: 10,
        };
        let order = packet_order(&set);
        let mut sorted = order.clone();
        sorted.sort_unstable();
        assert_eq!(sorted, (0..60).collect::<Vec<u32>>());
        assert_eq!(
            &order[..16],
            &[0, 1, 2, 3, 10, 11, 12, 13, 20, 21, 22, 23, 30, 31, 32, 33]
        );
        assert_eq!(&order[32..40], &[8, 9, 18, 19, 28, 29, 38, 39]);
        assert_eq!(&order[40..48], &[40, 41, 42, 43, 50, 51, 52, 53]);
        // Every block's pixels lie within 4 columns and 4 rows of each other.
        let blocks: Vec<&[u32]> = order.chunks(PACKET).collect();
        for block in &blocks[..2] {
            let (xs, ys): (Vec<u32>, Vec<u32>) = block.iter().map(|&i| (i % 10, i / 10)).unzip();
            assert!(xs.iter().max().unwrap() - xs.iter().min().unwrap() < 4);
            assert!(ys.iter().max().unwrap() - ys.iter().min().unwrap() < 4);
        }
        // Rays of no image keep their order.
        let plain = RaySet {
            image_width: 0,
            ..set
        };
        assert_eq!(packet_order(&plain), (0..60).collect::<Vec<u32>>());
    }
}
