// Struct twins of src/layout.rs: same names, same field names (checked by tests/wgsl.rs).

struct GpuBvhNode {
    min: vec3<f32>,
    prim_count: u32,
    max: vec3<f32>,
    first_index: u32,
}

struct GpuCwNode {
    p: vec3<f32>,
    e_imask: u32,
    child_base: u32,
    prim_base: u32,
    child_meta: vec2<u32>,
    q_lo_x: vec2<u32>,
    q_hi_x: vec2<u32>,
    q_lo_y: vec2<u32>,
    q_hi_y: vec2<u32>,
    q_lo_z: vec2<u32>,
    q_hi_z: vec2<u32>,
}

struct GpuPrimitive {
    p0: vec3<f32>,
    kind: u32,
    p1: vec3<f32>,
    material: u32,
    p2: vec3<f32>,
    normals: u32,
}

struct GpuNormals {
    n: array<f32, 9>,
}

struct GpuMaterial {
    diffuse: vec3<f32>,
    model: u32,
    specular: vec3<f32>,
    shininess: f32,
    mirror: vec3<f32>,
    light_samples: u32,
    emission: vec3<f32>,
    ior: f32,
    texture: u32,
    _pad0: u32,
    _pad1: u32,
    _pad2: u32,
}

struct GpuTexture {
    offset: u32,
    width: u32,
    height: u32,
    wrap: u32,
}

struct GpuTexCoords {
    uv: array<f32, 6>,
}

struct GpuLight {
    p0: vec3<f32>,
    kind: u32,
    p1: vec3<f32>,
    samples: u32,
    p2: vec3<f32>,
    prim: u32,
    color: vec3<f32>,
    strata_columns: u32,
}

struct GpuCamera {
    lens_to_world_x: vec3<f32>,
    focal_length_mm: f32,
    lens_to_world_y: vec3<f32>,
    lens_radius_mm: f32,
    lens_to_world_z: vec3<f32>,
    units_per_mm: f32,
    lens_center: vec3<f32>,
    inv_focal_length_mm: f32,
    film_center: vec3<f32>,
    film_width_mm: f32,
    film_u: vec3<f32>,
    film_height_mm: f32,
    film_v: vec3<f32>,
    aperture_blades: u32,
    aperture_table_offset: u32,
    shutter_open: f32,
    shutter_span: f32,
    focus_surface: u32,
    focus_radius_mm: f32,
    projection: u32,
    lens_surface_count: u32,
    lens_table_offset: u32,
    spectral: u32,
    _pad0: u32,
    _pad1: u32,
    _pad2: u32,
}

struct GpuFrame {
    width: u32,
    height: u32,
    spp: u32,
    max_depth: u32,
    seed: u32,
    pixel_sampler: u32,
    light_count: u32,
    node_count: u32,
    plane_start: u32,
    plane_count: u32,
    traversal_cap: u32,
    pixel_strata_columns: u32,
    lens_sampler: u32,
    lens_strata_columns: u32,
    pixel_table_offset: u32,
    lens_table_offset: u32,
    background: vec3<f32>,
    light_samples_per_vertex: u32,
    ambient: vec3<f32>,
    motion_base: u32,
    progressive: u32,
    integrator: u32,
    rr_depth: u32,
    vertex_dimension_pairs: u32,
    light_choice_start: u32,
    light_choice_pairs: u32,
    light_choice_offset: u32,
    light_power_total: f32,
}

struct GpuPass {
    tile_x: u32,
    tile_y: u32,
    tile_width: u32,
    tile_height: u32,
    sample_start: u32,
    sample_count: u32,
    light_sample_start: u32,
    light_sample_count: u32,
    commit: u32,
    loop_check: u32,
    listed_pixels: u32,
    scratch_offset: u32,
    aov_offset: u32,
    _pad1: u32,
    _pad2: u32,
    _pad3: u32,
}

struct GpuRay {
    origin: vec3<f32>,
    t_max: f32,
    direction: vec3<f32>,
    _pad0: u32,
}

struct GpuHit {
    prim: u32,
    t: f32,
    b1: f32,
    b2: f32,
}

struct GpuPathRay {
    origin: vec3<f32>,
    time: f32,
    direction: vec3<f32>,
    skip: u32,
}

struct GpuPath {
    throughput: vec3<f32>,
    pixel: u32,
    radiance: vec3<f32>,
    sample: u32,
    bounce_weight: vec3<f32>,
    rays: u32,
    shadow_count: u32,
    truncated: u32,
    bsdf_pdf: f32,
    camera_weight: f32,
}

struct GpuShadowRay {
    origin: vec3<f32>,
    t_max: f32,
    direction: vec3<f32>,
    time: f32,
    skip_a: u32,
    skip_b: u32,
    _pad0: u32,
    _pad1: u32,
}

struct GpuShadowTerm {
    f: vec3<f32>,
    light: u32,
}

struct GpuWave {
    depth: u32,
    shadow_stride: u32,
    path_capacity: u32,
    _pad0: u32,
}

struct GpuWaveArgs {
    paths: vec4<u32>,
    shadows: vec4<u32>,
}

struct GpuReflector {
    center: vec3<f32>,
    radius: f32,
    eye: vec3<f32>,
    count: u32,
    kind: u32,
    minor: f32,
    height: f32,
    mirror: u32,
    radii: vec4<f32>,
    orientation: vec4<f32>,
    control: array<vec4<f32>, 16>,
    sees_itself: u32,
    torus_half: u32,
    eye_uv: vec2<f32>,
}

// v turned by the unit quaternion q = (x, y, z, w): a curved shape's orientation
// (`GpuPrimitive`'s p2 and normals word, `GpuReflector::orientation`), as glam's `Quat * Vec3`.
fn turn(q: vec4<f32>, v: vec3<f32>) -> vec3<f32> {
    let b = q.xyz;
    return v * (q.w * q.w - dot(b, b)) + b * (dot(v, b) * 2.0) + cross(b, v) * (q.w * 2.0);
}

// The inverse of a unit quaternion's rotation.
fn conjugate(q: vec4<f32>) -> vec4<f32> {
    return vec4<f32>(-q.xyz, q.w);
}

struct GpuReflection {
    point: vec3<f32>,
    steps: u32,
    normal: vec3<f32>,
    shown: u32,
    uv: vec2<f32>,
    depth: f32,
    degenerate: u32,
}

// wgpu's indirect draw arguments; `fermat_cull` counts the vertices atomically.
struct GpuDrawArgs {
    index_count: atomic<u32>,
    instance_count: u32,
    first_index: u32,
    base_vertex: i32,
    first_instance: u32,
}
