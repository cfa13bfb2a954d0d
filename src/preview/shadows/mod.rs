//! The preview's shadows (`chambre preview --shadows`): a depth map per light, drawn once from
//! the main pass's triangles (the scene is static; a camera change that cuts curved shapes
//! anew draws them again), looked up per fragment by `lit_fraction` in `wgsl/preview/shading.wgsl`.
//!
//! - Point and spot lights get a cube of six 90° views (`CUBE_FACES`; the face a direction
//!   falls in: `cube_face`). Area lights get n² cubes at the centres of n x n strata of their
//!   surface (n sub-triangles a side for a triangle; n = 1 by default: the centre, where the
//!   preview lights them from), a fragment lit by the fraction of the cubes that see it: soft
//!   shadows for n > 1. A cube stands `EMITTER_CLEARANCE` of its far distance in front of the
//!   light, off its emitting surface.
//! - Directional lights get one orthographic view over the sphere that bounds the scene's
//!   bounded primitives; receivers outside it (the far parts of a plane) are lit.
//! - Each view's far plane lies beyond the bounded primitives; its near plane at `NEAR` of that
//!   distance. Casters nearer a light than that cast no shadow, and receivers outside a view
//!   are lit.
//!
//! The shadows are hard, as from a point: the ray tracer's area lights give soft ones. Each
//! map is `SHADOW_MAP_SIZE` texels square, or smaller where the scene's lights need more than
//! `SHADOW_MEMORY` of them at that size (`shadow_map_size`), filtered 2x2 by the comparison
//! sampler; a fragment is looked up `SHADOW_NORMAL_OFFSET` texels off its surface along its
//! normal, and the maps are drawn with a slope-scaled depth bias, so that surfaces do not
//! shadow themselves.

use bytemuck::{Pod, Zeroable};
use glam::{Mat4, Vec3, Vec4};

use crate::layout::{
    GpuLight, LIGHT_AREA, LIGHT_DIRECTIONAL, LIGHT_ENVIRONMENT, LIGHT_SUN, LIGHT_TRIANGLE,
};

pub(crate) mod maps;

pub use maps::SHADOW_SHADER;

/// Texels along each side of a shadow map, at most.
pub const SHADOW_MAP_SIZE: u32 = 1024;
/// Texels along each side of a shadow map, at least.
pub const SMALLEST_SHADOW_MAP: u32 = 128;
/// The bytes the maps may take together (4 a texel): 24 maps of 1024², four cubes.
pub const SHADOW_MEMORY: u64 = 96 << 20;

/// The side of `layers` shadow maps: `SHADOW_MAP_SIZE`, halved until they fit in
/// `SHADOW_MEMORY`; `None` where not even `SMALLEST_SHADOW_MAP` fits.
pub fn shadow_map_size(layers: u32) -> Option<u32> {
    let mut side = SHADOW_MAP_SIZE;
    while u64::from(layers) * u64::from(side) * u64::from(side) * 4 > SHADOW_MEMORY {
        side /= 2;
        if side < SMALLEST_SHADOW_MAP {
            return None;
        }
    }
    Some(side)
}
/// How far (texels of its map) a fragment is moved along its normal before its lookup.
pub const SHADOW_NORMAL_OFFSET: f32 = 1.5;
/// A view's near plane, in parts of its far distance.
pub const NEAR: f32 = 1e-3;
/// How far in front of an area light its cube stands, in parts of its far distance.
pub const EMITTER_CLEARANCE: f32 = 2.0 * NEAR;

/// The six faces of a light's cube, in layer order: the direction each looks along and its up.
pub const CUBE_FACES: [(Vec3, Vec3); 6] = [
    (Vec3::X, Vec3::Y),
    (Vec3::NEG_X, Vec3::Y),
    (Vec3::Y, Vec3::Z),
    (Vec3::NEG_Y, Vec3::Z),
    (Vec3::Z, Vec3::Y),
    (Vec3::NEG_Z, Vec3::Y),
];

/// The face of a cube (index into `CUBE_FACES`) that direction `d` falls in: its largest
/// coordinate's axis and sign, x before y before z where they tie (`cube_face` in
/// wgsl/preview/shading.wgsl).
pub fn cube_face(d: Vec3) -> u32 {
    let a = d.abs();
    if a.x >= a.y && a.x >= a.z {
        u32::from(d.x < 0.0)
    } else if a.y >= a.z {
        2 + u32::from(d.y < 0.0)
    } else {
        4 + u32::from(d.z < 0.0)
    }
}

/// One light's shadow maps as the fragment shader finds them (`ShadowLight` in
/// wgsl/preview/shading.wgsl).
#[repr(C)]
#[derive(Clone, Copy, Debug, Default, PartialEq, Pod, Zeroable)]
pub struct ShadowLight {
    /// Its first layer in the maps' array.
    pub first: u32,
    /// Its layers: 0 (no shadows), 1 (directional) or 6 a cube (an area light's several).
    pub layers: u32,
    /// A texel's width in scene units: at unit distance along a cube face's axis (times the
    /// distance there), or across the directional view.
    pub texel: f32,
    /// Its first cube's origin in `ShadowPlan::origins` (the others follow).
    pub origins: u32,
}

/// Every light's shadow map: per light its entry, and per layer its view's matrix (world to
/// wgpu clip space, depth in [0, 1]).
#[derive(Clone, Debug, PartialEq)]
pub struct ShadowPlan {
    /// Per light of the scene's light array: its map's entry.
    pub lights: Vec<ShadowLight>,
    /// Per layer of the maps: its view.
    pub views: Vec<Mat4>,
    /// Per cube: where it stands (`w` unused).
    pub origins: Vec<[f32; 4]>,
    /// Texels along each side of a map.
    pub side: u32,
}

impl ShadowPlan {
    /// The maps of `lights`, `side` texels square, over a scene whose bounded primitives lie in
    /// the sphere at `center` of radius `radius`; area lights get `area_samples`² cubes.
    pub fn new(
        lights: &[GpuLight],
        (center, radius): (Vec3, f32),
        side: u32,
        area_samples: u32,
    ) -> ShadowPlan {
        let mut plan = ShadowPlan {
            lights: Vec::new(),
            views: Vec::new(),
            origins: Vec::new(),
            side,
        };
        for light in lights {
            let first = plan.views.len() as u32;
            let entry = if light.kind == LIGHT_ENVIRONMENT {
                // Light from everywhere: the preview draws it unshadowed.
                ShadowLight::default()
            } else if light.kind == LIGHT_DIRECTIONAL || light.kind == LIGHT_SUN {
                plan.views
                    .push(directional_view(Vec3::from(light.p0), (center, radius)));
                ShadowLight {
                    first,
                    layers: 1,
                    texel: 2.0 * radius / side as f32,
                    ..Default::default()
                }
            } else {
                let origins = plan.origins.len() as u32;
                for origin in cube_origins(light, (center, radius), area_samples) {
                    let far = 1.01 * (origin.distance(center) + radius);
                    let projection = quarter_turn_perspective(NEAR * far, far);
                    for (forward, up) in CUBE_FACES {
                        plan.views.push(projection * look_to(origin, forward, up));
                    }
                    plan.origins.push(origin.extend(0.0).to_array());
                }
                ShadowLight {
                    first,
                    layers: plan.views.len() as u32 - first,
                    texel: 2.0 / side as f32,
                    origins,
                }
            };
            plan.lights.push(entry);
        }
        plan
    }

    /// No shadows: an entry with no layers per light.
    pub fn none(light_count: usize) -> ShadowPlan {
        ShadowPlan {
            lights: vec![ShadowLight::default(); light_count],
            views: Vec::new(),
            origins: Vec::new(),
            side: 1,
        }
    }

    /// The layers `lights` need: a directional light's one, a point or spot light's cube of
    /// six, an area light's `area_samples`² cubes.
    pub fn layers(lights: &[GpuLight], area_samples: u32) -> u32 {
        lights
            .iter()
            .map(|l| match l.kind {
                LIGHT_ENVIRONMENT => 0,
                LIGHT_DIRECTIONAL | LIGHT_SUN => 1,
                LIGHT_AREA | LIGHT_TRIANGLE => 6 * area_samples * area_samples,
                _ => 6,
            })
            .sum()
    }
}

/// Where `light`'s cubes stand: a point or spot light's position; for an area light, the
/// centres of n x n strata of its parallelogram (the centroids of the n² triangles its
/// triangle is cut into, n to a side), each moved `EMITTER_CLEARANCE` of its far distance
/// along the light's normal, off the emitting surface the cube would otherwise cut.
fn cube_origins(light: &GpuLight, (center, radius): (Vec3, f32), n: u32) -> Vec<Vec3> {
    let [p0, p1, p2] = [light.p0, light.p1, light.p2].map(Vec3::from);
    let at = |(a, b): (f32, f32)| p0 + a / n as f32 * p1 + b / n as f32 * p2;
    let points: Vec<Vec3> = match light.kind {
        LIGHT_AREA => (0..n * n)
            .map(|k| at(((k % n) as f32 + 0.5, (k / n) as f32 + 0.5)))
            .collect(),
        LIGHT_TRIANGLE => (0..n)
            .flat_map(|j| (0..n - j).map(move |i| (i as f32, j as f32)))
            .flat_map(|(i, j)| {
                let up = at((i + 1.0 / 3.0, j + 1.0 / 3.0));
                let down = (i + j + 1.0 < n as f32).then(|| at((i + 2.0 / 3.0, j + 2.0 / 3.0)));
                std::iter::once(up).chain(down)
            })
            .collect(),
        _ => return vec![p0],
    };
    let normal = p1.cross(p2).normalize_or_zero();
    points
        .into_iter()
        .map(|p| p + EMITTER_CLEARANCE * (p.distance(center) + radius) * normal)
        .collect()
}

/// The orthographic view along a directional light (`toward` points to the light) over the
/// sphere at `center` of radius `radius`: its box is the sphere's, from 2 radii before it.
fn directional_view(toward: Vec3, (center, radius): (Vec3, f32)) -> Mat4 {
    let forward = -toward.normalize();
    let eye = center - 2.0 * radius * forward;
    let up = forward.any_orthonormal_vector();
    // x and y over [-radius, radius] to [-1, 1]; depth 0 to 4 radii to [0, 1].
    let projection = Mat4::from_cols(
        Vec4::new(1.0 / radius, 0.0, 0.0, 0.0),
        Vec4::new(0.0, 1.0 / radius, 0.0, 0.0),
        Vec4::new(0.0, 0.0, -1.0 / (4.0 * radius), 0.0),
        Vec4::W,
    );
    projection * look_to(eye, forward, up)
}

/// The view from `eye` looking along `forward` with `up` upward: x right, y up, looking down
/// -z (right-handed, as OpenGL's).
fn look_to(eye: Vec3, forward: Vec3, up: Vec3) -> Mat4 {
    let f = forward.normalize();
    let right = f.cross(up).normalize();
    let up = right.cross(f);
    Mat4::from_cols(
        Vec4::new(right.x, up.x, -f.x, 0.0),
        Vec4::new(right.y, up.y, -f.y, 0.0),
        Vec4::new(right.z, up.z, -f.z, 0.0),
        Vec4::new(-right.dot(eye), -up.dot(eye), f.dot(eye), 1.0),
    )
}

/// The perspective of a 90° square view looking down -z, depth `near` to `far` mapped to
/// [0, 1] (wgpu's).
fn quarter_turn_perspective(near: f32, far: f32) -> Mat4 {
    Mat4::from_cols(
        Vec4::X,
        Vec4::Y,
        Vec4::new(0.0, 0.0, far / (near - far), -1.0),
        Vec4::new(0.0, 0.0, near * far / (near - far), 0.0),
    )
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::layout::{LIGHT_POINT, LIGHT_SPOT};

    fn light(kind: u32, p0: Vec3) -> GpuLight {
        GpuLight {
            p0: p0.to_array(),
            kind,
            p1: [0.5, 0.0, 0.0],
            p2: [0.0, 0.0, 0.5],
            color: [1.0; 3],
            ..Default::default()
        }
    }

    /// A point seen by a view lands in its clip volume (x, y in [-1, 1], depth in [0, 1]).
    fn inside(view: Mat4, p: Vec3) -> bool {
        let q = view.project_point3(p);
        q.x.abs() <= 1.0 + 1e-5 && q.y.abs() <= 1.0 + 1e-5 && (0.0..=1.0).contains(&q.z)
    }

    /// Every point of the bounding sphere falls in the face `cube_face` picks for it, for a
    /// point light inside the sphere, on it and far outside it (the faces cover the directions,
    /// and the far plane the sphere).
    #[test]
    fn each_direction_falls_in_the_face_picked_for_it() {
        let sphere = (Vec3::new(0.3, -0.2, 0.1), 2.0);
        let mut state = 7u64;
        let mut next = || {
            state = state
                .wrapping_mul(6364136223846793005)
                .wrapping_add(1442695040888963407);
            (state >> 40) as f32 / (1u64 << 24) as f32 * 2.0 - 1.0
        };
        for position in [
            Vec3::ZERO,
            Vec3::new(0.0, 2.0, 0.0),
            Vec3::new(5.0, 9.0, -4.0),
        ] {
            let plan = ShadowPlan::new(&[light(LIGHT_POINT, position)], sphere, 1024, 1);
            assert_eq!(plan.views.len(), 6);
            for _ in 0..2000 {
                let d = Vec3::new(next(), next(), next());
                if d.length() > 1.0 || d.length() < 1e-3 {
                    continue;
                }
                let p = sphere.0 + sphere.1 * d;
                if p.distance(position) < 1e-2 {
                    continue;
                }
                let face = cube_face(p - position) as usize;
                assert!(
                    inside(plan.views[face], p),
                    "{p} from {position}: face {face}"
                );
            }
        }
    }

    /// An area light's cubes stand at the centres of its strata, a triangle's at the centroids
    /// of its pieces: their mean is the light's centre, each off the surface on its emitting
    /// side.
    #[test]
    fn an_area_lights_cubes_spread_over_it() {
        let sphere = (Vec3::ZERO, 1.0);
        for (kind, centre, count) in [
            (LIGHT_AREA, Vec3::new(0.25, 3.0, 0.25), 16),
            (LIGHT_TRIANGLE, Vec3::new(1.0 / 6.0, 3.0, 1.0 / 6.0), 16),
        ] {
            let origins = cube_origins(&light(kind, Vec3::new(0.0, 3.0, 0.0)), sphere, 4);
            assert_eq!(origins.len(), count);
            let mean = origins.iter().sum::<Vec3>() / count as f32;
            let off = mean - centre;
            assert!(off.x.abs() < 1e-6 && off.z.abs() < 1e-6, "{kind}: {mean}");
            assert!(
                origins.iter().all(|o| o.y < 3.0 && o.y > 2.98),
                "{origins:?}"
            );
            let mut xs: Vec<f32> = origins.iter().map(|o| o.x).collect();
            xs.dedup_by(|a, b| (*a - *b).abs() < 1e-6);
            assert!(xs.len() > 1);
        }
    }

    /// Maps keep 1024 texels a side up to four cubes, then halve as the lights need more, down
    /// to 128; beyond, none fit.
    #[test]
    fn maps_shrink_to_fit_their_memory() {
        assert_eq!(shadow_map_size(1), Some(1024));
        assert_eq!(shadow_map_size(24), Some(1024));
        assert_eq!(shadow_map_size(25), Some(512));
        assert_eq!(shadow_map_size(96), Some(512));
        assert_eq!(shadow_map_size(1536), Some(128));
        assert_eq!(shadow_map_size(1537), None);
    }

    /// The faces tie toward x, then y: a direction on a cube's edge gets one face, the same in
    /// both twins.
    #[test]
    fn ties_go_to_the_first_axis() {
        assert_eq!(cube_face(Vec3::new(1.0, 1.0, 1.0)), 0);
        assert_eq!(cube_face(Vec3::new(-1.0, 1.0, 1.0)), 1);
        assert_eq!(cube_face(Vec3::new(0.0, -1.0, 1.0)), 3);
        assert_eq!(cube_face(Vec3::new(0.0, 0.0, -1.0)), 5);
    }

    /// A directional light's view holds the whole bounding sphere, whatever its direction.
    #[test]
    fn a_directional_view_holds_the_bounding_sphere() {
        let sphere = (Vec3::new(1.0, 2.0, 3.0), 0.5);
        for toward in [Vec3::Y, Vec3::new(1.0, 1.0, 0.0), Vec3::new(0.0, 0.0, -1.0)] {
            let plan = ShadowPlan::new(&[light(LIGHT_DIRECTIONAL, toward)], sphere, 1024, 1);
            assert_eq!(plan.lights[0].layers, 1);
            for d in [
                Vec3::X,
                Vec3::NEG_X,
                Vec3::Y,
                Vec3::NEG_Y,
                Vec3::Z,
                Vec3::NEG_Z,
            ] {
                assert!(
                    inside(plan.views[0], sphere.0 + 0.999 * sphere.1 * d),
                    "{toward} {d}"
                );
            }
        }
    }

    /// Layers follow the lights: a cube per local light, one per directional light; an area
    /// light's cube stands off its surface, on the side it emits to.
    #[test]
    fn layers_follow_the_lights() {
        let sphere = (Vec3::ZERO, 1.0);
        let lights = [
            light(LIGHT_SPOT, Vec3::Y),
            light(LIGHT_DIRECTIONAL, Vec3::Y),
            light(LIGHT_AREA, Vec3::new(0.0, 3.0, 0.0)),
        ];
        assert_eq!(ShadowPlan::layers(&lights, 1), 13);
        let plan = ShadowPlan::new(&lights, sphere, 512, 1);
        assert_eq!(plan.lights[0].texel, 2.0 / 512.0);
        let firsts: Vec<(u32, u32, u32)> = plan
            .lights
            .iter()
            .map(|l| (l.first, l.layers, l.origins))
            .collect();
        assert_eq!(firsts, [(0, 6, 0), (6, 1, 0), (7, 6, 1)]);
        assert_eq!(plan.views.len(), 13);
        // Edges x and z: the normal x × z = -y.
        let origin = Vec3::from_slice(&plan.origins[1]);
        assert!(origin.y < 3.0 && (origin.x - 0.25).abs() < 1e-6, "{origin}");
        assert_eq!(ShadowPlan::none(3).lights, vec![ShadowLight::default(); 3]);
        // Three by three cubes for the area light: 6 + 1 + 54 layers.
        assert_eq!(ShadowPlan::layers(&lights, 3), 61);
        let plan = ShadowPlan::new(&lights, sphere, 512, 3);
        assert_eq!((plan.lights[2].layers, plan.origins.len()), (54, 10));
        // `layers`, which sizes the maps before the plan is made, counts what the plan makes.
        assert_eq!(plan.views.len() as u32, ShadowPlan::layers(&lights, 3));
    }
}
