// The path tracer's steps at a path vertex, which wf_shade takes under render.integrator = "path".
// Mirrors: src/integrator/path.rs (emission weights, the bounce and Russian roulette).

// The first random dimension of the path tracer's draws at vertex `depth`.
fn bsdf_dimension(depth: u32) -> u32 {
    return LIGHT_DIMENSION
        + 2u * (depth * frame.vertex_dimension_pairs + frame.light_samples_per_vertex + BSDF_PAIR);
}

fn emitter_area(prim: GpuPrimitive) -> f32 {
    if (prim.kind == PRIM_TRIANGLE) {
        return 0.5 * length(cross(prim.p1 - prim.p0, prim.p2 - prim.p0));
    }
    return length(cross(prim.p1, prim.p2));
}

// The weight of the emission a ray from `origin` sees at `surface` of `prim`, drawn with
// density `pdf` (0: a camera or mirror ray).
fn emission_weight(prim: GpuPrimitive, material: GpuMaterial, surface: Surface, origin: vec3<f32>,
                   direction: vec3<f32>, pdf: f32) -> f32 {
    if (material.light_samples == 0u || pdf <= 0.0) {
        return 1.0;
    }
    let to_surface = surface.position - origin;
    let distance2 = dot(to_surface, to_surface);
    let cos_light = -dot(surface.geometric_normal, direction);
    let area = emitter_area(prim);
    let share = light_choice_probability(material.emission, area);
    return emitter_hit_weight(share * f32(material.light_samples), distance2, cos_light, area, pdf);
}

// Where a bounce's ray starts and the primitive it skips (see the Rust twin).
struct Leaving {
    origin: vec3<f32>,
    skip: u32,
}

fn leaving(kind: u32, id: u32, surface: Surface, transmitted: bool) -> Leaving {
    var normal = surface.geometric_normal;
    var outside = surface.front_facing;
    if (transmitted) {
        normal = -surface.geometric_normal;
        outside = !surface.front_facing;
    }
    let origin = offset_ray_origin(surface.position, surface.position_error, normal);
    return Leaving(origin, select(NONE, id, leaving_rays_skip(kind, outside)));
}

// The bounce that leaves vertex `depth`: the BSDF's direction and the throughput's factor at the
// next vertex over Russian roulette's odds; not valid where the path ends.
fn path_bounce(material: GpuMaterial, surface: Surface, wo: vec3<f32>, depth: u32,
               throughput: vec3<f32>, rng: ptr<function, Rng>) -> BsdfSample {
    let dim = bsdf_dimension(depth);
    rng_seek(rng, dim);
    var u: vec2<f32>;
    // The first bounce takes its points from the pixel pattern (not an interleaved one, which
    // every dimension of a pixel shares): see first_bounce_pattern in the Rust twin.
    if (depth == 0u && frame.pixel_sampler != SAMPLER_INTERLEAVED) {
        let source = PatternSource(frame.pixel_sampler, frame.pixel_strata_columns,
                                   frame.pixel_table_offset, dim);
        u = sample_2d(source, (*rng).pixel % frame.width, (*rng).pixel / frame.width,
                      (*rng).sample, rng);
    } else {
        u = rng_next_2d(rng);
    }
    rng_seek(rng, dim + 2u * (ROULETTE_PAIR - BSDF_PAIR));
    let lobe_roulette = rng_next_2d(rng);
    var s = sample_bsdf(material, surface.shading_normal, surface.geometric_normal, wo,
                        surface.front_facing, u, lobe_roulette.x);
    if (s.valid && depth >= frame.rr_depth) {
        let survival = min(max3(throughput * s.weight), 0.95);
        if (lobe_roulette.y >= survival) {
            return no_bsdf_sample();
        }
        s.weight = s.weight / survival;
    }
    return s;
}
