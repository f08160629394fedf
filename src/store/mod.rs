//! The on-disk cell store: what `cliffmap build` writes and every later stage reads.
//!
//! Layout of a store directory (see docs/formats.md):
//! ```text
//! STORE/manifest.json            Manifest: georeference, quadtree, every CellRecord (written last)
//! STORE/build.json               build key of the last or current build (for resuming and repair)
//! STORE/.lock                   writer lock (pid and command of the writer; see `StoreLock`)
//! STORE/recipe.json              the `cliffmap build` command line that made the store (for repair)
//! STORE/stats.json               texel-stretch statistics ({"summary", "cells"})
//! STORE/stats_histogram.png      histogram of average texel stretch per cell
//! STORE/cells/{level}/{x}-{y}.mesh        CellMesh (binary, cell-local f32)
//! STORE/cells/{level}/{x}-{y}.png         RGBA8 colour texture
//! STORE/cells/{level}/{x}-{y}.normal.png  RGB8 normal map
//! STORE/cells/{level}/{x}-{y}.relief.png  L8 height of the DEM above the TIN (`ReliefRecord`)
//! STORE/cells/{level}/{x}-{y}.json        CellRecord of a finished cell (resume marker)
//! STORE/cells/{level}/{x}-{y}.photo.png       RGBA8 photo-enhanced texture (`cliffmap project`;
//!                                             the atlas of its blocks, see `photo_texture`)
//! STORE/cells/{level}/{x}-{y}.photo.conf.png  L8 photo share per texel (likewise)
//! ```
//! Every file is written atomically; every cell file's size and CRC-32 are recorded and
//! verified on read.

mod files;
mod lock;
mod manifest;
mod mesh;
mod obj;
pub mod photo_texture;
mod surface;
mod writer;

use std::path::{Path, PathBuf};

pub use files::{crc32_hex, is_intact, read_verified, write_file};
pub use lock::StoreLock;
pub use manifest::{
    CellFiles, CellRecord, DemInfo, FileRef, Manifest, Parameterization, PhotoCellRecord,
    PhotoLevelReport, PhotoReport, PhotoSettings, ReliefRecord, ReparamRecord, ReparamSettings,
    STORE_FORMAT, STORE_VERSION,
};
pub use obj::obj_text;
pub use photo_texture::{PHOTO_BLOCK, PhotoBlocks, magnify};
pub use surface::{CameraPlacement, SurfacePoint};
pub use writer::BackgroundWriter;

use crate::cells::CellMesh;
use crate::error::{Error, Result};

/// An opened store: its directory and manifest. Reading a cell verifies its checksums.
#[derive(Clone, Debug)]
pub struct Store {
    /// The store directory.
    pub dir: PathBuf,
    /// The parsed manifest.
    pub manifest: Manifest,
}

impl Store {
    /// Opens the store in `dir` (reads and validates `manifest.json`).
    pub fn open(dir: &Path) -> Result<Store> {
        if !dir.is_dir() {
            return Err(Error::store(
                dir,
                "not a directory (expected a cliffmap store made by `cliffmap build`)",
            ));
        }
        Ok(Store {
            dir: dir.to_path_buf(),
            manifest: Manifest::read(dir)?,
        })
    }

    /// The record of cell `id`, or an error listing how to find valid ids.
    pub fn cell(&self, id: &str) -> Result<&CellRecord> {
        self.manifest.cell(id).ok_or_else(|| {
            Error::BadOption(format!(
                "cell {id:?} is not in store {} (ids look like \"LEVEL-X-Y\", e.g. {:?}; see stats.json)",
                self.dir.display(),
                self.manifest.cells.first().map(|c| c.id.as_str()).unwrap_or("0-0-0")
            ))
        })
    }

    /// Reads and verifies a cell's (orthographic) mesh.
    pub fn read_mesh(&self, rec: &CellRecord) -> Result<CellMesh> {
        self.read_mesh_file(&rec.files.mesh)
    }

    /// Reads and verifies the mesh the cell currently uses: the reparameterized one (with
    /// texture coordinates) if the cell has it, else the orthographic one.
    pub fn read_active_mesh(&self, rec: &CellRecord) -> Result<CellMesh> {
        self.read_mesh_file(
            rec.reparam
                .as_ref()
                .map_or(&rec.files.mesh, |r| &r.files.mesh),
        )
    }

    /// Reads and verifies the mesh file `f` (one of the store's mesh records).
    pub fn read_mesh_file(&self, f: &FileRef) -> Result<CellMesh> {
        let bytes = read_verified(&self.dir, f)?;
        CellMesh::from_bytes(&bytes, &self.dir.join(&f.path))
    }

    /// Reads and verifies a cell's colour texture.
    pub fn read_texture(&self, rec: &CellRecord) -> Result<image::RgbaImage> {
        self.read_png(&rec.files.texture).map(|i| i.to_rgba8())
    }

    /// Reads and verifies the colour texture of the cell's active parameterization (the
    /// reparameterized one if present, else the orthographic one); photo textures excluded.
    pub fn read_active_texture(&self, rec: &CellRecord) -> Result<image::RgbaImage> {
        self.read_png(
            rec.reparam
                .as_ref()
                .map_or(&rec.files.texture, |r| &r.files.texture),
        )
        .map(|i| i.to_rgba8())
    }

    /// Reads and verifies the normal map of the cell's active parameterization (same
    /// layout as [`Store::read_active_texture`]).
    pub fn read_active_normal_map(&self, rec: &CellRecord) -> Result<image::RgbImage> {
        self.read_png(
            rec.reparam
                .as_ref()
                .map_or(&rec.files.normal, |r| &r.files.normal),
        )
        .map(|i| i.to_rgb8())
    }

    /// Reads and verifies a cell's normal map.
    pub fn read_normal_map(&self, rec: &CellRecord) -> Result<image::RgbImage> {
        self.read_png(&rec.files.normal).map(|i| i.to_rgb8())
    }

    /// Reads and verifies a cell's relief map (`None` for a cell without one), checked to be
    /// the orthographic layout's `rec.texels` square.
    pub fn read_relief_map(&self, rec: &CellRecord) -> Result<Option<crate::cells::ReliefMap>> {
        let Some(r) = &rec.relief else {
            return Ok(None);
        };
        let image = self.read_png(&r.file)?.to_luma8();
        if image.dimensions() != (rec.texels, rec.texels)
            || !(r.range_m.is_finite() && r.range_m >= 0.0)
        {
            return Err(Error::store(
                self.dir.join(&r.file.path),
                format!(
                    "relief map of cell {} is {}x{} with range {} m; expected {}x{} and a finite range >= 0",
                    rec.id,
                    image.width(),
                    image.height(),
                    r.range_m,
                    rec.texels,
                    rec.texels
                ),
            ));
        }
        Ok(Some(crate::cells::ReliefMap {
            image,
            range_m: r.range_m,
        }))
    }

    /// Reads and verifies a cell's photo-enhanced texture and its confidence map (photo
    /// share per texel), whole (`p.texels` square) whether stored dense or in blocks
    /// ([`photo_texture`]).
    pub fn read_photo_texture(
        &self,
        rec: &CellRecord,
        p: &PhotoCellRecord,
    ) -> Result<(image::RgbaImage, image::GrayImage)> {
        let active = match p.blocks {
            Some(_) => Some(self.read_active_texture(rec)?),
            None => None,
        };
        self.photo_texture_over(rec, p, active.as_ref())
    }

    /// [`Store::read_photo_texture`] and the cell's active texture ([`Store::read_active_texture`])
    /// under it, each file read and decoded once.
    pub fn read_photo_texture_and_active(
        &self,
        rec: &CellRecord,
        p: &PhotoCellRecord,
    ) -> Result<(image::RgbaImage, image::GrayImage, image::RgbaImage)> {
        let active = self.read_active_texture(rec)?;
        let (texture, confidence) = self.photo_texture_over(rec, p, Some(&active))?;
        Ok((texture, confidence, active))
    }

    /// The photo texture of `p`, its blocks (if stored in blocks) composed over `active`
    /// (the cell's active texture; required then).
    fn photo_texture_over(
        &self,
        rec: &CellRecord,
        p: &PhotoCellRecord,
        active: Option<&image::RgbaImage>,
    ) -> Result<(image::RgbaImage, image::GrayImage)> {
        let texture = self.read_png(&p.texture)?.to_rgba8();
        let confidence = self.read_png(&p.confidence)?.to_luma8();
        let Some(blocks) = &p.blocks else {
            return Ok((texture, confidence));
        };
        let owned;
        let active = match active {
            Some(a) => a,
            None => {
                owned = self.read_active_texture(rec)?;
                &owned
            }
        };
        let path = self.dir.join(&p.texture.path);
        let (w, h) = active.dimensions();
        if w != h || w == 0 || !p.texels.is_multiple_of(w) || !(p.texels / w).is_power_of_two() {
            return Err(Error::store(
                path,
                format!(
                    "photo texture of {} texels does not enlarge the cell's {w}x{h} active texture by a power of two",
                    p.texels
                ),
            ));
        }
        photo_texture::compose(active, p.texels / w, blocks, &texture, &confidence)
            .map_err(|e| Error::store(path, e))
    }

    /// The confidence map of [`Store::read_photo_texture`] alone (the colour texture is not
    /// read or rebuilt).
    pub fn read_photo_confidence(&self, p: &PhotoCellRecord) -> Result<image::GrayImage> {
        let confidence = self.read_png(&p.confidence)?.to_luma8();
        match &p.blocks {
            None => Ok(confidence),
            Some(blocks) => photo_texture::compose_confidence(p.texels, blocks, &confidence)
                .map_err(|e| Error::store(self.dir.join(&p.confidence.path), e)),
        }
    }

    /// Reads and verifies one of the store's files by its record.
    pub fn read_file(&self, f: &FileRef) -> Result<Vec<u8>> {
        read_verified(&self.dir, f)
    }

    /// Reads, verifies and decodes a PNG of the store.
    pub fn read_png(&self, f: &FileRef) -> Result<image::DynamicImage> {
        let bytes = read_verified(&self.dir, f)?;
        image::load_from_memory_with_format(&bytes, image::ImageFormat::Png)
            .map_err(|e| Error::store(self.dir.join(&f.path), format!("cannot decode PNG: {e}")))
    }
}

/// Side in texels of the cell's active texture (reparameterized if present, else ortho).
pub fn active_texels(rec: &CellRecord) -> u32 {
    rec.reparam.as_ref().map_or(rec.texels, |r| r.texels)
}

/// Relative path stem of a cell's files: `cells/{level}/{x}-{y}`.
pub fn cell_stem(level: u8, x: u32, y: u32) -> String {
    format!("cells/{level}/{x}-{y}")
}

/// Texture coordinate of vertex `i` of cell `rec` drawn with `mesh`
/// ([`CellMesh::texcoord`] over the cell's origin and nominal square).
pub fn texcoord(rec: &CellRecord, mesh: &CellMesh, i: usize) -> [f32; 2] {
    mesh.texcoord(i, rec.origin, &rec.extent)
}
