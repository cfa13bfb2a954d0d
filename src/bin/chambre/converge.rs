//! `chambre converge`: the speed–accuracy trade of a scene measured (`chambre::converge`), its
//! CSV and plots written.

use std::path::PathBuf;
use std::process::ExitCode;

use chambre::bench::rays::Backend;
use chambre::converge::ConvergeSettings;
use chambre::output::{OutputTarget, Protected};
use chambre::sampler::SamplerName;

use super::args::{at_least_one, named, positive};
use super::print;

/// Measure how a scene's error against a reference falls with samples per pixel and with time,
/// for each sample pattern and backend.
#[derive(Debug, clap::Args)]
pub struct ConvergeArgs {
    /// Scene file (TOML; see docs/scene-format.md).
    pub scene: PathBuf,
    /// Reference image: a linear EXR of the scene's size (default: rendered on the CPU path at
    /// --reference-spp with Sobol patterns and another seed).
    #[arg(long)]
    pub reference: Option<PathBuf>,
    /// Samples per pixel of the rendered reference.
    #[arg(long, value_parser = positive(), default_value_t = 1024)]
    pub reference_spp: u32,
    /// The largest sample count: runs at 1, 2, 4, … up to it.
    #[arg(long, value_parser = positive(), default_value_t = 64)]
    pub max_spp: u32,
    /// Sample patterns to compare, each used for the pixel and the lens samples.
    #[arg(long, value_parser = named::<SamplerName>(), value_delimiter = ',',
          default_values_t = [SamplerName::Random, SamplerName::Stratified, SamplerName::Sobol])]
    pub samplers: Vec<SamplerName>,
    /// Also render adaptively (`--noise-target`) at each of these targets, with --max-spp as
    /// the most samples a pixel takes: one more curve per pattern and backend, and a table of
    /// the time uniform sampling needs for the same RMSE.
    #[arg(long, value_delimiter = ',', value_name = "X,Y,...")]
    pub noise_targets: Vec<f64>,
    /// The adaptive renders' `render.min_spp` (default: the scene's, or 16).
    #[arg(long, value_name = "N")]
    pub min_spp: Option<u32>,
    /// Renders of each run: its times are their medians (the images are the same).
    #[arg(long, value_parser = at_least_one, default_value_t = 1)]
    pub runs: usize,
    /// Backends to measure, side by side.
    #[arg(long, value_parser = named::<Backend>(), value_delimiter = ',', default_values_t = [Backend::Cpu])]
    pub backends: Vec<Backend>,
    /// The CSV to write: one row per run, the command and machine in `#` comments.
    #[arg(long, default_value = "converge.csv")]
    pub csv: PathBuf,
    /// Where to write the log-log plot: SVG, or PNG for a `.png` (repeat for both). Default:
    /// beside the CSV, its name with `.svg`.
    #[arg(long, value_name = "F.svg|F.png", conflicts_with = "no_plot")]
    pub plot: Vec<PathBuf>,
    /// Write the CSV alone, no plot.
    #[arg(long)]
    pub no_plot: bool,
    /// Replace the CSV and the plots even where they are write-protected files (refused
    /// otherwise, before the first render).
    #[arg(long)]
    pub force: bool,
    /// Override any scene field, e.g. --set render.width=200 (also -D).
    #[arg(long = "set", short = 'D', value_name = "KEY=VALUE")]
    pub set: Vec<String>,
}

impl ConvergeArgs {
    /// The plots to write: those `--plot` names, else one beside the CSV (its name with `.svg`,
    /// or `.svg` added when the CSV's own name ends so), none with `--no-plot`.
    pub fn plots(&self) -> Vec<PathBuf> {
        if self.no_plot {
            return Vec::new();
        }
        if !self.plot.is_empty() {
            return self.plot.clone();
        }
        let beside = self.csv.with_extension("svg");
        if beside != self.csv {
            return vec![beside];
        }
        let mut name = self.csv.clone().into_os_string();
        name.push(".svg");
        vec![PathBuf::from(name)]
    }

    /// What the library measures: the arguments but the files written.
    fn settings(&self) -> ConvergeSettings {
        ConvergeSettings {
            scene: self.scene.clone(),
            reference: self.reference.clone(),
            reference_spp: self.reference_spp,
            max_spp: self.max_spp,
            samplers: self.samplers.clone(),
            noise_targets: self.noise_targets.clone(),
            min_spp: self.min_spp,
            runs: self.runs,
            backends: self.backends.clone(),
            set: self.set.clone(),
        }
    }
}

pub fn run(args: &ConvergeArgs) -> anyhow::Result<ExitCode> {
    // Every output is checked before the first render, and written whole or not at all.
    let (plots, protected) = (args.plots(), Protected::replaced_if(args.force));
    OutputTarget::prepare_beside_with(&args.csv, protected)?;
    for plot in &plots {
        OutputTarget::prepare_beside_with(plot, protected)?;
    }
    let study = chambre::converge::run(&args.settings())?;
    let command = std::env::args().collect::<Vec<_>>().join(" ");
    OutputTarget::write_beside(&args.csv, study.to_csv(&command).as_bytes())?;
    for plot in &plots {
        let bytes = chambre::plot::figure_bytes(&study, plot)
            .map_err(|e| anyhow::anyhow!("{}: {e}", plot.display()))?;
        OutputTarget::write_beside(plot, &bytes)?;
    }
    let written: Vec<String> = std::iter::once(&args.csv)
        .chain(&plots)
        .map(|p| p.display().to_string())
        .collect();
    note!("wrote {}", written.join(", "));
    print(&study.to_markdown())?;
    Ok(ExitCode::SUCCESS)
}
