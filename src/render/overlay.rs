//! Overlay textures: the per-texel stretch of a cell's parameterization as a heat map.

use crate::cells::CellMesh;
use crate::stats::cell_texel_stretch;
use crate::store::CellRecord;

/// What is drawn over the terrain.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub enum Overlay {
    /// The texture alone.
    #[default]
    None,
    /// Cells tinted by quadtree level, with their bounding boxes drawn as lines.
    Levels,
    /// Per-texel stretch heat map instead of the colour texture (see [`stretch_heatmap`]).
    Stretch,
    /// Per-texel photo share instead of the colour texture (see [`share_map`]): where the
    /// projected photos supply the colour a cell shows.
    PhotoShare,
}

impl Overlay {
    /// Whether the overlay replaces the cells' colour textures (so switching to or from it
    /// reloads the cells).
    pub fn replaces_texture(self) -> bool {
        matches!(self, Overlay::Stretch | Overlay::PhotoShare)
    }
}

/// The colour of texels of cells that have no photo texture in [`Overlay::PhotoShare`]
/// (mid grey).
pub const NO_PHOTO_COLOUR: [u8; 4] = [128, 128, 128, 255];

/// Colour (sRGB RGBA8) of a photo share `s` (0..=255 as stored in a confidence map, 255 =
/// the photo's colour alone): dark blue 0 (the existing texture), through green (one half)
/// to yellow (the photo alone).
pub fn share_colour(s: u8) -> [u8; 4] {
    const STOPS: [[f32; 3]; 3] = [[0.05, 0.1, 0.55], [0.1, 0.8, 0.2], [0.95, 0.9, 0.1]];
    let t = s as f32 / 255.0 * 2.0;
    let (a, b, f) = if t <= 1.0 {
        (STOPS[0], STOPS[1], t)
    } else {
        (STOPS[1], STOPS[2], t - 1.0)
    };
    let c = [0, 1, 2].map(|i| ((a[i] + f * (b[i] - a[i])) * 255.0).round() as u8);
    [c[0], c[1], c[2], 255]
}

/// The photo-share map of a cell: [`share_colour`] of each texel of its confidence map
/// (the photo texture's layout and size).
pub fn share_map(confidence: &image::GrayImage) -> image::RgbaImage {
    let (w, h) = confidence.dimensions();
    image::RgbaImage::from_fn(w, h, |x, y| {
        image::Rgba(share_colour(confidence.get_pixel(x, y).0[0]))
    })
}

/// Heat-map colour of a stretch value (sRGB RGBA8): 1 (optimal) dark blue, through cyan (1.25),
/// green (1.5), yellow (2, the "steep" mark, 60° for the ortho map) to red at ≥ 4; values
/// below 1 (compression) purple; NaN (texel not covered) mid grey.
pub fn heat_colour(stretch: f32) -> [u8; 4] {
    if !stretch.is_finite() {
        return [128, 128, 128, 255];
    }
    const STOPS: [(f32, [f32; 3]); 6] = [
        (0.5, [0.55, 0.1, 0.6]),
        (1.0, [0.05, 0.1, 0.55]),
        (1.25, [0.0, 0.7, 0.9]),
        (1.5, [0.1, 0.8, 0.2]),
        (2.0, [0.95, 0.9, 0.1]),
        (4.0, [0.85, 0.05, 0.05]),
    ];
    let s = stretch.clamp(STOPS[0].0, STOPS[STOPS.len() - 1].0);
    let k = STOPS
        .iter()
        .position(|st| st.0 >= s)
        .unwrap_or(STOPS.len() - 1)
        .max(1);
    let (a, b) = (STOPS[k - 1], STOPS[k]);
    let t = ((s - a.0) / (b.0 - a.0)).clamp(0.0, 1.0);
    let c = [0, 1, 2].map(|i| ((a.1[i] + t * (b.1[i] - a.1[i])) * 255.0).round() as u8);
    [c[0], c[1], c[2], 255]
}

/// The per-texel stretch heat map of a cell drawn with `mesh` (its surface triangles and
/// texture coordinates from [`crate::store::texcoord`]) on a `texels × texels` texture budgeted for the
/// cell's nominal square (stretch as in [`crate::stats::texel_stretch`]).
pub fn stretch_heatmap(rec: &CellRecord, mesh: &CellMesh, texels: u32) -> image::RgbaImage {
    let t = texels.max(1);
    let s = cell_texel_stretch(mesh, &rec.surface_texcoords(mesh), rec.base_area(), t);
    image::RgbaImage::from_fn(t, t, |x, y| {
        image::Rgba(heat_colour(s[(y * t + x) as usize]))
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn heat_colours_follow_the_scale() {
        assert_eq!(heat_colour(f32::NAN), [128, 128, 128, 255]);
        assert_eq!(heat_colour(1.0), [13, 26, 140, 255]);
        assert_eq!(heat_colour(2.0), [242, 230, 26, 255]);
        assert_eq!(heat_colour(9.0), heat_colour(4.0));
        // Redder with more stretch.
        assert!(heat_colour(3.0)[1] < heat_colour(2.0)[1]);
    }

    #[test]
    fn share_colours_run_from_blue_to_yellow() {
        assert_eq!(share_colour(0), [13, 26, 140, 255]);
        assert_eq!(share_colour(255), [242, 230, 26, 255]);
        let mid = share_colour(128);
        assert!(mid[1] > 190 && mid[0] < 40 && mid[2] < 70, "{mid:?}");
        // more photo: redder and greener up to the top, never grey
        assert!(share_colour(200)[0] > share_colour(128)[0]);
        assert_ne!(share_colour(128), NO_PHOTO_COLOUR);
        let map = share_map(&image::GrayImage::from_fn(2, 1, |x, _| {
            image::Luma([x as u8 * 255])
        }));
        assert_eq!(map.get_pixel(0, 0).0, share_colour(0));
        assert_eq!(map.get_pixel(1, 0).0, share_colour(255));
    }
}
