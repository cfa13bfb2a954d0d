//! Composes the render kernel: generated constants, then the WGSL libraries, then the kernel.
//! Plain concatenation, in dependency order; `tests/wgsl_validate.rs` validates the result.

use crate::layout::wgsl_prelude;

/// (file name, source) of every WGSL module, in composition order.
pub const MODULES: [(&str, &str); 9] = [
    ("types.wgsl", include_str!("../../wgsl/types.wgsl")),
    ("rng.wgsl", include_str!("../../wgsl/rng.wgsl")),
    ("sampling.wgsl", include_str!("../../wgsl/sampling.wgsl")),
    ("camera.wgsl", include_str!("../../wgsl/camera.wgsl")),
    ("intersect.wgsl", include_str!("../../wgsl/intersect.wgsl")),
    ("traverse.wgsl", include_str!("../../wgsl/traverse.wgsl")),
    ("sampler.wgsl", include_str!("../../wgsl/sampler.wgsl")),
    (
        "integrator.wgsl",
        include_str!("../../wgsl/integrator.wgsl"),
    ),
    ("render.wgsl", include_str!("../../wgsl/render.wgsl")),
];

/// The complete kernel source, with a marker comment where each module starts.
pub fn render_kernel_source() -> String {
    let mut source = wgsl_prelude();
    for (name, text) in MODULES {
        source += &format!("\n// ---- {name} ----\n");
        source += text;
    }
    source
}
