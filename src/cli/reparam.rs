//! `cliffmap reparam`: reparameterize the stretched cells of a store.

use std::path::PathBuf;

use cliffmap::param::{Objective, ParamOptions};
use cliffmap::pipeline::{ReparamOptions, reparam_store};
use cliffmap::resample::{Fill, Mode, ResampleOptions};

use super::stats::print_summary;

/// Flags of `cliffmap reparam`.
#[derive(clap::Args, Debug)]
pub struct Args {
    /// The store directory (made by `cliffmap build`).
    pub store: PathBuf,
    /// Cells whose ortho Rel_texel is above this get the new parameterization.
    #[arg(long, default_value_t = 1.1, allow_hyphen_values = true)]
    pub threshold: f64,
    /// Energy exponent: 0 = conformal, larger favours area preservation (1 = symmetric Dirichlet).
    #[arg(long, default_value_t = ParamOptions::default().theta)]
    pub theta: f64,
    /// Relaxation stops when a sweep improves the energy by less than this fraction.
    #[arg(long, default_value_t = ParamOptions::default().relax_tolerance)]
    pub relax_tol: f64,
    /// Relaxation sweeps per refinement round at most.
    #[arg(long, default_value_t = ParamOptions::default().max_sweeps)]
    pub max_sweeps: u32,
    /// Global projected-Newton finish (θ = 1): at most this many iterations; 0 disables it.
    #[arg(long, default_value_t = ParamOptions::default().newton_iterations)]
    pub newton_iterations: u32,
    /// The global finish stops when an iteration lowers the excess energy (E − 4) by less than this fraction.
    #[arg(long, default_value_t = ParamOptions::default().newton_tolerance)]
    pub newton_tol: f64,
    /// What the global finish returns: "distortion" (the converged symmetric Dirichlet
    /// minimum, SLIM's objective) or "packed-stretch" (the iterate that resolves the surface
    /// most finely in the square texture).
    #[arg(long, default_value = "distortion", value_parser = ["distortion", "packed-stretch"])]
    pub objective: String,
    /// Gutter around the chart in texels.
    #[arg(long, default_value_t = ParamOptions::default().gutter_texels)]
    pub gutter: f64,
    /// Give reparameterized cells textures of twice the side (mixed-resolution mode).
    #[arg(long)]
    pub mixed_resolution: bool,
    /// Resampling filter: "subtexel:N" (N x N subtexels), "bilinear" or "exact".
    #[arg(long, default_value = "subtexel:4", value_parser = parse_mode)]
    pub resample: Mode,
    /// Fill of texels outside the chart: average border colour, or pull-push.
    #[arg(long, default_value = "average-border", value_parser = ["average-border", "pull-push"])]
    pub fill: String,
    /// PNG compression of the textures written: fast (fdeflate, the default), balanced or
    /// best. Same pixels; balanced files are ~0.77× the size of fast ones at ~1/18 the
    /// encoding speed (docs/performance.md, "PNG encoding").
    #[arg(long, value_enum, default_value = "fast")]
    pub png_compression: super::values::PngCompressionArg,
    /// No progress bars or summary.
    #[arg(long)]
    pub quiet: bool,
}

fn parse_mode(s: &str) -> Result<Mode, String> {
    match s {
        "bilinear" => Ok(Mode::Bilinear),
        "exact" => Ok(Mode::Exact),
        _ => s
            .strip_prefix("subtexel:")
            .and_then(|n| n.parse::<u32>().ok())
            .filter(|n| (1..=64).contains(n))
            .map(Mode::Subtexel)
            .ok_or_else(|| {
                format!("expected subtexel:N (N in 1..=64), bilinear or exact, got {s:?}")
            }),
    }
}

/// The library options these flags describe.
pub fn options(a: &Args) -> ReparamOptions {
    ReparamOptions {
        threshold: a.threshold,
        param: ParamOptions {
            theta: a.theta,
            relax_tolerance: a.relax_tol,
            max_sweeps: a.max_sweeps,
            gutter_texels: a.gutter,
            newton_iterations: a.newton_iterations,
            newton_tolerance: a.newton_tol,
            objective: if a.objective == "distortion" {
                Objective::Distortion
            } else {
                Objective::PackedStretch
            },
            ..ParamOptions::default()
        },
        mixed_resolution: a.mixed_resolution,
        resample: ResampleOptions {
            mode: a.resample,
            fill: if a.fill == "pull-push" {
                Fill::PullPush
            } else {
                Fill::AverageBorder
            },
            ..ResampleOptions::default()
        },
        png_compression: a.png_compression.into(),
        progress: super::progress::progress_sink(a.quiet),
    }
}

/// Runs `reparam`.
pub fn run(a: Args) -> anyhow::Result<()> {
    let store = reparam_store(&a.store, &options(&a))?;
    if !a.quiet {
        let n = store
            .manifest
            .cells
            .iter()
            .filter(|c| c.reparam.is_some())
            .count();
        println!(
            "reparameterized {n} of {} cells (threshold {})",
            store.manifest.cells.len(),
            a.threshold
        );
        print_summary(&a.store, &store.manifest, a.threshold)?;
    }
    Ok(())
}
