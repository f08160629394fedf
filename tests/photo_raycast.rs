//! Ray casting of photo pixel corners against synthetic scenes: analytic texture positions
//! on a flat wall, occlusion, cameras that see nothing, grazing rays, reconstruction across
//! cell borders, silhouette rejection, UTM-sized coordinates and thread-count independence.

use cliffmap::camera::{CameraModel, rotation_look_at};
use cliffmap::photo::{FootprintOptions, FootprintSet, PixelFootprint, photo_footprints};
use cliffmap::raycast::{BvhQuality, LevelScene, RayAccel, SceneCell};
use glam::DVec3;

const TEXELS: u32 = 64;

/// Every test runs with both accelerations: the default camera-space grid and a BVH.
fn accels() -> [RayAccel; 3] {
    [
        RayAccel::default(),
        RayAccel::parse("grid:1").unwrap(),
        BvhQuality::Fast.into(),
    ]
}

/// A vertical wall in the plane y = `y` (front face towards −y) over x ∈ [x0, x1],
/// z ∈ [z0, z1], as an n × n grid, translated by `shift`. Texture: x right from x0, y down
/// from z1, `TEXELS / (x1 − x0)` texels per metre on both axes.
#[allow(clippy::too_many_arguments)] // a test helper: the wall's extent, spelled out
fn wall(cell: u32, x0: f64, x1: f64, y: f64, z0: f64, z1: f64, n: u32, shift: DVec3) -> SceneCell {
    let s = TEXELS as f64 / (x1 - x0);
    let mut positions = Vec::new();
    let mut texcoords = Vec::new();
    for j in 0..=n {
        for i in 0..=n {
            let (x, z) = (
                x0 + (x1 - x0) * i as f64 / n as f64,
                z0 + (z1 - z0) * j as f64 / n as f64,
            );
            positions.push([(x - x0) as f32, 0.0, (z - z0) as f32]);
            texcoords.push([((x - x0) * s) as f32, ((z1 - z) * s) as f32]);
        }
    }
    let mut triangles = Vec::new();
    let v = |i: u32, j: u32| j * (n + 1) + i;
    for j in 0..n {
        for i in 0..n {
            // Counter-clockwise in (x, z): normal towards −y.
            triangles.push([v(i, j), v(i + 1, j), v(i + 1, j + 1)]);
            triangles.push([v(i, j), v(i + 1, j + 1), v(i, j + 1)]);
        }
    }
    SceneCell {
        cell,
        origin: DVec3::new(x0, y, z0) + shift,
        positions,
        triangles,
        texcoords,
        texels: TEXELS,
    }
}

/// A heightfield cell over [x0, x0+size] × [y0, y0+size] (n × n quads), orthographic texture
/// (x right, y down from the north edge), translated by `shift`.
fn heightfield(
    cell: u32,
    x0: f64,
    y0: f64,
    size: f64,
    n: u32,
    shift: DVec3,
    z: impl Fn(f64, f64) -> f64,
) -> SceneCell {
    let s = TEXELS as f64 / size;
    let mut positions = Vec::new();
    let mut texcoords = Vec::new();
    for j in 0..=n {
        for i in 0..=n {
            let (x, y) = (
                x0 + size * i as f64 / n as f64,
                y0 + size * j as f64 / n as f64,
            );
            positions.push([(x - x0) as f32, (y - y0) as f32, z(x, y) as f32]);
            texcoords.push([((x - x0) * s) as f32, ((y0 + size - y) * s) as f32]);
        }
    }
    let mut triangles = Vec::new();
    let v = |i: u32, j: u32| j * (n + 1) + i;
    for j in 0..n {
        for i in 0..n {
            triangles.push([v(i, j), v(i + 1, j), v(i + 1, j + 1)]);
            triangles.push([v(i, j), v(i + 1, j + 1), v(i, j + 1)]);
        }
    }
    SceneCell {
        cell,
        origin: DVec3::new(x0, y0, 0.0) + shift,
        positions,
        triangles,
        texcoords,
        texels: TEXELS,
    }
}

fn camera(pos: DVec3, target: DVec3, w: u32, h: u32, fov_deg: f64) -> CameraModel {
    CameraModel::with_fov(
        pos,
        rotation_look_at(pos, target).unwrap(),
        w,
        h,
        fov_deg.to_radians(),
    )
}

/// Two wall cells meeting at x = 10 (cells 0 and 1), at y = 30.
fn two_walls(shift: DVec3) -> Vec<SceneCell> {
    vec![
        wall(0, 0.0, 10.0, 30.0, 0.0, 10.0, 4, shift),
        wall(1, 10.0, 20.0, 30.0, 0.0, 10.0, 4, shift),
    ]
}

fn wall_camera(shift: DVec3) -> CameraModel {
    // Off-centre so that the cell border x = 10 does not run exactly through a corner column.
    let mut c = camera(
        DVec3::new(10.07, 0.0, 5.0) + shift,
        DVec3::new(10.07, 30.0, 5.0) + shift,
        80,
        60,
        15.0,
    );
    c.k1 = -0.05; // exercise the undistortion
    c
}

/// Analytic texture position of pixel position (u, v) on wall cell `cell` (x0 = 10·cell).
fn wall_tex(cam: &CameraModel, shift: DVec3, cell: u32, u: f64, v: f64) -> [f64; 2] {
    let d = cam.pixel_ray(u, v).unwrap();
    let o = cam.position - shift;
    let p = o + d * ((30.0 - o.y) / d.y);
    let s = TEXELS as f64 / 10.0;
    [(p.x - 10.0 * cell as f64) * s, (10.0 - p.z) * s]
}

fn corner_uv(fp: &PixelFootprint, k: usize) -> (f64, f64) {
    let [dc, dr] = [[0, 0], [1, 0], [1, 1], [0, 1]][k];
    (
        (fp.pixel[0] + dc) as f64 - 0.5,
        (fp.pixel[1] + dr) as f64 - 0.5,
    )
}

fn check_sorted(set: &FootprintSet) {
    let all: Vec<&PixelFootprint> = set.iter().collect();
    for w in all.windows(2) {
        let key = |f: &PixelFootprint| (f.cell, f.pixel[1], f.pixel[0]);
        assert!(
            key(w[0]) < key(w[1]),
            "footprints not sorted by (cell, row, col)"
        );
    }
    assert_eq!(
        set.pixels_hit,
        set.len() as u64 + set.rejected_silhouette + set.dropped
    );
}

#[test]
fn flat_wall_gives_analytic_texture_positions_and_reconstructs_the_cell_border() {
    for accel in accels() {
        let shift = DVec3::ZERO;
        let cam = wall_camera(shift);
        let scene = LevelScene::new(two_walls(shift), cam.position, accel);
        let set = photo_footprints(&scene, &cam, &FootprintOptions::default());
        check_sorted(&set);
        // The wall fills the view (it spans ±10.6 m × ±5 m around the axis, the view ±5.3 m × ±4 m).
        assert_eq!(set.pixels_hit, 80 * 60);
        assert_eq!(set.rejected_silhouette, 0);
        assert_eq!(set.dropped, 0);
        assert_eq!(set.len(), 80 * 60);
        for fp in set.iter() {
            for k in 0..4 {
                let (u, v) = corner_uv(fp, k);
                let t = wall_tex(&cam, shift, fp.cell, u, v);
                let got = fp.corners[k];
                // Reconstructed corners extend the cell's affine map: the same analytic value.
                assert!(
                    (got[0] as f64 - t[0]).abs() < 2e-3 && (got[1] as f64 - t[1]).abs() < 2e-3,
                    "{fp:?} corner {k}: {t:?}"
                );
            }
            let d = cam
                .pixel_ray(fp.pixel[0] as f64, fp.pixel[1] as f64)
                .unwrap();
            assert!(
                (fp.cos_view as f64 - d.y).abs() < 1e-3,
                "cos {} vs {}",
                fp.cos_view,
                d.y
            );
            assert!((fp.distance as f64 - 30.0 / d.y).abs() < 1e-2);
        }
        // The column of pixels over x = 10 has corners in both cells: reconstructed.
        assert!(
            set.reconstructed >= 60,
            "reconstructed {}",
            set.reconstructed
        );
        assert_eq!(
            set.reconstructed,
            set.iter().filter(|f| f.reconstructed > 0).count() as u64
        );

        // Without reconstruction those pixels are dropped.
        let opts = FootprintOptions {
            reconstruct: false,
            ..FootprintOptions::default()
        };
        let plain = photo_footprints(&scene, &cam, &opts);
        check_sorted(&plain);
        assert_eq!(plain.reconstructed, 0);
        assert_eq!(plain.len() as u64, set.len() as u64 - set.reconstructed);
        assert_eq!(plain.dropped, set.reconstructed);
    }
}

#[test]
fn utm_sized_coordinates_give_the_same_footprints() {
    for accel in accels() {
        let near = photo_footprints(
            &LevelScene::new(
                two_walls(DVec3::ZERO),
                wall_camera(DVec3::ZERO).position,
                accel,
            ),
            &wall_camera(DVec3::ZERO),
            &FootprintOptions::default(),
        );
        let shift = DVec3::new(431_000.0, 6_878_000.0, 0.0);
        let cam = wall_camera(shift);
        let far = photo_footprints(
            &LevelScene::new(
                two_walls(shift),
                cam.position + DVec3::new(3.0, -2.0, 1.0),
                accel,
            ),
            &cam,
            &FootprintOptions::default(),
        );
        assert_eq!(near.len(), far.len());
        assert_eq!(
            (near.pixels_hit, near.reconstructed, near.dropped),
            (far.pixels_hit, far.reconstructed, far.dropped)
        );
        for (a, b) in near.iter().zip(far.iter()) {
            assert_eq!(
                (a.cell, a.pixel, a.reconstructed),
                (b.cell, b.pixel, b.reconstructed)
            );
            for k in 0..4 {
                assert!(
                    (a.corners[k][0] - b.corners[k][0]).abs() < 2e-3
                        && (a.corners[k][1] - b.corners[k][1]).abs() < 2e-3
                );
            }
            assert!((a.distance - b.distance).abs() < 1e-3);
        }
    }
}

#[test]
fn cameras_facing_away_or_behind_the_surface_see_nothing() {
    for accel in accels() {
        let scene = LevelScene::new(two_walls(DVec3::ZERO), DVec3::new(10.0, 0.0, 5.0), accel);
        // Facing away from the wall.
        let away = camera(
            DVec3::new(10.0, 0.0, 5.0),
            DVec3::new(10.0, -30.0, 5.0),
            40,
            30,
            40.0,
        );
        let set = photo_footprints(&scene, &away, &FootprintOptions::default());
        assert_eq!(set, FootprintSet::default());
        // Behind the wall, looking at its back face.
        let behind = camera(
            DVec3::new(10.0, 60.0, 5.0),
            DVec3::new(10.0, 30.0, 5.0),
            40,
            30,
            40.0,
        );
        let set = photo_footprints(&scene, &behind, &FootprintOptions::default());
        assert_eq!(set, FootprintSet::default());
        // Below a terrain, looking up.
        let ground = LevelScene::new(
            vec![heightfield(0, 0.0, 0.0, 40.0, 8, DVec3::ZERO, |x, y| {
                0.1 * x + 0.05 * y
            })],
            DVec3::new(20.0, 20.0, -10.0),
            accel,
        );
        let below = camera(
            DVec3::new(20.0, 20.0, -10.0),
            DVec3::new(21.0, 20.0, 10.0),
            40,
            30,
            60.0,
        );
        assert_eq!(
            photo_footprints(&ground, &below, &FootprintOptions::default()),
            FootprintSet::default()
        );
        // The same terrain seen from above is seen.
        let above = camera(
            DVec3::new(20.0, 20.0, 30.0),
            DVec3::new(21.0, 20.0, 0.0),
            40,
            30,
            60.0,
        );
        assert!(!photo_footprints(&ground, &above, &FootprintOptions::default()).is_empty());
    }
}

#[test]
fn an_occluding_wall_hides_what_is_behind_it() {
    for accel in accels() {
        let mut cells = two_walls(DVec3::ZERO);
        // Occluder (cell 2) at y = 20 over x ∈ [8, 12], z ∈ [3, 7].
        cells.push(wall(2, 8.0, 12.0, 20.0, 3.0, 7.0, 2, DVec3::ZERO));
        let cam = wall_camera(DVec3::ZERO);
        let scene = LevelScene::new(cells, cam.position, accel);
        let set = photo_footprints(&scene, &cam, &FootprintOptions::default());
        check_sorted(&set);
        let hits_occluder = |u: f64, v: f64| {
            let d = cam.pixel_ray(u, v).unwrap();
            let p = cam.position + d * ((20.0 - cam.position.y) / d.y);
            (8.0..=12.0).contains(&p.x) && (3.0..=7.0).contains(&p.z)
        };
        let mut front = 0;
        for fp in set.iter() {
            let any = (0..4).any(|k| {
                let (u, v) = corner_uv(fp, k);
                hits_occluder(u, v)
            });
            let all = (0..4).all(|k| {
                let (u, v) = corner_uv(fp, k);
                hits_occluder(u, v)
            });
            if fp.cell == 2 {
                front += 1;
                assert!(any, "occluder footprint {fp:?} away from the occluder");
            } else {
                assert!(!any, "wall footprint {fp:?} behind the occluder");
            }
            if all {
                assert_eq!(fp.cell, 2);
            }
        }
        assert!(front > 100, "occluder footprints {front}");
        // The occluder's outline is a depth jump between cells: rejected, not reconstructed.
        assert!(set.rejected_silhouette > 0);
    }
}

#[test]
fn grazing_rays_give_no_nan_and_no_huge_footprints() {
    for accel in accels() {
        // Flat ground seen from 0.5 m above, looking almost along it.
        let cells: Vec<SceneCell> = (0..4)
            .map(|i| heightfield(i, 0.0, 50.0 * i as f64, 50.0, 10, DVec3::ZERO, |_, _| 0.0))
            .collect();
        let cam = camera(
            DVec3::new(25.0, -1.0, 0.5),
            DVec3::new(25.0, 200.0, 0.0),
            120,
            90,
            40.0,
        );
        let scene = LevelScene::new(cells, cam.position, accel);
        let opts = FootprintOptions::default();
        let set = photo_footprints(&scene, &cam, &opts);
        check_sorted(&set);
        assert!(!set.is_empty());
        assert!(set.dropped > 0, "grazing footprints should be dropped");
        for fp in set.iter() {
            assert!(fp.corners.iter().flatten().all(|c| c.is_finite()), "{fp:?}");
            assert!(fp.cos_view.is_finite() && fp.cos_view > 0.0 && fp.cos_view <= 1.0);
            assert!(fp.distance.is_finite() && fp.distance > 0.0);
            let c = fp.corners;
            let area = 0.5
                * (0..4)
                    .map(|k| c[k][0] * c[(k + 1) % 4][1] - c[(k + 1) % 4][0] * c[k][1])
                    .sum::<f32>()
                    .abs();
            assert!(area <= opts.max_area, "area {area}");
            for (a, b) in [(0, 1), (1, 2), (2, 3), (3, 0), (0, 2), (1, 3)] {
                let l = ((c[a][0] - c[b][0]).powi(2) + (c[a][1] - c[b][1]).powi(2)).sqrt();
                assert!(l <= opts.max_extent * 1.0001, "extent {l}");
            }
        }
    }
}

/// A ridge along x at y = 15 (5 m high, 45° flanks) in one cell; camera in front of it,
/// high enough to see the ground behind the ridge over its crest.
fn ridge_scene(accel: RayAccel) -> (LevelScene, CameraModel) {
    let ridge = |_: f64, y: f64| (5.0 - (y - 15.0).abs()).max(0.0);
    let cell = heightfield(0, 0.0, 0.0, 40.0, 40, DVec3::ZERO, ridge);
    let cam = camera(
        DVec3::new(20.0, -20.0, 15.0),
        DVec3::new(20.0, 20.0, 2.0),
        96,
        72,
        40.0,
    );
    (LevelScene::new(vec![cell], cam.position, accel), cam)
}

#[test]
fn silhouette_pixels_are_rejected_and_counted() {
    for accel in accels() {
        let (scene, cam) = ridge_scene(accel);
        let set = photo_footprints(&scene, &cam, &FootprintOptions::default());
        check_sorted(&set);
        assert!(
            set.rejected_silhouette >= 40,
            "rejected {}",
            set.rejected_silhouette
        );
        // The rejected pixels lie on the crest line: each column of the image has at most a
        // few, and the crest (y = 15, z = 5) projects into them.
        let off = FootprintOptions {
            reject_silhouettes: false,
            ..FootprintOptions::default()
        };
        let all = photo_footprints(&scene, &cam, &off);
        assert_eq!(all.rejected_silhouette, 0);
        assert_eq!(all.len() as u64, set.len() as u64 + set.rejected_silhouette);
        let kept: std::collections::HashSet<[u32; 2]> = set.iter().map(|f| f.pixel).collect();
        let mut per_column = vec![0u32; 96];
        for fp in all.iter().filter(|f| !kept.contains(&f.pixel)) {
            per_column[fp.pixel[0] as usize] += 1;
            // The crest projects within a pixel or two of the rejected pixel.
            let x = fp.pixel[0] as f64;
            let crest_v = (0..=400)
                .filter_map(|i| cam.project(DVec3::new(-10.0 + 0.15 * i as f64, 15.0, 5.0)))
                .filter(|p| (p[0] - x).abs() < 0.6)
                .map(|p| p[1])
                .next()
                .unwrap();
            assert!(
                (fp.pixel[1] as f64 - crest_v).abs() < 2.5,
                "rejected {fp:?}, crest at v = {crest_v}"
            );
        }
        assert!(per_column.iter().all(|&n| n <= 4), "{per_column:?}");
    }
}

#[test]
fn results_do_not_depend_on_the_thread_count() {
    for accel in accels() {
        let (scene, cam) = ridge_scene(accel);
        let run = |threads: usize| {
            rayon::ThreadPoolBuilder::new()
                .num_threads(threads)
                .build()
                .unwrap()
                .install(|| photo_footprints(&scene, &cam, &FootprintOptions::default()))
        };
        assert_eq!(run(1), run(3));
    }
}

/// Deterministic pseudo-random numbers in [0, 1).
struct Lcg(u64);
impl Lcg {
    fn next(&mut self) -> f64 {
        self.0 = self
            .0
            .wrapping_mul(6364136223846793005)
            .wrapping_add(1442695040888963407);
        (self.0 >> 11) as f64 / (1u64 << 53) as f64
    }
}

#[test]
fn view_grid_finds_the_nearest_hit_of_every_corner_ray() {
    use cliffmap::raycast::{ViewGrid, ViewGridParams, nearest_brute_force};
    // A random triangle soup around a distorted camera: big and tiny triangles, triangles
    // behind the camera and crossing its image plane, at UTM-sized coordinates.
    let mut rng = Lcg(11);
    let centre = DVec3::new(431_017.3, 6_878_004.1, 612.0);
    let mut positions = Vec::new();
    let mut triangles = Vec::new();
    for k in 0..600u32 {
        let size = if k % 10 == 0 {
            30.0
        } else {
            0.2 + 3.0 * rng.next()
        };
        let c = DVec3::new(
            rng.next() * 80.0 - 40.0,
            rng.next() * 80.0 - 10.0,
            rng.next() * 40.0 - 20.0,
        );
        for _ in 0..3 {
            let p = c + DVec3::new(rng.next() - 0.5, rng.next() - 0.5, rng.next() - 0.5) * size;
            positions.push([p.x as f32, p.y as f32, p.z as f32]);
        }
        triangles.push([3 * k, 3 * k + 1, 3 * k + 2]);
    }
    let texcoords = vec![[0.0f32, 0.0]; positions.len()];
    let cell = SceneCell {
        cell: 0,
        origin: centre,
        positions: positions.clone(),
        triangles: triangles.clone(),
        texcoords,
        texels: TEXELS,
    };
    let mut cam = camera(
        centre + DVec3::new(0.3, -0.2, 0.1),
        centre + DVec3::new(2.0, 30.0, -3.0),
        64,
        48,
        70.0,
    );
    cam.k1 = -0.08;
    cam.k2 = 0.01;
    let scene = LevelScene::new(vec![cell], cam.position, BvhQuality::Fast);
    let tris: Vec<[glam::Vec3; 3]> = triangles
        .iter()
        .map(|t| {
            t.map(|i| {
                (centre - cam.position
                    + glam::DVec3::from_array(positions[i as usize].map(f64::from)))
                .as_vec3()
            })
        })
        .collect();
    let mut hits = 0;
    for bin_px in [1.0, 3.0, 8.0, 64.0] {
        let grid = ViewGrid::for_camera(&scene, &cam, ViewGridParams { bin_px });
        assert!(grid.stats().entries > 0);
        for j in 0..=48 {
            for i in 0..=64 {
                let d = cam
                    .pixel_ray(i as f64 - 0.5, j as f64 - 0.5)
                    .unwrap()
                    .as_vec3();
                // Scene triangle ids are the scene's own order: compare the source triangles.
                let g = grid.nearest(glam::Vec3::ZERO, d).map(|mut h| {
                    h.triangle = scene.triangle_source(h.triangle).unwrap().1 as u32;
                    h
                });
                let b = nearest_brute_force(&tris, glam::Vec3::ZERO, d, 0.0, f32::INFINITY);
                match (g, b) {
                    (Some(g), Some(b)) => {
                        hits += 1;
                        assert!(
                            g.triangle == b.triangle || (g.t - b.t).abs() <= 1e-5 * b.t,
                            "bin {bin_px}, corner ({i}, {j}): {g:?} vs {b:?}"
                        );
                    }
                    (None, None) => {}
                    _ => panic!("bin {bin_px}, corner ({i}, {j}): {g:?} vs {b:?}"),
                }
            }
        }
    }
    assert!(hits > 4 * 1000, "{hits} hits");
    // Rays outside the photo (not binned) are still answered exactly.
    let grid = ViewGrid::for_camera(&scene, &cam, ViewGridParams::default());
    for k in 0..200 {
        let d = glam::DVec3::new(rng.next() - 0.5, rng.next() - 0.5, rng.next() - 0.5)
            .normalize()
            .as_vec3();
        let g = grid
            .nearest(glam::Vec3::ZERO, d)
            .map(|h| scene.triangle_source(h.triangle).unwrap().1 as u32);
        let b =
            nearest_brute_force(&tris, glam::Vec3::ZERO, d, 0.0, f32::INFINITY).map(|h| h.triangle);
        assert_eq!(g, b, "ray {k}");
    }
}

#[test]
fn view_grid_and_bvh_give_the_same_footprints() {
    // A camera standing on rough ground (its triangles cross the image plane) looking at a
    // ridge, with distortion.
    let rough = |x: f64, y: f64| {
        (5.0 - (y - 15.0).abs()).max(0.0) + 0.3 * (x * 0.7).sin() * (y * 0.5).cos()
    };
    let cells: Vec<SceneCell> = (0..4)
        .map(|i| {
            heightfield(
                i,
                20.0 * (i % 2) as f64,
                -10.0 + 25.0 * (i / 2) as f64,
                20.0,
                24,
                DVec3::ZERO,
                rough,
            )
        })
        .collect();
    let mut cam = camera(
        DVec3::new(20.0, -9.0, 1.7),
        DVec3::new(22.0, 20.0, 1.0),
        160,
        120,
        75.0,
    );
    cam.k1 = -0.1;
    let run = |accel: RayAccel| {
        photo_footprints(
            &LevelScene::new(cells.clone(), cam.position, accel),
            &cam,
            &FootprintOptions::default(),
        )
    };
    let bvh = run(BvhQuality::Fast.into());
    assert!(
        bvh.len() > 5_000 && bvh.rejected_silhouette > 0,
        "{} {}",
        bvh.len(),
        bvh.rejected_silhouette
    );
    for accel in [
        RayAccel::default(),
        RayAccel::parse("grid:2").unwrap(),
        RayAccel::parse("grid:40").unwrap(),
    ] {
        assert_eq!(run(accel), bvh, "{}", accel.name());
    }
}

/// `LevelScene::last_rows` bounds the rows of every footprint a cell receives (what lets a
/// lone photo's cells be written before the rest of the photo is cast), with and without
/// radial distortion, and is not looser than the image.
#[test]
fn last_rows_bound_every_footprint_row() {
    // four terrain cells of a bumpy 80 m square, seen obliquely from one side
    let bumps = |x: f64, y: f64| 3.0 * (0.2 * x).sin() * (0.13 * y).cos() + 0.05 * y;
    let cells: Vec<SceneCell> = (0..4u32)
        .map(|k| {
            let (x0, y0) = (40.0 * (k % 2) as f64, 40.0 * (k / 2) as f64);
            heightfield(k, x0, y0, 40.0, 24, DVec3::ZERO, bumps)
        })
        .collect();
    for (k1, k2) in [(0.0, 0.0), (-0.25, 0.05), (0.2, 0.0)] {
        let mut cam = camera(
            DVec3::new(40.0, -25.0, 18.0),
            DVec3::new(40.0, 45.0, 0.0),
            160,
            120,
            70.0,
        );
        cam.k1 = k1;
        cam.k2 = k2;
        let scene = LevelScene::new(cells.clone(), cam.position, RayAccel::default());
        let bounds = scene.last_rows(&cam);
        let set = photo_footprints(&scene, &cam, &FootprintOptions::default());
        assert!(set.len() > 3000, "{} footprints", set.len());
        for (sc, bound) in scene.cells.iter().zip(&bounds) {
            let bound = bound.expect("every vertex is in front of the camera");
            assert!(bound <= cam.height + 2, "k1 {k1}: bound {bound}");
            let rows: Vec<u32> = set
                .cells
                .iter()
                .filter(|c| c.cell == sc.cell)
                .flat_map(|c| c.iter().map(|f| f.pixel[1]))
                .collect();
            let last = rows.iter().max().copied().unwrap_or(0);
            assert!(
                last <= bound,
                "k1 {k1} cell {}: row {last} past {bound}",
                sc.cell
            );
            // the near cells are bounded inside the image, within a few rows of their last
            if bound < cam.height {
                assert!(
                    bound - last <= 8,
                    "k1 {k1} cell {}: {bound} for {last}",
                    sc.cell
                );
            }
        }
        assert!(bounds.iter().any(|b| b.is_some_and(|b| b < cam.height)));
    }
    // a camera among the cells (vertices behind it): not bounded
    let inside = camera(
        DVec3::new(40.0, 40.0, 10.0),
        DVec3::new(40.0, 80.0, 0.0),
        64,
        48,
        60.0,
    );
    let scene = LevelScene::new(cells, inside.position, RayAccel::default());
    assert!(scene.last_rows(&inside).iter().any(Option::is_none));
}
