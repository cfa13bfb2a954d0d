// The preview's shadow maps (`chambre preview --shadows`): the main pass's triangles drawn
// depth only through one view of one light (a cube face, or a directional light's box), once
// per layer. Mirrors: src/preview/shadows/mod.rs (the views), src/preview/shadows/maps.rs
// (`Shadows`).

@group(0) @binding(0) var<uniform> light_view: mat4x4<f32>;

@vertex
fn shadow_vertex(@location(0) position: vec3<f32>) -> @builtin(position) vec4<f32> {
    return light_view * vec4<f32>(position, 1.0);
}
