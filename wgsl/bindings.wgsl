// The kernels' bindings, declared once for every kernel: group 0 is the scene's (camera,
// geometry, materials, lights, textures: one bind group for every kernel of a render), group 1
// each kernel's own (its queues, sums and per-dispatch uniforms).
// Mirrors: src/gpu/kernels.rs (BINDINGS and SCENE_BINDINGS: the same numbers, names, access and
// groups, checked by tests/wgsl.rs; the pipeline builder makes the bind group layouts from them).

@group(0) @binding(0) var<uniform> camera: GpuCamera;
@group(0) @binding(1) var<uniform> frame: GpuFrame;
@group(1) @binding(2) var<uniform> pass_info: GpuPass;
@group(1) @binding(3) var<storage, read> nodes: array<GpuBvhNode>;
@group(0) @binding(4) var<storage, read> prims: array<GpuPrimitive>;
@group(0) @binding(5) var<storage, read> normals: array<GpuNormals>;
@group(0) @binding(6) var<storage, read> materials: array<GpuMaterial>;
@group(0) @binding(7) var<storage, read> lights: array<GpuLight>;
// The running per-pixel sums (rgb, samples); when passes are split into light windows, a second
// half holds the scratch sums of the pass in progress (see render.wgsl).
@group(1) @binding(8) var<storage, read_write> accumulation: array<vec4<f32>>;
@group(1) @binding(9) var<storage, read_write> status: array<atomic<u32>, STATUS_WORDS>;
@group(0) @binding(10) var<storage, read> sample_table: array<vec2<f32>>;
// The ray benchmark's rays and per-ray results (wgsl/trace.wgsl).
@group(1) @binding(11) var<storage, read> rays: array<GpuRay>;
@group(1) @binding(12) var<storage, read_write> distances: array<f32>;
// The compressed wide BVH (wgsl/traverse_cwbvh.wgsl); its leaves index `prims`, which then holds
// the primitives in the CWBVH's order.
@group(0) @binding(13) var<storage, read> cw_nodes: array<GpuCwNode>;
// The pixels an adaptive pass samples (`y * width + x`), when `pass_info.listed_pixels` is not 0.
@group(1) @binding(14) var<storage, read> pixel_list: array<u32>;
// The Fermat kernel's searches, one surface and eye each (a dispatch's y picks one), the
// vertices each solves (xyz, and in w the mirror each lies on: 1 + its index, 0 for none) and
// their reflection points, search after search (wgsl/preview/fermat.wgsl).
@group(1) @binding(15) var<storage, read> reflectors: array<GpuReflector>;
@group(1) @binding(16) var<storage, read> fermat_vertices: array<vec4<f32>>;
@group(1) @binding(17) var<storage, read_write> reflections: array<GpuReflection>;
// The wavefront render's closest hit of each path's current ray (wgsl/wavefront.wgsl).
@group(1) @binding(18) var<storage, read_write> wf_hits: array<GpuHit>;
// The preview's reflected triangles for `fermat_cull` (wgsl/preview/fermat.wgsl): per triangle its three
// vertices (indices into the distinct reflected vertices, whose solves `vertex_solves` gives:
// indices into `fermat_vertices`) and, in w, 1 + the index of the mirror it lies on (0: on
// none); the triangles whose reflection shows on a search's surface, as the index triples of
// an indexed draw, (the search's row) x (distinct vertices) + the vertex, in one list for all
// the searches of the dispatch (room for every triangle of every search), and the one indirect
// draw that draws them all.
@group(1) @binding(19) var<storage, read> reflected_triangles: array<vec4<u32>>;
@group(1) @binding(20) var<storage, read_write> shown_indices: array<u32>;
@group(1) @binding(21) var<storage, read_write> draw_args: GpuDrawArgs;
// A patch's search's corner B for each vertex (where V -> O crosses the patch), search after
// search as `reflections`: it depends on the vertex and the patch only, not on the eye, so
// `fermat_start` finds it once for a set of vertices and `fermat` reads it every frame.
@group(1) @binding(22) var<storage, read_write> fermat_starts: array<vec2<f32>>;
// Per distinct reflected vertex, the index of its Fermat solve (vertices at one position share
// one): what `reflected_triangles` indexes.
@group(1) @binding(23) var<storage, read> vertex_solves: array<u32>;
// The wavefront render (wgsl/wavefront.wgsl): the stage dispatch's depth (one GpuWave per stage
// dispatch of a batch, at its own dynamic offset); each path's ray and state; the paths each
// depth's stages take (two lists of `path_capacity` entries, used in turn by depth); the
// counters of the lists being filled (WF_PATH_COUNTER, WF_SHADOW_COUNTER); each depth's indirect
// dispatches, written by `wf_prepare` and read by the stages they size; the shadow rays of a
// depth's vertices (`shadow_stride` slots a path), what each adds where its light is visible,
// and the list of those emitted; the camera rays' first hits for the AOV layers (two a path).
@group(1) @binding(24) var<uniform> wave: GpuWave;
@group(1) @binding(25) var<storage, read_write> wf_rays: array<GpuPathRay>;
@group(1) @binding(26) var<storage, read_write> wf_paths: array<GpuPath>;
@group(1) @binding(27) var<storage, read_write> wf_queue: array<u32>;
@group(1) @binding(28) var<storage, read_write> wf_counters: array<atomic<u32>, WF_COUNTERS>;
@group(1) @binding(29) var<storage, read_write> wf_args: array<GpuWaveArgs>;
@group(1) @binding(30) var<storage, read> wf_args_in: array<GpuWaveArgs>;
@group(1) @binding(31) var<storage, read_write> wf_shadow_rays: array<GpuShadowRay>;
@group(1) @binding(32) var<storage, read_write> wf_shadow_terms: array<GpuShadowTerm>;
@group(1) @binding(33) var<storage, read_write> wf_shadow_queue: array<u32>;
@group(1) @binding(34) var<storage, read_write> wf_aovs: array<vec4<f32>>;
// Textured triangles' texture coordinates (at their normals' index), the textures the
// materials read, and their texels (wgsl/texture.wgsl).
@group(0) @binding(35) var<storage, read> texcoords: array<GpuTexCoords>;
@group(0) @binding(36) var<storage, read> textures: array<GpuTexture>;
@group(0) @binding(37) var<storage, read> texels: array<u32>;
// The environment light's map: its texels' RGB, each texel's density in (u, v), the marginal CDF
// over rows and each row's conditional CDF (`EnvironmentMap::packed`; wgsl/environment.wgsl).
@group(0) @binding(38) var<storage, read> environment: array<f32>;
