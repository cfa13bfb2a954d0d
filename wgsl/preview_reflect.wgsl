// Fermat reflections in the raster preview (seed 004): the reflected triangles of one mirror
// sphere, each vertex V drawn at its reflection point P (the `fermat` kernel's output) with the
// depth |P - V|, so the nearest reflected surface along each reflected ray wins (first level of
// hidden-surface removal, in a depth buffer of its own); a fragment lands only where the main
// pass saw this reflector (second level: reflections behind the reflector, or behind whatever
// hides it, are discarded). Lit as if the eye were at P. A fragment replaces the main pass's
// colour of the pixel (the sphere reflecting the background) with the sphere's own shading plus
// its mirror reflectance times the reflected radiance; the depth test leaves the nearest.
// Composed after wgsl/preview.wgsl. Mirrors: src/gpu/preview.rs (Reflections),
// src/preview.rs (reflected_triangles), src/fermat.rs (the solver and its validity tests).

// What the reflection pass of one reflector needs beyond the preview's uniforms.
struct ReflectorPass {
    // The sphere: centre and radius (w).
    sphere: vec4<f32>,
    // Reflected depths |P - V| are divided by this to land in [0, 1].
    far: f32,
    // 1 + the reflector's index: the id the main pass wrote where it is seen.
    id: u32,
    // The reflector's material.
    material: u32,
    _pad0: u32,
}

@group(1) @binding(0) var<storage, read> reflected_vertices: array<PreviewVertex>;
@group(1) @binding(1) var<storage, read> reflected_points: array<GpuReflection>;
@group(1) @binding(2) var<uniform> reflector_pass: ReflectorPass;
@group(1) @binding(3) var reflector_ids: texture_2d<u32>;
// Per reflected vertex, the index of its Fermat solve (vertices at one position share one).
@group(1) @binding(4) var<storage, read> solve_of: array<u32>;

struct ReflectedOut {
    @builtin(position) clip: vec4<f32>,
    // V, the reflected scene point.
    @location(0) world: vec3<f32>,
    @location(1) normal: vec3<f32>,
    @location(2) @interpolate(flat) material: u32,
    // P, the point of the mirror V is seen at: the eye V's lighting is computed for.
    @location(3) mirror_point: vec3<f32>,
}

// Vertex `i`'s reflection is drawn: E and V both see P from outside the sphere and the law of
// reflection holds at P. (A search whose triangle shrank below f32's resolution reports its
// step system singular; its point still counts if the law holds there.)
fn reflection_holds(i: u32) -> bool {
    let r = reflected_points[solve_of[i]];
    let n = normalize(r.point - reflector_pass.sphere.xyz);
    let to_eye = normalize(preview.eye.xyz - r.point);
    let to_vertex = normalize(reflected_vertices[i].position - r.point);
    let half = to_eye + to_vertex;
    return dot(n, to_eye) > 0.0 && dot(n, to_vertex) > 0.0
        && length(cross(n, normalize(half))) < REFLECTION_TOLERANCE;
}

@vertex
fn reflected_vertex(@builtin(vertex_index) i: u32) -> ReflectedOut {
    let v = reflected_vertices[i];
    let r = reflected_points[solve_of[i]];
    var clip = preview.clip * vec4<f32>(r.point, 1.0);
    // Depth linear in |P - V| (interpolated across the triangle after the perspective divide,
    // as the seed's z-buffer does).
    clip.z = clamp(r.depth / reflector_pass.far, 0.0, 1.0) * clip.w;
    let first = i - i % 3u;
    if (!(reflection_holds(first) && reflection_holds(first + 1u) && reflection_holds(first + 2u))) {
        // The whole triangle collapses to one point and draws nothing.
        clip = vec4<f32>(0.0, 0.0, 0.0, 1.0);
    }
    return ReflectedOut(clip, v.position, v.normal, v.material, r.point);
}

@fragment
fn reflected_fragment(f: ReflectedOut) -> @location(0) vec4<f32> {
    if (textureLoad(reflector_ids, vec2<i32>(f.clip.xy), 0).r != reflector_pass.id) {
        discard;
    }
    let sphere = reflector_pass.sphere;
    let own = shade(reflector_pass.material, f.mirror_point, f.mirror_point - sphere.xyz,
        preview.eye.xyz);
    let reflected = shade(f.material, f.world, f.normal, f.mirror_point);
    return vec4<f32>(own + preview_materials[reflector_pass.material].mirror * reflected, 1.0);
}
