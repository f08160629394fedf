//! Optional per-texel metadata of exported cells as `EXT_structural_metadata` property
//! textures (docs/export.md, "Metadata"): the texel stretch of the cell's chart (the surface
//! area a texel carries over its share of the cell's nominal square, 1 = ideal; as
//! [`crate::stats::texel_stretch`]) and, on photo textures, the photo's share of each
//! texel's colour (the store's confidence map).
//!
//! Class `texel` of schema `cliffmap`: `stretch` `UINT16`, normalized, scale
//! [`STRETCH_SCALE`] (steps of 1/1024 up to 64), raw 0 = no data (texels off the surface);
//! `photo_share` `UINT8`, normalized. Each cell has its own property texture: the stretch in
//! an RGB PNG of the mesh's texture layout, the raw value's low byte in red and high byte in
//! green (channels `[0, 1]`, little-endian as the extension concatenates them), and the
//! share in a grey PNG of the photo texture's size (channel `[0]`); both sampled NEAREST.

use serde_json::{Value, json};

/// The largest stretch the `stretch` property holds (values above are clamped).
pub const STRETCH_SCALE: f64 = 64.0;

/// A cell's property textures, as PNG bytes.
#[derive(Clone, Debug, PartialEq)]
pub struct CellMetadata {
    /// The stretch (RGB8, raw `UINT16` in red and green), the mesh texture layout's size.
    pub stretch_png: Vec<u8>,
    /// The photo share (L8), for cells exported with their photo texture.
    pub share_png: Option<Vec<u8>>,
}

/// The raw `UINT16` of a stretch value: 0 (no data) for NaN or non-positive values, else
/// `round(s / STRETCH_SCALE · 65535)` within 1..=65535.
pub fn stretch_raw(s: f32) -> u16 {
    if !(s > 0.0) {
        return 0;
    }
    (s as f64 / STRETCH_SCALE * 65535.0)
        .round()
        .clamp(1.0, 65535.0) as u16
}

/// The stretch values of a `texels × texels` texture (row-major) as the RGB image of the
/// property texture.
pub fn stretch_image(stretch: &[f32], texels: u32) -> image::RgbImage {
    image::RgbImage::from_fn(texels, texels, |x, y| {
        let r = stretch_raw(
            stretch
                .get((y * texels + x) as usize)
                .copied()
                .unwrap_or(f32::NAN),
        );
        let [lo, hi] = r.to_le_bytes();
        image::Rgb([lo, hi, 0])
    })
}

/// The schema of the `texel` class.
pub fn schema() -> Value {
    json!({
        "id": "cliffmap",
        "classes": {"texel": {
            "description": "Per-texel properties of a cliffmap cell texture",
            "properties": {
                "stretch": {
                    "description": "Surface area a texel carries over its share of the cell's nominal square (1 = ideal; clamped at 64)",
                    "type": "SCALAR",
                    "componentType": "UINT16",
                    "normalized": true,
                    "scale": STRETCH_SCALE,
                    "noData": 0
                },
                "photo_share": {
                    "description": "Weight of ground-photo colour in the texel's colour (0..1)",
                    "type": "SCALAR",
                    "componentType": "UINT8",
                    "normalized": true
                }
            }
        }}
    })
}

/// One cell's property texture: the glTF texture indices of its stretch and photo share.
pub fn property_texture(stretch: usize, share: Option<usize>) -> Value {
    let mut props = json!({"stretch": {"index": stretch, "texCoord": 0, "channels": [0, 1]}});
    if let Some(i) = share {
        props["photo_share"] = json!({"index": i, "texCoord": 0, "channels": [0]});
    }
    json!({"class": "texel", "properties": props})
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn stretch_is_encoded_little_endian_with_no_data_zero() {
        assert_eq!(stretch_raw(f32::NAN), 0);
        assert_eq!(stretch_raw(0.0), 0);
        assert_eq!(stretch_raw(1.0), 1024);
        assert_eq!(stretch_raw(1000.0), 65535);
        let img = stretch_image(&[1.0, 2.5, f32::NAN, 64.0], 2);
        let back = |x, y| {
            let p = img.get_pixel(x, y).0;
            u16::from_le_bytes([p[0], p[1]]) as f64 / 65535.0 * STRETCH_SCALE
        };
        assert!((back(0, 0) - 1.0).abs() < 1e-3 && (back(1, 0) - 2.5).abs() < 1e-3);
        assert_eq!(img.get_pixel(0, 1).0, [0, 0, 0]);
        assert!((back(1, 1) - 64.0).abs() < 1e-9);
    }
}
