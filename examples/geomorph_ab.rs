//! Draw cost of geomorphing, frame-interleaved: one scene with morph targets loaded renders
//! every camera of a flight untimed (loading what it needs), then twice timed — geomorphing
//! off and on, in alternating order — so both see the same resident cells and machine load.
//! Prints medians and the median of per-camera ratios.
//!
//! Usage: `cargo run --release --example geomorph_ab -- STORE [PATH.json] [FRAMES] [WxH]`
//! (default: the store's default flight, 60 frames, 960x540).

use std::path::PathBuf;

use cliffmap::render::{FlightPath, GeomorphOptions, SceneOptions, StoreRenderer, percentile};

fn main() -> anyhow::Result<()> {
    let args: Vec<String> = std::env::args().skip(1).collect();
    let store =
        PathBuf::from(args.first().ok_or_else(|| {
            anyhow::anyhow!("usage: geomorph_ab STORE [PATH.json] [FRAMES] [WxH]")
        })?);
    let path_file = args
        .get(1)
        .filter(|s| s.ends_with(".json"))
        .map(PathBuf::from);
    let rest = &args[1 + usize::from(path_file.is_some())..];
    let frames: usize = rest.first().map(|s| s.parse()).transpose()?.unwrap_or(60);
    let (w, h) = match rest.get(1) {
        Some(s) => {
            let (a, b) = s
                .split_once('x')
                .ok_or_else(|| anyhow::anyhow!("size must be WxH"))?;
            (a.parse()?, b.parse()?)
        }
        None => (960u32, 540u32),
    };
    let opts = SceneOptions {
        geomorph: GeomorphOptions {
            enabled: true,
            ..Default::default()
        },
        ..Default::default()
    };
    let mut scene = StoreRenderer::open(&store, w, h, opts)?;
    let path = match &path_file {
        Some(p) => FlightPath::from_json_file(p)?,
        None => FlightPath::default_for(&scene.store().manifest)?,
    };
    let (mut off, mut on, mut ratio, mut morphed) =
        (Vec::new(), Vec::new(), Vec::new(), Vec::new());
    for (k, cam) in path.cameras(frames.max(2), w, h).iter().enumerate() {
        // Warm frames until nothing is uploaded any more (parents lent for textures included).
        scene.set_geomorph(true);
        for _ in 0..20 {
            if scene.frame(cam, true)?.uploads == 0 {
                break;
            }
            std::thread::sleep(std::time::Duration::from_millis(20));
        }
        let mut t = [0.0; 2];
        for step in 0..2 {
            let g = (k + step) % 2 == 1;
            scene.set_geomorph(g);
            let r = scene.frame(cam, true)?;
            t[usize::from(g)] = r.frame_ms;
            if g {
                morphed.push(r.morphed as f64);
            }
        }
        off.push(t[0]);
        on.push(t[1]);
        ratio.push(t[1] / t[0]);
    }
    let info = &scene.gpu().info;
    println!(
        "store {}, {w}x{h}, {} cameras, adapter {} ({:?}, {:?})",
        store.display(),
        off.len(),
        info.name,
        info.backend,
        info.device_type
    );
    println!(
        "frame ms median: off {:.1}, on {:.1}; fps median off {:.2}, on {:.2}; per-camera ratio on/off: median {:.3} (p25 {:.3}, p75 {:.3}); morphed cells per frame median {}",
        percentile(&off, 0.5),
        percentile(&on, 0.5),
        1e3 / percentile(&off, 0.5),
        1e3 / percentile(&on, 0.5),
        percentile(&ratio, 0.5),
        percentile(&ratio, 0.25),
        percentile(&ratio, 0.75),
        percentile(&morphed, 0.5)
    );
    Ok(())
}
