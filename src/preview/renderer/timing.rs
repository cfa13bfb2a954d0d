//! A preview frame's stages (the Fermat solves, their cull, the main pass, the reflection pass)
//! and the time each takes ([`StageTimes`], `PreviewRenderer::stage_times`).

/// The stages of a preview frame, each one or more passes.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub(crate) enum Stage {
    /// The Fermat kernel's solves (`fermat`).
    Solve,
    /// Their cull (`fermat_cull`).
    Cull,
    /// The main pass: the scene and the id target.
    Main,
    /// The reflection pass.
    Reflect,
}

impl Stage {
    /// A frame's stages, in the order it records them.
    pub(crate) const ALL: [Stage; 4] = [Stage::Solve, Stage::Cull, Stage::Main, Stage::Reflect];
}

/// Time of each stage of a preview frame, milliseconds (`PreviewRenderer::stage_times`).
#[derive(Clone, Copy, Debug, Default, PartialEq, serde::Serialize)]
pub struct StageTimes {
    /// The Fermat solves.
    pub solve_ms: f64,
    /// The cull of the reflected triangles.
    pub cull_ms: f64,
    /// The main pass.
    pub main_ms: f64,
    /// The reflection pass.
    pub reflect_ms: f64,
}

impl StageTimes {
    pub(crate) fn add(&mut self, stage: Stage, ms: f64) {
        *match stage {
            Stage::Solve => &mut self.solve_ms,
            Stage::Cull => &mut self.cull_ms,
            Stage::Main => &mut self.main_ms,
            Stage::Reflect => &mut self.reflect_ms,
        } += ms;
    }

    /// Each stage's median over `samples` (not empty).
    pub(crate) fn median(samples: &[StageTimes]) -> StageTimes {
        let of = |f: fn(&StageTimes) -> f64| {
            let mut values: Vec<f64> = samples.iter().map(f).collect();
            values.sort_by(f64::total_cmp);
            values[values.len() / 2]
        };
        StageTimes {
            solve_ms: of(|t| t.solve_ms),
            cull_ms: of(|t| t.cull_ms),
            main_ms: of(|t| t.main_ms),
            reflect_ms: of(|t| t.reflect_ms),
        }
    }
}
