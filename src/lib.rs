#![warn(missing_docs)]
//! chambre: a GPU ray tracer built around the optics of the view camera.
//!
//! The data flows through stages named after what they do; each WGSL stage has a Rust twin
//! that the CPU reference path runs and the tests compare against:
//!
//! ```text
//! scene.toml --scene::load--> Scene --pack::flatten--> FlatScene (accel: obvhs BVH; layout::Gpu*)
//!     |-- gpu::GpuRenderer  (wgsl/*.wgsl, wgpu compute) --|
//!     |-- cpu::CpuRenderer  (integrator, accel) ------------+--> render::Image --> output
//! Scene --export::mitsuba--> Mitsuba 3 XML (+ PLY meshes), to render the same scene with a peer
//! ```
//!
//! Every WGSL file's Rust twin, each traversal's role (renders, reference, fallback,
//! benchmark), the modules in the order the data flows through them and where a new shape,
//! light, material, kernel or benchmark goes: `docs/architecture.md` (its tables are tested).
//!
//! Kernels are listed in `gpu/kernels.rs` (modules, entry point, bindings) and built by its one
//! pipeline builder, specialised to the scene's features (`layout::FEATURES`).

pub mod accel;
pub mod adaptive;
pub mod bench;
pub mod camera;
pub mod converge;
pub mod cpu;
pub mod error;
pub mod export;
pub mod gpu;
pub mod integrator;
pub mod layout;
pub mod math;
pub mod metrics;
pub mod named;
pub mod output;
pub mod pack;
pub mod plot;
pub mod preview;
pub mod provenance;
pub mod render;
pub mod sampler;
pub mod scene;
pub mod shard;

pub use error::{Error, Result};

/// Renders `scene` on the best backend, as `chambre render --backend auto` does: a real GPU
/// when there is one and it accepts the scene, else the CPU path (which is faster than a CPU
/// implementation of the GPU API such as lavapipe). Returns the output and the backend used.
pub fn render_best(scene: &scene::Scene) -> Result<(render::RenderOutput, String)> {
    use std::sync::atomic::AtomicBool;
    let flat = pack::flatten(scene);
    let cancel = AtomicBool::new(false);
    let gpu = gpu::GpuContext::new()
        .ok()
        .filter(|context| !context.is_cpu_adapter)
        .and_then(|context| gpu::GpuRenderer::new(context, &flat).ok());
    match gpu {
        Some(mut renderer) => {
            let name = format!("GPU: {}", renderer.adapter_description());
            Ok((
                render::render(&flat, &mut renderer, &mut |_, _| {}, &cancel)?,
                name,
            ))
        }
        None => {
            let mut renderer = cpu::CpuRenderer::new(&flat);
            let output = render::render(&flat, &mut renderer, &mut |_, _| {}, &cancel)?;
            Ok((output, "CPU".to_string()))
        }
    }
}
