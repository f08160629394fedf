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
//!     [--match G [--kernel box|bspline] --lift demo|tall]
//! ```
//! `--truth`: the samples' greys from the scene's true colour at their points (`--blur M`:
//! averaged over an M × M box on the true surface; `--ortho DX,DY`: from the scene's ortho,
//! bilinear, shifted by DX, DY metres). `--binary`: labels sky or terrain only;
//! `--no-grey`: without the grey; `--steep-no-grey`: without it on steep samples.
//! `--match G`: each terrain sample's photo value averaged over the image of the patch its
//! label averages (a G × G ground box, or with `--kernel bspline` that box convolved with a
//! G-wide tent, lifted onto the scene's DEM: `--lift` names the scene, or `--truth` does);
//! with `--truth --blur G` the label is averaged over the same points. Prints the search's
//! samples only.
//! PHOTOS.json: a photo list with exact cameras (e.g. `render_eval`'s `OUT/photos/photos.json`).
#[path = "bench_util/scene_args.rs"]
#[allow(dead_code)] // this example uses only `scene_overrides`
mod scene_args;

use cliffmap::register::CameraParams;
use cliffmap::register::terrain::{
    GREY_CLASSES, GreyImage, LabelledTerrain, SKY, Sample, SampleAt, nmi, nmi_by, sample_pixel,
};
use glam::DVec3;
use rayon::prelude::*;

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
    let terrain = LabelledTerrain::new(&store, p.camera.position)?;
    let grey = GreyImage::from_photo(&p.image, 1);
    let cam = p.camera.resized(grey.width, grey.height);
    let mut band = terrain.sample(&cam, 1.0, 0.04, Some(24))?;
    let flag = |name: &str| {
        a.iter()
            .position(|x| x == name)
            .map(|j| a.get(j + 1).map_or("", String::as_str))
    };
    // --match G [--kernel box|bspline] --lift demo|tall (or --truth): each terrain sample's
    // photo value averaged over the image of the surface patch its label averages, a G × G
    // ground box (box) or that box convolved with a G-wide tent (bspline: what a G-metre
    // ortho read bilinearly averages; support 3G), lifted onto the scene's DEM
    let patches: Option<Vec<Vec<(DVec3, f32)>>> = match flag("--match") {
        None => None,
        Some(g) => {
            let g: f64 = g.parse()?;
            let bspline = flag("--kernel") == Some("bspline");
            let which = flag("--truth").or(flag("--lift"));
            let scene = scene_args::scene_overrides(
                match which {
                    Some("tall") => cliffmap::demo_scene::DemoScene::tall_walls(),
                    Some("demo") => cliffmap::demo_scene::DemoScene::default(),
                    _ => anyhow::bail!("--match needs --lift demo|tall or --truth"),
                },
                flag,
            )?;
            let (dem, _) = scene.generate()?;
            let h = |x: f64, y: f64| {
                dem.bilinear(
                    (scene.origin_y - y) / scene.spacing,
                    (x - scene.origin_x) / scene.spacing,
                )
            };
            let half = if bspline { 1.5 * g } else { 0.5 * g };
            let weight = |t: f64| -> f64 {
                if !bspline {
                    return 1.0;
                }
                let t = (t / g).abs();
                if t < 0.5 {
                    0.75 - t * t
                } else if t < 1.5 {
                    0.5 * (1.5 - t) * (1.5 - t)
                } else {
                    0.0
                }
            };
            let lift = |x: f64, y: f64| DVec3::new(x, y, h(x, y));
            let px_dist = |p: DVec3, q: DVec3| match (cam.project(p), cam.project(q)) {
                (Some(u), Some(v)) => (u[0] - v[0]).hypot(u[1] - v[1]),
                _ => 0.0,
            };
            Some(
                band.par_iter()
                    .map(|s| match s.at {
                        SampleAt::Point(p) => {
                            let ex = px_dist(lift(p.x - half, p.y), lift(p.x + half, p.y));
                            let ey = px_dist(lift(p.x, p.y - half), lift(p.x, p.y + half));
                            let (kx, ky) = (
                                (ex.ceil() as usize).clamp(1, 16),
                                (ey.ceil() as usize).clamp(1, 16),
                            );
                            let mut pts = Vec::with_capacity(kx * ky);
                            let mut sum = 0.0;
                            for j in 0..ky {
                                let dy = ((j as f64 + 0.5) / ky as f64 * 2.0 - 1.0) * half;
                                for i in 0..kx {
                                    let dx = ((i as f64 + 0.5) / kx as f64 * 2.0 - 1.0) * half;
                                    let w = weight(dx) * weight(dy);
                                    sum += w;
                                    pts.push((lift(p.x + dx, p.y + dy), w as f32));
                                }
                            }
                            for q in &mut pts {
                                q.1 /= sum as f32;
                            }
                            pts
                        }
                        SampleAt::Sky(_) => Vec::new(),
                    })
                    .collect(),
            )
        }
    };
    // --truth demo|tall: grey labels from the scene's solid texture at each sample's point
    // instead of the store's texture (geometry and classes kept)
    if let Some(i) = a.iter().position(|x| x == "--truth") {
        let scene = scene_args::scene_overrides(
            match a.get(i + 1).map(String::as_str) {
                Some("tall") => cliffmap::demo_scene::DemoScene::tall_walls(),
                _ => cliffmap::demo_scene::DemoScene::default(),
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
            .par_iter()
            .enumerate()
            .map(|(si, s)| match s.at {
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
                        None if blur > 0.0 && patches.is_some() => {
                            // the same points and weights the photo is averaged over
                            let mut acc = [0.0; 3];
                            for &(q, w) in patches.as_ref().map_or(&[][..], |v| &v[si][..]) {
                                let hb = |x: f64, y: f64| {
                                    dem.bilinear(
                                        (scene.origin_y - y) / scene.spacing,
                                        (x - scene.origin_x) / scene.spacing,
                                    )
                                };
                                let (gx, gy) = (
                                    hb(q.x + 0.25, q.y) - hb(q.x - 0.25, q.y),
                                    hb(q.x, q.y + 0.25) - hb(q.x, q.y - 0.25),
                                );
                                let sl = (gx.hypot(gy) / 0.5).atan().to_degrees();
                                let c = colour(q.x, q.y, q.z, sl);
                                for k in 0..3 {
                                    acc[k] += c[k] * w as f64;
                                }
                            }
                            acc
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
    let subsets: Vec<(&str, Vec<Sample>)> = if patches.is_some() {
        vec![("search, photo matched", band.clone())]
    } else {
        vec![
            ("search (band + 1/9 inner)", band.clone()),
            ("every pixel", all.clone()),
            ("no sky", pick(&|s| s.label != SKY)),
            ("near + sky", pick(&|s| !far(s))),
            ("far + sky", pick(&|s| s.label == SKY || far(s))),
            ("flat + sky", pick(&|s| !steep(s))),
            ("steep + sky", pick(&|s| s.label == SKY || steep(s))),
        ]
    };
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
                    let cm = c.camera().resized(grey.width, grey.height);
                    match &patches {
                        None => nmi(s, &cm, &grey),
                        Some(pp) => nmi_by(s.len(), |i| {
                            let smp = &s[i];
                            let v = match smp.at {
                                SampleAt::Sky(_) => {
                                    sample_pixel(smp, &cm).and_then(|px| grey.at(px[0], px[1]))
                                }
                                SampleAt::Point(_) => {
                                    let mut acc = [0.0f32; 2];
                                    let mut wsum = 0.0f32;
                                    for &(q, w) in &pp[i] {
                                        if let Some(v) =
                                            cm.project(q).and_then(|px| grey.at(px[0], px[1]))
                                        {
                                            acc[0] += w * v[0];
                                            acc[1] += w * v[1];
                                            wsum += w;
                                        }
                                    }
                                    (wsum > 0.0).then(|| [acc[0] / wsum, acc[1] / wsum])
                                }
                            };
                            (smp.label, v)
                        }),
                    }
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
