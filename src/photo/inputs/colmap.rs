//! COLMAP text models (`cameras.txt` + `images.txt`) as photos, with an optional similarity
//! transform into the terrain's world frame (`transform.json`). See docs/formats.md.
//!
//! Conventions checked against COLMAP's `src/colmap/sensor/models.h` and the text format:
//! the camera frame is x right, y down, z forward (as [`CameraModel`]); `images.txt` holds
//! the world-to-camera rotation as a unit quaternion `QW QX QY QZ` and translation `T`
//! (`x_cam = R·X + T`, centre `−Rᵀ·T`); the radial models act on normalized coordinates
//! `(x, y)·(1 + k1·r² + k2·r⁴)` like ours; pixel coordinates put the top-left pixel's
//! *corner* at (0, 0), so principal points shift by −0.5 into our pixel-centre convention.

use std::path::{Path, PathBuf};

use glam::{DMat3, DQuat, DVec3};
use serde::Deserialize;

use crate::camera::CameraModel;
use crate::error::{Error, Result};
use crate::photo::PhotoInput;
use crate::photo::inputs::input::{PhotoSpec, photo_spec};

/// Similarity from COLMAP's model frame to the world frame: `world = scale·R·colmap + t`.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Similarity {
    /// Scale factor (> 0).
    pub scale: f64,
    /// Rotation (orthonormal, determinant +1); `rotation.row(i)` is the JSON's row i.
    pub rotation: DMat3,
    /// Translation, world metres.
    pub translation: DVec3,
}

impl Default for Similarity {
    fn default() -> Self {
        Similarity {
            scale: 1.0,
            rotation: DMat3::IDENTITY,
            translation: DVec3::ZERO,
        }
    }
}

#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
struct TransformFile {
    #[serde(default)]
    scale: Option<f64>,
    #[serde(default)]
    rotation: Option<[[f64; 3]; 3]>,
    #[serde(default)]
    translation: Option<[f64; 3]>,
}

/// Reads `transform.json` (`{"scale": s, "rotation": [[r00, r01, r02], [..], [..]],
/// "translation": [x, y, z]}`, each optional: 1, identity, zero).
pub fn read_similarity(path: &Path) -> Result<Similarity> {
    let text = std::fs::read_to_string(path).map_err(|e| Error::io(path, e))?;
    let t: TransformFile = serde_json::from_str(&text)
        .map_err(|e| Error::bad_input(path, format!("invalid transform: {e}")))?;
    let scale = t.scale.unwrap_or(1.0);
    if !(scale.is_finite() && scale > 0.0) {
        return Err(Error::bad_input(
            path,
            format!("\"scale\" must be a positive number, got {scale}"),
        ));
    }
    let rotation = match t.rotation {
        Some(r) => DMat3::from_cols_array_2d(&r).transpose(),
        None => DMat3::IDENTITY,
    };
    let err = (rotation * rotation.transpose() - DMat3::IDENTITY)
        .to_cols_array()
        .iter()
        .fold(0.0f64, |m, v| m.max(v.abs()));
    if !rotation.is_finite() || err > 1e-6 || (rotation.determinant() - 1.0).abs() > 1e-6 {
        return Err(Error::bad_input(
            path,
            "\"rotation\" must be an orthonormal 3x3 matrix with determinant +1",
        ));
    }
    let tr = t.translation.unwrap_or([0.0; 3]);
    let translation = DVec3::from_array(tr);
    if !translation.is_finite() {
        return Err(Error::bad_input(path, "\"translation\" must be finite"));
    }
    Ok(Similarity {
        scale,
        rotation,
        translation,
    })
}

/// One COLMAP camera: model intrinsics without a pose.
#[derive(Clone, Copy, Debug)]
struct Intrinsics {
    width: u32,
    height: u32,
    fx: f64,
    fy: f64,
    cx: f64,
    cy: f64,
    k1: f64,
    k2: f64,
}

fn parse_f64(tok: &str, path: &Path, line: usize) -> Result<f64> {
    match tok.parse::<f64>() {
        Ok(v) if v.is_finite() => Ok(v),
        _ => Err(Error::bad_input(
            path,
            format!("line {line}: {tok:?} is not a finite number"),
        )),
    }
}

fn parse_cameras(path: &Path) -> Result<Vec<(u64, Intrinsics)>> {
    let text = std::fs::read_to_string(path).map_err(|e| Error::io(path, e))?;
    let mut out = Vec::new();
    for (i, raw) in text.lines().enumerate() {
        let line = raw.trim();
        if line.is_empty() || line.starts_with('#') {
            continue;
        }
        let n = i + 1;
        let tok: Vec<&str> = line.split_whitespace().collect();
        if tok.len() < 4 {
            return Err(Error::bad_input(
                path,
                format!("line {n}: expected CAMERA_ID MODEL WIDTH HEIGHT PARAMS..."),
            ));
        }
        let id: u64 = tok[0]
            .parse()
            .map_err(|_| Error::bad_input(path, format!("line {n}: bad camera id {:?}", tok[0])))?;
        let dim = |s: &str| -> Result<u32> {
            s.parse::<u32>().ok().filter(|&v| v > 0).ok_or_else(|| {
                Error::bad_input(
                    path,
                    format!("line {n}: image size {s:?} must be a positive integer"),
                )
            })
        };
        let (width, height) = (dim(tok[2])?, dim(tok[3])?);
        let p: Vec<f64> = tok[4..]
            .iter()
            .map(|t| parse_f64(t, path, n))
            .collect::<Result<_>>()?;
        let model = tok[1];
        let want = match model {
            "SIMPLE_PINHOLE" => 3,
            "PINHOLE" | "SIMPLE_RADIAL" => 4,
            "RADIAL" => 5,
            "OPENCV" => 8,
            other => {
                return Err(Error::bad_input(
                    path,
                    format!(
                        "line {n}: camera model {other} is not supported (use SIMPLE_PINHOLE, PINHOLE, SIMPLE_RADIAL, RADIAL or OPENCV without tangential terms)"
                    ),
                ));
            }
        };
        if p.len() != want {
            return Err(Error::bad_input(
                path,
                format!("line {n}: {model} needs {want} parameters, got {}", p.len()),
            ));
        }
        // (fx, fy, cx, cy, k1, k2) with COLMAP's corner-origin principal point.
        let (fx, fy, cx, cy, k1, k2) = match model {
            "SIMPLE_PINHOLE" => (p[0], p[0], p[1], p[2], 0.0, 0.0),
            "PINHOLE" => (p[0], p[1], p[2], p[3], 0.0, 0.0),
            "SIMPLE_RADIAL" => (p[0], p[0], p[1], p[2], p[3], 0.0),
            "RADIAL" => (p[0], p[0], p[1], p[2], p[3], p[4]),
            _ => {
                if p[6] != 0.0 || p[7] != 0.0 {
                    return Err(Error::bad_input(
                        path,
                        format!(
                            "line {n}: OPENCV tangential distortion (p1 {}, p2 {}) is not supported",
                            p[6], p[7]
                        ),
                    ));
                }
                (p[0], p[1], p[2], p[3], p[4], p[5])
            }
        };
        if !(fx > 0.0 && fy > 0.0) {
            return Err(Error::bad_input(
                path,
                format!("line {n}: focal lengths must be positive, got fx {fx} fy {fy}"),
            ));
        }
        if out.iter().any(|(j, _)| *j == id) {
            return Err(Error::bad_input(
                path,
                format!("line {n}: camera id {id} appears twice"),
            ));
        }
        out.push((
            id,
            Intrinsics {
                width,
                height,
                fx,
                fy,
                cx: cx - 0.5,
                cy: cy - 0.5,
                k1,
                k2,
            },
        ));
    }
    Ok(out)
}

/// One `images.txt` record: pose (COLMAP frame) and camera id.
struct ImageRecord {
    rotation: DMat3,
    translation: DVec3,
    camera: u64,
    name: String,
    line: usize,
}

fn parse_images(path: &Path) -> Result<Vec<ImageRecord>> {
    let text = std::fs::read_to_string(path).map_err(|e| Error::io(path, e))?;
    // Comment lines are dropped; every image is a header line followed by its (possibly
    // empty) POINTS2D line.
    let lines: Vec<(usize, &str)> = text
        .lines()
        .enumerate()
        .filter(|(_, l)| !l.trim_start().starts_with('#'))
        .map(|(i, l)| (i + 1, l))
        .collect();
    let mut out = Vec::new();
    let mut k = 0;
    while k < lines.len() {
        let (n, line) = lines[k];
        if line.trim().is_empty() {
            k += 1;
            continue;
        }
        let tok: Vec<&str> = line.split_whitespace().collect();
        if tok.len() < 10 {
            return Err(Error::bad_input(
                path,
                format!("line {n}: expected IMAGE_ID QW QX QY QZ TX TY TZ CAMERA_ID NAME"),
            ));
        }
        let v: Vec<f64> = tok[1..8]
            .iter()
            .map(|t| parse_f64(t, path, n))
            .collect::<Result<_>>()?;
        let q = DQuat::from_xyzw(v[1], v[2], v[3], v[0]);
        let norm = q.length();
        if !(norm > 0.5 && norm < 2.0) {
            return Err(Error::bad_input(
                path,
                format!("line {n}: quaternion norm {norm} is not ~1"),
            ));
        }
        let camera: u64 = tok[8]
            .parse()
            .map_err(|_| Error::bad_input(path, format!("line {n}: bad camera id {:?}", tok[8])))?;
        out.push(ImageRecord {
            rotation: DMat3::from_quat(q / norm),
            translation: DVec3::new(v[4], v[5], v[6]),
            camera,
            // Names may contain spaces: everything after the camera id.
            name: tok[9..].join(" "),
            line: n,
        });
        k += 2;
    }
    Ok(out)
}

/// The world-frame camera of a COLMAP image pose under the similarity `s`.
fn world_camera(
    intr: &Intrinsics,
    rotation: DMat3,
    translation: DVec3,
    s: &Similarity,
) -> CameraModel {
    let centre = -(rotation.transpose() * translation);
    CameraModel {
        position: s.scale * (s.rotation * centre) + s.translation,
        world_to_camera: rotation * s.rotation.transpose(),
        width: intr.width,
        height: intr.height,
        fx: intr.fx,
        fy: intr.fy,
        cx: intr.cx,
        cy: intr.cy,
        k1: intr.k1,
        k2: intr.k2,
    }
}

/// Reads a COLMAP text model in `dir` without decoding the images; see [`read_colmap`].
pub fn read_colmap_specs(dir: &Path) -> Result<Vec<PhotoSpec>> {
    let cams_path = dir.join("cameras.txt");
    let imgs_path = dir.join("images.txt");
    let cameras = parse_cameras(&cams_path)?;
    let images = parse_images(&imgs_path)?;
    if images.is_empty() {
        return Err(Error::bad_input(&imgs_path, "no images"));
    }
    let tf_path = dir.join("transform.json");
    let sim = if tf_path.exists() {
        read_similarity(&tf_path)?
    } else {
        Similarity::default()
    };
    let image_dir = if dir.join("images").is_dir() {
        dir.join("images")
    } else {
        dir.to_path_buf()
    };
    let mut out = Vec::with_capacity(images.len());
    for im in &images {
        let intr = cameras
            .iter()
            .find(|(id, _)| *id == im.camera)
            .map(|(_, c)| c)
            .ok_or_else(|| {
                Error::bad_input(
                    &imgs_path,
                    format!(
                        "line {}: camera {} is not in cameras.txt",
                        im.line, im.camera
                    ),
                )
            })?;
        let cam = world_camera(intr, im.rotation, im.translation, &sim);
        let image: PathBuf = image_dir.join(&im.name);
        out.push(photo_spec(&image, cam, &cams_path)?);
    }
    Ok(out)
}

/// Reads a COLMAP text model: `DIR/cameras.txt` (models SIMPLE_PINHOLE, PINHOLE,
/// SIMPLE_RADIAL, RADIAL, and OPENCV with zero tangential terms), `DIR/images.txt` (poses),
/// images from `DIR/images/NAME` (or `DIR/NAME` if there is no `images` folder), and the
/// optional `DIR/transform.json` similarity to the world frame. Cameras are fitted to the
/// images' real sizes and validated; errors name the file and line.
pub fn read_colmap(dir: &Path) -> Result<Vec<PhotoInput>> {
    read_colmap_specs(dir)?
        .iter()
        .map(PhotoSpec::load)
        .collect()
}
