//! chambre: a GPU ray tracer built around the optics of the view camera.
//!
//! The data flows through stages named after what they do; each WGSL stage has a Rust twin
//! that the CPU reference path runs and the tests compare against:
//!
//! ```text
//! scene.toml --scene::load--> Scene --pack::flatten--> FlatScene (accel: obvhs BVH; layout::Gpu*)
//!     |-- gpu::GpuRenderer  (wgsl/*.wgsl, wgpu compute) --|
//!     |-- cpu::CpuRenderer  (integrator.rs, camera.rs...) --+--> render::Image --> output
//! ```
//!
//! | stage                | Rust (CPU reference)        | WGSL (GPU)             |
//! |----------------------|-----------------------------|------------------------|
//! | random numbers       | `math/rng.rs`               | `wgsl/rng.wgsl`        |
//! | sample warping       | `math/sampling.rs`          | `wgsl/sampling.wgsl`   |
//! | pixel & lens samples | `sampler.rs`                | `wgsl/sampler.wgsl`    |
//! | primary rays         | `camera/mod.rs`             | `wgsl/camera.wgsl`     |
//! | intersection         | `accel/intersect.rs`        | `wgsl/intersect.wgsl`  |
//! | BVH traversal        | `accel/traverse.rs` (obvhs) | `wgsl/traverse.wgsl`   |
//! | shading, shadows, mirrors | `integrator.rs`        | `wgsl/integrator.wgsl` |
//! | pixel loop           | `cpu.rs`                    | `wgsl/render.wgsl`     |
//! | bindings             | `gpu/kernels.rs` (table)    | `wgsl/bindings.wgsl`   |
//!
//! Kernels are listed in `gpu/kernels.rs` (modules, entry point, bindings) and built by its one
//! pipeline builder, specialised to the scene's features (`layout::FEATURES`).

pub mod accel;
pub mod bench;
pub mod camera;
pub mod cpu;
pub mod error;
pub mod gpu;
pub mod integrator;
pub mod layout;
pub mod math;
pub mod output;
pub mod pack;
pub mod provenance;
pub mod render;
pub mod sampler;
pub mod scene;

pub use error::{Error, Result};
