//! `cliffmap demo`: the whole pipeline on the embedded procedural scene.

use std::path::PathBuf;

use cliffmap::demo_scene::{DemoScene, TextureChoice, texel_truth, texel_truth_covered};
use cliffmap::fsutil::write_png_atomic;
use cliffmap::pipeline::{
    BuildInputs, BuildOptions, ProjectOptions, ReparamOptions, build_store, project_store,
    reparam_store,
};

use super::stats::print_summary;

/// Renders the middle camera of the store's default flight to `out` (960x540, lit) and,
/// when the store has photo textures, the same view's photo share (`--overlay photo-share
/// --unlit`) to `share_out`.
fn render_view(
    store: &std::path::Path,
    m: &cliffmap::store::Manifest,
    out: &std::path::Path,
    share_out: &std::path::Path,
) -> anyhow::Result<String> {
    use cliffmap::render::{FlightPath, FrameOptions, Overlay, SceneOptions, StoreRenderer};
    let (w, h) = (960, 540);
    let cams = FlightPath::default_for(m)?.cameras(9, w, h);
    let cam = cams
        .get(4)
        .ok_or_else(|| anyhow::anyhow!("empty default flight"))?;
    let mut scene = StoreRenderer::open(store, w, h, SceneOptions::default())?;
    let r = scene.frame(cam, true)?;
    write_png_atomic(out, &scene.read_rgba()?)?;
    let mut msg = format!(
        "rendered {} ({} cells, {} triangles) on {}",
        out.display(),
        r.drawn,
        r.triangles,
        scene.gpu().describe()
    );
    if m.cells.iter().any(|c| c.photo.is_some()) {
        let opts = SceneOptions {
            overlay: Overlay::PhotoShare,
            frame: FrameOptions {
                lit: false,
                ..Default::default()
            },
            ..SceneOptions::default()
        };
        let mut scene = StoreRenderer::open(store, w, h, opts)?;
        scene.frame(cam, true)?;
        write_png_atomic(share_out, &scene.read_rgba()?)?;
        msg += &format!(
            "; its photo share (yellow photo, blue existing texture, grey no photo) in {}",
            share_out.display()
        );
    }
    Ok(msg)
}

/// Renders the scene's novel views from the store in three texture modes and scores them
/// against the exact truth, the oracle and the baseline: writes DIR/eval.json and the
/// views' images (side-by-side comparisons among them), returns the table of gains.
fn view_stage(
    scene: &DemoScene,
    dem: &cliffmap::Dem,
    ortho: &cliffmap::Ortho,
    photos: &[cliffmap::photo::PhotoInput],
    store: &std::path::Path,
    dir: &std::path::Path,
) -> anyhow::Result<String> {
    use cliffmap::eval::{
        EvalOptions, ReferenceSources, evaluate_views, gains_table, write_view_images,
    };
    let views = scene.novel_views(960, 540);
    let (c, (lo, hi)) = (
        dem.georef
            .world(dem.height as f64 / 2.0, dem.width as f64 / 2.0),
        dem.height_range(),
    );
    let tracer = cliffmap::demo_scene::DemTracer::new(
        dem,
        glam::DVec3::new(c.0, c.1, 0.5 * (lo + hi) as f64),
    )?;
    let src = ReferenceSources {
        scene,
        tracer: &tracer,
        ortho,
        photos,
    };
    let (reports, images) = evaluate_views(store, &src, &views, &EvalOptions::default())?;
    std::fs::create_dir_all(dir)?;
    for v in &images {
        write_view_images(dir, v)?;
    }
    cliffmap::fsutil::write_atomic(
        &dir.join("eval.json"),
        serde_json::to_string_pretty(&reports)?.as_bytes(),
    )?;
    Ok(gains_table(&reports))
}

/// Ray-traces the scene's ground-truth photos, projects them into the store and reports the
/// texel PSNR against the solid texture before and after (written to DIR/truth.json), then
/// the render-space evaluation of novel views (DIR/views/).
fn photo_stage(
    scene: &DemoScene,
    dem: &cliffmap::Dem,
    ortho: &cliffmap::Ortho,
    a: &Args,
    store: &std::path::Path,
) -> anyhow::Result<()> {
    if !(64..=8192).contains(&a.photo_width) {
        anyhow::bail!("--photo-width must be in 64..=8192, got {}", a.photo_width);
    }
    if !(1..=8).contains(&a.photo_supersample) {
        anyhow::bail!(
            "--photo-supersample must be in 1..=8, got {}",
            a.photo_supersample
        );
    }
    let opts = cliffmap::demo_scene::DemoPhotoOptions {
        width: a.photo_width,
        height: a.photo_width / 4 * 3,
        supersample: a.photo_supersample,
    };
    let list = scene.write_demo_photos(dem, &a.out.join("photos"), &opts)?;
    let photos = cliffmap::photo::read_photo_list(&list)?;
    let report = project_store(
        store,
        &photos,
        &ProjectOptions {
            progress: super::progress::progress_sink(a.quiet),
            ..ProjectOptions::default()
        },
    )?;
    let st = cliffmap::store::Store::open(store)?;
    let before = texel_truth(&st, scene, TextureChoice::Active)?;
    let after = texel_truth(&st, scene, TextureChoice::Photo)?;
    let (covered_before, covered_after) = texel_truth_covered(&st, scene)?;
    let json = serde_json::json!({
        "before": before,
        "after": after,
        "photo_covered_before": covered_before,
        "photo_covered_after": covered_after,
    });
    cliffmap::fsutil::write_atomic(
        &a.out.join("truth.json"),
        serde_json::to_string_pretty(&json)?.as_bytes(),
    )?;
    if !a.quiet {
        println!(
            "projected {} ground photos ({}) into {} cells",
            photos.len(),
            list.display(),
            report.cells_written
        );
        println!(
            "texel PSNR vs ground truth, finest level: steep (>60°) {:.2} -> {:.2} dB, flat (<30°) {:.2} -> {:.2} dB",
            before.steep_psnr, after.steep_psnr, before.flat_psnr, after.flat_psnr
        );
        println!(
            "  on the {} steep texels where photos dominate: {:.2} -> {:.2} dB",
            covered_after.steep_texels, covered_before.steep_psnr, covered_after.steep_psnr
        );
    }
    // Render-space evaluation: novel views, cliffmap's renders against the exact truth, the
    // oracle and the baseline (needs a GPU driver or Mesa).
    match view_stage(scene, dem, ortho, &photos, store, &a.out.join("views")) {
        Ok(table) if !a.quiet => {
            println!("render-space PSNR on novel views (docs/evaluation.md):\n{table}")
        }
        Ok(_) => {}
        Err(e) => eprintln!(
            "warning: no render-space evaluation ({e:#}); install a GPU driver or Mesa (see README)"
        ),
    }
    Ok(())
}

/// Flags of `cliffmap demo`.
#[derive(clap::Args, Debug)]
pub struct Args {
    /// Output directory; the store is DIR/store.
    #[arg(long, default_value = "demo-out")]
    out: PathBuf,
    /// Scene seed.
    #[arg(long, default_value_t = 7)]
    seed: u32,
    /// DEM samples per side of the scene.
    #[arg(long, default_value_t = 513)]
    samples: usize,
    /// Finest level's max vertical error (m).
    #[arg(long, default_value_t = 0.5)]
    max_error: f64,
    /// Width of the ray-traced ground-truth photos in pixels (height = 3/4 of it).
    #[arg(long, default_value_t = 1600)]
    photo_width: u32,
    /// Supersampling (per axis) of the ray-traced ground-truth photos.
    #[arg(long, default_value_t = 2)]
    photo_supersample: u32,
    /// Skip the ground-photo stage (synthetic photos, projection, ground-truth PSNR).
    #[arg(long)]
    no_photos: bool,
    /// No progress bars or summary.
    #[arg(long)]
    quiet: bool,
}

/// Runs `demo`.
pub fn run(a: Args) -> anyhow::Result<()> {
    if a.samples < 17 || a.samples > 8193 {
        anyhow::bail!("--samples must be in 17..=8193, got {}", a.samples);
    }
    let scene = DemoScene {
        seed: a.seed,
        samples: a.samples,
        ..DemoScene::default()
    };
    let (dem, ortho) = scene.generate()?;
    write_png_atomic(&a.out.join("scene_ortho.png"), &ortho.image)?;
    let store = a.out.join("store");
    let opts = BuildOptions {
        max_error: a.max_error,
        progress: super::progress::progress_sink(a.quiet),
        force: true,
        ..BuildOptions::default()
    };
    let inputs = BuildInputs {
        dem: &dem,
        ortho: Some(&ortho),
        dem_source: format!("demo:seed={},samples={}", a.seed, a.samples),
        ortho_source: Some(format!("demo:seed={}", a.seed)),
        fingerprint: format!("demo-v1:{}:{}", a.seed, a.samples),
    };
    let manifest = build_store(&inputs, &opts, &store)?;
    if !a.quiet {
        println!(
            "demo scene: {} cells in {} levels -> {}",
            manifest.cells.len(),
            manifest.quadtree.levels,
            store.display()
        );
    }
    let reparam = ReparamOptions {
        progress: super::progress::progress_sink(a.quiet),
        ..ReparamOptions::default()
    };
    let st = reparam_store(&store, &reparam)?;
    if !a.quiet {
        let n = st
            .manifest
            .cells
            .iter()
            .filter(|c| c.reparam.is_some())
            .count();
        println!(
            "reparameterized {n} stretched cells (Rel_texel > {})",
            reparam.threshold
        );
        print_summary(&store, &st.manifest, reparam.threshold)?;
    }
    if !a.no_photos {
        photo_stage(&scene, &dem, &ortho, &a, &store)?;
    }
    // Render a view along the default flight (needs a GPU or Mesa's software drivers).
    let st = cliffmap::store::Store::open(&store)?;
    let (frame, share) = (a.out.join("frame.png"), a.out.join("frame_photo_share.png"));
    match render_view(&store, &st.manifest, &frame, &share) {
        Ok(msg) if !a.quiet => println!("{msg}"),
        Ok(_) => {}
        Err(e) => eprintln!(
            "warning: no frame rendered ({e:#}); install a GPU driver or Mesa (see README)"
        ),
    }
    Ok(())
}
