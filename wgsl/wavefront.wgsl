// The wavefront render: a dispatch's camera samples as paths in buffers, and each stage of a
// path vertex a kernel of its own over the paths that reach it: the camera rays (`wf_camera`),
// their closest hits (`wf_closest`), the shading that emits shadow rays and the mirror bounce
// into queues (`wf_shade`), the queues' indirect dispatches (`wf_prepare`), the shadow rays' any
// hits (`wf_occluded`), the direct light they resolve (`wf_resolve`), then the pixels' sums
// (`wf_accumulate`). Each traversal kernel is as lean as the ray queries (wgsl/trace.wgsl): one
// ray an invocation, 32 bytes of ray read. The host runs the depths in turn (src/gpu/render.rs);
// the counts a depth queues reach the next kernels as indirect dispatches.
//
// Paths are numbered sample-major: path `s * P + e` is sample `s` of the dispatch's entry `e` (P
// entries: the band's pixels, or rows of a pixel list), so a workgroup traces neighbouring
// pixels' same sample, as the ray benchmark's coherent rays are ordered. Each path does what the
// megakernel's trace_path does for its sample, in the same order, with the same random numbers;
// a pixel's samples are summed in order, as the megakernel's pixel loop sums them.
// Mirrors: src/integrator.rs (trace_path, vertex by vertex).

// The invocation's index in a 1-D grid laid out in rows of at most MAX_WORKGROUPS_PER_DIMENSION
// workgroups (`wave_groups`).
fn wave_index(id: vec3<u32>, groups: vec3<u32>) -> u32 {
    return id.y * groups.x * TRACE_WORKGROUP_SIZE + id.x;
}

// Entries (pixels or pixel-list entries) of the dispatch.
fn wave_entries() -> u32 {
    return pass_info.tile_width * pass_info.tile_height;
}

// Whether entry `e` of the dispatch has a pixel: all do but those past a pixel list's end.
fn wave_entry_sampled(e: u32) -> bool {
    return pass_info.listed_pixels == 0u
        || pass_info.tile_y * pass_info.tile_width + e < pass_info.listed_pixels;
}

// The path that invocation `i` of a stage takes: every sampled path of the dispatch at depth 0,
// the depth's queue after it; NONE past the end.
fn wave_path(i: u32) -> u32 {
    if (wave.depth == 0u) {
        let entries = wave_entries();
        if (i >= entries * pass_info.sample_count || !wave_entry_sampled(i % entries)) {
            return NONE;
        }
        return i;
    }
    if (i >= wf_args_in[wave.depth].paths.w) {
        return NONE;
    }
    return wf_queue[(wave.depth % 2u) * wave.path_capacity + i];
}

// The workgroups of an indirect dispatch over `count` entries, and the count.
fn wave_groups(count: u32) -> vec4<u32> {
    let groups = (count + TRACE_WORKGROUP_SIZE - 1u) / TRACE_WORKGROUP_SIZE;
    let rows = (groups + MAX_WORKGROUPS_PER_DIMENSION - 1u) / MAX_WORKGROUPS_PER_DIMENSION;
    return vec4<u32>(min(groups, MAX_WORKGROUPS_PER_DIMENSION), rows, 1u, count);
}

// Camera sample of each path: its ray, and a path that has gathered nothing yet.
@compute @workgroup_size(TRACE_WORKGROUP_SIZE, 1, 1)
fn wf_camera(@builtin(global_invocation_id) id: vec3<u32>,
             @builtin(num_workgroups) groups: vec3<u32>) {
    let p = wave_path(wave_index(id, groups));
    if (p != NONE) {
        let entries = wave_entries();
        let e = p % entries;
        let pixel = pass_pixel(vec3<u32>(e % pass_info.tile_width, e / pass_info.tile_width, 0u));
        let x = pixel % frame.width;
        let y = pixel / frame.width;
        let sample = pass_info.sample_start + p / entries;
        var rng = sample_rng(x, y, sample);
        let camera_ray = camera_sample(x, y, sample, &rng);
        wf_rays[p] = GpuPathRay(camera_ray.origin, camera_ray.time, camera_ray.direction, NONE);
        wf_paths[p] = GpuPath(vec3<f32>(1.0), pixel, vec3<f32>(0.0), sample, vec3<f32>(1.0),
                              0u, 0u, 0u, 0.0, camera_ray.weight);
        // The wavelength is found again from the sample when the path is accumulated.
    }
    check_loop_limit();
}

// The closest hit of each path's ray.
@compute @workgroup_size(TRACE_WORKGROUP_SIZE, 1, 1)
fn wf_closest(@builtin(global_invocation_id) id: vec3<u32>,
              @builtin(num_workgroups) groups: vec3<u32>) {
    let p = wave_path(wave_index(id, groups));
    if (p != NONE) {
        let ray = wf_rays[p];
        let found = cw_closest_hit(ray_at_time(ray_query_new(ray.origin, ray.direction), ray.time),
                                   ray.skip, T_FAR);
        wf_hits[p] = GpuHit(found.prim, found.hit.t, found.hit.b1, found.hit.b2);
    }
    check_loop_limit();
}

// The camera ray's first hit of path `p`, for the AOV layers.
fn store_first_hit(p: u32, first_hit: FirstHit) {
    if (pass_info.aov_offset != 0u) {
        wf_aovs[2u * p] = vec4<f32>(first_hit.normal, first_hit.depth);
        wf_aovs[2u * p + 1u] = vec4<f32>(first_hit.albedo, 0.0);
    }
}

// Writes shadow-ray slot `slot` for sample `s` of a light.
fn store_shadow_ray(slot: u32, origin: vec3<f32>, time: f32, own: u32, s: LightSample, light: u32) {
    wf_shadow_rays[slot] = GpuShadowRay(origin, s.t_max, s.wi, time, own, s.skip, 0u, 0u);
    wf_shadow_terms[slot] = GpuShadowTerm(s.f, light);
}

// Queues the shadow rays of sampled light `l`'s samples in `window` (see `sampled_light`) from
// slot `base + count` on; returns the new count.
fn emit_light_samples(l: u32, share: LightShare, offset: u32, vertex: Vertex, window: LightWindow,
                      base: u32, count: u32, rng: ptr<function, Rng>) -> u32 {
    let light = lights[l];
    let shape = area_light_of(light);
    let range = window_samples(window, light.samples);
    let key = seek_light_samples(rng, vertex.depth, offset, range.x);
    var n = count;
    for (var k = range.x; k < range.y; k += 1u) {
        let square = light_sample_2d(light.samples, light.strata_columns, (*rng).sample, k, key,
                                     rng_next_2d(rng));
        let s = sampled_light_sample(light, shape, share, square, vertex, path_traced());
        n = store_traced_shadow_ray(base, n, vertex, s, l);
    }
    return n;
}

// Stores a traced light sample's shadow ray in slot `base + count` if the path has one left
// (else flags the overflow); returns the new count.
fn store_traced_shadow_ray(base: u32, count: u32, vertex: Vertex, s: LightSample, l: u32) -> u32 {
    if (!s.traced) {
        return count;
    }
    if (count >= wave.shadow_stride) {
        flag_status(STATUS_WAVE_OVERFLOW);
        return count;
    }
    store_shadow_ray(base + count, vertex.origin, vertex.time, vertex.own, s, l);
    return count + 1u;
}

// The shadow rays of path `p`'s vertex, in the order direct_light traces them (the chosen light,
// then light by light, sample by sample), in the path's slots; queued for `wf_occluded`. Returns
// how many.
fn emit_shadow_rays(p: u32, time: f32, surface: Surface, material: GpuMaterial, own: u32,
                    wo: vec3<f32>, depth: u32, window: LightWindow, rng: ptr<function, Rng>) -> u32 {
    let origin = offset_ray_origin(surface.position, surface.position_error, surface.geometric_normal);
    let vertex = Vertex(surface, material, wo, depth, origin, time, own);
    let base = p * wave.shadow_stride;
    var count = 0u;
    if (FEATURE_AREA_LIGHTS) {
        let choice = choose_light(depth, rng);
        if (choice.light != NONE) {
            count = emit_light_samples(choice.light, choice.share, 0u, vertex, window, base, count, rng);
        }
    }
    var offset = frame.light_choice_pairs;
    for (var l = 0u; l < frame.light_choice_start; l += 1u) {
        let light = lights[l];
        if (FEATURE_AREA_LIGHTS && is_sampled_light(light)) {
            count = emit_light_samples(l, every_vertex_share(light), offset, vertex, window, base,
                                       count, rng);
            offset += light.samples;
        } else if (FEATURE_PUNCTUAL_LIGHTS && window_is_first(window)) {
            count = store_traced_shadow_ray(base, count, vertex,
                                            punctual_light_sample(light, surface, material, wo), l);
        }
    }
    if (count > 0u) {
        let start = atomicAdd(&wf_counters[WF_SHADOW_COUNTER], count);
        for (var j = 0u; j < count; j += 1u) {
            wf_shadow_queue[start + j] = base + j;
        }
    }
    return count;
}

// Path `p`'s ray from `origin` along `direction` at `time`, skipping `own`, queued for the
// next depth.
fn queue_ray(p: u32, time: f32, origin: vec3<f32>, direction: vec3<f32>, own: u32) {
    wf_rays[p] = GpuPathRay(origin, time, direction, own);
    let slot = atomicAdd(&wf_counters[WF_PATH_COUNTER], 1u);
    wf_queue[((wave.depth + 1u) % 2u) * wave.path_capacity + slot] = p;
}

// Path `p`'s mirror bounce off `surface`, queued for the next depth (false where it leaves no
// ray: it would go into the surface).
fn queue_bounce(p: u32, ray: RayQuery, surface: Surface, own: u32) -> bool {
    let n = surface.shading_normal;
    let reflected = ray.direction - 2.0 * dot(ray.direction, n) * n;
    if (dot(reflected, surface.geometric_normal) <= 0.0) {
        return false;
    }
    let origin = offset_ray_origin(surface.position, surface.position_error, surface.geometric_normal);
    queue_ray(p, ray.time, origin, normalize(reflected), own);
    return true;
}

// The path tracer's emission at path `p`'s hit, weighted against the light samples that could
// have drawn it (src/integrator/path.rs).
fn path_emission(path: ptr<function, GpuPath>, prim: GpuPrimitive, material: GpuMaterial,
                 surface: Surface, ray: RayQuery) {
    if (surface.front_facing && max3(material.emission) > 0.0) {
        let weight = emission_weight(prim, material, surface, ray.origin, ray.direction,
                                     (*path).bsdf_pdf);
        (*path).radiance += (*path).throughput * material.emission * weight;
    }
}

// The path tracer's bounce off path `p`'s vertex (primitive `id`), queued for the next depth,
// or its end.
fn queue_path_bounce(p: u32, path: ptr<function, GpuPath>, ray: RayQuery, surface: Surface,
                     material: GpuMaterial, id: u32, rng: ptr<function, Rng>) {
    let s = path_bounce(material, surface, -ray.direction, wave.depth, (*path).throughput, rng);
    if (s.valid) {
        let leaves = leaving(prims[id].kind, id, surface, s.transmitted);
        queue_ray(p, ray.time, leaves.origin, s.wi, leaves.skip);
        (*path).bounce_weight = s.weight;
        (*path).bsdf_pdf = s.pdf;
        // Cut off while it still reflects: the path would go on (as Whitted's mirror bounce
        // at max_depth counts).
        if (wave.depth == frame.max_depth && window_is_first(pass_window())) {
            (*path).truncated = 1u;
        }
    }
}

// Shades each path's hit: what it sees that needs no shadow ray (background, emission,
// ambient), its shadow rays, and its mirror bounce, as one iteration of trace_path's loop.
@compute @workgroup_size(TRACE_WORKGROUP_SIZE, 1, 1)
fn wf_shade(@builtin(global_invocation_id) id: vec3<u32>,
            @builtin(num_workgroups) groups: vec3<u32>) {
    let p = wave_path(wave_index(id, groups));
    if (p == NONE) {
        check_loop_limit();
        return;
    }
    let depth = wave.depth;
    let first = window_is_first(pass_window());
    var path = wf_paths[p];
    path.rays += 1u;
    path.shadow_count = 0u;
    if (depth > 0u) {
        path.throughput *= path.bounce_weight;
    }
    let stored = wf_hits[p];
    let traced = wf_rays[p];
    if (stored.prim == NONE) {
        if (first) {
            path.radiance += path.throughput * frame.background;
            path.radiance += path.throughput * sky_seen(traced.direction, path.bsdf_pdf);
        }
        if (depth == 0u) {
            store_first_hit(p, FirstHit(0.0, vec3<f32>(0.0), vec3<f32>(0.0)));
        }
        wf_paths[p] = path;
        check_loop_limit();
        return;
    }
    // The path tracer's vertex after max_depth bounces only sees emission: where its
    // material emits nothing and has no texture, the path ends without the surface
    // (`dark_last_vertex` in path.rs).
    if (path_traced() && depth > frame.max_depth) {
        let plain = materials[prims[stored.prim].material];
        if (plain.texture == 0u && max3(plain.emission) <= 0.0) {
            wf_paths[p] = path;
            check_loop_limit();
            return;
        }
    }
    let ray = ray_at_time(ray_query_new(traced.origin, traced.direction), traced.time);
    let prim = prims[stored.prim];
    let hit = Hit(stored.t, stored.b1, stored.b2);
    let surface = moved_surface_at(stored.prim, ray, hit);
    let material = material_at(prim, hit, surface);
    if (depth == 0u) {
        store_first_hit(p, first_hit_of(stored.t, surface, material));
    }
    let path_mode = path_traced();
    if (path_mode && first) {
        path_emission(&path, prim, material, surface, ray);
    }
    // An area light shows its radiance from the front, is black from behind, reflects nothing.
    if (material.model == MODEL_EMITTER) {
        if (!path_mode && surface.front_facing && first) {
            path.radiance += path.throughput * material.emission;
        }
        wf_paths[p] = path;
        check_loop_limit();
        return;
    }
    // The path tracer's vertex after max_depth bounces only sees emission.
    if (path_mode && depth > frame.max_depth) {
        wf_paths[p] = path;
        check_loop_limit();
        return;
    }
    let wo = -ray.direction;
    if (first && !path_mode) {
        path.radiance += path.throughput * material.diffuse * frame.ambient;
    }
    // Rays leaving a flat primitive skip it; a curved one may shadow or reflect itself.
    let own = select(NONE, stored.prim, leaving_rays_skip(prim.kind, surface.front_facing));
    var rng = rng_new(frame.seed, path.pixel, path.sample);
    // Under the path tracer a material of deltas alone (a mirror, glass) meets no light sample.
    if (!path_mode || has_smooth_lobes(material)) {
        path.shadow_count = emit_shadow_rays(p, traced.time, surface, material, own, wo, depth,
                                             pass_window(), &rng);
    }
    path.rays += path.shadow_count;
    if (path_mode) {
        queue_path_bounce(p, &path, ray, surface, material, stored.prim, &rng);
    } else if (FEATURE_MIRRORS && max(max(material.mirror.x, material.mirror.y), material.mirror.z) > 0.0) {
        if (depth == frame.max_depth) {
            path.truncated = select(0u, 1u, first);
        } else if (queue_bounce(p, ray, surface, own)) {
            path.bounce_weight = material.mirror;
        }
    }
    wf_paths[p] = path;
    check_loop_limit();
}

// The indirect dispatches of the depth's shadow rays and of the next depth's paths, from the
// counters the shading filled; the counters start again from zero.
@compute @workgroup_size(1, 1, 1)
fn wf_prepare() {
    let paths = atomicExchange(&wf_counters[WF_PATH_COUNTER], 0u);
    let shadows = atomicExchange(&wf_counters[WF_SHADOW_COUNTER], 0u);
    wf_args[wave.depth + 1u].paths = wave_groups(paths);
    wf_args[wave.depth].shadows = wave_groups(shadows);
}

// Whether each queued shadow ray reaches its light; a blocked one's term is zeroed.
@compute @workgroup_size(TRACE_WORKGROUP_SIZE, 1, 1)
fn wf_occluded(@builtin(global_invocation_id) id: vec3<u32>,
               @builtin(num_workgroups) groups: vec3<u32>) {
    let i = wave_index(id, groups);
    if (i < wf_args_in[wave.depth].shadows.w) {
        let slot = wf_shadow_queue[i];
        let ray = wf_shadow_rays[slot];
        let query = ray_at_time(ray_query_new(ray.origin, ray.direction), ray.time);
        if (cw_occluded(query, ray.skip_a, ray.skip_b, ray.t_max)) {
            wf_shadow_terms[slot].f = vec3<f32>(0.0);
        }
    }
    check_loop_limit();
}

// Each path's direct light from its vertex's shadow terms, summed light by light in the order
// direct_light sums them (a blocked term adds zero), then weighted by the path's throughput.
@compute @workgroup_size(TRACE_WORKGROUP_SIZE, 1, 1)
fn wf_resolve(@builtin(global_invocation_id) id: vec3<u32>,
              @builtin(num_workgroups) groups: vec3<u32>) {
    let p = wave_path(wave_index(id, groups));
    if (p != NONE) {
        let count = wf_paths[p].shadow_count;
        if (count > 0u) {
            let base = p * wave.shadow_stride;
            var total = vec3<f32>(0.0);
            var sum = vec3<f32>(0.0);
            var light = wf_shadow_terms[base].light;
            for (var j = 0u; j < count; j += 1u) {
                let term = wf_shadow_terms[base + j];
                if (term.light != light) {
                    total += light_total(lights[light], sum);
                    sum = vec3<f32>(0.0);
                    light = term.light;
                }
                sum += term.f;
            }
            total += light_total(lights[light], sum);
            wf_paths[p].radiance += wf_paths[p].throughput * total;
        }
    }
    check_loop_limit();
}

// Each entry's samples summed in order and committed, as the megakernel commits a pixel.
@compute @workgroup_size(TRACE_WORKGROUP_SIZE, 1, 1)
fn wf_accumulate(@builtin(global_invocation_id) id: vec3<u32>,
                 @builtin(num_workgroups) groups: vec3<u32>) {
    let e = wave_index(id, groups);
    let entries = wave_entries();
    if (e >= entries) {
        return;
    }
    let pixel = pass_pixel(vec3<u32>(e % pass_info.tile_width, e / pass_info.tile_width, 0u));
    if (pixel == NONE) {
        return;
    }
    var sums = no_sums();
    var counters = PathCounters(0u, 0u);
    for (var s = 0u; s < pass_info.sample_count; s += 1u) {
        let p = s * entries + e;
        let path = wf_paths[p];
        var first_hit = FirstHit(0.0, vec3<f32>(0.0), vec3<f32>(0.0));
        if (pass_info.aov_offset != 0u) {
            let normal_depth = wf_aovs[2u * p];
            first_hit = FirstHit(normal_depth.w, normal_depth.xyz, wf_aovs[2u * p + 1u].xyz);
        }
        let wavelength = camera_wavelength(pixel % frame.width, pixel / frame.width, path.sample);
        add_sample(&sums, path.radiance * camera_counts_for(path.camera_weight, wavelength), first_hit);
        counters.rays += path.rays;
        counters.truncated += path.truncated;
    }
    commit_pixel(pixel, sums, counters);
    check_loop_limit();
}
