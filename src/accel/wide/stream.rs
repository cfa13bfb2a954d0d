//! Streams: many independent rays (bounces, rays that point every way) traced by one thread,
//! [`IN_FLIGHT`] of them at a time, a node each in turn. One ray's traversal is a chain of
//! dependent loads: where the BVH does not fit in the caches (the dragon's), a ray alone waits
//! on memory at most of its nodes, since the node it visits next is known only once the one
//! before is tested. Each step ends by prefetching the ray's next node, and the other rays'
//! steps then run while it arrives (the GPU hides the same latency with many rays a core).
//! A ray that finishes hands its place to the next of the stream, so the rays in flight stay
//! [`IN_FLIGHT`] to the stream's last few.
//!
//! Each ray's search is the one-ray traversal's ([`ClosestSearch`], [`AnySearch`]), the same
//! operations in the same order, so each result is the one-ray query's, bit for bit.

use super::*;

/// Rays a stream traverses at once: enough steps of other rays to cover a node's load from
/// memory (about 100 ns against about 40 ns a step), few enough that their stacks stay in
/// the first-level cache.
pub const IN_FLIGHT: usize = 8;

impl WideBvh {
    /// The closest hit along each of `rays` before `t_max`, as [`WideBvh::closest_hit`] finds
    /// it with no primitive skipped, into `hits`.
    pub fn closest_hit_stream<const F: u32>(
        &self,
        rays: &[RayQuery],
        t_max: f32,
        hits: &mut [Option<(u32, Hit)>],
    ) {
        assert_eq!(rays.len(), hits.len());
        self.closest_slots_stream::<F>(rays, t_max, hits);
        // The searches leave slots; their primitives are read here, all together. Read as each
        // ray finished, an incoherent ray's primitive was a lone miss in memory that stalled
        // every ray in flight (a tenth of the dragon's incoherent closest-hit time); in this loop
        // the reads are independent and their misses overlap.
        for (slot, _) in hits.iter_mut().flatten() {
            *slot = self.ids[*slot as usize];
        }
    }

    /// [`WideBvh::closest_hit_stream`] with each hit's slot in the wide BVH's primitives.
    fn closest_slots_stream<const F: u32>(
        &self,
        rays: &[RayQuery],
        t_max: f32,
        hits: &mut [Option<(u32, Hit)>],
    ) {
        #[cfg(target_arch = "x86_64")]
        if self.avx2 {
            // SAFETY: `avx2` is set only where the CPU reports AVX2.
            return unsafe { closest_stream_avx2::<F>(self, rays, t_max, hits) };
        }
        stream::<F, ClosestSearch>(self, rays, t_max, hits)
    }

    /// Whether anything lies along each of `rays` before `t_max`, as [`WideBvh::occluded`]
    /// says with no primitive skipped, into `blocked`.
    pub fn occluded_stream<const F: u32>(
        &self,
        rays: &[RayQuery],
        t_max: f32,
        blocked: &mut [bool],
    ) {
        assert_eq!(rays.len(), blocked.len());
        #[cfg(target_arch = "x86_64")]
        if self.avx2 {
            // SAFETY: as in `closest_hit_stream`.
            return unsafe { occluded_stream_avx2::<F>(self, rays, t_max, blocked) };
        }
        stream::<F, AnySearch>(self, rays, t_max, blocked)
    }
}

/// A traversal a stream can step: started on a ray, stepped a visit at a time with its stack,
/// finished into its result. A step that opens a node with hit packed leaves stops there,
/// asking the cache for the node's octets, and leaves the node `pending`: the ray's next step
/// tests its octets and goes on, the order of the one-ray traversal's operations unchanged.
pub(super) trait Search<'r>: Sized {
    type Stack;
    /// What a node's box test leaves for its octets and its children.
    type Opened: Copy;
    type Output;
    fn empty_stack() -> Self::Stack;
    /// The search for `ray`'s result before `t_max`, skipping nothing, at the root; `stack`
    /// is made empty for it.
    fn start(bvh: &WideBvh, ray: &'r RayQuery, t_max: f32, stack: &mut Self::Stack) -> Self;
    /// Whether the search has more to visit.
    fn running(&self) -> bool;
    /// One visit, or the octets of the node `pending` and what follows them; whether the
    /// search goes on.
    fn step<const F: u32>(
        &mut self,
        bvh: &WideBvh,
        stack: &mut Self::Stack,
        pending: &mut Option<(u32, Self::Opened)>,
    ) -> bool;
    fn finish<const F: u32>(self, bvh: &WideBvh) -> Self::Output;
}

impl<'r> Search<'r> for ClosestSearch<'r> {
    type Stack = Stack;
    type Opened = Opened;
    type Output = Option<(u32, Hit)>;

    #[inline(always)]
    fn empty_stack() -> Stack {
        Stack::empty()
    }

    #[inline(always)]
    fn start(bvh: &WideBvh, ray: &'r RayQuery, t_max: f32, stack: &mut Stack) -> Self {
        // A closest-hit search ends only with its stack empty; kept so for safety's sake.
        stack.len = 0;
        ClosestSearch::new(bvh, ray, NONE, t_max)
    }

    #[inline(always)]
    fn running(&self) -> bool {
        ClosestSearch::running(self)
    }

    #[inline(always)]
    fn step<const F: u32>(
        &mut self,
        bvh: &WideBvh,
        stack: &mut Stack,
        pending: &mut Option<(u32, Opened)>,
    ) -> bool {
        if let Some((code, opened)) = pending.take() {
            let node = &bvh.nodes[code as usize];
            self.test_octets::<F>(bvh, node, opened.mask);
            return self.descend(bvh, node, &opened, stack);
        }
        let code = self.code;
        if code & LEAF != 0 {
            self.test_leaf::<F>(bvh, code);
            return self.pop(stack);
        }
        let node = &bvh.nodes[code as usize];
        let opened = self.open(bvh, node);
        if opened.mask & node.packed != 0 {
            prefetch_octets(bvh, node);
            *pending = Some((code, opened));
            return true;
        }
        self.descend(bvh, node, &opened, stack)
    }

    /// The hit's slot, not yet its primitive: see [`WideBvh::closest_hit_stream`].
    #[inline(always)]
    fn finish<const F: u32>(self, bvh: &WideBvh) -> Self::Output {
        ClosestSearch::finish_in_slots::<F>(self, bvh)
    }
}

impl<'r> Search<'r> for AnySearch<'r> {
    type Stack = CodeStack;
    type Opened = u32;
    type Output = bool;

    #[inline(always)]
    fn empty_stack() -> CodeStack {
        CodeStack::empty()
    }

    #[inline(always)]
    fn start(bvh: &WideBvh, ray: &'r RayQuery, t_max: f32, stack: &mut CodeStack) -> Self {
        // An any-hit search that finds something leaves the rest of its stack behind.
        stack.len = 0;
        AnySearch::new(&bvh.nodes, ray, [NONE; 2], t_max)
    }

    #[inline(always)]
    fn running(&self) -> bool {
        self.visit.is_some()
    }

    #[inline(always)]
    fn step<const F: u32>(
        &mut self,
        bvh: &WideBvh,
        stack: &mut CodeStack,
        pending: &mut Option<(u32, u32)>,
    ) -> bool {
        let found = match pending.take() {
            Some((code, mask)) => {
                let node = &bvh.nodes[code as usize];
                self.any_in_octets::<F>(bvh, node, mask) || self.descend(bvh, node, mask, stack)
            }
            None => {
                let Some(code) = self.visit else {
                    return false;
                };
                if code & LEAF != 0 {
                    AnySearch::step::<F>(self, bvh, code, stack)
                } else {
                    let node = &bvh.nodes[code as usize];
                    let mask = self.open(bvh, node);
                    if mask & node.packed != 0 {
                        prefetch_octets(bvh, node);
                        *pending = Some((code, mask));
                        return true;
                    }
                    self.descend(bvh, node, mask, stack)
                }
            }
        };
        if found {
            self.found = true;
            self.visit = None;
        }
        // The one-ray traversal gains nothing by it; here the other rays' steps hide the load.
        match self.visit {
            Some(code) => {
                prefetch(&bvh.nodes, code);
                true
            }
            None => false,
        }
    }

    #[inline(always)]
    fn finish<const F: u32>(self, bvh: &WideBvh) -> bool {
        self.found || self.planes_occlude::<F>(bvh)
    }
}

/// The results of `rays` (before `t_max`) by searches of kind `S`, [`IN_FLIGHT`] stepped in
/// turn, into `out`.
#[inline(always)]
fn stream<'r, const F: u32, S: Search<'r>>(
    bvh: &WideBvh,
    rays: &'r [RayQuery],
    t_max: f32,
    out: &mut [S::Output],
) {
    let mut stacks: [S::Stack; IN_FLIGHT] = std::array::from_fn(|_| S::empty_stack());
    let mut searches: [Option<(usize, S)>; IN_FLIGHT] = std::array::from_fn(|_| None);
    let mut next = 0;
    // The next ray whose search has something to visit, the others finished at once (a
    // scene of planes only has an empty root).
    let mut launch = |stack: &mut S::Stack, out: &mut [S::Output]| {
        while next < rays.len() {
            let (i, search) = (next, S::start(bvh, &rays[next], t_max, stack));
            next += 1;
            if search.running() {
                return Some((i, search));
            }
            out[i] = search.finish::<F>(bvh);
        }
        None
    };
    let mut live = 0;
    for (search, stack) in searches.iter_mut().zip(stacks.iter_mut()) {
        *search = launch(stack, out);
        live += search.is_some() as usize;
    }
    let mut pending = [None; IN_FLIGHT];
    let mut lane = 0;
    while live > 0 {
        let stack = &mut stacks[lane];
        if let Some((_, search)) = &mut searches[lane]
            && !search.step::<F>(bvh, stack, &mut pending[lane])
        {
            let (i, done) = searches[lane].take().expect("the search just stepped");
            out[i] = done.finish::<F>(bvh);
            searches[lane] = launch(stack, out);
            live -= searches[lane].is_none() as usize;
        }
        lane = (lane + 1) % IN_FLIGHT;
    }
}

#[cfg(target_arch = "x86_64")]
#[target_feature(enable = "avx2")]
fn closest_stream_avx2<const F: u32>(
    bvh: &WideBvh,
    rays: &[RayQuery],
    t_max: f32,
    hits: &mut [Option<(u32, Hit)>],
) {
    stream::<F, ClosestSearch>(bvh, rays, t_max, hits)
}

#[cfg(target_arch = "x86_64")]
#[target_feature(enable = "avx2")]
fn occluded_stream_avx2<const F: u32>(
    bvh: &WideBvh,
    rays: &[RayQuery],
    t_max: f32,
    blocked: &mut [bool],
) {
    stream::<F, AnySearch>(bvh, rays, t_max, blocked)
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::bench::rays::{bounds, incoherent_rays};
    use crate::layout::{FEATURES_ALL, T_FAR};
    use crate::pack::flatten;
    use crate::scene::sample_scene;

    /// `bvh`'s streams find each ray's one-ray result exactly, on streams shorter than, as
    /// long as and longer than the rays in flight, before a far and a near `t_max`.
    fn check(name: &str, bvh: &WideBvh, rays: &[RayQuery]) {
        for t_max in [T_FAR, 0.3] {
            for len in [0, 1, 3, IN_FLIGHT, IN_FLIGHT + 1, rays.len()] {
                let rays = &rays[..len];
                let mut hits = vec![None; len];
                bvh.closest_hit_stream::<FEATURES_ALL>(rays, t_max, &mut hits);
                let mut blocked = vec![false; len];
                bvh.occluded_stream::<FEATURES_ALL>(rays, t_max, &mut blocked);
                for (i, ray) in rays.iter().enumerate() {
                    let expected = bvh.closest_hit::<FEATURES_ALL>(ray, NONE, t_max);
                    assert_eq!(hits[i], expected, "{name}: ray {i} of {len}, t_max {t_max}");
                    let occluded = bvh.occluded::<FEATURES_ALL>(ray, NONE, NONE, t_max);
                    assert_eq!(blocked[i], occluded, "{name}: shadow ray {i} of {len}");
                }
            }
        }
    }

    #[test]
    fn streams_find_what_one_ray_at_a_time_finds() {
        // Triangles; spheres, a plane and triangles; quads and spheres.
        for name in ["bunny.toml", "tabletop.toml", "cornell_direct.toml"] {
            let flat = flatten(&sample_scene(name, &[]));
            let wide = flat.wide().unwrap();
            let (lo, hi) = bounds(&flat);
            let rays = incoherent_rays(lo, hi, 500, 5);
            let rays: Vec<RayQuery> = (0..rays.len())
                .map(|i| RayQuery::new(rays.origins[i], rays.directions[i]))
                .collect();
            let hits = rays
                .iter()
                .filter(|ray| wide.closest_hit::<FEATURES_ALL>(ray, NONE, T_FAR).is_some())
                .count();
            assert!(hits > 50 && hits < rays.len(), "{name}: {hits} hits");
            check(name, wide, &rays);
            let portable = WideBvh {
                avx2: false,
                ..wide.clone()
            };
            check(&format!("{name}, portable"), &portable, &rays);
            // A root with nothing in it (a scene of planes only): every search is over at
            // its start, and a stream hands its place on at once.
            let mut empty = portable;
            empty.nodes[0].valid = 0;
            empty.avx2 = wide.avx2;
            check(&format!("{name}, empty root"), &empty, &rays);
        }
    }
}
