// Fermat reflections in the raster preview (`docs/fermat.md`): the reflected triangles of a batch of
// searches (the surfaces of the curved mirrors: a sphere, a torus's half, a teapot's patch) in
// one draw, each vertex V drawn at its reflection point P (the `fermat`
// kernel's output) with the depth |P - V|, so the nearest reflected surface along each
// reflected ray wins (first level of hidden-surface removal, in a depth buffer of its own); a
// fragment lands only where the main pass saw this reflector at P's distance (second level:
// reflections behind the reflector, on its hidden parts, or behind whatever hides it, are
// discarded). Lit as if the eye were at P. A fragment replaces the main pass's colour of the
// pixel (the mirror reflecting the background) with the mirror's own shading plus
// its mirror reflectance times the reflected radiance; the depth test leaves the nearest.
// Composed after wgsl/preview/shading.wgsl. Mirrors: src/preview/reflections/passes.rs
// (Reflections), src/preview/reflections/mod.rs (ReflectedSet), src/preview/reflections/fermat.rs
// (the solver and its validity tests).

// A reflected fragment whose P lies farther from the eye than the reflector's visible point by
// more than this fraction of its distance is on a hidden part of the reflector.
const HIDDEN_TOLERANCE: f32 = 0.02;

// What the reflection pass needs of one search beyond the preview's uniforms.
struct ReflectorPass {
    // Reflected depths |P - V| are divided by this to land in [0, 1].
    far: f32,
    // 1 + the index of the search's mirror: the id the main pass wrote where it is seen.
    id: u32,
    // The mirror's material.
    material: u32,
    // Vertices each search solves: the length of a search's row of `reflected_points`.
    solves: u32,
}

// The distinct reflected vertices (the index buffer, `fermat_cull`'s list, names a search's
// row times their count plus one of them).
@group(1) @binding(0) var<storage, read> reflected_vertices: array<PreviewVertex>;
// Every search's reflection points, search after search.
@group(1) @binding(1) var<storage, read> reflected_points: array<GpuReflection>;
// Per search of the draw (a batch of them: `preview::reflections::passes::SearchBatch`), its pass.
@group(1) @binding(2) var<storage, read> reflector_passes: array<ReflectorPass>;
@group(1) @binding(3) var reflector_ids: texture_2d<u32>;
// Per distinct reflected vertex, the index of its Fermat solve (vertices at one position share
// one).
@group(1) @binding(4) var<storage, read> solve_of: array<u32>;

struct ReflectedOut {
    @builtin(position) clip: vec4<f32>,
    // V, the reflected scene point.
    @location(0) world: vec3<f32>,
    @location(1) normal: vec3<f32>,
    @location(2) @interpolate(flat) material: u32,
    // P, the point of the mirror V is seen at: the eye V's lighting is computed for.
    @location(3) mirror_point: vec3<f32>,
    // The mirror's normal at P.
    @location(4) mirror_normal: vec3<f32>,
    // 0, or 1 + the index of the mirror V lies on (another mirror reflected in this one).
    @location(5) @interpolate(flat) reflector: u32,
    // The searched mirror's id and material (its `ReflectorPass`, read once a vertex).
    @location(6) @interpolate(flat) mirror_id: u32,
    @location(7) @interpolate(flat) mirror_material: u32,
}

// Index `k` of `fermat_cull`'s list: distinct reflected vertex k % count of the search in row
// k / count, at its reflection point; run once however many shown triangles share it.
@vertex
fn reflected_vertex(@builtin(vertex_index) k: u32) -> ReflectedOut {
    let count = arrayLength(&reflected_vertices);
    let row = k / count;
    let i = k % count;
    let search = reflector_passes[row];
    let v = reflected_vertices[i];
    let r = reflected_points[row * search.solves + solve_of[i]];
    var clip = preview.clip * vec4<f32>(r.point, 1.0);
    // Depth linear in |P - V| (interpolated across the triangle after the perspective divide,
    // as Roger and Holzschuch's z-buffer does).
    clip.z = clamp(r.depth / search.far, 0.0, 1.0) * clip.w;
    return ReflectedOut(clip, v.position, v.normal, v.material, r.point, r.normal, v.reflector,
        search.id, search.material);
}

@fragment
fn reflected_fragment(f: ReflectedOut) -> @location(0) vec4<f32> {
    let seen = textureLoad(reflector_ids, vec2<i32>(f.clip.xy), 0);
    if (seen.r != f.mirror_id) {
        discard;
    }
    // P on a part of the reflector the eye does not see (a torus hides parts of itself): the
    // reflector the main pass drew lies nearer the eye. The tolerance covers the flat
    // reflected triangle's departure from the curved surface between its corners.
    let seen_at = bitcast<f32>(seen.g);
    if (distance(f.mirror_point, preview.eye.xyz) > seen_at * (1.0 + HIDDEN_TOLERANCE)) {
        discard;
    }
    let own = shade(f.mirror_material, f.mirror_point, normalize(f.mirror_normal),
        preview.eye.xyz);
    var reflected = shade(f.material, f.world, f.normal, f.mirror_point);
    if (f.reflector != 0u && preview.max_depth >= 2u) {
        // A mirror seen in a mirror (another, or a teapot's spout in its body): where the ray
        // tracer bounces again, it reflects the background, as the main pass shows a mirror;
        // at max_depth 1 its path ends there and it shows its own shading only.
        reflected += preview_materials[f.material].mirror * preview.background.xyz;
    }
    return vec4<f32>(own + preview_materials[f.mirror_material].mirror * reflected, 1.0);
}
