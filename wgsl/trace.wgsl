// Ray queries for the ray benchmark: one invocation traces one ray of the `rays` buffer, with
// the render kernel's traversal, and writes its closest-hit distance (T_FAR on a miss), or
// 0 / T_FAR for an occluded / free ray. `pass_info.sample_count` is the number of rays.
// Mirrors: src/bench/rays.rs (trace_cpu).

@compute @workgroup_size(TRACE_WORKGROUP_SIZE, 1, 1)
fn trace_closest(@builtin(global_invocation_id) id: vec3<u32>) {
    let i = id.x;
    if (i < pass_info.sample_count) {
        let ray = rays[i];
        let found = closest_hit(ray_query_new(ray.origin, ray.direction), NONE, ray.t_max);
        distances[i] = select(T_FAR, found.hit.t, found.prim != NONE);
    }
    check_loop_limit();
}

@compute @workgroup_size(TRACE_WORKGROUP_SIZE, 1, 1)
fn trace_any(@builtin(global_invocation_id) id: vec3<u32>) {
    let i = id.x;
    if (i < pass_info.sample_count) {
        let ray = rays[i];
        let blocked = occluded(ray_query_new(ray.origin, ray.direction), NONE, NONE, ray.t_max);
        distances[i] = select(T_FAR, 0.0, blocked);
    }
    check_loop_limit();
}

// The same queries through the compressed wide BVH (`cw_nodes`; `prims` in its order).
@compute @workgroup_size(TRACE_WORKGROUP_SIZE, 1, 1)
fn trace_closest_cw(@builtin(global_invocation_id) id: vec3<u32>) {
    let i = id.x;
    if (i < pass_info.sample_count) {
        let ray = rays[i];
        let found = cw_closest_hit(ray_query_new(ray.origin, ray.direction), NONE, ray.t_max);
        distances[i] = select(T_FAR, found.hit.t, found.prim != NONE);
    }
    check_loop_limit();
}

@compute @workgroup_size(TRACE_WORKGROUP_SIZE, 1, 1)
fn trace_any_cw(@builtin(global_invocation_id) id: vec3<u32>) {
    let i = id.x;
    if (i < pass_info.sample_count) {
        let ray = rays[i];
        let blocked = cw_occluded(ray_query_new(ray.origin, ray.direction), NONE, NONE, ray.t_max);
        distances[i] = select(T_FAR, 0.0, blocked);
    }
    check_loop_limit();
}
