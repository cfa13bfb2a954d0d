// The render kernel: one invocation per pixel of a band of rows (or of a band of rows of the
// list of pixels an adaptive pass samples), a range of samples and a window of light samples
// per dispatch. A pass's sum goes to the pixel's scratch slot (which exists only when passes are
// split) until the pass's last light window commits it, with the sample count, to the running
// accumulation (one of its two halves in an adaptive render): the accumulation is a valid
// per-pixel mean after every dispatch; the AOV layers, when asked for, sum the first hits' depth,
// normal and albedo. Layout: src/render.rs (AccumulationLayout). Bindings: wgsl/bindings.wgsl.
// Mirrors: src/cpu.rs (CpuRenderer::run_dispatch).

// The pixel of invocation `id`, or NONE where the band or the list ends.
fn pass_pixel(id: vec3<u32>) -> u32 {
    if (id.x >= pass_info.tile_width || id.y >= pass_info.tile_height) {
        return NONE;
    }
    if (pass_info.listed_pixels == 0u) {
        return (pass_info.tile_y + id.y) * frame.width + pass_info.tile_x + id.x;
    }
    let entry = (pass_info.tile_y + id.y) * pass_info.tile_width + id.x;
    if (entry >= pass_info.listed_pixels) {
        return NONE;
    }
    return pixel_list[entry];
}

@compute @workgroup_size(WORKGROUP_SIZE, WORKGROUP_SIZE, 1)
fn render(@builtin(global_invocation_id) id: vec3<u32>) {
    let pixel = pass_pixel(id);
    if (pixel == NONE) {
        return;
    }
    let x = pixel % frame.width;
    let y = pixel / frame.width;
    let window = LightWindow(pass_info.light_sample_start, pass_info.light_sample_count);
    var counters = PathCounters(0u, 0u);
    var sum = vec3<f32>(0.0);
    // The AOV sums: (normal, depth) and (albedo, unused).
    var normal_depth = vec4<f32>(0.0);
    var albedo = vec4<f32>(0.0);
    for (var s = 0u; s < pass_info.sample_count; s += 1u) {
        var first_hit = FirstHit(0.0, vec3<f32>(0.0), vec3<f32>(0.0));
        sum += trace_sample(x, y, pass_info.sample_start + s, window, &counters, &first_hit);
        normal_depth += vec4<f32>(first_hit.normal, first_hit.depth);
        albedo += vec4<f32>(first_hit.albedo, 0.0);
    }
    let scratch = pass_info.scratch_offset + pixel;
    if (!window_is_first(window)) {
        sum += accumulation[scratch].xyz;
    }
    if (pass_info.commit != 0u) {
        accumulation[pass_info.accumulation_offset + pixel] +=
            vec4<f32>(sum, f32(pass_info.sample_count));
        // Every light window retraces the same camera paths: the committing one adds the AOVs.
        if (pass_info.aov_offset != 0u) {
            accumulation[pass_info.aov_offset + pixel] += normal_depth;
            accumulation[pass_info.aov_offset + frame.width * frame.height + pixel] += albedo;
        }
    } else {
        accumulation[scratch] = vec4<f32>(sum, 0.0);
    }
    atomicAdd(&status[STATUS_RAYS], counters.rays);
    atomicAdd(&status[STATUS_TRUNCATED], counters.truncated);
    check_loop_limit();
}
