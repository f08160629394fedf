//! Ground-photo projection: photos taken from known camera poses are merged into the cells'
//! textures, so that walls get real detail instead of a smeared ortho image.
//!
//! Sub-stages, one folder each, in the order a projection runs them (each uses only those
//! before it): `inputs` (photo lists, COLMAP, pyramids), `footprints` (pixel-corner casts,
//! silhouettes, reconstruction), `splatting` (texture sizes, exact-area deposits, pixel
//! weights and colour transforms), `blending` (photos per texel, then against the existing
//! texture, and the gutter), `leveling` (fitting each photo's colour transform).
//!
//! Data types (the stage's plain data, shared by its files):
//! - [`PhotoInput`]: a decoded photo and its [`crate::camera::CameraModel`] (world frame),
//!   read from `photos.json` ([`read_photo_list`]) or a COLMAP text model ([`read_colmap`]);
//!   [`PhotoSpec`] is the same without decoded pixels (load one photo at a time).
//! - Ray casting is the stage below ([`crate::raycast`]): [`photo_footprints`] casts a
//!   photo's pixel-corner rays against a [`crate::raycast::LevelScene`] (all cells of one
//!   quadtree level in one f32 frame near the camera).
//! - [`PixelFootprint`]: one photo pixel's footprint in one cell's texture: the four pixel
//!   corners' texture positions (texel units of the cell's active texture), with the view
//!   cosine and distance at the pixel centre. [`FootprintSet`] holds every footprint of one
//!   photo on one quadtree level (per cell: [`CellFootprints`]), plus the counts of rejected and
//!   reconstructed pixels.
//!
//! - Splatting, blending and leveling (docs/projection.md): [`splat_footprint`] deposits a
//!   footprint into the texels it covers by exact overlap area; [`PhotoAccum`] /
//!   [`CellAccum`] accumulate colour and confidence ([`ConfidenceParams`]) per texel and
//!   photo / over photos ([`BlendMode`]); [`blend_cell`] merges the result with the existing
//!   texture; [`fit_colour_transform`] levels a photo's colours to the ortho
//!   ([`ColourTransform`]); [`PhotoPyramid`] halves photos for coarser levels.
//!
//! Texture positions are in texel units of the cell's *active* texture (the reparameterized
//! one if the cell has it, else the orthographic one): x right, y down, texel `(i, j)`
//! covers `[i, i+1] × [j, j+1]`, so uv = position / texels.

mod blending;
mod footprints;
mod inputs;
mod leveling;
mod splatting;

pub use blending::blend::{Blended, blend_cell, magnify};
pub use blending::cell_accum::{BlendMode, CellAccum, CellContext, MIN_COS_SLOPE};
pub use footprints::footprint::{
    FootprintBuffers, FootprintOptions, for_each_footprint_batch, for_each_footprint_batch_in,
    for_each_footprint_batch_rows_in, photo_footprints, photo_footprints_in,
};
pub use inputs::colmap::{Similarity, read_colmap, read_colmap_specs, read_similarity};
pub use inputs::input::{
    PhotoEntry, PhotoSpec, image_size, photo_spec, read_photo_entries, read_photo_list,
    read_photo_specs,
};
pub use inputs::mask::{
    BORDER_EDGE_SHARE, BORDER_MAX_DEPTH, BORDER_TOLERANCE, BorderSide, PADDING_EDGE_SHARE,
    PixelMask, uniform_border,
};
pub use inputs::pyramid::{PhotoPyramid, downsample2, downsample2_in, half_camera};
pub use leveling::colour_leveling::{
    ColourPairs, ColourTransform, LevelingParams, collect_pairs, fit_colour_transform,
    normal_cos_slope,
};
pub use splatting::accumulate::{PhotoAccum, TexelSums};
pub use splatting::confidence::{BorderFeather, ConfidenceParams, smoothstep};
pub use splatting::occlusion::{OcclusionMap, occlusion_weight};
pub use splatting::samples::{Exclusion, PhotoSamples};
pub use splatting::sizing::{SIZING_BINS, SizeRequest, SizingBins, choose_scales, texture_bytes};
pub use splatting::splat::{
    MAX_SPLAT_BBOX, MIN_SPLAT_AREA, Splat, SplatKind, footprint_area, splat_footprint,
};

use std::path::PathBuf;

/// A photo with its camera, ready to project.
#[derive(Clone, Debug)]
pub struct PhotoInput {
    /// Short name for reports (the image's file name).
    pub name: String,
    /// The image file it was read from.
    pub image_path: PathBuf,
    /// The photo's pixels (sRGB).
    pub image: image::RgbImage,
    /// The camera, in the store's georeferenced frame, for an image of exactly this size.
    pub camera: crate::camera::CameraModel,
    /// The pixels not to use (the photo list's `"mask"`: 0 = ignore), if any.
    pub mask: Option<PixelMask>,
}

/// One photo pixel's footprint in one cell's texture.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct PixelFootprint {
    /// Index of the cell in the manifest's `cells` list.
    pub cell: u32,
    /// The photo pixel `[column, row]` whose colour this footprint carries (pixel of the
    /// image the footprints were cast for).
    pub pixel: [u32; 2],
    /// Texture positions (texel units, x right, y down) of the pixel's corners, in the
    /// order (col, row), (col+1, row), (col+1, row+1), (col, row+1).
    pub corners: [[f32; 2]; 4],
    /// |cos| of the angle between the ray through the pixel centre and the surface normal,
    /// in (0, 1].
    pub cos_view: f32,
    /// Distance from the camera centre to the surface at the pixel centre, metres.
    pub distance: f32,
    /// How many of the four corners were reconstructed (0 = all four hit this cell).
    pub reconstructed: u8,
}

/// All footprints of one photo on one quadtree level, and what happened to the rest.
#[derive(Clone, Debug, Default)]
pub struct FootprintSet {
    /// The cells that received footprints, by increasing manifest index.
    pub cells: Vec<CellFootprints>,
    /// Pixels with at least one corner ray hitting the terrain's front face (= footprints +
    /// rejected_silhouette + dropped).
    pub pixels_hit: u64,
    /// Pixels rejected because their footprint crosses a silhouette edge.
    pub rejected_silhouette: u64,
    /// Footprints with at least one reconstructed corner.
    pub reconstructed: u64,
    /// Pixels that hit the terrain but whose footprint could not be completed (dropped).
    pub dropped: u64,
}

impl FootprintSet {
    /// Number of footprints (at most one per pixel).
    pub fn len(&self) -> usize {
        self.cells.iter().map(CellFootprints::len).sum()
    }

    /// `true` if there are no footprints.
    pub fn is_empty(&self) -> bool {
        self.cells.iter().all(|c| c.len() == 0)
    }

    /// Every footprint, sorted by (cell, row, column).
    pub fn iter(&self) -> impl Iterator<Item = &PixelFootprint> {
        self.cells.iter().flat_map(CellFootprints::iter)
    }

    /// Adds `other`'s pixel counts (hit, rejected, reconstructed, dropped) to `self`'s.
    pub fn add_counts(&mut self, other: &FootprintSet) {
        self.pixels_hit += other.pixels_hit;
        self.rejected_silhouette += other.rejected_silhouette;
        self.reconstructed += other.reconstructed;
        self.dropped += other.dropped;
    }

    /// Moves the footprints and counts of `later` (a set of later photo rows, e.g. the next
    /// batch of [`for_each_footprint_batch`]) into `self`: each cell's footprints stay in
    /// (row, column) order and the cells sorted. Leaves `later` without footprints.
    pub fn append(&mut self, later: &mut FootprintSet) {
        self.add_counts(later);
        let mut merged = Vec::with_capacity(self.cells.len().max(later.cells.len()));
        let (mut a, mut b) = (
            std::mem::take(&mut self.cells).into_iter().peekable(),
            later.cells.drain(..).peekable(),
        );
        loop {
            let next = match (a.peek(), b.peek()) {
                (Some(x), Some(y)) if x.cell == y.cell => {
                    let (mut x, y) = (a.next(), b.next());
                    if let (Some(x), Some(y)) = (x.as_mut(), y) {
                        x.chunks.extend(y.chunks);
                    }
                    x
                }
                (Some(x), Some(y)) if x.cell < y.cell => a.next(),
                (Some(_), Some(_)) | (None, Some(_)) => b.next(),
                (Some(_), None) => a.next(),
                (None, None) => None,
            };
            match next {
                Some(c) => merged.push(c),
                None => break,
            }
        }
        drop((a, b));
        self.cells = merged;
    }
}

/// Equal footprints in the same order and equal counts (however they are chunked).
impl PartialEq for FootprintSet {
    fn eq(&self, o: &Self) -> bool {
        (
            self.pixels_hit,
            self.rejected_silhouette,
            self.reconstructed,
            self.dropped,
        ) == (
            o.pixels_hit,
            o.rejected_silhouette,
            o.reconstructed,
            o.dropped,
        ) && self.len() == o.len()
            && self.iter().eq(o.iter())
    }
}

/// The footprints of one cell, in (row, column) order, kept in chunks of photo rows as the
/// ray casting produced them (so they are never copied into one array).
#[derive(Clone, Debug, Default, PartialEq)]
pub struct CellFootprints {
    /// Index of the cell in the manifest's `cells` list.
    pub cell: u32,
    /// Consecutive runs of footprints, in order.
    pub chunks: Vec<Vec<PixelFootprint>>,
}

impl CellFootprints {
    /// Number of footprints.
    pub fn len(&self) -> usize {
        self.chunks.iter().map(Vec::len).sum()
    }

    /// `true` if there are none.
    pub fn is_empty(&self) -> bool {
        self.chunks.iter().all(Vec::is_empty)
    }

    /// The footprints in (row, column) order.
    pub fn iter(&self) -> impl Iterator<Item = &PixelFootprint> {
        self.chunks.iter().flatten()
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn fp(cell: u32, row: u32) -> PixelFootprint {
        PixelFootprint {
            cell,
            pixel: [0, row],
            corners: [[0.0; 2]; 4],
            cos_view: 1.0,
            distance: 1.0,
            reconstructed: 0,
        }
    }

    fn set(cells: &[(u32, &[u32])], hit: u64) -> FootprintSet {
        FootprintSet {
            cells: cells
                .iter()
                .map(|&(c, rows)| CellFootprints {
                    cell: c,
                    chunks: vec![rows.iter().map(|&r| fp(c, r)).collect()],
                })
                .collect(),
            pixels_hit: hit,
            rejected_silhouette: 1,
            reconstructed: 2,
            dropped: 3,
        }
    }

    #[test]
    fn append_merges_cells_in_order_and_keeps_rows_in_order() {
        let mut a = set(&[(1, &[0, 1]), (4, &[0])], 10);
        let mut b = set(&[(0, &[2]), (4, &[2, 3]), (7, &[3])], 5);
        a.append(&mut b);
        assert!(b.is_empty());
        assert_eq!(
            a.cells.iter().map(|c| c.cell).collect::<Vec<_>>(),
            vec![0, 1, 4, 7]
        );
        let rows: Vec<[u32; 2]> = a.iter().map(|f| [f.cell, f.pixel[1]]).collect();
        assert_eq!(
            rows,
            vec![[0, 2], [1, 0], [1, 1], [4, 0], [4, 2], [4, 3], [7, 3]]
        );
        assert_eq!(
            (
                a.pixels_hit,
                a.rejected_silhouette,
                a.reconstructed,
                a.dropped
            ),
            (15, 2, 4, 6)
        );
    }
}
