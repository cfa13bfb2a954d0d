// Closest-hit and any-hit traversal of the compressed wide BVH (eight children per node, child
// boxes quantised to 8 bits per plane), then the unbounded planes by brute force: the render
// kernel's traversal (the CPU path traverses the BVH2; both find the same hits).
// Mirrors: src/accel/cwbvh.rs, step by step; the node order is obvhs's `traverse!` macro's.
// Reads the bindings `cw_nodes`, `prims` and `frame`; reports caps through status.wgsl.
// The eight children are tested by eight calls, each skipping an empty slot at once (one slab
// test over four boxes at a time, without the skip, was 1.3x slower on an H100).

// obvhs's ray_get_octant_inv4: for each of the four bytes, 7 minus the ray's octant.
fn cw_octant_inv4(direction: vec3<f32>) -> u32 {
    return select(0x04040404u, 0u, direction.x < 0.0)
        | select(0x02020202u, 0u, direction.y < 0.0)
        | select(0x01010101u, 0u, direction.z < 0.0);
}

// Byte `i` (0..8) of a pair of little-endian words.
fn cw_byte(words: vec2<u32>, i: u32) -> u32 {
    return (words[i / 4u] >> ((i % 4u) * 8u)) & 0xffu;
}

// The hit bits of one child: for an inner child, bit 24 + its traversal rank; for a leaf, its
// primitives' bits from `prim_base`; none for an empty slot or a missed box. obvhs's
// `CwBvhNode::get_child_and_index_bits`, one byte at a time.
fn cw_child_hit(ray: RayQuery, node: GpuCwNode, e: vec3<f32>, child: u32, oct_inv4: u32, t_max: f32) -> u32 {
    let child_meta = cw_byte(node.child_meta, child);
    if (child_meta == 0u) {
        return 0u;
    }
    let lo = node.p + e * vec3<f32>(f32(cw_byte(node.q_lo_x, child)), f32(cw_byte(node.q_lo_y, child)), f32(cw_byte(node.q_lo_z, child)));
    let hi = node.p + e * vec3<f32>(f32(cw_byte(node.q_hi_x, child)), f32(cw_byte(node.q_hi_y, child)), f32(cw_byte(node.q_hi_z, child)));
    if (intersect_box(ray, lo, hi, t_max) >= T_FAR) {
        return 0u;
    }
    if ((child_meta & (child_meta << 1u) & 0x10u) != 0u) {
        return 1u << ((child_meta ^ (oct_inv4 & 0xffu)) & 0x1fu);
    }
    return (child_meta >> 5u) << (child_meta & 0x1fu);
}

fn cw_child_hits(ray: RayQuery, node: GpuCwNode, oct_inv4: u32, t_max: f32) -> u32 {
    let e = vec3<f32>(
        bitcast<f32>((node.e_imask & 0xffu) << 23u),
        bitcast<f32>(((node.e_imask >> 8u) & 0xffu) << 23u),
        bitcast<f32>(((node.e_imask >> 16u) & 0xffu) << 23u));
    return cw_child_hit(ray, node, e, 0u, oct_inv4, t_max)
        | cw_child_hit(ray, node, e, 1u, oct_inv4, t_max)
        | cw_child_hit(ray, node, e, 2u, oct_inv4, t_max)
        | cw_child_hit(ray, node, e, 3u, oct_inv4, t_max)
        | cw_child_hit(ray, node, e, 4u, oct_inv4, t_max)
        | cw_child_hit(ray, node, e, 5u, oct_inv4, t_max)
        | cw_child_hit(ray, node, e, 6u, oct_inv4, t_max)
        | cw_child_hit(ray, node, e, 7u, oct_inv4, t_max);
}

// The traversal stack, one per invocation for every ray it traces (the two queries never
// nest). A function's `var` is zeroed at each call, which lavapipe does in full for every ray
// (the cornell_direct frame 1.33x slower, area_light 1.48x, the bunny 1.15x); a private
// variable is zeroed once, when the invocation starts.
var<private> cw_stack: array<vec2<u32>, CWBVH_STACK_SIZE>;

// Traversal state: the node group being expanded, (child_base, hit bits 24..32 | inner mask
// 0..8), and the primitives of the last node's leaves, (prim_base, bits 0..24).
struct CwState {
    current: vec2<u32>,
    prims: vec2<u32>,
    stack_size: u32,
}

// Expands the current group's nearest child: pushes the rest of the group, intersects the
// child's children. Returns false on a stack overflow (flagged).
fn cw_step(ray: RayQuery, oct_inv4: u32, t_max: f32, state: ptr<function, CwState>) -> bool {
    let hits = (*state).current.y;
    let bit = firstLeadingBit(hits);
    (*state).current.y = hits & ~(1u << bit);
    if (((*state).current.y & 0xff000000u) != 0u) {
        if ((*state).stack_size >= CWBVH_STACK_SIZE) {
            flag_status(STATUS_STACK_OVERFLOW);
            return false;
        }
        cw_stack[(*state).stack_size] = (*state).current;
        (*state).stack_size += 1u;
    }
    let slot = (bit - 24u) ^ (oct_inv4 & 0xffu);
    let rank_in_base = countOneBits(hits & ~(0xffffffffu << slot));
    let node = cw_nodes[(*state).current.x + rank_in_base];
    let mask = cw_child_hits(ray, node, oct_inv4, t_max);
    (*state).current = vec2<u32>(node.child_base, (mask & 0xff000000u) | (node.e_imask >> 24u));
    (*state).prims = vec2<u32>(node.prim_base, mask & 0x00ffffffu);
    return true;
}

// Once the current group has no child left, the next from the stack; false when the stack is
// empty too (the traversal is over).
fn cw_next_group(state: ptr<function, CwState>) -> bool {
    if (((*state).current.y & 0xff000000u) != 0u) {
        return true;
    }
    if ((*state).stack_size == 0u) {
        return false;
    }
    (*state).stack_size -= 1u;
    (*state).current = cw_stack[(*state).stack_size];
    return true;
}

// One loop iteration's node work, shared by both queries: the visit cap (flagged), then the
// current group's nearest child expanded into `state.prims`. False ends the traversal.
fn cw_advance(ray: RayQuery, oct_inv4: u32, t_max: f32, visits: u32,
              state: ptr<function, CwState>) -> bool {
    if (visits >= frame.traversal_cap) {
        flag_status(STATUS_TRAVERSAL_CAP);
        return false;
    }
    (*state).prims = vec2<u32>(0u, 0u);
    if (((*state).current.y & 0xff000000u) != 0u) {
        return cw_step(ray, oct_inv4, t_max, state);
    }
    return true;
}

// Closest intersection before `t_max_in`, ignoring primitive `skip` (the planar primitive a
// secondary ray leaves); as traverse.wgsl's closest_hit.
fn cw_closest_hit(ray: RayQuery, skip: u32, t_max_in: f32) -> PrimHit {
    var best = PrimHit(NONE, Hit(t_max_in, 0.0, 0.0));
    let oct_inv4 = cw_octant_inv4(ray.direction);
    var state = CwState(vec2<u32>(0u, 0x80000000u), vec2<u32>(0u, 0u), 0u);
    for (var visits = 0u; cw_advance(ray, oct_inv4, best.hit.t, visits, &state); visits += 1u) {
        while (state.prims.y != 0u) {
            let bit = firstLeadingBit(state.prims.y);
            state.prims.y &= ~(1u << bit);
            let id = state.prims.x + bit;
            if (id != skip) {
                let hit = intersect_at_time(ray, id, best.hit.t);
                if (hit.t < best.hit.t) {
                    best = PrimHit(id, hit);
                }
            }
        }
        if (!cw_next_group(&state)) {
            break;
        }
    }
    return closest_plane(ray, skip, best);
}

// Whether anything but `skip_a` and `skip_b` lies along `ray` before `t_max`.
fn cw_occluded(ray: RayQuery, skip_a: u32, skip_b: u32, t_max: f32) -> bool {
    let oct_inv4 = cw_octant_inv4(ray.direction);
    var state = CwState(vec2<u32>(0u, 0x80000000u), vec2<u32>(0u, 0u), 0u);
    for (var visits = 0u; cw_advance(ray, oct_inv4, t_max, visits, &state); visits += 1u) {
        while (state.prims.y != 0u) {
            let bit = firstLeadingBit(state.prims.y);
            state.prims.y &= ~(1u << bit);
            let id = state.prims.x + bit;
            if (id != skip_a && id != skip_b && intersect_at_time(ray, id, t_max).t < t_max) {
                return true;
            }
        }
        if (!cw_next_group(&state)) {
            break;
        }
    }
    return plane_occludes(ray, skip_a, skip_b, t_max);
}
