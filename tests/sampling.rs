//! Statistical and exact properties of the random numbers and sample warps.

use chambre::math::rng::Rng;
use chambre::math::sampling::{
    concentric_disk, cos_quarter, sin_quarter, strata_columns, stratified_2d,
};

#[test]
fn rng_streams_are_reproducible_in_any_order() {
    let draw = |pixel, sample| {
        let mut r = Rng::new(42, pixel, sample);
        [r.next_f32(), r.next_f32(), r.next_f32()]
    };
    let forward: Vec<_> = (0..50).map(|i| draw(i, i * 3)).collect();
    let backward: Vec<_> = (0..50).rev().map(|i| draw(i, i * 3)).collect();
    assert!(forward.iter().eq(backward.iter().rev()));
    assert_ne!(draw(1, 0), draw(0, 1));
}

#[test]
fn stratified_puts_exactly_one_sample_per_stratum() {
    for n in [1u32, 2, 4, 7, 12, 16, 64, 97] {
        let columns = strata_columns(n);
        let rows = n / columns;
        let mut hits = vec![0; n as usize];
        let mut rng = Rng::new(1, 2, 3);
        for i in 0..n {
            let [x, y] = stratified_2d(i, n, columns, rng.next_2d());
            let cell = (y * rows as f32) as u32 * columns + (x * columns as f32) as u32;
            hits[cell as usize] += 1;
        }
        assert!(hits.iter().all(|&h| h == 1), "n = {n}: {hits:?}");
    }
}

#[test]
fn polynomial_trigonometry_is_accurate_on_its_domain() {
    for i in 0..=1000 {
        let x = -std::f32::consts::FRAC_PI_4 + i as f32 * std::f32::consts::FRAC_PI_2 / 1000.0;
        assert!((sin_quarter(x) as f64 - (x as f64).sin()).abs() < 2e-7);
        assert!((cos_quarter(x) as f64 - (x as f64).cos()).abs() < 2e-7);
    }
}

/// Chi-square test of uniformity over the unit disk: 16 rings x 16 sectors of equal area.
#[test]
fn concentric_disk_is_uniform_over_the_disk() {
    let (rings, sectors, n) = (16usize, 16usize, 200_000u32);
    let mut counts = vec![0f64; rings * sectors];
    let mut rng = Rng::new(7, 0, 0);
    for _ in 0..n {
        let [x, y] = concentric_disk(rng.next_2d());
        let r2 = (x * x + y * y) as f64;
        assert!(r2 <= 1.0 + 1e-6);
        let ring = ((r2 * rings as f64) as usize).min(rings - 1);
        let angle = (y as f64).atan2(x as f64) + std::f64::consts::PI;
        let sector = ((angle / std::f64::consts::TAU * sectors as f64) as usize).min(sectors - 1);
        counts[ring * sectors + sector] += 1.0;
    }
    let expected = n as f64 / counts.len() as f64;
    let chi2: f64 = counts
        .iter()
        .map(|c| (c - expected).powi(2) / expected)
        .sum();
    // 255 degrees of freedom: the 0.999 quantile is about 330.
    assert!(chi2 < 330.0, "chi-square {chi2}");
    assert_eq!(concentric_disk([0.5, 0.5]), [0.0, 0.0]);
}

mod patterns {
    use chambre::layout::*;
    use chambre::math::rng::Rng;
    use chambre::sampler::{
        PatternSource, SampleTable, permute, poisson_disk_set, sample_2d, sample_aperture,
        toroidal_distance,
    };
    use chambre::scene::SamplerName;

    const ALL: [SamplerName; 5] = [
        SamplerName::Random,
        SamplerName::Stratified,
        SamplerName::Poisson,
        SamplerName::Interleaved,
        SamplerName::Sobol,
    ];

    fn frame(spp: u32, sampler: SamplerName, table: &SampleTable) -> GpuFrame {
        GpuFrame {
            width: 64,
            height: 64,
            spp,
            seed: 9,
            pixel_sampler: sampler.code(),
            pixel_strata_columns: chambre::math::sampling::strata_columns(spp),
            pixel_table_offset: table.pixel_offset,
            ..Default::default()
        }
    }

    /// Every sample of the first `pixels` pixels (row-major in a 64-pixel-wide image) of a
    /// `sampler` pattern with `spp` samples.
    fn pixel_samples(sampler: SamplerName, spp: u32, pixels: u32) -> Vec<[f32; 2]> {
        let coordinates: Vec<(u32, u32)> = (0..pixels).map(|p| (p % 64, p / 64)).collect();
        samples_of(sampler, spp, &coordinates)
    }

    fn samples_of(sampler: SamplerName, spp: u32, pixels: &[(u32, u32)]) -> Vec<[f32; 2]> {
        let table = SampleTable::build(spp, 9, sampler, None, 0, 0.0, false);
        let frame = frame(spp, sampler, &table);
        let source = PatternSource::pixel(&frame);
        let mut out = Vec::new();
        for &(x, y) in pixels {
            for s in 0..spp {
                let mut rng = Rng::new(9, y * 64 + x, s);
                let mut flags = 0;
                out.push(sample_2d(
                    &frame,
                    &table.points,
                    source,
                    x,
                    y,
                    s,
                    &mut rng,
                    &mut flags,
                ));
                assert_eq!(flags, 0);
            }
        }
        out
    }

    #[test]
    fn hashed_permutation_is_a_permutation_for_every_size_it_meets() {
        for n in 1..=4096u32 {
            for key in [
                0u32,
                0x9e37_79b9,
                0xdead_beef,
                n.wrapping_mul(2_654_435_761),
            ] {
                let mut seen = vec![false; n as usize];
                for i in 0..n {
                    let j = permute(i, n, key).expect("the walk stays under its cap") as usize;
                    assert!(!seen[j], "n = {n}, key = {key:#x}: {j} twice");
                    seen[j] = true;
                }
            }
        }
    }

    #[test]
    fn stratified_puts_one_sample_in_each_stratum_of_every_pixel() {
        for spp in [1u32, 6, 16, 17, 64] {
            let columns = chambre::math::sampling::strata_columns(spp);
            let rows = spp / columns;
            let samples = pixel_samples(SamplerName::Stratified, spp, 20);
            for pixel in samples.chunks(spp as usize) {
                let mut hits = vec![0; spp as usize];
                for [x, y] in pixel {
                    let cell = (y * rows as f32) as u32 * columns + (x * columns as f32) as u32;
                    hits[cell as usize] += 1;
                }
                assert!(hits.iter().all(|&h| h == 1), "spp {spp}: {hits:?}");
            }
        }
    }

    /// Cells of a `columns x rows` grid that none of `points` falls in.
    fn empty_cells(points: &[[f32; 2]], columns: u32, rows: u32) -> usize {
        let mut hits = vec![0u32; (columns * rows) as usize];
        for [x, y] in points {
            assert!((0.0..1.0).contains(x) && (0.0..1.0).contains(y), "{x} {y}");
            hits[((y * rows as f32) as u32 * columns + (x * columns as f32) as u32) as usize] += 1;
        }
        hits.iter().filter(|&&h| h == 0).count()
    }

    #[test]
    fn the_progressive_stratified_pattern_is_stratified_at_every_power_of_two() {
        use chambre::sampler::progressive_stratified;
        let mut rng = Rng::new(5, 6, 7);
        for key in [0u32, 1, 0xdead_beef, 0x1234_5678] {
            for n in [16u32, 1000, 4096] {
                // Jittered inside the strata of the power of two at or above n.
                let bits = n.next_power_of_two().ilog2();
                let (columns, rows) = (bits / 2, bits - bits / 2);
                let points: Vec<[f32; 2]> = (0..n)
                    .map(|i| progressive_stratified(i, n, key, rng.next_2d()))
                    .collect();
                // Every prefix of 2^k points has one point in each cell of every 2^a x 2^b
                // grid, a + b = k, whose cells are unions of strata (the (0,2)-sequence's net
                // property down to the strata the jitter fills).
                for k in 0..=n.ilog2() {
                    for a in k.saturating_sub(rows)..=k.min(columns) {
                        let prefix = &points[..1 << k];
                        assert_eq!(
                            empty_cells(prefix, 1 << a, 1 << (k - a)),
                            0,
                            "key {key:#x}, n {n}: prefix 2^{k} in 2^{a} x 2^{} cells",
                            k - a
                        );
                    }
                }
            }
        }
    }

    #[test]
    fn every_pattern_is_progressive_under_adaptive_sampling() {
        // A pixel may stop after any number of samples: its first 4^j samples must cover the
        // 2^j x 2^j grid, where a random prefix of a stratified set leaves a third of the
        // cells empty. (A Poisson pixel's points are its table set moved by a toroidal shift,
        // which moves the grid too: its order is tested on the table below.)
        let spp = 256;
        for sampler in [
            SamplerName::Stratified,
            SamplerName::Interleaved,
            SamplerName::Sobol,
        ] {
            let table = SampleTable::build(spp, 9, sampler, None, 0, 0.0, true);
            let frame = GpuFrame {
                progressive: 1,
                ..frame(spp, sampler, &table)
            };
            let source = PatternSource::pixel(&frame);
            for (x, y) in [(0, 0), (5, 3), (17, 40), (63, 63)] {
                let points: Vec<[f32; 2]> = (0..spp)
                    .map(|s| {
                        let mut rng = Rng::new(9, y * 64 + x, s);
                        let mut flags = 0;
                        sample_2d(&frame, &table.points, source, x, y, s, &mut rng, &mut flags)
                    })
                    .collect();
                for j in 1..=4 {
                    let empty = empty_cells(&points[..1 << (2 * j)], 1 << j, 1 << j);
                    assert_eq!(empty, 0, "{sampler:?} pixel ({x}, {y}): 4^{j} samples");
                }
            }
        }
    }

    #[test]
    fn table_patterns_are_stored_in_a_progressive_order() {
        use chambre::sampler::progressive_order;
        // A jittered 16 x 16 grid: every prefix of 4^j points is one per cell of the 2^j grid,
        // whatever the scramble.
        let mut rng = Rng::new(1, 2, 3);
        let grid: Vec<[f32; 2]> = (0..256)
            .map(|i| chambre::math::sampling::stratified_2d(i, 256, 16, rng.next_2d()))
            .collect();
        let mut firsts = Vec::new();
        for seed in [0u32, 1, 77, 255, 1000] {
            let ordered = progressive_order(&grid, seed, seed % 2 == 1);
            firsts.push(ordered[0]);
            let mut sorted = ordered.clone();
            sorted.sort_by(|a, b| a.partial_cmp(b).unwrap());
            let mut original = grid.clone();
            original.sort_by(|a, b| a.partial_cmp(b).unwrap());
            assert_eq!(sorted, original, "the same points");
            for j in 0..=4 {
                assert_eq!(empty_cells(&ordered[..1 << (2 * j)], 1 << j, 1 << j), 0);
            }
        }
        // Scrambles order alike tables differently.
        firsts.dedup();
        assert!(firsts.len() >= 4, "{firsts:?}");
        // A Poisson set, not a grid: its prefixes leave few cells empty (at most a fifth, 13%
        // at worst here; a random order leaves 1/e, 37%), in either order.
        for key in [1u32, 2, 3] {
            for lens in [false, true] {
                let set = progressive_order(&poisson_disk_set(1024, key).points, key, lens);
                for j in 1..=4 {
                    let empty = empty_cells(&set[..1 << (2 * j)], 1 << j, 1 << j);
                    assert!(empty <= (1 << (2 * j)) / 5, "key {key}: {empty} of 4^{j}");
                }
            }
        }
        assert!(progressive_order(&[], 3, false).is_empty());
        assert_eq!(progressive_order(&[[0.5, 0.5]], 3, true), vec![[0.5, 0.5]]);
    }

    #[test]
    fn poisson_sets_have_exactly_n_points_and_respect_their_radius() {
        for n in [1u32, 2, 5, 16, 64, 256, 1024] {
            for key in [1u32, 77] {
                let set = poisson_disk_set(n, key);
                assert_eq!(set.points.len(), n as usize);
                let points: Vec<[f64; 2]> = set
                    .points
                    .iter()
                    .map(|p| [p[0] as f64, p[1] as f64])
                    .collect();
                let mut closest = f64::INFINITY;
                for i in 0..points.len() {
                    assert!(points[i].iter().all(|c| (0.0..1.0).contains(c)));
                    for j in 0..i {
                        closest = closest.min(toroidal_distance(points[i], points[j]));
                    }
                }
                // f32 storage may round a pair 1e-7 closer than the f64 radius.
                assert!(
                    closest >= set.radius - 1e-6,
                    "n {n}: {closest} < {}",
                    set.radius
                );
                // And the radius is a real Poisson-disk radius: at least 60% of the
                // hexagonal-packing spacing (Bridson's maximal sets reach about 75-85%).
                let hexagonal = (2.0 / (3f64.sqrt() * n as f64)).sqrt().min(0.7);
                assert!(set.radius > 0.6 * hexagonal, "n {n}: {}", set.radius);
            }
        }
    }

    #[test]
    fn shifted_poisson_pixels_keep_the_minimum_distance() {
        let spp = 32;
        // The closest pair of any uploaded set, before the per-pixel shifts.
        let table = SampleTable::build(spp, 9, SamplerName::Poisson, None, 0, 0.0, false);
        let closest_pair = |points: &[[f32; 2]]| {
            let mut closest = f64::INFINITY;
            for i in 0..points.len() {
                for j in 0..i {
                    let (a, b) = (points[i].map(f64::from), points[j].map(f64::from));
                    closest = closest.min(toroidal_distance(a, b));
                }
            }
            closest
        };
        let smallest = table.points[..(POISSON_SETS * spp) as usize]
            .chunks(spp as usize)
            .map(closest_pair)
            .fold(f64::INFINITY, f64::min);
        let samples = pixel_samples(SamplerName::Poisson, spp, 30);
        for pixel in samples.chunks(spp as usize) {
            assert!(closest_pair(pixel) >= smallest - 1e-6);
        }
    }

    /// Chi-square of sample counts over `bins` equal-probability bins against uniform.
    fn chi_square(counts: &[f64]) -> f64 {
        let total: f64 = counts.iter().sum();
        let expected = total / counts.len() as f64;
        counts
            .iter()
            .map(|c| (c - expected).powi(2) / expected)
            .sum()
    }

    #[test]
    fn every_sampler_is_uniform_over_the_disk_aperture() {
        // 8 rings x 8 sectors of equal area; 63 degrees of freedom, 0.999 quantile about 104.
        // Pixels: 64 for the per-pixel randomised samplers; for interleaved sampling the nine
        // distinct basis patterns of one tile (its other pixels repeat them exactly).
        let per_pixel: Vec<(u32, u32)> = (0..64).map(|p| (p % 8, p / 8)).collect();
        let one_tile: Vec<(u32, u32)> = (0..9).map(|p| (p % 3, p / 3)).collect();
        for sampler in ALL {
            let pixels = if sampler == SamplerName::Interleaved {
                &one_tile
            } else {
                &per_pixel
            };
            let mut counts = vec![0f64; 64];
            let camera = GpuCamera {
                lens_radius_mm: 1.0,
                ..Default::default()
            };
            for [u, v] in samples_of(sampler, 256, pixels) {
                let [x, y] = sample_aperture(&camera, &[[0.0, 0.0]], [u, v]);
                let r2 = (x * x + y * y) as f64;
                let ring = ((r2 * 8.0) as usize).min(7);
                let angle = (y as f64).atan2(x as f64) + std::f64::consts::PI;
                let sector = ((angle / std::f64::consts::TAU * 8.0) as usize).min(7);
                counts[ring * 8 + sector] += 1.0;
            }
            let chi2 = chi_square(&counts);
            assert!(chi2 < 104.0, "{sampler:?}: chi-square {chi2}");
        }
    }

    #[test]
    fn polygonal_apertures_are_uniform_by_area() {
        // Cells of a 12 x 12 grid that lie wholly inside the polygon all get the same expected
        // count; the rest of the polygon is one more bin.
        for blades in [3u32, 5, 6, 9] {
            let table = SampleTable::build(1, 1, SamplerName::Random, None, blades, 17.0, false);
            let camera = GpuCamera {
                lens_radius_mm: 1.0,
                aperture_blades: blades,
                aperture_table_offset: table.aperture_offset,
                ..Default::default()
            };
            let vertices = &table.points[table.aperture_offset as usize..];
            let inside = |x: f64, y: f64| {
                (0..blades as usize).all(|k| {
                    let (a, b) = (vertices[k], vertices[k + 1]);
                    let cross = (b[0] - a[0]) as f64 * (y - a[1] as f64)
                        - (b[1] - a[1]) as f64 * (x - a[0] as f64);
                    cross >= 0.0
                })
            };
            let cell = 2.0 / 12.0;
            let full: Vec<(usize, usize)> = (0..12)
                .flat_map(|i| (0..12).map(move |j| (i, j)))
                .filter(|&(i, j)| {
                    let (x0, y0) = (-1.0 + i as f64 * cell, -1.0 + j as f64 * cell);
                    [(0.0, 0.0), (1.0, 0.0), (0.0, 1.0), (1.0, 1.0)]
                        .iter()
                        .all(|(a, b)| inside(x0 + a * cell, y0 + b * cell))
                })
                .collect();
            let area = 0.5 * blades as f64 * (std::f64::consts::TAU / blades as f64).sin();
            let n = 400_000u32;
            let mut counts = vec![0f64; full.len() + 1];
            let mut rng = Rng::new(blades, 0, 0);
            for _ in 0..n {
                let [x, y] = sample_aperture(&camera, &table.points, rng.next_2d());
                assert!(inside(x as f64 * 0.999_99, y as f64 * 0.999_99), "{x} {y}");
                let (i, j) = (
                    ((x as f64 + 1.0) / cell) as usize,
                    ((y as f64 + 1.0) / cell) as usize,
                );
                let bin = full.iter().position(|&c| c == (i, j)).unwrap_or(full.len());
                counts[bin] += 1.0;
            }
            let cell_p = cell * cell / area;
            let rest_p = 1.0 - cell_p * full.len() as f64;
            let chi2: f64 = counts
                .iter()
                .enumerate()
                .map(|(b, c)| {
                    let e = n as f64 * if b < full.len() { cell_p } else { rest_p };
                    (c - e).powi(2) / e
                })
                .sum();
            // Degrees of freedom = full cells; the 0.999 quantile is below dof + 4 sqrt(2 dof) + 10.
            let dof = full.len() as f64;
            assert!(
                chi2 < dof + 4.0 * (2.0 * dof).sqrt() + 10.0,
                "{blades} blades: {chi2} ({dof} dof)"
            );
        }
    }
}

/// A pixel's light points over all its camera samples follow the pixel pattern: with 16 spp and
/// 4 light samples, the 64 points of a stratified or Sobol pattern fill every cell of the 8x8
/// grid exactly once (the product of the pixel's 4x4 strata and the light's 2x2; the first 64
/// points of Owen-scrambled Sobol are a (0,6,2)-net), where independent camera samples leave
/// cells empty.
#[test]
fn light_samples_are_stratified_over_the_whole_pixel() {
    use chambre::layout::{SAMPLER_RANDOM, SAMPLER_SOBOL, SAMPLER_STRATIFIED};
    use chambre::math::sampling::strata_columns;
    use chambre::sampler::light_sample_2d;
    let mut frame = chambre::layout::GpuFrame {
        spp: 16,
        pixel_strata_columns: strata_columns(16),
        seed: 9,
        ..Default::default()
    };
    let (light_samples, pixel, dim) = (4, 1234, 77);
    // The cells of the 8x8 grid (4x4 for fewer than 16 camera samples) that the light points
    // of the pixel's first `samples` camera samples leave empty.
    let empty_cells = |frame: &chambre::layout::GpuFrame, samples: u32| {
        let side = if samples < 16 { 4 } else { 8 };
        let mut counts = vec![0u32; side * side];
        for sample in 0..samples {
            let mut rng = Rng::new(frame.seed, pixel, sample);
            for k in 0..light_samples {
                let mut flags = 0;
                let u = rng.next_2d();
                let columns = strata_columns(light_samples);
                let key = chambre::sampler::pixel_hash(frame.seed, pixel, dim);
                let [x, y] =
                    light_sample_2d(frame, light_samples, columns, sample, k, key, u, &mut flags);
                assert_eq!(flags, 0);
                assert!((0.0..1.0).contains(&x) && (0.0..1.0).contains(&y));
                counts[(y * side as f32) as usize * side + (x * side as f32) as usize] += 1;
            }
        }
        counts.iter().filter(|&&c| c == 0).count()
    };
    for sampler in [SAMPLER_STRATIFIED, SAMPLER_SOBOL] {
        frame.pixel_sampler = sampler;
        assert_eq!(empty_cells(&frame, 16), 0, "sampler {sampler}");
    }
    // Under adaptive sampling a pixel stops after any number of samples: the light points of
    // its first samples are stratified too (the first 4 camera samples' 16 points fill the
    // 4x4 grid), for every pattern but random.
    frame.progressive = 1;
    for sampler in [
        SAMPLER_STRATIFIED,
        SAMPLER_SOBOL,
        chambre::layout::SAMPLER_POISSON,
        chambre::layout::SAMPLER_INTERLEAVED,
    ] {
        frame.pixel_sampler = sampler;
        assert_eq!(empty_cells(&frame, 16), 0, "sampler {sampler}, progressive");
        assert_eq!(empty_cells(&frame, 4), 0, "sampler {sampler}, 4 samples");
    }
    frame.progressive = 0;
    frame.pixel_sampler = SAMPLER_RANDOM;
    assert!(
        empty_cells(&frame, 16) > 10,
        "random light points leave cells empty"
    );
}
