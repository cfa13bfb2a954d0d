//! The CPU reference path: the same stages as the GPU kernel, in Rust, on all cores.
//! Twin: `wgsl/render.wgsl` (the per-pixel sample loop and the accumulation).

use rayon::prelude::*;

use crate::accel::FlatScene;
use crate::error::Result;
use crate::integrator::{SampleStats, trace_sample};
use crate::layout::GpuPass;
use crate::render::{Backend, TileStatus};

pub struct CpuRenderer<'a> {
    scene: &'a FlatScene,
    accumulation: Vec<[f32; 4]>,
}

impl<'a> CpuRenderer<'a> {
    pub fn new(scene: &'a FlatScene) -> Self {
        let pixels = scene.frame.width as usize * scene.frame.height as usize;
        CpuRenderer {
            scene,
            accumulation: vec![[0.0; 4]; pixels],
        }
    }
}

impl Backend for CpuRenderer<'_> {
    fn render_tile(&mut self, pass: GpuPass) -> Result<TileStatus> {
        let scene = self.scene;
        let width = scene.frame.width;
        let rows: Vec<(u32, Vec<[f32; 4]>, SampleStats)> = (pass.tile_y
            ..pass.tile_y + pass.tile_height)
            .into_par_iter()
            .map(|y| {
                let mut stats = SampleStats::default();
                let row = (pass.tile_x..pass.tile_x + pass.tile_width)
                    .map(|x| {
                        let mut sum = glam::Vec3::ZERO;
                        for s in 0..pass.sample_count {
                            sum += trace_sample(scene, x, y, pass.sample_start + s, &mut stats);
                        }
                        [sum.x, sum.y, sum.z, pass.sample_count as f32]
                    })
                    .collect();
                (y, row, stats)
            })
            .collect();
        let mut status = TileStatus::default();
        for (y, row, stats) in rows {
            let start = (y * width + pass.tile_x) as usize;
            for (acc, add) in self.accumulation[start..start + row.len()]
                .iter_mut()
                .zip(row)
            {
                for c in 0..4 {
                    acc[c] += add[c];
                }
            }
            status.rays += stats.rays;
            status.truncated += stats.truncated;
            status.flags |= stats.flags;
        }
        Ok(status)
    }

    fn accumulation(&mut self) -> Result<Vec<[f32; 4]>> {
        Ok(self.accumulation.clone())
    }
}
