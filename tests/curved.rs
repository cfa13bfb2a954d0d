//! Exact intersection of ellipsoids, cylinders and tori (`accel::curved`): against double
//! precision at scales from 1e-3 to 1e4, shading points within their error bounds of the true
//! surface, rays leaving them that meet them again only where they truly do, and the GPU's
//! kernels finding what the CPU finds.

mod common;

use chambre::accel::curved::curved_surface_point;
use chambre::accel::cwbvh;
use chambre::accel::intersect::{
    Hit, RayQuery, SurfacePoint, intersect_primitive, offset_ray_origin,
};
use chambre::bench::rays::{
    Bvh, Pinhole, Query, bounds, coherent_rays, incoherent_rays, trace_cpu,
};
use chambre::gpu::trace::GpuTracer;
use chambre::layout::{FEATURES_ALL, GpuPrimitive, T_FAR};
use chambre::math::rng::Rng;
use chambre::pack::{curved_primitive, flatten};
use chambre::scene::{CurvedPrimitive as Shape, Scene};
use glam::{DVec3, Quat, Vec3};

/// What the tests ask of a shape: the ray tracers' intersection and shading point (through
/// the primitive the kernels read), and the truth in double precision.
trait Probe {
    fn intersect(&self, ray: &RayQuery) -> Hit;
    fn surface_point(&self, ray: &RayQuery, t: f32) -> (SurfacePoint, Vec3);
    fn extent(&self) -> (Vec3, f32);
    fn distance(&self, p: DVec3) -> f64;
    fn crossings(&self, origin: DVec3, direction: DVec3) -> Vec<f64>;
}

/// A shape as a scene gives it: in its own frame, turned by `orientation` about its centre.
#[derive(Debug)]
struct Turned {
    shape: Shape,
    orientation: Quat,
}

impl Turned {
    /// The primitive the ray tracers intersect, packed as a scene's is.
    fn prim(&self) -> GpuPrimitive {
        curved_primitive(&self.shape, self.orientation, 0)
    }

    /// Where `p` (world) is for the unturned shape, in f64.
    fn unturned(&self, p: DVec3) -> DVec3 {
        let pivot = DVec3::from(self.prim().p0.map(f64::from));
        pivot + self.orientation.as_dquat().normalize().conjugate() * (p - pivot)
    }
}

impl Probe for Turned {
    fn intersect(&self, ray: &RayQuery) -> Hit {
        intersect_primitive::<FEATURES_ALL>(ray, &self.prim(), T_FAR)
    }

    fn surface_point(&self, ray: &RayQuery, t: f32) -> (SurfacePoint, Vec3) {
        curved_surface_point(ray, t, &self.prim())
    }

    fn extent(&self) -> (Vec3, f32) {
        let (centre, half) = self.shape.extent();
        let pivot = Vec3::from(self.prim().p0);
        (pivot + self.orientation * (centre - pivot), half)
    }

    fn distance(&self, p: DVec3) -> f64 {
        self.shape.distance(self.unturned(p))
    }

    fn crossings(&self, origin: DVec3, direction: DVec3) -> Vec<f64> {
        let back = self.orientation.as_dquat().normalize().conjugate();
        self.shape
            .crossings(self.unturned(origin), back * direction)
    }
}

/// The unturned shapes: their box, distance and crossings, in f64.
trait Unturned {
    fn extent(&self) -> (Vec3, f32);
    fn distance(&self, p: DVec3) -> f64;
    fn crossings(&self, origin: DVec3, direction: DVec3) -> Vec<f64>;
}

impl Unturned for Shape {
    /// The centre of its bounding box and its half-diagonal.
    fn extent(&self) -> (Vec3, f32) {
        match *self {
            Shape::Ellipsoid { center, radii } => (center, radii.length()),
            Shape::Cylinder {
                base,
                radius,
                height,
            } => (
                base + Vec3::Y * height / 2.0,
                (2.0 * radius * radius + height * height / 4.0).sqrt(),
            ),
            Shape::Torus {
                center,
                major,
                minor,
            } => (center, major + minor),
        }
    }

    /// The distance of `p` from the surface in f64, to first order where not exact (the
    /// ellipsoid); a cylinder's distance counts only the radial part (its rims are open).
    fn distance(&self, p: DVec3) -> f64 {
        match *self {
            Shape::Ellipsoid { center, radii } => {
                let (q, s) = (p - center.as_dvec3(), radii.as_dvec3());
                let f = (q / s).length_squared() - 1.0;
                f.abs() / (2.0 * q / (s * s)).length()
            }
            Shape::Cylinder { base, radius, .. } => {
                let q = p - base.as_dvec3();
                (q.x.hypot(q.z) - radius as f64).abs()
            }
            Shape::Torus {
                center,
                major,
                minor,
            } => torus_distance(p - center.as_dvec3(), major as f64, minor as f64).abs(),
        }
    }

    /// The distances along the ray (origin, unit direction), in f64, where it crosses the
    /// surface, in increasing order (a ray touching it tangentially may be missed).
    fn crossings(&self, origin: DVec3, direction: DVec3) -> Vec<f64> {
        match *self {
            Shape::Ellipsoid { center, radii } => {
                let s = radii.as_dvec3();
                let (f, e) = ((origin - center.as_dvec3()) / s, direction / s);
                quadratic(e.dot(e), f.dot(e), f.dot(f) - 1.0)
            }
            Shape::Cylinder {
                base,
                radius,
                height,
            } => {
                let f = origin - base.as_dvec3();
                let r = radius as f64;
                let (a, b, c) = (
                    direction.x.powi(2) + direction.z.powi(2),
                    f.x * direction.x + f.z * direction.z,
                    f.x * f.x + f.z * f.z - r * r,
                );
                quadratic(a, b, c)
                    .into_iter()
                    .filter(|t| (0.0..=height as f64).contains(&(f.y + t * direction.y)))
                    .collect()
            }
            Shape::Torus {
                center,
                major,
                minor,
            } => {
                let f = origin - center.as_dvec3();
                let (major, minor) = (major as f64, minor as f64);
                let g = |t: f64| torus_distance(f + t * direction, major, minor);
                // Inside the bounding sphere, a sign change every step of 1/20000 of it.
                let reach = major + minor;
                let along = f.dot(direction);
                let h2 = reach * reach - (f - along * direction).length_squared();
                if h2 < 0.0 {
                    return Vec::new();
                }
                let (from, to) = (-along - h2.sqrt(), -along + h2.sqrt());
                let steps = 20000;
                let mut roots = Vec::new();
                let mut previous = (from, g(from));
                for k in 1..=steps {
                    let t = from + (to - from) * k as f64 / steps as f64;
                    let value = g(t);
                    if (value < 0.0) != (previous.1 < 0.0) {
                        let (mut lo, mut hi) = (previous.0, t);
                        for _ in 0..80 {
                            let mid = 0.5 * (lo + hi);
                            if (g(mid) < 0.0) == (previous.1 < 0.0) {
                                lo = mid;
                            } else {
                                hi = mid;
                            }
                        }
                        roots.push(0.5 * (lo + hi));
                    }
                    previous = (t, value);
                }
                roots
            }
        }
    }
}

/// The torus's signed distance: sqrt((rho - R)^2 + y^2) - r.
fn torus_distance(q: DVec3, major: f64, minor: f64) -> f64 {
    (q.x.hypot(q.z) - major).hypot(q.y) - minor
}

/// The real roots of a t^2 + 2 b t + c, in increasing order.
fn quadratic(a: f64, b: f64, c: f64) -> Vec<f64> {
    let discriminant = b * b - a * c;
    if discriminant < 0.0 {
        return Vec::new();
    }
    let q = -b - b.signum() * discriminant.sqrt();
    let mut roots = vec![q / a, c / q];
    roots.sort_by(f64::total_cmp);
    roots
}

fn unit(rng: &mut Rng) -> Vec3 {
    let [u, v] = rng.next_2d();
    let z = 2.0 * u - 1.0;
    let r = (1.0 - z * z).max(0.0).sqrt();
    let phi = std::f32::consts::TAU * v;
    Vec3::new(r * phi.cos(), z, r * phi.sin())
}

/// Shapes of size `size` (within a factor of 3) whose centres lie `offset` from the origin, each
/// unturned and turned about a random axis.
fn shapes(rng: &mut Rng, size: f32, offset: f32) -> Vec<Turned> {
    let mut shapes = Vec::new();
    for _ in 0..6 {
        let mut scale = || size * (0.5 + 2.5 * rng.next_f32());
        let (a, b, c) = (scale(), scale(), scale());
        let centre = unit(rng) * offset;
        shapes.push(Shape::Ellipsoid {
            center: centre,
            radii: Vec3::new(a, b, c),
        });
        shapes.push(Shape::Cylinder {
            base: centre,
            radius: a,
            height: b,
        });
        shapes.push(Shape::Torus {
            center: centre,
            major: a.max(c),
            minor: a.min(c) * 0.6,
        });
    }
    // The extremes of proportion: a pancake and a needle, a needle and a band, a thin ring and
    // a torus whose hole has nearly closed.
    let centre = unit(rng) * offset;
    let thin = 1e-3 * size;
    shapes.extend([
        Shape::Ellipsoid {
            center: centre,
            radii: Vec3::new(size, thin, size),
        },
        Shape::Ellipsoid {
            center: centre,
            radii: Vec3::new(thin, size, thin),
        },
        Shape::Cylinder {
            base: centre,
            radius: thin,
            height: size,
        },
        Shape::Cylinder {
            base: centre,
            radius: size,
            height: thin,
        },
        Shape::Torus {
            center: centre,
            major: size,
            minor: thin,
        },
        Shape::Torus {
            center: centre,
            major: size,
            minor: 0.99 * size,
        },
    ]);
    shapes
        .into_iter()
        .flat_map(|shape| {
            let turn = Quat::from_axis_angle(unit(rng), std::f32::consts::TAU * rng.next_f32());
            [Quat::IDENTITY, turn].map(|orientation| Turned { shape, orientation })
        })
        .collect()
}

/// Rays from 1.2 to 20 half-diagonals away, aimed at random points of the shape's box.
fn rays_at(rng: &mut Rng, shape: &Turned, count: usize) -> Vec<RayQuery> {
    let (centre, half) = shape.extent();
    (0..count)
        .map(|_| {
            let origin = centre + unit(rng) * half * (1.2 + 18.8 * rng.next_f32());
            let target = centre + unit(rng) * half * rng.next_f32();
            RayQuery::new(origin, (target - origin).normalize())
        })
        .collect()
}

const REGIMES: [(f32, f32); 4] = [(1.0, 0.0), (1.0e-3, 1.0), (1.0, 100.0), (1.0e4, 1.0e5)];

/// The f32 hit is the first f64 crossing (to 1e-4 of the shape's size), misses are misses,
/// except for rays within 1e-3 of grazing, and every shading point lies on the true surface
/// within its own error bound.
#[test]
fn curved_hits_match_double_precision_at_every_scale() {
    let mut rng = Rng::new(21, 0, 0);
    for (size, offset) in REGIMES {
        let (mut hits, mut disagreements) = (0, Vec::new());
        for shape in shapes(&mut rng, size, offset) {
            let half = shape.extent().1;
            for ray in rays_at(&mut rng, &shape, 300) {
                let hit = shape.intersect(&ray);
                let origin = ray.origin.as_dvec3();
                let direction = ray.direction.as_dvec3().normalize();
                let truth = shape
                    .crossings(origin, direction)
                    .into_iter()
                    .find(|&t| t > 0.0);
                match (hit.t < T_FAR, truth) {
                    (true, Some(t)) => {
                        hits += 1;
                        if (hit.t as f64 - t).abs() > 1e-4 * half as f64 {
                            disagreements.push(format!("{shape:?}: t {} against {t}", hit.t));
                        }
                        let (point, outward) = shape.surface_point(&ray, hit.t);
                        let off = shape.distance(point.position.as_dvec3());
                        let bound = outward.abs().dot(point.error) as f64;
                        assert!(
                            off <= bound,
                            "{shape:?}: point {} is {off:e} off the surface, bound {bound:e}",
                            point.position
                        );
                    }
                    (false, None) => {}
                    (found, truth) => {
                        // Grazing: the ray passes within 1e-3 of the size of tangency.
                        let near = |t: f64| shape.distance(origin + t * direction);
                        let t = truth.unwrap_or(hit.t as f64);
                        if near(t) > 1e-3 * half as f64 || found {
                            disagreements.push(format!(
                                "{shape:?}: found {found}, truth {truth:?}, ray {ray:?}"
                            ));
                        }
                    }
                }
            }
        }
        eprintln!("size {size}, offset {offset}: {hits} hits, {disagreements:?}");
        assert!(hits > 1000, "size {size}: only {hits} hits");
        assert!(
            disagreements.len() <= hits / 1000,
            "size {size}, offset {offset}: {} disagreements: {:?}",
            disagreements.len(),
            &disagreements[..disagreements.len().min(5)]
        );
    }
}

/// pbrt-v4's Reintersect test for curved surfaces: from each hit, rays leaving the offset
/// origin to the side they came from meet the surface again only where double precision says
/// they cross it (a torus's other side, the inside of a cylinder), never at the point they
/// leave.
#[test]
fn rays_leaving_curved_surfaces_meet_them_again_only_where_they_cross_them() {
    let mut rng = Rng::new(22, 0, 0);
    for (size, offset) in REGIMES {
        let (mut leaving, mut again) = (0, 0);
        for shape in shapes(&mut rng, size, offset) {
            let half = shape.extent().1 as f64;
            for ray in rays_at(&mut rng, &shape, 60) {
                let hit = shape.intersect(&ray);
                if hit.t == T_FAR {
                    continue;
                }
                let (point, outward) = shape.surface_point(&ray, hit.t);
                let side = if outward.dot(ray.direction) < 0.0 {
                    outward
                } else {
                    -outward
                };
                let start = offset_ray_origin(point.position, point.error, side);
                for _ in 0..16 {
                    let d = unit(&mut rng);
                    let d = if d.dot(side) < 0.0 { -d } else { d };
                    leaving += 1;
                    let rehit = shape.intersect(&RayQuery::new(start, d));
                    if rehit.t == T_FAR {
                        continue;
                    }
                    again += 1;
                    let crossings = shape.crossings(start.as_dvec3(), d.as_dvec3().normalize());
                    let t = rehit.t as f64;
                    assert!(
                        crossings.iter().any(|&c| (c - t).abs() <= 1e-4 * half),
                        "{shape:?}: a ray leaving {} met the surface at t {t:e}; it crosses at {crossings:?}",
                        point.position
                    );
                }
            }
        }
        eprintln!(
            "size {size}, offset {offset}: {again} of {leaving} leaving rays met the surface again, each where it truly does"
        );
        assert!(leaving > 3000);
    }
}

/// Every feature of a scene of curved shapes, two of them turned (`rotate`), renders the same
/// on the GPU's kernels and the CPU: closest and any hit, BVH2 and compressed wide BVH.
#[test]
fn gpu_kernels_find_the_cpus_curved_hits() {
    let text = r#"
        [render]
        width = 12
        height = 8
        [camera]
        position = [0.0, 2.0, 6.0]
        look_at = [0.0, 0.3, 0.0]
        [[materials]]
        name = "grey"
        model = "lambert"
        diffuse = [0.5, 0.5, 0.5]
        [[shapes]]
        type = "torus"
        center = [-1.5, 0.3, 0.0]
        major_radius = 0.8
        minor_radius = 0.25
        rotate = [35.0, 0.0, 20.0]
        material = "grey"
        [[shapes]]
        type = "ellipsoid"
        center = [1.2, 0.6, 0.3]
        radii = [0.5, 0.8, 0.3]
        material = "grey"
        [[shapes]]
        type = "cylinder"
        center = [0.2, -0.5, -1.0]
        radius = 0.6
        height = 1.5
        rotate = [0.0, 10.0, 70.0]
        material = "grey"
    "#;
    let scene = Scene::from_str(std::path::Path::new("curved.toml"), text, &[]).unwrap();
    let flat = flatten(&scene);
    assert_eq!(flat.prims.len(), 3);
    let camera = Pinhole {
        position: [0.0, 2.0, 6.0],
        look_at: [0.0, 0.3, 0.0],
        up: [0.0, 1.0, 0.0],
        vertical_fov_deg: 40.0,
        width: 96,
        height: 64,
    };
    let (lo, hi) = bounds(&flat);
    let absolute = 1e-6 * (hi - lo).max_element();
    let cw = cwbvh::build(flat.primitives()).unwrap();
    let context = common::gpu_context().expect("GPU");
    for (set, rays) in [
        ("coherent", coherent_rays(&camera, 1, 3)),
        ("incoherent", incoherent_rays(lo, hi, 4096, 3)),
    ] {
        for query in [Query::ClosestHit, Query::AnyHit] {
            let cpu = trace_cpu(&flat, Bvh::Bvh2, &rays, query).unwrap();
            let hits = cpu.iter().filter(|&&t| t < T_FAR).count();
            assert!(
                hits > rays.len() / 10 && hits < rays.len(),
                "{set}: {hits} hits"
            );
            for wide in [None, Some(&cw)] {
                let tracer = GpuTracer::new(context.clone(), &flat, wide, &rays).unwrap();
                tracer.trace(query).unwrap();
                let gpu = tracer.distances().unwrap();
                let differ: Vec<_> = cpu
                    .iter()
                    .zip(&gpu)
                    .filter(|&(&c, &g)| {
                        (c < T_FAR) != (g < T_FAR) || (c - g).abs() > 1e-5 * c.abs() + absolute
                    })
                    .collect();
                eprintln!(
                    "{set} {query:?} cwbvh {}: {hits} hits, {} differ",
                    wide.is_some(),
                    differ.len()
                );
                // A ray grazing a surface may round to the other side where the GPU fuses
                // multiply-adds; lavapipe rounds as the CPU does.
                assert!(
                    differ.len() <= rays.len() / 1000,
                    "{set} {query:?}: {:?}",
                    &differ[..differ.len().min(5)]
                );
            }
        }
    }
}

/// A point on the inside of a sphere or an ellipsoid, lit by a light outside it, is shadowed by
/// the shape itself (its shadow ray leaves through the shape), on both paths; with the light
/// inside, the same points are lit. Rays leaving a convex shape's outside may skip it, rays
/// leaving its inside may not (`layout::leaving_rays_skip`).
#[test]
fn the_inside_of_a_convex_shape_is_shadowed_by_the_shape_itself() {
    for shape in [
        "type = \"sphere\"\n center = [0.0, 0.0, 0.0]\n radius = 5.0",
        "type = \"ellipsoid\"\n center = [0.0, 0.0, 0.0]\n radii = [5.0, 4.0, 6.0]",
    ] {
        for (light, lit) in [("[0.0, 0.0, 20.0]", false), ("[0.0, 0.0, 2.0]", true)] {
            let text = format!(
                r#"
                [render]
                width = 12
                height = 8
                spp = 1
                [camera]
                position = [0.0, 0.0, 0.0]
                look_at = [0.0, 0.0, -1.0]
                [[materials]]
                name = "grey"
                model = "lambert"
                diffuse = [0.5, 0.5, 0.5]
                [[shapes]]
                {shape}
                material = "grey"
                [[lights]]
                type = "point"
                position = {light}
                intensity = [50.0, 50.0, 50.0]
                "#
            );
            let scene = Scene::from_str(std::path::Path::new("inside.toml"), &text, &[]).unwrap();
            let flat = flatten(&scene);
            let gpu = common::render_gpu(&flat).expect("GPU");
            for (path, image) in [("CPU", common::render_cpu(&flat)), ("GPU", gpu)] {
                let brightest = image
                    .pixels
                    .iter()
                    .map(|p| p.max_element())
                    .fold(0.0, f32::max);
                eprintln!("{shape:?}, light at {light}, {path}: brightest pixel {brightest}");
                assert_eq!(brightest > 0.0, lit, "{shape}, light at {light}, {path}");
            }
        }
    }
}
