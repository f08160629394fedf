//! Relief mapping (docs/rendering.md): a flat TIN whose relief map says the DEM lies `r`
//! metres above it everywhere must look, in an oblique view, like the same TIN raised by
//! `r` drawn without relief mapping: the texture is looked up where the view ray meets the
//! raised surface. The same synthetic photo charts check the photo-share overlay. Headless
//! (Mesa lavapipe in CI); fails, never skips, without an adapter.

mod render_support;

use std::path::Path;

use cliffmap::camera::{CameraModel, rotation_look_at};
use cliffmap::render::{
    FrameOptions, NO_PHOTO_COLOUR, Overlay, SceneOptions, StoreRenderer, UvMode, share_colour,
};
use cliffmap::store::{ReliefRecord, cell_stem, write_file};
use glam::DVec3;
use render_support::{Synth, X0, Y0, write_store_textured};

const SIZE: u32 = 160;

/// A texture whose red grows east and green south (so a shifted lookup changes colour).
fn ramp(texels: u32) -> image::RgbaImage {
    image::RgbaImage::from_fn(texels, texels, |i, j| {
        image::Rgba([(i * 255 / texels) as u8, (j * 255 / texels) as u8, 90, 255])
    })
}

fn synth(z: f64) -> Synth {
    Synth {
        levels: 1,
        size: 100.0,
        z,
        finest_error: 0.1,
        texels: 64,
    }
}

/// Writes the store and, with `relief = Some((v, range))`, a constant relief map of 8-bit
/// value `v` and range `range` metres for every cell.
fn store(dir: &Path, z: f64, relief: Option<(u8, f64)>) {
    let s = synth(z);
    let mut m = write_store_textured(dir, &s, |_| ramp(s.texels), |_| false);
    if let Some((v, range)) = relief {
        for rec in &mut m.cells {
            let img = image::GrayImage::from_pixel(s.texels, s.texels, image::Luma([v]));
            let mut c = std::io::Cursor::new(Vec::new());
            img.write_to(&mut c, image::ImageFormat::Png).unwrap();
            let stem = cell_stem(rec.level, rec.x, rec.y);
            let file = write_file(dir, &format!("{stem}.relief.png"), &c.into_inner()).unwrap();
            rec.relief = Some(ReliefRecord {
                file,
                range_m: range,
            });
        }
        let text = serde_json::to_string_pretty(&m).unwrap();
        cliffmap::fsutil::write_atomic(&dir.join("manifest.json"), text.as_bytes()).unwrap();
    }
}

fn render(dir: &Path, relief: bool, cam: &CameraModel) -> image::RgbaImage {
    render_as(dir, relief, cam, UvMode::Ortho)
}

fn render_as(dir: &Path, relief: bool, cam: &CameraModel, uv_mode: UvMode) -> image::RgbaImage {
    render_overlay(dir, relief, cam, uv_mode, Overlay::None)
}

fn render_overlay(
    dir: &Path,
    relief: bool,
    cam: &CameraModel,
    uv_mode: UvMode,
    overlay: Overlay,
) -> image::RgbaImage {
    let opts = SceneOptions {
        uv_mode,
        overlay,
        frame: FrameOptions {
            lit: false,
            ..Default::default()
        },
        relief,
        ..Default::default()
    };
    let mut scene = StoreRenderer::open(dir, SIZE, SIZE, opts).unwrap_or_else(|e| {
        panic!("cannot open a headless GPU scene: {e}\n(install Mesa: apt-get install mesa-vulkan-drivers libegl1 libegl-mesa0 libgl1-mesa-dri)")
    });
    scene.frame(cam, true).unwrap();
    scene.read_rgba().unwrap()
}

/// Mean absolute channel difference (RGB) over the central half of the frame.
fn mean_diff(a: &image::RgbaImage, b: &image::RgbaImage) -> f64 {
    let (lo, hi) = (SIZE / 4, 3 * SIZE / 4);
    let mut sum = 0.0;
    let mut n = 0.0;
    for y in lo..hi {
        for x in lo..hi {
            let (p, q) = (a.get_pixel(x, y).0, b.get_pixel(x, y).0);
            for k in 0..3 {
                sum += (p[k] as f64 - q[k] as f64).abs();
                n += 1.0;
            }
        }
    }
    sum / n
}

#[test]
fn a_constant_relief_looks_like_the_raised_surface() {
    let z = 1234.0;
    // 8-bit value 223 of range 8 m: the DEM lies r = (223/255·2 − 1)·8 ≈ 5.99 m above the TIN
    let (v, range) = (223u8, 8.0);
    let r = (v as f64 / 255.0 * 2.0 - 1.0) * range;
    let (with, raised) = (tempfile::tempdir().unwrap(), tempfile::tempdir().unwrap());
    store(with.path(), z, Some((v, range)));
    store(raised.path(), z + r, None);
    // oblique view of the cell's centre from the south-west, about 50° down
    let centre = DVec3::new(X0 + 50.0, Y0 - 50.0, z);
    let pos = centre + DVec3::new(-30.0, -25.0, 48.0);
    let rot = rotation_look_at(pos, centre).unwrap();
    let cam = CameraModel::with_fov(pos, rot, SIZE, SIZE, 50f64.to_radians());

    let relief_on = render(with.path(), true, &cam);
    let relief_off = render(with.path(), false, &cam);
    let raised_img = render(raised.path(), false, &cam);
    let off = mean_diff(&relief_off, &raised_img);
    let on = mean_diff(&relief_on, &raised_img);
    eprintln!("mean difference to the raised surface: relief on {on:.3}, off {off:.3}");
    // without relief mapping the lookup is metres off (the ramp moves ~2.5 levels per metre)
    assert!(off > 3.0, "the test scene must show the shift: {off}");
    assert!(on < 0.1 * off && on < 0.6, "relief on: {on}, off: {off}");
    // the same with texture coordinates from a vertex stream: the lookup moves through the
    // triangle's map from (x, y) to texture coordinates (as on reparameterized charts)
    let stream_on = render_as(with.path(), true, &cam, UvMode::Reparam);
    let stream_raised = render_as(raised.path(), false, &cam, UvMode::Reparam);
    let stream = mean_diff(&stream_on, &stream_raised);
    eprintln!("vertex-stream coordinates: relief on {stream:.3}");
    assert!(
        stream < 0.1 * off && stream < 0.6,
        "stream: {stream}, off: {off}"
    );
}

/// A flat mesh of `n × n` squares over the cell's nominal square (at the height of
/// `flat_mesh`, without a skirt) with orthographic texture coordinates: interior vertices
/// lie away from the chart's seams, so relief mapping may move lookups there.
fn grid_mesh(rec: &cliffmap::store::CellRecord, n: u32) -> cliffmap::cells::CellMesh {
    let flat = render_support::flat_mesh(rec, true);
    let (o, e) = (rec.origin, rec.extent);
    let z = flat.positions[0][2];
    let mut positions = Vec::new();
    let mut uvs = Vec::new();
    for j in 0..=n {
        for i in 0..=n {
            let (u, v) = (i as f64 / n as f64, j as f64 / n as f64);
            let x = e.min_x + u * e.width() - o[0];
            let y = e.max_y - v * e.height() - o[1];
            positions.push([x as f32, y as f32, z]);
            uvs.push([u as f32, v as f32]);
        }
    }
    let mut triangles = Vec::new();
    let k = |i: u32, j: u32| j * (n + 1) + i;
    for j in 0..n {
        for i in 0..n {
            triangles.push([k(i, j), k(i, j + 1), k(i + 1, j + 1)]);
            triangles.push([k(i, j), k(i + 1, j + 1), k(i + 1, j)]);
        }
    }
    cliffmap::cells::CellMesh {
        surface_vertices: positions.len() as u32,
        surface_triangles: triangles.len() as u32,
        positions,
        uvs: Some(uvs),
        triangles,
    }
}

/// PNG bytes of `img`.
fn png(img: impl Into<image::DynamicImage>) -> Vec<u8> {
    let mut c = std::io::Cursor::new(Vec::new());
    img.into()
        .write_to(&mut c, image::ImageFormat::Png)
        .unwrap();
    c.into_inner()
}

/// Rewrites the manifest of the store in `dir` after `edit(record, cell_texels)` on each cell.
fn edit_cells(dir: &Path, mut edit: impl FnMut(&mut cliffmap::store::CellRecord, u32)) {
    let path = dir.join("manifest.json");
    let mut m: cliffmap::store::Manifest =
        serde_json::from_str(&std::fs::read_to_string(&path).unwrap()).unwrap();
    for rec in &mut m.cells {
        edit(rec, m.cell_texels);
    }
    let text = serde_json::to_string_pretty(&m).unwrap();
    cliffmap::fsutil::write_atomic(&path, text.as_bytes()).unwrap();
}

/// A chart record for `rec`: the 8 × 8 grid mesh (written to `dir`) with `texture` of
/// `texels` texels as the chart's own texture.
fn chart(
    dir: &Path,
    rec: &cliffmap::store::CellRecord,
    texels: u32,
    texture: cliffmap::store::FileRef,
) -> cliffmap::store::ReparamRecord {
    let stem = cell_stem(rec.level, rec.x, rec.y);
    let mesh = grid_mesh(rec, 8);
    let mesh_file = write_file(dir, &format!("{stem}.uv.mesh"), &mesh.to_bytes()).unwrap();
    cliffmap::store::ReparamRecord {
        texels,
        files: cliffmap::store::CellFiles {
            mesh: mesh_file,
            texture,
            normal: rec.files.normal.clone(),
        },
        metrics: Default::default(),
        rel_texel: 1.0,
        texel_stretch: Default::default(),
        bilinear_fallbacks: 0,
    }
}

/// Makes every cell of the store in `dir` a chart (the grid mesh with stored texture
/// coordinates, its texture as the chart's own) drawn with a photo texture twice its size:
/// the chart texture magnified, as the projection leaves texels no photo reached, with the
/// photo share `confidence` (0..255) in every texel.
fn make_photo_charts(dir: &Path, confidence: u8) {
    edit_cells(dir, |rec, texels| {
        let stem = cell_stem(rec.level, rec.x, rec.y);
        let photo = cliffmap::store::magnify(&ramp(texels), 2);
        let conf = image::GrayImage::from_pixel(2 * texels, 2 * texels, image::Luma([confidence]));
        let texture = write_file(dir, &format!("{stem}.photo.png"), &png(photo)).unwrap();
        let confidence = write_file(dir, &format!("{stem}.conf.png"), &png(conf)).unwrap();
        rec.reparam = Some(chart(dir, rec, texels, rec.files.texture.clone()));
        rec.photo = Some(cliffmap::store::PhotoCellRecord {
            texels: 2 * texels,
            texture,
            confidence,
            photo_texels: 0,
            steep_texels: 0,
            steep_photo_texels: 0,
            blocks: None,
        });
    });
}

#[test]
fn on_photo_charts_only_the_chart_textures_share_follows_the_relief() {
    let z = 1234.0;
    let (v, range) = (223u8, 8.0);
    let r = (v as f64 / 255.0 * 2.0 - 1.0) * range;
    let raised = tempfile::tempdir().unwrap();
    store(raised.path(), z + r, None);
    let centre = DVec3::new(X0 + 50.0, Y0 - 50.0, z);
    let pos = centre + DVec3::new(-30.0, -25.0, 48.0);
    let rot = rotation_look_at(pos, centre).unwrap();
    let cam = CameraModel::with_fov(pos, rot, SIZE, SIZE, 50f64.to_radians());
    let raised_img = render_as(raised.path(), false, &cam, UvMode::Reparam);
    // photo share 0: the texture is the chart's own everywhere, so it moves like the chart
    let base = tempfile::tempdir().unwrap();
    store(base.path(), z, Some((v, range)));
    make_photo_charts(base.path(), 0);
    let off = mean_diff(
        &render_as(base.path(), false, &cam, UvMode::Photo),
        &raised_img,
    );
    let on = mean_diff(
        &render_as(base.path(), true, &cam, UvMode::Photo),
        &raised_img,
    );
    eprintln!("photo share 0: relief on {on:.3}, off {off:.3} from the raised surface");
    assert!(off > 3.0, "the test scene must show the shift: {off}");
    assert!(on < 0.1 * off && on < 0.6, "relief on: {on}, off: {off}");
    // photo share 1: the photo's colour stays where the projection put it (on the TIN)
    let photo = tempfile::tempdir().unwrap();
    store(photo.path(), z, Some((v, range)));
    make_photo_charts(photo.path(), 255);
    let unmapped = render_as(photo.path(), false, &cam, UvMode::Photo);
    let mapped = render_as(photo.path(), true, &cam, UvMode::Photo);
    let moved = mean_diff(&mapped, &unmapped);
    eprintln!("photo share 1: relief on vs off {moved:.3}");
    assert!(moved < 0.05, "photo colour moved: {moved}");
    assert!(mean_diff(&mapped, &raised_img) > 3.0);
}

/// Makes every cell of the store in `dir` a chart (the 8 × 8 grid mesh) whose own texture is
/// the ramp at `texels` texels with blue `blue`, so that a render tells which texture it read.
fn make_charts(dir: &Path, texels: u32, blue: u8) {
    edit_cells(dir, |rec, _| {
        let stem = cell_stem(rec.level, rec.x, rec.y);
        let mut tex = ramp(texels);
        tex.pixels_mut().for_each(|p| p.0[2] = blue);
        let texture = write_file(dir, &format!("{stem}.chart.png"), &png(tex)).unwrap();
        rec.reparam = Some(chart(dir, rec, texels, texture));
    });
}

/// Mean blue over the central half of the frame.
fn mean_blue(img: &image::RgbaImage) -> f64 {
    let (lo, hi) = (SIZE / 4, 3 * SIZE / 4);
    let mut sum = 0.0;
    for y in lo..hi {
        for x in lo..hi {
            sum += img.get_pixel(x, y).0[2] as f64;
        }
    }
    sum / ((hi - lo) * (hi - lo)) as f64
}

#[test]
fn relief_mapped_charts_read_the_finer_of_chart_and_orthographic_texture() {
    let z = 1234.0;
    let centre = DVec3::new(X0 + 50.0, Y0 - 50.0, z);
    let pos = centre + DVec3::new(-30.0, -25.0, 48.0);
    let rot = rotation_look_at(pos, centre).unwrap();
    let cam = CameraModel::with_fov(pos, rot, SIZE, SIZE, 50f64.to_radians());
    // the orthographic texture is the ramp at 64 texels with blue 90; flat charts of 16 and
    // of 256 texels with blue 200
    for (texels, expect_ortho) in [(16, true), (256, false)] {
        let dir = tempfile::tempdir().unwrap();
        store(dir.path(), z, Some((223, 8.0)));
        make_charts(dir.path(), texels, 200);
        let on = mean_blue(&render_as(dir.path(), true, &cam, UvMode::Reparam));
        let off = mean_blue(&render_as(dir.path(), false, &cam, UvMode::Reparam));
        eprintln!(
            "chart of {texels} texels: mean blue {on:.1} with relief mapping, {off:.1} without"
        );
        // without relief mapping the chart is drawn as it is
        assert!((off - 200.0).abs() < 1.0, "{off}");
        let want = if expect_ortho { 90.0 } else { 200.0 };
        assert!(
            (on - want).abs() < 1.0,
            "chart of {texels}: {on}, want {want}"
        );
    }
}

#[test]
fn the_photo_share_overlay_shows_each_texels_share() {
    let dir = tempfile::tempdir().unwrap();
    store(dir.path(), 0.0, Some((128, 4.0)));
    make_photo_charts(dir.path(), 200);
    let centre = DVec3::new(X0 + 50.0, Y0 - 50.0, 0.0);
    let pos = centre + DVec3::new(0.0, 0.0, 120.0);
    let cam = CameraModel::with_fov(
        pos,
        rotation_look_at(pos, centre).unwrap(),
        SIZE,
        SIZE,
        40f64.to_radians(),
    );
    let at_centre = |mode| {
        let img = render_overlay(dir.path(), true, &cam, mode, Overlay::PhotoShare);
        img.get_pixel(SIZE / 2, SIZE / 2).0
    };
    let near = |a: [u8; 4], b: [u8; 4]| (0..3).all(|k| (a[k] as i32 - b[k] as i32).abs() <= 2);
    // the photo texture's layout is the chart's: its share shows wherever charts are drawn
    for mode in [UvMode::Photo, UvMode::Mixed] {
        let c = at_centre(mode);
        assert!(near(c, share_colour(200)), "{mode:?}: {c:?}");
    }
    // in the orthographic layout the chart's share map does not fit: no photo shown
    let c = at_centre(UvMode::Ortho);
    assert!(near(c, NO_PHOTO_COLOUR), "{c:?}");
}

#[test]
fn a_store_without_relief_maps_renders_as_before() {
    let dir = tempfile::tempdir().unwrap();
    store(dir.path(), 500.0, None);
    let centre = DVec3::new(X0 + 50.0, Y0 - 50.0, 500.0);
    let pos = centre + DVec3::new(-30.0, -25.0, 48.0);
    let rot = rotation_look_at(pos, centre).unwrap();
    let cam = CameraModel::with_fov(pos, rot, SIZE, SIZE, 50f64.to_radians());
    assert_eq!(
        render(dir.path(), true, &cam),
        render(dir.path(), false, &cam)
    );
}
