//! Where the terrain search's score peaks around a known camera (docs/registration.md,
//! "Where the score peaks"): samples cast once from the exact camera at full resolution
//! (as the search's last round does), the camera turned by small yaw, pitch and roll
//! offsets, the normalised mutual information printed per offset for all samples and for
//! subsets of them (without sky, terrain near / far, steep / not, silhouette band / inner).
//! A peak away from 0 is a bias of the score itself, and the subset whose peak moves most
//! is where it comes from.
//!
//! ```text
//! cargo run --release --example register_score_profile -- STORE PHOTOS.json NAME [STEP_DEG] [N]
//!     [--truth demo|tall [--seed N] [--relief P,C,E] [--blur M | --ortho DX,DY]]
//!     [--binary | --no-grey | --steep-no-grey]
//! ```
//! `--truth`: the samples' greys from the scene's true colour at their points (`--blur M`:
//! averaged over an M × M box on the true surface; `--ortho DX,DY`: from the scene's ortho,
//! bilinear, shifted by DX, DY metres). `--binary`: labels sky or terrain only;
//! `--no-grey`: without the grey; `--steep-no-grey`: without it on steep samples.
//! PHOTOS.json: a photo list with exact cameras (e.g. `render_eval`'s `OUT/photos/photos.json`).
#[path = "bench_util/scene_args.rs"]
#[allow(dead_code)] // this example uses only `scene_overrides`
mod scene_args;

use cliffmap::register::CameraParams;
use cliffmap::register::terrain::{GREY_CLASSES, GreyImage, SKY, Sample, TerrainScene, nmi};

fn main() -> anyhow::Result<()> {
    let a: Vec<String> = std::env::args().skip(1).collect();
    let usage = "usage: register_score_profile STORE PHOTOS.json NAME [STEP_DEG] [N]";
    let (store_dir, list, name) = match (a.first(), a.get(1), a.get(2)) {
        (Some(s), Some(l), Some(n)) => (s, l, n),
        _ => anyhow::bail!(usage),
    };
    let step: f64 = a.get(3).map_or(Ok(0.01), |s| s.parse())?;
    let n: i32 = a.get(4).map_or(Ok(6), |s| s.parse())?;
    let store = cliffmap::store::Store::open(std::path::Path::new(store_dir))?;
    let photos = cliffmap::photo::read_photo_list(std::path::Path::new(list))?;
    let p = photos
        .iter()
        .find(|p| &p.name == name)
        .ok_or_else(|| anyhow::anyhow!("no photo {name} in {list}"))?;
    let terrain = TerrainScene::new(&store, p.camera.position)?;
    let grey = GreyImage::from_photo(&p.image, 1);
    let cam = p.camera.resized(grey.width, grey.height);
    let mut band = terrain.sample(&cam, 1.0, 0.04, Some(24))?;
    // --truth demo|tall: grey labels from the scene's solid texture at each sample's point
    // instead of the store's texture (geometry and classes kept)
    if let Some(i) = a.iter().position(|x| x == "--truth") {
        let flag = |name: &str| {
            a.iter()
                .position(|x| x == name)
                .map(|j| a.get(j + 1).map_or("", String::as_str))
        };
        let scene = scene_args::scene_overrides(
            match a.get(i + 1).map(String::as_str) {
                Some("tall") => cliffmap::scene::DemoScene::tall_walls(),
                _ => cliffmap::scene::DemoScene::default(),
            },
            flag,
        )?;
        let colour = scene.surface_colour_fn();
        let (dem, ortho_image) = scene.generate()?;
        let blur: f64 = flag("--blur").map_or(Ok(0.0), str::parse)?;
        // --ortho DX,DY: grey from the scene's ortho image (bilinear, shifted by DX, DY m)
        let ortho = match flag("--ortho") {
            Some(v) => {
                let d: Vec<f64> = v.split(',').map(str::parse).collect::<Result<_, _>>()?;
                let [dx, dy] = d[..] else {
                    anyhow::bail!("--ortho takes DX,DY (metres), got {v:?}");
                };
                Some((ortho_image, dx, dy))
            }
            None => None,
        };
        let classes = GREY_CLASSES;
        let grey: Vec<Option<f64>> = band
            .iter()
            .map(|s| match s.at {
                cliffmap::register::terrain::SampleAt::Point(p) => {
                    let (gx, gy) = (
                        scene.height(p.x + 0.25, p.y) - scene.height(p.x - 0.25, p.y),
                        scene.height(p.x, p.y + 0.25) - scene.height(p.x, p.y - 0.25),
                    );
                    let slope = (gx.hypot(gy) / 0.5).atan().to_degrees();
                    let c = match &ortho {
                        Some((o, dx, dy)) => {
                            let (x, y) = (p.x + dx, p.y + dy);
                            let u = (x - scene.origin_x) / scene.spacing;
                            let v = (scene.origin_y - y) / scene.spacing;
                            let (w, h) = (o.image.width() as i64, o.image.height() as i64);
                            let (x0, y0) = (u.floor(), v.floor());
                            let (fx, fy) = (u - x0, v - y0);
                            let px = |i: i64, j: i64| {
                                let q = o
                                    .image
                                    .get_pixel(i.clamp(0, w - 1) as u32, j.clamp(0, h - 1) as u32)
                                    .0;
                                [
                                    q[0] as f64 / 255.0,
                                    q[1] as f64 / 255.0,
                                    q[2] as f64 / 255.0,
                                ]
                            };
                            let (i, j) = (x0 as i64, y0 as i64);
                            let (a00, a10, a01, a11) =
                                (px(i, j), px(i + 1, j), px(i, j + 1), px(i + 1, j + 1));
                            [0, 1, 2].map(|k| {
                                (a00[k] * (1.0 - fx) + a10[k] * fx) * (1.0 - fy)
                                    + (a01[k] * (1.0 - fx) + a11[k] * fx) * fy
                            })
                        }
                        None if blur > 0.0 => {
                            // the scene's colour averaged over a blur × blur box around (x, y)
                            // on the true surface, as the ortho's pixels are but not gridded
                            let mut acc = [0.0; 3];
                            for j in 0..4 {
                                for i in 0..4 {
                                    let x = p.x + (i as f64 + 0.5) / 4.0 * blur - blur / 2.0;
                                    let y = p.y + (j as f64 + 0.5) / 4.0 * blur - blur / 2.0;
                                    let hb = |x: f64, y: f64| {
                                        dem.bilinear(
                                            (scene.origin_y - y) / scene.spacing,
                                            (x - scene.origin_x) / scene.spacing,
                                        )
                                    };
                                    let (gx, gy) = (
                                        hb(x + 0.25, y) - hb(x - 0.25, y),
                                        hb(x, y + 0.25) - hb(x, y - 0.25),
                                    );
                                    let sl = (gx.hypot(gy) / 0.5).atan().to_degrees();
                                    let c = colour(x, y, hb(x, y), sl);
                                    for k in 0..3 {
                                        acc[k] += c[k] / 16.0;
                                    }
                                }
                            }
                            acc
                        }
                        None => colour(p.x, p.y, p.z, slope),
                    };
                    Some(0.2126 * c[0] + 0.7152 * c[1] + 0.0722 * c[2])
                }
                _ => None,
            })
            .collect();
        let mut sorted: Vec<f64> = grey.iter().flatten().copied().collect();
        sorted.sort_by(f64::total_cmp);
        for (s, g) in band.iter_mut().zip(&grey) {
            if let Some(g) = g {
                let rank = sorted.partition_point(|v| v < g);
                let class = ((rank * classes as usize) / sorted.len().max(1))
                    .min(classes as usize - 1) as u8;
                let rest = (s.label - 1) / classes;
                s.label = 1 + class + classes * rest;
            }
        }
    }
    {
        let classes = GREY_CLASSES;
        // --no-grey: labels without the texture's grey; --binary: sky or terrain only
        let steep_no_grey = a.iter().any(|x| x == "--steep-no-grey");
        let (no_grey, binary) = (
            a.iter().any(|x| x == "--no-grey"),
            a.iter().any(|x| x == "--binary"),
        );
        for s in band.iter_mut() {
            if s.label != SKY && binary {
                s.label = 1;
            } else if s.label != SKY
                && (no_grey || (steep_no_grey && (s.label - 1) / classes % 2 == 1))
            {
                s.label = 1 + classes * ((s.label - 1) / classes);
            }
        }
    }
    let all = terrain.sample(&cam, 1.0, 0.04, None)?;
    let classes = GREY_CLASSES;
    let far = |s: &Sample| s.label != SKY && (s.label - 1) / classes % 4 >= 2;
    let steep = |s: &Sample| s.label != SKY && (s.label - 1) / classes % 2 == 1;
    let pick = |f: &dyn Fn(&Sample) -> bool| band.iter().copied().filter(|s| f(s)).collect();
    let subsets: Vec<(&str, Vec<Sample>)> = vec![
        ("search (band + 1/9 inner)", band.clone()),
        ("every pixel", all.clone()),
        ("no sky", pick(&|s| s.label != SKY)),
        ("near + sky", pick(&|s| !far(s))),
        ("far + sky", pick(&|s| s.label == SKY || far(s))),
        ("flat + sky", pick(&|s| !steep(s))),
        ("steep + sky", pick(&|s| s.label == SKY || steep(s))),
    ];
    let truth = CameraParams::from_camera(&p.camera);
    for (axis, k) in [("yaw", 0usize), ("pitch", 1), ("roll", 2)] {
        println!("\n{name}: {axis} offset (°) -> score per subset (peak marked *)");
        let offs: Vec<f64> = (-n..=n).map(|i| i as f64 * step).collect();
        let mut table: Vec<Vec<f64>> = Vec::new();
        for (_, s) in &subsets {
            let row: Vec<f64> = offs
                .iter()
                .map(|d| {
                    let mut c = truth;
                    c.angles[k] += d.to_radians();
                    nmi(s, &c.camera().resized(grey.width, grey.height), &grey)
                })
                .collect();
            table.push(row);
        }
        print!("| subset (samples) |");
        for d in &offs {
            print!(" {d:+.3} |");
        }
        println!(" peak |");
        for ((label, s), row) in subsets.iter().zip(&table) {
            let best = (0..row.len())
                .max_by(|&i, &j| row[i].total_cmp(&row[j]))
                .unwrap_or(0);
            print!("| {label} ({}) |", s.len());
            for (i, v) in row.iter().enumerate() {
                print!(" {:.5}{} |", v, if i == best { "*" } else { "" });
            }
            // parabola through the peak and its neighbours
            let peak = if best > 0 && best + 1 < row.len() {
                let (l, m, r) = (row[best - 1], row[best], row[best + 1]);
                let den = l - 2.0 * m + r;
                offs[best]
                    + if den < 0.0 {
                        0.5 * (l - r) / den * step
                    } else {
                        0.0
                    }
            } else {
                offs[best]
            };
            println!(" {peak:+.4} |");
        }
    }
    Ok(())
}
