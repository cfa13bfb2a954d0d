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
