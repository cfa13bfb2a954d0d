//! `chambre export`: a scene written for another renderer (`chambre::export`).

use std::path::PathBuf;
use std::process::ExitCode;

use clap::Args;

use chambre::export::{MitsubaIntegrator, MitsubaOptions, write_mitsuba};
use chambre::output::Protected;

use super::args::named;
use super::{load_and_note, print};

/// `chambre export`: the arguments.
#[derive(Args, Debug, Clone)]
pub struct ExportArgs {
    /// Scene file (TOML or glTF; see docs/scene-format.md).
    pub scene: PathBuf,
    /// Write the scene as Mitsuba 3 XML here (meshes and spot-light profiles as files beside
    /// it, named after it); see docs/mitsuba.md.
    #[arg(long, value_name = "OUT.xml", required = true)]
    pub mitsuba: PathBuf,
    /// What Mitsuba computes: `direct` (chambre's direct light: Mitsuba's `direct`, or its
    /// `path` where mirrors bounce), `depth` (camera rays only), `path` (Mitsuba's path tracer).
    #[arg(long, value_parser = named::<MitsubaIntegrator>(), default_value_t)]
    pub integrator: MitsubaIntegrator,
    /// Write the nearest Mitsuba has where it has no match (ambient light dropped, Phong lobes
    /// dropped, movements and blades left out, ...), listing each change, instead of refusing.
    #[arg(long)]
    pub approximate: bool,
    /// Override any scene field, e.g. --set render.spp=64 (also -D).
    #[arg(long = "set", short = 'D', value_name = "KEY=VALUE")]
    pub set: Vec<String>,
    /// Replace the XML even where it is a write-protected file (refused otherwise).
    #[arg(long)]
    pub force: bool,
}

/// `chambre export`: the scene written for the peer, with what was changed or left out.
pub fn run(args: &ExportArgs) -> anyhow::Result<ExitCode> {
    let scene = load_and_note(&args.scene, &args.set)?;
    let options = MitsubaOptions {
        integrator: args.integrator,
        approximate: args.approximate,
        overrides: args.set.clone(),
        protected: Protected::replaced_if(args.force),
    };
    let export = write_mitsuba(&scene, &args.mitsuba, &options)?;
    for n in &export.notes {
        note!("note: {n}");
    }
    let files = export.files.len();
    print(&format!(
        "{}: Mitsuba 3 scene (integrator `{}`, sampler `{}`), {files} {} beside it\n",
        args.mitsuba.display(),
        export.integrator,
        export.sampler,
        if files == 1 { "file" } else { "files" }
    ))?;
    Ok(ExitCode::SUCCESS)
}
