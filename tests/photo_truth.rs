//! Ground truth of the demo scene: ground-photo cameras, ray-traced truth photos written as a
//! photos.json set, and texel-level PSNR of a store against the solid texture.

use cliffmap::camera::CameraModel;
use cliffmap::demo_scene::{
    DemoPhotoOptions, DemoScene, SKY_COLOUR, TextureChoice, texel_truth, texel_truth_with,
};
use cliffmap::photo::read_photo_list;
use cliffmap::pipeline::{BuildInputs, BuildOptions, build_store};
use cliffmap::store::Store;
use glam::DVec3;

/// The demo terrain at 4 m spacing (same 1024 m extent and features as the default).
fn scene() -> DemoScene {
    DemoScene {
        samples: 257,
        spacing: 4.0,
        ..DemoScene::default()
    }
}

fn slope_at(sc: &DemoScene, x: f64, y: f64) -> f64 {
    let gx = sc.height(x + 0.5, y) - sc.height(x - 0.5, y);
    let gy = sc.height(x, y + 0.5) - sc.height(x, y - 0.5);
    gx.hypot(gy).atan().to_degrees()
}

/// Slope where the optical axis first meets the terrain (`None` if it does not within 2 km).
fn axis_hit_slope(sc: &DemoScene, cam: &CameraModel) -> Option<(f64, f64)> {
    let f = cam.forward();
    (2..8000).map(|i| i as f64 * 0.25).find_map(|t| {
        let p: DVec3 = cam.position + t * f;
        (p.z < sc.height(p.x, p.y)).then(|| (slope_at(sc, p.x, p.y), t))
    })
}

#[test]
fn demo_cameras_stand_on_the_ground_and_face_walls() {
    let sc = scene();
    let shots = sc.photo_shots();
    assert!((3..=4).contains(&shots.len()), "{} cameras", shots.len());
    assert_eq!(shots, sc.photo_shots(), "deterministic");
    let mut steep = 0;
    for s in &shots {
        let c = s.camera;
        assert_eq!(c.problem(), None);
        assert_eq!((c.width, c.height), (1600, 1200));
        let above = c.position.z - sc.height(c.position.x, c.position.y);
        assert!(
            (above - 1.7).abs() < 1e-6,
            "{}: {above} m above ground",
            s.name
        );
        let hit = axis_hit_slope(&sc, &c);
        println!(
            "{}: optical axis meets the terrain at {hit:?} (slope deg, distance m)",
            s.name
        );
        if let Some((slope, dist)) = hit {
            steep += usize::from(slope > 60.0 && (80.0..500.0).contains(&dist));
        }
    }
    assert!(steep >= 3, "only {steep} cameras look at a wall");
    assert_eq!(
        shots.iter().filter(|s| s.camera.k1 != 0.0).count(),
        1,
        "one distorted camera"
    );
}

#[test]
fn truth_photos_apply_the_lens_distortion_consistently() {
    let sc = scene();
    let (dem, _) = sc.generate().unwrap();
    let shot = sc
        .photo_shots()
        .into_iter()
        .find(|s| s.camera.k1 != 0.0)
        .unwrap();
    // A stronger barrel distortion than the demo's, so the warp is tens of pixels.
    let cd = CameraModel {
        k1: -0.25,
        ..shot.camera.resized(400, 300)
    };
    let cu = CameraModel {
        k1: 0.0,
        k2: 0.0,
        ..cd
    };
    let id = sc.render_truth_photo(&dem, &cd, 2).unwrap();
    let iu = sc.render_truth_photo(&dem, &cu, 2).unwrap();
    assert_eq!(
        id,
        sc.render_truth_photo(&dem, &cd, 2).unwrap(),
        "deterministic"
    );
    let sample = |x: f64, y: f64| -> [f64; 3] {
        let (x0, y0) = (x.floor().clamp(0.0, 398.0), y.floor().clamp(0.0, 298.0));
        let (fx, fy) = (x - x0, y - y0);
        let p = |i: f64, j: f64| iu.get_pixel(i as u32, j as u32).0.map(|c| c as f64);
        let (a, b, c, d) = (
            p(x0, y0),
            p(x0 + 1.0, y0),
            p(x0, y0 + 1.0),
            p(x0 + 1.0, y0 + 1.0),
        );
        [0, 1, 2].map(|k| {
            (a[k] * (1.0 - fx) + b[k] * fx) * (1.0 - fy) + (c[k] * (1.0 - fx) + d[k] * fx) * fy
        })
    };
    let sky = id.pixels().filter(|p| p.0 == SKY_COLOUR).count() as f64 / (400.0 * 300.0);
    assert!((0.05..0.8).contains(&sky), "sky fraction {sky}");
    // Warping the undistorted render through the distortion model reproduces the distorted
    // one much better than taking it unwarped.
    let (mut warped, mut plain, mut n) = (0.0, 0.0, 0);
    for v in 0..300u32 {
        for u in 0..400u32 {
            let (xd, yd) = ((u as f64 - cd.cx) / cd.fx, (v as f64 - cd.cy) / cd.fy);
            let [x, y] = cd.undistort(xd, yd).unwrap();
            let (uu, vu) = (cu.fx * x + cu.cx, cu.fy * y + cu.cy);
            if !(0.0..399.0).contains(&uu) || !(0.0..299.0).contains(&vu) {
                continue;
            }
            let d = |a: [f64; 3], b: [f64; 3]| (0..3).map(|k| (a[k] - b[k]).abs()).sum::<f64>();
            let p = id.get_pixel(u, v).0.map(|c| c as f64);
            warped += d(p, sample(uu, vu));
            plain += d(p, sample(u as f64, v as f64));
            n += 1;
        }
    }
    println!(
        "mean |diff| warped {:.2}, unwarped {:.2} over {n} pixels",
        warped / n as f64,
        plain / n as f64
    );
    assert!(warped < 0.5 * plain, "warped {warped} vs unwarped {plain}");
}

#[test]
fn demo_photo_set_reads_back_through_photos_json() {
    let sc = scene();
    let (dem, _) = sc.generate().unwrap();
    let tmp = tempfile::tempdir().unwrap();
    let opts = DemoPhotoOptions {
        width: 160,
        height: 120,
        supersample: 1,
    };
    let list = sc
        .write_demo_photos(&dem, &tmp.path().join("photos"), &opts)
        .unwrap();
    let photos = read_photo_list(&list).unwrap();
    let shots = sc.photo_shots();
    assert_eq!(photos.len(), shots.len());
    for (p, s) in photos.iter().zip(&shots) {
        assert_eq!(p.name, format!("{}.jpg", s.name));
        let want = s.camera.resized(160, 120);
        let got = p.camera;
        assert_eq!(
            (got.width, got.height, got.position),
            (160, 120, want.position)
        );
        assert!(
            (got.fx - want.fx).abs() < 1e-9 && (got.cy - want.cy).abs() < 1e-9 && got.k1 == want.k1
        );
        assert!(
            (got.world_to_camera - want.world_to_camera)
                .to_cols_array()
                .iter()
                .all(|v| v.abs() < 1e-9)
        );
        // The JPEG is the render (quality 95).
        let truth = sc.render_truth_photo(&dem, &want, 1).unwrap();
        let mad = truth
            .as_raw()
            .iter()
            .zip(p.image.as_raw())
            .map(|(a, b)| (*a as f64 - *b as f64).abs())
            .sum::<f64>()
            / truth.as_raw().len() as f64;
        assert!(mad < 4.0, "{}: JPEG differs by {mad}", s.name);
    }
    assert!(
        sc.write_demo_photos(
            &dem,
            tmp.path(),
            &DemoPhotoOptions {
                supersample: 0,
                ..opts
            }
        )
        .is_err()
    );
}

/// The truth texture of an ortho cell computed independently of `texel_truth`'s chart
/// rasterization: each texel centre's world (x, y) from the cell's extent, located in the
/// mesh's triangles in world x-y (f64; first triangle wins on shared edges), z and slope
/// from that triangle.
fn xy_truth_texture(
    sc: &DemoScene,
    store: &Store,
    rec: &cliffmap::store::CellRecord,
) -> image::RgbaImage {
    let mesh = store.read_mesh(rec).unwrap();
    let n = rec.texels;
    let e = &rec.extent;
    let o = DVec3::from_array(rec.origin);
    let colour = sc.surface_colour_fn();
    let mut img = image::RgbaImage::new(n, n);
    for t in mesh.surface() {
        let p = t.map(|k| o + glam::Vec3::from_array(mesh.positions[k as usize]).as_dvec3());
        let normal = (p[1] - p[0]).cross(p[2] - p[0]);
        if normal.z.abs() < 1e-12 {
            continue;
        }
        let slope = (normal.z.abs() / normal.length()).acos().to_degrees();
        let (x0, x1) = (
            p.iter().map(|q| q.x).fold(f64::MAX, f64::min),
            p.iter().map(|q| q.x).fold(f64::MIN, f64::max),
        );
        let (y0, y1) = (
            p.iter().map(|q| q.y).fold(f64::MAX, f64::min),
            p.iter().map(|q| q.y).fold(f64::MIN, f64::max),
        );
        let i0 = (((x0 - e.min_x) / e.width() * n as f64) - 0.5)
            .floor()
            .max(0.0) as u32;
        let i1 = (((x1 - e.min_x) / e.width() * n as f64) - 0.5)
            .ceil()
            .min(n as f64 - 1.0) as u32;
        let j0 = (((e.max_y - y1) / e.height() * n as f64) - 0.5)
            .floor()
            .max(0.0) as u32;
        let j1 = (((e.max_y - y0) / e.height() * n as f64) - 0.5)
            .ceil()
            .min(n as f64 - 1.0) as u32;
        for j in j0..=j1 {
            for i in i0..=i1 {
                let x = e.min_x + (i as f64 + 0.5) / n as f64 * e.width();
                let y = e.max_y - (j as f64 + 0.5) / n as f64 * e.height();
                let (a, b, c) = (p[0], p[1], p[2]);
                let den = (b.x - a.x) * (c.y - a.y) - (b.y - a.y) * (c.x - a.x);
                let w1 = ((x - a.x) * (c.y - a.y) - (y - a.y) * (c.x - a.x)) / den;
                let w2 = ((b.x - a.x) * (y - a.y) - (b.y - a.y) * (x - a.x)) / den;
                let w0 = 1.0 - w1 - w2;
                if w0 < -1e-9 || w1 < -1e-9 || w2 < -1e-9 || img.get_pixel(i, j).0[3] != 0 {
                    continue;
                }
                let z = w0 * a.z + w1 * b.z + w2 * c.z;
                let col = colour(x, y, z, slope).map(|v| (v * 255.0).round() as u8);
                img.put_pixel(i, j, image::Rgba([col[0], col[1], col[2], 255]));
            }
        }
    }
    img
}

#[test]
fn ortho_store_is_smeared_on_walls_and_truth_textures_score_high() {
    let sc = scene();
    let (dem, ortho) = sc.generate().unwrap();
    let tmp = tempfile::tempdir().unwrap();
    let inputs = BuildInputs {
        dem: &dem,
        ortho: Some(&ortho),
        dem_source: "demo".into(),
        ortho_source: Some("demo".into()),
        fingerprint: "photo_truth".into(),
    };
    let opts = BuildOptions {
        force: true,
        ..BuildOptions::default()
    };
    build_store(&inputs, &opts, tmp.path()).unwrap();
    let store = Store::open(tmp.path()).unwrap();
    let r = texel_truth(&store, &sc, TextureChoice::Active).unwrap();
    println!("ortho store: {r:?}");
    assert_eq!(r.level, store.manifest.quadtree.levels - 1);
    assert!(
        r.steep_texels > 1000 && r.flat_texels > 10 * r.steep_texels,
        "{r:?}"
    );
    assert!(
        r.steep_psnr < r.flat_psnr - 5.0,
        "steep {} vs flat {}",
        r.steep_psnr,
        r.flat_psnr
    );
    // Without photo textures, the photo choice is the active texture.
    let p = texel_truth(&store, &sc, TextureChoice::Photo).unwrap();
    assert_eq!(
        (p.photo_cells, p.steep_psnr, p.flat_psnr),
        (0, r.steep_psnr, r.flat_psnr)
    );
    // Sanity: textures filled with the truth at each texel's mesh point (found another way)
    // score near the 8-bit quantization limit (~59 dB) in every slope class.
    let t = texel_truth_with(&store, &sc, r.level, |rec| {
        Ok(xy_truth_texture(&sc, &store, rec))
    })
    .unwrap();
    println!("truth textures: {t:?}");
    assert!(
        t.steep_psnr > 50.0 && t.flat_psnr > 50.0 && t.mid_psnr > 50.0,
        "{t:?}"
    );
    assert!(t.unknown_texels * 100 < t.flat_texels, "{t:?}");
}
