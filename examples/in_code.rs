//! A scene built in Rust code, rendered on the best backend, written as a PNG:
//! `cargo run --release --example in_code -- out.png`

use chambre::output::OutputTarget;
use chambre::scene::SceneBuilder;

fn main() -> Result<(), Box<dyn std::error::Error>> {
    let path = std::env::args()
        .nth(1)
        .unwrap_or_else(|| "in_code.png".into());
    let scene = SceneBuilder::new(320, 240)
        .spp(16)
        .pinhole([0.0, 1.2, 4.0], [0.0, 0.6, 0.0], 40.0)
        .lambert("floor", [0.7, 0.7, 0.7])
        .blinn_phong("red", [0.6, 0.1, 0.1], [0.3, 0.3, 0.3], 64.0)
        .mirror("chrome", [0.9, 0.9, 0.9])
        .plane([0.0, 0.0, 0.0], [0.0, 1.0, 0.0], "floor")
        .sphere([-0.6, 0.5, 0.0], 0.5, "red")
        .sphere([0.6, 0.5, -0.3], 0.5, "chrome")
        .point_light([2.0, 4.0, 3.0], [40.0, 40.0, 40.0])
        .ambient([0.05, 0.05, 0.05])
        .build()?;
    // Checked before the render, written atomically after it.
    let target = OutputTarget::prepare(path.as_ref())?;
    let (output, backend) = chambre::render_best(&scene)?;
    target.write(&output.image)?;
    println!(
        "{path}: {}x{} at {} spp in {:.2} s on {backend}",
        output.image.width,
        output.image.height,
        output.samples_per_pixel,
        output.elapsed.as_secs_f64()
    );
    Ok(())
}
