//! The path tracer (`render.integrator = "path"`) against what is known exactly: furnaces, a
//! plane under a uniform sky, the geometric series of a closed box whose walls emit and reflect,
//! the direct light Whitted's integrator computes, and the CPU against the GPU.

mod common;

use std::path::{Path, PathBuf};

use chambre::cpu::CpuRenderer;
use chambre::gpu::GpuRenderer;
use chambre::gpu::render::PathKernels;
use chambre::pack::flatten;
use chambre::render::Image;
use chambre::scene::{Scene, SceneBuilder};

/// A scene built in code, path traced.
fn path_traced(builder: SceneBuilder) -> Scene {
    builder
        .render_field("integrator", "path".into())
        .build()
        .unwrap_or_else(|e| panic!("{e}"))
}

fn pixel(image: &Image, x: u32, y: u32) -> [f32; 3] {
    image.pixels[(y * image.width + x) as usize].to_array()
}

/// The mean of the image's first channel.
fn mean(image: &Image) -> f64 {
    image.pixels.iter().map(|p| p.x as f64).sum::<f64>() / image.pixels.len() as f64
}

/// A Lambert sphere in a sky of radiance 1 sees only the sky (a convex shape never sees
/// itself): its radiance is its albedo times 1, exactly, whatever the bounce drawn; with albedo 1
/// it vanishes into the sky (the white furnace). `max_depth = 0` is direct light, and the sky is
/// a light: the same image.
#[test]
fn a_convex_lambert_sphere_in_a_uniform_sky_reflects_exactly_its_albedo() {
    for (albedo, max_depth) in [(0.5, 4), (0.5, 0), (1.0, 4), (0.25, 1)] {
        let scene = path_traced(
            SceneBuilder::new(32, 32)
                .spp(4)
                .max_depth(max_depth)
                .background([1.0, 1.0, 1.0])
                .lambert("grey", [albedo; 3])
                .sphere([0.0, 0.0, -4.0], 1.0, "grey"),
        );
        for (path, image) in common::both(&scene) {
            // The centre 12 x 12 pixels lie inside the sphere's outline, the corners outside.
            for y in 10..22 {
                for x in 10..22 {
                    for c in pixel(&image, x, y) {
                        assert!(
                            (c - albedo as f32).abs() < 2e-6,
                            "{path}: albedo {albedo}, max_depth {max_depth}: ({x}, {y}) is {c}"
                        );
                    }
                }
            }
            for (x, y) in [(0, 0), (31, 0), (0, 31), (31, 31)] {
                assert_eq!(pixel(&image, x, y), [1.0; 3], "{path}: corner ({x}, {y})");
            }
        }
    }
}

/// An infinite Lambert plane under a uniform sky of radiance L receives irradiance pi L and so
/// reflects albedo * L, from every point (it never sees itself).
#[test]
fn an_infinite_plane_under_a_uniform_sky_reflects_albedo_times_the_sky() {
    let sky = 2.0;
    let albedo = 0.3;
    let scene = path_traced(
        SceneBuilder::new(24, 24)
            .spp(2)
            .background([sky; 3])
            .pinhole([0.0, 1.0, 0.0], [0.0, 0.0, -3.0], 40.0)
            .lambert("ground", [albedo; 3])
            .plane([0.0, 0.0, 0.0], [0.0, 1.0, 0.0], "ground"),
    );
    for (path, image) in common::both(&scene) {
        // The lower rows see the plane, the top row the sky.
        for x in 0..24 {
            let [ground, ..] = pixel(&image, x, 23);
            assert!(
                (ground - (albedo * sky) as f32).abs() < 2e-6,
                "{path}: ground ({x}, 23) is {ground}"
            );
            assert_eq!(pixel(&image, x, 0), [sky as f32; 3], "{path}: sky ({x}, 0)");
        }
    }
}

/// A glass sphere in a sky of radiance 1 vanishes (the furnace of a dielectric): Fresnel's
/// choice between reflection and refraction keeps a path's throughput, and the radiance's
/// eta^2 going in is undone coming out, so every path that leaves sees 1. Without Russian
/// roulette and with room for the internal reflections, no pixel differs from 1 but by
/// rounding.
#[test]
fn a_glass_sphere_in_a_uniform_sky_vanishes() {
    let scene = path_traced(
        SceneBuilder::new(24, 24)
            .spp(4)
            .max_depth(64)
            .render_field("rr_depth", toml::Value::Integer(1024))
            .background([1.0, 1.0, 1.0])
            .dielectric("glass", 1.5)
            .sphere([0.0, 0.0, -4.0], 1.0, "glass"),
    );
    for (path, image) in common::both(&scene) {
        for y in 0..24 {
            for x in 0..24 {
                for c in pixel(&image, x, y) {
                    assert!((c - 1.0).abs() < 1e-5, "{path}: ({x}, {y}) is {c}");
                }
            }
        }
    }
}

/// Through a glass slab at normal incidence a light of radiance L shows L (1 - R) / (1 + R),
/// R = ((n - 1) / (n + 1))^2: the two interfaces' transmission and every pair of internal
/// reflections (sum of (1 - R)^2 R^2k). The slab is two quads with outward normals.
#[test]
fn a_glass_slab_transmits_what_fresnel_says_at_normal_incidence() {
    let ior: f64 = 1.5;
    let r = ((ior - 1.0) / (ior + 1.0)).powi(2);
    let expected = (1.0 - r) / (1.0 + r);
    let scene = path_traced(
        SceneBuilder::new(16, 16)
            .spp(64)
            .max_depth(8)
            .pinhole([0.0, 0.0, 0.0], [0.0, 0.0, -1.0], 4.0)
            .dielectric("glass", ior)
            .quad(
                [-4.0, -4.0, -3.0],
                [8.0, 0.0, 0.0],
                [0.0, 8.0, 0.0],
                "glass",
            )
            .quad(
                [-4.0, -4.0, -3.5],
                [0.0, 8.0, 0.0],
                [8.0, 0.0, 0.0],
                "glass",
            )
            .area_light(
                [-10.0, -10.0, -6.0],
                [20.0, 0.0, 0.0],
                [0.0, 20.0, 0.0],
                [1.0, 1.0, 1.0],
                1,
            ),
    );
    for (path, image) in common::both(&scene) {
        let measured = mean(&image);
        eprintln!("{path}: {measured:.5} (Fresnel {expected:.5})");
        assert!(
            (measured - expected).abs() < 0.01,
            "{path}: the slab transmits {measured}, Fresnel {expected}"
        );
    }
}

/// A closed glass mesh in a sky of radiance 1 vanishes as a glass sphere does, which holds only
/// if its triangles keep the winding that says which side is inside: an OBJ material of
/// `illum 7` and `Ni` is glass under the path tracer (and keeps its Lambert lobe under
/// Whitted's integrator).
#[test]
fn an_obj_glass_tetrahedron_in_a_uniform_sky_vanishes() {
    let dir = scratch();
    let corners = [
        [1.0, 1.0, 1.0],
        [1.0, -1.0, -1.0],
        [-1.0, 1.0, -1.0],
        [-1.0, -1.0, 1.0],
    ];
    let mut obj = String::from("mtllib glass.mtl\nusemtl glass\n");
    for [x, y, z] in corners {
        obj += &format!("v {x} {y} {} \n", z - 4.0);
    }
    for skipped in 0..4 {
        let mut face: Vec<usize> = (0..4).filter(|&v| v != skipped).collect();
        // Counter-clockwise seen from outside: the normal points away from the fourth corner.
        let p = |v: usize| glam::Vec3::from(corners[v].map(|c| c as f32));
        let normal = (p(face[1]) - p(face[0])).cross(p(face[2]) - p(face[0]));
        if normal.dot(p(face[0]) - p(skipped)) < 0.0 {
            face.swap(1, 2);
        }
        obj += &format!("f {} {} {}\n", face[0] + 1, face[1] + 1, face[2] + 1);
    }
    std::fs::write(dir.join("glass.obj"), obj).unwrap();
    std::fs::write(
        dir.join("glass.mtl"),
        "newmtl glass\nKd 0.5 0.5 0.5\nNi 1.33\nillum 7\n",
    )
    .unwrap();
    let scene_file = |integrator: &str| {
        let toml = format!(
            "[render]\nwidth = 24\nheight = 24\nspp = 4\nmax_depth = 64\nrr_depth = 1024\n\
             background = [1.0, 1.0, 1.0]\nintegrator = \"{integrator}\"\n\n[camera]\n\
             position = [0.3, 0.2, 0.0]\nlook_at = [0.0, 0.0, -4.0]\nvertical_fov = 40.0\n\
             film = [36.0, 36.0]\n\n[[shapes]]\ntype = \"mesh\"\nfile = \"glass.obj\"\n"
        );
        let file = dir.join(format!("glass_{integrator}.toml"));
        std::fs::write(&file, toml).unwrap();
        Scene::load(&file, &[]).unwrap_or_else(|e| panic!("{e}"))
    };
    let whitted = scene_file("whitted");
    assert_eq!(whitted.materials[0].model, chambre::layout::MODEL_LAMBERT);
    let scene = scene_file("path");
    assert_eq!(scene.materials[0].model, chambre::layout::MODEL_DIELECTRIC);
    assert_eq!(scene.materials[0].ior, 1.33);
    for (path, image) in common::both(&scene) {
        for y in 0..24 {
            for x in 0..24 {
                for c in pixel(&image, x, y) {
                    assert!((c - 1.0).abs() < 1e-5, "{path}: ({x}, {y}) is {c}");
                }
            }
        }
    }
}

/// A scratch directory of this test process.
fn scratch() -> PathBuf {
    let dir = std::env::temp_dir().join(format!("chambre-path-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    dir
}

/// A cube [-1, 1]^3 of twelve triangles wound to face inwards (emitters shine from the side
/// their winding faces), all of one material that emits `emission` and reflects `albedo`, and
/// a scene looking around inside it.
fn closed_box(dir: &Path, albedo: f64, emission: f64, max_depth: u32, spp: u32) -> Scene {
    let mut obj = String::from("mtllib box.mtl\nusemtl wall\n");
    let corner = |axis: usize, side: f64, a: f64, b: f64| {
        let mut p = [0.0; 3];
        p[axis] = side;
        p[(axis + 1) % 3] = a;
        p[(axis + 2) % 3] = b;
        p
    };
    let mut vertices = 0;
    for axis in 0..3 {
        for side in [-1.0, 1.0] {
            let quad = [(-1.0, -1.0), (1.0, -1.0), (1.0, 1.0), (-1.0, 1.0)];
            for (a, b) in quad {
                let [x, y, z] = corner(axis, side, a, b);
                obj += &format!("v {x} {y} {z}\n");
            }
            // (e1 x e2) along +axis for this order: inwards on the -1 side; flip on the +1 side.
            let faces = match side < 0.0 {
                true => [[1, 2, 3], [1, 3, 4]],
                false => [[1, 3, 2], [1, 4, 3]],
            };
            for f in faces {
                let [i, j, k] = f.map(|v| v + vertices);
                obj += &format!("f {i} {j} {k}\n");
            }
            vertices += 4;
        }
    }
    std::fs::write(dir.join("box.obj"), obj).unwrap();
    let mtl = format!(
        "newmtl wall\nKd {albedo} {albedo} {albedo}\nKe {emission} {emission} {emission}\n"
    );
    std::fs::write(dir.join("box.mtl"), mtl).unwrap();
    let toml = format!(
        "[render]\nwidth = 16\nheight = 16\nspp = {spp}\nmax_depth = {max_depth}\n\
         integrator = \"path\"\n\n[camera]\nposition = [0.1, -0.2, 0.3]\n\
         look_at = [1.0, 0.5, -1.0]\nvertical_fov = 100.0\nfilm = [36.0, 36.0]\n\n\
         [[shapes]]\ntype = \"mesh\"\nfile = \"box.obj\"\n"
    );
    let file = dir.join(format!("box_{max_depth}.toml"));
    std::fs::write(&file, toml).unwrap();
    Scene::load(&file, &[]).unwrap_or_else(|e| panic!("{e}"))
}

/// Inside a closed box whose walls emit L and reflect albedo rho, the radiance is the geometric
/// series L (1 + rho + rho^2 + ...): the wall's own emission, then one term a bounce. Cut at
/// `max_depth` bounces, the series ends at rho^(max_depth + 1) (the last vertex's direct
/// light); with Russian roulette and a deep cut it is L / (1 - rho). The walls are emitting
/// triangles, so every term mixes light samples and BSDF hits by multiple importance sampling:
/// the sum is right only if the weights are.
#[test]
fn a_closed_emitting_box_sums_the_geometric_series_cut_at_max_depth() {
    let dir = scratch();
    let (rho, emission) = (0.5, 1.0);
    for (max_depth, spp) in [(0, 16), (1, 16), (3, 16), (40, 32)] {
        let scene = closed_box(&dir, rho, emission, max_depth, spp);
        let expected: f64 = (0..=max_depth + 1)
            .map(|k| emission * rho.powi(k as i32))
            .sum();
        for (path, image) in common::both(&scene) {
            let measured = mean(&image);
            eprintln!("{path}: max_depth {max_depth}: {measured:.5} (series {expected:.5})");
            assert!(
                (measured - expected).abs() < 0.01 * expected,
                "{path}: max_depth {max_depth}: the box's mean radiance is {measured}, the series \
                 {expected}"
            );
        }
    }
}

/// With `max_depth = 0` the path tracer computes the direct light Whitted's integrator does (no
/// ambient, no mirror), by other means: light samples and BSDF samples weighted by multiple
/// importance sampling. Both are unbiased, so their images agree to sampling error, block by
/// block.
#[test]
fn direct_light_by_multiple_importance_sampling_matches_light_sampling_alone() {
    let render = |integrator: &str| {
        let scene = common::load(
            "scenes/cornell_direct.toml",
            &[
                "render.width=32",
                "render.height=32",
                "render.spp=256",
                "render.max_depth=0",
                "render.ambient=[0.0,0.0,0.0]",
                &format!("render.integrator=\"{integrator}\""),
            ],
        );
        common::render_cpu(&flatten(&scene))
    };
    let (whitted, path) = (render("whitted"), render("path"));
    common::assert_blocks_agree(&whitted, &path, 0.03, ["Whitted", "path tracer"]);
}

/// The direct-lighting box with lights of very unequal power beside its own: a small bright
/// warm quad, a large dim blue one (each of several samples), and a point light, which every
/// vertex samples.
fn box_with_unequal_lights(dir: &Path) -> PathBuf {
    let base = Path::new(env!("CARGO_MANIFEST_DIR")).join("scenes/cornell_direct.toml");
    let mut toml = std::fs::read_to_string(base).unwrap();
    toml += "\n[[lights]]\ntype = \"area\"\ncorner = [0.6, 1.99, 0.5]\n\
             edge_u = [0.1, 0.0, 0.0]\nedge_v = [0.0, 0.0, 0.1]\nradiance = [60.0, 40.0, 20.0]\n\
             samples = 3\n\
             \n[[lights]]\ntype = \"point\"\nposition = [-0.5, 1.5, 0.5]\n\
             intensity = [0.3, 0.3, 0.3]\n\
             \n[[lights]]\ntype = \"area\"\ncorner = [-0.99, 0.3, -0.9]\n\
             edge_u = [0.0, 1.2, 0.0]\nedge_v = [0.0, 0.0, 1.5]\nradiance = [0.2, 0.3, 0.9]\n\
             samples = 2\n";
    let file = dir.join("unequal_lights.toml");
    std::fs::write(&file, toml).unwrap();
    file
}

/// The path tracer samples one area light a vertex, chosen in proportion to its power, and
/// divides by the probability it chose it with: with lights of very unequal power and sizes,
/// its direct light (`max_depth = 0`) is still Whitted's, which samples every light at every
/// vertex, block by block to sampling error. The lights are reordered for the choice (point
/// light first, the area lights after it) and the distribution is the power's.
#[test]
fn lights_chosen_by_power_light_the_scene_as_every_light_sampled() {
    let file = box_with_unequal_lights(&scratch());
    let load = |integrator: &str| {
        let overrides = [
            "render.width=32".to_string(),
            "render.height=32".to_string(),
            "render.spp=512".to_string(),
            "render.max_depth=0".to_string(),
            "render.ambient=[0.0,0.0,0.0]".to_string(),
            format!("render.integrator=\"{integrator}\""),
        ];
        flatten(&Scene::load(&file, &overrides).unwrap_or_else(|e| panic!("{e}")))
    };
    let (whitted, path) = (load("whitted"), load("path"));
    assert!(!whitted.frame.chooses_lights());
    let frame = &path.frame;
    assert_eq!((frame.light_choice_start, frame.light_count), (1, 4));
    assert_eq!(
        frame.light_choice_pairs, 3,
        "the most samples of a light chosen among"
    );
    let power: Vec<f64> = path.lights[1..]
        .iter()
        .map(|l| chambre::layout::luminance_f32(l.color) as f64 * l.area() as f64)
        .collect();
    let total: f64 = power.iter().sum();
    let offset = frame.light_choice_offset as usize;
    let cdf = [
        path.sample_table[offset][0],
        path.sample_table[offset][1],
        path.sample_table[offset + 1][0],
    ];
    let mut sum = 0.0;
    for (i, p) in power.iter().enumerate() {
        sum += p;
        assert!(
            (cdf[i] as f64 - sum / total).abs() < 1e-6,
            "entry {i}: {cdf:?}"
        );
    }
    assert_eq!(cdf[2], 1.0);
    let (a, b) = (common::render_cpu(&whitted), common::render_cpu(&path));
    common::assert_blocks_agree(&a, &b, 0.03, ["Whitted", "path tracer"]);
    if let Some(gpu) = common::render_gpu(&path) {
        let (within, _) = common::agreement(&b, &gpu, 1e-3);
        assert!(
            within >= 0.97,
            "only {:.3}% of pixels agree",
            within * 100.0
        );
    }
}

/// A chosen light whose samples exceed one invocation's budget splits into light windows as
/// any light does: every window chooses the same light (from the same random dimension), the
/// windows add up to the unsplit estimate on the CPU path, and the GPU's wavefront render, which
/// sizes its shadow-ray slots for the window of the chosen light, agrees with it.
#[test]
fn a_chosen_lights_samples_split_into_windows_sum_to_the_unsplit_estimate() {
    let file = box_with_unequal_lights(&scratch());
    let overrides = [
        "render.width=12",
        "render.height=12",
        "render.spp=2",
        "render.max_depth=1",
        "render.ambient=[0.0,0.0,0.0]",
        "render.integrator=\"path\"",
        "lights[0].samples=1500",
    ]
    .map(String::from);
    let flat = flatten(&Scene::load(&file, &overrides).unwrap_or_else(|e| panic!("{e}")));
    assert!(flat.frame.chooses_lights());
    let windowed = common::assert_windows_sum_to_unsplit(&flat);
    if let Some(gpu) = common::render_gpu(&flat) {
        let (within, mean_abs) = common::agreement(&windowed, &gpu, 1e-3);
        eprintln!(
            "GPU: {:.2}% within 1e-3, mean |diff| {mean_abs:.2e}",
            within * 100.0
        );
        assert!(
            within >= 0.97,
            "only {:.3}% of pixels agree",
            within * 100.0
        );
    }
}

/// The GPU's wavefront render and the CPU path trace the same paths with the same random
/// numbers: the images agree pixel for pixel but where rounding sends a path another way, and
/// so do the rays they count and the paths they say were cut off at max_depth (the CPU tests
/// its last rays against the box's few emitters, the GPU traces them).
#[test]
fn the_gpu_path_traces_the_cpus_paths() {
    let scene = common::load(
        "scenes/cornell_box.toml",
        &[
            "render.width=48",
            "render.height=48",
            "render.spp=4",
            "render.max_depth=3",
            "render.rr_depth=1",
            "render.integrator=\"path\"",
        ],
    );
    let flat = flatten(&scene);
    let cpu_output = common::render_clean(&flat, &mut CpuRenderer::new(&flat));
    let Some(context) = common::gpu_context() else {
        return;
    };
    let mut renderer = GpuRenderer::new(context, &flat).unwrap_or_else(|e| panic!("{e}"));
    let gpu_output = common::render_clean(&flat, &mut renderer);
    let near = |a: u64, b: u64| a > 0 && (a as f64 - b as f64).abs() <= 0.01 * a as f64;
    let (cpu_cut, gpu_cut) = (cpu_output.truncated_paths, gpu_output.truncated_paths);
    assert!(
        near(cpu_cut, gpu_cut),
        "cut off: CPU {cpu_cut}, GPU {gpu_cut}"
    );
    let (cpu_rays, gpu_rays) = (cpu_output.rays, gpu_output.rays);
    assert!(
        near(cpu_rays, gpu_rays),
        "rays: CPU {cpu_rays}, GPU {gpu_rays}"
    );
    let (cpu, gpu) = (cpu_output.image, gpu_output.image);
    let (within, mean_abs) = common::agreement(&cpu, &gpu, 1e-3);
    eprintln!(
        "{:.3}% of pixels within 1e-3, mean |diff| {mean_abs:.3e}; means {} and {}",
        within * 100.0,
        mean(&cpu),
        mean(&gpu)
    );
    assert!(
        within >= 0.97,
        "only {:.3}% of pixels agree",
        within * 100.0
    );
    assert!((mean(&cpu) - mean(&gpu)).abs() < 0.01 * mean(&cpu));
}

/// The megakernel renders Whitted's integrator only, and says so; ambient light is refused
/// under the path tracer, by field.
#[test]
fn what_the_path_tracer_refuses_is_refused_by_name() {
    let scene = path_traced(SceneBuilder::new(8, 8).lambert("grey", [0.5; 3]).sphere(
        [0.0, 0.0, -4.0],
        1.0,
        "grey",
    ));
    let flat = flatten(&scene);
    if let Some(context) = common::gpu_context() {
        let refused =
            GpuRenderer::with_kernels(context, &flat, flat.features(), PathKernels::Megakernel);
        let message = refused.err().expect("the megakernel refuses").to_string();
        assert!(message.contains("wavefront"), "{message}");
    }
    let ambient = SceneBuilder::new(8, 8)
        .render_field("integrator", "path".into())
        .ambient([0.1; 3])
        .lambert("grey", [0.5; 3])
        .sphere([0.0, 0.0, -4.0], 1.0, "grey")
        .build();
    let message = ambient.expect_err("ambient is refused").to_string();
    assert!(message.contains("render.ambient"), "{message}");
}

/// The albedo of a white GGX conductor (Smith's separable masking, Fresnel 1) seen head-on,
/// by quadrature in double precision over the half vector's angle: with wo the normal,
/// f cos_i dω_i = D(h) cos_h G1(wi) dω_h, wi at twice the half vector's angle.
fn ggx_albedo_head_on(alpha: f64) -> f64 {
    let a2 = alpha * alpha;
    let g1 = |c: f64| 2.0 * c / (c + (a2 + (1.0 - a2) * c * c).sqrt());
    let steps = 200_000;
    let top = std::f64::consts::FRAC_PI_4;
    (0..steps)
        .map(|k| {
            let theta = (k as f64 + 0.5) / steps as f64 * top;
            let (sin, cos) = theta.sin_cos();
            let d = a2 / (std::f64::consts::PI * (sin * sin + cos * cos * a2).powi(2));
            d * cos * g1((2.0 * theta).cos()) * 2.0 * std::f64::consts::PI * sin * top
                / steps as f64
        })
        .sum()
}

/// A rough conductor of reflectance 1 in a sky of radiance 1 shows its directional albedo
/// (a convex shape sees only the sky): head-on, the quadrature's value; below 1 by what
/// Smith's model loses between microfacets, more the rougher it is.
#[test]
fn a_white_rough_conductor_in_a_uniform_sky_shows_its_albedo() {
    for roughness in [0.3, 0.7, 1.0] {
        let expected = ggx_albedo_head_on(roughness * roughness);
        let scene = path_traced(
            SceneBuilder::new(32, 32)
                .spp(1024)
                .max_depth(0)
                .background([1.0, 1.0, 1.0])
                .rough_conductor("metal", [1.0; 3], roughness)
                .sphere([0.0, 0.0, -4.0], 1.0, "metal"),
        );
        for (path, image) in common::both(&scene) {
            // The centre pixels see normals within about 4° of the view.
            let centre: Vec<f32> = [(15, 15), (16, 15), (15, 16), (16, 16)]
                .iter()
                .map(|&(x, y)| pixel(&image, x, y)[0])
                .collect();
            let got = centre.iter().sum::<f32>() as f64 / 4.0;
            assert!(
                (got - expected).abs() < 0.01 * expected,
                "{path}: roughness {roughness}: {got}, quadrature {expected}"
            );
            assert!(
                got < 1.0,
                "{path}: roughness {roughness} creates energy: {got}"
            );
        }
    }
}

/// A rough conductor's fields are checked by name: its roughness within [0.01, 1] (0 is a
/// mirror), no diffuse or mirror term, no shininess; no other model takes a roughness.
#[test]
fn rough_conductor_fields_are_refused_by_name() {
    let cases = [
        (
            "model = \"rough_conductor\"\nroughness = 0.0",
            "materials[0].roughness",
        ),
        (
            "model = \"rough_conductor\"\nroughness = 1.5",
            "materials[0].roughness",
        ),
        (
            "model = \"rough_conductor\"\ndiffuse = [0.5, 0.5, 0.5]",
            "materials[0].diffuse",
        ),
        (
            "model = \"rough_conductor\"\nmirror = [0.5, 0.5, 0.5]",
            "materials[0].mirror",
        ),
        (
            "model = \"rough_conductor\"\nshininess = 10.0",
            "materials[0].shininess",
        ),
        (
            "model = \"lambert\"\nroughness = 0.5",
            "materials[0].roughness",
        ),
    ];
    for (fields, field) in cases {
        let text = format!(
            "[render]\nwidth = 8\nheight = 8\n[camera]\nposition = [0.0, 0.0, 0.0]\n\
             look_at = [0.0, 0.0, -1.0]\nfilm = [24.0, 24.0]\n[[materials]]\nname = \"m\"\n{fields}\n"
        );
        let e = Scene::from_str(Path::new("scene.toml"), &text, &[])
            .unwrap_err()
            .to_string();
        assert!(e.contains(field), "{fields}: `{e}` should name {field}");
    }
}
