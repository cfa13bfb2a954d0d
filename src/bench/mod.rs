//! The benchmarks behind `BENCHMARKS.md`, each a report as a Markdown table and as JSON
//! (`chambre bench`; its arguments are the binary's).
//!
//! - [`rays`]: a mesh and a pinhole camera; coherent camera rays and incoherent rays, closest
//!   hit and any hit, Mrays/s with a checksum (hits, sum of hit distances) that another ray
//!   tracer can reproduce on the same rays.
//! - [`build`]: every obvhs build preset on a mesh: time, nodes, depth, SAH cost, memory.
//! - [`frame`]: the sample scenes on each backend, and the GPU kernel specialised to the scene
//!   against the general one.
//! - [`samplers`]: the lens sample patterns' error against samples and time.
//! - [`scale`]: the same rays on meshes from a thousand to ten million triangles.
//! - [`precision`]: f32 hits and pixels of both paths against an f64 oracle.
//! - [`motion`]: motion blur's BVH, swept over the shutter or per time slice.
//! - [`adaptive`]: adaptive sampling against uniform sampling at equal samples and equal time,
//!   on scene files and held-out scenes generated from a seed.
//!
//! Timings are medians (with min and max) of several runs after a warm-up, measured side by side
//! in one process: machines here are noisy, so only ratios within one run are compared.

pub mod adaptive;
pub mod build;
pub mod fermat;
pub mod frame;
pub mod motion;
pub mod precision;
pub mod preview;
pub mod rays;
pub mod samplers;
pub mod scale;

use std::path::{Path, PathBuf};

use serde::Serialize;

use crate::error::{Error, Result};
use crate::gpu::GpuContext;

/// The sample scene named `name`: its file in `scenes/`.
pub fn sample_scene(name: &str) -> PathBuf {
    PathBuf::from("scenes").join(format!("{name}.toml"))
}

/// A benchmark's report with where it ran, as written to JSON.
#[derive(Debug, Serialize)]
pub struct Report<'a, T: Serialize> {
    /// The command line that ran the benchmark.
    pub command: &'a str,
    /// Where and when it ran.
    pub machine: &'a Machine,
    /// The benchmark's own report.
    pub report: &'a T,
}

/// The Markdown report with its header line; the JSON one written to `json` when given.
pub fn finish<T: Serialize>(
    command: &str,
    machine: &Machine,
    markdown: String,
    report: &T,
    json: Option<&Path>,
) -> Result<String> {
    let text = format!("{}\n{markdown}", machine.to_markdown(command));
    if let Some(path) = json {
        write_json(
            path,
            &Report {
                command,
                machine,
                report,
            },
        )?;
    }
    Ok(text)
}

/// The benchmark's GPU context, or why there is none (a benchmark asked to measure the GPU
/// fails without one).
pub fn usable(context: &Result<GpuContext>) -> Result<&GpuContext> {
    context.as_ref().map_err(|e| match e {
        Error::NoAdapter(why) => Error::NoAdapter(why.clone()),
        other => Error::NoAdapter(other.to_string()),
    })
}

fn write_json<T: Serialize>(path: &std::path::Path, value: &T) -> Result<()> {
    let text = serde_json::to_string_pretty(value).map_err(|e| Error::Output {
        path: path.to_path_buf(),
        message: e.to_string(),
    })?;
    std::fs::write(path, text + "\n").map_err(|e| Error::io(path, e))
}

/// Median, minimum and maximum of repeated measurements.
#[derive(Clone, Copy, Debug, PartialEq, Serialize)]
pub struct Spread {
    /// Median (the upper one of an even count).
    pub median: f64,
    /// Smallest measurement.
    pub min: f64,
    /// Largest measurement.
    pub max: f64,
}

impl Spread {
    /// The spread of `samples` (at least one).
    pub fn of(samples: &[f64]) -> Spread {
        assert!(!samples.is_empty(), "a spread of no measurement");
        let mut sorted = samples.to_vec();
        sorted.sort_by(f64::total_cmp);
        Spread {
            median: sorted[sorted.len() / 2],
            min: sorted[0],
            max: sorted[sorted.len() - 1],
        }
    }
}

/// Where and when a benchmark ran: what a figure needs to be compared with another.
#[derive(Clone, Debug, Serialize)]
pub struct Machine {
    /// The crate version that ran.
    pub chambre_version: String,
    /// Date of the run (UTC), YYYY-MM-DD.
    pub date_utc: String,
    /// Threads of the CPU path (rayon's pool).
    pub cpu_threads: usize,
    /// The GPU adapter, or why there is none.
    pub adapter: String,
}

impl Machine {
    /// One line for a report: the command and where and when it ran.
    pub fn to_markdown(&self, command: &str) -> String {
        format!(
            "`{command}` — chambre {}, {}, {} CPU threads, adapter: {}\n",
            self.chambre_version, self.date_utc, self.cpu_threads, self.adapter
        )
    }

    /// This machine, now, with the adapter of `gpu` (or why there is none).
    pub fn here(gpu: &Result<GpuContext>) -> Machine {
        Machine {
            chambre_version: env!("CARGO_PKG_VERSION").to_string(),
            date_utc: crate::provenance::utc_date(),
            cpu_threads: rayon::current_num_threads(),
            adapter: match gpu {
                Ok(c) => c.adapter_description.clone(),
                Err(e) => format!("none ({e})"),
            },
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn spread_is_the_median_min_and_max() {
        let s = Spread::of(&[3.0, 1.0, 2.0, 10.0, 4.0]);
        assert_eq!((s.median, s.min, s.max), (3.0, 1.0, 10.0));
    }
}
