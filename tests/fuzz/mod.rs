//! A small mutation fuzzer for every parser a user's file reaches (shared by
//! `tests/fuzz_parsers.rs`, which runs it briefly in CI, and `examples/fuzz_parsers.rs`,
//! which runs it for minutes). Not coverage-guided (no nightly toolchain here for
//! `cargo fuzz`): each input is a random mutation (bit flips, interesting bytes and numbers,
//! deletions, duplications, insertions, truncations, splices) of a valid seed or of a
//! checked-in corpus file, deterministic for a given seed. A target passes an input when it
//! returns (`Ok` or `Err`) without panicking.
#![allow(dead_code)]

use std::path::{Path, PathBuf};

use cliffmap::camera::{camera_from_json_str, camera_to_json};
use cliffmap::cells::CellMesh;
use cliffmap::register::{PixelOrigin, parse_gcps};
use cliffmap::store::Manifest;
use cliffmap::{DemFormat, DemLoadOptions, load_dem};

/// One parser under test.
pub struct Target {
    /// Name (also the corpus directory).
    pub name: &'static str,
    /// Valid inputs to mutate.
    pub seeds: Vec<Vec<u8>>,
    /// Parses one input (true = accepted); `dir` is a scratch directory of its own.
    pub run: fn(&[u8], &Path) -> bool,
}

/// Deterministic xorshift64* generator.
pub struct Rng(pub u64);

impl Rng {
    pub fn next(&mut self) -> u64 {
        self.0 ^= self.0 >> 12;
        self.0 ^= self.0 << 25;
        self.0 ^= self.0 >> 27;
        self.0.wrapping_mul(0x2545_F491_4F6C_DD1D)
    }
    pub fn below(&mut self, n: usize) -> usize {
        if n == 0 {
            0
        } else {
            (self.next() % n as u64) as usize
        }
    }
}

const INTERESTING: &[u8] = &[
    0, 1, 0x7f, 0x80, 0xff, b'0', b'9', b'-', b'.', b'e', b'"', b',', b'{', b'}', b'[', b']',
    b'\n', b' ',
];
const NUMBERS: &[&str] = &[
    "0",
    "-1",
    "1e309",
    "-1e309",
    "NaN",
    "4294967296",
    "18446744073709551616",
    "1e-320",
    "99999999",
    "-0",
    "3.5",
];

/// A mutation of `input` (1–4 operations).
pub fn mutate(rng: &mut Rng, input: &[u8], other: &[u8]) -> Vec<u8> {
    let mut v = input.to_vec();
    for _ in 0..1 + rng.below(4) {
        let n = v.len();
        match rng.below(9) {
            0 if n > 0 => {
                let i = rng.below(n);
                v[i] ^= 1 << rng.below(8);
            }
            1 if n > 0 => {
                let i = rng.below(n);
                v[i] = INTERESTING[rng.below(INTERESTING.len())];
            }
            2 if n > 0 => {
                let i = rng.below(n);
                let l = (1 + rng.below(16)).min(n - i);
                v.drain(i..i + l);
            }
            3 if n > 0 => {
                let i = rng.below(n);
                let l = (1 + rng.below(64)).min(n - i);
                let chunk: Vec<u8> = v[i..i + l].to_vec();
                let at = rng.below(n);
                v.splice(at..at, chunk);
            }
            4 => {
                let at = rng.below(n + 1);
                let bytes: Vec<u8> = (0..1 + rng.below(8)).map(|_| rng.next() as u8).collect();
                v.splice(at..at, bytes);
            }
            5 if n > 0 => v.truncate(rng.below(n)),
            6 if n > 0 => {
                // replace a run of digits by an interesting number
                let i = rng.below(n);
                if let Some(s) = (i..n).find(|&k| v[k].is_ascii_digit()) {
                    let e = (s..n)
                        .find(|&k| !v[k].is_ascii_digit() && v[k] != b'.')
                        .unwrap_or(n);
                    let num = NUMBERS[rng.below(NUMBERS.len())].as_bytes().to_vec();
                    v.splice(s..e, num);
                }
            }
            7 if n > 0 && !other.is_empty() => {
                // splice with another input
                let i = rng.below(n);
                let j = rng.below(other.len());
                v.truncate(i);
                v.extend_from_slice(&other[j..]);
            }
            8 if n >= 4 => {
                // overwrite a little-endian u32 with an extreme value
                let i = rng.below(n - 3);
                let x: u32 = [0, 1, u32::MAX, 0x7fff_ffff, 1 << 16, 1 << 24][rng.below(6)];
                v[i..i + 4].copy_from_slice(&x.to_le_bytes());
            }
            _ => {}
        }
    }
    v
}

fn write(dir: &Path, name: &str, bytes: &[u8]) -> PathBuf {
    let p = dir.join(name);
    std::fs::write(&p, bytes).expect("scratch directory is writable");
    p
}

/// The memory cap given to the DEM readers (they refuse larger images before decoding).
pub const MAX_MEMORY: u64 = 64 << 20;

fn dem_opts(format: Option<DemFormat>) -> DemLoadOptions {
    DemLoadOptions {
        format,
        max_memory: MAX_MEMORY,
        ..Default::default()
    }
}

fn png16_seed() -> Vec<u8> {
    let img = image::ImageBuffer::<image::Luma<u16>, Vec<u16>>::from_fn(8, 6, |x, y| {
        image::Luma([(x * 977 + y * 131) as u16])
    });
    let mut c = std::io::Cursor::new(Vec::new());
    img.write_to(&mut c, image::ImageFormat::Png)
        .expect("png encodes");
    c.into_inner()
}

fn terrain_rgb_seed() -> Vec<u8> {
    let img =
        image::RgbImage::from_fn(8, 6, |x, y| image::Rgb([1, (x * 20) as u8, (y * 30) as u8]));
    let mut c = std::io::Cursor::new(Vec::new());
    img.write_to(&mut c, image::ImageFormat::Png)
        .expect("png encodes");
    c.into_inner()
}

/// The georeference of the DEM seeds: 2 m samples from (500000, 7000000), UTM 33N,
/// no-data -9999.
fn dem_geo() -> super::common::tiffgen::Geo {
    super::common::tiffgen::Geo {
        scale: (2.0, 2.0),
        tie: (0.0, 0.0, 500000.0, 7000000.0),
        pixel_is_point: false,
        epsg: Some(32633),
        nodata: Some("-9999".into()),
    }
}

fn geotiff_seeds(dir: &Path) -> Vec<Vec<u8>> {
    use super::common::tiffgen::write_strips;
    use tiff::encoder::{Compression, Predictor, colortype};
    let geo = dem_geo();
    let data: Vec<f32> = (0..8 * 6).map(|i| 100.0 + i as f32 * 0.5).collect();
    let mut out = Vec::new();
    for (k, comp) in [
        Compression::Uncompressed,
        Compression::Deflate(Default::default()),
    ]
    .into_iter()
    .enumerate()
    {
        let p = dir.join(format!("seed{k}.tif"));
        write_strips::<colortype::Gray32Float>(&p, 8, 6, &data, comp, Predictor::None, Some(&geo));
        out.push(std::fs::read(&p).expect("seed written"));
    }
    out
}

fn camera_seeds() -> Vec<Vec<u8>> {
    let cam = cliffmap::camera::CameraModel {
        position: glam::DVec3::new(10.0, 20.0, 300.0),
        world_to_camera: cliffmap::camera::rotation_from_yaw_pitch_roll(0.5, 0.1, 0.01),
        width: 1600,
        height: 1200,
        fx: 2000.0,
        fy: 2001.0,
        cx: 800.0,
        cy: 600.0,
        k1: -0.05,
        k2: 0.0,
    };
    vec![
        serde_json::to_vec_pretty(&camera_to_json(&cam)).expect("serializes"),
        serde_json::to_vec_pretty(&cliffmap::camera::camera_to_imgraft_json(&cam))
            .expect("serializes"),
    ]
}

const PHOTOS_JSON: &str = r#"{"photos": [{"image": "a.png", "camera": "a.json"}, {"image": "a.png", "imgraft": "b.json", "rotation_delta_deg": [0.1, 0.2, 0.3]}]}"#;

/// The files a photo list names: a 1600 x 1200 PNG and its two camera files.
fn photo_list_files(dir: &Path) {
    if dir.join("b.json").exists() {
        return;
    }
    let cams = camera_seeds();
    image::RgbImage::new(1600, 1200)
        .save(dir.join("a.png"))
        .expect("png written");
    write(dir, "a.json", &cams[0]);
    write(dir, "b.json", &cams[1]);
}

const COLMAP: &str = "# cameras.txt\n1 SIMPLE_RADIAL 1600 1200 2000 800 600 0.01\n2 PINHOLE 800 600 1000 1000 400 300\n\u{1}# images.txt\n1 0.99 0.01 0.02 0.03 1.0 2.0 3.0 1 a.png\n\n2 1 0 0 0 0 0 0 2 b.png\n\n";

const GCP_TEXT: &str = "% X Y Z U V\n446722.1 7396671.2 770.3 1951+9 1203\n446800.5 7396700.0 812.0 1000.5 500.25\n446900 7396800 900 3000 2000\n447000 7396900 950 100 2800\n";
const GCP_CSV: &str = "x,y,z,u,v,name,weight\n446722.1,7396671.2,770.3,1960,1203,a,1\n446800.5,7396700,812,1000.5,500.25,b,0.5\n446900,7396800,900,3000,2000,c,1\n";

/// A tiny store built from a 33 x 33 DEM (its manifest and one mesh are the seeds).
fn store_seeds(dir: &Path) -> (Vec<u8>, Vec<u8>) {
    use cliffmap::pipeline::{BuildInputs, BuildOptions, build_store};
    let heights: Vec<f32> = (0..33 * 33)
        .map(|i| if i % 33 > 15 { 40.0 } else { 0.0 } + (i / 33) as f32 * 0.3)
        .collect();
    let dem = cliffmap::Dem::from_heights(
        33,
        33,
        heights,
        cliffmap::GridGeoref::new(500000.0, 7000000.0, 2.0),
    )
    .expect("valid dem");
    let out = dir.join("seed_store");
    let inputs = BuildInputs {
        dem: &dem,
        ortho: None,
        dem_source: "fuzz".into(),
        ortho_source: None,
        fingerprint: "fuzz".into(),
    };
    let m = build_store(
        &inputs,
        &BuildOptions {
            max_error: 0.5,
            cell_intervals: 16,
            cell_texels: 16,
            force: true,
            ..BuildOptions::default()
        },
        &out,
    )
    .expect("builds");
    let manifest = std::fs::read(out.join("manifest.json")).expect("manifest");
    let mesh = std::fs::read(out.join(&m.cells[0].files.mesh.path)).expect("mesh");
    (manifest, mesh)
}

fn tiled_geotiff_seeds(dir: &Path) -> Vec<Vec<u8>> {
    use super::common::tiffgen::{Raw, f32_bytes, write_raw};
    let geo = dem_geo();
    // 20 x 18 samples in 16 x 16 tiles: partial tiles at the right and the bottom
    let (w, h) = (20u32, 18u32);
    let f: Vec<f32> = (0..w * h).map(|i| 100.0 + i as f32 * 0.25).collect();
    let i16s: Vec<u8> = (0..w * h)
        .flat_map(|i| (i as i16 * 3 - 200).to_ne_bytes())
        .collect();
    let mut out = Vec::new();
    for (k, (bits, format, bytes)) in [(32u16, 3u16, f32_bytes(&f)), (16, 2, i16s)]
        .into_iter()
        .enumerate()
    {
        let raw = Raw {
            width: w,
            height: h,
            bits,
            sample_format: format,
            samples: 1,
            photometric: 1,
            tile: Some((16, 16)),
            extra_alpha: false,
        };
        let p = dir.join(format!("tiled{k}.tif"));
        write_raw(&p, &raw, &bytes, Some(&geo), false);
        out.push(std::fs::read(&p).expect("seed written"));
    }
    out
}

/// The DEM the ortho target places its images on: 16 x 12 samples, 2 m apart, from
/// (500000, 7000000) (as the ortho seeds' georeference).
fn ortho_dem() -> cliffmap::Dem {
    cliffmap::Dem::from_heights(
        16,
        12,
        vec![100.0; 16 * 12],
        cliffmap::GridGeoref::new(500000.0, 7000000.0, 2.0),
    )
    .expect("valid dem")
}

/// Ortho seeds: an RGB GeoTIFF placed by its tags, and a PNG and a JPEG of the DEM's grid.
fn ortho_seeds(dir: &Path) -> Vec<Vec<u8>> {
    use super::common::tiffgen::{Geo, write_strips};
    use tiff::encoder::{Compression, Predictor, colortype};
    let geo = Geo {
        scale: (1.0, 1.0),
        tie: (0.0, 0.0, 499999.0, 7000001.0),
        pixel_is_point: false,
        epsg: None,
        nodata: None,
    };
    let rgb: Vec<u8> = (0..32 * 24 * 3).map(|i| (i * 7 % 251) as u8).collect();
    let p = dir.join("ortho.tif");
    write_strips::<colortype::RGB8>(
        &p,
        32,
        24,
        &rgb,
        Compression::Uncompressed,
        Predictor::None,
        Some(&geo),
    );
    let mut out = vec![std::fs::read(&p).expect("seed written")];
    let img = image::RgbImage::from_fn(16, 12, |x, y| {
        image::Rgb([(x * 15) as u8, (y * 20) as u8, 90])
    });
    for format in [image::ImageFormat::Png, image::ImageFormat::Jpeg] {
        let mut c = std::io::Cursor::new(Vec::new());
        img.write_to(&mut c, format).expect("image encodes");
        out.push(c.into_inner());
    }
    out
}

/// Loads an ortho from `b`: a TIFF placed by its tags, a PNG or JPEG (by the first bytes)
/// on the DEM's grid.
fn run_ortho(b: &[u8], d: &Path) -> bool {
    use cliffmap::{OrthoPlacement, load_ortho};
    let (name, placement) = if b.starts_with(b"II") || b.starts_with(b"MM") {
        ("o.tif", OrthoPlacement::FromFile)
    } else if b.starts_with(&[0x89, b'P']) {
        ("o.png", OrthoPlacement::SameGridAsDem)
    } else {
        ("o.jpg", OrthoPlacement::SameGridAsDem)
    };
    load_ortho(&write(d, name, b), placement, &ortho_dem(), MAX_MEMORY).is_ok()
}

const TRANSFORM_JSON: &str = r#"{"scale": 2.5, "rotation": [[0, -1, 0], [1, 0, 0], [0, 0, 1]], "translation": [446000.0, 7396000.0, 120.5]}"#;

/// `bytes` with its manifest checksum recomputed (so that a mutation of the records reaches
/// their parsing instead of stopping at the checksum), unchanged without a checksum field.
fn reseal_manifest(bytes: &[u8]) -> Vec<u8> {
    const KEY: &[u8] = b"\"content_crc32\": \"";
    let mut b = bytes.to_vec();
    let Some(at) = b
        .windows(KEY.len())
        .rposition(|w| w == KEY)
        .map(|i| i + KEY.len())
    else {
        return b;
    };
    if b.len() < at + 9 || b[at + 8] != b'"' {
        return b;
    }
    b[at..at + 8].copy_from_slice(b"00000000");
    let crc = cliffmap::store::crc32_hex(&b);
    b[at..at + 8].copy_from_slice(crc.as_bytes());
    b
}

/// Every target with its generated seeds (`scratch` holds seed files).
pub fn targets(scratch: &Path) -> Vec<Target> {
    let (manifest, mesh) = store_seeds(scratch);
    let raw: Vec<u8> = (0..64)
        .flat_map(|i| (100.0f32 + i as f32).to_le_bytes())
        .collect();
    vec![
        Target {
            name: "dem_geotiff",
            seeds: geotiff_seeds(scratch),
            run: |b, d| load_dem(&write(d, "f.tif", b), &dem_opts(None)).is_ok(),
        },
        Target {
            name: "dem_png16",
            seeds: vec![png16_seed()],
            run: |b, d| load_dem(&write(d, "f.png", b), &dem_opts(Some(DemFormat::Png16))).is_ok(),
        },
        Target {
            name: "dem_terrain_rgb",
            seeds: vec![terrain_rgb_seed()],
            run: |b, d| {
                (load_dem(
                    &write(d, "f.png", b),
                    &dem_opts(Some(DemFormat::TerrainRgb)),
                ))
                .is_ok()
            },
        },
        Target {
            name: "dem_raw_f32",
            seeds: vec![raw],
            run: |b, d| {
                (load_dem(
                    &write(d, "f.f32", b),
                    &DemLoadOptions {
                        width: Some(8),
                        height: Some(8),
                        ..dem_opts(None)
                    },
                ))
                .is_ok()
            },
        },
        Target {
            name: "camera_json",
            seeds: camera_seeds(),
            run: |b, _| {
                (camera_from_json_str(
                    &String::from_utf8_lossy(b),
                    Path::new("fuzz.json"),
                    (1600, 1200),
                ))
                .is_ok()
            },
        },
        Target {
            name: "photos_json",
            seeds: vec![PHOTOS_JSON.as_bytes().to_vec()],
            run: |b, d| {
                photo_list_files(d);
                cliffmap::photo::read_photo_specs(&write(d, "photos.json", b)).is_ok()
            },
        },
        Target {
            name: "colmap_text",
            seeds: vec![COLMAP.as_bytes().to_vec()],
            run: |b, d| {
                // cameras.txt and images.txt joined by a 0x01 byte
                if !d.join("b.png").exists() {
                    image::RgbImage::new(1600, 1200)
                        .save(d.join("a.png"))
                        .expect("png written");
                    image::RgbImage::new(800, 600)
                        .save(d.join("b.png"))
                        .expect("png written");
                }
                let text = String::from_utf8_lossy(b);
                let (cams, imgs) = text.split_once('\u{1}').unwrap_or((&text, ""));
                write(d, "cameras.txt", cams.as_bytes());
                write(d, "images.txt", imgs.as_bytes());
                cliffmap::photo::read_colmap_specs(d).is_ok()
            },
        },
        Target {
            name: "gcp",
            seeds: vec![GCP_TEXT.as_bytes().to_vec(), GCP_CSV.as_bytes().to_vec()],
            run: |b, _| {
                (parse_gcps(
                    &String::from_utf8_lossy(b),
                    Path::new("fuzz.gcp"),
                    PixelOrigin::Format,
                ))
                .is_ok()
            },
        },
        Target {
            name: "manifest",
            seeds: vec![manifest.clone()],
            run: |b, d| {
                write(d, "manifest.json", b);
                Manifest::read(d).is_ok()
            },
        },
        Target {
            name: "manifest_resealed",
            seeds: vec![manifest],
            run: |b, d| {
                write(d, "manifest.json", &reseal_manifest(b));
                Manifest::read(d).is_ok()
            },
        },
        Target {
            name: "dem_geotiff_tiled",
            seeds: tiled_geotiff_seeds(scratch),
            run: |b, d| load_dem(&write(d, "f.tif", b), &dem_opts(None)).is_ok(),
        },
        Target {
            name: "ortho_image",
            seeds: ortho_seeds(scratch),
            run: run_ortho,
        },
        Target {
            name: "colmap_transform",
            seeds: vec![TRANSFORM_JSON.as_bytes().to_vec()],
            run: |b, d| cliffmap::photo::read_similarity(&write(d, "transform.json", b)).is_ok(),
        },
        Target {
            name: "mesh",
            seeds: vec![mesh],
            run: |b, _| CellMesh::from_bytes(b, Path::new("fuzz.mesh")).is_ok(),
        },
    ]
}

/// The checked-in corpus files of `target` (fuzz/corpus/NAME/*), sorted.
pub fn corpus(name: &str) -> Vec<Vec<u8>> {
    let dir = Path::new(env!("CARGO_MANIFEST_DIR"))
        .join("fuzz/corpus")
        .join(name);
    let mut files: Vec<PathBuf> = std::fs::read_dir(&dir)
        .map(|r| r.filter_map(|e| e.ok().map(|e| e.path())).collect())
        .unwrap_or_default();
    files.sort();
    files.iter().filter_map(|p| std::fs::read(p).ok()).collect()
}

/// What one fuzzing run found.
#[derive(Debug, Default)]
pub struct Report {
    /// Inputs run.
    pub runs: u64,
    /// Inputs that panicked: (input, panic message).
    pub panics: Vec<(Vec<u8>, String)>,
    /// Slowest input, seconds.
    pub slowest_s: f64,
    /// Inputs the parser accepted (returned Ok).
    pub accepted: u64,
    /// Seeds (generated and corpus) the parser rejected: should be none.
    pub rejected_seeds: usize,
}

/// Runs `target` on its seeds, then on `iterations` mutations (or until `deadline`).
pub fn fuzz(
    target: &Target,
    extra: &[Vec<u8>],
    seed: u64,
    iterations: u64,
    deadline: Option<std::time::Instant>,
    scratch: &Path,
) -> Report {
    let dir = scratch.join(target.name);
    std::fs::create_dir_all(&dir).expect("scratch directory");
    let pool: Vec<Vec<u8>> = target.seeds.iter().chain(extra).cloned().collect();
    let mut rng = Rng(seed | 1);
    let mut rep = Report::default();
    let one = |input: &[u8], rep: &mut Report| -> bool {
        let t = std::time::Instant::now();
        let r =
            std::panic::catch_unwind(std::panic::AssertUnwindSafe(|| (target.run)(input, &dir)));
        rep.slowest_s = rep.slowest_s.max(t.elapsed().as_secs_f64());
        rep.runs += 1;
        let ok = matches!(r, Ok(true));
        rep.accepted += u64::from(ok);
        if let Err(e) = r {
            let msg = e
                .downcast_ref::<String>()
                .cloned()
                .or_else(|| e.downcast_ref::<&str>().map(|s| s.to_string()))
                .unwrap_or_default();
            rep.panics.push((input.to_vec(), msg));
        }
        ok
    };
    for p in &pool {
        if !one(p, &mut rep) {
            rep.rejected_seeds += 1;
        }
    }
    let mut i = 0;
    while i < iterations && deadline.is_none_or(|d| std::time::Instant::now() < d) {
        let a = &pool[rng.below(pool.len())];
        let b = &pool[rng.below(pool.len())];
        let input = mutate(&mut rng, a, b);
        one(&input, &mut rep);
        i += 1;
    }
    rep
}
