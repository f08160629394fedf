//! Demo ground photos and the ground-truth evaluation of an ortho-only store.
//!
//! `cargo run --release --example demo_truth -- OUT [--scale S] [--supersample N] [--no-store]`
//! renders the demo photos (1600x1200 scaled by S, default 1) with their cameras and
//! photos.json into OUT/photos, writes a 640-px-wide preview of each as OUT/preview_NAME.png,
//! then (unless --no-store) builds an ortho-only store of the demo scene in OUT/store and
//! prints the PSNR table of its finest level against the solid-texture ground truth.

use std::path::PathBuf;
use std::time::Instant;

use cliffmap::demo_scene::{DemoScene, TextureChoice, texel_truth};
use cliffmap::pipeline::{BuildInputs, BuildOptions, build_store};
use cliffmap::store::Store;

fn main() -> anyhow::Result<()> {
    let args: Vec<String> = std::env::args().skip(1).collect();
    let out = PathBuf::from(args.first().ok_or_else(|| {
        anyhow::anyhow!("usage: demo_truth OUT [--scale S] [--supersample N] [--no-store]")
    })?);
    let flag = |name: &str| {
        args.iter()
            .position(|a| a == name)
            .and_then(|i| args.get(i + 1))
            .map(|s| s.as_str())
    };
    let scale: f64 = flag("--scale").unwrap_or("1").parse()?;
    let ss: u32 = flag("--supersample").unwrap_or("2").parse()?;
    let scene = DemoScene::default();
    let (dem, ortho) = scene.generate()?;
    let t = Instant::now();
    let dir = out.join("photos");
    std::fs::create_dir_all(&dir)?;
    let mut entries = Vec::new();
    for shot in scene.photo_shots() {
        let cam = shot
            .camera
            .resized((1600.0 * scale) as u32, (1200.0 * scale) as u32);
        let p = cam.position;
        println!(
            "{:<14} at ({:.1}, {:.1}, {:.1}) forward ({:.3}, {:.3}, {:.3}) k1 {}",
            shot.name,
            p.x,
            p.y,
            p.z,
            cam.forward().x,
            cam.forward().y,
            cam.forward().z,
            cam.k1
        );
        let img = scene.render_truth_photo(&dem, &cam, ss)?;
        img.save(dir.join(format!("{}.png", shot.name)))?;
        let small = image::imageops::resize(&img, 640, 480, image::imageops::FilterType::Triangle);
        cliffmap::fsutil::write_png_atomic(
            &out.join(format!("preview_{}.png", shot.name)),
            &small,
        )?;
        entries.push(shot.name);
    }
    println!(
        "rendered {} photos in {:.1} s",
        entries.len(),
        t.elapsed().as_secs_f64()
    );
    if args.iter().any(|a| a == "--no-store") {
        return Ok(());
    }
    let store_dir = out.join("store");
    let inputs = BuildInputs {
        dem: &dem,
        ortho: Some(&ortho),
        dem_source: "demo".into(),
        ortho_source: Some("demo".into()),
        fingerprint: "demo_truth".into(),
    };
    build_store(
        &inputs,
        &BuildOptions {
            force: true,
            ..BuildOptions::default()
        },
        &store_dir,
    )?;
    let store = Store::open(&store_dir)?;
    let r = texel_truth(&store, &scene, TextureChoice::Active)?;
    println!("| texels | count | PSNR dB |\n|---|---|---|");
    println!(
        "| steep (> 60°) | {} | {:.2} |",
        r.steep_texels, r.steep_psnr
    );
    println!("| mid | {} | {:.2} |", r.mid_texels, r.mid_psnr);
    println!("| flat (< 30°) | {} | {:.2} |", r.flat_texels, r.flat_psnr);
    println!(
        "| all | {} | {:.2} |",
        r.steep_texels + r.mid_texels + r.flat_texels,
        r.all_psnr
    );
    Ok(())
}
