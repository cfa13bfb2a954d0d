// The raster preview (`chambre preview`): the scene's triangles through the view camera's clip
// matrix (film tilt, swing and shift as the ray tracer defines them), shaded per fragment with
// Lambert's BRDF, the ambient term, emission, and every light (an area light's exact
// unoccluded irradiance, by Lambert's formula), shadowed by its shadow maps where the preview
// draws shadows (`--shadows`; src/preview/shadows/mod.rs makes the maps' views).
// Curved mirrors show Fermat reflections: this pass writes each pixel's reflector id, and
// wgsl/preview/reflect.wgsl draws the reflected triangles where their reflector is seen.
// Mirrors: src/preview/tessellate.rs (the triangles), src/preview/mod.rs (the clip matrix),
// src/preview/renderer/mod.rs (the pipeline), src/preview/renderer/shading.rs (its variant).

struct PreviewUniforms {
    clip: mat4x4<f32>,
    light_count: u32,
    // The scene's max_depth: how many bounces the ray tracer's paths take (`PreviewUniforms`).
    max_depth: u32,
    _pad1: u32,
    _pad2: u32,
    ambient: vec4<f32>,
    // The eye (the lens centre), world space; w unused.
    eye: vec4<f32>,
    // The background radiance; w unused.
    background: vec4<f32>,
}

@group(0) @binding(0) var<uniform> preview: PreviewUniforms;
@group(0) @binding(1) var<storage, read> preview_materials: array<GpuMaterial>;
@group(0) @binding(2) var<storage, read> preview_lights: array<GpuLight>;

// A light's shadow maps (`preview::ShadowLight`): `layers` 0 (no shadows), 1 (a directional
// light's orthographic view) or six per cube of 90-degree views (an area light's several),
// the cubes standing at `shadow_origins[origins]` and on.
struct ShadowLight {
    first: u32,
    layers: u32,
    // A texel's width: at unit distance along a cube face's axis, or across the view.
    texel: f32,
    origins: u32,
}

@group(0) @binding(3) var shadow_maps: texture_depth_2d_array;
@group(0) @binding(4) var shadow_sampler: sampler_comparison;
// Per layer: world to the view's clip space (depth in [0, 1]).
@group(0) @binding(5) var<storage, read> shadow_views: array<mat4x4<f32>>;
@group(0) @binding(6) var<storage, read> shadow_lights: array<ShadowLight>;
// Per cube: where it stands (w unused).
@group(0) @binding(7) var<storage, read> shadow_origins: array<vec4<f32>>;

// One vertex of the triangle list (`preview::PreviewVertex`); the reflection pass reads them
// from a storage buffer.
struct PreviewVertex {
    position: vec3<f32>,
    material: u32,
    normal: vec3<f32>,
    // 0, or 1 + the index of the reflector the vertex lies on.
    reflector: u32,
}

struct VertexIn {
    @location(0) position: vec3<f32>,
    @location(1) material: u32,
    @location(2) normal: vec3<f32>,
    @location(3) reflector: u32,
}

struct VertexOut {
    @builtin(position) clip: vec4<f32>,
    @location(0) world: vec3<f32>,
    @location(1) normal: vec3<f32>,
    @location(2) @interpolate(flat) material: u32,
    @location(3) @interpolate(flat) reflector: u32,
}

// The main pass's targets: radiance, and which reflector (1 + index, 0 for none) each pixel sees
// with the distance from the eye it sees it at (f32 bits), which tells a reflector's hidden
// parts from its visible ones.
struct PreviewOut {
    @location(0) color: vec4<f32>,
    @location(1) reflector: vec2<u32>,
}

@vertex
fn preview_vertex(v: VertexIn) -> VertexOut {
    let clip = preview.clip * vec4<f32>(v.position, 1.0);
    return VertexOut(clip, v.position, v.normal, v.material, v.reflector);
}

// Whether the scene has area lights, and whether the preview draws shadows: code not needed is
// left out of the pipeline (`preview::renderer::shading::ShadingVariant`).
override PREVIEW_AREA_LIGHTS: bool = true;
override PREVIEW_SHADOWS: bool = true;

// Irradiance-like factor (W/m^2 per unit BRDF) at `p` with normal `n` from light `light`.
fn light_at(light: GpuLight, p: vec3<f32>, n: vec3<f32>) -> vec3<f32> {
    // A sun as the directional light it nears; an environment as its mean radiance over the
    // hemisphere above n, unshadowed (the irradiance pi L of a constant sky).
    if (light.kind == LIGHT_DIRECTIONAL || light.kind == LIGHT_SUN) {
        return light.color * max(dot(n, light.p0), 0.0);
    }
    if (light.kind == LIGHT_ENVIRONMENT) {
        return light.color * light.p1 * 3.14159265358979323846;
    }
    if (PREVIEW_AREA_LIGHTS && (light.kind == LIGHT_AREA || light.kind == LIGHT_TRIANGLE)) {
        return light.color * projected_solid_angle(light, p, n);
    }
    let to_light = light.p0 - p;
    let d2 = max(dot(to_light, to_light), 1e-20);
    let wi = to_light * inverseSqrt(d2);
    var falloff = 1.0 / d2;
    if (light.kind == LIGHT_SPOT) {
        let cone = clamp(-dot(light.p1, wi) * light.p2.x + light.p2.y, 0.0, 1.0);
        falloff *= cone * cone;
    }
    return light.color * max(dot(n, wi), 0.0) * falloff;
}

// The projected solid angle, integral of cos(theta) d(omega), of an area light (a
// parallelogram p0, p0 + p1, p0 + p1 + p2, p0 + p2, or a triangle p0, p0 + p1, p0 + p2) seen
// from `p` with normal `n`: Lambert's formula, half the sum over its edges of the angle an edge
// subtends times the cosine between `n` and the normal of the plane through `p` and the edge,
// after the light is clipped to the half-space above `p`'s tangent plane (where the formula
// holds). Zero behind the light, which emits on the side of p1 x p2 only. Irradiance from
// radiance L is L times it, exactly, as the ray tracer's light sampling converges to.
fn projected_solid_angle(light: GpuLight, p: vec3<f32>, n: vec3<f32>) -> f32 {
    if (dot(p - light.p0, cross(light.p1, light.p2)) <= 0.0) {
        return 0.0;
    }
    // Corners relative to p; a triangle's third is its last.
    let a = light.p0 - p;
    let b = a + light.p1;
    let d = a + light.p2;
    var clipped = ClippedPolygon(vec3<f32>(0.0), vec3<f32>(0.0), 0u, 0.0);
    clip_edge(&clipped, n, a, b);
    if (light.kind == LIGHT_TRIANGLE) {
        clip_edge(&clipped, n, b, d);
    } else {
        let c = b + light.p2;
        clip_edge(&clipped, n, b, c);
        clip_edge(&clipped, n, c, d);
    }
    clip_edge(&clipped, n, d, a);
    if (clipped.count > 1u) {
        clipped.sum += edge_term(clipped.last, clipped.first, n);
    }
    // The sign is the winding seen from p; the clipped light is one convex polygon.
    return 0.5 * abs(clipped.sum);
}

// The light clipped to n . x > 0 as Sutherland-Hodgman emits it, corner by corner, and
// Lambert's sum over the edges emitted so far (no array: lavapipe keeps arrays indexed at run
// time in memory, which tripled every preview frame, point lights' too).
struct ClippedPolygon {
    first: vec3<f32>,
    last: vec3<f32>,
    count: u32,
    sum: f32,
}

fn emit_corner(polygon: ptr<function, ClippedPolygon>, n: vec3<f32>, x: vec3<f32>) {
    if ((*polygon).count == 0u) {
        (*polygon).first = x;
    } else {
        (*polygon).sum += edge_term((*polygon).last, x, n);
    }
    (*polygon).last = x;
    (*polygon).count += 1u;
}

// Edge a -> b of the light: a kept where above the plane, the crossing added where the edge
// crosses it.
fn clip_edge(polygon: ptr<function, ClippedPolygon>, n: vec3<f32>, a: vec3<f32>, b: vec3<f32>) {
    let da = dot(n, a);
    let db = dot(n, b);
    if (da > 0.0) {
        emit_corner(polygon, n, a);
    }
    if ((da > 0.0) != (db > 0.0)) {
        emit_corner(polygon, n, a + (b - a) * (da / (da - db)));
    }
}

// One edge's term of Lambert's formula: the angle it subtends times n . the unit normal of the
// plane through the point and the edge (atan2 rather than acos: acos loses half the digits
// near 0).
fn edge_term(a: vec3<f32>, b: vec3<f32>, n: vec3<f32>) -> f32 {
    let u = normalize(a);
    let v = normalize(b);
    let c = cross(u, v);
    let s = length(c);
    if (s == 0.0) {
        return 0.0;
    }
    return atan2(s, dot(u, v)) * dot(n, c) / s;
}

// The face of a cube that direction `d` falls in (`preview::cube_face`): its largest
// coordinate's axis and sign, x before y before z where they tie.
fn cube_face(d: vec3<f32>) -> u32 {
    let a = abs(d);
    if (a.x >= a.y && a.x >= a.z) {
        return select(0u, 1u, d.x < 0.0);
    }
    if (a.y >= a.z) {
        return select(2u, 3u, d.y < 0.0);
    }
    return select(4u, 5u, d.z < 0.0);
}

// How much of light `i` reaches `p` (normal `n`) past its shadow maps: 1 lit, 0 shadowed,
// between on a shadow's edge (the comparison sampler's 2x2 filter) or, for an area light's
// several cubes, where some see `p` and some do not (their mean). The lookup stands
// SHADOW_NORMAL_OFFSET texels off the surface so that it does not shadow itself, and a cube's
// face is the one that moved point falls in (near a face's edge the point before the move may
// fall in the next).
fn lit_fraction(i: u32, p: vec3<f32>, n: vec3<f32>) -> f32 {
    let shadow = shadow_lights[i];
    if (!PREVIEW_SHADOWS || shadow.layers == 0u) {
        return 1.0;
    }
    if (shadow.layers == 1u) {
        return map_lit(shadow.first, p + SHADOW_NORMAL_OFFSET * shadow.texel * n, false);
    }
    let cubes = shadow.layers / 6u;
    var lit = 0.0;
    for (var k = 0u; k < cubes; k += 1u) {
        let origin = shadow_origins[shadow.origins + k].xyz;
        let d = p - origin;
        let texel = shadow.texel * max(abs(d.x), max(abs(d.y), abs(d.z)));
        let looked_up = p + SHADOW_NORMAL_OFFSET * texel * n;
        lit += map_lit(shadow.first + 6u * k + cube_face(looked_up - origin), looked_up, true);
    }
    return lit / f32(cubes);
}

// Whether map `layer` sees `x` (1), does not (0), or between on an edge. Points nearer its
// light than the view's near plane or beyond its far plane are lit, as are points outside a
// directional light's box; a cube's face is chosen so that `x` is in it (`in_cube`), up to
// rounding at its edge.
fn map_lit(layer: u32, x: vec3<f32>, in_cube: bool) -> f32 {
    let q = shadow_views[layer] * vec4<f32>(x, 1.0);
    if (q.w <= 0.0) {
        return 1.0;
    }
    let ndc = q.xyz / q.w;
    var uv = vec2<f32>(0.5 * ndc.x + 0.5, 0.5 - 0.5 * ndc.y);
    if (ndc.z < 0.0 || ndc.z > 1.0) {
        return 1.0;
    }
    if (in_cube) {
        uv = clamp(uv, vec2<f32>(0.0), vec2<f32>(1.0));
    } else if (any(uv < vec2<f32>(0.0)) || any(uv > vec2<f32>(1.0))) {
        return 1.0;
    }
    return textureSampleCompareLevel(shadow_maps, shadow_sampler, uv, layer, ndc.z);
}

// Radiance leaving `world` (normal `normal`) toward `eye` under the preview's lighting.
fn shade(material_index: u32, world: vec3<f32>, normal: vec3<f32>, eye: vec3<f32>) -> vec3<f32> {
    let material = preview_materials[material_index];
    var n = normalize(normal);
    let facing = dot(n, eye - world) > 0.0;
    if (material.model == MODEL_EMITTER) {
        // One-sided, as the ray tracer shows it.
        return select(vec3<f32>(0.0), material.emission, facing);
    }
    // Two-sided shading: the normal faces the eye.
    if (!facing) {
        n = -n;
    }
    var radiance = material.diffuse * preview.ambient.xyz;
    for (var i = 0u; i < preview.light_count; i += 1u) {
        let irradiance = light_at(preview_lights[i], world, n);
        if (any(irradiance > vec3<f32>(0.0))) {
            radiance += material.diffuse / 3.14159265 * irradiance * lit_fraction(i, world, n);
        }
    }
    return radiance;
}

// A curved mirror's fragment reflects the background here; its reflection pass draws the
// reflected scene over it.
@fragment
fn preview_fragment(f: VertexOut) -> PreviewOut {
    var radiance = shade(f.material, f.world, f.normal, preview.eye.xyz);
    if (f.reflector != 0u) {
        radiance += preview_materials[f.material].mirror * preview.background.xyz;
    }
    let seen_at = bitcast<u32>(distance(f.world, preview.eye.xyz));
    return PreviewOut(vec4<f32>(radiance, 1.0), vec2<u32>(f.reflector, seen_at));
}
