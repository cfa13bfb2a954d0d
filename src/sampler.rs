//! Camera sample patterns: where sample `i` of a pixel falls inside the pixel and on the
//! aperture. Twin: `wgsl/sampler.wgsl`. Choices and measurements: `docs/camera.md` and
//! `BENCHMARKS.md`.
//!
//! Five patterns, each drawing 2-D points in [0, 1)^2 that the camera then maps to the pixel or to
//! the aperture (concentric disk or polygon, both area-preserving so strata keep equal areas):
//!
//! - `random`: independent uniform points.
//! - `stratified`: one jittered point per cell of a `columns x rows` grid; each pixel and each
//!   dimension pair visits the cells in its own pseudo-random order (Kensler's hashed
//!   permutation), so the pixel position of a sample does not predict its lens position.
//! - `poisson`: `POISSON_SETS` Poisson-disk sets of `spp` points built once on the CPU
//!   (Bridson's algorithm on the torus, trimmed to exactly `spp` points), uploaded in the sample
//!   table; a pixel picks a set by hash and moves it by a Cranley-Patterson shift, which keeps
//!   the minimum distance because the sets are toroidal.
//! - `interleaved`: Keller and Heidrich's interleaved sampling: `INTERLEAVED_TILE^2` jittered
//!   basis patterns repeated regularly across the image, with no per-pixel randomness.
//! - `sobol`: the first two Sobol dimensions, shuffled and Owen-scrambled with Burley's
//!   hash-based nested uniform scrambling ("Practical Hash-based Owen Scrambling", JCGT 2020).
//!   A Sobol lens under a Sobol pixel pattern takes Sobol dimensions 2 and 3 of the pixel's own
//!   shuffled index (`sobol_owen_lens`): pixel and lens points form one 4-D Sobol point.
//!
//! Every pattern consumes the same two random dimensions per 2-D sample, so switching the camera
//! sampler leaves the light samples untouched and comparisons isolate the camera.
//!
//! Under adaptive sampling (`GpuFrame::progressive`) a pixel stops after any number of samples,
//! so every prefix of its samples must be stratified, not only the whole `spp`: `stratified`
//! then visits its strata in the order of an Owen-scrambled (0,2)-sequence
//! ([`progressive_stratified`]), and the light samples of the stratified, Poisson and
//! interleaved patterns follow that pattern over the pixel's `spp x light_samples` points. The
//! precomputed Poisson and interleaved sets are always stored in a progressive order
//! ([`progressive_order`]); `random` and `sobol` are progressive as they are.

use std::f64::consts::TAU;

use rayon::prelude::*;

use crate::layout::*;
use crate::math::rng::{Rng, pcg_hash};
use crate::math::sampling::{concentric_disk, div_rem, strata_columns, stratified_2d};
use crate::named::named_enum;

/// Samples per pixel the table-based samplers (poisson, interleaved) accept.
pub const MAX_TABLE_SPP: u32 = 4096;
/// Largest number of aperture blades.
pub const MAX_BLADES: u32 = 64;

named_enum! {
    /// A sample pattern, as scene files and flags name it.
    #[derive(Debug, Clone, Copy, PartialEq, Eq, Default, serde::Deserialize)]
    #[serde(rename_all = "lowercase")]
    pub enum SamplerName {
        /// Independent uniform points.
        Random = "random",
        /// One jittered point per cell of a grid, cells in a hashed per-pixel order (the default).
        #[default]
        Stratified = "stratified",
        /// Precomputed Poisson-disk sets, one picked and shifted per pixel; spp <= `MAX_TABLE_SPP`.
        Poisson = "poisson",
        /// Keller and Heidrich's interleaved jittered patterns; spp <= `MAX_TABLE_SPP`.
        Interleaved = "interleaved",
        /// Shuffled, Owen-scrambled 2-D Sobol points.
        Sobol = "sobol",
    }
}

impl SamplerName {
    /// The `SAMPLER_*` code the kernels switch on.
    pub fn code(self) -> u32 {
        match self {
            SamplerName::Random => SAMPLER_RANDOM,
            SamplerName::Stratified => SAMPLER_STRATIFIED,
            SamplerName::Poisson => SAMPLER_POISSON,
            SamplerName::Interleaved => SAMPLER_INTERLEAVED,
            SamplerName::Sobol => SAMPLER_SOBOL,
        }
    }

    /// Whether the sampler reads precomputed patterns from the sample table.
    pub fn uses_table(self) -> bool {
        matches!(self, SamplerName::Poisson | SamplerName::Interleaved)
    }
}

/// The sample table uploaded once per render: precomputed patterns and aperture vertices.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct SampleTable {
    /// Every pattern and the aperture polygon's vertices, one after the other (at least one point:
    /// a binding cannot be empty).
    pub points: Vec<[f32; 2]>,
    /// Where the pixel sampler's patterns start in `points`.
    pub pixel_offset: u32,
    /// Where the lens sampler's patterns start in `points`.
    pub lens_offset: u32,
    /// Where the aperture polygon's vertices start in `points` (0 with a circular aperture).
    pub aperture_offset: u32,
}

impl SampleTable {
    /// Patterns for `spp` samples of the pixel and lens samplers (`lens: None` for a pinhole,
    /// which draws no lens points), and the unit-circle vertices of a polygonal aperture.
    /// `progressive` (adaptive sampling, `GpuFrame::progressive`) stores the Poisson and
    /// interleaved sets in a progressive order ([`progressive_order`]) instead of a shuffle.
    pub fn build(
        spp: u32,
        seed: u32,
        pixel: SamplerName,
        lens: Option<SamplerName>,
        blades: u32,
        rotation_deg: f64,
        progressive: bool,
    ) -> SampleTable {
        let mut table = SampleTable::default();
        table.pixel_offset = table.append_patterns(spp, seed, pixel, PIXEL_DIMENSION, progressive);
        if let Some(lens) = lens {
            table.lens_offset = table.append_patterns(spp, seed, lens, LENS_DIMENSION, progressive);
        }
        if blades >= 3 {
            table.aperture_offset = table.points.len() as u32;
            table.points.extend(aperture_vertices(blades, rotation_deg));
        }
        if table.points.is_empty() {
            // A binding needs at least one element; nothing reads it.
            table.points.push([0.0, 0.0]);
        }
        table
    }

    fn append_patterns(
        &mut self,
        spp: u32,
        seed: u32,
        sampler: SamplerName,
        dim: u32,
        progressive: bool,
    ) -> u32 {
        let offset = self.points.len() as u32;
        let salt = pcg_hash(seed ^ pcg_hash(dim));
        match sampler {
            SamplerName::Poisson => {
                // The sets are independent, each made from its own key: built on every core
                // (a 4096-point set takes about 0.1 s), stored in order.
                let sets: Vec<Vec<[f32; 2]>> = (0..POISSON_SETS)
                    .into_par_iter()
                    .map(|set| {
                        let key = pcg_hash(salt ^ set);
                        let points = poisson_disk_set(spp, key).points;
                        ordered(points, key, progressive, dim == LENS_DIMENSION)
                    })
                    .collect();
                self.points.extend(sets.into_iter().flatten());
            }
            SamplerName::Interleaved => {
                for pattern in 0..INTERLEAVED_TILE * INTERLEAVED_TILE {
                    let key = pcg_hash(salt ^ pattern);
                    let points = jittered_pattern(spp, key);
                    self.points
                        .extend(ordered(points, key, progressive, dim == LENS_DIMENSION));
                }
            }
            _ => {}
        }
        offset
    }
}

/// A table's set (made with `key`) as stored: shuffled as made, or in a progressive order
/// under adaptive sampling, scrambled by the set's own key so that the pixel's and the lens's
/// sets are not ordered alike.
fn ordered(points: Vec<[f32; 2]>, key: u32, progressive: bool, lens: bool) -> Vec<[f32; 2]> {
    match progressive {
        true => progressive_order(&points, pcg_hash(key ^ 0x0bde_2e55), lens),
        false => points,
    }
}

/// A Poisson-disk point set on the unit torus: no two points closer than `radius`.
#[derive(Clone, Debug)]
pub struct PoissonSet {
    /// The points in [0, 1)^2, in random order.
    pub points: Vec<[f32; 2]>,
    /// The minimum toroidal distance between any two points.
    pub radius: f64,
}

/// Distance between two points of the unit torus. Each side is at most 0.5, so the plain
/// root of the squares neither overflows nor underflows to harm (libm's `hypot`, which guards
/// against both, took half the time of building a 4096-point Poisson table).
pub fn toroidal_distance(a: [f64; 2], b: [f64; 2]) -> f64 {
    let d = |x: f64, y: f64| {
        let d = (x - y).abs();
        d.min(1.0 - d)
    };
    let (dx, dy) = (d(a[0], b[0]), d(a[1], b[1]));
    (dx * dx + dy * dy).sqrt()
}

/// Exactly `n` points with a large minimum toroidal distance, in random order.
///
/// Bridson's algorithm (30 candidates per active point) fills the torus for a radius below the
/// densest packing's; the radius shrinks by 5% until at least `n` points fit, and the surplus is
/// removed closest pair first (Yuksel's sample elimination, greedily), which keeps the radius.
pub fn poisson_disk_set(n: u32, key: u32) -> PoissonSet {
    let n = n.max(1) as usize;
    // Hexagonal packing of n disks on the unit torus has spacing sqrt(2 / (sqrt(3) n)).
    let hexagonal = (2.0 / (3f64.sqrt() * n as f64)).sqrt();
    let mut radius = (0.85 * hexagonal).min(0.7);
    let mut rng = Rng::new(key, 0x5eed, 0);
    let mut points = loop {
        let points = bridson_torus(radius, &mut rng);
        if points.len() >= n {
            break points;
        }
        radius *= 0.95;
    };
    eliminate_closest(&mut points, n, radius);
    // Shuffle (Fisher-Yates) so any prefix of the samples is spread over the domain.
    for i in (1..points.len()).rev() {
        let j = (rng.next_u32() as usize) % (i + 1);
        points.swap(i, j);
    }
    PoissonSet {
        points: points.iter().map(|p| [p[0] as f32, p[1] as f32]).collect(),
        radius,
    }
}

fn bridson_torus(radius: f64, rng: &mut Rng) -> Vec<[f64; 2]> {
    let cells = ((std::f64::consts::SQRT_2 / radius).floor() as usize).max(1);
    let mut grid: Vec<Option<usize>> = vec![None; cells * cells];
    let cell_of = |p: [f64; 2]| {
        let c = |x: f64| ((x * cells as f64) as usize).min(cells - 1);
        (c(p[0]), c(p[1]))
    };
    let mut points = vec![rng.next_2d().map(f64::from)];
    let (cx, cy) = cell_of(points[0]);
    grid[cy * cells + cx] = Some(0);
    let mut active = vec![0usize];
    let reach = (radius * cells as f64).ceil() as isize;
    while !active.is_empty() {
        let slot = (rng.next_u32() as usize) % active.len();
        let base = points[active[slot]];
        let found = (0..30).find_map(|_| {
            let [u, v] = rng.next_2d().map(f64::from);
            let r = radius * (1.0 + 3.0 * u).sqrt();
            let a = TAU * v;
            let p = [
                (base[0] + r * a.cos()).rem_euclid(1.0),
                (base[1] + r * a.sin()).rem_euclid(1.0),
            ];
            let (px, py) = cell_of(p);
            let clear = (-reach..=reach).all(|dy| {
                (-reach..=reach).all(|dx| {
                    let gx = (px as isize + dx).rem_euclid(cells as isize) as usize;
                    let gy = (py as isize + dy).rem_euclid(cells as isize) as usize;
                    grid[gy * cells + gx].is_none_or(|q| toroidal_distance(p, points[q]) >= radius)
                })
            });
            clear.then_some((p, px, py))
        });
        match found {
            Some((p, px, py)) => {
                grid[py * cells + px] = Some(points.len());
                active.push(points.len());
                points.push(p);
            }
            None => {
                active.swap_remove(slot);
            }
        }
    }
    points
}

/// Removes points until `n` remain, always one of the closest remaining pair. Each point's
/// nearest distance is found through a grid of cells about `spacing` wide (the set's radius),
/// searched ring by ring until no unsearched cell can hold a nearer point: the same distances
/// as comparing every pair, in time about linear in the points instead of quadratic (4096
/// samples took minutes).
fn eliminate_closest(points: &mut Vec<[f64; 2]>, n: usize, spacing: f64) {
    let mut grid = PointGrid::new(points, spacing);
    let mut distance: Vec<f64> = (0..points.len()).map(|i| grid.nearest(points, i)).collect();
    while points.len() > n {
        let worst = (0..points.len())
            .min_by(|&a, &b| distance[a].total_cmp(&distance[b]))
            .unwrap();
        grid.remove(points, worst);
        let removed = points.swap_remove(worst);
        distance.swap_remove(worst);
        // Only a point whose nearest was the one removed has a new nearest: its distance to it
        // is the very number its nearest distance was taken as (the others' is larger).
        for i in 0..points.len() {
            if toroidal_distance(points[i], removed) <= distance[i] {
                distance[i] = grid.nearest(points, i);
            }
        }
    }
}

/// The points of a set on the unit torus, by the cell of a `cells x cells` grid they lie in.
struct PointGrid {
    cells: usize,
    members: Vec<Vec<usize>>,
}

impl PointGrid {
    fn new(points: &[[f64; 2]], spacing: f64) -> PointGrid {
        let cells = ((1.0 / spacing).floor() as usize).clamp(1, 4096);
        let mut grid = PointGrid {
            cells,
            members: vec![Vec::new(); cells * cells],
        };
        for (i, &p) in points.iter().enumerate() {
            let cell = grid.cell(p);
            grid.members[cell].push(i);
        }
        grid
    }

    fn coordinates(&self, p: [f64; 2]) -> (usize, usize) {
        let c = |x: f64| ((x * self.cells as f64) as usize).min(self.cells - 1);
        (c(p[0]), c(p[1]))
    }

    fn cell(&self, p: [f64; 2]) -> usize {
        let (x, y) = self.coordinates(p);
        y * self.cells + x
    }

    /// Point `i` leaves the set by `swap_remove`: the last point takes its index.
    fn remove(&mut self, points: &[[f64; 2]], i: usize) {
        let cell = self.cell(points[i]);
        self.members[cell].retain(|&m| m != i);
        let last = points.len() - 1;
        if last != i {
            let cell = self.cell(points[last]);
            for m in &mut self.members[cell] {
                if *m == last {
                    *m = i;
                }
            }
        }
    }

    /// The toroidal distance from point `i` to its nearest other point (infinite alone).
    fn nearest(&self, points: &[[f64; 2]], i: usize) -> f64 {
        let (cx, cy) = self.coordinates(points[i]);
        let cells = self.cells as isize;
        let width = 1.0 / self.cells as f64;
        let mut best = f64::INFINITY;
        // Ring k holds the cells k steps away (Chebyshev) from the point's: any point beyond
        // it is more than k cells' widths away.
        for k in 0..=(self.cells / 2) as isize {
            for dy in -k..=k {
                for dx in -k..=k {
                    if dx.abs().max(dy.abs()) != k {
                        continue;
                    }
                    let x = (cx as isize + dx).rem_euclid(cells) as usize;
                    let y = (cy as isize + dy).rem_euclid(cells) as usize;
                    for &j in &self.members[y * self.cells + x] {
                        if j != i {
                            best = best.min(toroidal_distance(points[i], points[j]));
                        }
                    }
                }
            }
            if best <= k as f64 * width {
                break;
            }
        }
        best
    }
}

/// One interleaved basis pattern: a jittered stratification of `n` points, shuffled.
fn jittered_pattern(n: u32, key: u32) -> Vec<[f32; 2]> {
    let columns = strata_columns(n);
    let mut rng = Rng::new(key, 0x1ea7, 0);
    let mut points: Vec<[f32; 2]> = (0..n)
        .map(|i| stratified_2d(i, n, columns, rng.next_2d()))
        .collect();
    for i in (1..points.len()).rev() {
        let j = (rng.next_u32() as usize) % (i + 1);
        points.swap(i, j);
    }
    points
}

/// `points` reordered so that every prefix is spread over the unit square: along a Hilbert
/// curve through them, position `r_k` is taken `k`-th, `r_k` the bits of `k` reversed over the
/// power of two `2^m` at or above `n` (van der Corput's order) and Owen-scrambled by `seed`,
/// skipping positions past `n`. A prefix of `2^j` points then has one point in each run of
/// `2^(m-j)` consecutive positions along the curve, a compact region of about `2^-j` of the
/// square, at a random place in it; for `4^j` points of a jittered grid of a power of four that
/// is one point in each cell of every coarser `2^i x 2^i` grid, exactly. The scramble differs
/// between tables. A lens table (`lens`) takes Sobol's second dimension instead of van der
/// Corput's: the pixel's and the lens's positions of sample `k` are then one point of a (0,2)-
/// sequence, jointly stratified, where two scrambles of van der Corput's order would pair their
/// points in correlated places (the first half of one curve with one half of the other: a
/// bias no halves can see, measured at 2.6x uniform sampling's error on a defocused scene with
/// interleaved patterns). The set itself is unchanged.
pub fn progressive_order(points: &[[f32; 2]], seed: u32, lens: bool) -> Vec<[f32; 2]> {
    let n = points.len();
    if n == 0 {
        return Vec::new();
    }
    let mut along: Vec<(u64, [f32; 2])> = points.iter().map(|&p| (hilbert_index(p), p)).collect();
    along.sort_by_key(|&(d, _)| d);
    let bits = n.next_power_of_two().trailing_zeros();
    (0..n.next_power_of_two() as u32)
        .map(|k| match bits {
            0 => 0,
            // The top `bits` bits of the scrambled 32-bit coordinate (given reversed).
            _ => {
                let reversed = match lens {
                    false => k,
                    true => sobol_dimension_reversed(k, &SOBOL_TABLES_1),
                };
                (scramble_reversed(reversed, seed) >> (32 - bits)) as usize
            }
        })
        .filter(|&r| r < n)
        .map(|r| along[r].1)
        .collect()
}

/// The position of `p` (in [0, 1)^2) along the Hilbert curve of a 2^16 x 2^16 grid.
fn hilbert_index(p: [f32; 2]) -> u64 {
    const SIDE: u32 = 1 << 16;
    let cell = |v: f32| ((v.clamp(0.0, 1.0) * SIDE as f32) as u32).min(SIDE - 1);
    let (mut x, mut y) = (cell(p[0]), cell(p[1]));
    let mut d = 0u64;
    let mut s = SIDE / 2;
    while s > 0 {
        let rx = u32::from(x & s != 0);
        let ry = u32::from(y & s != 0);
        d += s as u64 * s as u64 * ((3 * rx) ^ ry) as u64;
        // Rotate the quadrant so the curve's pieces join.
        if ry == 0 {
            if rx == 1 {
                x = SIDE - 1 - x;
                y = SIDE - 1 - y;
            }
            std::mem::swap(&mut x, &mut y);
        }
        s /= 2;
    }
    d
}

/// Unit-circle vertices of a regular `blades`-gon, the first repeated at the end. With
/// `rotation_deg = 0` the edge between vertices 0 and 1 stands vertical on the right (+x);
/// positive rotations turn the polygon counter-clockwise (+x towards +y).
pub fn aperture_vertices(blades: u32, rotation_deg: f64) -> Vec<[f32; 2]> {
    let n = blades as f64;
    (0..=blades)
        .map(|k| {
            let angle = rotation_deg.to_radians() + TAU * (k as f64 - 0.5) / n;
            [angle.cos() as f32, angle.sin() as f32]
        })
        .collect()
}

/// A hash of (seed, pixel, dimension) for per-pixel, per-dimension decisions (set choice,
/// shifts, permutations); disjoint from the per-sample `Rng` keys.
pub fn pixel_hash(seed: u32, pixel: u32, dim: u32) -> u32 {
    pcg_hash(pcg_hash(pcg_hash(seed) ^ pixel) ^ (dim | 0x8000_0000))
}

pub(crate) fn unit_float(bits: u32) -> f32 {
    (bits >> 8) as f32 * (1.0 / 16_777_216.0)
}

/// Kensler's hashed permutation of [0, n) ("Correlated Multi-Jittered Sampling", 2013): index
/// `i`'s place in the permutation keyed by `key`, by cycle-walking a bijection of the enclosing
/// power of two.
/// The walk is capped at `PERMUTE_WALK_CAP` steps (a kernel loop must be bounded); `None` when
/// the cap is hit. `tests/sampling.rs` checks the cap is never reached for n <= 4096.
pub fn permute(i: u32, n: u32, key: u32) -> Option<u32> {
    let mut w = n.wrapping_sub(1);
    w |= w >> 1;
    w |= w >> 2;
    w |= w >> 4;
    w |= w >> 8;
    w |= w >> 16;
    let mut i = i;
    for _ in 0..PERMUTE_WALK_CAP {
        i = permute_round(i, w, key);
        if i < n {
            return Some(div_rem(i.wrapping_add(key), n).1);
        }
    }
    None
}

/// One step of [`permute`]'s walk: the keyed bijection of [0, w] (w one less than a power of
/// two) applied to `i`.
#[inline(always)]
pub(crate) fn permute_round(mut i: u32, w: u32, key: u32) -> u32 {
    i ^= key;
    i = i.wrapping_mul(0xe170_893d);
    i ^= key >> 16;
    i ^= (i & w) >> 4;
    i ^= key >> 8;
    i = i.wrapping_mul(0x0929_eb3f);
    i ^= key >> 23;
    i ^= (i & w) >> 1;
    i = i.wrapping_mul(1 | key >> 27);
    i = i.wrapping_mul(0x6935_fa69);
    i ^= (i & w) >> 11;
    i = i.wrapping_mul(0x74dc_b303);
    i ^= (i & w) >> 2;
    i = i.wrapping_mul(0x9e50_1cc3);
    i ^= (i & w) >> 2;
    i = i.wrapping_mul(0xc860_a3df);
    i &= w;
    i ^ (i >> 5)
}

fn laine_karras_permutation(mut x: u32, seed: u32) -> u32 {
    x = x.wrapping_add(seed);
    x ^= x.wrapping_mul(0x6c50_b47c);
    x ^= x.wrapping_mul(0xb82f_1e52);
    x ^= x.wrapping_mul(0xc7af_e638);
    x ^= x.wrapping_mul(0x8d22_f6e6);
    x
}

/// Owen scrambling of a 32-bit fixed-point coordinate (or index), hash-based.
pub fn nested_uniform_scramble(x: u32, seed: u32) -> u32 {
    scramble_reversed(x.reverse_bits(), seed)
}

/// [`nested_uniform_scramble`] of a coordinate given with its bits reversed: Sobol coordinates
/// come reversed from their tables (dimension 0 is the index reversed), which saves two
/// reversals (a dozen instructions each on x86) per coordinate.
fn scramble_reversed(reversed: u32, seed: u32) -> u32 {
    laine_karras_permutation(reversed, seed).reverse_bits()
}

/// A Sobol generator matrix as four tables of 256 entries, one per byte of the index: the XOR
/// of the columns that byte's set bits select, stored bit-reversed (what Owen scrambling reads;
/// see [`scramble_reversed`]). A product is then four loads and three XORs, where a loop over
/// the index's bits took up to 32 data-dependent branches (a shuffled index has random high
/// bits, so about half of them mispredict): that loop made Sobol samples cost 1.5x random ones.
type SobolTables = [[u32; 256]; 4];

const fn reversed_byte_tables(matrix: &[u32; 32]) -> SobolTables {
    let mut tables = [[0u32; 256]; 4];
    let mut byte = 0;
    while byte < 4 {
        let mut value = 0;
        while value < 256 {
            let mut x = 0;
            let mut bit = 0;
            while bit < 8 {
                if (value >> bit) & 1 != 0 {
                    x ^= matrix[8 * byte + bit];
                }
                bit += 1;
            }
            tables[byte][value] = x.reverse_bits();
            value += 1;
        }
        byte += 1;
    }
    tables
}

static SOBOL_TABLES_1: SobolTables = reversed_byte_tables(&SOBOL_MATRIX_1);
static SOBOL_TABLES_2: SobolTables = reversed_byte_tables(&SOBOL_MATRIX_2);
static SOBOL_TABLES_3: SobolTables = reversed_byte_tables(&SOBOL_MATRIX_3);

/// `index` through a Sobol generator matrix given as byte tables, bit-reversed: the XOR of the
/// matrix's columns of its set bits.
fn sobol_dimension_reversed(index: u32, tables: &SobolTables) -> u32 {
    let [b0, b1, b2, b3] = index.to_le_bytes();
    tables[0][b0 as usize]
        ^ tables[1][b1 as usize]
        ^ tables[2][b2 as usize]
        ^ tables[3][b3 as usize]
}

/// The lens point of sample `index` in the joint pixel x lens Sobol pattern: Sobol dimensions 2
/// and 3 of the same shuffled index as the pixel's (`pixel_seed` shuffles it, as in
/// [`sobol_owen_2d`]), each Owen-scrambled by `lens_seed`. The four coordinates of a sample are
/// then one 4-D Sobol point, jointly stratified (pbrt-v4's `SobolSampler` idea), where padding
/// two 2-D sets pairs them at random.
pub fn sobol_owen_lens(index: u32, pixel_seed: u32, lens_seed: u32) -> [f32; 2] {
    let shuffled = nested_uniform_scramble(index, pixel_seed);
    let x = sobol_dimension_reversed(shuffled, &SOBOL_TABLES_2);
    let y = sobol_dimension_reversed(shuffled, &SOBOL_TABLES_3);
    [
        unit_float(scramble_reversed(x, pcg_hash(lens_seed ^ 0x0000_a511))),
        unit_float(scramble_reversed(y, pcg_hash(lens_seed ^ 0x0000_b0b1))),
    ]
}

/// Point `index` of the shuffled, Owen-scrambled 2-D Sobol sequence keyed by `seed`.
pub fn sobol_owen_2d(index: u32, seed: u32) -> [f32; 2] {
    let shuffled = nested_uniform_scramble(index, seed);
    // Dimension 0 is the index's bits reversed: given reversed, it is the index itself.
    let x = scramble_reversed(shuffled, pcg_hash(seed ^ 0x0000_a511));
    let y = scramble_reversed(
        sobol_dimension_reversed(shuffled, &SOBOL_TABLES_1),
        pcg_hash(seed ^ 0x0000_b0b1),
    );
    [unit_float(x), unit_float(y)]
}

/// Point `index` of the progressive stratified pattern of `n` points keyed by `key`: the
/// stratum of point `index` of the Owen-scrambled (0,2)-sequence [`sobol_owen_2d`] in the grid
/// of the power of two `2^m` at or above `n` (`2^floor(m/2)` columns by `2^ceil(m/2)` rows),
/// jittered inside it by `u`. Every prefix of `2^k` points of a (0,2)-sequence has one point in
/// each cell of every `2^a x 2^b` grid with `a + b = k`, and the jitter keeps each point in its
/// stratum, so a pixel that stops after any number of samples is as stratified as a uniform
/// render of that many (the progressive jittered sequences of Christensen, Kensler and
/// Kilpatrick, "Progressive Multi-Jittered Sample Sequences", 2018, made from Sobol's (0,2)
/// digits); the first `2^m` points are one per stratum of the grid.
pub fn progressive_stratified(index: u32, n: u32, key: u32, u: [f32; 2]) -> [f32; 2] {
    let [x, y] = sobol_owen_2d(index, key);
    let bits = 32 - (n.max(1) - 1).leading_zeros();
    let (columns, rows) = (1u32 << (bits / 2), 1u32 << (bits - bits / 2));
    // Exact: the coordinates have 24 bits and the counts are powers of two.
    let cell = (y * rows as f32) as u32 * columns + (x * columns as f32) as u32;
    stratified_2d(cell, columns * rows, columns, u)
}

/// Where a pixel's sample comes from: the sampler, its strata and its patterns.
#[derive(Clone, Copy, Debug)]
pub struct PatternSource {
    /// The `SAMPLER_*` pattern.
    pub sampler: u32,
    /// Columns of the stratified grid of `spp` cells.
    pub strata_columns: u32,
    /// Where the pattern's precomputed points start in the sample table.
    pub table_offset: u32,
    /// First random dimension the samples draw (`PIXEL_DIMENSION` or `LENS_DIMENSION`).
    pub dim: u32,
}

impl PatternSource {
    /// The pixel-position samples of `frame` (random dimensions 0-1).
    pub fn pixel(frame: &GpuFrame) -> Self {
        PatternSource {
            sampler: frame.pixel_sampler,
            strata_columns: frame.pixel_strata_columns,
            table_offset: frame.pixel_table_offset,
            dim: PIXEL_DIMENSION,
        }
    }

    /// The lens samples of `frame` (random dimensions 2-3).
    pub fn lens(frame: &GpuFrame) -> Self {
        PatternSource {
            sampler: frame.lens_sampler,
            strata_columns: frame.lens_strata_columns,
            table_offset: frame.lens_table_offset,
            dim: LENS_DIMENSION,
        }
    }
}

/// The 2-D point of sample `sample` of pixel (x, y) in [0, 1)^2. Always draws `rng.next_2d()`;
/// ORs `STATUS_PERMUTE_CAP` into `flags` if the stratified permutation gives up.
#[allow(clippy::too_many_arguments)]
pub fn sample_2d(
    frame: &GpuFrame,
    table: &[[f32; 2]],
    source: PatternSource,
    x: u32,
    y: u32,
    sample: u32,
    rng: &mut Rng,
    flags: &mut u32,
) -> [f32; 2] {
    let u = rng.next_2d();
    if source.sampler == SAMPLER_RANDOM {
        return u;
    }
    let key = pixel_hash(frame.seed, y * frame.width + x, source.dim);
    match source.sampler {
        SAMPLER_STRATIFIED if frame.progressive != 0 => {
            progressive_stratified(sample, frame.spp, key, u)
        }
        SAMPLER_STRATIFIED => {
            let stratum = permute(sample, frame.spp, key).unwrap_or_else(|| {
                *flags |= STATUS_PERMUTE_CAP;
                sample
            });
            stratified_2d(stratum, frame.spp, source.strata_columns, u)
        }
        SAMPLER_POISSON => {
            let set = key % POISSON_SETS;
            let p = table[(source.table_offset + set * frame.spp + sample) as usize];
            let shift = [
                unit_float(pcg_hash(key)),
                unit_float(pcg_hash(key ^ 0x5151)),
            ];
            [wrap_unit(p[0] + shift[0]), wrap_unit(p[1] + shift[1])]
        }
        SAMPLER_INTERLEAVED => {
            let pattern = (x % INTERLEAVED_TILE) + INTERLEAVED_TILE * (y % INTERLEAVED_TILE);
            table[(source.table_offset + pattern * frame.spp + sample) as usize]
        }
        // A Sobol lens under a Sobol pixel pattern: the joint 4-D pattern.
        SAMPLER_SOBOL if source.dim == LENS_DIMENSION && frame.pixel_sampler == SAMPLER_SOBOL => {
            let pixel_key = pixel_hash(frame.seed, y * frame.width + x, PIXEL_DIMENSION);
            sobol_owen_lens(sample, pixel_key, key)
        }
        SAMPLER_SOBOL => sobol_owen_2d(sample, key),
        _ => u,
    }
}

/// The point of light sample `k` (of `light_samples`, stratified by `light_columns` columns) of
/// camera sample `sample`; `key` is the pixel's key for the light, `pixel_hash(seed, pixel,
/// first dimension of the light)`, made once per light, and `u` the sample's own random pair
/// (always drawn). Light samples follow the pixel pattern over
/// the pixel's `spp x light_samples` points, so consecutive camera samples do not repeat each
/// other's light points: Sobol takes point `sample * light_samples + k` of an Owen-scrambled
/// sequence; stratified, Poisson and interleaved patterns (whose tables hold `spp` points, not
/// `spp x light_samples`) a permuted stratum of the product grid (the pixel pattern's strata
/// times the light's), or under adaptive sampling (`frame.progressive`) point `sample *
/// light_samples + k` of the progressive stratified pattern ([`progressive_stratified`]) of
/// those points, whose every prefix is stratified. Random patterns, and pixels with more than
/// `MAX_LIGHT_PATTERN_POINTS` light points, stratify each camera sample's light samples alone.
#[allow(clippy::too_many_arguments)]
pub fn light_sample_2d(
    frame: &GpuFrame,
    light_samples: u32,
    light_columns: u32,
    sample: u32,
    k: u32,
    key: u32,
    u: [f32; 2],
    flags: &mut u32,
) -> [f32; 2] {
    // The kernel's `spp > MAX_LIGHT_PATTERN_POINTS / light_samples`, without its division.
    let points = frame.spp as u64 * light_samples as u64;
    if frame.pixel_sampler == SAMPLER_RANDOM || points > MAX_LIGHT_PATTERN_POINTS as u64 {
        return stratified_2d(k, light_samples, light_columns, u);
    }
    let index = sample * light_samples + k;
    if frame.pixel_sampler == SAMPLER_SOBOL {
        return sobol_owen_2d(index, key);
    }
    let n = frame.spp * light_samples;
    if frame.progressive != 0 {
        return progressive_stratified(index, n, key, u);
    }
    let stratum = permute(index, n, key).unwrap_or_else(|| {
        *flags |= STATUS_PERMUTE_CAP;
        index
    });
    stratified_2d(stratum, n, frame.pixel_strata_columns * light_columns, u)
}

/// x - floor(x) for x in [0, 2), staying below 1 (a sum of two values in [0, 1) may round to 1).
fn wrap_unit(x: f32) -> f32 {
    let w = if x >= 1.0 { x - 1.0 } else { x };
    w.min(0.999_999_94)
}

/// A point of the aperture in mm (lens frame), uniform by area: the disk of radius
/// `lens_radius_mm` by the concentric map, or the inscribed regular polygon by picking one of its
/// `n` equal triangles with `u.x` and a uniform point of that triangle.
pub fn sample_aperture(camera: &GpuCamera, table: &[[f32; 2]], u: [f32; 2]) -> [f32; 2] {
    let r = camera.lens_radius_mm;
    if camera.aperture_blades == 0 {
        let [x, y] = concentric_disk(u);
        return [r * x, r * y];
    }
    let n = camera.aperture_blades;
    let scaled = u[0] * n as f32;
    let k = (scaled as u32).min(n - 1);
    let radial = (scaled - k as f32).sqrt();
    let a = table[(camera.aperture_table_offset + k) as usize];
    let b = table[(camera.aperture_table_offset + k + 1) as usize];
    let s = r * radial;
    [
        s * (a[0] + u[1] * (b[0] - a[0])),
        s * (a[1] + u[1] * (b[1] - a[1])),
    ]
}

#[cfg(test)]
mod name_tests {
    use super::SamplerName;
    use crate::named::Named;

    #[test]
    fn scene_files_and_flags_spell_the_samplers_alike() {
        for v in SamplerName::VALUES {
            let quoted = format!("\"{}\"", v.name);
            assert_eq!(
                serde_json::from_str::<SamplerName>(&quoted).unwrap(),
                v.value
            );
        }
    }
}

#[cfg(test)]
mod sobol_matrix_tests {
    use super::*;

    /// The matrix-vector product over GF(2), bit by bit: the byte tables' reference.
    fn product_bit_by_bit(index: u32, matrix: &[u32; 32]) -> u32 {
        (0..32)
            .filter(|&k| (index >> k) & 1 != 0)
            .fold(0, |x, k| x ^ matrix[k])
    }

    #[test]
    fn the_byte_tables_multiply_as_the_matrices_do() {
        let mut rng = Rng::new(7, 0, 0);
        let pairs = [
            (&SOBOL_MATRIX_1, &SOBOL_TABLES_1),
            (&SOBOL_MATRIX_2, &SOBOL_TABLES_2),
            (&SOBOL_MATRIX_3, &SOBOL_TABLES_3),
        ];
        for (matrix, tables) in pairs {
            let edges = [0, 1, 0x80, 0x100, 0x8000_0000, u32::MAX, 0xdead_beef];
            let random = (0..1000).map(|_| rng.next_u32());
            for index in edges.into_iter().chain(random) {
                assert_eq!(
                    sobol_dimension_reversed(index, tables),
                    product_bit_by_bit(index, matrix).reverse_bits(),
                    "index {index:#x}"
                );
            }
        }
    }

    #[test]
    fn dimension_1_is_the_recurrence_of_x_plus_1() {
        let mut v = 1u32 << 31;
        for column in SOBOL_MATRIX_1 {
            assert_eq!(column, v);
            v ^= v >> 1;
        }
    }

    #[test]
    fn each_sobol_dimension_stratifies_every_power_of_two_prefix() {
        for tables in [&SOBOL_TABLES_1, &SOBOL_TABLES_2, &SOBOL_TABLES_3] {
            for m in 1..=12 {
                let mut seen = vec![false; 1 << m];
                for i in 0..1u32 << m {
                    let cell =
                        (sobol_dimension_reversed(i, tables).reverse_bits() >> (32 - m)) as usize;
                    assert!(!seen[cell], "dimension prefix {m}: cell {cell} twice");
                    seen[cell] = true;
                }
            }
        }
    }

    #[test]
    fn the_joint_lens_points_pair_with_the_pixel_points_as_sobol_dimensions_do() {
        // The shuffled index is the pixel's: 2^m pixel points and their lens points are the
        // first 2^m points of a 4-D Sobol sequence, scrambled, so the lens projection alone is
        // stratified too, and for 16 points each 4 x 4 lens cell holds one (dimensions 2 and 3
        // of Sobol form a (0, 2)-net at this size).
        let (pixel_seed, lens_seed) = (0x1234_5678, 0x9abc_def0);
        let mut cells = [0u32; 16];
        for i in 0..16 {
            let [u, v] = sobol_owen_lens(i, pixel_seed, lens_seed);
            cells[(u * 4.0) as usize + 4 * (v * 4.0) as usize] += 1;
        }
        assert!(cells.iter().all(|&c| c == 1), "{cells:?}");
    }
}

#[cfg(test)]
mod elimination_tests {
    use super::*;

    /// The elimination as it was written first: every pair compared.
    fn eliminate_by_every_pair(points: &mut Vec<[f64; 2]>, n: usize) {
        let nearest = |points: &[[f64; 2]], i: usize| {
            (0..points.len())
                .filter(|&j| j != i)
                .map(|j| toroidal_distance(points[i], points[j]))
                .fold(f64::INFINITY, f64::min)
        };
        let mut distance: Vec<f64> = (0..points.len()).map(|i| nearest(points, i)).collect();
        while points.len() > n {
            let worst = (0..points.len())
                .min_by(|&a, &b| distance[a].total_cmp(&distance[b]))
                .unwrap();
            let removed = points.swap_remove(worst);
            distance.swap_remove(worst);
            for i in 0..points.len() {
                if toroidal_distance(points[i], removed) <= distance[i] {
                    distance[i] = nearest(points, i);
                }
            }
        }
    }

    /// The grid's elimination removes the very points comparing every pair removes, in the
    /// same order, on Bridson sets and on clumped random points (cells of many points, and
    /// points on cell edges and across the torus's seam), from one point to a few hundred.
    #[test]
    fn the_grid_eliminates_as_every_pair_does() {
        let mut rng = Rng::new(5, 0, 0);
        for round in 0..40u32 {
            let radius = 0.02 + 0.2 * rng.next_f32() as f64;
            let mut points = match round % 2 {
                0 => bridson_torus(radius, &mut rng),
                _ => (0..1 + round * 7)
                    .map(|k| {
                        let [u, v] = rng.next_2d().map(f64::from);
                        // Clumps of points, some at exact cell edges and at the seam.
                        match k % 3 {
                            0 => [(0.999 + 0.002 * u).rem_euclid(1.0), 0.5 * v],
                            1 => [(u * 4.0).floor() / 4.0, v],
                            _ => [u, v],
                        }
                    })
                    .collect(),
            };
            let n = points.len() * (1 + round as usize % 3) / 4;
            let mut expected = points.clone();
            eliminate_by_every_pair(&mut expected, n);
            eliminate_closest(&mut points, n, radius);
            assert_eq!(points, expected, "round {round}");
        }
    }
}
