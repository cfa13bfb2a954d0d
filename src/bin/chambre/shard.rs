//! Renders in shards: the manifest a shard writes beside its band (`render --shard I/N`), and
//! `chambre merge`, which puts the bands back together.

use std::path::{Path, PathBuf};
use std::process::ExitCode;

use clap::Args;

use anyhow::bail;

use chambre::output::{OutputTarget, Protected, same_path};
use chambre::render::RenderOutput;
use chambre::scene::Scene;
use chambre::shard::{Manifest, Shard};

/// `chambre merge`'s arguments.
#[derive(Args)]
pub struct MergeArgs {
    /// Every shard's manifest (`*.shard-I-of-N.json`).
    #[arg(required = true)]
    pub manifests: Vec<PathBuf>,
    /// The image to write (.png, .exr or .pfm).
    #[arg(short, long)]
    pub output: PathBuf,
    /// Replace the output even where it is a write-protected file (refused otherwise).
    #[arg(long)]
    pub force: bool,
}

/// What a shard's manifest says of its band.
pub fn shard_manifest(
    shard: Shard,
    scene_file: &Path,
    scene: &Scene,
    full_crop: [u32; 4],
    image: &Path,
    overrides: &[String],
    output: &RenderOutput,
) -> Manifest {
    let mut identity = std::fs::read(scene_file).unwrap_or_default();
    for o in overrides {
        identity.extend_from_slice(o.as_bytes());
    }
    let [x0, x1, _, _] = full_crop;
    Manifest {
        shard,
        width: scene.render.width,
        height: scene.render.height,
        band: [x0, x1, scene.render.crop[2], scene.render.crop[3]],
        image: image
            .file_name()
            .map_or(String::new(), |n| n.to_string_lossy().into_owned()),
        render_hash: format!("{:016x}", chambre::provenance::fnv1a64(&identity)),
        spp_min: output.samples_per_pixel,
        spp_max: output.max_samples_per_pixel,
        band_hash: chambre::shard::band_hash(output.image.pixels.iter().map(|p| p.to_array())),
    }
}

/// `chambre merge`: the shards' bands stacked into one image, written atomically.
pub fn run_merge(args: &MergeArgs) -> anyhow::Result<ExitCode> {
    let (manifests, output) = (&args.manifests, &args.output);
    let protected = Protected::replaced_if(args.force);
    let target = OutputTarget::prepare_with(output, protected)?;
    let merged = chambre::shard::merge(manifests)?;
    let image = &merged.image;
    if let Some(input) = merged.inputs.iter().find(|input| same_path(input, output)) {
        bail!(
            "-o {}: is {}, an input of the merge",
            output.display(),
            input.display()
        );
    }
    target.write(image)?;
    note!(
        "{}: {}x{} from {} shards",
        output.display(),
        image.width,
        image.height,
        manifests.len()
    );
    for line in &merged.notes {
        note!("{line}");
    }
    Ok(ExitCode::SUCCESS)
}
