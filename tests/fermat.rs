//! The Fermat solver on a sphere: where it converged to the side E and V see, the law of
//! reflection holds to 1e-4 rad and the point is Alhazen's (solved independently in f64). Within
//! the seed's 5 steps it does so for 82% of random configurations (the issue asks 99%: not yet;
//! the rest are printed with where they are), a floor this test keeps.

use chambre::fermat::{
    Reflector, Solver, Sphere, alhazen_sphere, reflection_error, seen_from_outside,
};
use chambre::math::rng::Rng;
use glam::DVec3;

/// A random direction (uniform on the sphere).
fn direction(rng: &mut Rng) -> DVec3 {
    let [a, b] = rng.next_2d();
    let z = 2.0 * a as f64 - 1.0;
    let phi = std::f64::consts::TAU * b as f64;
    let s = (1.0 - z * z).max(0.0).sqrt();
    DVec3::new(s * phi.cos(), z, s * phi.sin())
}

#[test]
fn the_solver_finds_alhazens_point_within_five_steps() {
    let base = Sphere::new(DVec3::new(0.3, -0.2, 0.1), 1.3);
    let solver = Solver::default();
    let (mut converged, mut failures) = (0, Vec::new());
    let trials = 2000;
    let mut rng = Rng::new(11, 0, 0);
    for _ in 0..trials {
        let eye =
            base.center + direction(&mut rng) * base.radius * (2.0 + 4.0 * rng.next_f32() as f64);
        let vertex =
            base.center + direction(&mut rng) * base.radius * (1.2 + 3.0 * rng.next_f32() as f64);
        let (e, v) = (eye - base.center, vertex - base.center);
        // Beyond 150° apart the reflection grazes the silhouette.
        if e.angle_between(v).to_degrees() > 150.0 {
            continue;
        }
        let sphere = base.facing(eye, vertex);
        let solution = solver.solve(&sphere, eye, vertex);
        let p = sphere.point(solution.uv);
        let error = reflection_error(p, sphere.normal(solution.uv), eye, vertex);
        let exact = alhazen_sphere(&sphere, eye, vertex);
        let visible = seen_from_outside(p, sphere.normal(solution.uv), eye, vertex);
        if error < 1e-4 && visible {
            converged += 1;
            assert!(
                (p - exact).length() < 1e-4 * sphere.radius,
                "converged to {p}, Alhazen's point is {exact}"
            );
        } else {
            let polar = (p - sphere.center).normalize().y.abs();
            failures.push((error, visible, polar, e.angle_between(v).to_degrees()));
        }
    }
    let total = converged + failures.len();
    eprintln!(
        "{converged} of {total} converged within 5 steps; failures (error rad, on the side seen, \
         |cos| to the poles' axis, angle E-O-V in degrees): {failures:?}"
    );
    assert!(total > 1500, "{total} configurations kept");
    assert!(
        converged as f64 >= 0.8 * total as f64,
        "{converged} of {total}"
    );
}

#[test]
fn alhazens_point_obeys_the_law_of_reflection() {
    let sphere = Sphere::new(DVec3::ZERO, 1.0);
    let (eye, vertex) = (DVec3::new(0.0, 0.5, 4.0), DVec3::new(3.0, -1.0, 1.0));
    let p = alhazen_sphere(&sphere, eye, vertex);
    assert!((p.length() - 1.0).abs() < 1e-12);
    assert!(reflection_error(p, p, eye, vertex) < 1e-9);
    // Symmetric case: E and V mirror images through the x axis; P on it.
    let p = alhazen_sphere(
        &sphere,
        DVec3::new(3.0, 1.0, 0.0),
        DVec3::new(3.0, -1.0, 0.0),
    );
    assert!((p - DVec3::X).length() < 1e-12, "{p}");
}
