//! The photo part of `stats.json`: how much of the steep terrain photos improved, and what
//! each photo contributed (from the manifest records of the last `cliffmap project` run).

use serde_json::json;

use crate::store::Manifest;

/// Adds to `json["summary"]`:
/// - `photo_improved_steep_fraction`: on the finest level, covered texels steeper than 60°
///   whose colour now comes mainly from photos (photo share > 0.5), over all covered texels
///   steeper than 60° of that level (0 if the store has no photo run or no steep texels).
///   The finest level is the one seen close up; coarser levels show the same surface
///   again, so they are reported separately in `photo_levels`;
/// - `photo_improved_steep_fraction_all_levels`: the same over all levels;
/// - `photo_levels`: per level the texel counts ([`crate::store::PhotoLevelReport`]);
/// - `photos`: per photo its [`crate::store::PhotoReport`] (texels written, pixels hit,
///   rejected silhouette pixels, reconstructed footprints, colour gain/offset);
/// - `photo_settings`: blend mode, reconstruction, leveling and BVH preset (or null).
///
/// and to each cell with a photo texture a `photo` object (texel counts).
pub(crate) fn add_photos(json: &mut serde_json::Value, manifest: &Manifest) {
    let frac = |steep: u64, photo: u64| {
        if steep > 0 {
            photo as f64 / steep as f64
        } else {
            0.0
        }
    };
    let (levels, photos) = manifest
        .photos
        .as_ref()
        .map_or((Vec::new(), Vec::new()), |p| {
            (p.levels.clone(), p.photos.clone())
        });
    let finest = levels.iter().max_by_key(|l| l.level);
    let finest_fraction = finest.map_or(0.0, |l| frac(l.steep_texels, l.steep_photo_texels));
    let all = frac(
        levels.iter().map(|l| l.steep_texels).sum(),
        levels.iter().map(|l| l.steep_photo_texels).sum(),
    );
    let s = &mut json["summary"];
    s["photo_improved_steep_fraction"] = json!(finest_fraction);
    s["photo_improved_steep_fraction_all_levels"] = json!(all);
    s["photo_levels"] = json!(levels);
    s["photos"] = json!(photos);
    s["photo_settings"] = match &manifest.photos {
        Some(p) => json!({
            "blend": p.blend,
            "reconstruct": p.reconstruct,
            "level_colours": p.level_colours,
            "ray_accel": p.ray_accel,
        }),
        None => serde_json::Value::Null,
    };
    if let Some(cells) = json["cells"].as_array_mut() {
        for (c, v) in manifest.cells.iter().zip(cells.iter_mut()) {
            if let Some(p) = &c.photo {
                v["photo"] = json!({
                    "texels": p.texels,
                    "photo_texels": p.photo_texels,
                    "steep_texels": p.steep_texels,
                    "steep_photo_texels": p.steep_photo_texels,
                });
            }
        }
    }
}
