// Closest-hit and any-hit BVH2 traversal, then the unbounded planes by brute force.
// Mirrors: src/accel/traverse.rs, which uses obvhs's Bvh2::ray_traverse_dynamic; the node order
// below (nearer child first, far child pushed) is that function's.
// Reads the bindings `nodes`, `prims` and `frame`; reports caps through status.wgsl.

// The traversal stack, one per invocation for every ray it traces (the two queries never
// nest). A function's `var` is zeroed at each call: 64 words a ray, which lavapipe writes out
// in full; a private variable is zeroed once, when the invocation starts.
var<private> bvh_stack: array<u32, BVH_STACK_SIZE>;

fn closest_hit(ray: RayQuery, skip: u32, t_max_in: f32) -> PrimHit {
    var best = PrimHit(NONE, Hit(t_max_in, 0.0, 0.0));
    if (frame.node_count > 0u) {
        let root = nodes[0];
        if (intersect_box(ray, root.min, root.max, best.hit.t) < best.hit.t) {
            if (root.prim_count > 0u) {
                best = closest_in_leaf(ray, root, skip, best);
            } else {
                var stack_size = 0u;
                var current = root.first_index;
                for (var visits = 0u; ; visits += 1u) {
                    if (visits >= frame.traversal_cap) {
                        flag_status(STATUS_TRAVERSAL_CAP);
                        break;
                    }
                    var near = nodes[current];
                    var far = nodes[current + 1u];
                    var t_near = intersect_box(ray, near.min, near.max, best.hit.t);
                    var t_far = intersect_box(ray, far.min, far.max, best.hit.t);
                    if (t_near > t_far) {
                        let node = near;
                        near = far;
                        far = node;
                        let t = t_near;
                        t_near = t_far;
                        t_far = t;
                    }
                    var go_near = false;
                    if (t_near < best.hit.t) {
                        if (near.prim_count > 0u) {
                            best = closest_in_leaf(ray, near, skip, best);
                        } else {
                            go_near = true;
                        }
                    }
                    var go_far = false;
                    if (t_far < best.hit.t) {
                        if (far.prim_count > 0u) {
                            best = closest_in_leaf(ray, far, skip, best);
                        } else {
                            go_far = true;
                        }
                    }
                    if (go_near && go_far) {
                        if (stack_size >= BVH_STACK_SIZE) {
                            flag_status(STATUS_STACK_OVERFLOW);
                            break;
                        }
                        bvh_stack[stack_size] = far.first_index;
                        stack_size += 1u;
                        current = near.first_index;
                    } else if (go_near) {
                        current = near.first_index;
                    } else if (go_far) {
                        current = far.first_index;
                    } else {
                        if (stack_size == 0u) {
                            break;
                        }
                        stack_size -= 1u;
                        current = bvh_stack[stack_size];
                    }
                }
            }
        }
    }
    return closest_plane(ray, skip, best);
}

fn closest_in_leaf(ray: RayQuery, leaf: GpuBvhNode, skip: u32, best_in: PrimHit) -> PrimHit {
    var best = best_in;
    for (var id = leaf.first_index; id < leaf.first_index + leaf.prim_count; id += 1u) {
        if (id != skip) {
            let hit = intersect_at_time(ray, id, best.hit.t);
            if (hit.t < best.hit.t) {
                best = PrimHit(id, hit);
            }
        }
    }
    return best;
}

fn leaf_occludes(ray: RayQuery, leaf: GpuBvhNode, skip_a: u32, skip_b: u32, t_max: f32) -> bool {
    for (var id = leaf.first_index; id < leaf.first_index + leaf.prim_count; id += 1u) {
        if (id != skip_a && id != skip_b && intersect_at_time(ray, id, t_max).t < t_max) {
            return true;
        }
    }
    return false;
}

fn occluded(ray: RayQuery, skip_a: u32, skip_b: u32, t_max: f32) -> bool {
    if (frame.node_count > 0u) {
        let root = nodes[0];
        if (intersect_box(ray, root.min, root.max, t_max) < t_max) {
            if (root.prim_count > 0u) {
                if (leaf_occludes(ray, root, skip_a, skip_b, t_max)) {
                    return true;
                }
            } else {
                var stack_size = 0u;
                var current = root.first_index;
                for (var visits = 0u; ; visits += 1u) {
                    if (visits >= frame.traversal_cap) {
                        flag_status(STATUS_TRAVERSAL_CAP);
                        break;
                    }
                    var near = nodes[current];
                    var far = nodes[current + 1u];
                    var t_near = intersect_box(ray, near.min, near.max, t_max);
                    var t_far = intersect_box(ray, far.min, far.max, t_max);
                    if (t_near > t_far) {
                        let node = near;
                        near = far;
                        far = node;
                        let t = t_near;
                        t_near = t_far;
                        t_far = t;
                    }
                    var go_near = false;
                    if (t_near < t_max) {
                        if (near.prim_count > 0u) {
                            if (leaf_occludes(ray, near, skip_a, skip_b, t_max)) {
                                return true;
                            }
                        } else {
                            go_near = true;
                        }
                    }
                    var go_far = false;
                    if (t_far < t_max) {
                        if (far.prim_count > 0u) {
                            if (leaf_occludes(ray, far, skip_a, skip_b, t_max)) {
                                return true;
                            }
                        } else {
                            go_far = true;
                        }
                    }
                    if (go_near && go_far) {
                        if (stack_size >= BVH_STACK_SIZE) {
                            flag_status(STATUS_STACK_OVERFLOW);
                            break;
                        }
                        bvh_stack[stack_size] = far.first_index;
                        stack_size += 1u;
                        current = near.first_index;
                    } else if (go_near) {
                        current = near.first_index;
                    } else if (go_far) {
                        current = far.first_index;
                    } else {
                        if (stack_size == 0u) {
                            break;
                        }
                        stack_size -= 1u;
                        current = bvh_stack[stack_size];
                    }
                }
            }
        }
    }
    return plane_occludes(ray, skip_a, skip_b, t_max);
}
