//! Parsing of "Camera JSON" (docs/formats.md): cliffmap cameras and ImGRAFT-style files.

use std::path::Path;

use glam::DVec3;
use serde_json::{Map, Value};

use super::{CameraModel, rotation_from_yaw_pitch_roll, rotation_look_at};
use crate::error::{Error, Result};

/// Reads a camera file. `default_size` (width, height) is the image size used when the file
/// gives none (a cliffmap camera with only `fov_y_deg`).
pub fn camera_from_json_file(path: &Path, default_size: (u32, u32)) -> Result<CameraModel> {
    let text = std::fs::read_to_string(path).map_err(|e| Error::io(path, e))?;
    camera_from_json_str(&text, path, default_size)
}

/// Parses camera JSON text; `path` names the source in errors. See [`camera_from_json_file`].
pub fn camera_from_json_str(
    text: &str,
    path: &Path,
    default_size: (u32, u32),
) -> Result<CameraModel> {
    let v: Value = serde_json::from_str(text)
        .map_err(|e| Error::bad_input(path, format!("invalid JSON: {e}")))?;
    let obj = v
        .as_object()
        .ok_or_else(|| Error::bad_input(path, "a camera must be a JSON object"))?;
    let cam = if obj
        .keys()
        .any(|k| k.starts_with("camera_xyz") || k.starts_with("viewdir_yaw_pitch_roll"))
    {
        imgraft(obj, path)?
    } else {
        cliffmap(obj, path, default_size)?
    };
    validate(cam, path)
}

fn num(obj: &Map<String, Value>, key: &str, path: &Path) -> Result<Option<f64>> {
    match obj.get(key) {
        None | Some(Value::Null) => Ok(None),
        Some(v) => match v.as_f64() {
            Some(x) if x.is_finite() => Ok(Some(x)),
            _ => Err(Error::bad_input(
                path,
                format!("\"{key}\" must be a finite number, got {v}"),
            )),
        },
    }
}

fn nums(obj: &Map<String, Value>, key: &str, n: usize, path: &Path) -> Result<Option<Vec<f64>>> {
    let Some(v) = obj.get(key) else {
        return Ok(None);
    };
    let bad = || {
        Error::bad_input(
            path,
            format!("\"{key}\" must be an array of {n} finite numbers, got {v}"),
        )
    };
    let arr = v.as_array().ok_or_else(bad)?;
    let out: Vec<f64> = arr
        .iter()
        .map(|x| x.as_f64().filter(|x| x.is_finite()))
        .collect::<Option<_>>()
        .ok_or_else(bad)?;
    if out.len() != n {
        return Err(bad());
    }
    Ok(Some(out))
}

fn size(obj: &Map<String, Value>, path: &Path) -> Result<Option<(u32, u32)>> {
    let pair = match nums(obj, "image_size_wh", 2, path)? {
        Some(v) => Some((v[0], v[1])),
        None => match (num(obj, "width", path)?, num(obj, "height", path)?) {
            (Some(w), Some(h)) => Some((w, h)),
            (None, None) => None,
            _ => {
                return Err(Error::bad_input(
                    path,
                    "give both \"width\" and \"height\" or neither",
                ));
            }
        },
    };
    match pair {
        None => Ok(None),
        Some((w, h))
            if w >= 1.0
                && h >= 1.0
                && w <= 1e6
                && h <= 1e6
                && w.fract() == 0.0
                && h.fract() == 0.0 =>
        {
            Ok(Some((w as u32, h as u32)))
        }
        Some((w, h)) => Err(Error::bad_input(
            path,
            format!("image size {w} x {h} must be positive whole pixels"),
        )),
    }
}

fn imgraft(obj: &Map<String, Value>, path: &Path) -> Result<CameraModel> {
    // The position is the `camera_xyz...` key holding an array (e.g. `camera_xyz_utm33n_nn1954_m`;
    // sibling keys such as `camera_xyz_source` are notes).
    let xyz_key = obj
        .iter()
        .find(|(k, v)| k.starts_with("camera_xyz") && v.is_array())
        .map(|(k, _)| k.clone());
    let xyz = match xyz_key {
        Some(k) => nums(obj, &k, 3, path)?.unwrap_or_default(),
        None => {
            return Err(Error::bad_input(
                path,
                "ImGRAFT camera without \"camera_xyz...\" position",
            ));
        }
    };
    let angles = if let Some(r) = nums(obj, "viewdir_yaw_pitch_roll_rad", 3, path)? {
        r
    } else if let Some(d) = nums(obj, "viewdir_yaw_pitch_roll_deg", 3, path)? {
        d.iter().map(|a| a.to_radians()).collect()
    } else {
        return Err(Error::bad_input(
            path,
            "ImGRAFT camera needs \"viewdir_yaw_pitch_roll_rad\" or \"_deg\"",
        ));
    };
    let (w, h) = size(obj, path)?
        .ok_or_else(|| Error::bad_input(path, "ImGRAFT camera needs \"image_size_wh\""))?;
    let (fx, fy) = match obj.get("f_px") {
        Some(Value::Array(_)) => nums(obj, "f_px", 2, path)?
            .map(|f| (f[0], f[1]))
            .unwrap_or_default(),
        Some(_) => num(obj, "f_px", path)?.map(|f| (f, f)).unwrap_or_default(),
        None => {
            return Err(Error::bad_input(
                path,
                "ImGRAFT camera needs \"f_px\" (focal length in pixels)",
            ));
        }
    };
    let (cx, cy) = if let Some(c) = nums(obj, "c_px_0based", 2, path)? {
        (c[0], c[1])
    } else if let Some(c) = nums(obj, "c_px_1based", 2, path)? {
        (c[0] - 1.0, c[1] - 1.0)
    } else {
        ((w as f64 - 1.0) / 2.0, (h as f64 - 1.0) / 2.0)
    };
    Ok(CameraModel {
        position: DVec3::new(xyz[0], xyz[1], xyz[2]),
        world_to_camera: rotation_from_yaw_pitch_roll(angles[0], angles[1], angles[2]),
        width: w,
        height: h,
        fx,
        fy,
        cx,
        cy,
        k1: num(obj, "k1", path)?.unwrap_or(0.0),
        k2: num(obj, "k2", path)?.unwrap_or(0.0),
    })
}

fn cliffmap(
    obj: &Map<String, Value>,
    path: &Path,
    default_size: (u32, u32),
) -> Result<CameraModel> {
    let p = nums(obj, "position", 3, path)?.ok_or_else(|| {
        Error::bad_input(path, "camera needs \"position\": [x, y, z] (world metres)")
    })?;
    let position = DVec3::new(p[0], p[1], p[2]);
    let rotation = if let Some(t) = nums(obj, "look_at", 3, path)? {
        rotation_look_at(position, DVec3::new(t[0], t[1], t[2]))
            .ok_or_else(|| Error::bad_input(path, "\"look_at\" must differ from \"position\""))?
    } else {
        match (num(obj, "yaw_deg", path)?, num(obj, "pitch_deg", path)?) {
            (Some(y), Some(p)) => {
                let r = num(obj, "roll_deg", path)?.unwrap_or(0.0);
                rotation_from_yaw_pitch_roll(y.to_radians(), p.to_radians(), r.to_radians())
            }
            _ => {
                return Err(Error::bad_input(
                    path,
                    "camera needs a view direction: \"look_at\": [x, y, z] or \"yaw_deg\" and \"pitch_deg\"",
                ));
            }
        }
    };
    let explicit = size(obj, path)?;
    let (w, h) = explicit.unwrap_or(default_size);
    let fov = num(obj, "fov_y_deg", path)?;
    if let Some(f) = fov
        && !(f > 0.0 && f < 180.0)
    {
        return Err(Error::bad_input(
            path,
            format!("\"fov_y_deg\" must be in (0, 180), got {f}"),
        ));
    }
    let (fx, fy) = (num(obj, "fx", path)?, num(obj, "fy", path)?);
    let mut cam = match (fx.or(fy), fov) {
        (Some(_), _) if explicit.is_none() => {
            return Err(Error::bad_input(
                path,
                "\"fx\"/\"fy\" are in pixels: give \"width\" and \"height\" too",
            ));
        }
        (Some(f), _) => {
            let mut c = CameraModel::with_fov(position, rotation, w, h, 1.0);
            c.fx = fx.unwrap_or(f);
            c.fy = fy.unwrap_or(f);
            c
        }
        (None, Some(f)) => CameraModel::with_fov(position, rotation, w, h, f.to_radians()),
        (None, None) => {
            return Err(Error::bad_input(
                path,
                "camera needs \"fov_y_deg\" (or \"fx\" with width/height)",
            ));
        }
    };
    if let Some(cx) = num(obj, "cx", path)? {
        cam.cx = cx;
    }
    if let Some(cy) = num(obj, "cy", path)? {
        cam.cy = cy;
    }
    cam.k1 = num(obj, "k1", path)?.unwrap_or(0.0);
    cam.k2 = num(obj, "k2", path)?.unwrap_or(0.0);
    Ok(cam)
}

fn validate(c: CameraModel, path: &Path) -> Result<CameraModel> {
    match c.problem() {
        Some(msg) => Err(Error::bad_input(path, msg)),
        None => Ok(c),
    }
}

/// The cliffmap Camera JSON (docs/formats.md) of `cam`: position, ImGRAFT angles in degrees
/// (`yaw_deg`, `pitch_deg`, `roll_deg`), `width`/`height`, `fx`, `fy`, `cx`, `cy`, `k1`, `k2`.
/// Reading it back with [`camera_from_json_str`] gives the same camera up to rounding
/// (rotations to ~1e-12).
pub fn camera_to_json(cam: &CameraModel) -> Value {
    let (yaw, pitch, roll) = super::yaw_pitch_roll_from_rotation(&cam.world_to_camera);
    serde_json::json!({
        "position": [cam.position.x, cam.position.y, cam.position.z],
        "yaw_deg": yaw.to_degrees(),
        "pitch_deg": pitch.to_degrees(),
        "roll_deg": roll.to_degrees(),
        "width": cam.width,
        "height": cam.height,
        "fx": cam.fx,
        "fy": cam.fy,
        "cx": cam.cx,
        "cy": cam.cy,
        "k1": cam.k1,
        "k2": cam.k2,
    })
}

/// The ImGRAFT-style Camera JSON of `cam` (the keys of the Engabreen camera file):
/// `image_size_wh`, `camera_xyz_m`, `viewdir_yaw_pitch_roll_rad` and `_deg`, `f_px`
/// (`[fx, fy]`), `c_px_0based`, `c_px_1based`, `k1`, `k2`, `R_world_to_camera_rows` and a
/// `model` note. Reading it back with [`camera_from_json_str`] gives the same camera up to
/// rounding.
pub fn camera_to_imgraft_json(cam: &CameraModel) -> Value {
    let (yaw, pitch, roll) = super::yaw_pitch_roll_from_rotation(&cam.world_to_camera);
    let r = cam.world_to_camera;
    serde_json::json!({
        "image_size_wh": [cam.width, cam.height],
        "camera_xyz_m": [cam.position.x, cam.position.y, cam.position.z],
        "viewdir_yaw_pitch_roll_rad": [yaw, pitch, roll],
        "viewdir_yaw_pitch_roll_deg": [yaw.to_degrees(), pitch.to_degrees(), roll.to_degrees()],
        "f_px": [cam.fx, cam.fy],
        "c_px_0based": [cam.cx, cam.cy],
        "c_px_1based": [cam.cx + 1.0, cam.cy + 1.0],
        "k1": cam.k1,
        "k2": cam.k2,
        "R_world_to_camera_rows": [r.row(0).to_array(), r.row(1).to_array(), r.row(2).to_array()],
        "model": "ImGRAFT camera.m pinhole: x_c = R*(X - xyz); (x,y)=x_c[0:2]/x_c[2]; r2=min(x^2+y^2,4); (x,y)*=(1+k1*r2+k2*r2^2); u=fx*x+cx, v=fy*y+cy",
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn imgraft_writer_round_trips() {
        let cam = CameraModel {
            position: DVec3::new(446722.0, 7396671.0, 770.0),
            world_to_camera: rotation_from_yaw_pitch_roll(3.83, 0.1, -0.013),
            width: 4290,
            height: 2856,
            fx: 6014.4,
            fy: 6021.5,
            cx: 2144.5,
            cy: 1427.0,
            k1: -0.11,
            k2: 0.01,
        };
        let back = parse(&camera_to_imgraft_json(&cam).to_string()).unwrap();
        assert_eq!(
            (
                back.width,
                back.height,
                back.fx,
                back.fy,
                back.cx,
                back.cy,
                back.k1,
                back.k2
            ),
            (4290, 2856, 6014.4, 6021.5, 2144.5, 1427.0, -0.11, 0.01)
        );
        assert!(back.position == cam.position);
        assert!(
            (back.world_to_camera - cam.world_to_camera)
                .to_cols_array()
                .iter()
                .all(|v| v.abs() < 1e-12)
        );
    }

    fn parse(s: &str) -> Result<CameraModel> {
        camera_from_json_str(s, Path::new("cam.json"), (640, 480))
    }

    #[test]
    fn cliffmap_forms() {
        let a =
            parse(r#"{"position":[1,2,3],"yaw_deg":90,"pitch_deg":10,"fov_y_deg":60}"#).unwrap();
        assert_eq!((a.width, a.height), (640, 480));
        assert!((a.fov_y().to_degrees() - 60.0).abs() < 1e-9);
        assert!((a.forward().y - 10f64.to_radians().cos()).abs() < 1e-12);
        let b = parse(r#"{"position":[0,0,10],"look_at":[0,100,10],"fov_y_deg":45,"width":200,"height":100,"k1":-0.1}"#)
            .unwrap();
        assert_eq!((b.width, b.height, b.k1), (200, 100, -0.1));
        let c = parse(
            r#"{"position":[0,0,0],"look_at":[1,0,0],"fx":100,"width":200,"height":100,"cx":90}"#,
        )
        .unwrap();
        assert_eq!((c.fx, c.fy, c.cx), (100.0, 100.0, 90.0));
    }

    #[test]
    fn writer_round_trips() {
        let r = crate::camera::rotation_look_at(DVec3::ZERO, DVec3::new(-3.0, 1.0, -0.4)).unwrap();
        let mut cam = CameraModel::with_fov(
            DVec3::new(431_234.5, 6_877_100.25, 612.7),
            r,
            1600,
            1200,
            0.8,
        );
        cam.k1 = -0.05;
        cam.cx += 3.5;
        let text = camera_to_json(&cam).to_string();
        let back = parse(&text).unwrap();
        assert_eq!(
            (back.width, back.height, back.fx, back.cx, back.k1),
            (1600, 1200, cam.fx, cam.cx, -0.05)
        );
        assert_eq!(back.position, cam.position);
        assert!(
            (back.world_to_camera - cam.world_to_camera)
                .to_cols_array()
                .iter()
                .all(|v| v.abs() < 1e-12)
        );
    }

    #[test]
    fn rejects_bad_cameras() {
        for s in [
            "[]",
            r#"{"yaw_deg":0,"pitch_deg":0,"fov_y_deg":60}"#,
            r#"{"position":[0,0],"yaw_deg":0,"pitch_deg":0,"fov_y_deg":60}"#,
            r#"{"position":[0,0,0],"fov_y_deg":60}"#,
            r#"{"position":[0,0,0],"yaw_deg":0,"pitch_deg":0}"#,
            r#"{"position":[0,0,0],"yaw_deg":0,"pitch_deg":0,"fov_y_deg":190}"#,
            r#"{"position":[0,0,0],"look_at":[0,0,0],"fov_y_deg":60}"#,
            r#"{"position":[0,0,0],"yaw_deg":0,"pitch_deg":0,"fx":100}"#,
            r#"{"camera_xyz":[0,0,0],"viewdir_yaw_pitch_roll_deg":[0,0,0],"f_px":100}"#,
        ] {
            let e = parse(s).unwrap_err().to_string();
            assert!(e.contains("cam.json"), "{e}");
        }
    }
}
