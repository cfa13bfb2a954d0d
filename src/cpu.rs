//! The CPU reference path: the same stages as the GPU kernel, in Rust, on all cores.
//! Twin: `wgsl/render.wgsl` (the per-pixel sample loop, the scratch sum of a pass split into
//! light windows, and the accumulation).

use std::sync::atomic::{AtomicBool, Ordering};

use glam::Vec3;
use rayon::prelude::*;

use crate::accel::FlatScene;
use crate::error::Result;
use crate::integrator::{LightWindow, SampleStats, trace_sample};
use crate::layout::GpuPass;
use crate::render::{Backend, TileStatus};

pub struct CpuRenderer<'a> {
    scene: &'a FlatScene,
    accumulation: Vec<[f32; 4]>,
    /// Sums of a pass whose light windows are not all done (allocated on first use).
    scratch: Vec<Vec3>,
    cancel: Option<&'a AtomicBool>,
}

impl<'a> CpuRenderer<'a> {
    pub fn new(scene: &'a FlatScene) -> Self {
        let pixels = scene.frame.width as usize * scene.frame.height as usize;
        CpuRenderer {
            scene,
            accumulation: vec![[0.0; 4]; pixels],
            scratch: Vec::new(),
            cancel: None,
        }
    }

    /// Rows not yet started when `cancel` is set are skipped, so a stop takes effect within a
    /// row, not a whole tile (one tile can take minutes with many light samples). A skipped
    /// row adds nothing, not even to its pixels' sample counts, so every pixel stays a mean.
    pub fn with_cancel(mut self, cancel: &'a AtomicBool) -> Self {
        self.cancel = Some(cancel);
        self
    }

    fn cancelled(&self) -> bool {
        self.cancel.is_some_and(|c| c.load(Ordering::Relaxed))
    }
}

impl Backend for CpuRenderer<'_> {
    fn render_tile(&mut self, pass: GpuPass) -> Result<TileStatus> {
        let scene = self.scene;
        let width = scene.frame.width;
        let window = LightWindow::of_pass(&pass);
        let rows: Vec<(u32, Vec<Vec3>, SampleStats)> = (pass.tile_y
            ..pass.tile_y + pass.tile_height)
            .into_par_iter()
            .filter(|_| !self.cancelled())
            .map(|y| {
                let mut stats = SampleStats::default();
                let row = (pass.tile_x..pass.tile_x + pass.tile_width)
                    .map(|x| {
                        let mut sum = Vec3::ZERO;
                        for s in 0..pass.sample_count {
                            let sample = pass.sample_start + s;
                            sum += trace_sample(scene, x, y, sample, window, &mut stats);
                        }
                        sum
                    })
                    .collect();
                (y, row, stats)
            })
            .collect();
        if pass.commit == 0 && self.scratch.is_empty() {
            self.scratch = vec![Vec3::ZERO; self.accumulation.len()];
        }
        let mut status = TileStatus::default();
        for (y, row, stats) in rows {
            let start = (y * width + pass.tile_x) as usize;
            for (i, mut sum) in row.into_iter().enumerate() {
                let pixel = start + i;
                if !window.is_first() {
                    sum += self.scratch[pixel];
                }
                if pass.commit != 0 {
                    let acc = &mut self.accumulation[pixel];
                    let add = [sum.x, sum.y, sum.z, pass.sample_count as f32];
                    for c in 0..4 {
                        acc[c] += add[c];
                    }
                } else {
                    self.scratch[pixel] = sum;
                }
            }
            status.rays += stats.rays;
            status.truncated += stats.truncated;
            status.flags |= stats.flags;
        }
        Ok(status)
    }

    /// Moves the accumulation out (it is read once, at the end): a copy of a 16384^2 image
    /// would cost 4 GiB and seconds after a Ctrl-C.
    fn accumulation(&mut self) -> Result<Vec<[f32; 4]>> {
        Ok(std::mem::take(&mut self.accumulation))
    }
}
