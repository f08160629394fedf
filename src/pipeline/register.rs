//! `register`: every photo of a list refined against a store's terrain, then a new photo
//! list with the refined cameras and a report.
//!
//! Output files (all written atomically, the list last): `OUT` (the same format as
//! `photos.json`, image paths relative to its folder), `OUT_STEM.NAME.camera.json` per photo
//! (cliffmap Camera JSON), and `OUT_STEM.report.json` (per photo: verdict, reason, scores,
//! parameter changes, repeatability, time).

use std::path::{Path, PathBuf};

use serde_json::{Value, json};

use crate::camera::{CameraModel, camera_to_json};
use crate::error::{Error, Result};
use crate::fsutil::write_atomic;
use crate::photo::PhotoSpec;
use crate::register::{
    CameraParams, Param, TerrainFit, TerrainOptions, TerrainScene, register_to_terrain,
};
use crate::store::Store;

/// One photo's registration.
#[derive(Clone, Debug, PartialEq)]
pub struct PhotoRegistration {
    /// The photo's name (its file name).
    pub name: String,
    /// The camera given.
    pub rough: CameraModel,
    /// The terrain fit (its `camera` is the one written).
    pub fit: TerrainFit,
    /// The camera file written.
    pub camera_file: PathBuf,
}

/// Registers each photo of `specs` (decoded one at a time) against the store in `store_dir`
/// with `opts`, and writes the refined list to `out` with camera files and a report beside
/// it (module docs). A photo that does not converge keeps its given camera (its camera
/// file is a copy of it) and is reported with the reason; `warn` is called with a line for
/// it.
pub fn register_photos(
    store_dir: &Path,
    specs: &[PhotoSpec],
    out: &Path,
    opts: &TerrainOptions,
    warn: &mut dyn FnMut(&str),
) -> Result<Vec<PhotoRegistration>> {
    let store = Store::open(store_dir)?;
    let dir = out
        .parent()
        .filter(|d| !d.as_os_str().is_empty())
        .unwrap_or(Path::new("."))
        .to_path_buf();
    let stem = out.file_stem().map_or_else(
        || "registered".to_string(),
        |s| s.to_string_lossy().into_owned(),
    );
    let mut results = Vec::with_capacity(specs.len());
    for spec in specs {
        let photo = spec.load()?;
        let terrain = TerrainScene::new(&store, spec.camera.position)?;
        let fit = register_to_terrain(&terrain, &photo.image, &spec.camera, opts)
            .map_err(|e| Error::BadOption(format!("{}: {e}", spec.image_path.display())))?;
        if let Some(why) = &fit.reason {
            warn(&format!(
                "{}: not registered, keeping its given camera: {why}",
                spec.name
            ));
        }
        let safe: String = spec
            .name
            .chars()
            .map(|c| {
                if c.is_ascii_alphanumeric() || c == '-' || c == '_' {
                    c
                } else {
                    '_'
                }
            })
            .collect();
        let camera_file = dir.join(format!("{stem}.{safe}.camera.json"));
        let text = serde_json::to_string_pretty(&camera_to_json(&fit.camera))
            .map_err(|e| Error::BadOption(e.to_string()))?;
        write_atomic(&camera_file, text.as_bytes())?;
        results.push(PhotoRegistration {
            name: spec.name.clone(),
            rough: spec.camera,
            fit,
            camera_file,
        });
    }
    let report = json!({ "photos": results.iter().map(report_entry).collect::<Vec<Value>>() });
    let report_path = dir.join(format!("{stem}.report.json"));
    write_atomic(
        &report_path,
        serde_json::to_string_pretty(&report)
            .map_err(|e| Error::BadOption(e.to_string()))?
            .as_bytes(),
    )?;
    let entries: Vec<Value> = specs
        .iter()
        .zip(&results)
        .map(|(s, r)| json!({ "image": relative_or_absolute(&s.image_path, &dir), "camera": file_name(&r.camera_file) }))
        .collect();
    write_atomic(
        out,
        serde_json::to_string_pretty(&json!({ "photos": entries }))
            .map_err(|e| Error::BadOption(e.to_string()))?
            .as_bytes(),
    )?;
    Ok(results)
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
        "converged": r.fit.converged,
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
