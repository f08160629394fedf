//! Headless GPU rendering of hand-built stores (Mesa lavapipe/llvmpipe in CI). These tests
//! fail, never skip, when no adapter is available.

mod render_support;

use cliffmap::camera::{CameraModel, rotation_look_at};
use cliffmap::render::{FrameOptions, SceneOptions, StoreRenderer, UvMode};
use glam::DVec3;
use render_support::{Synth, X0, Y0, write_store};

const SKY: [u8; 3] = [170, 200, 235];

fn open(dir: &std::path::Path, size: u32, lit: bool, mode: UvMode) -> StoreRenderer {
    let opts = SceneOptions {
        uv_mode: mode,
        frame: FrameOptions {
            lit,
            sky: SKY,
            ..Default::default()
        },
        ..Default::default()
    };
    StoreRenderer::open(dir, size, size, opts).unwrap_or_else(|e| {
        panic!("cannot open a headless GPU scene: {e}\n(install Mesa: apt-get install mesa-vulkan-drivers libegl1 libegl-mesa0 libgl1-mesa-dri)")
    })
}

fn looking_down(centre: DVec3, height: f64, size: u32) -> CameraModel {
    let pos = centre + DVec3::new(0.0, 0.0, height);
    let r = rotation_look_at(pos, centre).unwrap();
    CameraModel::with_fov(pos, r, size, size, 60f64.to_radians())
}

/// One flat 100-m cell at z = 0 with 16-texel textures.
fn one_cell() -> Synth {
    Synth {
        levels: 1,
        size: 100.0,
        z: 0.0,
        finest_error: 0.1,
        texels: 16,
    }
}

fn close(a: [u8; 4], b: [u8; 3], tol: i32) -> bool {
    (0..3).all(|i| (a[i] as i32 - b[i] as i32).abs() <= tol)
}

#[test]
fn unlit_flat_cell_shows_its_texture_and_sky_elsewhere() {
    let dir = tempfile::tempdir().unwrap();
    let s = Synth {
        levels: 1,
        size: 100.0,
        z: 1234.0,
        finest_error: 0.1,
        texels: 32,
    };
    let colour = [200u8, 60, 30, 255];
    write_store(dir.path(), &s, |_| colour, |_| false);
    let mut scene = open(dir.path(), 128, false, UvMode::Mixed);
    let centre = DVec3::new(X0 + 50.0, Y0 - 50.0, 1234.0);
    let cam = looking_down(centre, 100.0, 128);
    let r = scene.frame(&cam, true).unwrap();
    assert_eq!((r.drawn, r.holes), (1, 0));
    assert_eq!(r.triangles, 10, "2 surface + 8 skirt triangles");
    let img = scene.read_rgba().unwrap();
    for (x, y) in [(64, 64), (40, 40), (90, 70)] {
        let p = img.get_pixel(x, y).0;
        assert!(
            close(p, [200, 60, 30], 2),
            "pixel ({x},{y}) = {p:?}, want the texture colour"
        );
    }
    for (x, y) in [(0, 0), (127, 0), (0, 127), (127, 127)] {
        let p = img.get_pixel(x, y).0;
        assert!(close(p, SKY, 2), "corner ({x},{y}) = {p:?}, want sky");
    }
    // The cell's edges land where the f64 camera model projects them (no UTM jitter):
    // the west edge x = X0 maps to column u; pixels left of it are sky, right of it texture.
    let u = cam.project(DVec3::new(X0, Y0 - 50.0, 1234.0)).unwrap()[0];
    let (left, right) = ((u - 1.5).round() as u32, (u + 1.5).round() as u32);
    assert!(
        close(img.get_pixel(left, 64).0, SKY, 2),
        "left of the edge at {u:.2}"
    );
    assert!(
        close(img.get_pixel(right, 64).0, [200, 60, 30], 2),
        "right of the edge at {u:.2}"
    );
}

#[test]
fn refines_to_children_and_draws_stored_uvs() {
    let dir = tempfile::tempdir().unwrap();
    let s = Synth {
        levels: 2,
        size: 100.0,
        z: 500.0,
        finest_error: 0.05,
        texels: 64,
    };
    let colours = |x: u32, y: u32| -> [u8; 4] {
        [
            [30, 160, 40, 255],
            [40, 60, 200, 255],
            [220, 200, 40, 255],
            [120, 30, 140, 255],
        ][(y * 2 + x) as usize]
    };
    // Level-1 cells are coloured by quadrant; the NE one is stored with explicit UVs.
    write_store(
        dir.path(),
        &s,
        |r| {
            if r.level == 0 {
                [255, 255, 255, 255]
            } else {
                colours(r.x, r.y)
            }
        },
        |r| r.level == 1 && r.x == 1 && r.y == 0,
    );
    let centre = DVec3::new(X0 + 50.0, Y0 - 50.0, 500.0);
    for mode in [UvMode::Mixed, UvMode::Ortho, UvMode::Reparam] {
        let mut scene = open(dir.path(), 96, false, mode);
        let cam = looking_down(centre, 95.0, 96);
        let r = scene.frame(&cam, true).unwrap();
        assert_eq!(
            r.drawn, 4,
            "{mode:?}: the root should be refined into its 4 children"
        );
        let img = scene.read_rgba().unwrap();
        // North is up, east is right.
        for (x, y, want) in [
            (30, 30, colours(0, 0)),
            (66, 30, colours(1, 0)),
            (30, 66, colours(0, 1)),
            (66, 66, colours(1, 1)),
        ] {
            let p = img.get_pixel(x, y).0;
            assert!(
                close(p, [want[0], want[1], want[2]], 2),
                "{mode:?}: pixel ({x},{y}) = {p:?}, want {want:?}"
            );
        }
        // From far away the root (white) is enough.
        let far = looking_down(centre, 5000.0, 96);
        let r = scene.frame(&far, true).unwrap();
        assert_eq!(r.drawn, 1);
        assert!(close(
            scene.read_rgba().unwrap().get_pixel(48, 48).0,
            [255, 255, 255],
            2
        ));
    }
}

#[test]
fn lighting_darkens_surfaces_facing_away_from_the_sun() {
    let dir = tempfile::tempdir().unwrap();
    let s = one_cell();
    write_store(dir.path(), &s, |_| [200, 200, 200, 255], |_| false);
    let cam = looking_down(DVec3::new(X0 + 50.0, Y0 - 50.0, 0.0), 100.0, 64);
    let mut lit_high = open(dir.path(), 64, true, UvMode::Mixed);
    let high = lit_high
        .frame(&cam, true)
        .and_then(|_| lit_high.read_rgba())
        .unwrap()
        .get_pixel(32, 32)
        .0;
    let opts = SceneOptions {
        frame: FrameOptions {
            lit: true,
            sun_dir: DVec3::new(1.0, 0.0, 0.2),
            ..Default::default()
        },
        ..Default::default()
    };
    let mut low_sun = StoreRenderer::open(dir.path(), 64, 64, opts).unwrap();
    let low = low_sun
        .frame(&cam, true)
        .and_then(|_| low_sun.read_rgba())
        .unwrap()
        .get_pixel(32, 32)
        .0;
    assert!(
        high[0] <= 200 && low[0] < high[0],
        "sun high {high:?}, sun low {low:?}"
    );
}

#[test]
fn corrupt_cells_fail_with_the_file_named() {
    let dir = tempfile::tempdir().unwrap();
    let s = one_cell();
    let m = write_store(dir.path(), &s, |_| [1, 2, 3, 255], |_| false);
    let mesh = dir.path().join(&m.cells[0].files.mesh.path);
    std::fs::write(&mesh, b"CLIFMESH garbage").unwrap();
    let mut scene = open(dir.path(), 32, false, UvMode::Mixed);
    let cam = looking_down(DVec3::new(X0 + 50.0, Y0 - 50.0, 0.0), 100.0, 32);
    let e = scene.frame(&cam, true).unwrap_err().to_string();
    assert!(e.contains("0-0.mesh"), "{e}");
}

#[test]
fn uploads_name_the_texture_they_cannot_take_and_share_placeholders() {
    use cliffmap::render::{CellData, GpuContext, TerrainRenderer};
    let s = one_cell();
    let rec = render_support::record(
        &s,
        cliffmap::cells::CellKey {
            level: 0,
            x: 0,
            y: 0,
        },
    );
    let ctx = GpuContext::new().unwrap_or_else(|e| panic!("no headless GPU: {e}"));
    let renderer = TerrainRenderer::new(ctx, 32, 32).unwrap();
    let data = || {
        CellData::new(
            &rec,
            render_support::flat_mesh(&rec, false),
            image::RgbaImage::from_pixel(16, 16, image::Rgba([10, 20, 30, 255])),
            image::RgbImage::from_pixel(16, 16, image::Rgb([128, 128, 255])),
            UvMode::Mixed,
        )
    };
    // cells without relief map, chart or orthographic texture all upload (one shared
    // placeholder of each kind, counted in no cell's bytes)
    let plain = renderer.upload(&rec, &data()).unwrap();
    let again = renderer.upload(&rec, &data()).unwrap();
    assert_eq!(plain.bytes, again.bytes);
    let mut with_ortho = data();
    with_ortho.ortho_mips = Some(vec![image::RgbaImage::new(8, 8)]);
    let extra = renderer.upload(&rec, &with_ortho).unwrap();
    assert_eq!(extra.bytes, plain.bytes + 8 * 8 * 4);
    // an empty optional texture is an error naming it, not a panic
    let upload_error = |bad| {
        renderer
            .upload(&rec, &bad)
            .map(|_| ())
            .unwrap_err()
            .to_string()
    };
    let mut bad = data();
    bad.ortho_mips = Some(Vec::new());
    let e = upload_error(bad);
    assert!(e.contains("orthographic texture of 0x0"), "{e}");
    let mut bad = data();
    bad.base_mips = Some(vec![image::RgbaImage::new(0, 4)]);
    let e = upload_error(bad);
    assert!(e.contains("chart texture of 0x4"), "{e}");
}
