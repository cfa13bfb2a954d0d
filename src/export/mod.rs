//! Scenes written for other renderers: scene.toml --scene::load--> Scene --export--> a peer's
//! scene file. `mitsuba`: Mitsuba 3 XML, with meshes as PLY files beside it (`chambre export
//! --mitsuba`). What a peer cannot express is refused by name, placed in the scene file, unless
//! the caller asks for the nearest it has (`approximate`), which is then listed. The mapping and
//! its reasons: `docs/mitsuba.md`.

mod files;
pub mod mitsuba;

use std::path::PathBuf;

pub use mitsuba::{MitsubaExport, MitsubaIntegrator, MitsubaOptions, to_mitsuba, write_mitsuba};

/// `chambre export`: the arguments.
#[derive(clap::Args, Debug, Clone)]
pub struct ExportArgs {
    /// Scene file (TOML or glTF; see docs/scene-format.md).
    pub scene: PathBuf,
    /// Write the scene as Mitsuba 3 XML here (meshes and spot-light profiles as files beside
    /// it, named after it); see docs/mitsuba.md.
    #[arg(long, value_name = "OUT.xml", required = true)]
    pub mitsuba: PathBuf,
    /// What Mitsuba computes: `direct` (chambre's direct light: Mitsuba's `direct`, or its
    /// `path` where mirrors bounce), `depth` (camera rays only), `path` (Mitsuba's path tracer).
    #[arg(long, value_enum, default_value_t)]
    pub integrator: MitsubaIntegrator,
    /// Write the nearest Mitsuba has where it has no match (ambient light dropped, Phong lobes
    /// dropped, movements and blades left out, ...), listing each change, instead of refusing.
    #[arg(long)]
    pub approximate: bool,
    /// Override any scene field, e.g. --set render.spp=64 (also -D).
    #[arg(long = "set", short = 'D', value_name = "KEY=VALUE")]
    pub set: Vec<String>,
}

/// `chambre export` on `scene` (loaded from `args.scene` with `args.set`): writes the files
/// `args` asks for.
pub fn run(scene: &crate::scene::Scene, args: &ExportArgs) -> crate::Result<MitsubaExport> {
    let options = MitsubaOptions {
        integrator: args.integrator,
        approximate: args.approximate,
        overrides: args.set.clone(),
    };
    write_mitsuba(scene, &args.mitsuba, &options)
}
