//! `register`: every photo of a list refined against a store's terrain, then a new photo
//! list with the refined cameras and a report.
//!
//! Four ways a photo gets its camera: **known** photos (named in [`TieSettings::known`],
//! e.g. fitted with GCPs) keep theirs; every other photo, in list order, is first **tied**
//! ([`tie_photo`]) to the nearest placed photo taken within [`TieOptions::max_distance_m`]
//! of it (same place: rotation only), else **resected** ([`resect_photo`], position
//! included) against the nearest photo whose position is trusted (known, resected, or tied
//! to such a photo) within [`TieSettings::resect_distance_m`], else registered against the
//! **terrain** ([`register_to_terrain`], the position kept). Photos still unplaced then try
//! ties and resections against photos placed after them. A photo none of them places keeps
//! its given camera, with a warning.
//!
//! Output files (all written atomically, the list last): `OUT` (the same format as
//! `photos.json`, image paths relative to its folder), `OUT_STEM.NAME.camera.json` per photo
//! (cliffmap Camera JSON), and `OUT_STEM.report.json` (per photo: verdict, reason, scores,
//! parameter changes, repeatability, time).

use std::path::{Path, PathBuf};

use serde_json::{Value, json};

use super::decoded_photos::{DEFAULT_BUDGET_BYTES, DecodedPhotos};
use crate::camera::rough_camera;
use crate::camera::{CameraModel, camera_to_json};
use crate::error::{Error, Result};
use crate::fsutil::write_atomic;
use crate::photo::{PhotoEntry, PhotoSpec};
use crate::register::{
    CameraParams, LabelTexture, LabelledTerrain, MaskedPhoto, Param, ResectFit, ResectOptions,
    TerrainFit, TerrainOptions, TieFit, TieOptions, register_masked_to_terrain, resect_photo,
    tie_photo,
};
use crate::store::Store;

/// One photo's registration.
#[derive(Clone, Debug, PartialEq)]
pub struct PhotoRegistration {
    /// The photo's name (its file name).
    pub name: String,
    /// The camera given.
    pub rough: CameraModel,
    /// The terrain fit (its `camera` is the one written; for a known or tied photo a fit
    /// of that camera with no search: scores NaN, no evaluations).
    pub fit: TerrainFit,
    /// How the camera was found: "terrain", "terrain_photos" (the terrain, then again
    /// against the other placed photos' pixels: `--textures best`), "known", "tie" or
    /// "resection".
    pub method: &'static str,
    /// The tie tried after the terrain failed, if any (accepted or not), and its anchor.
    pub tie: Option<(String, TieFit)>,
    /// The resection tried, if any (accepted or not), and its anchor.
    pub resection: Option<(String, ResectFit)>,
    /// The camera file written.
    pub camera_file: PathBuf,
}

/// Known photos and photo-to-photo ties for [`register_photos_with`].
#[derive(Clone, Debug)]
pub struct TieSettings {
    /// Names of photos whose given cameras are trusted (kept, and anchors for ties).
    pub known: Vec<String>,
    /// When a tie is tried and accepted.
    pub options: TieOptions,
    /// Moving surfaces to leave out of the ties' matches (e.g. a glacier between time-lapse
    /// shots): a grey raster on the store's DEM grid, values ≥ 128 moving.
    pub moving_mask: Option<image::GrayImage>,
    /// Most distance (metres) from a photo's given position to an anchor it may be resected
    /// against ([`resect_photo`]); 0 turns resection off.
    pub resect_distance_m: f64,
    /// How a resection matches and when it is accepted.
    pub resection: ResectOptions,
}

impl TieSettings {
    /// Errors for a negative or non-finite tie or resection distance and a non-positive
    /// RMSE bound (messages name the command's flags).
    pub fn validate(&self) -> Result<()> {
        let checks = [
            ("--tie-distance-m", self.options.max_distance_m, true),
            ("--tie-rmse-px", self.options.max_rmse_px, false),
            ("--resect-distance-m", self.resect_distance_m, true),
            ("--resect-rmse-px", self.resection.max_rmse_px, false),
        ];
        for (flag, v, zero_ok) in checks {
            let ok = v.is_finite() && (v > 0.0 || (zero_ok && v == 0.0));
            if !ok {
                let want = if zero_ok {
                    "must be >= 0"
                } else {
                    "must be positive"
                };
                return Err(Error::BadOption(format!("{flag} {want}, got {v}")));
            }
        }
        Ok(())
    }
}

impl Default for TieSettings {
    fn default() -> Self {
        TieSettings {
            known: Vec::new(),
            options: TieOptions::default(),
            moving_mask: None,
            resect_distance_m: 1000.0,
            resection: ResectOptions::default(),
        }
    }
}

/// The photos of a list with cameras: entries with a camera as they are, entries with a
/// rough pose only ([`PhotoEntry::Rough`]) given a rough camera by [`rough_camera`] from
/// their EXIF data, the store's CRS and its terrain (the finest level's TIN, for the height
/// of a photographer on the ground); `note(name, line)` gets where each rough value came
/// from. Errors name the image and the value missing.
pub fn resolve_photo_entries(
    store_dir: &Path,
    entries: Vec<PhotoEntry>,
    note: &mut dyn FnMut(&str, &str),
) -> Result<Vec<PhotoSpec>> {
    if entries.iter().all(|e| matches!(e, PhotoEntry::Fitted(_))) {
        return Ok(entries
            .into_iter()
            .filter_map(|e| match e {
                PhotoEntry::Fitted(s) => Some(s),
                PhotoEntry::Rough { .. } => None,
            })
            .collect());
    }
    let store = Store::open(store_dir)?;
    let m = &store.manifest;
    let (cx, cy) = m.georef.world(
        (m.dem.height as f64 - 1.0) / 2.0,
        (m.dem.width as f64 - 1.0) / 2.0,
    );
    let near = glam::DVec3::new(cx, cy, (m.dem.height_min + m.dem.height_max) / 2.0);
    let terrain = LabelledTerrain::new(&store, near)?;
    let top = terrain.top_z().max(m.dem.height_max) + 100.0;
    let ground = |x: f64, y: f64| {
        terrain
            .hit(glam::DVec3::new(x, y, top), glam::DVec3::NEG_Z)
            .map(|p| p.z)
    };
    let mut out = Vec::with_capacity(entries.len());
    for e in entries {
        match e {
            PhotoEntry::Fitted(s) => out.push(s),
            PhotoEntry::Rough {
                name,
                image_path,
                size,
                pose,
                mask_path,
            } => {
                let r = rough_camera(&image_path, size, &pose, m.crs.as_deref(), &ground)?;
                for line in &r.notes {
                    note(&name, line);
                }
                out.push(PhotoSpec {
                    name,
                    image_path,
                    camera: r.camera,
                    unregistered: None,
                    mask_path,
                });
            }
        }
    }
    Ok(out)
}

/// [`register_photos_with`] without known photos, ties on by default.
pub fn register_photos(
    store_dir: &Path,
    specs: &[PhotoSpec],
    out: &Path,
    opts: &TerrainOptions,
    warn: &mut dyn FnMut(&str),
) -> Result<Vec<PhotoRegistration>> {
    register_photos_with(store_dir, specs, out, opts, &TieSettings::default(), warn)
}

/// Registers each photo of `specs` against the store in `store_dir` (each image decoded
/// once while the images kept for reuse fit in 1 GiB) with `opts`, known photos and ties
/// as `ties` says, and writes the refined list to `out` with camera files and a report
/// beside it (module docs). A photo nothing places keeps
/// its given camera (its camera file is a copy of it) and is reported with the reason;
/// `warn` is called with a line for it. Errors for a known name not in the list or a
/// moving mask not of the store's DEM size.
pub fn register_photos_with(
    store_dir: &Path,
    specs: &[PhotoSpec],
    out: &Path,
    opts: &TerrainOptions,
    ties: &TieSettings,
    warn: &mut dyn FnMut(&str),
) -> Result<Vec<PhotoRegistration>> {
    opts.validate()?;
    ties.validate()?;
    let store = Store::open(store_dir)?;
    check_tie_settings(&store, specs, ties)?;
    if opts.labels == LabelTexture::Best {
        check_photo_labels(&store, specs, &ties.known, warn)?;
    }
    // each photo decoded once while memory allows (anchors and label sources are reused)
    let images = DecodedPhotos::new(specs, DEFAULT_BUDGET_BYTES);
    let (dir, stem) = output_dir_and_stem(out);
    // known photos first, then each other photo: tied to a placed photo from the same place
    // if one is, else resected, else registered against the terrain; last, ties and
    // resections for the photos the terrain did not place, to photos placed after them
    let mut run = Registration::new(&store, specs, &images, opts, ties);
    for i in 0..specs.len() {
        if run.fits[i].is_none() {
            run.place(i, warn)?;
        }
    }
    for i in 0..specs.len() {
        run.retry_if_unplaced(i)?;
    }
    if opts.labels == LabelTexture::Best {
        second_pass_against_photos(
            &store,
            specs,
            &images,
            &mut run.fits,
            &run.trusted,
            opts,
            warn,
        )?;
    }
    let results = run.into_results(&dir, &stem, warn)?;
    write_report(&dir, &stem, opts, &results)?;
    write_photo_list(out, &dir, specs, &results)?;
    Ok(results)
}

/// Refuses a known photo not in the list and a moving mask not of the store's DEM size.
fn check_tie_settings(store: &Store, specs: &[PhotoSpec], ties: &TieSettings) -> Result<()> {
    if let Some(k) = ties
        .known
        .iter()
        .find(|k| !specs.iter().any(|s| &s.name == *k))
    {
        return Err(Error::BadOption(format!(
            "known photo {k:?} is not in the photo list"
        )));
    }
    if let Some(m) = &ties.moving_mask {
        let d = &store.manifest.dem;
        if m.dimensions() != (d.width, d.height) {
            return Err(Error::BadOption(format!(
                "the moving-surface mask is {}x{}, the store's DEM {}x{}",
                m.width(),
                m.height(),
                d.width,
                d.height
            )));
        }
    }
    Ok(())
}

/// The folder of `out` and the stem its side files are named after.
fn output_dir_and_stem(out: &Path) -> (PathBuf, String) {
    let dir = out
        .parent()
        .filter(|d| !d.as_os_str().is_empty())
        .unwrap_or(Path::new("."))
        .to_path_buf();
    let stem = out.file_stem().map_or_else(
        || "registered".to_string(),
        |s| s.to_string_lossy().into_owned(),
    );
    (dir, stem)
}

/// A photo's camera so far and how it was found.
type Placed = Option<(TerrainFit, &'static str)>;

/// One `register` run: every photo's fit, tie and resection so far, and whose position
/// may anchor a resection.
struct Registration<'a> {
    store: &'a Store,
    specs: &'a [PhotoSpec],
    images: &'a DecodedPhotos<'a>,
    opts: &'a TerrainOptions,
    ties: &'a TieSettings,
    fits: Vec<Placed>,
    tied: Vec<Option<(String, TieFit)>>,
    resected: Vec<Option<(String, ResectFit)>>,
    /// Known, resected, or tied to such a photo.
    trusted: Vec<bool>,
}

impl<'a> Registration<'a> {
    /// The run before any photo is placed: known photos keep their cameras.
    fn new(
        store: &'a Store,
        specs: &'a [PhotoSpec],
        images: &'a DecodedPhotos<'a>,
        opts: &'a TerrainOptions,
        ties: &'a TieSettings,
    ) -> Registration<'a> {
        let fits: Vec<Placed> = specs
            .iter()
            .map(|s| {
                ties.known
                    .contains(&s.name)
                    .then(|| (given(&s.camera), "known"))
            })
            .collect();
        let trusted = fits.iter().map(|f| f.is_some()).collect();
        Registration {
            store,
            specs,
            images,
            opts,
            ties,
            fits,
            tied: vec![None; specs.len()],
            resected: vec![None; specs.len()],
            trusted,
        }
    }

    /// Whether a world point lies on terrain that does not move (outside the moving mask).
    fn stable(&self) -> impl Fn(glam::DVec3) -> bool + Sync + 'a {
        let georef = self.store.manifest.georef;
        let mask = self.ties.moving_mask.as_ref();
        move |p| mask.is_none_or(|m| !georef.mask_covers(m, p.x, p.y))
    }

    /// Whether the photo named `anchor` has a trusted position.
    fn trusted_anchor(&self, anchor: &str) -> bool {
        self.specs
            .iter()
            .position(|s| s.name == anchor)
            .is_some_and(|j| self.trusted[j])
    }

    /// The nearest photo to photo `i` within `reach` metres that `eligible` allows, not
    /// `tried` already: its index and camera.
    fn nearest_anchor(
        &self,
        i: usize,
        reach: f64,
        tried: Option<&str>,
        eligible: impl Fn(usize, &TerrainFit) -> bool,
    ) -> Option<(usize, CameraModel)> {
        let here = self.specs[i].camera.position;
        (0..self.specs.len())
            .filter(|&j| j != i && Some(self.specs[j].name.as_str()) != tried)
            .filter_map(|j| {
                let (f, _) = self.fits[j].as_ref()?;
                eligible(j, f).then(|| (f.camera.position.distance(here), j, f.camera))
            })
            .filter(|(d, ..)| *d <= reach)
            .min_by(|a, b| a.0.total_cmp(&b.0).then(a.1.cmp(&b.1)))
            .map(|(_, j, camera)| (j, camera))
    }

    /// The tie of photo `i` to the nearest placed photo within reach not tried yet, if any.
    fn try_tie(&self, i: usize, tried: Option<&str>) -> Result<Option<(String, TieFit)>> {
        let reach = self.ties.options.max_distance_m;
        let Some((j, anchor)) = self.nearest_anchor(i, reach, tried, |_, f| f.converged) else {
            return Ok(None);
        };
        let (a_img, p_img) = (self.images.get(j)?, self.images.get(i)?);
        let terrain = LabelledTerrain::new(self.store, anchor.position)?;
        let tie = tie_photo(
            &anchor,
            &a_img,
            &p_img,
            &self.specs[i].camera,
            |o, d| terrain.hit(o, d),
            self.stable(),
            &self.ties.options,
        )
        .map_err(|e| Error::BadOption(format!("{}: {e}", self.specs[i].image_path.display())))?;
        Ok(Some((self.specs[j].name.clone(), tie)))
    }

    /// Photo `i` resected against the nearest photo with a trusted position within reach,
    /// not `tried` already.
    fn try_resect(&self, i: usize, tried: Option<&str>) -> Result<Option<(String, ResectFit)>> {
        if !(self.ties.resect_distance_m > 0.0) {
            return Ok(None);
        }
        let reach = self.ties.resect_distance_m;
        let Some((j, anchor)) = self.nearest_anchor(i, reach, tried, |j, _| self.trusted[j]) else {
            return Ok(None);
        };
        let (a_img, p_img) = (self.images.get(j)?, self.images.get(i)?);
        let terrain = LabelledTerrain::new(self.store, anchor.position)?;
        let (rough, resect_opts) = self.resection_start(i, j, &anchor)?;
        let fit = resect_photo(
            &anchor,
            &a_img,
            &p_img,
            &rough,
            |o, d| terrain.hit(o, d),
            self.stable(),
            &resect_opts,
        )
        .map_err(|e| Error::BadOption(format!("{}: {e}", self.specs[i].image_path.display())))?;
        Ok(Some((self.specs[j].name.clone(), fit)))
    }

    /// The start camera and options of photo `i`'s resection against photo `j`: with the
    /// same camera body (EXIF make, model, serial, lens, focal length) and image size, the
    /// anchor's intrinsics and the focal length not fitted (it would trade against the
    /// distance along the view).
    fn resection_start(
        &self,
        i: usize,
        j: usize,
        anchor: &CameraModel,
    ) -> Result<(CameraModel, ResectOptions)> {
        let specs = self.specs;
        let body = |k: usize| crate::camera::exif_camera_body(&specs[k].image_path);
        let same_body = (anchor.width, anchor.height)
            == (specs[i].camera.width, specs[i].camera.height)
            && matches!((body(i)?, body(j)?), (Some(a), Some(b)) if a == b);
        let (rough, mut resect_opts) = (specs[i].camera, self.ties.resection.clone());
        // the terrain the points are put on: the finest level, within its error bound
        resect_opts.surface_error_m = self.store.manifest.max_error;
        if !same_body {
            return Ok((rough, resect_opts));
        }
        resect_opts
            .free
            .retain(|p| !matches!(p, Param::F | Param::Fx | Param::Fy));
        let rough = CameraModel {
            fx: anchor.fx,
            fy: anchor.fy,
            cx: anchor.cx,
            cy: anchor.cy,
            k1: anchor.k1,
            k2: anchor.k2,
            ..rough
        };
        Ok((rough, resect_opts))
    }

    /// Places photo `i`: tied to a placed photo from the same place, else resected against
    /// a trusted one, else registered against the terrain.
    fn place(&mut self, i: usize, warn: &mut dyn FnMut(&str)) -> Result<()> {
        if let Some((anchor, tie)) = self.try_tie(i, None)? {
            let accepted = tie.accepted.then(|| {
                let mut f = given(&tie.camera);
                f.seconds = tie.seconds;
                f
            });
            self.trusted[i] = accepted.is_some() && self.trusted_anchor(&anchor);
            self.tied[i] = Some((anchor, tie));
            if let Some(f) = accepted {
                self.fits[i] = Some((f, "tie"));
                return Ok(());
            }
        }
        if let Some((anchor, r)) = self.try_resect(i, None)? {
            let accepted = r.accepted.then(|| {
                let mut f = given(&r.camera);
                f.seconds = r.seconds;
                f
            });
            self.resected[i] = Some((anchor, r));
            if let Some(f) = accepted {
                self.fits[i] = Some((f, "resection"));
                self.trusted[i] = true;
                return Ok(());
            }
        }
        self.register_against_terrain(i, warn)
    }

    /// Photo `i` registered against the terrain (labelled by the trusted photos placed so
    /// far with `--textures best`).
    fn register_against_terrain(&mut self, i: usize, warn: &mut dyn FnMut(&str)) -> Result<()> {
        let spec = &self.specs[i];
        let photo = self.images.get(i)?;
        let mut terrain =
            LabelledTerrain::for_options(self.store, spec.camera.position, self.opts)?;
        if self.opts.labels == LabelTexture::Best {
            // the photos placed so far with trusted cameras (known, or tied or resected to
            // such a photo) label the terrain they show
            let trusted = &self.trusted;
            set_label_photos(&mut terrain, self.images, &self.fits, |j| {
                j != i && trusted[j]
            })?;
        }
        let mask = registration_mask(spec, &photo)?;
        let masked = MaskedPhoto {
            image: &photo,
            mask: mask.as_ref(),
        };
        let fit = register_masked_to_terrain(&terrain, &masked, &spec.camera, self.opts)
            .map_err(|e| Error::BadOption(format!("{}: {e}", spec.image_path.display())))?;
        if fit.photo_label_share.is_some_and(|s| s < 0.01) {
            warn(&format!(
                "{}: none of the trusted photos shows what it sees; registered against the \
                 store's textures",
                spec.name
            ));
        }
        self.fits[i] = Some((fit, "terrain"));
        Ok(())
    }

    /// A photo the terrain did not place tries a resection, then a tie, against photos
    /// placed after it (anchors not tried before).
    fn retry_if_unplaced(&mut self, i: usize) -> Result<()> {
        let unplaced = self.fits[i]
            .as_ref()
            .is_some_and(|(f, m)| !f.converged && *m == "terrain");
        if !unplaced {
            return Ok(());
        }
        let earlier = self.fits[i].as_ref().map_or(0.0, |(f, _)| f.seconds);
        let tried = self.resected[i].as_ref().map(|(a, _)| a.clone());
        if let Some((anchor, r)) = self.try_resect(i, tried.as_deref())? {
            if r.accepted {
                let mut f = given(&r.camera);
                f.seconds = r.seconds + earlier;
                self.fits[i] = Some((f, "resection"));
                self.trusted[i] = true;
                self.resected[i] = Some((anchor, r));
                return Ok(());
            }
            self.resected[i] = Some((anchor, r));
        }
        let tried = self.tied[i].as_ref().map(|(a, _)| a.clone());
        if let Some((anchor, tie)) = self.try_tie(i, tried.as_deref())? {
            if tie.accepted {
                let mut f = given(&tie.camera);
                f.seconds = tie.seconds + earlier;
                self.fits[i] = Some((f, "tie"));
                self.trusted[i] = self.trusted_anchor(&anchor);
            }
            self.tied[i] = Some((anchor, tie));
        }
        Ok(())
    }

    /// Each photo's registration, its camera file written as `DIR/STEM.NAME.camera.json`
    /// (a photo nothing placed keeps its given camera, with a warning).
    fn into_results(
        self,
        dir: &Path,
        stem: &str,
        warn: &mut dyn FnMut(&str),
    ) -> Result<Vec<PhotoRegistration>> {
        let specs = self.specs;
        let fits: Vec<(TerrainFit, &'static str)> = self
            .fits
            .into_iter()
            .zip(specs)
            .map(|(f, s)| f.unwrap_or_else(|| (given(&s.camera), "known")))
            .collect();
        let mut results = Vec::with_capacity(specs.len());
        for (((spec, (fit, method)), tie), resection) in
            specs.iter().zip(fits).zip(self.tied).zip(self.resected)
        {
            if let Some(why) = &fit.reason {
                warn(&format!(
                    "{}: not registered, keeping its given camera: {why}{}",
                    spec.name,
                    attempts_note(&tie, &resection)
                ));
            }
            let camera_file = dir.join(format!("{stem}.{}.camera.json", safe_name(&spec.name)));
            let text = serde_json::to_string_pretty(&camera_to_json(&fit.camera))
                .map_err(|e| Error::BadOption(e.to_string()))?;
            write_atomic(&camera_file, text.as_bytes())?;
            results.push(PhotoRegistration {
                name: spec.name.clone(),
                rough: spec.camera,
                fit,
                method,
                tie,
                resection,
                camera_file,
            });
        }
        Ok(results)
    }
}

/// What the tie and the resection of an unregistered photo said (`; tie to A: why`).
fn attempts_note(
    tie: &Option<(String, TieFit)>,
    resection: &Option<(String, ResectFit)>,
) -> String {
    let mut note = match tie {
        Some((anchor, t)) => format!(
            "; tie to {anchor}: {}",
            t.reason.as_deref().unwrap_or("accepted")
        ),
        None => String::new(),
    };
    if let Some((anchor, r)) = resection {
        note += &format!(
            "; resection against {anchor}: {}",
            r.reason.as_deref().unwrap_or("accepted")
        );
    }
    note
}

/// A photo name as a file name part: ASCII letters, digits, `-` and `_`, the rest `_`.
fn safe_name(name: &str) -> String {
    name.chars()
        .map(|c| {
            if c.is_ascii_alphanumeric() || c == '-' || c == '_' {
                c
            } else {
                '_'
            }
        })
        .collect()
}

/// Writes `DIR/STEM.report.json`: the textures registered against and each photo's entry.
fn write_report(
    dir: &Path,
    stem: &str,
    opts: &TerrainOptions,
    results: &[PhotoRegistration],
) -> Result<()> {
    let report = json!({
        "textures": opts.labels.name(),
        "photos": results.iter().map(report_entry).collect::<Vec<Value>>(),
    });
    let report_path = dir.join(format!("{stem}.report.json"));
    write_atomic(
        &report_path,
        serde_json::to_string_pretty(&report)
            .map_err(|e| Error::BadOption(e.to_string()))?
            .as_bytes(),
    )
}

/// Writes the refined photo list `out` (image paths relative to `dir`; a photo not
/// registered is marked so, and `project` leaves it out unless asked).
fn write_photo_list(
    out: &Path,
    dir: &Path,
    specs: &[PhotoSpec],
    results: &[PhotoRegistration],
) -> Result<()> {
    let entries: Vec<Value> = specs
        .iter()
        .zip(results)
        .map(|(s, r)| {
            let mut e = json!({ "image": relative_or_absolute(&s.image_path, dir), "camera": file_name(&r.camera_file) });
            if let Some(m) = &s.mask_path {
                e["mask"] = json!(relative_or_absolute(m, dir));
            }
            if !r.fit.converged {
                // the given camera is kept; `project` leaves the photo out unless asked
                e["registered"] = json!(false);
                e["reason"] = json!(format!(
                    "not registered, its given camera kept: {}",
                    r.fit.reason.as_deref().unwrap_or("did not converge")
                ));
            }
            e
        })
        .collect();
    write_atomic(
        out,
        serde_json::to_string_pretty(&json!({ "photos": entries }))
            .map_err(|e| Error::BadOption(e.to_string()))?
            .as_bytes(),
    )
}

/// The fit recorded for a camera taken as it is (known, or from a tie): trusted, no search.
fn given(camera: &CameraModel) -> TerrainFit {
    TerrainFit {
        camera: *camera,
        found: *camera,
        converged: true,
        reason: None,
        score_start: f64::NAN,
        score_final: f64::NAN,
        repeat_px: f64::NAN,
        evaluations: 0,
        edges: None,
        position_kept_parallax_px_per_m: None,
        photo_label_share: None,
        seconds: 0.0,
    }
}

/// The report entry of one photo: verdict, scores and each parameter's change.
fn report_entry(r: &PhotoRegistration) -> Value {
    let a = CameraParams::from_camera(&r.rough);
    let b = CameraParams::from_camera(&r.fit.found);
    let change = |p: Param| {
        let d = b.get(p) - a.get(p);
        if p.is_angle() { d.to_degrees() } else { d }
    };
    json!({
        "name": r.name,
        "method": r.method,
        "converged": r.fit.converged,
        "tie": r.tie.as_ref().map(|(anchor, t)| json!({
            "anchor": anchor,
            "accepted": t.accepted,
            "reason": t.reason,
            "matches": t.matches[0],
            "matches_on_stable_terrain": t.matches[1],
            "inliers": t.matches[2],
            "rmse_inliers_px": t.rmse_inliers_px,
            "turn_deg": t.turn_deg,
            "seconds": t.seconds,
        })),
        "resection": r.resection.as_ref().map(|(anchor, f)| json!({
            "anchor": anchor,
            "accepted": f.accepted,
            "reason": f.reason,
            "terrain_points": f.counts[0],
            "coarse_matches": f.counts[1],
            "fine_matches": f.counts[2],
            "inliers": f.counts[3],
            "rmse_inliers_px": f.rmse_inliers_px,
            "sigma_position_m": f.sigma_position_m,
            "moved_m": f.moved_m,
            "focal_fitted": f.focal_fitted,
            "seconds": f.seconds,
        })),
        "reason": r.fit.reason,
        "score_start": r.fit.score_start,
        "score_final": r.fit.score_final,
        "repeat_px": r.fit.repeat_px,
        "change_found": {
            "yaw_deg": change(Param::Yaw), "pitch_deg": change(Param::Pitch), "roll_deg": change(Param::Roll),
            "fx_px": change(Param::Fx), "fy_px": change(Param::Fy),
            "x_m": change(Param::X), "y_m": change(Param::Y), "z_m": change(Param::Z),
        },
        "applied": r.fit.converged,
        "edges": r.fit.edges.as_ref().map(|e| json!({
            "matched": e.matched,
            "median_px": e.median_px,
            "position_repeat_m": e.position_repeat_m,
            "sigma": e.sigma.iter().map(|(p, v)| {
                let v = if p.is_angle() { v.to_degrees() } else { *v };
                (format!("{}{}", p.name(), if p.is_angle() { "_deg" } else if matches!(p, Param::X | Param::Y | Param::Z) { "_m" } else { "_px" }), json!(v))
            }).collect::<serde_json::Map<String, Value>>(),
        })),
        "position_kept_parallax_px_per_m": r.fit.position_kept_parallax_px_per_m,
        "photo_label_share": r.fit.photo_label_share,
        "evaluations": r.fit.evaluations,
        "seconds": r.fit.seconds,
        "camera": file_name(&r.camera_file),
    })
}

fn file_name(p: &Path) -> String {
    p.file_name().map_or_else(
        || p.display().to_string(),
        |n| n.to_string_lossy().into_owned(),
    )
}

/// `p` relative to `dir` when `p` lies under it, else `p` made absolute.
fn relative_or_absolute(p: &Path, dir: &Path) -> String {
    let abs = |q: &Path| std::fs::canonicalize(q).unwrap_or_else(|_| q.to_path_buf());
    let (pa, da) = (abs(p), abs(dir));
    match pa.strip_prefix(&da) {
        Ok(rel) => rel.display().to_string(),
        Err(_) => pa.display().to_string(),
    }
}

/// With photo textures as the terrain's labels: a photo to be registered must not be one
/// of those the store's textures were projected from (it would be fitted to its own colours
/// where its given camera put them, and keep that camera); known photos may be. A store
/// without photo textures and a run without known photos get a warning (the active
/// textures label the samples).
fn check_photo_labels(
    store: &Store,
    specs: &[PhotoSpec],
    known: &[String],
    warn: &mut dyn FnMut(&str),
) -> Result<()> {
    let Some(projected) = &store.manifest.photos else {
        if !known.is_empty() {
            return Ok(());
        }
        warn(&format!(
            "{}: no photo textures and no --known photos to label the terrain (project \
             photos whose cameras are trusted first, or name them with --known); \
             registering against the active textures",
            store.dir.display()
        ));
        return Ok(());
    };
    if let Some(s) = specs
        .iter()
        .find(|s| !known.contains(&s.name) && projected.photos.iter().any(|p| p.name == s.name))
    {
        return Err(Error::BadOption(format!(
            "{}: the store's photo textures were projected from this photo ({}), so \
             registering it against them would only find the camera it was projected with; \
             name it with --known, project only trusted photos first, or register against \
             the active textures",
            s.image_path.display(),
            store.dir.display()
        )));
    }
    Ok(())
}

/// With `--textures best`, after every photo has been placed or not: each photo the terrain
/// search was run on is registered again, in list order, from its camera (the one found, or
/// the given one if the search refused it), with the pixels of every other placed photo
/// (known, tied, resected, or registered; their current cameras, so a photo sees the ones
/// before it already refined) labelling the terrain they show. Kept when that search
/// converges (method "terrain_photos", so a photo the terrain alone could not confirm may
/// be placed by the others); skipped for a photo no other placed photo overlaps (under 1 %
/// of its terrain samples, on the photo reduced 8 times). Two rough photos of one target:
/// on the demo scene median pixel errors 0.63 / 0.46 → 0.38 / 0.32 px and their
/// disagreement on the terrain both show 1.04 → 0.35 px; on the tall-walls scene 8 → 12 of
/// 12 cameras placed (docs/registration.md).
fn second_pass_against_photos(
    store: &Store,
    specs: &[PhotoSpec],
    images: &DecodedPhotos,
    fits: &mut [Option<(TerrainFit, &'static str)>],
    trusted: &[bool],
    opts: &TerrainOptions,
    warn: &mut dyn FnMut(&str),
) -> Result<()> {
    let placed = |f: &Option<(TerrainFit, &'static str)>, j: usize| {
        f.as_ref().is_some_and(|(f, _)| f.converged) || trusted[j]
    };
    for i in 0..specs.len() {
        // every photo the terrain search was run on: registered ones from their camera,
        // refused ones (whose camera is still the given one) from that
        let Some((first, "terrain")) = &fits[i] else {
            continue;
        };
        let source = |j: usize| j != i && placed(&fits[j], j);
        if !(0..specs.len()).any(source) {
            continue;
        }
        let spec = &specs[i];
        let mut terrain = LabelledTerrain::for_options(store, spec.camera.position, opts)?;
        set_label_photos(&mut terrain, images, fits, source)?;
        let small = first.camera.resized(
            (first.camera.width / 8).max(16),
            (first.camera.height / 8).max(12),
        );
        if terrain.photo_label_share(&small)? < 0.01 {
            continue;
        }
        let photo = images.get(i)?;
        let start = first.camera;
        let mask = registration_mask(spec, &photo)?;
        let masked = MaskedPhoto {
            image: &photo,
            mask: mask.as_ref(),
        };
        let fit = register_masked_to_terrain(&terrain, &masked, &start, opts)
            .map_err(|e| Error::BadOption(format!("{}: {e}", spec.image_path.display())))?;
        if fit.converged {
            let mut f = fit;
            f.seconds += first.seconds;
            fits[i] = Some((f, "terrain_photos"));
        } else if first.converged {
            warn(&format!(
                "{}: registered against the terrain; the second pass against the other \
                 photos did not confirm a change ({}), the first camera kept",
                spec.name,
                fit.reason.as_deref().unwrap_or("not converged")
            ));
        }
    }
    Ok(())
}

/// Gives `terrain` the photos `pick` chooses among those with a fit as label photos (their
/// fitted cameras; images from `images`).
fn set_label_photos(
    terrain: &mut LabelledTerrain,
    images: &DecodedPhotos,
    fits: &[Option<(TerrainFit, &'static str)>],
    pick: impl Fn(usize) -> bool,
) -> Result<()> {
    let mut sources = Vec::new();
    for (j, fit) in fits.iter().enumerate().filter(|(j, _)| pick(*j)) {
        if let Some((f, _)) = fit {
            sources.push((f.camera, images.get(j)?));
        }
    }
    let refs: Vec<(CameraModel, &image::RgbImage)> =
        sources.iter().map(|(c, img)| (*c, img.as_ref())).collect();
    terrain.set_label_photos(&refs);
    Ok(())
}

/// The pixels of photo `spec` (decoded as `image`) registration leaves out: its mask file
/// (`"mask"`) and its uniform borders ([`crate::photo::uniform_border`]); `None` when none.
fn registration_mask(
    spec: &PhotoSpec,
    image: &image::RgbImage,
) -> Result<Option<crate::photo::PixelMask>> {
    let (mut mask, _) = crate::photo::uniform_border(image);
    if let Some(p) = &spec.mask_path {
        mask.union(&crate::photo::PixelMask::read(
            p,
            image.width(),
            image.height(),
        )?);
    }
    Ok((mask.count() > 0).then_some(mask))
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_library_checks_the_options_the_command_line_used_to() {
        assert!(TieSettings::default().validate().is_ok());
        let mut t = TieSettings::default();
        t.options.max_distance_m = -1.0;
        let e = t.validate().unwrap_err().to_string();
        assert!(e.contains("--tie-distance-m"), "{e}");
        let mut t = TieSettings::default();
        t.resection.max_rmse_px = 0.0;
        let e = t.validate().unwrap_err().to_string();
        assert!(e.contains("--resect-rmse-px"), "{e}");
        let t = TieSettings {
            resect_distance_m: 0.0, // resection off
            ..TieSettings::default()
        };
        assert!(t.validate().is_ok());
        let o = TerrainOptions {
            search_deg: [4.0, 40.0, 2.0],
            ..TerrainOptions::default()
        };
        assert!(
            o.validate()
                .unwrap_err()
                .to_string()
                .contains("--search-deg")
        );
        let o = TerrainOptions {
            repeat_px: f64::NAN,
            ..TerrainOptions::default()
        };
        assert!(
            o.validate()
                .unwrap_err()
                .to_string()
                .contains("--repeat-px")
        );
    }
}
