//! Photo lists: `photos.json` (cliffmap / ImGRAFT cameras per photo) and the checks every
//! photo source shares (camera validity, image readable, camera size fitted to the image).
//!
//! `photos.json` (docs/formats.md): `{"photos": [{"image": "a.jpg", "camera": "a.json"},
//! {"image": "b.jpg", "imgraft": "b_imgraft.json", "rotation_delta_deg": [dyaw, dpitch,
//! droll]}, {"image": "c.jpg", "rough": {"heading_deg": 250}}]}`; relative paths resolve
//! against the list's folder. A `"rough"` entry has no fitted camera, only what the photo's
//! EXIF data and the photographer give ([`RoughPose`]): `cliffmap register` makes its camera
//! ([`crate::camera::rough_camera`]); [`read_photo_specs`] refuses it.

use std::path::{Path, PathBuf};

use serde::Deserialize;

use crate::camera::{
    CameraModel, RoughPose, apply_rotation_delta, camera_from_json_file, fit_camera_to_image,
    validate_camera,
};
use crate::error::{Error, Result};
use crate::photo::{PhotoInput, PixelMask};

/// A photo's image file and its camera, fitted to the image's real size (pixels not decoded
/// yet; [`PhotoSpec::load`] decodes them).
#[derive(Clone, Debug, PartialEq)]
pub struct PhotoSpec {
    /// Short name for reports (the image's file name).
    pub name: String,
    /// The image file.
    pub image_path: PathBuf,
    /// The camera in the world frame, for an image of exactly the file's size.
    pub camera: CameraModel,
    /// Why `cliffmap register` could not confirm this camera (it kept the one it was given),
    /// from a registered list's `"registered": false` entry; `None` for a camera to trust.
    /// `cliffmap project` leaves such photos out unless asked (docs/formats.md).
    pub unregistered: Option<String>,
    /// The photo's mask image (`"mask"` in the list: 0 = ignore the pixel), if any.
    pub mask_path: Option<PathBuf>,
}

impl PhotoSpec {
    /// Decodes the image (sRGB, converted to RGB8; JPEG strictly, so a truncated or damaged
    /// photo is refused, [`crate::fsutil::decode_rgb8`]), turned as its EXIF orientation
    /// says ([`crate::fsutil::decode_photo_rgb8`]). Errors name the file.
    pub fn load(&self) -> Result<PhotoInput> {
        let image = crate::fsutil::decode_photo_rgb8(&self.image_path)?;
        if image.dimensions() != (self.camera.width, self.camera.height) {
            return Err(Error::bad_input(
                &self.image_path,
                format!(
                    "decoded image is {} x {}, its header said {} x {}",
                    image.width(),
                    image.height(),
                    self.camera.width,
                    self.camera.height
                ),
            ));
        }
        let mask = match &self.mask_path {
            Some(p) => Some(PixelMask::read(p, image.width(), image.height())?),
            None => None,
        };
        Ok(PhotoInput {
            name: self.name.clone(),
            image_path: self.image_path.clone(),
            image,
            camera: self.camera,
            mask,
        })
    }
}

/// The real pixel size of a photo file (header only), as shown: sides swapped for EXIF
/// orientations that turn it by 90° ([`crate::fsutil::photo_dimensions`]). Errors name the
/// file.
pub fn image_size(path: &Path) -> Result<(u32, u32)> {
    crate::fsutil::photo_dimensions(path)
}

/// A validated [`PhotoSpec`] from an image file and the camera read for it.
pub fn photo_spec(
    image_path: &Path,
    camera: CameraModel,
    camera_source: &Path,
) -> Result<PhotoSpec> {
    spec_for_size(image_path, image_size(image_path)?, camera, camera_source)
}

fn spec_for_size(
    image_path: &Path,
    size: (u32, u32),
    camera: CameraModel,
    camera_source: &Path,
) -> Result<PhotoSpec> {
    let camera = fit_camera_to_image(camera, size, camera_source, image_path)?;
    validate_camera(&camera, camera_source)?;
    Ok(PhotoSpec {
        name: file_name(image_path),
        image_path: image_path.to_path_buf(),
        camera,
        unregistered: None,
        mask_path: None,
    })
}

#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
struct ListFile {
    photos: Vec<Entry>,
}

#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
struct Entry {
    image: PathBuf,
    #[serde(default)]
    camera: Option<PathBuf>,
    #[serde(default)]
    imgraft: Option<PathBuf>,
    #[serde(default)]
    rotation_delta_deg: Option<[f64; 3]>,
    #[serde(default)]
    rough: Option<RoughPose>,
    /// `false` in a registered list for a photo whose camera `register` could not confirm.
    #[serde(default)]
    registered: Option<bool>,
    /// Why not, with `"registered": false`.
    #[serde(default)]
    reason: Option<String>,
    /// A mask image of the photo's size: 0 = ignore the pixel.
    #[serde(default)]
    mask: Option<PathBuf>,
}

/// One entry of a photo list: a photo with its camera, or with a rough pose only.
#[derive(Clone, Debug, PartialEq)]
pub enum PhotoEntry {
    /// A photo with a camera (`"camera"` or `"imgraft"`).
    Fitted(PhotoSpec),
    /// A photo with a rough pose only (`"rough"`).
    Rough {
        /// Short name (the image's file name).
        name: String,
        /// The image file.
        image_path: PathBuf,
        /// The image's size in pixels.
        size: (u32, u32),
        /// What the list gives.
        pose: RoughPose,
        /// The photo's mask image (0 = ignore the pixel), if any.
        mask_path: Option<PathBuf>,
    },
}

impl PhotoEntry {
    /// The photo's short name.
    pub fn name(&self) -> &str {
        match self {
            PhotoEntry::Fitted(s) => &s.name,
            PhotoEntry::Rough { name, .. } => name,
        }
    }
}

fn file_name(path: &Path) -> String {
    path.file_name().map_or_else(
        || path.display().to_string(),
        |n| n.to_string_lossy().into(),
    )
}

/// Reads `photos.json` and every camera it names, without decoding the images; see
/// [`read_photo_list`]. An entry with a rough pose only is an error (it needs
/// `cliffmap register` first; [`read_photo_entries`] reads it).
pub fn read_photo_specs(path: &Path) -> Result<Vec<PhotoSpec>> {
    read_photo_entries(path)?
        .into_iter()
        .enumerate()
        .map(|(i, e)| match e {
            PhotoEntry::Fitted(s) => Ok(s),
            PhotoEntry::Rough { image_path, .. } => Err(Error::bad_input(
                path,
                format!(
                    "photo {i} ({}) has a rough pose only (\"rough\"): run `cliffmap register` first, which writes a list with cameras",
                    image_path.display()
                ),
            )),
        })
        .collect()
}

/// Reads `photos.json` like [`read_photo_specs`], keeping entries with a rough pose only
/// (their image size read, their values checked).
pub fn read_photo_entries(path: &Path) -> Result<Vec<PhotoEntry>> {
    let text = std::fs::read_to_string(path).map_err(|e| Error::io(path, e))?;
    let list: ListFile = serde_json::from_str(&text).map_err(|e| {
        Error::bad_input(
            path,
            format!("invalid photo list: {e} (expected {{\"photos\": [{{\"image\": ..., \"camera\", \"imgraft\" or \"rough\": ...}}]}})"),
        )
    })?;
    if list.photos.is_empty() {
        return Err(Error::bad_input(path, "\"photos\" is empty"));
    }
    let base = path.parent().unwrap_or(Path::new(""));
    let mut out = Vec::with_capacity(list.photos.len());
    for (i, e) in list.photos.iter().enumerate() {
        let image = base.join(&e.image);
        let cam_file = match (&e.camera, &e.imgraft, &e.rough) {
            (Some(c), None, None) | (None, Some(c), None) => base.join(c),
            (None, None, Some(pose)) => {
                if let Some(msg) = pose.problem() {
                    return Err(Error::bad_input(
                        path,
                        format!("photo {i} ({}): {msg}", e.image.display()),
                    ));
                }
                if e.rotation_delta_deg.is_some() {
                    return Err(Error::bad_input(
                        path,
                        format!(
                            "photo {i} ({}): \"rotation_delta_deg\" needs a camera, not a rough pose",
                            e.image.display()
                        ),
                    ));
                }
                let size = image_size(&image)?;
                let mut pose = pose.clone();
                pose.lens = pose.lens.map(|l| base.join(l));
                out.push(PhotoEntry::Rough {
                    name: file_name(&image),
                    mask_path: mask_for(base, &e.mask, &image, size)?,
                    size,
                    image_path: image,
                    pose,
                });
                continue;
            }
            _ => {
                return Err(Error::bad_input(
                    path,
                    format!(
                        "photo {i} ({}): give exactly one of \"camera\", \"imgraft\" and \"rough\"",
                        e.image.display()
                    ),
                ));
            }
        };
        if let Some(d) = e.rotation_delta_deg
            && d.iter().any(|v| !v.is_finite() || v.abs() > 180.0)
        {
            return Err(Error::bad_input(
                path,
                format!(
                    "photo {i}: \"rotation_delta_deg\" must be three finite angles in [-180, 180], got {d:?}"
                ),
            ));
        }
        let size = image_size(&image)?;
        let mut cam = camera_from_json_file(&cam_file, size)?;
        if let Some(d) = e.rotation_delta_deg {
            cam = apply_rotation_delta(&cam, d);
        }
        let mut spec = spec_for_size(&image, size, cam, &cam_file)?;
        spec.mask_path = mask_for(base, &e.mask, &image, size)?;
        if e.registered == Some(false) {
            spec.unregistered = Some(
                e.reason
                    .clone()
                    .unwrap_or_else(|| "its camera was not confirmed".into()),
            );
        }
        out.push(PhotoEntry::Fitted(spec));
    }
    Ok(out)
}

/// The mask file of a list entry (`mask`, relative to the list's folder `base`), checked to
/// exist and to have the size of its photo `image`.
fn mask_for(
    base: &Path,
    mask: &Option<PathBuf>,
    image: &Path,
    size: (u32, u32),
) -> Result<Option<PathBuf>> {
    let Some(m) = mask else { return Ok(None) };
    let m = base.join(m);
    let msize = image_size(&m)?;
    if msize != size {
        return Err(Error::bad_input(
            &m,
            format!(
                "mask is {}x{} pixels but its photo {} is {}x{}",
                msize.0,
                msize.1,
                image.display(),
                size.0,
                size.1
            ),
        ));
    }
    Ok(Some(m))
}

/// Reads `photos.json` (docs/formats.md): each entry's image (decoded to RGB8) and camera
/// (`"camera"`: any Camera JSON; `"imgraft"`: an ImGRAFT-style file, same reader), with an
/// optional `"rotation_delta_deg"` applied by [`apply_rotation_delta`]. Relative paths
/// resolve against the list's folder. Cameras are fitted to the image's real size and
/// validated; a missing or unreadable file is an error naming it.
pub fn read_photo_list(path: &Path) -> Result<Vec<PhotoInput>> {
    read_photo_specs(path)?
        .iter()
        .map(PhotoSpec::load)
        .collect()
}
