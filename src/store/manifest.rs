//! The store manifest (`manifest.json`) and per-cell records.

use std::path::Path;

use serde::{Deserialize, Serialize};

use crate::cells::{CellKey, Quadtree, SampleRect};
use crate::error::{Error, Result};
use crate::georef::{GridGeoref, WorldRect};

/// Value of [`Manifest::format`].
pub const STORE_FORMAT: &str = "cliffmap-store";
/// The manifest version this cliffmap writes and reads.
pub const STORE_VERSION: u32 = 1;

/// A file of the store, relative to the store directory, with its size and CRC-32.
#[derive(Clone, Debug, PartialEq, Eq, Serialize, Deserialize)]
pub struct FileRef {
    /// Path relative to the store directory, with `/` separators.
    pub path: String,
    /// Size in bytes.
    pub bytes: u64,
    /// CRC-32 (IEEE) of the content, as 8 lowercase hex digits.
    pub crc32: String,
}

/// The files of one cell.
#[derive(Clone, Debug, PartialEq, Eq, Serialize, Deserialize)]
pub struct CellFiles {
    /// Binary mesh ([`super::CellMesh`]).
    pub mesh: FileRef,
    /// RGBA8 PNG colour texture (alpha 0 = unknown colour, filled for display).
    pub texture: FileRef,
    /// RGB8 PNG normal map in the cell-local frame (n * 0.5 + 0.5).
    pub normal: FileRef,
}

/// Which texture parameterization a cell uses.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "lowercase")]
pub enum Parameterization {
    /// Texture coordinates derived from x, y over the cell's nominal square (no UVs stored).
    Ortho,
    /// Texture coordinates stored in the mesh (reparameterized chart).
    Reparam,
}

/// Everything the manifest knows about one cell.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct CellRecord {
    /// `"{level}-{x}-{y}"`.
    pub id: String,
    /// Quadtree level, 0 = root.
    pub level: u8,
    /// Column within the level.
    pub x: u32,
    /// Row within the level.
    pub y: u32,
    /// The clipped rectangle of full-resolution DEM samples the cell covers.
    pub rect: SampleRect,
    /// World position (f64) of the cell-local frame's origin; mesh positions are relative to it.
    pub origin: [f64; 3],
    /// World rectangle of the cell's nominal square (the texture's extent in ortho mode).
    pub extent: WorldRect,
    /// World bounding box of the surface (skirt excluded), minimum corner.
    pub bbox_min: [f64; 3],
    /// World bounding box of the surface, maximum corner.
    pub bbox_max: [f64; 3],
    /// Error bound the TIN was built for (world units).
    pub epsilon: f64,
    /// Measured max vertical distance from every DEM sample of the cell to the TIN.
    pub max_error: f64,
    /// Surface vertices.
    pub vertices: u32,
    /// Surface triangles.
    pub triangles: u32,
    /// Skirt depth below the border vertices (world units).
    pub skirt_depth: f64,
    /// Texture parameterization in use.
    pub parameterization: Parameterization,
    /// Texture side in texels.
    pub texels: u32,
    /// The cell's files.
    pub files: CellFiles,
    /// Texel-stretch statistics of the cell (orthographic parameterization).
    pub stats: crate::stats::CellStats,
    /// The reparameterized variant, if `cliffmap reparam` chose this cell.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub reparam: Option<ReparamRecord>,
    /// The photo-enhanced texture, if `cliffmap project` wrote one for this cell.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub photo: Option<PhotoCellRecord>,
    /// The DEM's height above the cell's TIN (absent in stores built before 2026-12-06).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub relief: Option<ReliefRecord>,
}

/// A cell's relief map ([`crate::cells::relief`]): per texel of the nominal square (the
/// orthographic layout, `CellRecord::texels` square), the height of the full-resolution DEM
/// surface above the cell's TIN at the texel centre.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct ReliefRecord {
    /// 8-bit greyscale PNG: `height = (v / 255 · 2 − 1) · range_m`.
    pub file: FileRef,
    /// Largest absolute height of the map, world units (0: the TIN is exact at every texel).
    pub range_m: f64,
}

/// A cell's photo-enhanced texture: the active parameterization's texture (reparameterized
/// if the cell has one, else orthographic) with photo colour merged in, and its confidence.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct PhotoCellRecord {
    /// Texture side in texels: the active texture's times a power of two (photo-driven
    /// sizes, docs/projection.md "Texture sizes").
    pub texels: u32,
    /// RGBA8 PNG enhanced colour texture, the active texture's layout (same texture
    /// coordinates) at `texels`.
    pub texture: FileRef,
    /// 8-bit greyscale PNG: per texel, the weight of photo colour in the result (0..255 = 0..1).
    pub confidence: FileRef,
    /// Texels whose colour now comes mainly from photos (photo weight > 0.5), in texels of
    /// the photo texture.
    pub photo_texels: u64,
    /// Covered texels whose surface slope exceeds 60 degrees (photo texture's texels).
    pub steep_texels: u64,
    /// Steep texels whose colour now comes mainly from photos (photo texture's texels).
    pub steep_photo_texels: u64,
    /// When present, `texture` and `confidence` hold only these blocks of the texture (an
    /// atlas, [`super::photo_texture`]); the rest is the active texture magnified, with
    /// confidence 0. Read the whole texture with [`super::Store::read_photo_texture`].
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub blocks: Option<super::PhotoBlocks>,
}

/// A cell's reparameterized variant: mesh with texture coordinates, resampled texture and
/// normal map, and the chart's distortion metrics.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct ReparamRecord {
    /// Texture side in texels (twice the store's in mixed-resolution mode).
    pub texels: u32,
    /// Mesh (same vertices and triangles as the ortho mesh, plus UVs), texture, normal map.
    pub files: CellFiles,
    /// Distortion metrics of the chart (base area = the cell's nominal square).
    pub metrics: crate::param::ChartMetrics,
    /// Rel_texel of the chart at the store's texel density: `metrics.rel_texel *
    /// (cell_texels / texels)²`, comparable with `stats.rel_texel` of the ortho map.
    pub rel_texel: f64,
    /// Per-texel stretch of the chart, relative to an ortho texel's base area.
    pub texel_stretch: crate::stats::Percentiles,
    /// Texels where the resampling fell back to bilinear filtering (collapsed footprints).
    pub bilinear_fallbacks: u64,
}

/// Settings of the last `cliffmap reparam` run on the store.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct ReparamSettings {
    /// Cells with ortho Rel_texel above this were reparameterized.
    pub threshold: f64,
    /// Energy exponent theta.
    pub theta: f64,
    /// Iteration budget of the global projected-Newton finish (0 = none; absent in stores
    /// made before it existed).
    #[serde(default)]
    pub newton_iterations: u32,
    /// Reparameterized cells got textures of twice the side.
    pub mixed_resolution: bool,
    /// Resampling filter, e.g. "subtexel:4".
    pub resample: String,
    /// Cells whose parameterization failed and that kept the ortho map.
    pub failed_cells: Vec<String>,
    /// Every parameterization option used (absent in stores written before 2026-12-04;
    /// `cliffmap verify --repair` needs it to redo a damaged reparameterized cell).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub param: Option<crate::param::ParamOptions>,
    /// Fill of texels outside the chart ("average-border" or "pull-push"; absent in older stores).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub fill: Option<String>,
    /// PNG compression of the reparameterized textures (absent in stores written before the
    /// knob existed, which used `fast`, the default).
    #[serde(default)]
    pub png_compression: crate::fsutil::PngCompression,
}

impl CellRecord {
    /// Texture coordinates of the surface vertices of this cell drawn with `mesh`
    /// ([`crate::cells::CellMesh::surface_texcoords`] over the cell's origin and nominal square).
    pub fn surface_texcoords(&self, mesh: &crate::cells::CellMesh) -> Vec<[f32; 2]> {
        mesh.surface_texcoords(self.origin, &self.extent)
    }

    /// Area in m² of the cell's nominal square (the base a texture budget is spread over).
    pub fn base_area(&self) -> f64 {
        (self.extent.width() * self.extent.height()).abs()
    }

    /// The error the cell makes, in world metres (≥ 0), the one a renderer's screen-space
    /// error is measured with: the larger of its geometric error
    /// ([`CellRecord::geometric_error`]) and half a texel of its texture (the texture's own
    /// approximation error).
    pub fn error(&self) -> f64 {
        let texel = if self.texels > 0 {
            self.extent.width().abs() / self.texels as f64
        } else {
            0.0
        };
        self.geometric_error().max(0.5 * texel)
    }

    /// The cell's geometric error in metres (≥ 0): its measured `max_error`, or `epsilon` if
    /// that is not a finite non-negative number — the largest height difference between its
    /// surface and the DEM samples it covers.
    pub fn geometric_error(&self) -> f64 {
        if self.max_error.is_finite() && self.max_error >= 0.0 {
            self.max_error
        } else {
            self.epsilon.max(0.0)
        }
    }

    /// The cell's quadtree key.
    pub fn key(&self) -> CellKey {
        CellKey {
            level: self.level,
            x: self.x,
            y: self.y,
        }
    }
}

/// What the DEM was.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct DemInfo {
    /// Source file (or `"demo:seed=..."`).
    pub source: String,
    /// Samples per row.
    pub width: u32,
    /// Rows.
    pub height: u32,
    /// Lowest height.
    pub height_min: f64,
    /// Highest height.
    pub height_max: f64,
    /// Fraction of no-data samples (filled).
    pub void_fraction: f64,
}

/// The store's top-level description, written last by a build.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct Manifest {
    /// Always [`STORE_FORMAT`].
    pub format: String,
    /// Always [`STORE_VERSION`] for stores this cliffmap writes.
    pub version: u32,
    /// Version of cliffmap that wrote the store.
    pub generator: String,
    /// Coordinate reference system, if known (e.g. "EPSG:25833").
    pub crs: Option<String>,
    /// Georeference of the DEM grid (sample centres).
    pub georef: GridGeoref,
    /// The DEM.
    pub dem: DemInfo,
    /// Ortho source, or `None` if textures were derived from the DEM (hypsometric tint + hillshade).
    pub ortho: Option<String>,
    /// Ground sample distance of the ortho image (metres, the larger of its two spacings);
    /// `None` without an ortho or for stores written before 2026-12-03.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub ortho_spacing: Option<f64>,
    /// Quadtree shape.
    pub quadtree: Quadtree,
    /// Error bound of the finest level; level l uses `max_error * 2^(finest - l)`.
    pub max_error: f64,
    /// Texture side in texels for every cell.
    pub cell_texels: u32,
    /// Hash of inputs and options; a build with the same key may resume.
    pub build_key: String,
    /// All cells, root first, row-major within a level.
    pub cells: Vec<CellRecord>,
    /// Settings of the last `cliffmap reparam` run, if any.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub reparam: Option<ReparamSettings>,
    /// Settings and per-photo results of the last `cliffmap project` run, if any.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub photos: Option<PhotoSettings>,
    /// CRC-32 of this manifest's pretty JSON serialization with this field absent, set by
    /// [`Manifest::write`] and checked by [`Manifest::read`] (absent in stores written
    /// before 2026-12-04, which are read unchecked).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub content_crc32: Option<String>,
}

/// Settings of the last `cliffmap project` run and what each photo contributed.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct PhotoSettings {
    /// How photo colours were combined per texel: "blend" (by confidence) or "best".
    pub blend: String,
    /// Whether footprints with missing corners were reconstructed.
    pub reconstruct: bool,
    /// Whether per-photo colour leveling towards the ortho was applied.
    pub level_colours: bool,
    /// Ray-casting acceleration used ([`crate::raycast::RayAccel::name`]: `grid:BIN_PX` or
    /// `bvh:PRESET`; stores written before the grid existed hold the BVH preset alone).
    #[serde(alias = "bvh_quality")]
    pub ray_accel: String,
    /// Colour space photo colours were averaged and blended in ("linear" or "srgb"; stores
    /// written before 2026-12-03 averaged sRGB values).
    #[serde(default = "srgb_name")]
    pub colour_space: String,
    /// Whether photo textures were sized by the detail the photos deliver.
    #[serde(default)]
    pub photo_driven_sizes: bool,
    /// Largest photo texture side allowed, texels (0 in older stores: the active size).
    #[serde(default)]
    pub max_photo_texels: u32,
    /// GPU bytes the enlarged photo textures of all levels were allowed.
    #[serde(default)]
    pub photo_texture_budget: u64,
    /// Pose uncertainty of the occlusion margin, full-resolution photo pixels (0: no
    /// margin, as in stores written before 2026-12-04).
    #[serde(default)]
    pub occlusion_margin_px: f64,
    /// One report per photo, in input order.
    pub photos: Vec<PhotoReport>,
    /// Per quadtree level (root first): texel counts over all cells of the level.
    #[serde(default)]
    pub levels: Vec<PhotoLevelReport>,
}

fn srgb_name() -> String {
    "srgb".to_string()
}

/// Texel counts of one quadtree level after `cliffmap project` (all cells of the level,
/// with or without photo colour; "covered" = texel centre on the cell's surface).
#[derive(Clone, Debug, Default, PartialEq, Serialize, Deserialize)]
pub struct PhotoLevelReport {
    /// Quadtree level.
    pub level: u8,
    /// Cells of the level that got a photo texture.
    pub cells_with_photo: u64,
    /// Covered texels whose colour now comes mainly from photos (photo share > 0.5).
    pub photo_texels: u64,
    /// Covered texels whose surface slope (from the normal map) exceeds 60 degrees.
    pub steep_texels: u64,
    /// Steep covered texels whose colour now comes mainly from photos.
    pub steep_photo_texels: u64,
    /// Cells whose photos resolve finer detail than their active texture holds.
    #[serde(default)]
    pub wanted_larger: u64,
    /// Cells that got a photo texture larger than their active texture.
    #[serde(default)]
    pub upsized_cells: u64,
    /// GPU bytes (RGBA8 with mips) of the level's photo textures.
    #[serde(default)]
    pub photo_texture_bytes: u64,
    /// The level's share of the budget for enlarged photo textures, bytes.
    #[serde(default)]
    pub texture_budget_bytes: u64,
}

/// What one photo contributed to the store. `texels_written` is summed over all levels; the
/// pixel counts refer to the photo at full resolution (the finest level's ray casts).
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct PhotoReport {
    /// Name of the photo (its file name).
    pub name: String,
    /// Image path relative to the store directory (as given if it cannot be made relative).
    pub image: String,
    /// Texels that received colour from this photo.
    pub texels_written: u64,
    /// Covered texels (all levels, counted in texels of the cells' active textures) whose
    /// colour now comes mainly from photos and from this photo more than from any other.
    #[serde(default)]
    pub texels_supplied: u64,
    /// Pixels whose centre ray hit the terrain.
    pub pixels_hit: u64,
    /// Pixels rejected because their footprint crossed a silhouette edge.
    pub rejected_silhouette: u64,
    /// Footprints completed by reconstructing missing corners.
    pub reconstructed_footprints: u64,
    /// Per-channel colour gain applied to the photo (1 = unchanged).
    pub colour_gain: [f64; 3],
    /// Per-channel colour offset applied to the photo (0..1 scale; 0 = unchanged).
    pub colour_offset: [f64; 3],
    /// Texels the colour leveling was fitted on (0 = leveling off or too few samples:
    /// identity).
    #[serde(default)]
    pub colour_samples: u64,
    /// Of `pixels_hit` (full-resolution pixels, finest level), those with a footprint whose
    /// colour the resolution rule lets dominate the existing texture at the texel under it
    /// (weight at least 1/2; docs/projection.md, "What a photo supplied").
    #[serde(default)]
    pub pixels_supplying: u64,
    /// Of `pixels_hit`, those with a footprint where the existing texture resolves the
    /// surface about as finely or more (the photo's colour counts for less than half).
    #[serde(default)]
    pub pixels_outweighed: u64,
    /// Of `pixels_hit`, those whose footprint could not be completed.
    #[serde(default)]
    pub pixels_dropped: u64,
    /// Of `pixels_hit`, those a mask left out (the photo list's `"mask"` or a uniform
    /// border).
    #[serde(default)]
    pub pixels_masked: u64,
    /// Of `pixels_hit`, those nearer to the camera than `--min-distance`.
    #[serde(default)]
    pub pixels_near: u64,
    /// What the automatic mask of uniform borders left out, per side ("top: 12000 pixels
    /// of colour [255, 255, 255]"); absent when nothing.
    #[serde(default, skip_serializing_if = "Vec::is_empty")]
    pub border_masked: Vec<String>,
    /// What the run found wrong with this photo, each also logged as a warning.
    #[serde(default, skip_serializing_if = "Vec::is_empty")]
    pub warnings: Vec<String>,
}

impl PhotoReport {
    /// The share of the photo's terrain pixels (`pixels_hit`) whose colour reached a
    /// texture (`pixels_supplying`), in [0, 1]; 0 for a photo that hit no terrain.
    pub fn supplying_share(&self) -> f64 {
        if self.pixels_hit == 0 {
            0.0
        } else {
            self.pixels_supplying as f64 / self.pixels_hit as f64
        }
    }
}

impl Manifest {
    /// Whether the cells' own textures hold image information: an ortho was given (by its
    /// source or its spacing). `false` for textures derived from the DEM (tint and
    /// hillshade), which any photo that sees the surface replaces (docs/projection.md,
    /// "What an existing texture holds").
    pub fn textures_hold_an_image(&self) -> bool {
        self.ortho.is_some() || self.ortho_spacing.is_some()
    }

    /// Reads and validates `manifest.json` in `dir`.
    pub fn read(dir: &Path) -> Result<Manifest> {
        let path = dir.join("manifest.json");
        let text = std::fs::read_to_string(&path).map_err(|e| Error::io(&path, e))?;
        let m: Manifest = serde_json::from_str(&text)
            .map_err(|e| Error::store(&path, format!("invalid manifest: {e}")))?;
        if m.format != STORE_FORMAT {
            return Err(Error::store(
                &path,
                format!("format is {:?}, expected {STORE_FORMAT:?}", m.format),
            ));
        }
        if m.version != STORE_VERSION {
            return Err(Error::StoreVersion {
                path,
                found: m.version,
                supported: STORE_VERSION,
            });
        }
        if let Some(want) = &m.content_crc32 {
            let got = raw_checksum(text.as_bytes());
            if got.as_deref() != Some(want.as_str()) {
                return Err(Error::store(
                    &path,
                    format!(
                        "checksum mismatch (recorded {want}, content {}): the manifest is damaged; `cliffmap verify --repair` rebuilds it from the recorded inputs",
                        got.unwrap_or_else(|| "unreadable".into())
                    ),
                ));
            }
        }
        Ok(m)
    }

    /// Writes `dir/manifest.json` atomically with its content checksum: the CRC-32 of the
    /// file's bytes with the checksum's own 8 digits written as `00000000`.
    pub fn write(&mut self, dir: &Path) -> Result<()> {
        self.content_crc32 = Some(CRC_PLACEHOLDER.into());
        let mut bytes =
            serde_json::to_vec_pretty(self).map_err(|e| Error::store(dir, e.to_string()))?;
        let at = checksum_digits(&bytes)
            .ok_or_else(|| Error::store(dir, "manifest checksum field not found"))?;
        let crc = super::crc32_hex(&bytes);
        bytes[at..at + 8].copy_from_slice(crc.as_bytes());
        self.content_crc32 = Some(crc);
        crate::fsutil::write_atomic(&dir.join("manifest.json"), &bytes)
    }

    /// The record of cell `id`, if present.
    pub fn cell(&self, id: &str) -> Option<&CellRecord> {
        self.cells.iter().find(|c| c.id == id)
    }
}

/// What [`Manifest::write`] hashes in place of the checksum's digits.
const CRC_PLACEHOLDER: &str = "00000000";
const CRC_KEY: &[u8] = b"\"content_crc32\": \"";

/// Byte offset of the 8 checksum digits in a manifest file (the last `content_crc32` key).
fn checksum_digits(bytes: &[u8]) -> Option<usize> {
    let at = bytes.windows(CRC_KEY.len()).rposition(|w| w == CRC_KEY)? + CRC_KEY.len();
    (bytes.len() >= at + 9 && bytes[at + 8] == b'"').then_some(at)
}

/// The CRC-32 of a manifest file's bytes with its checksum digits replaced by the
/// placeholder (independent of the fields this version knows), or `None` without a checksum.
fn raw_checksum(bytes: &[u8]) -> Option<String> {
    let at = checksum_digits(bytes)?;
    let mut b = bytes.to_vec();
    b[at..at + 8].copy_from_slice(CRC_PLACEHOLDER.as_bytes());
    Some(super::crc32_hex(&b))
}

#[cfg(test)]
mod tests {
    use super::*;

    fn tiny() -> Manifest {
        let text = r#"{"format": "cliffmap-store", "version": 1, "generator": "t", "crs": null,
            "georef": {"origin_x": 0.0, "origin_y": 0.0, "spacing_x": 1.0, "spacing_y": 1.0},
            "dem": {"source": "t", "width": 2, "height": 2, "height_min": 0.0, "height_max": 0.0, "void_fraction": 0.0},
            "ortho": null, "quadtree": {"dem_width": 2, "dem_height": 2, "finest_intervals": 2, "levels": 1},
            "max_error": 0.5, "cell_texels": 8, "build_key": "0", "cells": []}"#;
        serde_json::from_str(text).unwrap()
    }

    #[test]
    fn another_version_is_a_typed_error() {
        let dir = tempfile::tempdir().unwrap();
        let mut m = tiny();
        m.version = STORE_VERSION + 1;
        m.write(dir.path()).unwrap();
        match Manifest::read(dir.path()).unwrap_err() {
            Error::StoreVersion {
                found, supported, ..
            } => assert_eq!((found, supported), (STORE_VERSION + 1, STORE_VERSION)),
            other => panic!("expected StoreVersion, got {other:?}"),
        }
    }

    #[test]
    fn the_checksum_covers_the_bytes_and_survives_fields_this_version_does_not_know() {
        let dir = tempfile::tempdir().unwrap();
        let mut m = tiny();
        m.write(dir.path()).unwrap();
        let back = Manifest::read(dir.path()).unwrap();
        assert_eq!(back.max_error, 0.5);
        let path = dir.path().join("manifest.json");
        let text = std::fs::read_to_string(&path).unwrap();
        // One changed digit of a value: detected.
        std::fs::write(&path, text.replacen("0.5", "0.6", 1)).unwrap();
        assert!(
            Manifest::read(dir.path())
                .unwrap_err()
                .to_string()
                .contains("checksum mismatch")
        );
        // A field written by a later version (unknown here) with a correct checksum: accepted.
        let mut future = text
            .replacen('{', "{\n  \"future_field\": [1, 2],", 1)
            .into_bytes();
        let at = checksum_digits(&future).unwrap();
        future[at..at + 8].copy_from_slice(CRC_PLACEHOLDER.as_bytes());
        let crc = crate::store::crc32_hex(&future);
        future[at..at + 8].copy_from_slice(crc.as_bytes());
        std::fs::write(&path, &future).unwrap();
        assert_eq!(Manifest::read(dir.path()).unwrap().max_error, 0.5);
        // A manifest without a checksum (older stores) is read unchecked.
        let mut old = tiny();
        old.content_crc32 = None;
        std::fs::write(&path, serde_json::to_vec_pretty(&old).unwrap()).unwrap();
        assert!(Manifest::read(dir.path()).is_ok());
    }
}
