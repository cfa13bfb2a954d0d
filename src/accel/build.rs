//! BVH construction: obvhs's BVH2 (PLOC + reinsertion), then a depth bound.
//!
//! The GPU traverses with a fixed stack of `layout::BVH_STACK_SIZE` entries, and PLOC has no
//! depth bound: a fan of 3,000 thin triangles gives depth 82, 400 nested slivers 393. Rather than
//! refuse such meshes or traverse with a slower stackless loop, the tree is repacked so that no
//! leaf lies deeper than the stack allows. Subtrees that would end too deep are rebuilt as
//! balanced trees (object median on the longest centroid axis, one primitive per leaf), whose
//! height is ceil(log2 n) + 1; the SAH structure is kept everywhere else. Such subtrees are rare
//! and degenerate, so the SAH cost of the rebuild hardly matters, and both paths traverse the
//! same tree.

use std::time::{Duration, Instant};

use glam::Vec3A;
use obvhs::BvhBuildParams;
use obvhs::aabb::Aabb;
use obvhs::bvh2::{Bvh2, node::Bvh2Node};

/// obvhs's build presets, fastest first; chambre builds with `medium`, the one measured best
/// for build time plus render time in `BENCHMARKS.md`.
pub const PRESETS: [(&str, BvhBuildParams); 6] = [
    ("fastest", BvhBuildParams::fastest_build()),
    ("very_fast", BvhBuildParams::very_fast_build()),
    ("fast", BvhBuildParams::fast_build()),
    ("medium", BvhBuildParams::medium_build()),
    ("slow", BvhBuildParams::slow_build()),
    ("very_slow", BvhBuildParams::very_slow_build()),
];

/// A BVH over `aabbs` whose leaves lie at most `max_depth` levels deep (the root is level 1),
/// and the time the build took.
pub fn build_bvh(aabbs: &[Aabb], max_depth: usize) -> (Bvh2, Duration) {
    build_bvh_with(aabbs, BvhBuildParams::medium_build(), max_depth)
}

/// [`build_bvh`] with the given obvhs parameters (see [`PRESETS`]).
pub fn build_bvh_with(
    aabbs: &[Aabb],
    params: BvhBuildParams,
    max_depth: usize,
) -> (Bvh2, Duration) {
    let start = Instant::now();
    if aabbs.is_empty() {
        return (Bvh2::default(), start.elapsed());
    }
    let mut core_time = Duration::ZERO;
    let bvh = obvhs::bvh2::builder::build_bvh2(aabbs, params, &mut core_time);
    let bvh = if tree_depth(&bvh.nodes) > max_depth {
        bound_depth(&bvh, aabbs, max_depth)
    } else {
        bvh
    };
    (bvh, start.elapsed())
}

/// Levels of the longest root-to-leaf path (a lone leaf has depth 1; no nodes, 0).
pub fn tree_depth(nodes: &[Bvh2Node]) -> usize {
    if nodes.is_empty() {
        return 0;
    }
    let mut deepest = 0;
    let mut stack = vec![(0usize, 1usize)];
    while let Some((index, depth)) = stack.pop() {
        deepest = deepest.max(depth);
        let node = &nodes[index];
        if node.prim_count == 0 {
            stack.push((node.first_index as usize, depth + 1));
            stack.push((node.first_index as usize + 1, depth + 1));
        }
    }
    deepest
}

/// Expected loop iterations of one traversal of a ray that enters the root box, by the surface
/// area heuristic: a node is entered with probability area(node) / area(root); entering an
/// inner node costs one iteration (its children's pair test), a leaf one per primitive. This is
/// the tree's SAH cost with unit traversal and intersection costs. The render driver sizes
/// dispatches from it (`render::plan_passes`), since lavapipe cuts an invocation's loops after
/// 65535 iterations in total.
pub fn expected_traversal_iterations(nodes: &[Bvh2Node]) -> f32 {
    let Some(root) = nodes.first() else {
        return 0.0;
    };
    let root_area = root.aabb.half_area().max(f32::MIN_POSITIVE);
    let mut expected = 0.0f64;
    let mut stack = vec![0usize];
    while let Some(index) = stack.pop() {
        let node = &nodes[index];
        let p = (node.aabb.half_area() / root_area).min(1.0) as f64;
        if node.prim_count > 0 {
            expected += p * node.prim_count as f64;
        } else {
            expected += p;
            stack.push(node.first_index as usize);
            stack.push(node.first_index as usize + 1);
        }
    }
    expected as f32
}

/// Height of the balanced tree `rebuild_balanced` makes over `n` primitives.
fn balanced_height(n: usize) -> usize {
    n.max(1).next_power_of_two().trailing_zeros() as usize + 1
}

/// Per node: primitives below it and the height of its subtree.
fn subtree_facts(nodes: &[Bvh2Node]) -> (Vec<usize>, Vec<usize>) {
    let mut count = vec![0; nodes.len()];
    let mut height = vec![0; nodes.len()];
    // Post-order without recursion: children are finished before their parent is.
    let mut stack = vec![(0usize, false)];
    while let Some((index, children_done)) = stack.pop() {
        let node = &nodes[index];
        if node.prim_count > 0 {
            count[index] = node.prim_count as usize;
            height[index] = 1;
        } else if children_done {
            let (left, right) = (node.first_index as usize, node.first_index as usize + 1);
            count[index] = count[left] + count[right];
            height[index] = 1 + height[left].max(height[right]);
        } else {
            stack.push((index, true));
            stack.push((node.first_index as usize, false));
            stack.push((node.first_index as usize + 1, false));
        }
    }
    (count, height)
}

/// A copy of `bvh` with every subtree that would end deeper than `max_depth` rebuilt balanced.
/// A node is kept while both children can still be rebuilt within the bound below it; the
/// root qualifies whenever `balanced_height(all primitives) <= max_depth`.
fn bound_depth(bvh: &Bvh2, aabbs: &[Aabb], max_depth: usize) -> Bvh2 {
    let (count, height) = subtree_facts(&bvh.nodes);
    let mut out = Repacked {
        nodes: vec![Bvh2Node::default()],
        primitive_indices: Vec::with_capacity(bvh.primitive_indices.len()),
    };
    // (old node, slot in the new array, level)
    let mut work = vec![(0usize, 0usize, 1usize)];
    while let Some((old, slot, level)) = work.pop() {
        let node = &bvh.nodes[old];
        if node.prim_count > 0 {
            let first = node.first_index as usize;
            let prims = &bvh.primitive_indices[first..first + node.prim_count as usize];
            out.nodes[slot] = out.leaf(node.aabb, prims);
            continue;
        }
        let (left, right) = (node.first_index as usize, node.first_index as usize + 1);
        let fits_as_is = level + height[old] - 1 <= max_depth;
        let children_fit = level + balanced_height(count[left].max(count[right])) <= max_depth;
        if fits_as_is || children_fit {
            let children = out.nodes.len();
            out.nodes.extend([Bvh2Node::default(); 2]);
            out.nodes[slot] = Bvh2Node {
                aabb: node.aabb,
                prim_count: 0,
                first_index: children as u32,
                ..Default::default()
            };
            work.push((left, children, level + 1));
            work.push((right, children + 1, level + 1));
        } else {
            let mut prims = Vec::with_capacity(count[old]);
            collect_primitives(bvh, old, &mut prims);
            out.rebuild_balanced(slot, &mut prims, aabbs);
        }
    }
    let mut bounded = Bvh2 {
        nodes: out.nodes,
        primitive_indices: out.primitive_indices,
        ..Default::default()
    };
    bounded.max_depth = bounded.max_depth.max(tree_depth(&bounded.nodes) + 1);
    bounded
}

fn collect_primitives(bvh: &Bvh2, root: usize, out: &mut Vec<u32>) {
    let mut stack = vec![root];
    while let Some(index) = stack.pop() {
        let node = &bvh.nodes[index];
        if node.prim_count > 0 {
            let first = node.first_index as usize;
            out.extend_from_slice(&bvh.primitive_indices[first..first + node.prim_count as usize]);
        } else {
            stack.push(node.first_index as usize);
            stack.push(node.first_index as usize + 1);
        }
    }
}

/// The node array and primitive order being written by `bound_depth`.
struct Repacked {
    nodes: Vec<Bvh2Node>,
    primitive_indices: Vec<u32>,
}

impl Repacked {
    fn leaf(&mut self, aabb: Aabb, prims: &[u32]) -> Bvh2Node {
        let first = self.primitive_indices.len() as u32;
        self.primitive_indices.extend_from_slice(prims);
        Bvh2Node {
            aabb,
            prim_count: prims.len() as u32,
            first_index: first,
            ..Default::default()
        }
    }

    /// Writes a balanced tree over `prims` with its root at `slot`: split at the median
    /// centroid along the longest axis of the centroids' bounds, down to single primitives.
    fn rebuild_balanced(&mut self, slot: usize, prims: &mut [u32], aabbs: &[Aabb]) {
        let mut work = vec![(slot, 0usize, prims.len())];
        while let Some((slot, start, end)) = work.pop() {
            let range = &mut prims[start..end];
            let bounds = range
                .iter()
                .fold(Aabb::INVALID, |b, &p| b.union(&aabbs[p as usize]));
            if range.len() == 1 {
                self.nodes[slot] = self.leaf(bounds, range);
                continue;
            }
            let centroids = range.iter().fold(Aabb::INVALID, |b, &p| {
                let c = aabbs[p as usize].center();
                b.union(&Aabb::new(c, c))
            });
            let axis = longest_axis(centroids.max - centroids.min);
            let middle = range.len() / 2;
            range.select_nth_unstable_by(middle, |&a, &b| {
                let ca = aabbs[a as usize].center()[axis];
                let cb = aabbs[b as usize].center()[axis];
                ca.total_cmp(&cb)
            });
            let children = self.nodes.len();
            self.nodes.extend([Bvh2Node::default(); 2]);
            self.nodes[slot] = Bvh2Node {
                aabb: bounds,
                prim_count: 0,
                first_index: children as u32,
                ..Default::default()
            };
            work.push((children, start, start + middle));
            work.push((children + 1, start + middle, end));
        }
    }
}

fn longest_axis(extent: Vec3A) -> usize {
    if extent.x >= extent.y && extent.x >= extent.z {
        0
    } else if extent.y >= extent.z {
        1
    } else {
        2
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn boxes(n: usize, f: impl Fn(usize) -> (Vec3A, Vec3A)) -> Vec<Aabb> {
        (0..n)
            .map(|i| {
                let (a, b) = f(i);
                Aabb::new(a.min(b), a.max(b))
            })
            .collect()
    }

    /// Every primitive is in exactly one leaf, every inner node's box holds its children's,
    /// and the depth is within the bound.
    fn check(bvh: &Bvh2, aabbs: &[Aabb], max_depth: usize) {
        assert!(
            tree_depth(&bvh.nodes) <= max_depth,
            "{}",
            tree_depth(&bvh.nodes)
        );
        let mut seen = vec![0u32; aabbs.len()];
        let mut stack = vec![0usize];
        while let Some(i) = stack.pop() {
            let node = &bvh.nodes[i];
            if node.prim_count > 0 {
                let first = node.first_index as usize;
                for &p in &bvh.primitive_indices[first..first + node.prim_count as usize] {
                    seen[p as usize] += 1;
                    let b = &aabbs[p as usize];
                    assert!(node.aabb.min.cmple(b.min).all() && node.aabb.max.cmpge(b.max).all());
                }
            } else {
                for c in [node.first_index as usize, node.first_index as usize + 1] {
                    let child = &bvh.nodes[c].aabb;
                    assert!(node.aabb.min.cmple(child.min).all());
                    assert!(node.aabb.max.cmpge(child.max).all());
                    stack.push(c);
                }
            }
        }
        assert!(
            seen.iter().all(|&s| s == 1),
            "a primitive is lost or repeated"
        );
    }

    #[test]
    fn nested_slivers_are_bounded_to_any_feasible_depth() {
        // Thin boxes of geometrically growing length, all from the origin: PLOC chains them.
        let aabbs = boxes(400, |i| {
            let l = 1.02f32.powi(i as i32);
            (Vec3A::ZERO, Vec3A::new(l, l * 1e-3, 0.0))
        });
        let (free, _) = build_bvh(&aabbs, usize::MAX);
        assert!(
            tree_depth(&free.nodes) > 64,
            "the test case is no longer deep"
        );
        for max_depth in [64, 20, balanced_height(400)] {
            let (bvh, _) = build_bvh(&aabbs, max_depth);
            check(&bvh, &aabbs, max_depth);
        }
    }

    #[test]
    fn expected_iterations_count_every_node_of_nested_boxes_once() {
        // Identical boxes: every node is entered by every ray that enters the root.
        let aabbs = boxes(8, |_| (Vec3A::ZERO, Vec3A::ONE));
        let (bvh, _) = build_bvh(&aabbs, 64);
        let inner = bvh.nodes.iter().filter(|n| n.prim_count == 0).count();
        let expected = inner as f32 + 8.0;
        assert!((expected_traversal_iterations(&bvh.nodes) - expected).abs() < 1e-4);
        // Disjoint boxes along a line: far fewer than the node count.
        let spread = boxes(1024, |i| {
            let p = Vec3A::new(i as f32 * 10.0, 0.0, 0.0);
            (p, p + 1.0)
        });
        let (bvh, _) = build_bvh(&spread, 64);
        assert!(expected_traversal_iterations(&bvh.nodes) < 0.05 * bvh.nodes.len() as f32);
    }

    #[test]
    fn shallow_trees_are_left_as_obvhs_built_them() {
        let aabbs = boxes(1000, |i| {
            let p = Vec3A::new((i % 10) as f32, (i / 10 % 10) as f32, (i / 100) as f32);
            (p, p + 0.5)
        });
        let (free, _) = build_bvh(&aabbs, usize::MAX);
        let (bounded, _) = build_bvh(&aabbs, 64);
        let facts = |b: &Bvh2| -> Vec<_> {
            b.nodes
                .iter()
                .map(|n| (n.aabb, n.prim_count, n.first_index))
                .collect()
        };
        assert_eq!(facts(&free), facts(&bounded));
        check(&bounded, &aabbs, 64);
    }
}
