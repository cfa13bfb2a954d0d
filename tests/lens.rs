//! Real lenses: the shipped prescriptions read, their paraxial properties (ray-transfer matrices)
//! against exact rays traced through their surfaces in the paraxial limit, rays lost to the
//! stop and the barrel, the image circle, renders through the glass on both paths, focus, and
//! the spectral mode (dispersion at each wavelength, the film's bands, axial colour rendered).

use std::path::Path;

use chambre::camera::lens::{LensSystem, Lost, Paraxial, Prescription, lens_ray};
use chambre::layout::LENS_PUPIL_CELLS;
use glam::{DVec3, Vec2, Vec3};

/// The shipped lenses and their nominal focal lengths (mm), as their sources state them.
const LENSES: [(&str, f64); 4] = [
    ("scenes/lenses/dgauss_50mm.dat", 50.0),
    ("scenes/lenses/wide_22mm.dat", 22.0),
    ("scenes/lenses/telephoto_250mm.dat", 254.0),
    ("scenes/lenses/sironar_n_150mm.dat", 150.0),
];

fn lens(path: &str) -> LensSystem {
    let prescription = Prescription::read(Path::new(path)).unwrap();
    LensSystem::new(&prescription, None).unwrap()
}

/// A ray from the rear focal point at a small angle leaves the lens parallel to the axis, at
/// the height f tan(angle): the traced back focal distance and focal length agree with the
/// paraxial ones to 1e-6 (the angle, 1e-6 rad, leaves aberrations of order 1e-12).
#[test]
fn traced_rays_in_the_paraxial_limit_agree_with_the_transfer_matrices() {
    for (path, nominal) in LENSES {
        let lens = lens(path);
        let f = lens.paraxial.focal_length;
        assert!(
            (f / nominal - 1.0).abs() < 0.02,
            "{path}: f = {f} mm, nominal {nominal}"
        );
        assert_paraxial_trace(path, &lens);
    }
}

/// A ray leaving `lens`'s rear focal point at 1e-6 rad leaves the lens parallel to the axis at
/// the height f tan(angle), to 1e-6.
fn assert_paraxial_trace(name: &str, lens: &LensSystem) {
    assert_paraxial_trace_at(name, lens, &lens.paraxial);
}

/// [`assert_paraxial_trace`] with the focal length and rear focal point of `paraxial` (the lens
/// at another wavelength), the rear focal point its back focal distance behind the rear vertex.
fn assert_paraxial_trace_at(name: &str, lens: &LensSystem, paraxial: &Paraxial) {
    let f = paraxial.focal_length;
    let focal_point = lens.rear_z() - paraxial.back_focal_distance;
    let angle = 1e-6_f64;
    let direction = DVec3::new(0.0, angle.sin(), angle.cos());
    let (origin, out) = lens
        .trace_from_film(DVec3::new(0.0, 0.0, focal_point), direction)
        .unwrap_or_else(|lost| panic!("{name}: {lost:?}"));
    let focal_error = (out.y / out.z).abs() * f / (f * angle.tan());
    assert!(focal_error < 1e-6, "{name}: not parallel: {focal_error:e}");
    let traced_f = origin.y / angle.tan();
    assert!(
        (traced_f / f - 1.0).abs() < 1e-6,
        "{name}: {traced_f} against {f}"
    );
}

/// The dispersive lenses: a Sellmeier singlet (strong axial colour) and the Sironar's Abbe
/// glasses at the e line.
const DISPERSIVE: [&str; 2] = [
    "scenes/lenses/singlet_bk7_100mm.dat",
    "scenes/lenses/sironar_n_150mm.dat",
];

/// The wavelengths (nm) the spectral tests trace at: the range's ends and the Fraunhofer lines.
const WAVELENGTHS: [f64; 6] = [380.0, 486.1327, 546.074, 587.5618, 656.2725, 740.0];

/// At every wavelength, rays traced through the lens's glasses at that wavelength agree with its
/// paraxial properties there (the transfer matrices of the prescription's indices at that
/// wavelength) to 1e-6: the axial colour the spectral mode renders is the lens's own. The
/// singlet's focal length runs from short to long wavelengths as its Abbe number says.
#[test]
fn traced_rays_at_each_wavelength_agree_with_the_paraxial_colours() {
    for path in DISPERSIVE {
        let lens = lens(path);
        for nm in WAVELENGTHS {
            let paraxial = lens.prescription.at_wavelength(nm).paraxial();
            assert_paraxial_trace_at(
                &format!("{path} at {nm} nm"),
                &lens.at_wavelength(nm),
                &paraxial,
            );
        }
    }
    let singlet = lens(DISPERSIVE[0]);
    let f = |nm: f64| {
        singlet
            .prescription
            .at_wavelength(nm)
            .paraxial()
            .focal_length
    };
    // f_C - f_F = f_d / nu_d for a thin lens: 100 / 64.17 = 1.558 mm (thickness moves it a little).
    let spread = f(656.2725) - f(486.1327);
    assert!((spread - 100.18 / 64.17).abs() < 0.02, "{spread}");
    assert!(f(380.0) < f(486.1327) && f(656.2725) < f(740.0));
}

/// The chief ray (through the stop's centre, `LensSystem::chief_ray`) from a film point h off
/// the axis in the rear focal plane at each wavelength leaves, in the paraxial limit, at the
/// slope -h / f there (to 1e-6): the magnification's change with wavelength that lateral colour
/// is. Far off the axis it still crosses the stop's centre (the singlet's stop is flush with its
/// front vertex, where a ray's plane crossing falls a rounding error behind the vertex).
#[test]
fn chief_rays_leave_at_the_slope_of_each_wavelengths_focal_length() {
    for path in DISPERSIVE {
        let lens = lens(path);
        for nm in WAVELENGTHS {
            let paraxial = lens.prescription.at_wavelength(nm).paraxial();
            let coloured = lens.at_wavelength(nm);
            let f = paraxial.focal_length;
            let h = 1e-5 * f;
            let film = DVec3::new(0.0, h, lens.rear_z() - paraxial.back_focal_distance);
            let (_, d) = coloured
                .chief_ray(film)
                .unwrap_or_else(|| panic!("{path} {nm} nm: no chief ray"));
            let ratio = -d.y / d.z * f / h;
            assert!((ratio - 1.0).abs() < 1e-6, "{path} {nm} nm: {ratio}");
            assert!(
                coloured
                    .chief_ray(DVec3::new(0.0, 0.3 * f, film.z))
                    .is_some(),
                "{path} {nm} nm: no chief ray at 0.3 f"
            );
        }
    }
}

/// `chambre lens`'s report: the focal length and back focal distance it prints are the
/// paraxial ones; a dispersive lens's axial colour is the back focal distance's change from F to
/// C (F' to C' at the e line) that the matrices at those wavelengths give, and its lateral colour
/// a finite figure in micrometres; a lens without glass data reports no colour.
#[test]
fn the_lens_report_gives_the_paraxial_figures_and_the_colours() {
    use chambre::camera::glass::ReferenceLine;
    use chambre::camera::report::lens_report;
    let value = |report: &str, label: &str, word: usize| -> f64 {
        let line = report
            .lines()
            .find(|l| l.starts_with(label))
            .unwrap_or_else(|| panic!("no `{label}` in\n{report}"));
        let words: Vec<&str> = line[label.len()..].split_whitespace().collect();
        words[word].trim_start_matches('+').parse().unwrap()
    };
    for path in DISPERSIVE {
        let lens = lens(path);
        let report = lens_report(&lens);
        let p = &lens.paraxial;
        assert!((value(&report, "focal length", 0) - p.focal_length).abs() < 1e-4);
        assert!((value(&report, "back focal distance", 0) - p.back_focal_distance).abs() < 1e-4);
        let (short, long) = lens.prescription.line.abbe_span();
        let at = |nm: f64| {
            lens.prescription
                .at_wavelength(nm)
                .paraxial()
                .back_focal_distance
        };
        let axial = value(&report, "axial colour", 3);
        assert!(
            (axial - (at(long) - at(short))).abs() < 1e-4,
            "{path}: {axial}"
        );
        let lateral = value(&report, "lateral colour", 0);
        assert!(
            lateral.is_finite() && lateral.abs() < 1e3,
            "{path}: {lateral} µm"
        );
        let line = match lens.prescription.line {
            ReferenceLine::D => "the d line",
            ReferenceLine::E => "the e line",
        };
        assert!(report.contains(line), "{path}: {report}");
    }
    let plain = lens_report(&lens(LENSES[0].0));
    assert!(!plain.contains("colour"), "{plain}");
}

/// The kernels' f32 trace at a wavelength (the table's Sellmeier terms) follows the f64 trace
/// through the lens at that wavelength: the ray's end within 64 ulps of its distance from the
/// origin and its direction within 64 ulps, across the film; and at the reference line with the
/// table's index ratios as before.
#[test]
fn the_kernels_trace_at_a_wavelength_follows_the_f64_one() {
    const U: [f32; 2] = [0.45, 0.6];
    for path in DISPERSIVE {
        let lens = lens(path);
        let f = lens.paraxial.focal_length;
        let films: Vec<DVec3> = [0.0, 0.1, 0.25, 0.4]
            .iter()
            .map(|&k| DVec3::new(0.3 * k * f, -k * f, -f).as_vec3().as_dvec3())
            .collect();
        let table = lens.kernel_table(f, |i, _| vec![films[i as usize % films.len()]], true);
        let worst = WAVELENGTHS
            .iter()
            .map(|&nm| f32_trace_error(&lens.at_wavelength(nm), &table, &films, U, nm as f32))
            .fold((0.0_f64, 0.0_f64), |a, b| (a.0.max(b.0), a.1.max(b.1)));
        eprintln!(
            "{path}: worst {:.1} ulps in the end point, {:.1} in the direction",
            worst.0, worst.1
        );
        assert!(worst.0 < 64.0 && worst.1 < 64.0, "{path}: {worst:?}");
    }
}

/// The kernels' f32 trace (`lens_ray` from `table`, at `nm` nanometres; 0: the reference
/// line) from each of `films`, film point i in cell (i, 0), aimed at the point `u` of its
/// cell's bounds, against `lens`'s f64 trace of the same aim: the worst distance between their
/// end points in ulps of the end's distance from the origin, and between their directions in
/// ulps.
fn f32_trace_error(
    lens: &LensSystem,
    table: &[[f32; 2]],
    films: &[DVec3],
    u: [f32; 2],
    nm: f32,
) -> (f64, f64) {
    let count = lens.surfaces.len() as u32;
    let ulp = f32::EPSILON as f64;
    let mut worst = (0.0_f64, 0.0_f64);
    for (i, &film) in films.iter().enumerate() {
        let cell = [i as u32, 0];
        let ray = lens_ray(table, 0, count, film.as_vec3(), Vec3::Z, cell, u, nm);
        assert!(ray.weight > 0.0, "{nm} nm: ray {i} lost in f32");
        let bounds = (1 + 2 * count + 2 * (cell[1] * LENS_PUPIL_CELLS + cell[0])) as usize;
        let (lo, hi) = (Vec2::from(table[bounds]), Vec2::from(table[bounds + 1]));
        let aim = (lo + Vec2::from(u) * (hi - lo)).extend(table[0][1]);
        let (o, d) = lens
            .trace_from_film(film, (aim.as_dvec3() - film).normalize())
            .unwrap();
        worst.0 = worst
            .0
            .max((ray.origin.as_dvec3() - o).length() / (o.length() * ulp));
        worst.1 = worst.1.max((ray.direction.as_dvec3() - d).length() / ulp);
    }
    worst
}

/// The spectral mode through glass that does not disperse (an Abbe number of 1e6) renders the
/// RGB image in expectation: the film's three bands each count once on average. Over a uniform
/// sky at 48 x 32 pixels and 128 samples, each channel's mean differs from the RGB render's by
/// less than four standard errors of the pixels' differences, and that error is below 0.3%
/// (measured: 0.19%).
/// (The differences are noise, not 0: which samples the barrel loses is independent of their
/// wavelengths, so each channel keeps a different share of the passing rays.)
#[test]
fn the_spectral_mode_without_dispersion_renders_the_rgb_image() {
    let folder = std::env::temp_dir().join(format!("chambre-spectral-{}", std::process::id()));
    std::fs::create_dir_all(&folder).unwrap();
    let file = folder.join("flint.dat");
    std::fs::write(&file, "0 0 0 20 0\n100 3 1.7 30 1e6\n-100 0 1 30\n").unwrap();
    let render = |spectral: bool| {
        let text = format!(
            "[render]\nwidth = 48\nheight = 32\nspp = 128\nmax_depth = 0\n\
             background = [1.0, 1.0, 1.0]\n\n[camera]\nposition = [0.0, 0.0, 0.0]\n\
             look_at = [0.0, 0.0, -1.0]\nfilm = [36.0, 24.0]\nlens = \"{}\"\nf_number = 8.0\n\
             lens_shift = [3.0, 0.0]\nspectral = {spectral}\n\n\
             [[materials]]\nname = \"grey\"\nmodel = \"lambert\"\ndiffuse = [0.5, 0.5, 0.5]\n\n\
             [[shapes]]\ntype = \"sphere\"\ncenter = [0.0, 0.0, 10.0]\nradius = 0.1\n\
             material = \"grey\"\n",
            file.display()
        );
        let path = Path::new(env!("CARGO_MANIFEST_DIR")).join(IN_SCENES);
        let scene = Scene::from_str(&path, &text, &[]).unwrap_or_else(|e| panic!("{e}"));
        common::render_cpu(&chambre::pack::flatten(&scene))
    };
    let (plain, spectral) = (render(false), render(true));
    std::fs::remove_dir_all(&folder).unwrap();
    let n = plain.pixels.len() as f64;
    for c in 0..3 {
        let differences: Vec<f64> = plain
            .pixels
            .iter()
            .zip(&spectral.pixels)
            .map(|(p, q)| (q[c] - p[c]) as f64)
            .collect();
        let level = plain.pixels.iter().map(|p| p[c] as f64).sum::<f64>() / n;
        let mean = differences.iter().sum::<f64>() / n;
        let variance = differences.iter().map(|d| (d - mean).powi(2)).sum::<f64>() / (n - 1.0);
        let error = (variance / n).sqrt();
        eprintln!(
            "channel {c}: mean {level:.5}, difference {:+.3}% ({:.2} standard errors of {:.3}%)",
            100.0 * mean / level,
            mean / error,
            100.0 * error / level
        );
        assert!(
            mean.abs() < 4.0 * error,
            "channel {c}: {mean} against {error}"
        );
        assert!(error < 0.003 * level, "channel {c}: standard error {error}");
    }
}

/// Axial colour, rendered: a white half-plane's edge 2 m away through the N-BK7 singlet at
/// f/11, its film at the paraxial focus of 440 nm (the middle of the film's blue band) and then
/// of 680 nm (the red band's). The channel whose band is focused has the sharper edge, at most
/// 0.6 of the other's 20-80% width: blue first, then red. Without the spectral mode the three
/// channels' edges are one.
#[test]
fn the_spectral_mode_focuses_blue_and_red_apart() {
    let singlet = lens(DISPERSIVE[0]);
    // The half-plane stands 2 m before the lens centre H'; its image at `nm` by Newton's
    // x x' = f^2 from the focal points there, in axial mm (from the first vertex towards the
    // film), and the film's distance from H'.
    let film_distance = |nm: f64| {
        let p = singlet.prescription.at_wavelength(nm).paraxial();
        let h = singlet.paraxial.rear_principal;
        let (object, front_focus) = (h - 2000.0, -p.front_focal_distance);
        let image =
            p.last_vertex + p.back_focal_distance + p.focal_length.powi(2) / (front_focus - object);
        image - h
    };
    let (width, height) = (120u32, 40u32);
    let edge_widths = |film_distance: f64, spectral: bool| {
        let text = format!(
            "[render]\nwidth = {width}\nheight = {height}\nspp = 64\nseed = 2\nmax_depth = 0\n\
             background = [0.0, 0.0, 0.0]\nambient = [1.0, 1.0, 1.0]\n\n\
             [camera]\nposition = [0.0, 0.0, 0.0]\nlook_at = [0.0, 0.0, -1.0]\n\
             film = [3.0, 1.0]\nlens = \"lenses/singlet_bk7_100mm.dat\"\nf_number = 11.0\n\
             film_distance = {film_distance}\nspectral = {spectral}\nlens_sampler = \"stratified\"\n\n\
             [[materials]]\nname = \"white\"\nmodel = \"lambert\"\ndiffuse = [1.0, 1.0, 1.0]\n\n\
             [[shapes]]\ntype = \"quad\"\ncorner = [-5.0, -5.0, -2.0]\n\
             edge_u = [5.0, 0.0, 0.0]\nedge_v = [0.0, 10.0, 0.0]\nmaterial = \"white\"\n"
        );
        let path = Path::new(env!("CARGO_MANIFEST_DIR")).join(IN_SCENES);
        let scene = Scene::from_str(&path, &text, &[]).unwrap_or_else(|e| panic!("{e}"));
        let image = common::render_cpu(&chambre::pack::flatten(&scene));
        // Each channel's column profile (the mean of the rows), white on the left, and the
        // distance between its crossings of 80% and 20% of the white side's level.
        let mut widths = [0.0f64; 3];
        for (c, w) in widths.iter_mut().enumerate() {
            let profile: Vec<f64> = (0..width)
                .map(|x| {
                    (0..height)
                        .map(|y| image.pixels[(y * width + x) as usize][c] as f64)
                        .sum::<f64>()
                        / height as f64
                })
                .collect();
            let white = profile[..15].iter().sum::<f64>() / 15.0;
            let crossing = |level: f64| {
                let x = profile.iter().position(|&v| v < level * white).unwrap();
                let (a, b) = (profile[x - 1], profile[x]);
                x as f64 - 1.0 + (a - level * white) / (a - b)
            };
            *w = crossing(0.2) - crossing(0.8);
        }
        widths
    };
    let [red_f, _, blue_f] = edge_widths(film_distance(440.0), true);
    let [red_c, _, blue_c] = edge_widths(film_distance(680.0), true);
    let [red, green, blue] = edge_widths(film_distance(440.0), false);
    eprintln!(
        "edge widths (px): at 440 nm red {red_f:.2} blue {blue_f:.2}; at 680 nm red {red_c:.2} blue {blue_c:.2}; RGB {red:.2} {green:.2} {blue:.2}"
    );
    assert!(
        blue_f < 0.6 * red_f,
        "at 440 nm: blue {blue_f}, red {red_f}"
    );
    assert!(
        red_c < 0.6 * blue_c,
        "at 680 nm: red {red_c}, blue {blue_c}"
    );
    assert!((red - blue).abs() < 1e-3 && (green - blue).abs() < 1e-3);
}

fn parsed(name: &str, text: &str) -> LensSystem {
    let prescription = Prescription::parse(Path::new(name), text).unwrap();
    LensSystem::new(&prescription, None).unwrap()
}

/// A plano-convex singlet written with `inf` has the lensmaker's focal length R / (n - 1)
/// whatever its thickness (to 1e-9), its plane facing the film or the object, and rays traced
/// through it in the paraxial limit agree.
#[test]
fn a_plano_convex_lens_written_with_inf_has_the_lensmakers_focal_length() {
    let (r, n) = (60.0, 1.5168);
    let lensmaker = r / (n - 1.0);
    for text in [
        format!("0 0 1 10\n{r} 8 {n} 40\ninf 0 1 40\n"),
        format!("0 0 1 10\ninf 8 {n} 40\n{} 0 1 40\n", -r),
    ] {
        let lens = parsed("plano_convex.dat", &text);
        let f = lens.paraxial.focal_length;
        assert!(
            (f / lensmaker - 1.0).abs() < 1e-9,
            "{text}: f = {f}, lensmaker's {lensmaker}"
        );
        assert_paraxial_trace(&text, &lens);
    }
}

/// A parallel glass plate of thickness 6 and index 1.7 (two `inf` surfaces) in front of a
/// converging lens, and the lens alone (each placed with its H' at the origin: the plate moves
/// neither focal point nor H').
fn plate_and_lens(plate: &str) -> (LensSystem, LensSystem) {
    let lens = "0 0 1 40\n100 5 1.5 60\n-100 0 1 60\n";
    let with_plate = format!("{plate} 6 1.7 200\n{plate} 10 1 200\n{lens}");
    (parsed("plate.dat", &with_plate), parsed("lens.dat", lens))
}

/// Film points whose rays through the stop's centre leave the lens at 0 to about 40 degrees.
const PLATE_FILM_HEIGHTS: [f64; 5] = [0.0, 10.0, 30.0, 60.0, 85.0];

/// Through the plate a ray keeps its direction (to 1e-12) and is shifted sideways by the
/// textbook t sin(theta) (1 - cos(theta) / sqrt(n^2 - sin^2(theta))), to 1e-9 mm, in f64: the
/// same ray traced through the lens alone is the one the plate receives.
#[test]
fn a_parallel_plate_shifts_a_ray_by_the_textbook_amount() {
    let (plate, alone) = plate_and_lens("inf");
    let (t, n) = (6.0, 1.7);
    let f = alone.paraxial.focal_length;
    let mut steepest = 0.0_f64;
    for height in PLATE_FILM_HEIGHTS {
        let film = DVec3::new(0.0, -height, -f);
        let direction = (DVec3::new(0.0, 0.0, alone.stop_z()) - film).normalize();
        let (o1, d1) = alone.trace_from_film(film, direction).unwrap();
        let (o2, d2) = plate.trace_from_film(film, direction).unwrap();
        assert!((d2 - d1).length() < 1e-12, "{height}: {d1} became {d2}");
        let across = o2 - o1;
        let shift = (across - across.dot(d1) * d1).length();
        let theta = d1.z.acos();
        let (sin, cos) = theta.sin_cos();
        let textbook = t * sin * (1.0 - cos / (n * n - sin * sin).sqrt());
        assert!(
            (shift - textbook).abs() < 1e-9,
            "{height}: shifted {shift}, textbook {textbook} at {} degrees",
            theta.to_degrees()
        );
        steepest = steepest.max(theta.to_degrees());
    }
    assert!(steepest > 35.0, "{steepest} degrees at most");
}

/// The kernels' f32 trace ([`lens_ray`], twin of wgsl/camera.wgsl) through the plate's planes
/// (radius 0 in the table) agrees with the f64 trace to f32 precision: the ray's end within
/// 16 ulps of its distance from the origin, its direction within 16 ulps (measured: 1.8 and 1.4).
/// The same plate written with radius 1e6 misses that by far (measured: 25000 ulps, f32
/// cancellation in the sphere's intersection).
#[test]
fn a_parallel_plate_traced_in_f32_agrees_with_f64() {
    // Off the bounds' centre: a ray along the axis meets the front vertex and the stop flush
    // with it at the same z, where the f32 trace may put the vertex an ulp past the stop.
    const U: [f32; 2] = [0.5, 0.6];
    let error_through = |plate: &str| {
        let (lens, _) = plate_and_lens(plate);
        let f = lens.paraxial.focal_length;
        let films: Vec<DVec3> = PLATE_FILM_HEIGHTS
            .iter()
            .map(|&h| DVec3::new(0.0, -h, -f).as_vec3().as_dvec3())
            .collect();
        let table = lens.kernel_table(f, |i, _| vec![films[i as usize % films.len()]], false);
        let worst = f32_trace_error(&lens, &table, &films, U, 0.0);
        eprintln!(
            "{plate}: worst error {:.1} ulps in the end point, {:.1} in the direction",
            worst.0, worst.1
        );
        worst
    };
    let (end, direction) = error_through("inf");
    assert!(end < 16.0 && direction < 16.0, "{end} and {direction} ulps");
    let (end, _) = error_through("1e6");
    assert!(end > 1000.0, "radius 1e6 in f32: {end} ulps");
}

/// The image circle's dark edge, found apart from the illumination grids, is where the last ray
/// passes: just inside it (1e-3 f) a ray aimed along the meridian passes (a dense search of
/// 100001 aims finds it), just outside it none of 301 x 301 aims over a square wider than every
/// aperture does, for each shipped lens at f/22 and the double Gauss wide open.
#[test]
fn the_dark_edge_of_the_image_circle_is_where_the_last_ray_passes() {
    let mut cases: Vec<LensSystem> = LENSES
        .iter()
        .map(|(path, _)| {
            let p = Prescription::read(Path::new(path)).unwrap();
            LensSystem::new(&p, Some(22.0)).unwrap()
        })
        .collect();
    cases.push(lens(LENSES[0].0));
    for lens in cases {
        let f = lens.paraxial.focal_length;
        let circle = lens.image_circle(f, f / 400.0, 4.0 * f);
        let (z, half) = (lens.aim_z(), 4.0 * lens.rear_square());
        let from = |r: f64| DVec3::new(r, 0.0, -f);
        let passes = |film: DVec3, x: f64, y: f64| {
            let d = (DVec3::new(x, y, z) - film).normalize();
            lens.trace_from_film(film, d).is_ok()
        };
        let inside = from(circle.dark_radius - 1e-3 * f);
        let found = (0..=100_000).any(|i| passes(inside, -half + 2.0 * half * i as f64 / 1e5, 0.0));
        let outside = from(circle.dark_radius + 1e-3 * f);
        let leaked = (0..=300).any(|i| {
            (0..=300).any(|j| {
                let t = |k: i32| -half + 2.0 * half * k as f64 / 300.0;
                passes(outside, t(i), t(j))
            })
        });
        eprintln!(
            "f/{:.1}, f = {f:.1}: dark edge at {:.3} mm",
            lens.f_number, circle.dark_radius
        );
        assert!(found, "f = {f}: no ray just inside {}", circle.dark_radius);
        assert!(
            !leaked,
            "f = {f}: a ray just outside {}",
            circle.dark_radius
        );
    }
}

/// Stopped down, the marginal rays of the widest aperture are lost at the stop and the axial
/// rays within it pass; a ray far off axis is lost to a barrel, never returned.
#[test]
fn the_stop_and_the_barrel_stop_rays() {
    let prescription = Prescription::read(Path::new(LENSES[0].0)).unwrap();
    let wide = LensSystem::new(&prescription, None).unwrap();
    let stopped = LensSystem::new(&prescription, Some(8.0)).unwrap();
    let f = wide.paraxial.focal_length;
    let from = DVec3::new(0.0, 0.0, -f);
    // Aimed at the rear element's edge: through at f/2, stopped at f/8.
    let rear = wide.surfaces[0];
    let edge = DVec3::new(0.0, 0.9 * rear.aperture_radius, rear.z) - from;
    assert!(wide.trace_from_film(from, edge.normalize()).is_ok());
    assert_eq!(
        stopped.trace_from_film(from, edge.normalize()),
        Err(Lost::Blocked(stopped.stop))
    );
    let far = DVec3::new(0.0, 0.8, 1.0).normalize();
    assert!(matches!(
        wide.trace_from_film(from, far),
        Err(Lost::Blocked(_))
    ));
}

/// Through a small stop that nothing else vignettes, the relative illumination follows the
/// cos^4 law of the angle the film point sees the exit pupil's centre at (a biconvex lens of
/// 100 mm at f/16, its stop in front; within 1% out to 17 degrees), and a lens stopped down
/// loses less to vignetting than wide open, never more.
#[test]
fn relative_illumination_follows_the_cosine_fourth_law_through_a_small_stop() {
    let f = 100.0_f64;
    let sag = f - (f * f - 100.0).sqrt();
    let text = format!("0 0 1 10\n{f} {} 1.5 20\n{} 0 1 20\n", 2.0 * sag + 0.1, -f);
    let prescription = Prescription::parse(Path::new("biconvex.dat"), &text).unwrap();
    let lens = LensSystem::new(&prescription, Some(16.0)).unwrap();
    let p = lens.paraxial;
    let exit_pupil_z = p.rear_principal - p.exit_pupil;
    let film = p.focal_length;
    for r in [5.0, 15.0, 30.0] {
        let relative = lens.relative_illumination(r, film, 400);
        let cos = (film + exit_pupil_z) / (r * r + (film + exit_pupil_z).powi(2)).sqrt();
        let law = cos.powi(4);
        assert!(
            (relative / law - 1.0).abs() < 0.01,
            "r {r}: {relative} against {law}"
        );
    }
    let prescription = Prescription::read(Path::new(LENSES[0].0)).unwrap();
    let open = LensSystem::new(&prescription, None).unwrap();
    let stopped = LensSystem::new(&prescription, Some(8.0)).unwrap();
    let film = open.paraxial.focal_length;
    let mut previous = 1.0;
    for r in [5.0, 10.0, 15.0, 20.0] {
        let (wide, narrow) = (
            open.relative_illumination(r, film, 128),
            stopped.relative_illumination(r, film, 128),
        );
        assert!(
            wide <= previous + 1e-9,
            "falls off the axis: {wide} after {previous}"
        );
        assert!(
            narrow >= wide - 0.01,
            "r {r}: f/8 {narrow} against f/2 {wide}"
        );
        previous = wide;
    }
}

mod common;

/// Where the tests' scene texts say they stand: a path no file has, in `scenes/`, so that their
/// `lens = "lenses/..."` finds the shipped prescriptions.
const IN_SCENES: &str = "scenes/virtual_lens_scene.toml";

use chambre::metrics::rel_mse;
use chambre::scene::Scene;

/// A scene of `camera` lines (TOML) with spheres on a floor under two lights, `size` pixels,
/// read as if it stood in `scenes/` (so `lens = "lenses/..."` finds the shipped files).
fn scene(camera: &str, size: [u32; 2], spp: u32, seed: u32, extra: &str) -> Scene {
    let text = format!(
        r#"
[render]
width = {w}
height = {h}
spp = {spp}
seed = {seed}
background = [0.2, 0.25, 0.3]
{extra}

[camera]
position = [0.0, 1.0, 6.0]
look_at = [0.0, 0.8, 0.0]
lens_sampler = "stratified"
{camera}

[[materials]]
name = "clay"
model = "lambert"
diffuse = [0.7, 0.5, 0.3]

[[materials]]
name = "floor"
model = "lambert"
diffuse = [0.4, 0.4, 0.4]

[[shapes]]
type = "sphere"
center = [0.0, 0.8, 0.0]
radius = 0.8
material = "clay"

[[shapes]]
type = "sphere"
center = [1.3, 0.4, 2.0]
radius = 0.4
material = "clay"

[[shapes]]
type = "sphere"
center = [-1.5, 0.5, -3.0]
radius = 0.5
material = "clay"

[[shapes]]
type = "quad"
corner = [-10.0, 0.0, -10.0]
edge_u = [0.0, 0.0, 20.0]
edge_v = [20.0, 0.0, 0.0]
material = "floor"

[[lights]]
type = "point"
position = [3.0, 5.0, 4.0]
intensity = [30.0, 30.0, 30.0]

[[lights]]
type = "area"
corner = [-3.0, 4.0, 1.0]
edge_u = [1.0, 0.0, 0.0]
edge_v = [0.0, 0.0, 1.0]
radiance = [4.0, 4.0, 4.0]
"#,
        w = size[0],
        h = size[1],
    );
    let path = Path::new(env!("CARGO_MANIFEST_DIR")).join(IN_SCENES);
    Scene::from_str(&path, &text, &[]).unwrap_or_else(|e| panic!("{e}"))
}

/// A uniform sky of radiance 1 seen through `camera` at 12 x 8 pixels and `spp` samples (one
/// small sphere behind the camera, which no ray meets).
fn sky(camera: &str, spp: u32) -> Scene {
    let text = format!(
        r#"
[render]
width = 12
height = 8
spp = {spp}
max_depth = 0
background = [1.0, 1.0, 1.0]

[camera]
position = [0.0, 0.0, 0.0]
look_at = [0.0, 0.0, -1.0]
lens_sampler = "stratified"
{camera}

[[materials]]
name = "grey"
model = "lambert"
diffuse = [0.5, 0.5, 0.5]

[[shapes]]
type = "sphere"
center = [0.0, 0.0, 10.0]
radius = 0.1
material = "grey"
"#
    );
    let path = Path::new(env!("CARGO_MANIFEST_DIR")).join(IN_SCENES);
    Scene::from_str(&path, &text, &[]).unwrap_or_else(|e| panic!("{e}"))
}

/// The same scene through a real lens renders alike on the GPU and the CPU (the kernels' f32
/// tracing through the glass, the exit-pupil bounds and the weights), under Whitted and the
/// path tracer (the wavefront render), wide open and with the lens tilted and the film shifted,
/// and through the Sironar's plane cemented interfaces with a rising front.
#[test]
fn a_real_lens_renders_alike_on_gpu_and_cpu() {
    let cameras = [
        "film = [36.0, 24.0]\nlens = \"lenses/dgauss_50mm.dat\"\nfocus_distance = 6.0",
        "film = [36.0, 24.0]\nlens = \"lenses/dgauss_50mm.dat\"\nf_number = 4.0\n\
         focus_distance = 6.0\nlens_tilt = 6.0\nfilm_shift = [0.0, 4.0]",
        // A base tilt: the lens turns about an axis 80 mm below it, which moves it as well.
        "film = [36.0, 24.0]\nlens = \"lenses/dgauss_50mm.dat\"\nf_number = 4.0\n\
         focus_distance = 6.0\nlens_tilt = 5.0\nlens_pivot = [0.0, -80.0, 0.0]",
        // Two plane cemented interfaces, refracting in the kernels where their index changes.
        "film = [120.0, 80.0]\nlens = \"lenses/sironar_n_150mm.dat\"\nf_number = 8.0\n\
         focus_distance = 6.0\nfilm_shift = [0.0, 12.0]",
        // The spectral mode: each sample at its wavelength through Sellmeier and Abbe glasses.
        "film = [36.0, 24.0]\nlens = \"lenses/singlet_bk7_100mm.dat\"\nf_number = 6.0\n\
         focus_distance = 6.0\nspectral = true\nlens_shift = [4.0, 0.0]",
        "film = [120.0, 80.0]\nlens = \"lenses/sironar_n_150mm.dat\"\nf_number = 8.0\n\
         focus_distance = 6.0\nspectral = true\nfilm_shift = [0.0, 12.0]",
    ];
    for camera in cameras {
        for integrator in ["max_depth = 1", "integrator = \"path\"\nmax_depth = 3"] {
            let images = common::both(&scene(camera, [48, 32], 16, 3, integrator));
            let Some((_, gpu)) = images.get(1) else {
                continue;
            };
            let (within, mean) = common::agreement(&images[0].1, gpu, 1e-3);
            assert!(
                within >= 0.999,
                "{camera} {integrator}: {within} within 1e-3, mean {mean}"
            );
        }
    }
}

/// A real lens that is nearly the thin lens (a biconvex singlet of 100 mm at f/16, its field
/// 3 degrees wide, so cos^4 stays within 0.5%) renders the thin lens's image of the same focal
/// length and f-number, with a lens tilt and a film shift: its error against the thin lens (whose
/// image is nearly noiseless here) is no more than the error between two of its own renders of
/// different seeds (twice its variance: so any bias is below its noise), and its mean is the thin
/// lens's within 1%.
#[test]
fn a_nearly_thin_real_lens_renders_the_thin_lens_image() {
    let prescription = Prescription::read(Path::new("scenes/lenses/singlet_100mm.dat")).unwrap();
    let f = LensSystem::new(&prescription, Some(16.0))
        .unwrap()
        .paraxial
        .focal_length;
    let movements = "film = [8.0, 6.0]\nf_number = 16.0\nfocus_distance = 6.0\n\
                     lens_tilt = 3.0\nfilm_shift = [1.0, 0.5]";
    let real = format!("{movements}\nlens = \"lenses/singlet_100mm.dat\"");
    let thin = format!("{movements}\nfocal_length = {f}");
    let render = |camera: &str, seed: u32| {
        let scene = scene(camera, [40, 30], 256, seed, "max_depth = 1");
        common::render_cpu(&chambre::pack::flatten(&scene))
    };
    let (real, real_again, thin) = (render(&real, 1), render(&real, 2), render(&thin, 3));
    let (error, noise) = (rel_mse(&real, &thin), rel_mse(&real, &real_again));
    assert!(
        error <= noise,
        "relMSE {error:e} against the thin lens, {noise:e} between seeds"
    );
    let mean = |image: &chambre::render::Image| {
        image.pixels.iter().map(|p| p.x as f64).sum::<f64>() / image.pixels.len() as f64
    };
    let ratio = mean(&real) / mean(&thin);
    assert!(
        (ratio - 1.0).abs() < 0.01,
        "mean {ratio} of the thin lens's"
    );
}

/// Under a uniform sky of radiance 1 each pixel records the relative illumination at its film
/// point: it matches the f64 integral over the rays the f64 tracer lets through (within 2%,
/// where at least 30% of the axis's light arrives), centred, with a rising front and with a
/// tilted lens.
#[test]
fn relative_illumination_on_the_film_matches_the_traced_exit_pupil() {
    let cameras = [
        "film = [36.0, 24.0]\nlens = \"lenses/dgauss_50mm.dat\"",
        "film = [36.0, 24.0]\nlens = \"lenses/dgauss_50mm.dat\"\nf_number = 2.8\n\
         film_shift = [0.0, 6.0]",
        "film = [36.0, 24.0]\nlens = \"lenses/dgauss_50mm.dat\"\nf_number = 2.8\n\
         lens_tilt = 8.0",
    ];
    for camera in cameras {
        let sky = sky(camera, 4096);
        let image = common::render_cpu(&chambre::pack::flatten(&sky));
        let spec = &sky.camera;
        let lens = spec.lens.as_ref().unwrap();
        let s = spec.standards();
        let axis = lens.irradiance(DVec3::new(0.0, 0.0, -spec.film_distance_mm), 256);
        let normal = s.lens.transpose() * s.film.z_axis;
        let mut compared = 0;
        for y in 0..8u32 {
            for x in 0..12u32 {
                let film_mm = glam::DVec2::new(
                    (x as f64 + 0.5) / 12.0 * 36.0 - 18.0,
                    12.0 - (y as f64 + 0.5) / 8.0 * 24.0,
                );
                let point = s.to_lens_frame(s.film_point(film_mm));
                let expected = lens.irradiance_on(point, normal, 256) / axis;
                let got = image.pixels[(y * 12 + x) as usize].x as f64;
                if expected >= 0.3 {
                    compared += 1;
                    assert!(
                        (got / expected - 1.0).abs() < 0.02,
                        "{camera}: pixel ({x}, {y}) {got} against {expected}"
                    );
                }
            }
        }
        assert!(compared >= 24, "{camera}: {compared} pixels compared");
    }
}

/// What a real lens replaces or does not have yet is refused by field name, as are an f-number
/// wider than the lens opens, a film pushed into the glass and a lens file that is missing.
#[test]
fn camera_fields_a_real_lens_cannot_take_are_refused_by_name() {
    let lens = "film = [36.0, 24.0]\nlens = \"lenses/dgauss_50mm.dat\"";
    let cases = [
        (
            format!("{lens}\nfocal_length = 50.0"),
            "camera.focal_length",
        ),
        (
            format!("{lens}\naperture_blades = 6"),
            "camera.aperture_blades",
        ),
        (format!("{lens}\nf_number = 1.4"), "camera.f_number"),
        (
            format!("{lens}\nfocus_points = [[0, 0, 9], [1, 0, 9], [0, 1, 9]]"),
            "camera.focus_points",
        ),
        (
            format!("{lens}\nlens_pivot = \"nodal\""),
            "camera.lens_pivot",
        ),
        (
            format!("{lens}\nfocus_surface = \"sphere\"\nfocus_distance = 5.0"),
            "camera.focus_surface",
        ),
        (
            format!("{lens}\nfilm_distance = 52.0\nlens_tilt = 70.0"),
            "film corner reaches",
        ),
        (
            "film = [36.0, 24.0]\nlens = \"lenses/none.dat\"".to_string(),
            "none.dat",
        ),
        // The spectral mode needs glass that disperses: none in the double Gauss's file, and
        // no glass at all in a thin lens.
        (format!("{lens}\nspectral = true"), "camera.spectral"),
        (
            "film = [36.0, 24.0]\nf_number = 4.0\nspectral = true".to_string(),
            "camera.spectral",
        ),
    ];
    for (camera, field) in cases {
        let text = format!(
            "[render]\nwidth = 36\nheight = 24\n\n[camera]\nposition = [0, 0, 5]\n\
             look_at = [0, 0, 0]\n{camera}\n\n[[materials]]\nname = \"m\"\n\
             model = \"lambert\"\ndiffuse = [0.5, 0.5, 0.5]\n\n[[shapes]]\n\
             type = \"sphere\"\ncenter = [0, 0, 0]\nradius = 1\nmaterial = \"m\"\n"
        );
        let path = Path::new(env!("CARGO_MANIFEST_DIR")).join(IN_SCENES);
        match Scene::from_str(&path, &text, &[]) {
            Err(e) => assert!(e.to_string().contains(field), "{camera}: {e}"),
            Ok(_) => panic!("{camera}: accepted"),
        }
    }
}

/// With the film square to the axis, a corner's light depends on its distance from the axis
/// alone: the rise that keeps every corner above half the axis's light puts the top corners on
/// the image circle `chambre lens` reports (within 1%). A film past the circle is warned of.
#[test]
fn movement_limits_put_the_corners_on_the_image_circle() {
    let f = 50.3582;
    let camera = format!(
        "film = [24.0, 16.0]\nlens = \"lenses/dgauss_50mm.dat\"\nf_number = 8.0\n\
         film_distance = {f}"
    );
    let scene = scene(&camera, [24, 16], 1, 1, "");
    let spec = &scene.camera;
    let lens = spec.lens.as_ref().unwrap();
    let circle = lens.image_circle(spec.film_distance_mm, f / 400.0, 4.0 * f);
    let limits = spec.movement_limits();
    let rise = limits
        .iter()
        .find(|(m, _)| *m == chambre::camera::coverage::Movement::Rise)
        .and_then(|(_, v)| *v)
        .unwrap();
    let corner = 12.0_f64.hypot(8.0 + rise);
    assert!(
        (corner / circle.half_radius - 1.0).abs() < 0.01,
        "corner at {corner} mm, circle {circle:?}"
    );
    assert!(scene.warnings().is_empty(), "{:?}", scene.warnings());
    let wide_open = "film = [36.0, 24.0]\nlens = \"lenses/dgauss_50mm.dat\"";
    let wide_open = self::scene(wide_open, [36, 24], 1, 1, "");
    assert!(
        wide_open
            .warnings()
            .iter()
            .any(|w| w.contains("image circle"))
    );
}

/// At the extremes the image stays finite and true: the double Gauss stopped to f/256 (a stop
/// 0.2 mm across, too small for the first search of its pupil; 2% of the rays aimed through its
/// bounds pass) still exposes the middle of a uniform sky to 1, within 6% over the four central
/// pixels at 65536 samples (about 4 standard deviations), and every pixel is finite.
#[test]
fn a_stop_closed_to_f256_still_exposes_the_axis() {
    let camera = "film = [36.0, 24.0]\nlens = \"lenses/dgauss_50mm.dat\"\nf_number = 256.0";
    let image = common::render_cpu(&chambre::pack::flatten(&sky(camera, 65536)));
    assert!(image.pixels.iter().all(|p| p.is_finite()));
    let central = [(5, 3), (6, 3), (5, 4), (6, 4)];
    let centre = central
        .iter()
        .map(|&(x, y)| image.pixels[y * 12 + x].x as f64)
        .sum::<f64>()
        / 4.0;
    assert!((centre - 1.0).abs() < 0.06, "centre {centre}");
}

/// Movements far past the image circle and rays at grazing angles render finite pixels, alike on
/// both paths: the double Gauss's film risen 60 mm (its circle is 56 mm across to dark: the
/// frame goes black), the wide angle wide open on a film twice its circle's width with the lens
/// tilted 12 degrees (rays meeting its steep surfaces at grazing angles, some totally
/// reflected), and the spectral singlet shifted 40 mm and swung 25 degrees. Tilted 30 degrees,
/// the wide angle's film would cross the lens plane: refused by name.
#[test]
fn far_past_the_image_circle_and_at_grazing_angles_pixels_stay_finite() {
    let cameras = [
        "film = [36.0, 24.0]\nlens = \"lenses/dgauss_50mm.dat\"\nfocus_distance = 6.0\n\
         film_shift = [0.0, 60.0]",
        "film = [72.0, 48.0]\nlens = \"lenses/wide_22mm.dat\"\nfocus_distance = 6.0\n\
         lens_tilt = 12.0",
        "film = [36.0, 24.0]\nlens = \"lenses/singlet_bk7_100mm.dat\"\nfocus_distance = 6.0\n\
         spectral = true\nlens_shift = [40.0, 0.0]\nlens_swing = 25.0",
    ];
    for camera in cameras {
        let images = common::both(&scene(camera, [36, 24], 16, 4, "max_depth = 1"));
        for (name, image) in &images {
            assert_eq!(image.non_finite_count(), 0, "{camera}: {name}");
        }
        let lit = images[0]
            .1
            .pixels
            .iter()
            .filter(|p| p.max_element() > 0.0)
            .count();
        eprintln!("{camera}: {lit} of {} pixels lit", images[0].1.pixels.len());
        if let Some((_, gpu)) = images.get(1) {
            let (within, mean) = common::agreement(&images[0].1, gpu, 1e-3);
            assert!(
                within >= 0.999,
                "{camera}: {within} within 1e-3, mean {mean}"
            );
        }
    }
    let crossing = "film = [72.0, 48.0]\nlens = \"lenses/wide_22mm.dat\"\nlens_tilt = 30.0";
    let text = format!(
        "[render]\nwidth = 36\nheight = 24\n\n[camera]\nposition = [0, 0, 5]\n\
         look_at = [0, 0, 0]\n{crossing}\n\n[[materials]]\nname = \"m\"\n\
         model = \"lambert\"\ndiffuse = [0.5, 0.5, 0.5]\n\n[[shapes]]\n\
         type = \"sphere\"\ncenter = [0, 0, 0]\nradius = 1\nmaterial = \"m\"\n"
    );
    let path = Path::new(env!("CARGO_MANIFEST_DIR")).join(IN_SCENES);
    let refusal = Scene::from_str(&path, &text, &[]).unwrap_err().to_string();
    assert!(refusal.contains("no image can form"), "{refusal}");
}

/// The tabletop's board through a tilted double Gauss wide open (f/2), focused by
/// `focus_points`: the thick lens's paraxial solution, refined by tracing to the least blur of
/// the three points, keeps the board as sharp as the same lens stopped down to f/22 (deep
/// focus) from front to back (within its own wide-open halo), where the untilted lens focused
/// on the middle blurs both ends.
/// The refinement leaves less traced blur than the paraxial solution.
#[test]
fn a_tilted_real_lens_focused_on_three_points_keeps_a_receding_board_sharp() {
    use chambre::camera::lens_focus::{TracedFocus, traced_focus, triangle_samples};
    use chambre::camera::optics::solve_focus_points;
    let path = Path::new(concat!(env!("CARGO_MANIFEST_DIR"), "/scenes/tabletop.toml"));
    let points = "focus_points = [[-0.4, 0.0, -0.5], [0.4, 0.0, -0.5], [0.0, 0.0, -3.0]]";
    // The board alone, lit by the ambient term only (as the thin lens's test in
    // tests/view_camera.rs), so that light-sampling noise does not pass for detail.
    let text = std::fs::read_to_string(path)
        .unwrap()
        .split("\n[[")
        .filter(|section| {
            !section.starts_with("shapes]]\ntype = \"sphere\"") && !section.starts_with("lights]]")
        })
        .collect::<Vec<_>>()
        .join("\n[[")
        .replace("ambient = [0.05, 0.05, 0.05]", "ambient = [1.0, 1.0, 1.0]")
        .replace("focal_length = 90.0", "lens = \"lenses/dgauss_50mm.dat\"")
        .replace("aperture_blades = 7\n", "");
    let small = ["render.width=240", "render.height=160", "render.spp=32"].map(String::from);
    let load = |focus: &str, f_number: &str| {
        let text = text
            .replace(points, focus)
            .replace("f_number = 2.8", &format!("f_number = {f_number}"));
        Scene::from_str(path, &text, &small).unwrap_or_else(|e| panic!("{e}"))
    };
    let tilted = load(points, "2.0302");
    let c = &tilted.camera;
    let world = [
        DVec3::new(-0.4, 0.0, -0.5),
        DVec3::new(0.4, 0.0, -0.5),
        DVec3::new(0.0, 0.0, -3.0),
    ];
    let samples = triangle_samples(&world);
    let blur = |t: Vec<TracedFocus>| t.iter().map(|t| t.blur_um).collect::<Vec<_>>();
    let refined = blur(traced_focus(c, &samples).unwrap());
    let mut paraxial = c.clone();
    paraxial.movements.lens_tilt = 0.0;
    let solution = solve_focus_points(&paraxial, world).unwrap();
    paraxial.movements.lens_tilt = solution.lens_tilt;
    paraxial.movements.lens_swing = solution.lens_swing;
    paraxial.film_distance_mm = solution.film_distance_mm;
    let before = blur(traced_focus(&paraxial, &samples).unwrap());
    let sum = |b: &[f64]| b.iter().map(|v| v * v).sum::<f64>();
    eprintln!(
        "traced blur (um): paraxial {before:.1?} at tilt {:.4}, refined {refined:.1?} at tilt {:.4}",
        solution.lens_tilt, c.movements.lens_tilt
    );
    assert!(sum(&refined) < sum(&before), "{refined:?} vs {before:?}");
    assert!(
        c.movements.lens_tilt.abs() > 1.0,
        "{}",
        c.movements.lens_tilt
    );

    let render = |scene: &Scene| common::render_cpu(&chambre::pack::flatten(scene));
    let (tilted_image, tilted_deep) = (render(&tilted), render(&load(points, "22")));
    let plain_focus = "focus_distance = 1.5";
    let (plain_image, plain_deep) = (
        render(&load(plain_focus, "2.0302")),
        render(&load(plain_focus, "22")),
    );
    // The middle half of the columns: the corners' vignetting makes their pixels noisy.
    let columns = (0.25, 0.75);
    let bands = [
        ("far", (0.0, 0.3)),
        ("middle", (0.45, 0.6)),
        ("near", (0.8, 1.0)),
    ]
    .map(|(name, rows)| {
        let t = common::sharpness(&tilted_image, rows, columns)
            / common::sharpness(&tilted_deep, rows, columns);
        let p = common::sharpness(&plain_image, rows, columns)
            / common::sharpness(&plain_deep, rows, columns);
        eprintln!("{name}: tilted real lens {t:.3}, untilted {p:.3} of f/22's sharpness");
        (name, t, p)
    });
    // Wide open, the double Gauss's halo (spherical aberration) lowers contrast even in focus:
    // the untilted lens reaches about 0.85 of f/22's sharpness on the band it is focused on.
    for (name, t, p) in bands {
        assert!(
            t > 0.7,
            "{name}: the tilted real lens blurs the board ({t:.3})"
        );
        if name != "middle" {
            assert!(
                p < 0.6,
                "{name}: the untilted lens should blur here ({p:.3})"
            );
            assert!(
                t > 1.5 * p,
                "{name}: tilting should sharpen ({t:.3} vs {p:.3})"
            );
        }
    }
}

/// The thick lens's paraxial `focus_points` solution puts its plane of sharp focus (measured
/// from H) through the three points to 1e-9 of their distance, whatever the lens turns about:
/// its centre, its front nodal point, its stop, or a base tilt's axis 120 mm below it (which
/// moves the lens as it turns, and so needs a different tilt).
#[test]
fn a_real_lens_focus_plane_passes_through_the_points_for_every_pivot() {
    use chambre::camera::optics::solve_focus_points;
    let world = [
        DVec3::new(-1.0, 0.0, 2.0),
        DVec3::new(1.2, 0.1, 1.0),
        DVec3::new(0.0, 0.3, -4.0),
    ];
    let mut tilts = Vec::new();
    for pivot in [
        "\"rear_nodal\"",
        "\"front_nodal\"",
        "\"stop\"",
        "[0.0, -120.0, 0.0]",
    ] {
        let scene = scene(
            &format!(
                "film = [36.0, 24.0]\nlens = \"lenses/dgauss_50mm.dat\"\nf_number = 8.0\n\
                 lens_pivot = {pivot}"
            ),
            [36, 24],
            1,
            0,
            "",
        );
        let mut c = scene.camera.clone();
        let solution = solve_focus_points(&c, world).unwrap_or_else(|e| panic!("{pivot}: {e}"));
        c.movements.lens_tilt = solution.lens_tilt;
        c.movements.lens_swing = solution.lens_swing;
        c.film_distance_mm = solution.film_distance_mm;
        let plane = c.focus_plane().unwrap();
        for p in world {
            let distance = (p - c.position).length();
            assert!(
                plane.signed_distance(p).abs() < 1e-9 * distance,
                "{pivot}: {} off the plane",
                plane.signed_distance(p)
            );
        }
        tilts.push(solution.lens_tilt);
    }
    eprintln!("lens tilts by pivot: {tilts:?}");
    assert!(tilts.iter().all(|t| t.abs() > 1.0), "{tilts:?}");
    // The base tilt moves the lens by about 120 mm x the tilt's angle: its solution differs.
    assert!((tilts[3] - tilts[0]).abs() > 1e-3, "{tilts:?}");
}

/// An out-of-focus point images as the exit pupil seen from its film point: a round disc on
/// the axis, and near the corner of a double Gauss wide open, where the front and rear
/// elements' rims both cut the bundle, a cat's eye narrower along the radius than across it.
#[test]
fn a_defocused_point_images_as_a_disc_on_the_axis_and_a_cats_eye_near_the_corner() {
    let (width, height) = (360u32, 240u32);
    // Two white spheres 100 m away (large enough that a pixel's samples find them often, small
    // against the blur), lit by the ambient term alone against black, with the
    // lens focused at 0.5 m: one on the axis, one towards the top right corner.
    let text = format!(
        "[render]\nwidth = {width}\nheight = {height}\nspp = 128\nseed = 5\nmax_depth = 0\n\
         background = [0.0, 0.0, 0.0]\nambient = [1.0, 1.0, 1.0]\n\n\
         [camera]\nposition = [0.0, 0.0, 0.0]\nlook_at = [0.0, 0.0, -1.0]\n\
         film = [36.0, 24.0]\nlens = \"lenses/dgauss_50mm.dat\"\nfocus_distance = 0.5\n\
         lens_sampler = \"stratified\"\n\n\
         [[materials]]\nname = \"white\"\nmodel = \"lambert\"\ndiffuse = [1.0, 1.0, 1.0]\n\n\
         [[shapes]]\ntype = \"sphere\"\ncenter = [0.0, 0.0, -100.0]\nradius = 1.0\n\
         material = \"white\"\n\n\
         [[shapes]]\ntype = \"sphere\"\ncenter = [27.0, 18.0, -100.0]\nradius = 1.0\n\
         material = \"white\"\n"
    );
    let path = Path::new(env!("CARGO_MANIFEST_DIR")).join(IN_SCENES);
    let scene = Scene::from_str(&path, &text, &[]).unwrap_or_else(|e| panic!("{e}"));
    let image = common::render_cpu(&chambre::pack::flatten(&scene));
    // Each blob's light-weighted second moments in its quadrant of the image (x right, y up):
    // the ratio of the narrow to the wide axis, and the narrow axis's angle from the radius.
    let blob = |x_range: std::ops::Range<u32>, y_range: std::ops::Range<u32>| {
        let (mut sum, mut mx, mut my) = (0.0, 0.0, 0.0);
        let mut pixels = Vec::new();
        for y in y_range {
            for x in x_range.clone() {
                let v = image.pixels[(y * width + x) as usize].y as f64;
                let (px, py) = (x as f64 + 0.5, height as f64 - (y as f64 + 0.5));
                pixels.push((px, py, v));
                sum += v;
                mx += v * px;
                my += v * py;
            }
        }
        let (cx, cy) = (mx / sum, my / sum);
        let (mut sxx, mut syy, mut sxy) = (0.0, 0.0, 0.0);
        for (px, py, v) in pixels {
            sxx += v * (px - cx).powi(2);
            syy += v * (py - cy).powi(2);
            sxy += v * (px - cx) * (py - cy);
        }
        let (sxx, syy, sxy) = (sxx / sum, syy / sum, sxy / sum);
        let mean = 0.5 * (sxx + syy);
        let spread = (0.25 * (sxx - syy).powi(2) + sxy * sxy).sqrt();
        let (wide, narrow) = (mean + spread, mean - spread);
        // The narrow axis's direction (eigenvector of the smaller eigenvalue).
        let narrow_axis = glam::DVec2::new(sxy, narrow - sxx).normalize_or(glam::DVec2::X);
        let radial = glam::DVec2::new(cx - 0.5 * width as f64, cy - 0.5 * height as f64);
        let angle = if radial.length() > 1.0 {
            narrow_axis
                .dot(radial.normalize())
                .abs()
                .acos()
                .to_degrees()
        } else {
            0.0
        };
        ((narrow / wide).sqrt(), angle, (cx, cy), wide.sqrt())
    };
    let centre = blob(
        width / 2 - 40..width / 2 + 40,
        height / 2 - 40..height / 2 + 40,
    );
    let corner = blob(width / 2 + 40..width, 0..height / 2 - 20);
    eprintln!("centre blob {centre:?}, corner blob {corner:?}");
    assert!(
        centre.3 > 3.0,
        "the axis's blob is {} px: not defocused",
        centre.3
    );
    assert!(centre.0 > 0.9, "the axis's blob is not round: {centre:?}");
    // Inside the frame, so that the border does not cut the blob into a false cat's eye.
    let ((x, y), reach) = (corner.2, 2.5 * corner.3);
    assert!(
        x + reach < width as f64 && y + reach < height as f64,
        "{corner:?}"
    );
    // The sphere's own 5 px image rounds both blobs a little (the ratio is 0.72 measured).
    assert!(
        corner.0 < 0.8,
        "the corner's blob is not a cat's eye: {corner:?}"
    );
    assert!(
        corner.1 < 20.0,
        "the cat's eye's narrow axis is not radial: {corner:?}"
    );
}
