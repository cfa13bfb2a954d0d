//! The CPU's wide BVH: the CWBVH's tree (`cwbvh::build`) with each node's eight child boxes
//! dequantised once into f32 planes stored lane by lane, so that one node test is a handful of
//! 8-wide vector operations (AVX2 where the CPU has it, chosen at run time; SSE otherwise)
//! instead of the BVH2's two scalar box tests per node and three times as many nodes.
//! The primitive tests are the ones every path uses (`intersect::intersect_primitive`), the
//! static triangles and quads of a node's leaves tested eight at a time (`octet`: the same
//! tests, lane by lane), so the hits are the BVH2's: the boxes are the CWBVH's, dequantised
//! with the very arithmetic of `cwbvh::child_hits` (`p + e * q`) and tested with
//! `intersect::intersect_box`'s slab test (the same distances: the AVX2 test picks each axis's
//! near and far planes by the ray's direction instead of sorting the two), so a child this
//! traversal skips is one the GPU's CWBVH skips too. Coherent rays can also go through
//! in packets of eight (`packet`), each node tested once for the packet.
//!
//! No GPU twin: the GPU traverses the compressed nodes (`wgsl/traverse_cwbvh.wgsl`), 80 bytes
//! where these take 256, because its bottleneck is memory traffic; a CPU's is the node test.

use std::mem::MaybeUninit;

use glam::Vec3;

use super::cwbvh::CwGeometry;
use super::intersect::{Hit, RayQuery, SLAB_FAR_SCALE, intersect_primitive};
use super::octet::{Octet, QuadOctet, Rows, TriangleOctet};
use super::pages::on_huge_pages;
use super::planes::{closest_plane, plane_occludes};
use crate::layout::{
    CWBVH_STACK_SIZE, FEATURE_TRIANGLES, GpuCwNode, GpuPrimitive, NONE, PRIM_QUAD, PRIM_TRIANGLE,
    has,
};

mod packet;
mod stream;
pub use packet::PACKET;
pub use stream::IN_FLIGHT;

/// Lanes of a node: the CWBVH's eight children.
const LANES: usize = 8;
/// A child code with this bit is a leaf: primitives `code & LEAF_FIRST` onwards, `(code >>
/// LEAF_COUNT_SHIFT) & 3` of them (a CWBVH leaf holds one to three).
const LEAF: u32 = 1 << 31;
const LEAF_COUNT_SHIFT: u32 = 29;
const LEAF_FIRST: u32 = (1 << LEAF_COUNT_SHIFT) - 1;
/// Entries the traversal stack can hold: each level of the tree pushes at most seven siblings.
const STACK_ENTRIES: usize = (LANES - 1) * CWBVH_STACK_SIZE as usize + 1;

/// One node: its children's boxes as planes (`planes[axis][lane]` their lower bounds,
/// `planes[3 + axis][lane]` their upper ones), what each child is, and the octets that hold its
/// leaves' static triangles and quads.
#[derive(Clone, Copy, Debug, Default)]
#[repr(C, align(64))]
struct WideNode {
    planes: [[f32; LANES]; 6],
    /// Per lane: an inner child's node index, or a leaf's `LEAF` code.
    child: [u32; LANES],
    /// Bit per lane: the lane holds a child.
    valid: u32,
    /// Bit per lane: a leaf whose triangles are in the octets from `octet_start` on, or whose
    /// quads are in those from `quad_start` on (it is never pushed); the other leaves hold
    /// another kind of primitive, several kinds, or moving ones.
    packed: u32,
    /// The node's first octet in `WideBvh::octets`.
    octet_start: u32,
    /// The node's octets: as many as its packed leaves' triangles fill, eight a piece.
    octet_count: u32,
    /// The node's first quad octet in `WideBvh::quads`.
    quad_start: u32,
    /// The node's quad octets.
    quad_count: u32,
    /// Per octet of the node's triangles: the bits of the leaves it holds, so that the
    /// octets of the leaves a test missed are passed over without reading them.
    octet_leaves: [u8; LANES],
}

// Four cache lines a node.
const _: () = assert!(std::mem::size_of::<WideNode>() == 256);

/// The wide BVH of a scene and the primitives its leaves index.
#[derive(Clone)]
pub struct WideBvh {
    nodes: Vec<WideNode>,
    /// The static triangles of the nodes' leaves, node by node.
    octets: Vec<TriangleOctet>,
    /// The static quads of the nodes' leaves, node by node.
    quads: Vec<QuadOctet>,
    /// Bounded primitives in leaf order, then the planes.
    prims: Vec<GpuPrimitive>,
    /// For each of `prims`, its index in the scene's primitives (`FlatScene::prims`).
    ids: Vec<u32>,
    /// For each of the scene's primitives, its index in `prims` (the inverse of `ids`).
    slot_of: Vec<u32>,
    /// Per bounded primitive in leaf order, its velocity; empty when nothing moves.
    velocities: Vec<Vec3>,
    plane_start: u32,
    plane_count: u32,
    /// The CPU runs the AVX2 build of the traversal.
    avx2: bool,
    /// The CPU has AVX-512F too: packets test a triangle against all their rays at once.
    avx512: bool,
}

impl WideBvh {
    /// The wide BVH of `cw`, whose primitives were built from `scene_prims` (the scene's order;
    /// the velocity records at `motion_base` when it is not 0). Fails when there are more
    /// primitives than a leaf code can address.
    pub fn build(
        cw: &CwGeometry,
        scene_prims: &[GpuPrimitive],
        motion_base: u32,
    ) -> Result<Self, String> {
        let count = cw.plane_start as usize + cw.plane_count as usize;
        if count > LEAF_FIRST as usize {
            return Err(format!(
                "{count} primitives: the CPU's wide BVH addresses at most {LEAF_FIRST}"
            ));
        }
        let slot_of: Vec<u32> = (0..count as u32).map(|i| cw.new_index(i)).collect();
        let mut ids = vec![NONE; count];
        for (scene_index, &slot) in slot_of.iter().enumerate() {
            ids[slot as usize] = scene_index as u32;
        }
        let velocities = if motion_base == 0 {
            Vec::new()
        } else {
            ids[..cw.plane_start as usize]
                .iter()
                .map(|&i| Vec3::from(scene_prims[(motion_base + i) as usize].p0))
                .collect()
        };
        let mut nodes: Vec<WideNode> = cw.nodes.iter().map(wide_node).collect();
        let prims = cw.prims[..count].to_vec();
        let (octets, quads) = pack_octets(&mut nodes, &prims, !velocities.is_empty());
        Ok(WideBvh {
            nodes: on_huge_pages(nodes),
            octets: on_huge_pages(octets),
            quads: on_huge_pages(quads),
            prims: on_huge_pages(prims),
            ids,
            slot_of,
            velocities,
            plane_start: cw.plane_start,
            plane_count: cw.plane_count,
            avx2: avx2_available(),
            avx512: avx512_available(),
        })
    }

    /// Closest intersection along `ray` before `t_max`, ignoring the scene's primitive `skip`:
    /// (index in the scene's primitives, hit), as `traverse::closest_hit` finds it.
    pub fn closest_hit<const F: u32>(
        &self,
        ray: &RayQuery,
        skip: u32,
        t_max: f32,
    ) -> Option<(u32, Hit)> {
        let skip = self.slot(skip);
        #[cfg(target_arch = "x86_64")]
        if self.avx2 {
            // SAFETY: `avx2` is set only where the CPU reports AVX2.
            return unsafe { closest_hit_avx2::<F>(self, ray, skip, t_max) };
        }
        closest_hit_inline::<F>(self, ray, skip, t_max)
    }

    /// Whether anything but the scene's primitives `skip_a` and `skip_b` lies along `ray`
    /// before `t_max`, as `traverse::occluded` says.
    pub fn occluded<const F: u32>(
        &self,
        ray: &RayQuery,
        skip_a: u32,
        skip_b: u32,
        t_max: f32,
    ) -> bool {
        let skip = [self.slot(skip_a), self.slot(skip_b)];
        #[cfg(target_arch = "x86_64")]
        if self.avx2 {
            // SAFETY: as in `closest_hit`.
            return unsafe { occluded_avx2::<F>(self, ray, skip, t_max) };
        }
        occluded_inline::<F>(self, ray, skip, t_max)
    }

    /// The slot in `prims` of the scene's primitive `index` (`NONE` stays `NONE`).
    fn slot(&self, index: u32) -> u32 {
        match index {
            NONE => NONE,
            i => self.slot_of[i as usize],
        }
    }

    /// The triangle octets of `node`.
    #[inline(always)]
    fn triangles_of(&self, node: &WideNode) -> &[TriangleOctet] {
        let start = node.octet_start as usize;
        &self.octets[start..start + node.octet_count as usize]
    }

    /// The triangle octets of `node` that hold a leaf of `mask`, chosen by the node's
    /// `octet_leaves`.
    #[inline(always)]
    fn triangles_in<'a>(
        &'a self,
        node: &'a WideNode,
        mask: u32,
    ) -> impl Iterator<Item = &'a TriangleOctet> + 'a {
        self.triangles_of(node)
            .iter()
            .zip(node.octet_leaves)
            .filter(move |&(_, leaves)| u32::from(leaves) & mask != 0)
            .map(|(octet, _)| octet)
    }

    /// The quad octets of `node` that hold a leaf of `mask`.
    #[inline(always)]
    fn quads_in<'a>(
        &'a self,
        node: &'a WideNode,
        mask: u32,
    ) -> impl Iterator<Item = &'a QuadOctet> + 'a {
        self.quads_of(node)
            .iter()
            .filter(move |octet| octet.leaves & mask != 0)
    }

    /// The quad octets of `node`.
    #[inline(always)]
    fn quads_of(&self, node: &WideNode) -> &[QuadOctet] {
        let start = node.quad_start as usize;
        &self.quads[start..start + node.quad_count as usize]
    }

    fn planes(&self) -> std::ops::Range<u32> {
        self.plane_start..self.plane_start + self.plane_count
    }

    /// `ray` where leaf primitive `slot` is at the ray's time (itself in a static scene).
    fn ray_for(&self, ray: &RayQuery, slot: u32) -> RayQuery {
        match self.velocities.get(slot as usize) {
            Some(&v) => ray.relative_to(v * ray.time),
            None => *ray,
        }
    }
}

fn avx2_available() -> bool {
    #[cfg(target_arch = "x86_64")]
    {
        std::arch::is_x86_feature_detected!("avx2")
    }
    #[cfg(not(target_arch = "x86_64"))]
    {
        false
    }
}

fn avx512_available() -> bool {
    #[cfg(target_arch = "x86_64")]
    {
        avx2_available() && std::arch::is_x86_feature_detected!("avx512f")
    }
    #[cfg(not(target_arch = "x86_64"))]
    {
        false
    }
}

/// Byte `i` (0..8) of a pair of little-endian words.
fn byte(words: [u32; 2], i: usize) -> u32 {
    (words[i / 4] >> ((i % 4) * 8)) & 0xff
}

/// A CWBVH node with its children's boxes dequantised as `cwbvh::child_hits` does.
fn wide_node(node: &GpuCwNode) -> WideNode {
    let scale = |shift: u32| f32::from_bits(((node.e_imask >> shift) & 0xff) << 23);
    let e = Vec3::new(scale(0), scale(8), scale(16));
    let p = Vec3::from(node.p);
    let inner_mask = node.e_imask >> 24;
    let mut wide = WideNode::default();
    for lane in 0..LANES {
        let meta = byte(node.child_meta, lane);
        if meta == 0 {
            continue;
        }
        let q = |words: [u32; 2]| byte(words, lane) as f32;
        let lo = p + e * Vec3::new(q(node.q_lo_x), q(node.q_lo_y), q(node.q_lo_z));
        let hi = p + e * Vec3::new(q(node.q_hi_x), q(node.q_hi_y), q(node.q_hi_z));
        for axis in 0..3 {
            wide.planes[axis][lane] = lo[axis];
            wide.planes[3 + axis][lane] = hi[axis];
        }
        wide.valid |= 1 << lane;
        wide.child[lane] = if meta & (meta << 1) & 0x10 != 0 {
            // An inner child: the slot in `meta`; inner children are consecutive from
            // `child_base` in slot order.
            let slot = (meta & 0x1f) - 24;
            node.child_base + (inner_mask & ((1 << slot) - 1)).count_ones()
        } else {
            let first = node.prim_base + (meta & 0x1f);
            LEAF | ((meta >> 5).count_ones() << LEAF_COUNT_SHIFT) | first
        };
    }
    wide
}

/// Packs the triangles of each node's leaves that hold only triangles into octets, and the
/// quads of those that hold only quads into quad octets, node by node (none when primitives
/// move: their rays are moved per primitive), and marks those leaves `packed`.
fn pack_octets(
    nodes: &mut [WideNode],
    prims: &[GpuPrimitive],
    moving: bool,
) -> (Vec<TriangleOctet>, Vec<QuadOctet>) {
    let (mut octets, mut quad_octets) = (Vec::new(), Vec::new());
    if moving {
        return (octets, quad_octets);
    }
    for node in nodes.iter_mut() {
        let (mut triangles, mut quads) = (Vec::new(), Vec::new());
        for lane in 0..LANES {
            let code = node.child[lane];
            if node.valid & (1 << lane) == 0 || code & LEAF == 0 {
                continue;
            }
            let slots = leaf_slots(code);
            let entries = slots
                .clone()
                .map(|slot| (slot, &prims[slot as usize], lane as u32));
            let all = |kind| slots.clone().all(|slot| prims[slot as usize].kind == kind);
            if all(PRIM_TRIANGLE) {
                node.packed |= 1 << lane;
                triangles.extend(entries);
            } else if all(PRIM_QUAD) {
                node.packed |= 1 << lane;
                quads.extend(entries);
            }
        }
        node.octet_start = octets.len() as u32;
        octets.extend(
            triangles
                .chunks(super::octet::LANES)
                .map(TriangleOctet::pack),
        );
        node.octet_count = octets.len() as u32 - node.octet_start;
        // Eight leaves of at most three triangles fill three octets: within `octet_leaves`.
        for (leaves, octet) in node
            .octet_leaves
            .iter_mut()
            .zip(&octets[node.octet_start as usize..])
        {
            *leaves = octet.leaves as u8;
        }
        node.quad_start = quad_octets.len() as u32;
        quad_octets.extend(quads.chunks(super::octet::LANES).map(QuadOctet::pack));
        node.quad_count = quad_octets.len() as u32 - node.quad_start;
    }
    (octets, quad_octets)
}

/// The primitive slots of a leaf's code.
fn leaf_slots(code: u32) -> std::ops::Range<u32> {
    let first = code & LEAF_FIRST;
    first..first + ((code >> LEAF_COUNT_SHIFT) & 3)
}

fn min(a: f32, b: f32) -> f32 {
    if a < b { a } else { b }
}

fn max(a: f32, b: f32) -> f32 {
    if a > b { a } else { b }
}

/// The end of a child's slab test, from its entry and exit distances: the exit (scaled by
/// `SLAB_FAR_SCALE`) is neither before the entry nor behind the ray, and the entry is before
/// `t_max`. (`slab_hits_avx2` is the same on eight children.)
#[inline(always)]
fn slab_hit(t_near: f32, t_far: f32, t_max: f32) -> bool {
    let t_far = t_far * SLAB_FAR_SCALE;
    t_far >= t_near && t_far >= 0.0 && t_near < t_max
}

/// The slab test of `intersect::intersect_box` on the eight children at once: a bit per child
/// hit before `t_max`, and each child's entry distance. Lane loops the compiler vectorises
/// (no NaN can arise: the reciprocals are finite and non-zero, the planes finite).
#[inline(always)]
fn node_hits(node: &WideNode, origin: [f32; 3], inv: [f32; 3], t_max: f32) -> (u32, [f32; LANES]) {
    let mut near = [0.0; LANES];
    let mut mask = 0;
    for (lane, near) in near.iter_mut().enumerate() {
        let mut t_near = f32::NEG_INFINITY;
        let mut t_far = f32::INFINITY;
        for axis in 0..3 {
            let t1 = (node.planes[axis][lane] - origin[axis]) * inv[axis];
            let t2 = (node.planes[3 + axis][lane] - origin[axis]) * inv[axis];
            t_near = max(t_near, min(t1, t2));
            t_far = min(t_far, max(t1, t2));
        }
        *near = t_near;
        mask |= (slab_hit(t_near, t_far, t_max) as u32) << lane;
    }
    (mask & node.valid, near)
}

/// The rows of a node's planes a ray enters and leaves each axis's slab by: the lower
/// bounds' rows where its direction is positive on that axis, the upper ones' where negative.
#[derive(Clone, Copy)]
struct Slabs {
    near: [usize; 3],
    far: [usize; 3],
}

impl Slabs {
    #[inline(always)]
    fn of(inv: [f32; 3]) -> Slabs {
        // Arithmetic on the signs, not a branch or a remainder: this runs for every ray.
        let backward = inv.map(|i| 3 * (i < 0.0) as usize);
        Slabs {
            near: [backward[0], 1 + backward[1], 2 + backward[2]],
            far: [3 - backward[0], 4 - backward[1], 5 - backward[2]],
        }
    }
}

/// [`node_hits`] in AVX2 intrinsics, with the same results: where the direction is positive
/// on an axis, `(lo - o) * inv <= (hi - o) * inv` (rounding is monotonic), so the lane
/// loop's `min` and `max` of the two are the near and far planes' distances, which `slabs`
/// names once per ray instead of sorting them at every node; `max` and `min` of the three
/// axes are exact in any order. The hit bits are taken by one `movemask` where the
/// compiler's version of the lane loop reduced them by shuffles.
#[cfg(target_arch = "x86_64")]
#[target_feature(enable = "avx2")]
#[inline]
fn node_hits_avx2(
    node: &WideNode,
    origin: [f32; 3],
    inv: [f32; 3],
    slabs: Slabs,
    t_max: f32,
) -> (u32, [f32; LANES]) {
    use std::arch::x86_64::*;
    let distance = |row: usize, axis: usize| {
        // SAFETY: `Slabs::of` names rows 0 to 5 only (checking them cost 6 branches a node);
        // a row is eight f32s.
        let plane = unsafe { _mm256_loadu_ps(node.planes.get_unchecked(row).as_ptr()) };
        _mm256_mul_ps(
            _mm256_sub_ps(plane, _mm256_set1_ps(origin[axis])),
            _mm256_set1_ps(inv[axis]),
        )
    };
    let near = |axis| distance(slabs.near[axis], axis);
    let far = |axis| distance(slabs.far[axis], axis);
    let t_near = _mm256_max_ps(_mm256_max_ps(near(0), near(1)), near(2));
    let t_far = _mm256_min_ps(_mm256_min_ps(far(0), far(1)), far(2));
    slab_hits_avx2(t_near, t_far, t_max, node.valid)
}

/// The end of an eight-child slab test in AVX2, from each child's entry and exit distances: a
/// bit per child of `valid` whose exit (scaled by `SLAB_FAR_SCALE`) is neither before its entry
/// nor behind the ray and whose entry is before `t_max`, and the entry distances.
#[cfg(target_arch = "x86_64")]
#[target_feature(enable = "avx2")]
#[inline]
fn slab_hits_avx2(
    t_near: std::arch::x86_64::__m256,
    t_far: std::arch::x86_64::__m256,
    t_max: f32,
    valid: u32,
) -> (u32, [f32; LANES]) {
    use std::arch::x86_64::*;
    let t_far = _mm256_mul_ps(t_far, _mm256_set1_ps(SLAB_FAR_SCALE));
    let hit = _mm256_and_ps(
        _mm256_and_ps(
            _mm256_cmp_ps::<_CMP_GE_OQ>(t_far, t_near),
            _mm256_cmp_ps::<_CMP_GE_OQ>(t_far, _mm256_setzero_ps()),
        ),
        _mm256_cmp_ps::<_CMP_LT_OQ>(t_near, _mm256_set1_ps(t_max)),
    );
    let mut near = [0.0; LANES];
    // SAFETY: `near` holds eight f32s.
    unsafe { _mm256_storeu_ps(near.as_mut_ptr(), t_near) };
    (_mm256_movemask_ps(hit) as u32 & valid, near)
}

/// The node test of the build in use: AVX2 intrinsics, or the lane loop.
#[inline(always)]
fn test_node(
    node: &WideNode,
    origin: [f32; 3],
    inv: [f32; 3],
    slabs: Slabs,
    t_max: f32,
    avx2: bool,
) -> (u32, [f32; LANES]) {
    #[cfg(target_arch = "x86_64")]
    if avx2 {
        // SAFETY: `avx2` is true only where the CPU has AVX2.
        return unsafe { node_hits_avx2(node, origin, inv, slabs, t_max) };
    }
    let _ = (avx2, slabs);
    node_hits(node, origin, inv, t_max)
}

/// Asks the cache for an inner child's node while the ray works on its siblings.
#[inline(always)]
fn prefetch(nodes: &[WideNode], code: u32) {
    #[cfg(target_arch = "x86_64")]
    if code & LEAF == 0 {
        use std::arch::x86_64::{_MM_HINT_T0, _mm_prefetch};
        let node = (&nodes[code as usize] as *const WideNode).cast::<i8>();
        // SAFETY: prefetching is a hint; the address is the node's own.
        unsafe {
            for line in 0..4 {
                _mm_prefetch::<_MM_HINT_T0>(node.add(64 * line));
            }
        }
    }
}

/// Asks the cache for every line of a node's octets (which of them hold a hit leaf is known
/// only once they are read).
#[inline(always)]
fn prefetch_octets(bvh: &WideBvh, node: &WideNode) {
    prefetch_lines(bvh.triangles_of(node));
    prefetch_lines(bvh.quads_of(node));
}

/// Asks the cache for every line of `items`.
#[inline(always)]
fn prefetch_lines<T>(items: &[T]) {
    #[cfg(target_arch = "x86_64")]
    {
        use std::arch::x86_64::{_MM_HINT_T0, _mm_prefetch};
        let start = items.as_ptr().cast::<i8>();
        for offset in (0..std::mem::size_of_val(items)).step_by(64) {
            // SAFETY: prefetching is a hint; the addresses are within the items.
            unsafe { _mm_prefetch::<_MM_HINT_T0>(start.add(offset)) };
        }
    }
    #[cfg(not(target_arch = "x86_64"))]
    let _ = items;
}

/// The traversal stack: (child code, entry distance) pairs. The array is left uninitialised
/// and only entries below `len` are ever read: zeroing its 1.8 KB for every ray cost 4% of a
/// frame of a few primitives (`cornell_direct`, where two traversals a sample are short).
struct Stack {
    entries: [MaybeUninit<(u32, f32)>; STACK_ENTRIES],
    len: usize,
}

impl Stack {
    #[inline(always)]
    fn empty() -> Stack {
        Stack {
            entries: [const { MaybeUninit::uninit() }; STACK_ENTRIES],
            len: 0,
        }
    }

    /// A stack holding the root of `nodes`, unless it is empty (a scene of planes only).
    #[inline(always)]
    fn at_root(nodes: &[WideNode]) -> Stack {
        let mut stack = Stack::empty();
        if nodes[0].valid != 0 {
            stack.push((0, f32::NEG_INFINITY));
        }
        stack
    }

    #[inline(always)]
    fn push(&mut self, entry: (u32, f32)) {
        self.entries[self.len] = MaybeUninit::new(entry);
        self.len += 1;
    }

    #[inline(always)]
    fn pop(&mut self) -> Option<(u32, f32)> {
        self.len = self.len.checked_sub(1)?;
        // SAFETY: the entry was below the length before, so it has been written.
        Some(unsafe { self.entries[self.len].assume_init() })
    }

    /// Entry `i`, below `len`.
    #[inline(always)]
    fn get(&self, i: usize) -> (u32, f32) {
        debug_assert!(i < self.len);
        // SAFETY: every entry below `len` has been written by `push` or `push_nearest_last`.
        unsafe { self.entries[i].assume_init() }
    }

    /// Pushes the children of `mask` so that the nearest is popped first (insertion by
    /// distance among at most eight), asking the cache for each inner child's node.
    #[inline(always)]
    fn push_nearest_last(
        &mut self,
        nodes: &[WideNode],
        node: &WideNode,
        mut mask: u32,
        near: &[f32; LANES],
    ) {
        let base = self.len;
        while mask != 0 {
            let lane = mask.trailing_zeros() as usize;
            mask &= mask - 1;
            let entry = (node.child[lane], near[lane]);
            prefetch(nodes, entry.0);
            // Farthest first: shift nearer entries up.
            let mut at = self.len;
            while at > base && self.get(at - 1).1 < entry.1 {
                self.entries[at] = self.entries[at - 1];
                at -= 1;
            }
            self.entries[at] = MaybeUninit::new(entry);
            self.len += 1;
        }
    }
}

/// For each 8-bit mask, the lanes of its set bits in ascending order, three bits a lane: the
/// permutation that packs those lanes of a vector to its front.
const PACK_LANES: [u32; 256] = {
    let mut table = [0; 256];
    let mut mask = 0;
    while mask < 256 {
        let (mut lanes, mut at, mut lane) = (0, 0, 0);
        while lane < LANES {
            if mask & (1 << lane) != 0 {
                lanes |= (lane as u32) << (3 * at);
                at += 1;
            }
            lane += 1;
        }
        table[mask] = lanes;
        mask += 1;
    }
    table
};

/// The stack of an any-hit traversal: child codes only (the order does not matter, so no
/// distances), pushed eight lanes at a time and kept with eight spare slots for it.
struct CodeStack {
    codes: [MaybeUninit<u32>; STACK_ENTRIES + LANES],
    len: usize,
}

impl CodeStack {
    #[inline(always)]
    fn empty() -> CodeStack {
        CodeStack {
            codes: [const { MaybeUninit::uninit() }; STACK_ENTRIES + LANES],
            len: 0,
        }
    }

    #[inline(always)]
    fn pop(&mut self) -> Option<u32> {
        self.len = self.len.checked_sub(1)?;
        // SAFETY: the slot was below the length before, so it has been written.
        Some(unsafe { self.codes[self.len].assume_init() })
    }

    /// Pushes the children of `mask` in lane order but the last, which it returns: the child
    /// popped next anyway, visited without a trip through the stack. Two or more are pushed
    /// with AVX2 by one permutation and one store of all eight lanes, the length then raised
    /// by the count: a loop over the set bits mispredicted its exit at a third of the any-hit
    /// traversal's mispredicted branches. One is stored alone: the vector store for every
    /// count made the camera's shadow rays 16% slower (docs/embree.md).
    #[inline(always)]
    fn push_children(&mut self, node: &WideNode, mask: u32, avx2: bool) -> Option<u32> {
        if mask == 0 {
            return None;
        }
        let last = 31 - mask.leading_zeros() as usize;
        let mask = mask & !(1 << last);
        // The depth bound (`cwbvh::build`) keeps the stack within `STACK_ENTRIES`; the eight
        // lanes written at once need the spare slots above that.
        assert!(self.len <= STACK_ENTRIES, "the traversal stack overflowed");
        #[cfg(target_arch = "x86_64")]
        if avx2 && mask & (mask.wrapping_sub(1)) != 0 {
            // SAFETY: `avx2` is true only where the CPU has AVX2.
            unsafe { self.push_children_avx2(node, mask) };
            return Some(node.child[last]);
        }
        let _ = avx2;
        let mut mask = mask;
        while mask != 0 {
            let lane = mask.trailing_zeros() as usize;
            mask &= mask - 1;
            self.codes[self.len] = MaybeUninit::new(node.child[lane]);
            self.len += 1;
        }
        Some(node.child[last])
    }

    #[cfg(target_arch = "x86_64")]
    #[target_feature(enable = "avx2")]
    #[inline]
    fn push_children_avx2(&mut self, node: &WideNode, mask: u32) {
        use std::arch::x86_64::*;
        let lanes = _mm256_and_si256(
            _mm256_srlv_epi32(
                _mm256_set1_epi32(PACK_LANES[mask as usize & 0xff] as i32),
                _mm256_setr_epi32(0, 3, 6, 9, 12, 15, 18, 21),
            ),
            _mm256_set1_epi32(7),
        );
        // SAFETY: `child` is eight u32s; `len <= STACK_ENTRIES` (asserted by the caller)
        // leaves eight slots from `len` on.
        unsafe {
            let children = _mm256_loadu_si256(node.child.as_ptr().cast());
            let packed = _mm256_permutevar8x32_epi32(children, lanes);
            _mm256_storeu_si256(self.codes.as_mut_ptr().add(self.len).cast(), packed);
        }
        self.len += mask.count_ones() as usize;
    }
}

/// The nearest hit nearer than `best` in `octets`, but in slot `skip`, taken in lane order (as
/// the leaves' own loop would take them: the first of equal distances).
#[inline(always)]
fn nearest_in<'a, R: Rows + 'a>(
    octets: impl Iterator<Item = &'a Octet<R>>,
    ray: &RayQuery,
    skip: u32,
    best: &mut Hit,
    best_slot: &mut u32,
    avx2: bool,
) {
    for octet in octets {
        let lanes = octet.lanes & !octet.skipping(skip, avx2);
        let (mut hits, found) = octet.hits::<[Hit; LANES]>(ray, best.t, lanes, avx2);
        while hits != 0 {
            let lane = hits.trailing_zeros() as usize;
            hits &= hits - 1;
            if found[lane].t < best.t {
                *best = found[lane];
                *best_slot = octet.slot[lane];
            }
        }
    }
}

/// Whether anything but slots `skip` in `octets` lies along `ray` before `t_max`.
#[inline(always)]
fn any_in<'a, R: Rows + 'a>(
    octets: impl Iterator<Item = &'a Octet<R>>,
    ray: &RayQuery,
    skip: [u32; 2],
    t_max: f32,
    avx2: bool,
) -> bool {
    // A `for` loop: `Iterator::any` went through a `try_fold` the compiler kept out of line,
    // compiled without AVX2.
    for octet in octets {
        let skipped = octet.skipping(skip[0], avx2) | octet.skipping(skip[1], avx2);
        let lanes = octet.lanes & !skipped;
        if octet.hits::<()>(ray, t_max, lanes, avx2).0 != 0 {
            return true;
        }
    }
    false
}

/// A node's children's box test: a bit per child hit, and each child's entry distance.
#[derive(Clone, Copy)]
struct Opened {
    mask: u32,
    near: [f32; LANES],
}

/// One ray's closest-hit traversal, one visit (a node, or a leaf of other primitives) a
/// [`step`](Self::step): the one-ray query steps it to its end; a stream (`stream`) steps
/// several in turn, so that while one ray's next node comes from memory the others work.
/// Its stack is kept apart: in one struct with it, the ray's fields were reloaded from memory
/// at every step (12 instructions a visit).
struct ClosestSearch<'r> {
    ray: &'r RayQuery,
    origin: [f32; 3],
    inv: [f32; 3],
    slabs: Slabs,
    skip: u32,
    best: Hit,
    best_slot: u32,
    /// The code visited next, `NONE` once the search is over: no child's code is `NONE` (a
    /// leaf's first slot is below `LEAF_FIRST`, which `build` checks).
    code: u32,
}

impl<'r> ClosestSearch<'r> {
    /// The search for `ray`'s closest hit before `t_max` but slot `skip`, at the root (over at
    /// once in a scene of planes only, whose root is empty).
    #[inline(always)]
    fn new(bvh: &WideBvh, ray: &'r RayQuery, skip: u32, t_max: f32) -> Self {
        let inv = ray.inv_direction.to_array();
        ClosestSearch {
            ray,
            origin: ray.origin.to_array(),
            inv,
            slabs: Slabs::of(inv),
            skip,
            best: Hit {
                t: t_max,
                b1: 0.0,
                b2: 0.0,
            },
            best_slot: NONE,
            code: if bvh.nodes[0].valid == 0 { NONE } else { 0 },
        }
    }

    fn running(&self) -> bool {
        self.code != NONE
    }

    /// Visits the code in hand (the search must be running) and takes the next: the nearest
    /// hit child directly, else the nearest entry of the stack nearer than the best hit.
    /// Whether the search goes on.
    #[inline(always)]
    fn step<const F: u32>(&mut self, bvh: &WideBvh, stack: &mut Stack) -> bool {
        let code = self.code;
        if code & LEAF != 0 {
            self.test_leaf::<F>(bvh, code);
            return self.pop(stack);
        }
        let node = &bvh.nodes[code as usize];
        let opened = self.open(bvh, node);
        self.test_octets::<F>(bvh, node, opened.mask);
        self.descend(bvh, node, &opened, stack)
    }

    /// The node's children's box test.
    #[inline(always)]
    fn open(&self, bvh: &WideBvh, node: &WideNode) -> Opened {
        let (origin, inv, slabs) = (self.origin, self.inv, self.slabs);
        let (mask, near) = test_node(node, origin, inv, slabs, self.best.t, bvh.avx2);
        Opened { mask, near }
    }

    /// Takes the nearest of the stack's entries nearer than the best hit, if any.
    #[inline(always)]
    fn pop(&mut self, stack: &mut Stack) -> bool {
        self.code = NONE;
        while let Some((next, t_near)) = stack.pop() {
            if t_near < self.best.t {
                self.code = next;
                break;
            }
        }
        self.running()
    }

    /// Goes on from a node whose octets are tested: to the child [`Self::descend_to`] names,
    /// else to the stack's next entry.
    #[inline(always)]
    fn descend(
        &mut self,
        bvh: &WideBvh,
        node: &WideNode,
        opened: &Opened,
        stack: &mut Stack,
    ) -> bool {
        match self.descend_to(bvh, node, opened, stack) {
            Some(next) => {
                self.code = next;
                true
            }
            None => self.pop(stack),
        }
    }

    /// The primitives of a leaf that is not packed, one by one.
    #[inline(always)]
    fn test_leaf<const F: u32>(&mut self, bvh: &WideBvh, code: u32) {
        for slot in leaf_slots(code) {
            if slot == self.skip {
                continue;
            }
            let moved = bvh.ray_for(self.ray, slot);
            let prim = &bvh.prims[slot as usize];
            let hit = intersect_primitive::<F>(&moved, prim, self.best.t);
            if hit.t < self.best.t {
                self.best = hit;
                self.best_slot = slot;
            }
        }
    }

    /// The octets of `node`'s packed leaves among the hit children `mask`.
    #[inline(always)]
    fn test_octets<const F: u32>(&mut self, bvh: &WideBvh, node: &WideNode, mask: u32) {
        if mask & node.packed != 0 {
            let (ray, skip, avx2) = (self.ray, self.skip, bvh.avx2);
            let (best, best_slot) = (&mut self.best, &mut self.best_slot);
            if has(F, FEATURE_TRIANGLES) {
                let triangles = bvh.triangles_in(node, mask);
                nearest_in(triangles, ray, skip, best, best_slot, avx2);
            }
            nearest_in(bvh.quads_in(node, mask), ray, skip, best, best_slot, avx2);
        }
    }

    /// The hit inner child of an opened node to visit next without a trip through the
    /// stack, if any (the others wait there, farthest first).
    #[inline(always)]
    fn descend_to(
        &mut self,
        bvh: &WideBvh,
        node: &WideNode,
        opened: &Opened,
        stack: &mut Stack,
    ) -> Option<u32> {
        let (mask, near) = (opened.mask, &opened.near);
        let inner = mask & !node.packed;
        if inner == 0 {
            return None;
        }
        let first = inner.trailing_zeros() as usize;
        let rest = inner & (inner - 1);
        let nearer = if rest == 0 {
            first
        } else if rest & (rest - 1) == 0 {
            let second = rest.trailing_zeros() as usize;
            // The order `push_nearest_last` gives two: the later lane first at a tie.
            let (nearer, farther) = if near[first] < near[second] {
                (first, second)
            } else {
                (second, first)
            };
            prefetch(&bvh.nodes, node.child[farther]);
            stack.push((node.child[farther], near[farther]));
            nearer
        } else {
            stack.push_nearest_last(&bvh.nodes, node, inner, near);
            return None;
        };
        if near[nearer] >= self.best.t {
            return None;
        }
        let code = node.child[nearer];
        prefetch(&bvh.nodes, code);
        Some(code)
    }

    /// The search's result once it is over: the planes tested, the slot named as the scene's
    /// primitive.
    #[inline(always)]
    fn finish<const F: u32>(self, bvh: &WideBvh) -> Option<(u32, Hit)> {
        self.finish_in_slots::<F>(bvh)
            .map(|(slot, hit)| (bvh.ids[slot as usize], hit))
    }

    /// [`ClosestSearch::finish`] with the hit's slot in the wide BVH's primitives left as it is,
    /// for a caller that names many results' primitives at once.
    #[inline(always)]
    fn finish_in_slots<const F: u32>(mut self, bvh: &WideBvh) -> Option<(u32, Hit)> {
        let (best, best_slot) = (&mut self.best, &mut self.best_slot);
        closest_plane::<F>(
            &bvh.prims,
            bvh.planes(),
            self.ray,
            self.skip,
            best,
            best_slot,
        );
        (self.best_slot != NONE).then_some((self.best_slot, self.best))
    }
}

#[inline(always)]
fn closest_hit_inline<const F: u32>(
    bvh: &WideBvh,
    ray: &RayQuery,
    skip: u32,
    t_max: f32,
) -> Option<(u32, Hit)> {
    let mut search = ClosestSearch::new(bvh, ray, skip, t_max);
    let mut stack = Stack::empty();
    if search.running() {
        while search.step::<F>(bvh, &mut stack) {}
    }
    search.finish::<F>(bvh)
}

/// One ray's any-hit traversal, one visit a [`step`](Self::step), its stack kept apart, as
/// [`ClosestSearch`].
struct AnySearch<'r> {
    ray: &'r RayQuery,
    origin: [f32; 3],
    inv: [f32; 3],
    slabs: Slabs,
    skip: [u32; 2],
    t_max: f32,
    /// The code visited next; none once the search is over.
    visit: Option<u32>,
    /// Something was found (kept for a stream, which finishes the search later).
    found: bool,
}

impl<'r> AnySearch<'r> {
    /// The search for anything but slots `skip` along `ray` before `t_max`, at the root of
    /// `nodes`, with `stack` empty.
    #[inline(always)]
    fn new(nodes: &[WideNode], ray: &'r RayQuery, skip: [u32; 2], t_max: f32) -> Self {
        let inv = ray.inv_direction.to_array();
        AnySearch {
            ray,
            origin: ray.origin.to_array(),
            inv,
            slabs: Slabs::of(inv),
            skip,
            t_max,
            visit: (nodes[0].valid != 0).then_some(0),
            found: false,
        }
    }

    /// Visits `code`, the one `visit` held, and puts the next in `visit` (none when the BVH
    /// has nothing left to visit): whether something lies along the ray (the search is then
    /// over).
    #[inline(always)]
    fn step<const F: u32>(&mut self, bvh: &WideBvh, code: u32, stack: &mut CodeStack) -> bool {
        let (ray, skip, t_max) = (self.ray, self.skip, self.t_max);
        if code & LEAF != 0 {
            for slot in leaf_slots(code) {
                if skip.contains(&slot) {
                    continue;
                }
                let moved = bvh.ray_for(ray, slot);
                let prim = &bvh.prims[slot as usize];
                if intersect_primitive::<F>(&moved, prim, t_max).t < t_max {
                    return true;
                }
            }
            self.visit = stack.pop();
            return false;
        }
        let node = &bvh.nodes[code as usize];
        let mask = self.open(bvh, node);
        self.any_in_octets::<F>(bvh, node, mask) || self.descend(bvh, node, mask, stack)
    }

    /// The node's children's box test: a bit per child hit.
    #[inline(always)]
    fn open(&self, bvh: &WideBvh, node: &WideNode) -> u32 {
        let (origin, inv, slabs) = (self.origin, self.inv, self.slabs);
        test_node(node, origin, inv, slabs, self.t_max, bvh.avx2).0
    }

    /// Whether something in the octets of `node`'s packed leaves among the hit children
    /// `mask` lies along the ray.
    #[inline(always)]
    fn any_in_octets<const F: u32>(&self, bvh: &WideBvh, node: &WideNode, mask: u32) -> bool {
        if mask & node.packed == 0 {
            return false;
        }
        let (ray, skip, t_max, avx2) = (self.ray, self.skip, self.t_max, bvh.avx2);
        let triangles = has(F, FEATURE_TRIANGLES)
            && any_in(bvh.triangles_in(node, mask), ray, skip, t_max, avx2);
        triangles || any_in(bvh.quads_in(node, mask), ray, skip, t_max, avx2)
    }

    /// Goes on from a node whose octets held nothing: to its last hit inner child, the
    /// others pushed, else to the stack's top. Never finds anything (the `false` of `step`).
    #[inline(always)]
    fn descend(
        &mut self,
        bvh: &WideBvh,
        node: &WideNode,
        mask: u32,
        stack: &mut CodeStack,
    ) -> bool {
        self.visit = stack
            .push_children(node, mask & !node.packed, bvh.avx2)
            .or_else(|| stack.pop());
        false
    }

    /// Whether one of the planes lies along the ray, once the BVH held nothing.
    #[inline(always)]
    fn planes_occlude<const F: u32>(&self, bvh: &WideBvh) -> bool {
        let [skip_a, skip_b] = self.skip;
        plane_occludes::<F>(
            &bvh.prims,
            bvh.planes(),
            self.ray,
            skip_a,
            skip_b,
            self.t_max,
        )
    }
}

#[inline(always)]
fn occluded_inline<const F: u32>(
    bvh: &WideBvh,
    ray: &RayQuery,
    skip: [u32; 2],
    t_max: f32,
) -> bool {
    let mut search = AnySearch::new(&bvh.nodes, ray, skip, t_max);
    let mut stack = CodeStack::empty();
    while let Some(code) = search.visit {
        if search.step::<F>(bvh, code, &mut stack) {
            return true;
        }
    }
    search.planes_occlude::<F>(bvh)
}

#[cfg(target_arch = "x86_64")]
#[target_feature(enable = "avx2")]
fn closest_hit_avx2<const F: u32>(
    bvh: &WideBvh,
    ray: &RayQuery,
    skip: u32,
    t_max: f32,
) -> Option<(u32, Hit)> {
    closest_hit_inline::<F>(bvh, ray, skip, t_max)
}

#[cfg(target_arch = "x86_64")]
#[target_feature(enable = "avx2")]
fn occluded_avx2<const F: u32>(bvh: &WideBvh, ray: &RayQuery, skip: [u32; 2], t_max: f32) -> bool {
    occluded_inline::<F>(bvh, ray, skip, t_max)
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::accel::traverse::{closest_hit, occluded};
    use crate::bench::rays::{bounds, incoherent_rays};
    use crate::layout::{FEATURES_ALL, T_FAR};
    use crate::pack::{FlatScene, flatten};
    use crate::scene::sample_scene;

    fn scene(name: &str, overrides: &[&str]) -> FlatScene {
        flatten(&sample_scene(name, overrides))
    }

    /// Every query of the wide BVH, with the AVX2 node test and with the portable one, finds
    /// what the BVH2 finds: the same primitive at the same distance, and the same occlusion,
    /// skipped primitives included (a secondary ray skips the one it leaves).
    fn check(name: &str, flat: &FlatScene) {
        let wide = flat.wide().unwrap();
        let portable = WideBvh {
            avx2: false,
            ..wide.clone()
        };
        let (lo, hi) = bounds(flat);
        let rays = incoherent_rays(lo, hi, 3000, 11);
        let mut hits = 0;
        let mut ties = 0;
        for i in 0..rays.len() {
            let time = (i % 7) as f32 / 7.0;
            let ray = RayQuery::new(rays.origins[i], rays.directions[i]).at_time(time);
            let expected = closest_hit::<FEATURES_ALL>(flat.primitives(), &ray, NONE, T_FAR);
            hits += expected.is_some() as usize;
            // Half the rays skip what they would hit, as a ray leaving that surface does.
            let skip = match (i % 2, expected) {
                (0, Some((id, _))) => id,
                _ => NONE,
            };
            let expected = closest_hit::<FEATURES_ALL>(flat.primitives(), &ray, skip, T_FAR);
            let t_max = expected.map_or(T_FAR, |(_, hit)| hit.t * 1.5);
            let blocked = occluded::<FEATURES_ALL>(flat.primitives(), &ray, skip, NONE, t_max);
            for (build, bvh) in [("avx2", wide), ("portable", &portable)] {
                let found = bvh.closest_hit::<FEATURES_ALL>(&ray, skip, T_FAR);
                // The same distance; another primitive only at a tie (a ray through the edge
                // two triangles share hits both at once, and the first found wins).
                let t = |h: Option<(u32, Hit)>| h.map(|(_, hit)| hit.t);
                assert_eq!(t(found), t(expected), "{name} ({build}): ray {i}");
                if found.map(|h| h.0) != expected.map(|h| h.0) {
                    ties += 1;
                }
                assert_eq!(
                    bvh.occluded::<FEATURES_ALL>(&ray, skip, NONE, t_max),
                    blocked,
                    "{name} ({build}): shadow ray {i}"
                );
            }
        }
        assert!(
            hits > rays.len() / 10 && hits < rays.len(),
            "{name}: {hits} hits"
        );
        assert!(ties <= 4, "{name}: {ties} ties");
    }

    /// The AVX2 node test, which takes each axis's near and far planes by the ray's direction
    /// instead of sorting the two, finds the portable test's hit bits and entry distances
    /// (equal as numbers: a zero's sign may differ, which no comparison sees) on random nodes
    /// of boxes from 1e-6 to 1e6 wide, flat ones (a plane's two bounds equal) among them, and
    /// rays with components at the smallest direction kept, inside and outside the boxes.
    #[test]
    fn the_avx2_node_test_equals_the_portable_one() {
        if !avx2_available() {
            eprintln!("no AVX2 on this CPU: only the portable node test runs");
            return;
        }
        let mut rng = crate::math::rng::Rng::new(3, 0, 0);
        let mut unit = move || rng.next_f32() * 2.0 - 1.0;
        let (mut hits, mut compared) = (0, 0);
        for round in 0..20_000u32 {
            let scale = 10f32.powi((round % 13) as i32 - 6);
            let mut node = WideNode::default();
            for lane in 0..LANES {
                for axis in 0..3 {
                    let (a, b) = (unit() * scale, unit() * scale);
                    let (lo, hi) = if (round + lane as u32).is_multiple_of(5) {
                        (a, a)
                    } else {
                        (a.min(b), a.max(b))
                    };
                    node.planes[axis][lane] = lo;
                    node.planes[3 + axis][lane] = hi;
                }
            }
            node.valid = [0xff, 0b1010_0111][round as usize / 3 % 2];
            let origin = Vec3::new(unit(), unit(), unit()) * scale * 2.0;
            // Every other ray is aimed near the centre of one lane's box.
            let lane = round as usize / 2 % LANES;
            let centre = Vec3::from_array(std::array::from_fn(|axis| {
                0.5 * (node.planes[axis][lane] + node.planes[3 + axis][lane])
            }));
            let aimed = centre + Vec3::new(unit(), unit(), unit()) * 0.1 * scale - origin;
            let mut direction = match round % 2 {
                0 => aimed,
                _ => Vec3::new(unit(), unit(), unit()),
            };
            match round % 7 {
                0 => direction.x = 0.0,
                1 => direction.y = -0.0,
                2 => direction.z = 1e-30,
                _ => {}
            }
            let ray = RayQuery::new(origin, direction);
            let (origin, inv) = (ray.origin.to_array(), ray.inv_direction.to_array());
            let t_max = [T_FAR, scale, 0.1 * scale][round as usize % 3];
            let expected = node_hits(&node, origin, inv, t_max);
            // SAFETY: the CPU has AVX2 (checked above).
            let found = unsafe { node_hits_avx2(&node, origin, inv, Slabs::of(inv), t_max) };
            assert_eq!(found.0, expected.0, "round {round}: hit bits");
            for lane in 0..LANES {
                if expected.0 & (1 << lane) != 0 {
                    assert_eq!(found.1[lane], expected.1[lane], "round {round} lane {lane}");
                    compared += 1;
                }
            }
            hits += (expected.0 != 0) as usize;
        }
        assert!(hits > 2000 && hits < 19_000, "{hits} rounds with a hit");
        assert!(compared > 5000, "{compared} entry distances compared");
    }

    #[test]
    fn the_wide_bvh_finds_what_the_bvh2_finds() {
        check("bunny", &scene("bunny.toml", &[]));
        // Spheres, a plane and triangles together.
        check("tabletop", &scene("tabletop.toml", &[]));
        // Quads (the walls and the light) and spheres.
        check("cornell_direct", &scene("cornell_direct.toml", &[]));
        check(
            "tabletop, moving",
            &scene(
                "tabletop.toml",
                &[
                    // The light squares rise off the board (moving within its plane, they
                    // would overlap the dark ones: ties everywhere); a sphere rolls.
                    "shapes[0].velocity=[0.0,0.2,0.0]",
                    "shapes[2].velocity=[0.3,0.0,0.1]",
                    "camera.shutter=[0.0,1.0]",
                ],
            ),
        );
    }
}
