// The preview's last pass: each pixel where the main pass saw a mirror sphere gets the sphere's
// mirror reflectance times what its reflection pass drew there, or times the background where
// no reflected triangle landed (what a reflected ray escaping the scene sees).
// Mirrors: src/gpu/preview.rs (Reflections::composite).

@group(0) @binding(0) var shaded: texture_2d<f32>;
@group(0) @binding(1) var reflected_radiance: texture_2d<f32>;
@group(0) @binding(2) var reflector_ids: texture_2d<u32>;
// Entry 0: the background; entry k: reflector k - 1's mirror reflectance (rgb).
@group(0) @binding(3) var<storage, read> mirrors: array<vec4<f32>>;

// One triangle covering the whole target.
@vertex
fn composite_vertex(@builtin(vertex_index) i: u32) -> @builtin(position) vec4<f32> {
    let x = f32(i32(i & 1u) * 4 - 1);
    let y = f32(i32(i >> 1u) * 4 - 1);
    return vec4<f32>(x, y, 0.0, 1.0);
}

@fragment
fn composite_fragment(@builtin(position) p: vec4<f32>) -> @location(0) vec4<f32> {
    let pixel = vec2<i32>(p.xy);
    let base = textureLoad(shaded, pixel, 0);
    let id = textureLoad(reflector_ids, pixel, 0).r;
    if (id == 0u) {
        return base;
    }
    let reflected = textureLoad(reflected_radiance, pixel, 0);
    let seen = select(mirrors[0].xyz, reflected.xyz, reflected.w > 0.0);
    return vec4<f32>(base.xyz + mirrors[id].xyz * seen, 1.0);
}
