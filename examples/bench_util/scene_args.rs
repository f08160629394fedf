//! Command lines of the generated-scene benchmarks (`OUT [--flag value] [--switch]`) and
//! their deterministic random numbers.

use std::path::{Path, PathBuf};

use cliffmap::demo_scene::{DemoPhotoOptions, DemoScene};
use cliffmap::pipeline::{BuildInputs, BuildOptions, build_store};

/// The arguments after the program name: the output folder first, then flags.
pub struct SceneArgs {
    /// The output folder (first argument).
    pub out: PathBuf,
    args: Vec<String>,
}

impl SceneArgs {
    /// Reads the process arguments; `usage` is the error without an output folder.
    pub fn from_env(usage: &str) -> anyhow::Result<SceneArgs> {
        let args: Vec<String> = std::env::args().skip(1).collect();
        let out = PathBuf::from(
            args.first()
                .ok_or_else(|| anyhow::anyhow!("usage: {usage}"))?,
        );
        Ok(SceneArgs { out, args })
    }

    /// The value after `--name`, if given.
    pub fn flag(&self, name: &str) -> Option<&str> {
        self.args
            .iter()
            .position(|a| a == name)
            .and_then(|i| self.args.get(i + 1))
            .map(String::as_str)
    }

    /// The value after `--name` as two numbers `A,B` (`usage` names them in the error), if
    /// given.
    pub fn pair(&self, name: &str, usage: &str) -> anyhow::Result<Option<(f64, f64)>> {
        let Some(v) = self.flag(name) else {
            return Ok(None);
        };
        let (a, b) = v
            .split_once(',')
            .ok_or_else(|| anyhow::anyhow!("{name} wants {usage}"))?;
        Ok(Some((a.parse()?, b.parse()?)))
    }

    /// Whether the switch `--name` is given.
    pub fn has(&self, name: &str) -> bool {
        self.args.iter().any(|a| a == name)
    }

    /// `--scene demo|tall` (default demo), then the overrides that make a scene no one has
    /// tuned on: `--seed N` (the noise), `--relief PLATEAU,CANYON,ESCARPMENT` (wall heights,
    /// metres), `--photo-distance F` (factor on the cameras' distances).
    pub fn scene(&self) -> anyhow::Result<DemoScene> {
        let scene = match self.flag("--scene").unwrap_or("demo") {
            "demo" => DemoScene::default(),
            "tall" => DemoScene::tall_walls(),
            s => anyhow::bail!("unknown --scene {s} (demo or tall)"),
        };
        scene_overrides(scene, |n| self.flag(n))
    }
}

/// `scene` with the overrides `--seed N`, `--relief PLATEAU,CANYON,ESCARPMENT` and
/// `--photo-distance F` that `flag` finds applied.
pub fn scene_overrides<'a>(
    mut scene: DemoScene,
    flag: impl Fn(&str) -> Option<&'a str>,
) -> anyhow::Result<DemoScene> {
    if let Some(seed) = flag("--seed") {
        scene.seed = seed.parse()?;
    }
    if let Some(r) = flag("--relief") {
        let h: Vec<f64> = r.split(',').map(str::parse).collect::<Result<_, _>>()?;
        anyhow::ensure!(
            h.len() == 3 && h.iter().all(|v| v.is_finite() && *v >= 0.0),
            "--relief wants PLATEAU,CANYON,ESCARPMENT metres (>= 0), not {r:?}"
        );
        scene.relief = cliffmap::demo_scene::Relief {
            plateau: h[0],
            canyon: h[1],
            escarpment: h[2],
        };
    }
    if let Some(f) = flag("--photo-distance") {
        scene.photo_distance = f.parse()?;
        anyhow::ensure!(
            scene.photo_distance.is_finite() && scene.photo_distance > 0.0,
            "--photo-distance wants a factor > 0, not {f:?}"
        );
    }
    Ok(scene)
}

/// The setting of the benchmarks that place a second photo of each demo photo's target
/// taken elsewhere (`DemoScene::second_shots`): the scene's store and photos in `OUT`
/// (built unless `--reuse` finds them), and the common flags.
#[allow(dead_code)] // each example uses its own subset
pub struct PairScene {
    pub scene: DemoScene,
    pub dem: cliffmap::Dem,
    pub store: cliffmap::store::Store,
    /// The demo photos with their exact cameras.
    pub anchors: Vec<cliffmap::photo::PhotoInput>,
    /// The second places (`--turn-deg`, default 12; `--distance-ratio`, default 1.15).
    pub seconds: Vec<cliffmap::demo_scene::PhotoShot>,
    pub turn_deg: f64,
    pub distance_ratio: f64,
    /// `--starts` (default 5).
    pub starts: usize,
    /// `--photo-width` (default 1600).
    pub width: u32,
    /// `--max-error` of the store (default 0.2).
    pub max_error: f64,
    /// `--same-body`: the second photo taken with the anchor's camera (focal length known).
    pub same_body: bool,
    /// Whether the store and photos were built now (not reused with `--reuse`).
    pub built: bool,
}

#[allow(dead_code)] // not every example that includes this module uses it
impl PairScene {
    /// Reads the flags and builds (or, with `--reuse`, opens) the store and photos;
    /// `generator` names the builder in the store's manifest.
    pub fn from_args(a: &SceneArgs, generator: &str) -> anyhow::Result<PairScene> {
        let scene = a.scene()?;
        let parse = |name: &str, default: &str| a.flag(name).unwrap_or(default).to_string();
        let starts: usize = parse("--starts", "5").parse()?;
        let turn_deg: f64 = parse("--turn-deg", "12").parse()?;
        let distance_ratio: f64 = parse("--distance-ratio", "1.15").parse()?;
        let width: u32 = parse("--photo-width", "1600").parse()?;
        let max_error: f64 = parse("--max-error", "0.2").parse()?;
        let (dem, ortho) = scene.generate()?;
        let store_dir = a.out.join("store");
        let list = a.out.join("photos").join("photos.json");
        let built =
            !(a.has("--reuse") && store_dir.join("manifest.json").exists() && list.exists());
        if built {
            build_scene_store(&scene, &dem, &ortho, max_error, &store_dir, generator)?;
            write_scene_photos(&scene, &dem, &a.out.join("photos"), width)?;
        }
        let store = cliffmap::store::Store::open(&store_dir)?;
        let anchors = cliffmap::photo::read_photo_list(&list)?;
        let seconds = scene.second_shots(turn_deg, distance_ratio);
        Ok(PairScene {
            scene,
            dem,
            store,
            anchors,
            seconds,
            turn_deg,
            distance_ratio,
            starts,
            width,
            max_error,
            same_body: a.has("--same-body"),
            built,
        })
    }
}

#[allow(dead_code)]
impl PairScene {
    /// The second place of `anchor` (`NAME_second` for `NAME.jpg`), if the scene has one
    /// with a clear view of its target.
    pub fn second_of(
        &self,
        anchor: &cliffmap::photo::PhotoInput,
    ) -> Option<&cliffmap::demo_scene::PhotoShot> {
        let stem = anchor.name.trim_end_matches(".jpg");
        self.seconds
            .iter()
            .find(|s| s.name == format!("{stem}_second"))
    }
}

/// Terrain points the camera `truth` shows, on a 40-px grid of its rays (from 20 px in),
/// with their pixels: `hit(origin, direction)` gives a ray's terrain point.
#[allow(dead_code)]
pub fn shown_points(
    truth: &cliffmap::camera::CameraModel,
    hit: impl Fn(glam::DVec3, glam::DVec3) -> Option<glam::DVec3>,
) -> Vec<(glam::DVec3, [f64; 2])> {
    let mut shown = Vec::new();
    for v in (20..truth.height).step_by(40) {
        for u in (20..truth.width).step_by(40) {
            if let Some(p) = truth
                .pixel_ray(u as f64, v as f64)
                .and_then(|d| hit(truth.position, d))
            {
                shown.push((p, [u as f64, v as f64]));
            }
        }
    }
    shown
}

/// Median and 90th percentile of the image distance (pixels) between where `cam` shows the
/// points of [`shown_points`] and their true pixels (10⁶ for a point behind `cam`): what a
/// projection with `cam` feels. NaN without points.
#[allow(dead_code)]
pub fn pixel_errors(
    cam: &cliffmap::camera::CameraModel,
    shown: &[(glam::DVec3, [f64; 2])],
) -> (f64, f64) {
    let mut e: Vec<f64> = shown
        .iter()
        .map(|(p, q)| {
            cam.project(*p)
                .map_or(1e6, |r| (r[0] - q[0]).hypot(r[1] - q[1]))
        })
        .collect();
    e.sort_by(f64::total_cmp);
    let at = |f: f64| e.get((f * (e.len() as f64 - 1.0)) as usize).copied();
    (at(0.5).unwrap_or(f64::NAN), at(0.9).unwrap_or(f64::NAN))
}

/// Reparameterizes the store in `dir` quietly with the default options.
#[allow(dead_code)]
pub fn reparam_quietly(dir: &Path) -> anyhow::Result<()> {
    cliffmap::pipeline::reparam_store(
        dir,
        &cliffmap::pipeline::ReparamOptions {
            ..cliffmap::pipeline::ReparamOptions::default()
        },
    )?;
    Ok(())
}

/// Deterministic uniform numbers in [-1, 1] (SplitMix64).
pub struct Rng(pub u64);

impl Rng {
    /// The next number.
    pub fn next(&mut self) -> f64 {
        self.0 = self.0.wrapping_add(0x9E37_79B9_7F4A_7C15);
        let mut z = self.0;
        z = (z ^ (z >> 30)).wrapping_mul(0xBF58_476D_1CE4_E5B9);
        z = (z ^ (z >> 27)).wrapping_mul(0x94D0_49BB_1331_11EB);
        z ^= z >> 31;
        (z >> 11) as f64 / (1u64 << 53) as f64 * 2.0 - 1.0
    }
}

/// The smaller angle between two angles, radians.
pub fn angle_diff(a: f64, b: f64) -> f64 {
    let d = (a - b).rem_euclid(std::f64::consts::TAU);
    d.min(std::f64::consts::TAU - d)
}

/// Builds the store of a generated scene (its DEM and ortho) into `dir` with `max_error`,
/// quietly and from scratch; `tag` names the source in the manifest.
pub fn build_scene_store(
    scene: &DemoScene,
    dem: &cliffmap::dem::Dem,
    ortho: &cliffmap::ortho::Ortho,
    max_error: f64,
    dir: &Path,
    tag: &str,
) -> anyhow::Result<()> {
    let inputs = BuildInputs {
        dem,
        ortho: Some(ortho),
        dem_source: tag.into(),
        ortho_source: Some(tag.into()),
        fingerprint: format!("{tag}:{scene:?}"),
    };
    build_store(
        &inputs,
        &BuildOptions {
            max_error,
            force: true,
            ..BuildOptions::default()
        },
        dir,
    )?;
    Ok(())
}

/// Height of the generated scenes' photos for a `width` (4:3).
pub fn photo_height(width: u32) -> u32 {
    width / 4 * 3
}

/// Writes the scene's demo photos (ray cast from its ground truth, `width` pixels wide, 4:3,
/// supersampled 2×) and their photos.json into `dir`.
pub fn write_scene_photos(
    scene: &DemoScene,
    dem: &cliffmap::dem::Dem,
    dir: &Path,
    width: u32,
) -> anyhow::Result<()> {
    scene.write_demo_photos(
        dem,
        dir,
        &DemoPhotoOptions {
            width,
            height: photo_height(width),
            supersample: 2,
        },
    )?;
    Ok(())
}

/// `c` perturbed at random inside issue #17's rough-pose ranges: yaw ±3°, pitch and roll
/// ±1.5°, focal length ±3 % (when `focal`; the draw is made either way), position
/// ±`position_error` m horizontally and ±0.4 × that vertically. Draws from `rng` in that
/// order.
pub fn rough_start(
    mut c: cliffmap::register::CameraParams,
    rng: &mut Rng,
    position_error: f64,
    focal: bool,
) -> cliffmap::register::CameraParams {
    c.angles[0] += (3.0 * rng.next()).to_radians();
    c.angles[1] += (1.5 * rng.next()).to_radians();
    c.angles[2] += (1.5 * rng.next()).to_radians();
    let df = 0.03 * rng.next();
    if focal {
        c.focal = [c.focal[0] * (1.0 + df), c.focal[1] * (1.0 + df)];
    }
    c.position += glam::DVec3::new(
        position_error * rng.next(),
        position_error * rng.next(),
        0.4 * position_error * rng.next(),
    );
    c
}

/// Raises `c` to at least 0.5 m above the terrain below it (a perturbed position must not
/// end underground).
pub fn keep_above_ground(
    c: &mut cliffmap::register::CameraParams,
    terrain: &cliffmap::register::LabelledTerrain,
) {
    let ground = terrain
        .hit(c.position + glam::DVec3::Z * 1000.0, -glam::DVec3::Z)
        .map_or(c.position.z - 1.7, |g| g.z);
    c.position.z = c.position.z.max(ground + 0.5);
}
