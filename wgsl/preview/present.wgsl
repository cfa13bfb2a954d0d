// The interactive preview's presentation (`chambre preview --window`; Rust:
// src/preview/window/mod.rs): the preview's linear image, clamped to [0, 1] as the PNG output is, drawn into the window
// with one triangle that covers it. An sRGB surface encodes the colour itself; on another
// surface the shader applies the sRGB curve.

struct Present {
    // Image texels per window pixel, x and y.
    scale: vec2<f32>,
    // 1: the surface is not sRGB, encode here.
    encode_srgb: u32,
    _pad: u32,
}

@group(0) @binding(0) var image: texture_2d<f32>;
@group(0) @binding(1) var<uniform> present: Present;

@vertex
fn present_vertex(@builtin(vertex_index) i: u32) -> @builtin(position) vec4<f32> {
    let corner = vec2<f32>(f32((i << 1u) & 2u), f32(i & 2u));
    return vec4<f32>(corner * 2.0 - 1.0, 0.0, 1.0);
}

fn srgb(linear: f32) -> f32 {
    if (linear <= 0.0031308) {
        return 12.92 * linear;
    }
    return 1.055 * pow(linear, 1.0 / 2.4) - 0.055;
}

@fragment
fn present_fragment(@builtin(position) position: vec4<f32>) -> @location(0) vec4<f32> {
    let size = textureDimensions(image);
    let texel = min(vec2<u32>(position.xy * present.scale), size - 1u);
    let c = clamp(textureLoad(image, texel, 0).rgb, vec3<f32>(0.0), vec3<f32>(1.0));
    if (present.encode_srgb == 1u) {
        return vec4<f32>(srgb(c.r), srgb(c.g), srgb(c.b), 1.0);
    }
    return vec4<f32>(c, 1.0);
}
