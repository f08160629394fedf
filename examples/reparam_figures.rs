//! Side-by-side figure and texel density gain of reparameterized cells.
//!
//! Builds a store (the demo scene, or the store given as first argument after `build`),
//! reparameterizes it, and for every reparameterized cell measures the texture density on
//! its steep triangles (slope > 60°): texels per m² of surface under the orthographic map and
//! under the chart. Prints a table; writes `ortho | reparam` texture pairs of the cell with the
//! largest ortho Rel_texel to `docs/img/reparam_side_by_side.png` (or the path in $FIG).
//!
//! ```sh
//! cargo run --release --example reparam_figures               # demo scene
//! cargo run --release --example reparam_figures -- STORE      # an existing store (reparam is rerun)
//! ```

use std::path::PathBuf;

use cliffmap::demo_scene::DemoScene;
use cliffmap::pipeline::{BuildInputs, BuildOptions, ReparamOptions, build_store, reparam_store};
use cliffmap::store::{CellRecord, Store};

/// (steep surface m², ortho texels on it, reparam texels on it) of one cell.
fn steep_density(st: &Store, c: &CellRecord) -> anyhow::Result<(f64, f64, f64)> {
    let ortho = st.read_mesh(c)?;
    let re = st.read_active_mesh(c)?;
    let uvs = re
        .uvs
        .as_ref()
        .ok_or_else(|| anyhow::anyhow!("cell {} has no chart", c.id))?;
    let t_o = c.texels as f64;
    let t_r = c.reparam.as_ref().map_or(t_o, |r| r.texels as f64);
    let (mut area, mut tex_o, mut tex_r) = (0.0, 0.0, 0.0);
    for t in ortho.surface() {
        let p = t.map(|i| glam::DVec3::from(ortho.positions[i as usize].map(f64::from)));
        let n = (p[1] - p[0]).cross(p[2] - p[0]);
        let a3 = 0.5 * n.length();
        if a3 <= 0.0 || n.z.abs() / n.length() > (60f64).to_radians().cos() {
            continue; // not steeper than 60°
        }
        let uv_area = |q: [[f64; 2]; 3]| {
            0.5 * ((q[1][0] - q[0][0]) * (q[2][1] - q[0][1])
                - (q[2][0] - q[0][0]) * (q[1][1] - q[0][1]))
                .abs()
        };
        let ou = t.map(|i| cliffmap::store::texcoord(c, &ortho, i as usize).map(f64::from));
        let ru = t.map(|i| uvs[i as usize].map(f64::from));
        area += a3;
        tex_o += uv_area(ou) * t_o * t_o;
        tex_r += uv_area(ru) * t_r * t_r;
    }
    Ok((area, tex_o, tex_r))
}

fn main() -> anyhow::Result<()> {
    let tmp = tempfile::tempdir()?;
    let dir: PathBuf = match std::env::args().nth(1) {
        Some(p) => PathBuf::from(p),
        None => {
            let (dem, ortho) = DemoScene::default().generate()?;
            let inputs = BuildInputs {
                dem: &dem,
                ortho: Some(&ortho),
                dem_source: "demo".into(),
                ortho_source: None,
                fingerprint: "figures".into(),
            };
            let d = tmp.path().join("store");
            build_store(
                &inputs,
                &BuildOptions {
                    ..Default::default()
                },
                &d,
            )?;
            d
        }
    };
    println!("| mode | cells | steep surface (m²) | ortho texels/m² | reparam texels/m² | gain |");
    println!("|---|---|---|---|---|---|");
    for mixed in [false, true] {
        let st = reparam_store(
            &dir,
            &ReparamOptions {
                mixed_resolution: mixed,
                ..Default::default()
            },
        )?;
        let finest = st.manifest.quadtree.levels - 1;
        let (mut a, mut o, mut r, mut n) = (0.0, 0.0, 0.0, 0);
        for c in st
            .manifest
            .cells
            .iter()
            .filter(|c| c.reparam.is_some() && c.level == finest)
        {
            let (ca, co, cr) = steep_density(&st, c)?;
            a += ca;
            o += co;
            r += cr;
            n += 1;
        }
        println!(
            "| {} | {n} finest | {:.0} | {:.3} | {:.3} | {:.2}x |",
            if mixed {
                "mixed resolution (2x side)"
            } else {
                "reparam (same size)"
            },
            a,
            o / a,
            r / a,
            r / o
        );
        if !mixed {
            let best = st
                .manifest
                .cells
                .iter()
                .filter(|c| c.reparam.is_some())
                .max_by(|x, y| x.stats.rel_texel.total_cmp(&y.stats.rel_texel))
                .ok_or_else(|| anyhow::anyhow!("no reparameterized cell"))?;
            let ortho = st.read_texture(best)?;
            let re = st
                .read_png(
                    &best
                        .reparam
                        .as_ref()
                        .map(|r| r.files.texture.clone())
                        .unwrap_or(best.files.texture.clone()),
                )?
                .to_rgba8();
            let (w, h) = (
                ortho.width() + re.width() + 8,
                ortho.height().max(re.height()),
            );
            let mut fig = image::RgbaImage::from_pixel(w, h, image::Rgba([255, 255, 255, 255]));
            image::imageops::overlay(&mut fig, &ortho, 0, 0);
            image::imageops::overlay(&mut fig, &re, (ortho.width() + 8) as i64, 0);
            for p in fig.pixels_mut() {
                p.0[3] = 255;
            }
            let out = std::env::var("FIG")
                .map(PathBuf::from)
                .unwrap_or_else(|_| PathBuf::from("docs/img/reparam_side_by_side.png"));
            cliffmap::fsutil::write_png_atomic(&out, &fig)?;
            println!(
                "(figure: cell {} Rel_texel {:.3} -> {})",
                best.id,
                best.stats.rel_texel,
                out.display()
            );
        }
    }
    Ok(())
}
